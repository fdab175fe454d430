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

use super::digits::{assemble, mul, split_balanced};
use super::plane::Plane;
use super::point::Point4;
use super::wide::{I192, I256};

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

/// `Σ_j d_j·c_j` for offsets `d_j = d1·2^64 + d0` (balanced, `|d1| ≤ 2^19 + 1`)
/// and minors `|c_j| < 2^112`, split the same way (`|c1| ≤ 2^47 + 1`).
///
/// Digit sums: `d0·c0` terms are up to `2^126` each, so each is split
/// into its low limb (into `g0`, below `3·2^64`) and high part (into `g1`,
/// below `2^63` each); `g1` adds `d0·c1 + d1·c0 < 2^111 + 2^83` per term;
/// `g2 = Σ d1·c1 < 2^69`. All far inside `i128`.
#[inline(always)]
fn sum_offset_minor_products(d: &[(i64, i64); 3], c: [i128; 3]) -> I256 {
    let mut g = [0i128; 4];
    for j in 0..3 {
        let (d0, d1) = d[j];
        let (c0, c1) = split_balanced(c[j]);
        let c1 = c1 as i64;
        let low = mul(d0, c0);
        g[0] += low as u64 as i128;
        g[1] += (low >> 64) + mul(d0, c1) + mul(d1, c0);
        g[2] += mul(d1, c1);
    }
    assemble(g)
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

    // W = Σ_i n_p,i·qr_i with qr_i = q1·2^64 + q0 (balanced): the digit
    // sums are below 3·2^55·2^63 < 2^120 and 3·2^55·2^48 < 2^104.
    let mut gw = [0i128; 3];
    for i in 0..3 {
        let (q0, q1) = split_balanced(qr[i]);
        gw[0] += mul(np[i], q0);
        gw[1] += mul(np[i], q1 as i64);
    }
    let w: I192 = assemble(gw);
    if w.is_zero() {
        return None;
    }

    let d = [p.d, q.d, r.d].map(|d| {
        let (d0, d1) = split_balanced(d);
        (d0, d1 as i64)
    });
    let coord = |i: usize| -> I256 { sum_offset_minor_products(&d, [qr[i], rp[i], pq[i]]) };
    // X = −Σ d·(n×n); normalising to W > 0 flips the sign of all four.
    let flip = !w.is_negative();
    let (x, y, z) = (
        coord(0).negate_if(flip),
        coord(1).negate_if(flip),
        coord(2).negate_if(flip),
    );
    Some(Point4::from_parts(x, y, z, w.negate_if(!flip)))
}
