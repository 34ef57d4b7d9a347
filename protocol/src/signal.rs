//! Field metadata: how each message's bytes map to named, scaled signals.
//!
//! The DBC generator and the byte-layout tests read these tables; every field type carries its
//! own metadata through [`WireField`], so a table cannot disagree with the type it describes.

/// Integer type of a field on the wire, always little-endian (Intel byte order in DBC terms).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 16-bit.
    I16,
    /// Unsigned 16-bit.
    U16,
    /// Unsigned 32-bit.
    U32,
}

impl WireType {
    /// Size on the wire, bytes.
    pub const fn bytes(self) -> usize {
        match self {
            WireType::U8 => 1,
            WireType::I16 | WireType::U16 => 2,
            WireType::U32 => 4,
        }
    }

    /// Whether the raw value is two's-complement signed.
    pub const fn signed(self) -> bool {
        matches!(self, WireType::I16)
    }
}

/// A type that appears as a field on the wire. Physical value = raw × 10^`EXP10` in `UNIT`.
pub trait WireField {
    /// Raw integer type.
    const TYPE: WireType;
    /// Decimal exponent of the scale (−4 means 1e-4 per count).
    const EXP10: i8;
    /// Physical unit, as written in the DBC.
    const UNIT: &'static str;
    /// Smallest raw value a receiver accepts.
    const RAW_MIN: i64;
    /// Largest raw value a receiver accepts.
    const RAW_MAX: i64;
    /// Named values of an enumeration (`VAL_` in the DBC); empty for numbers.
    const VALUES: &'static [(u32, &'static str)] = &[];
    /// Names of flag bits, bit 0 first; a flags field appears in the DBC as one 1-bit signal
    /// per name. Empty for non-flag fields.
    const FLAGS: &'static [&'static str] = &[];
}

/// One field of a message: a scalar, or an array of scalars with one name per element.
#[derive(Debug, Clone, Copy)]
pub struct Field {
    /// Field name; array elements are named `{name}_{instance}`.
    pub name: &'static str,
    /// Raw type of one element.
    pub ty: WireType,
    /// Decimal exponent of the scale.
    pub exp10: i8,
    /// Physical unit.
    pub unit: &'static str,
    /// Smallest accepted raw value.
    pub raw_min: i64,
    /// Largest accepted raw value.
    pub raw_max: i64,
    /// Element names of an array field; empty for a scalar.
    pub instances: &'static [&'static str],
    /// Named values of an enumeration.
    pub values: &'static [(u32, &'static str)],
    /// Names of flag bits.
    pub flags: &'static [&'static str],
}

impl Field {
    /// Number of elements (1 for a scalar).
    pub const fn count(&self) -> usize {
        if self.instances.is_empty() {
            1
        } else {
            self.instances.len()
        }
    }

    /// Size of the whole field on the wire, bytes.
    pub const fn bytes(&self) -> usize {
        self.ty.bytes() * self.count()
    }
}

/// A scalar field of type `T`.
pub const fn scalar<T: WireField>(name: &'static str) -> Field {
    array::<T>(name, &[])
}

/// An array field of type `T`, one element per name in `instances`.
pub const fn array<T: WireField>(name: &'static str, instances: &'static [&'static str]) -> Field {
    Field {
        name,
        ty: T::TYPE,
        exp10: T::EXP10,
        unit: T::UNIT,
        raw_min: T::RAW_MIN,
        raw_max: T::RAW_MAX,
        instances,
        values: T::VALUES,
        flags: T::FLAGS,
    }
}

/// Total payload size of a field table, bytes.
pub const fn payload_bytes(fields: &[Field]) -> usize {
    let mut total = 0;
    let mut rest = fields;
    while let [first, tail @ ..] = rest {
        total += first.bytes();
        rest = tail;
    }
    total
}
