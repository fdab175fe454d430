//! Points: integer input points and exact homogeneous vertices.

use super::budget::MAX_COORD;
use super::digits::{assemble, split_balanced, to_balanced};
use super::wide::{I192, I256, Int};
use crate::Error;

/// An input point with integer coordinates, each within `±2^26`
/// ([`MAX_COORD`]). The only way in is [`IntPoint::new`], which checks the
/// budget, so every `IntPoint` is safe for the exact predicates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct IntPoint {
    coords: [i64; 3],
}

impl IntPoint {
    /// The origin.
    pub const ORIGIN: IntPoint = IntPoint { coords: [0; 3] };

    /// A point from integer coordinates.
    ///
    /// # Errors
    /// [`Error::CoordinateOutOfRange`] when a coordinate exceeds `±2^26`.
    pub fn new(x: i64, y: i64, z: i64) -> Result<Self, Error> {
        Self::from_array([x, y, z])
    }

    /// A point from an `[x, y, z]` array; see [`IntPoint::new`].
    ///
    /// # Errors
    /// [`Error::CoordinateOutOfRange`] when a coordinate exceeds `±2^26`.
    pub fn from_array(coords: [i64; 3]) -> Result<Self, Error> {
        for (axis, &value) in coords.iter().enumerate() {
            if !(-MAX_COORD..=MAX_COORD).contains(&value) {
                return Err(Error::CoordinateOutOfRange { axis, value });
            }
        }
        Ok(Self { coords })
    }

    /// The coordinates `[x, y, z]`.
    #[must_use]
    #[inline]
    pub const fn coords(&self) -> [i64; 3] {
        self.coords
    }

    /// The x coordinate.
    #[must_use]
    #[inline]
    pub const fn x(&self) -> i64 {
        self.coords[0]
    }

    /// The y coordinate.
    #[must_use]
    #[inline]
    pub const fn y(&self) -> i64 {
        self.coords[1]
    }

    /// The z coordinate.
    #[must_use]
    #[inline]
    pub const fn z(&self) -> i64 {
        self.coords[2]
    }
}

/// An exact vertex in homogeneous coordinates: the point `(X/W, Y/W, Z/W)`.
///
/// Vertices are intersections of three planes ([`super::intersect_3_planes`])
/// or lifted input points. `W > 0` always (the sign is normalised when the
/// vertex is built), so classification needs no sign correction (paper
/// eq. 6 with `sign(x₄) = 1`). `X, Y, Z` fit 197 bits and `W` 168 bits
/// (see [`super::budget`]).
///
/// The vertex also caches the correctly rounded `f64` value of each
/// coordinate, which the floating-point filter of
/// [`super::classify_vertex`] uses.
#[derive(Clone, Copy, Debug)]
pub struct Point4 {
    /// `X, Y, Z` in balanced base-`2^64` digits (`X = Σ x_k·2^(64k)`, the
    /// low three in `[−2^63, 2^63)`), the form the exact classification
    /// multiplies with single `64 × 64` products.
    pub(crate) xyz_digits: [[i64; 4]; 3],
    /// `W` in balanced digits likewise.
    pub(crate) w_digits: [i64; 3],
    pub(crate) approx: [f64; 4],
}

impl Point4 {
    /// Builds a vertex from exact parts with `w > 0`, caching the `f64`s.
    #[inline]
    pub(crate) fn from_parts(x: I256, y: I256, z: I256, w: I192) -> Self {
        debug_assert!(!w.is_negative() && !w.is_zero());
        Self {
            xyz_digits: [to_balanced(&x), to_balanced(&y), to_balanced(&z)],
            w_digits: to_balanced(&w),
            approx: [x.to_f64(), y.to_f64(), z.to_f64(), w.to_f64()],
        }
    }

    /// Builds a vertex from exact parts below `2^126` in magnitude with
    /// `w > 0`: the same digits and `f64`s as [`Point4::from_parts`] gives
    /// for these values (balanced digits are unique, and the `i128` to
    /// `f64` conversion rounds to nearest), without wide arithmetic.
    #[inline(always)]
    pub(crate) fn from_narrow(x: i128, y: i128, z: i128, w: i128) -> Self {
        debug_assert!(w > 0);
        // Written out rather than through `array::map`, which the compiler
        // leaves as a call per array on this hot path (every new vertex).
        let digits = |v: i128| -> [i64; 2] {
            debug_assert!(v.unsigned_abs() < 1 << 126);
            let (lo, hi) = split_balanced(v);
            [lo, hi as i64]
        };
        let ([x0, x1], [y0, y1], [z0, z1], [w0, w1]) = (digits(x), digits(y), digits(z), digits(w));
        Self {
            xyz_digits: [[x0, x1, 0, 0], [y0, y1, 0, 0], [z0, z1, 0, 0]],
            w_digits: [w0, w1, 0],
            approx: [
                narrow_to_f64(x),
                narrow_to_f64(y),
                narrow_to_f64(z),
                narrow_to_f64(w),
            ],
        }
    }

    /// Builds a vertex from exact parts that fit `i64`, with `w > 0`: the
    /// same digits and `f64`s as [`Point4::from_parts`] gives for these
    /// values (one balanced digit each, and the `i64` to `f64` conversion
    /// rounds to nearest).
    #[inline(always)]
    pub(crate) fn from_small(x: i64, y: i64, z: i64, w: i64) -> Self {
        debug_assert!(w > 0);
        Self {
            xyz_digits: [[x, 0, 0, 0], [y, 0, 0, 0], [z, 0, 0, 0]],
            w_digits: [w, 0, 0],
            approx: [x as f64, y as f64, z as f64, w as f64],
        }
    }

    /// Homogeneous numerators `[X, Y, Z]`.
    #[must_use]
    #[inline]
    pub fn xyz(&self) -> [I256; 3] {
        self.xyz_digits.map(|d| assemble(d.map(i128::from)))
    }

    /// Homogeneous denominator `W` (always positive).
    #[must_use]
    #[inline]
    pub fn w(&self) -> I192 {
        assemble(self.w_digits.map(i128::from))
    }

    /// The cached `f64` values of `[X, Y, Z, W]`, each correctly rounded.
    #[must_use]
    #[inline]
    pub fn approx(&self) -> [f64; 4] {
        self.approx
    }

    /// The Cartesian position in `f64` (for export and display only; the
    /// relative error of each coordinate is below `2^-51`).
    #[must_use]
    pub fn to_f64(&self) -> [f64; 3] {
        let [x, y, z, w] = self.approx;
        [x / w, y / w, z / w]
    }

    /// True when both vertices are the same point (exact cross-multiplied
    /// comparison `X₁·W₂ = X₂·W₁`, etc., in 384-bit arithmetic).
    #[must_use]
    pub fn same_position(&self, other: &Point4) -> bool {
        // Each `f64` coordinate is within `2^-51` of its exact value
        // (relative), so positions apart by more than `2^-40` of their
        // size are certainly different points.
        let (p, q) = (self.to_f64(), other.to_f64());
        if (0..3).any(|i| (p[i] - q[i]).abs() > p[i].abs().max(q[i].abs()) * f64::powi(2.0, -40)) {
            return false;
        }
        let cross = |a: &I256, wb: &I192| -> Int<6> { a.wrapping_mul(wb) };
        let (a, b) = (self.xyz(), other.xyz());
        let (wa, wb) = (self.w(), other.w());
        (0..3).all(|i| cross(&a[i], &wb) == cross(&b[i], &wa))
    }
}

/// The nearest `f64` to `v` (ties to even), as `v as f64` but without the
/// generic 128-bit conversion routine: below `2^63` the hardware converts;
/// above, the leading 64 bits are kept with a sticky bit for the rest (9
/// bits below the rounding position, so rounding is still correct) and
/// scaled by an exact power of two.
#[inline(always)]
fn narrow_to_f64(v: i128) -> f64 {
    if let Ok(small) = i64::try_from(v) {
        return small as f64;
    }
    let m = v.unsigned_abs();
    let lz = m.leading_zeros();
    let top = m << lz;
    let (hi, lo) = ((top >> 64) as u64, top as u64);
    let sticky = u64::from((hi & 1) | lo != 0);
    // hi·2^64 ≈ m·2^lz, and (hi >> 1 | sticky) carries the same rounding.
    let scale = f64::from_bits(u64::from(1023 + 65 - lz) << 52);
    let magnitude = ((hi >> 1) | sticky) as i64 as f64 * scale;
    if v < 0 { -magnitude } else { magnitude }
}

impl From<IntPoint> for Point4 {
    /// Lifts an input point to `(x, y, z, 1)`.
    fn from(p: IntPoint) -> Self {
        let [x, y, z] = p.coords();
        Point4::from_parts(
            I256::from_i64(x),
            I256::from_i64(y),
            I256::from_i64(z),
            I192::from_i64(1),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::narrow_to_f64;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The conversion rounds as `as f64` does, at every magnitude and at
    /// ties (values with few significant bits and a trailing one).
    #[test]
    fn narrow_conversion_rounds_to_nearest() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut values = vec![0, 1, -1, i128::MAX, i128::MIN, i128::MIN + 1];
        for bits in 1..127u32 {
            let v: i128 = rng.random::<i128>() >> (127 - bits);
            let tie = (1i128 << bits.min(125)) | (1i128 << bits.saturating_sub(54));
            values.extend([v, -v, tie, -tie, tie + 1, tie - 1]);
        }
        for v in values {
            assert_eq!(narrow_to_f64(v).to_bits(), (v as f64).to_bits(), "{v}");
        }
    }
}
