//! Which side of a plane an exact vertex lies on (paper 1 §3.2, eq. 6).
//!
//! Notation: vertex `(X, Y, Z, W)` with `W > 0`; plane `s = (a, b, c, d)`.
//! The vertex is on the side given by the sign of the 4D dot product
//!
//! ```text
//!     T = X·a + Y·b + Z·c + W·d          (|T| ≤ 2^252, see budget)
//! ```
//!
//! (eq. 6 with `sign(W) = 1`). The exact path evaluates `T` in 256-bit
//! wrapping arithmetic, with products truncated to four limbs.
//!
//! # The floating-point filter and its error bound
//!
//! [`classify_vertex`] first evaluates `T` in `f64` from the cached,
//! correctly rounded coefficients (`x_i = X_i(1+α_i)`, `a_i = A_i(1+β_i)`,
//! `|α_i|, |β_i| ≤ u = 2^-53`; no overflow since all magnitudes are below
//! `2^256`, no underflow since non-zero integers are at least 1):
//!
//! ```text
//!     t_i = fl(x_i·a_i),   s = fl((t_1 + t_2) + (t_3 + t_4)),
//!     m = fl((|t_1| + |t_2|) + (|t_3| + |t_4|)).
//! ```
//!
//! Each term of `s` carries at most five relative roundings (two
//! conversions, one product, two sums), so `|s − T| ≤ γ₅ Σ|X_i A_i|` with
//! `γ₅ = 5u/(1 − 5u)`. Since `|t_i| ≥ (1 − u)³|X_i A_i|` and
//! `m ≥ (1 − u)² Σ|t_i|`, we get `|s − T| ≤ γ₅ (1 − u)⁻⁵ m < 5.001·u·m`.
//! The filter accepts the sign of `s` only when `|s| > 2^-50·m = 8u·m`
//! (a power-of-two product, so computed exactly); then
//! `|T| ≥ |s| − |s − T| > (8 − 5.001)·u·m > 0` and `T` has the sign of `s`.
//! Otherwise (about one random case in 10^14, but every vertex that lies on
//! or extremely close to the plane) it falls back to the exact path.

use super::digits::{assemble, mul, sign_of_digits, split_balanced};
use super::plane::Plane;
use super::point::Point4;
use super::sign::Sign;
use super::wide::{I256, Int};

/// Relative error bound of the filter: `2^-50 = 8u` (see the module docs).
pub const FILTER_EPSILON: f64 = 1.0 / (1u64 << 50) as f64;

/// The side of `s` that `v` is on, exactly: a floating-point filter with a
/// proven error bound, then the exact 256-bit path when the filter cannot
/// decide.
#[must_use]
#[inline]
pub fn classify_vertex(v: &Point4, s: &Plane) -> Sign {
    match classify_vertex_filtered(v, s) {
        Some(sign) => sign,
        None => classify_vertex_fallback(v, s),
    }
}

/// The exact path of [`classify_vertex`], kept out of line: the filter
/// decides almost every call, and the inlined exact path would take the
/// registers of the loops that classify.
#[cold]
#[inline(never)]
fn classify_vertex_fallback(v: &Point4, s: &Plane) -> Sign {
    classify_vertex_exact(v, s)
}

/// The side of `s` that `v` is on, computed in 256-bit integer arithmetic
/// only (the exact path of [`classify_vertex`]).
#[must_use]
#[inline]
pub fn classify_vertex_exact(v: &Point4, s: &Plane) -> Sign {
    sign_of_digits(dot_digits(v, s))
}

/// `T` as digit sums by weight `2^(64k)` (see `digits`): X, Y, Z contribute
/// balanced digit × coefficient products, at most `2^63·2^55 = 2^118`
/// (three per digit); W·d contributes products of balanced digits, at most
/// `2^126` at `k = 0, 1` and below `2^63·2^41` at `k = 2, 3`. Every digit
/// sum, plus a carry below `2^64`, stays below `2^127`.
#[inline]
fn dot_digits(v: &Point4, s: &Plane) -> [i128; 4] {
    let n = [s.a, s.b, s.c];
    let mut g = [0i128; 4];
    for (digits, &a) in v.xyz_digits.iter().zip(&n) {
        for k in 0..4 {
            g[k] += mul(digits[k], a);
        }
    }
    let [w0, w1, w2] = v.w_digits;
    let (d0, d1) = split_balanced(s.d);
    let d1 = d1 as i64;
    g[0] += mul(w0, d0);
    g[1] += mul(w0, d1) + mul(w1, d0);
    g[2] += mul(w1, d1) + mul(w2, d0);
    g[3] += mul(w2, d1);
    g
}

/// The exact value `T = X·a + Y·b + Z·c + W·d`: the signed distance of
/// `v` to `s` times `W·|n|` (at most `2^252` in magnitude).
#[must_use]
pub fn plane_dot_exact(v: &Point4, s: &Plane) -> I256 {
    assemble(dot_digits(v, s))
}

/// An estimate of `T / W` (the signed distance of `v` to `s`, times `|n|`)
/// and a bound on its absolute error, from the cached `f64`s (see
/// `FilteredDot::offset`, which states the bound and proves it).
#[must_use]
#[inline]
pub fn offset_estimate(v: &Point4, s: &Plane) -> (f64, f64) {
    FilteredDot::new(v, s).offset(v)
}

/// The `f64` evaluation of `T` that both the sign filter and the offset
/// estimate start from, so that a caller needing both computes it once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FilteredDot {
    /// `s = fl((t_1 + t_2) + (t_3 + t_4))`.
    sum: f64,
    /// `m = fl((|t_1| + |t_2|) + (|t_3| + |t_4|))`.
    magnitude: f64,
}

impl FilteredDot {
    /// Evaluates `T` for `v` and `s` in `f64` (module docs).
    #[inline]
    pub(crate) fn new(v: &Point4, s: &Plane) -> Self {
        let [x, y, z, w] = v.approx;
        let [a, b, c, d] = s.approx;
        let (t0, t1, t2, t3) = (x * a, y * b, z * c, w * d);
        Self {
            sum: (t0 + t1) + (t2 + t3),
            magnitude: (t0.abs() + t1.abs()) + (t2.abs() + t3.abs()),
        }
    }

    /// `s`, the `f64` value of `T`.
    #[inline]
    pub(crate) fn sum(self) -> f64 {
        self.sum
    }

    /// The side, when the error bound certifies it.
    ///
    /// One comparison, `|s| > 2^-50·m`, tells whether the filter decides
    /// (the same as `s > 2^-50·m` or `s < −2^-50·m`), and the side is then
    /// the sign of `s`, chosen without a branch: the side of a vertex is as
    /// good as random to the branch predictor, whereas the filter almost
    /// always decides.
    #[inline]
    pub(crate) fn sign(self) -> Option<Sign> {
        let bound = self.magnitude * FILTER_EPSILON;
        if self.sum.abs() > bound {
            Some(if self.sum.is_sign_negative() {
                Sign::Negative
            } else {
                Sign::Positive
            })
        } else {
            None
        }
    }

    /// [`offset_estimate`] of `v`, the vertex this was evaluated for:
    /// `q = fl(s/W̃)` and the bound `e = fl(fl(m/W̃)·21u)` on `|q − T/W|`.
    ///
    /// With `W̃ = W(1+δ)`, `|δ| ≤ u`, and `|s − T| < 5.001·u·m` (module
    /// docs): `s/W̃ − T/W = (s − T)/W̃ − (T/W)·δ/(1+δ)`, where
    /// `|T/W| ≤ (1+u)(1 + 5.001·u)·m/W̃` since `|s| ≤ m` (rounding is
    /// monotone, so `|fl(a+b)| ≤ fl(|a|+|b|)` at each sum); the quotient
    /// adds `u·|s|/W̃ ≤ u·m/W̃`. In all `|q − T/W| < 7.01·u·m/W̃`, while
    /// `e ≥ 21u·(1−u)²·m/W̃` (`21u` is exact; `m/W̃` is `0` or far above
    /// the subnormals, as `m ≥ 1` when not `0` and `W̃ < 2^170`). The
    /// threefold margin also covers the rounding of the difference of two
    /// estimates and of the sum of their bounds when they are compared.
    #[inline]
    pub(crate) fn offset(self, v: &Point4) -> (f64, f64) {
        let w = v.approx[3];
        let u = f64::EPSILON / 2.0;
        (self.sum / w, self.magnitude / w * (21.0 * u))
    }
}

/// Compares the signed distances of `a` and `b` to `s` exactly:
/// `T_a / W_a` against `T_b / W_b`, i.e. `T_a·W_b` against `T_b·W_a` in
/// 448-bit arithmetic (`|T|·W < 2^(252+168)`).
#[must_use]
pub fn compare_offsets(a: &Point4, b: &Point4, s: &Plane) -> core::cmp::Ordering {
    let (ta, tb) = (plane_dot_exact(a, s), plane_dot_exact(b, s));
    let lhs: Int<7> = ta.wrapping_mul(&b.w());
    let rhs: Int<7> = tb.wrapping_mul(&a.w());
    lhs.cmp(&rhs)
}

/// The floating-point filter alone: `Some(side)` when the `f64` evaluation
/// is certified by the error bound in the module docs, `None` when only the
/// exact path can decide (always the case for a vertex exactly on `s`).
#[must_use]
#[inline]
pub fn classify_vertex_filtered(v: &Point4, s: &Plane) -> Option<Sign> {
    FilteredDot::new(v, s).sign()
}

#[cfg(test)]
mod tests {
    use super::{FILTER_EPSILON, FilteredDot, Sign};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The filter's decision as two comparisons against `±2^-50·m`.
    fn two_sided_test(dot: FilteredDot) -> Option<Sign> {
        let bound = dot.magnitude * FILTER_EPSILON;
        if dot.sum > bound {
            Some(Sign::Positive)
        } else if dot.sum < -bound {
            Some(Sign::Negative)
        } else {
            None
        }
    }

    /// One comparison of `|s|` and the sign bit decide as the two
    /// comparisons do: on random sums, at the bound and next to it, at
    /// zeros of either sign and at zero magnitude.
    #[test]
    fn one_comparison_decides_as_two() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut cases = vec![(0.0, 0.0), (-0.0, 0.0), (0.0, 1.0), (-0.0, 1.0)];
        for _ in 0..10_000 {
            let magnitude = rng.random::<f64>() * f64::powi(2.0, rng.random_range(-60..600));
            let bound = magnitude * FILTER_EPSILON;
            let sum = (rng.random::<f64>() * 2.0 - 1.0) * magnitude;
            for s in [sum, bound, -bound, bound.next_up(), bound.next_down()] {
                cases.extend([(s, magnitude), (-s, magnitude)]);
            }
        }
        for (sum, magnitude) in cases {
            let dot = FilteredDot { sum, magnitude };
            assert_eq!(dot.sign(), two_sided_test(dot), "{sum} {magnitude}");
        }
    }
}
