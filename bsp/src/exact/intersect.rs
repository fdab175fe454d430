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
//!
//! # The narrow path
//!
//! Planes with small coefficients (most in practice: tools and cells at a
//! millimetre or micrometre grid) give vertices far inside the budget. With
//! `|n| < 2^bn` and `|d| < 2^bd` for all three planes, each minor is below
//! `2·2^(2bn)`, so `|W| < 3·2^bn·2^(2bn+1) < 2^(3bn+3)` and
//! `|X| < 3·2^bd·2^(2bn+1) < 2^(2bn+bd+3)`, partial sums included. When both
//! are at most `2^126` ([`NARROW_BITS`]), plain `i128` arithmetic is exact and
//! gives the same vertex, digit for digit, as the wide path.
//!
//! Between the two, when the minors and the offsets fit `i64` (`2bn + 1 ≤
//! 63`, `bd ≤ 63`: normals below `2^31`, as those of tool planes built from
//! micrometre coordinates), every product in `W` and `X, Y, Z` is a single
//! `i64 × i64 → i128` product, summed in `i128` under the same bounds (the
//! medium path); it gives the narrow path's values.
//!
//! When both bounds are at most `2^63` ([`SMALL_BITS`]), plain `i64` is
//! exact (the minors too: `3bn + 3 ≤ 63` gives `2bn + 1 ≤ 41`), which is
//! the case of planes with normals and offsets below `2^20`, or normals
//! below `2^11` (a direction grid of 2,048 steps per axis) and offsets
//! below `2^38`.

use super::digits::{assemble, mul, split_balanced};
use super::plane::Plane;
use super::point::Point4;
use super::wide::{I192, I256};

/// Bound (in bits) on `|W|` and `|X|, |Y|, |Z|` for the narrow path.
const NARROW_BITS: u32 = 126;
/// Bound (in bits) on `|W|` and `|X|, |Y|, |Z|` for the `i64` path.
const SMALL_BITS: u32 = 63;

/// The path that computes the meet of planes whose normals have at most
/// `bn` bits and offsets at most `bd` bits exactly (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Path {
    /// `i64` throughout.
    Small,
    /// `i64` minors and offsets, `i128` sums of their products.
    Medium,
    /// `i128` throughout.
    Narrow,
    /// Digit sums into 192- and 256-bit values.
    Wide,
}

impl Path {
    /// The narrowest exact path for the given bit counts.
    #[inline(always)]
    fn for_bits(bn: u32, bd: u32) -> Self {
        let (w_bits, xyz_bits) = (3 * bn + 3, 2 * bn + bd + 3);
        if w_bits <= SMALL_BITS && xyz_bits <= SMALL_BITS {
            Path::Small
        } else if 2 * bn < SMALL_BITS
            && bd <= SMALL_BITS
            && w_bits <= NARROW_BITS
            && xyz_bits <= NARROW_BITS
        {
            Path::Medium
        } else if w_bits <= NARROW_BITS && xyz_bits <= NARROW_BITS {
            Path::Narrow
        } else {
            Path::Wide
        }
    }
}

/// `u × v` for vectors whose component products are below `2^62` in
/// magnitude (components below `2^31`, or a normal and a line moment as in
/// [`intersect_small`]); each component of the result is below `2^63`.
#[inline(always)]
fn cross_small(u: [i64; 3], v: [i64; 3]) -> [i64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// [`intersect_3_planes`] in `i64`, for normals `n` and offsets `d` whose
/// bit counts select [`Path::Small`], through the line `p ∩ q`: with its
/// direction `u = n_p × n_q` and moment `m = d_p n_q − d_q n_p`,
///
/// ```text
///     W = n_r · u,    X = n_r × m − d_r u
/// ```
///
/// which expand to the module's determinants term for term (24 products
/// instead of 30). Bounds: `|u| < 2^(2bn+1)`, `|m| < 2^(bn+bd+1)`, each
/// term of `X` below `2^(2bn+bd+2)` and `X` below `2^(2bn+bd+3) ≤ 2^63`,
/// `W` below `2^(3bn+3) ≤ 2^63`, partial sums included: nothing wraps and
/// negating is exact.
#[inline(always)]
fn intersect_small(n: [[i64; 3]; 3], d: [i64; 3]) -> Option<Point4> {
    let [np, nq, nr] = n;
    let u = cross_small(np, nq);
    let m = [0, 1, 2].map(|i| d[0] * nq[i] - d[1] * np[i]);
    let w = nr[0] * u[0] + nr[1] * u[1] + nr[2] * u[2];
    if w == 0 {
        return None;
    }
    let [a, b, c] = cross_small(nr, m);
    let (x, y, z) = (a - d[2] * u[0], b - d[2] * u[1], c - d[2] * u[2]);
    Some(if w > 0 {
        Point4::from_small(x, y, z, w)
    } else {
        Point4::from_small(-x, -y, -z, -w)
    })
}

/// [`intersect_3_planes`] for normals `n` and offsets `d` whose bit counts
/// select [`Path::Medium`] (module docs): the minors `n_i × n_j` in `i64`
/// (each product below `2^(2bn)`, each component below `2^(2bn+1) ≤
/// 2^63`), then every product of a normal or offset with a minor as one
/// `i64 × i64 → i128` product, with the sums below `2^126`.
#[inline(always)]
fn intersect_medium(n: [[i64; 3]; 3], d: [i64; 3]) -> Option<Point4> {
    let [np, nq, nr] = n;
    let c = [
        cross_small(nq, nr),
        cross_small(nr, np),
        cross_small(np, nq),
    ];
    let w = mul(np[0], c[0][0]) + mul(np[1], c[0][1]) + mul(np[2], c[0][2]);
    if w == 0 {
        return None;
    }
    let coord =
        |i: usize| -> i128 { -(mul(d[0], c[0][i]) + mul(d[1], c[1][i]) + mul(d[2], c[2][i])) };
    let (x, y, z) = (coord(0), coord(1), coord(2));
    Some(if w > 0 {
        Point4::from_narrow(x, y, z, w)
    } else {
        Point4::from_narrow(-x, -y, -z, -w)
    })
}

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

/// [`intersect_3_planes`] in `i128` (see the module docs for when it is
/// exact), given the normals, offsets and minors `[n_q×n_r, n_r×n_p,
/// n_p×n_q]`.
#[inline(always)]
fn intersect_narrow(n: [[i64; 3]; 3], d: [i128; 3], c: [[i128; 3]; 3]) -> Option<Point4> {
    let w: i128 = (0..3).map(|i| n[0][i] as i128 * c[0][i]).sum();
    if w == 0 {
        return None;
    }
    let coord = |i: usize| -> i128 { -(d[0] * c[0][i] + d[1] * c[1][i] + d[2] * c[2][i]) };
    let (x, y, z) = (coord(0), coord(1), coord(2));
    Some(if w > 0 {
        Point4::from_narrow(x, y, z, w)
    } else {
        Point4::from_narrow(-x, -y, -z, -w)
    })
}

/// The unique common point of three planes as an exact homogeneous vertex
/// with `W > 0`, or `None` when the normals are linearly dependent (two
/// planes parallel, or all three containing a common direction).
#[must_use]
#[inline]
pub fn intersect_3_planes(p: &Plane, q: &Plane, r: &Plane) -> Option<Point4> {
    intersect_3_planes_with(p, q, r, |v| v)
}

/// [`intersect_3_planes`], handing the vertex to `sink` inside the path
/// that built it: a caller that stores it (pushes it onto an array) writes
/// it once, in place, instead of building it on the stack and copying it.
#[inline(always)]
pub(crate) fn intersect_3_planes_with<R>(
    p: &Plane,
    q: &Plane,
    r: &Plane,
    sink: impl FnOnce(Point4) -> R,
) -> Option<R> {
    let bn = u32::from(p.normal_bits.max(q.normal_bits).max(r.normal_bits));
    let bd = u32::from(p.offset_bits.max(q.offset_bits).max(r.offset_bits));
    let path = Path::for_bits(bn, bd);
    // The coefficients are read inside each inlined path, so that they stay
    // in registers there; the wide paths, out of line, read them again.
    let n = || [p.normal(), q.normal(), r.normal()];
    let d = || [p.d, q.d, r.d];
    match path {
        // |d| < 2^(63 − 3 − 2bn): the conversions are exact.
        Path::Small => intersect_small(n(), d().map(|d| d as i64)).map(sink),
        // |d| < 2^63: the conversions are exact.
        Path::Medium => intersect_medium(n(), d().map(|d| d as i64)).map(sink),
        Path::Narrow | Path::Wide => intersect_beyond_i64(p, q, r, path).map(sink),
    }
}

/// [`intersect_3_planes`] on the [`Path::Narrow`] or [`Path::Wide`] path,
/// kept out of line: its callers inline only the `i64` paths.
#[inline(never)]
fn intersect_beyond_i64(p: &Plane, q: &Plane, r: &Plane, path: Path) -> Option<Point4> {
    let n = [p.normal(), q.normal(), r.normal()];
    let d = [p.d, q.d, r.d];
    let minors = minors(n);
    if path == Path::Narrow {
        intersect_narrow(n, d, minors)
    } else {
        intersect_wide(n, d, minors)
    }
}

/// The minors `[n_q × n_r, n_r × n_p, n_p × n_q]` of normals `[n_p, n_q, n_r]`.
#[inline(always)]
fn minors([np, nq, nr]: [[i64; 3]; 3]) -> [[i128; 3]; 3] {
    [cross(nq, nr), cross(nr, np), cross(np, nq)]
}

/// [`intersect_3_planes`] in wide arithmetic, exact for every input in
/// budget; arguments as for [`intersect_narrow`].
#[inline]
fn intersect_wide(n: [[i64; 3]; 3], d: [i128; 3], c: [[i128; 3]; 3]) -> Option<Point4> {
    let ([np, _, _], [qr, rp, pq]) = (n, c);
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

    let d = d.map(|d| {
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The narrow path gives the wide path's vertex, digit for digit, over
    /// the whole range where it is taken.
    #[test]
    fn narrow_and_wide_paths_agree() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut narrow = 0;
        for _ in 0..20_000 {
            let bn = rng.random_range(1..=41u32);
            let bd = rng.random_range(1..=83u32.min(123 - 2 * bn));
            let plane = |rng: &mut ChaCha8Rng| {
                let n = [0; 3].map(|_| rng.random_range(-(1i64 << bn) + 1..1i64 << bn));
                let d = rng.random_range(-(1i128 << bd) + 1..1i128 << bd);
                Plane::new(n[0], n[1], n[2], d).ok()
            };
            let (Some(p), Some(q), Some(r)) = (plane(&mut rng), plane(&mut rng), plane(&mut rng))
            else {
                continue;
            };
            let (n, d) = ([p.normal(), q.normal(), r.normal()], [p.d, q.d, r.d]);
            let c = [cross(n[1], n[2]), cross(n[2], n[0]), cross(n[0], n[1])];
            let (a, b) = (intersect_narrow(n, d, c), intersect_wide(n, d, c));
            assert_eq!(a.is_some(), b.is_some());
            if let (Some(a), Some(b)) = (a, b) {
                assert_eq!((a.xyz_digits, a.w_digits), (b.xyz_digits, b.w_digits));
                assert_eq!(a.approx.map(f64::to_bits), b.approx.map(f64::to_bits));
                narrow += 1;
            }
        }
        assert!(narrow > 10_000);
    }

    /// The medium path gives the wide path's vertex, digit for digit, for
    /// random planes over its whole range of normal bit counts, offsets up
    /// to the largest it takes, and coefficients at their largest
    /// magnitudes.
    #[test]
    fn medium_and_wide_paths_agree() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let mut medium = 0;
        for _ in 0..40_000 {
            let bn = rng.random_range(1..=31u32);
            let bd_max = 63u32.min(NARROW_BITS - 3 - 2 * bn);
            let bd = rng.random_range(1..=bd_max);
            let extreme = rng.random_bool(0.1);
            let n_max = (1i64 << bn) - 1;
            let plane = |rng: &mut ChaCha8Rng| {
                if extreme {
                    let mut n = [n_max; 3];
                    n[rng.random_range(0..3)] = rng.random_range(0..=n_max);
                    signed_plane(rng, n, (1i128 << bd) - 1)
                } else {
                    let n = [0; 3].map(|_| rng.random_range(-n_max..=n_max));
                    let d = rng.random_range(-(1i128 << bd) + 1..1i128 << bd);
                    Plane::new(n[0], n[1], n[2], d).ok()
                }
            };
            let (Some(p), Some(q), Some(r)) = (plane(&mut rng), plane(&mut rng), plane(&mut rng))
            else {
                continue;
            };
            let pbn = u32::from(p.normal_bits.max(q.normal_bits).max(r.normal_bits));
            let pbd = u32::from(p.offset_bits.max(q.offset_bits).max(r.offset_bits));
            if Path::for_bits(pbn, pbd) != Path::Medium {
                continue;
            }
            let n = [p.normal(), q.normal(), r.normal()];
            let (a, b) = (
                intersect_3_planes(&p, &q, &r),
                intersect_wide(n, [p.d, q.d, r.d], minors(n)),
            );
            assert_eq!(a.is_some(), b.is_some());
            if let (Some(a), Some(b)) = (a, b) {
                assert_eq!((a.xyz_digits, a.w_digits), (b.xyz_digits, b.w_digits));
                assert_eq!(a.approx.map(f64::to_bits), b.approx.map(f64::to_bits));
                medium += 1;
            }
        }
        assert!(medium > 10_000, "{medium}");
    }

    /// A plane with normal components and offset of the given magnitudes
    /// and random signs.
    fn signed_plane(rng: &mut ChaCha8Rng, n: [i64; 3], d: i128) -> Option<Plane> {
        let mut sign = || if rng.random::<bool>() { 1 } else { -1 };
        Plane::new(
            sign() * n[0],
            sign() * n[1],
            sign() * n[2],
            sign() as i128 * d,
        )
        .ok()
    }

    /// Checks that `intersect_3_planes` takes the `i64` path for `p, q, r`
    /// and gives the wide path's vertex, digit for digit; true when the
    /// planes meet in a point.
    fn small_path_agrees(p: &Plane, q: &Plane, r: &Plane) -> bool {
        let bn = u32::from(p.normal_bits.max(q.normal_bits).max(r.normal_bits));
        let bd = u32::from(p.offset_bits.max(q.offset_bits).max(r.offset_bits));
        assert_eq!(Path::for_bits(bn, bd), Path::Small);
        let n = [p.normal(), q.normal(), r.normal()];
        let (a, b) = (
            intersect_3_planes(p, q, r),
            intersect_wide(n, [p.d, q.d, r.d], minors(n)),
        );
        assert_eq!(a.is_some(), b.is_some());
        let (Some(a), Some(b)) = (a, b) else {
            return false;
        };
        assert_eq!((a.xyz_digits, a.w_digits), (b.xyz_digits, b.w_digits));
        assert_eq!(a.approx.map(f64::to_bits), b.approx.map(f64::to_bits));
        true
    }

    /// The `i64` path gives the wide path's vertex, digit for digit, for
    /// random planes at every normal bit count it takes, with offsets up to
    /// the largest it takes, and at the edge of its range (every
    /// coefficient at its largest magnitude); one bit more selects a wider
    /// path.
    #[test]
    fn small_and_wide_paths_agree() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut random, mut extreme) = (0, 0);
        for bn in 1..=(SMALL_BITS - 3) / 3 {
            let bd_max = SMALL_BITS - 3 - 2 * bn;
            assert_ne!(Path::for_bits(bn + 1, bd_max), Path::Small);
            assert_ne!(Path::for_bits(bn, bd_max + 1), Path::Small);
            let (n_max, d_max) = ((1i64 << bn) - 1, (1i128 << bd_max) - 1);
            for _ in 0..300 {
                let bd = rng.random_range(1..=bd_max);
                let plane = |rng: &mut ChaCha8Rng| {
                    let n = [0; 3].map(|_| rng.random_range(-n_max..=n_max));
                    let d = rng.random_range(-(1i128 << bd) + 1..1i128 << bd);
                    Plane::new(n[0], n[1], n[2], d).ok()
                };
                if let (Some(p), Some(q), Some(r)) =
                    (plane(&mut rng), plane(&mut rng), plane(&mut rng))
                    && small_path_agrees(&p, &q, &r)
                {
                    random += 1;
                }
            }
            for _ in 0..30 {
                // Extreme magnitudes, with a random component zeroed or
                // lowered now and then so that the normals are independent.
                let plane = |rng: &mut ChaCha8Rng| {
                    let mut n = [n_max; 3];
                    n[rng.random_range(0..3)] = rng.random_range(0..=n_max);
                    signed_plane(rng, n, d_max)
                };
                if let (Some(p), Some(q), Some(r)) =
                    (plane(&mut rng), plane(&mut rng), plane(&mut rng))
                    && small_path_agrees(&p, &q, &r)
                {
                    extreme += 1;
                }
            }
        }
        assert!(random > 5_000 && extreme > 200, "{random} {extreme}");
    }
}
