//! The vertex at which three planes meet (paper 1 §3.2, eqs. 4–5).
//!
//! Notation: `p, q, r` — planes with normals `n_p, n_q, n_r` and offsets
//! `d_p, d_q, d_r`; `×` — cross product. Solving `n_i·x = −d_i` by Cramer's
//! rule gives
//!
//! ```text
//!     W = n_p · (n_q × n_r)                                  (3×3 determinant)
//!     X = −(d_p (n_q × n_r) + d_q (n_r × n_p) + d_r (n_p × n_q))
//! ```
//!
//! so that `x = X / W`. The three cross products (2×2 minors) are shared by
//! all four determinants: nine `i64 × i64` products in native `i128`, then
//! three `i128 × i64 → 192-bit` products for `W` and nine
//! `i128 × i128 → 256-bit` products for `X`. Bounds are in [`super::budget`].

use super::plane::Plane;
use super::point::Point4;
use super::wide::{I64, I128, I192, I256};

/// `u × v` for 55-bit vectors; each component fits 111 bits.
#[inline]
fn cross(u: [i64; 3], v: [i64; 3]) -> [i128; 3] {
    let m = |a: i64, b: i64| a as i128 * b as i128;
    [
        m(u[1], v[2]) - m(u[2], v[1]),
        m(u[2], v[0]) - m(u[0], v[2]),
        m(u[0], v[1]) - m(u[1], v[0]),
    ]
}

/// `Σ d_j·c_j` exactly, for offsets `|d_j| ≤ 2^83` and minors `|c_j| < 2^112`.
///
/// Each product is formed in sign–magnitude from 64-bit halves: with
/// `|d| = d₁·2^64 + d₀` (`d₁ < 2^20`) and `|c| = c₁·2^64 + c₀` (`c₁ < 2^48`),
/// `|d·c| = d₀c₀ + (d₁c₀ + d₀c₁)·2^64 + d₁c₁·2^128`, where the middle sum is
/// below `2^113` and `d₁c₁` below `2^68`, so four `64 × 64` multiplies and
/// `u128` additions suffice. The signed sum is kept as a 256-bit wrapping
/// value in two `u128` halves.
#[inline]
fn sum_of_products(d: [i128; 3], c: [i128; 3]) -> I256 {
    let (mut lo, mut hi) = (0u128, 0u128);
    for j in 0..3 {
        let (dm, cm) = (d[j].unsigned_abs(), c[j].unsigned_abs());
        let (d0, d1) = (dm as u64 as u128, dm >> 64);
        let (c0, c1) = (cm as u64 as u128, cm >> 64);
        let low = d0 * c0;
        let mid = d1 * c0 + d0 * c1;
        let (plo, carry) = low.overflowing_add(mid << 64);
        let phi = (mid >> 64) + d1 * c1 + carry as u128;
        // Negate (phi, plo) when the signs differ: (x ^ mask) − mask, with
        // the carry out of the low half being `plo == 0`.
        let negative = (d[j] < 0) != (c[j] < 0);
        let mask = (negative as u128).wrapping_neg();
        let nlo = (plo ^ mask).wrapping_sub(mask);
        let nhi = (phi ^ mask).wrapping_add((negative & (plo == 0)) as u128);
        let (slo, carry) = lo.overflowing_add(nlo);
        lo = slo;
        hi = hi.wrapping_add(nhi).wrapping_add(carry as u128);
    }
    I256::from_limbs([lo as u64, (lo >> 64) as u64, hi as u64, (hi >> 64) as u64])
}

/// The unique common point of three planes as an exact homogeneous vertex
/// with `W > 0`, or `None` when the normals are linearly dependent (two
/// planes parallel, or all three containing a common direction).
#[must_use]
#[inline]
pub fn intersect_3_planes(p: &Plane, q: &Plane, r: &Plane) -> Option<Point4> {
    let (np, nq, nr) = (p.normal(), q.normal(), r.normal());
    let qr = cross(nq, nr);
    let rp = cross(nr, np);
    let pq = cross(np, nq);

    let mut w = I192::ZERO;
    for i in 0..3 {
        w.add_product(&I128::from_i128(qr[i]), &I64::from_i64(np[i]));
    }
    if w.is_zero() {
        return None;
    }

    let d = [p.d, q.d, r.d];
    let coord = |i: usize| -> I256 { sum_of_products([d[0], d[1], d[2]], [qr[i], rp[i], pq[i]]) };
    // X = −Σ d·(n×n); normalising to W > 0 flips the sign of all four.
    let flip = !w.is_negative();
    let (x, y, z) = (
        coord(0).negate_if(flip),
        coord(1).negate_if(flip),
        coord(2).negate_if(flip),
    );
    Some(Point4::from_parts(x, y, z, w.negate_if(!flip)))
}
