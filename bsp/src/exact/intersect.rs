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
use super::wide::{I128, I192, I256};

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
        w = w.wrapping_add(&I192::from_i128(qr[i]).wrapping_mul_i64(np[i]));
    }
    if w.is_zero() {
        return None;
    }

    let (dp, dq, dr) = (
        I128::from_i128(p.d),
        I128::from_i128(q.d),
        I128::from_i128(r.d),
    );
    let coord = |i: usize| -> I256 {
        let t0: I256 = dp.wrapping_mul(&I128::from_i128(qr[i]));
        let t1: I256 = dq.wrapping_mul(&I128::from_i128(rp[i]));
        let t2: I256 = dr.wrapping_mul(&I128::from_i128(pq[i]));
        t0.wrapping_add(&t1).wrapping_add(&t2)
    };
    // X = −Σ d·(n×n); normalising to W > 0 flips the sign of all four.
    let flip = !w.is_negative();
    let (x, y, z) = (
        coord(0).negate_if(flip),
        coord(1).negate_if(flip),
        coord(2).negate_if(flip),
    );
    Some(Point4::from_parts(x, y, z, w.negate_if(!flip)))
}
