//! The result type of every predicate.

use core::ops::{Mul, Neg};

/// The sign of an exact quantity; for a point and a plane, which side the
/// point is on.
///
/// For a plane `a·x + b·y + c·z + d = 0` with normal `n = (a, b, c)`,
/// `Positive` means `n·p + d > 0` (the side `n` points to), `Negative` means
/// `n·p + d < 0`, and `Zero` means the point lies exactly on the plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(i8)]
pub enum Sign {
    /// Strictly below zero: the negative half-space.
    Negative = -1,
    /// Exactly zero: on the plane.
    #[default]
    Zero = 0,
    /// Strictly above zero: the positive half-space.
    Positive = 1,
}

impl Sign {
    /// The sign of an `i128`.
    #[must_use]
    #[inline]
    pub fn of_i128(v: i128) -> Self {
        match v.cmp(&0) {
            core::cmp::Ordering::Less => Sign::Negative,
            core::cmp::Ordering::Equal => Sign::Zero,
            core::cmp::Ordering::Greater => Sign::Positive,
        }
    }

    /// `-1`, `0` or `1`.
    #[must_use]
    #[inline]
    pub fn as_i32(self) -> i32 {
        self as i8 as i32
    }
}

impl Neg for Sign {
    type Output = Sign;
    #[inline]
    fn neg(self) -> Sign {
        match self {
            Sign::Negative => Sign::Positive,
            Sign::Zero => Sign::Zero,
            Sign::Positive => Sign::Negative,
        }
    }
}

impl Mul for Sign {
    type Output = Sign;
    #[inline]
    fn mul(self, rhs: Sign) -> Sign {
        match (self, rhs) {
            (Sign::Zero, _) | (_, Sign::Zero) => Sign::Zero,
            (a, b) if a == b => Sign::Positive,
            _ => Sign::Negative,
        }
    }
}
