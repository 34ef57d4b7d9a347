//! One value per leg joint ([`Joints`]) and one per drive ([`PerDrive`]).
//!
//! The robot's 16 leg joints and 5 drives used to travel through the code as bare `[T; 16]` and
//! `[T; 5]` arrays, whose order (which index is `knee_bl`? which is the wheel drive?) only a
//! comment stated. These types carry that order in the type: a [`Joints`] is always in the
//! bus's joint order ([`JOINT_NAMES`](crate::JOINT_NAMES): leg-major FL, FR, BL, BR; within a
//! leg `hip1`, `hip2`, knee, ankle — index `leg as usize * 4 + joint`), a [`PerDrive`] always in
//! [`Drive::ALL`] order, and both are read by [`Leg`] or [`Drive`] rather than by a number.
//!
//! Neither type knows a unit: the fields and variables that hold them name it
//! (`leg_targets_rad: Joints<f32>`, the simulator's `efforts_nm`), as everywhere in the project.
//!
//! No accessor panics: per-leg and per-drive access is total (every [`Leg`] and [`Drive`] has
//! its slot), access by a raw index returns an `Option` ([`Joints::get`]), and neither type
//! implements `Index`.
//!
//! On the wire a `Joints<T>` is exactly a `[T; 16]`: postcard writes its 16 elements in order,
//! with no length ([`LegTargets::position`](crate::LegTargets::position)).

use core::{array, slice};

use serde::{Deserialize, Serialize};

use crate::node::{Drive, Leg};

/// One value per leg joint, in the bus's joint order ([`JOINT_NAMES`](crate::JOINT_NAMES)):
/// index `leg as usize * 4 + joint`, with `joint` 0…3 = `hip1`, `hip2`, knee, ankle.
///
/// ```
/// use protocol::{Joints, Leg};
///
/// let mut targets_rad = Joints::splat(0.0_f32);
/// targets_rad.leg_mut(Leg::Bl)[2] = 1.2; // knee_bl
/// assert_eq!(targets_rad.get(10), Some(&1.2));
/// assert_eq!(targets_rad.leg(Leg::Bl), &[0.0, 0.0, 1.2, 0.0]);
/// let degrees = targets_rad.map(f32::to_degrees);
/// assert_eq!(degrees.iter().filter(|d| **d != 0.0).count(), 1);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Joints<T>([T; 16]);

impl<T> Joints<T> {
    /// Number of leg joints: 4 legs × 4 joints.
    pub const LEN: usize = 16;

    /// From the values in joint order.
    pub const fn new(values: [T; 16]) -> Self {
        Self(values)
    }

    /// The same value for every joint.
    pub const fn splat(value: T) -> Self
    where
        T: Copy,
    {
        Self([value; 16])
    }

    /// Each joint's value from its index in joint order (0…15).
    pub fn from_fn(f: impl FnMut(usize) -> T) -> Self {
        Self(array::from_fn(f))
    }

    /// From each leg's four values (`hip1`, `hip2`, knee, ankle), legs in [`Leg::ALL`] order.
    pub fn from_legs(legs: [[T; 4]; 4]) -> Self {
        let [[a0, a1, a2, a3], [b0, b1, b2, b3], [c0, c1, c2, c3], [d0, d1, d2, d3]] = legs;
        Self([
            a0, a1, a2, a3, b0, b1, b2, b3, c0, c1, c2, c3, d0, d1, d2, d3,
        ])
    }

    /// Each leg's four values from the leg.
    pub fn from_leg_fn(f: impl FnMut(Leg) -> [T; 4]) -> Self {
        Self::from_legs(Leg::ALL.map(f))
    }

    /// The values in joint order.
    pub const fn as_array(&self) -> &[T; 16] {
        &self.0
    }

    /// The value at `index` in joint order, `None` past the last joint.
    pub fn get(&self, index: usize) -> Option<&T> {
        self.0.get(index)
    }

    /// The value at `index` in joint order, to change; `None` past the last joint.
    pub fn get_mut(&mut self, index: usize) -> Option<&mut T> {
        self.0.get_mut(index)
    }

    /// The four values of `leg` (`hip1`, `hip2`, knee, ankle).
    pub fn leg(&self, leg: Leg) -> &[T; 4] {
        match (leg, &self.0) {
            (Leg::Fl, [values @ .., _, _, _, _, _, _, _, _, _, _, _, _])
            | (Leg::Fr, [_, _, _, _, values @ .., _, _, _, _, _, _, _, _])
            | (Leg::Bl, [_, _, _, _, _, _, _, _, values @ .., _, _, _, _])
            | (Leg::Br, [_, _, _, _, _, _, _, _, _, _, _, _, values @ ..]) => values,
        }
    }

    /// The four values of `leg`, to change.
    pub fn leg_mut(&mut self, leg: Leg) -> &mut [T; 4] {
        match (leg, &mut self.0) {
            (Leg::Fl, [values @ .., _, _, _, _, _, _, _, _, _, _, _, _])
            | (Leg::Fr, [_, _, _, _, values @ .., _, _, _, _, _, _, _, _])
            | (Leg::Bl, [_, _, _, _, _, _, _, _, values @ .., _, _, _, _])
            | (Leg::Br, [_, _, _, _, _, _, _, _, _, _, _, _, values @ ..]) => values,
        }
    }

    /// Each leg with its four values, in [`Leg::ALL`] order.
    pub fn iter_legs(&self) -> impl Iterator<Item = (Leg, &[T; 4])> + '_ {
        Leg::ALL.into_iter().map(move |leg| (leg, self.leg(leg)))
    }

    /// The values in joint order.
    pub fn iter(&self) -> slice::Iter<'_, T> {
        self.0.iter()
    }

    /// The values in joint order, to change.
    pub fn iter_mut(&mut self) -> slice::IterMut<'_, T> {
        self.0.iter_mut()
    }

    /// `f` applied to every value, order kept.
    pub fn map<U>(self, f: impl FnMut(T) -> U) -> Joints<U> {
        Joints(self.0.map(f))
    }

    /// Each joint's values of `self` and `other`, paired.
    pub fn zip<U>(self, other: Joints<U>) -> Joints<(T, U)> {
        let [a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15] = self.0;
        let [b0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11, b12, b13, b14, b15] = other.0;
        Joints([
            (a0, b0),
            (a1, b1),
            (a2, b2),
            (a3, b3),
            (a4, b4),
            (a5, b5),
            (a6, b6),
            (a7, b7),
            (a8, b8),
            (a9, b9),
            (a10, b10),
            (a11, b11),
            (a12, b12),
            (a13, b13),
            (a14, b14),
            (a15, b15),
        ])
    }
}

impl<T> From<[T; 16]> for Joints<T> {
    fn from(values: [T; 16]) -> Self {
        Self(values)
    }
}

impl<T> From<Joints<T>> for [T; 16] {
    fn from(joints: Joints<T>) -> Self {
        joints.0
    }
}

impl<T> IntoIterator for Joints<T> {
    type Item = T;
    type IntoIter = array::IntoIter<T, 16>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<'a, T> IntoIterator for &'a Joints<T> {
    type Item = &'a T;
    type IntoIter = slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

impl<'a, T> IntoIterator for &'a mut Joints<T> {
    type Item = &'a mut T;
    type IntoIter = slice::IterMut<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter_mut()
    }
}

impl<T: postcard::experimental::max_size::MaxSize> postcard::experimental::max_size::MaxSize
    for Joints<T>
{
    const POSTCARD_MAX_SIZE: usize =
        <[T; 16] as postcard::experimental::max_size::MaxSize>::POSTCARD_MAX_SIZE;
}

/// One value per drive, in [`Drive::ALL`] order: the four leg drives (FL, FR, BL, BR), then the
/// wheel drive. Every [`Drive`] has its slot, so [`PerDrive::get`] needs no `Option`.
///
/// ```
/// use protocol::{Drive, PerDrive};
///
/// let mut faulted = PerDrive::splat(false);
/// *faulted.get_mut(Drive::Wheel) = true;
/// assert!(faulted.get(Drive::Wheel) & !faulted.get(Drive::LegFl));
/// assert_eq!(faulted.iter().filter(|f| **f).count(), 1);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PerDrive<T>([T; 5]);

impl<T> PerDrive<T> {
    /// Number of drives: one per leg, one for both wheels.
    pub const LEN: usize = 5;

    /// From the values in [`Drive::ALL`] order.
    pub const fn new(values: [T; 5]) -> Self {
        Self(values)
    }

    /// The same value for every drive.
    pub const fn splat(value: T) -> Self
    where
        T: Copy,
    {
        Self([value; 5])
    }

    /// Each drive's value from the drive.
    pub fn from_fn(f: impl FnMut(Drive) -> T) -> Self {
        Self(Drive::ALL.map(f))
    }

    /// The values in [`Drive::ALL`] order.
    pub const fn as_array(&self) -> &[T; 5] {
        &self.0
    }

    /// The value of `drive`.
    pub fn get(&self, drive: Drive) -> &T {
        let [fl, fr, bl, br, wheel] = &self.0;
        match drive {
            Drive::LegFl => fl,
            Drive::LegFr => fr,
            Drive::LegBl => bl,
            Drive::LegBr => br,
            Drive::Wheel => wheel,
        }
    }

    /// The value of `drive`, to change.
    pub fn get_mut(&mut self, drive: Drive) -> &mut T {
        let [fl, fr, bl, br, wheel] = &mut self.0;
        match drive {
            Drive::LegFl => fl,
            Drive::LegFr => fr,
            Drive::LegBl => bl,
            Drive::LegBr => br,
            Drive::Wheel => wheel,
        }
    }

    /// The values in [`Drive::ALL`] order.
    pub fn iter(&self) -> slice::Iter<'_, T> {
        self.0.iter()
    }

    /// The values in [`Drive::ALL`] order, to change.
    pub fn iter_mut(&mut self) -> slice::IterMut<'_, T> {
        self.0.iter_mut()
    }

    /// Each drive with its value, in [`Drive::ALL`] order.
    pub fn iter_drives(&self) -> impl Iterator<Item = (Drive, &T)> + '_ {
        Drive::ALL.into_iter().zip(&self.0)
    }

    /// `f` applied to every value, order kept.
    pub fn map<U>(self, f: impl FnMut(T) -> U) -> PerDrive<U> {
        PerDrive(self.0.map(f))
    }
}

impl<T> From<[T; 5]> for PerDrive<T> {
    fn from(values: [T; 5]) -> Self {
        Self(values)
    }
}

impl<T> From<PerDrive<T>> for [T; 5] {
    fn from(drives: PerDrive<T>) -> Self {
        drives.0
    }
}

impl<T> IntoIterator for PerDrive<T> {
    type Item = T;
    type IntoIter = array::IntoIter<T, 5>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<'a, T> IntoIterator for &'a PerDrive<T> {
    type Item = &'a T;
    type IntoIter = slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::node::JOINT_NAMES;

    #[test]
    fn legs_are_the_joint_names_in_order() {
        let names = Joints::new(JOINT_NAMES);
        for (leg, values) in names.iter_legs() {
            for (joint, name) in values.iter().enumerate() {
                assert_eq!(Some(name), names.get(leg as usize * 4 + joint));
                assert!(name.ends_with(leg.suffix()));
            }
        }
        assert_eq!(
            names.leg(Leg::Fr),
            &["hip1_fr", "hip2_fr", "knee_fr", "ankle_fr"]
        );
        assert_eq!(Joints::from_leg_fn(|leg| *names.leg(leg)), names);
        assert_eq!(names.get(16), None);
    }

    #[test]
    fn leg_mut_changes_only_that_leg() {
        for leg in Leg::ALL {
            let mut values = Joints::from_fn(|i| i);
            *values.leg_mut(leg) = [99; 4];
            for (i, value) in values.iter().enumerate() {
                let expected = if i / 4 == leg as usize { 99 } else { i };
                assert_eq!(*value, expected);
            }
        }
    }

    #[test]
    fn zip_and_map_keep_the_order() {
        let a = Joints::from_fn(|i| i);
        let b = Joints::from_fn(|i| 100 + i);
        let zipped = a.zip(b);
        assert_eq!(zipped.map(|(x, y)| y - x), Joints::splat(100));
        assert!(zipped.iter().enumerate().all(|(i, &(x, _))| x == i));
    }

    #[test]
    fn every_drive_has_its_own_slot() {
        let mut drives = PerDrive::from_fn(|drive| drive as u8);
        for drive in Drive::ALL {
            assert_eq!(*drives.get(drive), drive as u8);
            *drives.get_mut(drive) += 10;
        }
        assert_eq!(<[u8; 5]>::from(drives), [10, 11, 12, 13, 14]);
        let order: [Drive; 5] = PerDrive::from_fn(|d| d).into();
        assert_eq!(order, Drive::ALL);
    }

    #[test]
    fn on_the_wire_joints_are_their_array() {
        let values = Joints::from_fn(|i| i as i16 * 301 - 2000);
        let mut a = [0_u8; 64];
        let mut b = [0_u8; 64];
        let from_joints = postcard::to_slice(&values, &mut a).unwrap();
        let from_array = postcard::to_slice(values.as_array(), &mut b).unwrap();
        assert_eq!(from_joints, from_array);
        let back: Joints<i16> = postcard::from_bytes(from_joints).unwrap();
        assert_eq!(back, values);
    }
}
