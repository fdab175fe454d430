//! Planes with integer coefficients and the plane constructors of Table 1.

use core::hash::{Hash, Hasher};

use super::budget::{MAX_NORMAL, MAX_OFFSET};
use super::point::IntPoint;
use super::sign::Sign;
use crate::Error;

/// The plane `a·x + b·y + c·z + d = 0` with integer coefficients,
/// `|a|, |b|, |c| ≤ 2^55` and `|d| ≤ 2^83` (see [`super::budget`]).
///
/// The normal `n = (a, b, c)` points into the *positive* half-space
/// `n·p + d > 0`. The plane also caches the `f64` values of its coefficients
/// (each correctly rounded) for the classification filter; equality and
/// hashing use the exact coefficients only.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    pub(crate) a: i64,
    pub(crate) b: i64,
    pub(crate) c: i64,
    /// Bits of the largest normal component: `|a|, |b|, |c| < 2^normal_bits`
    /// (fills padding; lets constructions pick a narrower path).
    pub(crate) normal_bits: u8,
    /// Bits of the offset: `|d| < 2^offset_bits`.
    pub(crate) offset_bits: u8,
    pub(crate) d: i128,
    pub(crate) approx: [f64; 4],
}

impl Plane {
    /// The plane `a·x + b·y + c·z + d = 0`.
    ///
    /// # Errors
    /// [`Error::NormalOutOfRange`] or [`Error::OffsetOutOfRange`] outside the
    /// budget, [`Error::ZeroNormal`] for `a = b = c = 0`.
    pub fn new(a: i64, b: i64, c: i64, d: i128) -> Result<Self, Error> {
        for (component, &value) in [a, b, c].iter().enumerate() {
            if !(-MAX_NORMAL..=MAX_NORMAL).contains(&value) {
                return Err(Error::NormalOutOfRange { component, value });
            }
        }
        if !(-MAX_OFFSET..=MAX_OFFSET).contains(&d) {
            return Err(Error::OffsetOutOfRange { value: d });
        }
        if a == 0 && b == 0 && c == 0 {
            return Err(Error::ZeroNormal);
        }
        Ok(Self::new_unchecked(a, b, c, d))
    }

    /// Builds a plane whose coefficients are already known to be in budget.
    #[inline]
    pub(crate) fn new_unchecked(a: i64, b: i64, c: i64, d: i128) -> Self {
        debug_assert!(
            [a, b, c]
                .iter()
                .all(|v| v.unsigned_abs() <= MAX_NORMAL as u64)
        );
        debug_assert!(d.unsigned_abs() <= MAX_OFFSET as u128);
        let largest = a.unsigned_abs().max(b.unsigned_abs()).max(c.unsigned_abs());
        Self {
            a,
            b,
            c,
            normal_bits: (u64::BITS - largest.leading_zeros()) as u8,
            offset_bits: (u128::BITS - d.unsigned_abs().leading_zeros()) as u8,
            d,
            approx: [a as f64, b as f64, c as f64, offset_to_f64(d)],
        }
    }

    /// The normal `(a, b, c)`.
    #[must_use]
    #[inline]
    pub fn normal(&self) -> [i64; 3] {
        [self.a, self.b, self.c]
    }

    /// The offset `d`.
    #[must_use]
    #[inline]
    pub fn offset(&self) -> i128 {
        self.d
    }

    /// The cached `f64` values of `[a, b, c, d]`, each correctly rounded.
    #[must_use]
    #[inline]
    pub fn approx(&self) -> [f64; 4] {
        self.approx
    }

    /// The same plane with the opposite orientation (`−a, −b, −c, −d`).
    #[must_use]
    #[inline]
    pub fn flipped(&self) -> Plane {
        // Negation keeps the bit counts, and the cached values are
        // correctly rounded, so negating them gives those of the negated
        // coefficients (rounding to nearest is symmetric); `0 − x` rather
        // than `−x` keeps a zero `+0.0`, as the conversions give it.
        Plane {
            a: -self.a,
            b: -self.b,
            c: -self.c,
            d: -self.d,
            approx: self.approx.map(|x| 0.0 - x),
            ..*self
        }
    }

    /// `n·p + d`, exactly: the signed distance of `p` to the plane scaled by
    /// `|n|`. Its magnitude is below `3·2^81 + 2^83 < 2^85`, so it cannot
    /// overflow.
    #[must_use]
    #[inline]
    pub fn eval(&self, p: IntPoint) -> i128 {
        let [x, y, z] = p.coords();
        self.a as i128 * x as i128
            + self.b as i128 * y as i128
            + self.c as i128 * z as i128
            + self.d
    }

    /// The Euclidean signed distance of `p` to the plane, in `f64` (for
    /// display and tolerances outside the kernel; decisions use
    /// [`Plane::side_of`]).
    #[must_use]
    pub fn signed_distance(&self, p: IntPoint) -> f64 {
        let [a, b, c, _] = self.approx;
        self.eval(p) as f64 / (a * a + b * b + c * c).sqrt()
    }

    /// Which side of the plane the input point `p` is on, exactly.
    #[must_use]
    #[inline]
    pub fn side_of(&self, p: IntPoint) -> Sign {
        Sign::of_i128(self.eval(p))
    }
}

/// The nearest `f64` to an offset `|d| ≤ 2^83`, without the slow generic
/// `i128` conversion: `d = h·2^32 + l` with `|h| < 2^52` and `0 ≤ l < 2^32`
/// are both exact in `f64`, so the one rounded addition is correctly rounded.
#[inline]
fn offset_to_f64(d: i128) -> f64 {
    let h = (d >> 32) as i64;
    let l = (d as u64 & 0xffff_ffff) as f64;
    h as f64 * 4_294_967_296.0 + l
}

impl PartialEq for Plane {
    fn eq(&self, other: &Self) -> bool {
        (self.a, self.b, self.c, self.d) == (other.a, other.b, other.c, other.d)
    }
}

impl Eq for Plane {}

impl Hash for Plane {
    fn hash<H: Hasher>(&self, state: &mut H) {
        (self.a, self.b, self.c, self.d).hash(state);
    }
}

/// The plane through `p`, `q`, `r` with normal `(q − p) × (r − p)`: the
/// points run counter-clockwise seen from the positive side.
///
/// Coefficients are not reduced; for inputs in budget they always are in
/// budget (`|n| ≤ 2^55`, `|d| < 2^83`).
///
/// # Errors
/// [`Error::CollinearPoints`] when the points are collinear or coincide.
pub fn plane_from_points(p: IntPoint, q: IntPoint, r: IntPoint) -> Result<Plane, Error> {
    let [px, py, pz] = p.coords();
    let [qx, qy, qz] = q.coords();
    let [rx, ry, rz] = r.coords();
    // Edges fit 28 bits, their products 55 bits: i64 is exact here.
    let (ux, uy, uz) = (qx - px, qy - py, qz - pz);
    let (vx, vy, vz) = (rx - px, ry - py, rz - pz);
    let a = uy * vz - uz * vy;
    let b = uz * vx - ux * vz;
    let c = ux * vy - uy * vx;
    if a == 0 && b == 0 && c == 0 {
        return Err(Error::CollinearPoints);
    }
    let d = -(a as i128 * px as i128 + b as i128 * py as i128 + c as i128 * pz as i128);
    Ok(Plane::new_unchecked(a, b, c, d))
}

/// [`plane_from_points`] divided by the gcd of its four coefficients: the
/// canonical form of the plane, so equal oriented planes compare equal.
///
/// # Errors
/// [`Error::CollinearPoints`] when the points are collinear or coincide.
pub fn plane_from_points_normalized(p: IntPoint, q: IntPoint, r: IntPoint) -> Result<Plane, Error> {
    plane_from_points(p, q, r).map(|plane| plane.normalized())
}

impl Plane {
    /// The plane divided by the gcd of `|a|, |b|, |c|, |d|` (same
    /// orientation, same point set, smallest coefficients).
    #[must_use]
    pub fn normalized(&self) -> Plane {
        // Most planes of general tools are already reduced: stop as soon
        // as a partial gcd is 1.
        let g_ab = gcd_u64(self.a.unsigned_abs(), self.b.unsigned_abs());
        if g_ab == 1 {
            return *self;
        }
        let g_abc = gcd_u64(g_ab, self.c.unsigned_abs());
        if g_abc == 1 {
            return *self;
        }
        // g_abc > 0 because the normal is non-zero; gcd(g, d) = gcd(g, d mod g)
        // keeps the last gcd in 64 bits.
        let g = gcd_u64(g_abc, (self.d.unsigned_abs() % g_abc as u128) as u64);
        if g == 1 {
            return *self;
        }
        let gi = g as i64;
        Plane::new_unchecked(self.a / gi, self.b / gi, self.c / gi, self.d / g as i128)
    }
}

impl Plane {
    /// The plane with normal `n` through the integer point `p`, reduced:
    /// the same as [`Plane::normalized`] of `n·x − n·p = 0`. The offset is
    /// a multiple of any common factor of `n`, so only the normal's gcd
    /// is taken (and no further than a partial gcd of 1).
    ///
    /// Preconditions: `n ≠ 0`, `|n_i| ≤ 2^55` and `|p_i| ≤ 2^26` (then
    /// `|n·p| < 2^83`).
    #[must_use]
    pub(crate) fn reduced_through(n: [i64; 3], p: [i64; 3]) -> Plane {
        let [mut a, mut b, mut c] = n;
        let g_ab = gcd_with_remainder(a.unsigned_abs(), b.unsigned_abs());
        if g_ab != 1 {
            let g = gcd_with_remainder(g_ab, c.unsigned_abs()) as i64;
            if g > 1 {
                (a, b, c) = (a / g, b / g, c / g);
            }
        }
        let d = -(i128::from(a) * i128::from(p[0])
            + i128::from(b) * i128::from(p[1])
            + i128::from(c) * i128::from(p[2]));
        Plane::new_unchecked(a, b, c, d)
    }
}

/// `gcd(x, y)` by one Euclid step (`max mod min`) before the binary gcd:
/// the binary loop takes about one step per bit the larger number has
/// over the smaller, which a remainder removes at once (a normal's common
/// factor against a component, or components of unlike sizes).
fn gcd_with_remainder(x: u64, y: u64) -> u64 {
    let (small, large) = if x < y { (x, y) } else { (y, x) };
    if small == 0 {
        return large;
    }
    gcd_u64(small, large % small)
}

/// Binary (Stein) gcd over an unsigned integer type; `gcd(0, 0) = 0`.
macro_rules! binary_gcd {
    ($name:ident, $t:ty) => {
        /// Binary (Stein) gcd; `gcd(0, 0) = 0`.
        pub(crate) fn $name(mut a: $t, mut b: $t) -> $t {
            if a == 0 || b == 0 {
                return a | b;
            }
            let shift = (a | b).trailing_zeros();
            a >>= a.trailing_zeros();
            loop {
                b >>= b.trailing_zeros();
                if a > b {
                    core::mem::swap(&mut a, &mut b);
                }
                b -= a;
                if b == 0 {
                    return a << shift;
                }
            }
        }
    };
}
binary_gcd!(gcd_u64, u64);
binary_gcd!(gcd_u128, u128);

/// True when the normals of `p` and `q` are parallel (eq. 1:
/// `n_p × n_q = 0`), whichever their orientations.
#[must_use]
#[inline]
pub fn are_planes_parallel(p: &Plane, q: &Plane) -> bool {
    // Products of 55-bit components fit 110 bits: i128 is exact.
    let (pa, pb, pc) = (p.a as i128, p.b as i128, p.c as i128);
    let (qa, qb, qc) = (q.a as i128, q.b as i128, q.c as i128);
    pb * qc == pc * qb && pc * qa == pa * qc && pa * qb == pb * qa
}

#[cfg(test)]
mod tests {
    use super::Plane;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The plane through an integer point with a reduced normal is the
    /// normalized plane, for normals with and without common factors.
    #[test]
    fn reduced_through_a_point_is_the_normalized_plane() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for round in 0..20_000 {
            let factor = [1, 2, 3, 6, 1 << 20, 7 * 11 * 13][round % 6];
            let bits = rng.random_range(0..=55u32 - 22);
            let mut n = [0; 3].map(|_| {
                let x = rng.random_range(-(1i64 << bits)..=1i64 << bits) * factor;
                if rng.random_range(0..4) == 0 { 0 } else { x }
            });
            if n == [0; 3] {
                n[round % 3] = factor;
            }
            let p = [0; 3].map(|_| rng.random_range(-(1i64 << 26)..=1 << 26));
            let d = -(0..3)
                .map(|i| i128::from(n[i]) * i128::from(p[i]))
                .sum::<i128>();
            let expected = Plane::new_unchecked(n[0], n[1], n[2], d).normalized();
            assert_eq!(Plane::reduced_through(n, p), expected, "{n:?} {p:?}");
        }
    }

    /// A flipped plane is the plane built from the negated coefficients,
    /// cached values and bit counts included, at every offset magnitude.
    #[test]
    fn flipped_is_the_plane_of_negated_coefficients() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for bits in 0..=83u32 {
            for _ in 0..20 {
                // Some normal components zero, as in axis-aligned planes.
                let n = [0; 3].map(|_| {
                    if rng.random_bool(0.3) {
                        0
                    } else {
                        rng.random_range(-(1i64 << 55)..=1i64 << 55)
                    }
                });
                let d = rng.random::<i128>() >> (127 - bits);
                let Ok(p) = Plane::new(n[0], n[1], n[2], d) else {
                    continue;
                };
                let (f, g) = (p.flipped(), Plane::new(-n[0], -n[1], -n[2], -d).unwrap());
                assert_eq!(f, g);
                assert_eq!(f.approx.map(f64::to_bits), g.approx.map(f64::to_bits));
                assert_eq!(
                    (f.normal_bits, f.offset_bits),
                    (g.normal_bits, g.offset_bits)
                );
            }
        }
    }
}
