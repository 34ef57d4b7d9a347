//! Building blocks for wire types: fixed-width little-endian integers, scaled fixed-point
//! values with checked constructors, one-byte enumerations and flag sets.
//!
//! postcard encodes integers as varints by default; every wire type here goes through
//! [`Fixed`] instead, so each field has one size and one byte position whatever its value —
//! the layout a DBC can describe.

use serde::{Deserializer, Serializer};

/// An integer that is encoded fixed-width little-endian.
pub trait Fixed: Copy {
    /// Write `self` in its fixed width.
    fn serialize_fixed<S: Serializer>(self, serializer: S) -> Result<S::Ok, S::Error>;
    /// Read a value in its fixed width.
    fn deserialize_fixed<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error>;
}

impl Fixed for u8 {
    fn serialize_fixed<S: Serializer>(self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_u8(self)
    }
    fn deserialize_fixed<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        <u8 as serde::Deserialize>::deserialize(deserializer)
    }
}

macro_rules! fixed_le {
    ($($int:ty),*) => {$(
        impl Fixed for $int {
            fn serialize_fixed<S: Serializer>(self, serializer: S) -> Result<S::Ok, S::Error> {
                postcard::fixint::le::serialize(&self, serializer)
            }
            fn deserialize_fixed<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                postcard::fixint::le::deserialize(deserializer)
            }
        }
    )*};
}
fixed_le!(i16, u16, u32);

/// 10^`exp` as `f32`, for the small exponents the wire uses.
pub const fn pow10(exp: i8) -> f32 {
    let mut value = 1.0_f32;
    let mut i = 0_i8;
    if exp >= 0 {
        while i < exp {
            value *= 10.0;
            i += 1;
        }
        value
    } else {
        while i < -exp {
            value *= 10.0;
            i += 1;
        }
        1.0 / value
    }
}

/// Round half away from zero to an integer; `None` for NaN and infinities.
pub(crate) fn round_to_i64(value: f32) -> Option<i64> {
    if !value.is_finite() {
        return None;
    }
    let shifted = if value >= 0.0 {
        value + 0.5
    } else {
        value - 0.5
    };
    // `as` saturates; |value| beyond i64 is far outside every wire range anyway.
    Some(shifted as i64)
}

/// Defines a fixed-point wire scalar: `$name($raw)` meaning raw × 10^`$exp` `$unit`,
/// accepted only within `$min..=$max` raw counts.
macro_rules! wire_scalar {
    ($(#[$meta:meta])* $name:ident($raw:ty) = $ty:ident, exp10 $exp:literal, unit $unit:literal,
     raw $min:expr, $max:expr) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
        pub struct $name($raw);

        impl $name {
            /// Smallest accepted raw value.
            pub const RAW_MIN: $raw = $min;
            /// Largest accepted raw value.
            pub const RAW_MAX: $raw = $max;
            /// One count in physical units: the quantization step.
            pub const STEP: f32 = $crate::wire::pow10($exp);
            const COUNTS_PER_UNIT: f32 = $crate::wire::pow10(-$exp);

            /// From raw counts; `None` outside `RAW_MIN..=RAW_MAX`.
            #[allow(unused_comparisons)] // full-range types compare against their own limits
            pub const fn from_raw(raw: $raw) -> Option<Self> {
                if raw >= $min && raw <= $max {
                    Some(Self(raw))
                } else {
                    None
                }
            }

            /// Raw counts as sent on the wire.
            pub const fn raw(self) -> $raw {
                self.0
            }

            /// From a physical value, rounded to the nearest count; `None` when the value is
            /// not finite or falls outside the accepted range.
            pub fn from_si(value: f32) -> Option<Self> {
                let counts = $crate::wire::round_to_i64(value * Self::COUNTS_PER_UNIT)?;
                if counts < i64::from(Self::RAW_MIN) || counts > i64::from(Self::RAW_MAX) {
                    return None;
                }
                <$raw>::try_from(counts).ok().map(Self)
            }

            /// From a physical value, clamped into the accepted range; NaN becomes the value
            /// nearest zero. For senders that must always put something safe on the wire.
            pub fn saturating_from_si(value: f32) -> Self {
                let counts = $crate::wire::round_to_i64(value * Self::COUNTS_PER_UNIT)
                    .unwrap_or(if value > 0.0 { i64::MAX } else if value < 0.0 { i64::MIN } else { 0 })
                    .clamp(i64::from(Self::RAW_MIN), i64::from(Self::RAW_MAX));
                <$raw>::try_from(counts).map(Self).unwrap_or(Self(Self::RAW_MIN))
            }

            /// Physical value.
            pub fn si(self) -> f32 {
                self.0 as f32 / Self::COUNTS_PER_UNIT
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                $crate::wire::Fixed::serialize_fixed(self.0, serializer)
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                let raw = <$raw as $crate::wire::Fixed>::deserialize_fixed(deserializer)?;
                Self::from_raw(raw).ok_or_else(|| serde::de::Error::custom("value out of range"))
            }
        }

        impl postcard::experimental::max_size::MaxSize for $name {
            const POSTCARD_MAX_SIZE: usize = core::mem::size_of::<$raw>();
        }

        impl $crate::signal::WireField for $name {
            const TYPE: $crate::signal::WireType = $crate::signal::WireType::$ty;
            const EXP10: i8 = $exp;
            const UNIT: &'static str = $unit;
            const RAW_MIN: i64 = $min as i64;
            const RAW_MAX: i64 = $max as i64;
        }
    };
}
pub(crate) use wire_scalar;

/// Defines a one-byte enumeration; an unknown byte is rejected as out of range.
macro_rules! wire_enum {
    ($(#[$meta:meta])* $name:ident {
        $($(#[$vmeta:meta])* $variant:ident = $value:literal => $label:literal),+ $(,)?
    }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum $name {
            $($(#[$vmeta])* $variant = $value),+
        }

        impl $name {
            /// Every value, in wire order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];

            /// The value for a raw byte, or `None` if the byte names no value.
            pub const fn from_raw(raw: u8) -> Option<Self> {
                match raw {
                    $($value => Some($name::$variant),)+
                    _ => None,
                }
            }

            /// The raw byte.
            pub const fn raw(self) -> u8 {
                self as u8
            }

            /// Name as written in the DBC value table.
            pub const fn label(self) -> &'static str {
                match self {
                    $($name::$variant => $label),+
                }
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                serializer.serialize_u8(self.raw())
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                let raw = <u8 as serde::Deserialize>::deserialize(deserializer)?;
                Self::from_raw(raw).ok_or_else(|| serde::de::Error::custom("unknown enumeration value"))
            }
        }

        impl postcard::experimental::max_size::MaxSize for $name {
            const POSTCARD_MAX_SIZE: usize = 1;
        }

        impl $crate::signal::WireField for $name {
            const TYPE: $crate::signal::WireType = $crate::signal::WireType::U8;
            const EXP10: i8 = 0;
            const UNIT: &'static str = "";
            const RAW_MIN: i64 = $crate::wire::min_of(&[$($value),+]);
            const RAW_MAX: i64 = $crate::wire::max_of(&[$($value),+]);
            const VALUES: &'static [(u32, &'static str)] = &[$(($value, $label)),+];
        }
    };
}
pub(crate) use wire_enum;

/// Defines a set of flag bits; a set bit with no name is rejected as out of range.
macro_rules! wire_flags {
    ($(#[$meta:meta])* $name:ident($raw:ty) = $ty:ident {
        $($(#[$fmeta:meta])* $flag:ident = $bit:literal => $label:literal),+ $(,)?
    }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct $name($raw);

        // The DBC lists flag names by bit position, so bits must run 0, 1, 2, … in order.
        const _: () = {
            let mut rest: &[usize] = &[$($bit),+];
            let mut expected = 0;
            while let [bit, tail @ ..] = rest {
                assert!(*bit == expected, "flag bits must be contiguous from 0, in order");
                expected += 1;
                rest = tail;
            }
        };

        impl $name {
            $($(#[$fmeta])* pub const $flag: $name = $name(1 << $bit);)+
            /// Every named bit.
            pub const KNOWN: $raw = 0 $(| (1 << $bit))+;
            /// No flag set.
            pub const EMPTY: $name = $name(0);

            /// From raw bits; `None` if a bit without a name is set.
            pub const fn from_bits(bits: $raw) -> Option<Self> {
                if bits | Self::KNOWN == Self::KNOWN {
                    Some(Self(bits))
                } else {
                    None
                }
            }

            /// Raw bits.
            pub const fn bits(self) -> $raw {
                self.0
            }

            /// Whether every flag of `other` is set.
            pub const fn contains(self, other: Self) -> bool {
                self.0 & other.0 == other.0
            }

            /// `self` with the flags of `other` set.
            pub const fn with(self, other: Self) -> Self {
                Self(self.0 | other.0)
            }

            /// `self` with the flags of `other` cleared.
            pub const fn without(self, other: Self) -> Self {
                Self(self.0 & !other.0)
            }

            /// Whether no flag is set.
            pub const fn is_empty(self) -> bool {
                self.0 == 0
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                $crate::wire::Fixed::serialize_fixed(self.0, serializer)
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                let raw = <$raw as $crate::wire::Fixed>::deserialize_fixed(deserializer)?;
                Self::from_bits(raw).ok_or_else(|| serde::de::Error::custom("unknown flag bit"))
            }
        }

        impl postcard::experimental::max_size::MaxSize for $name {
            const POSTCARD_MAX_SIZE: usize = core::mem::size_of::<$raw>();
        }

        impl $crate::signal::WireField for $name {
            const TYPE: $crate::signal::WireType = $crate::signal::WireType::$ty;
            const EXP10: i8 = 0;
            const UNIT: &'static str = "";
            const RAW_MIN: i64 = 0;
            const RAW_MAX: i64 = Self::KNOWN as i64;
            const FLAGS: &'static [&'static str] = &[$($label),+];
        }
    };
}
pub(crate) use wire_flags;

/// Smallest of a non-empty list (for enumeration ranges).
pub const fn min_of(values: &[u8]) -> i64 {
    let mut min = u8::MAX;
    let mut rest = values;
    while let [first, tail @ ..] = rest {
        if *first < min {
            min = *first;
        }
        rest = tail;
    }
    min as i64
}

/// Largest of a list (for enumeration ranges).
pub const fn max_of(values: &[u8]) -> i64 {
    let mut max = 0;
    let mut rest = values;
    while let [first, tail @ ..] = rest {
        if *first > max {
            max = *first;
        }
        rest = tail;
    }
    max as i64
}
