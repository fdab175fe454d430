//! Seeded generators of test inputs at the full bit budget, plus the
//! adversarial families: extreme magnitudes, nearly and exactly degenerate
//! triples, points exactly on planes.

use chisel_bsp::exact::budget::{MAX_COORD, MAX_NORMAL, MAX_OFFSET};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Raw plane coefficients `(a, b, c, d)` inside the budget.
pub type RawPlane = (i64, i64, i64, i128);

pub type Rng = ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

pub fn coord(rng: &mut ChaCha8Rng) -> i64 {
    rng.random_range(-MAX_COORD..=MAX_COORD)
}

pub fn point(rng: &mut ChaCha8Rng) -> [i64; 3] {
    [coord(rng), coord(rng), coord(rng)]
}

/// A point within `±bound` of `centre` on each axis, clamped to the budget.
pub fn point_near(rng: &mut ChaCha8Rng, centre: [i64; 3], bound: i64) -> [i64; 3] {
    centre.map(|c| (c + rng.random_range(-bound..=bound)).clamp(-MAX_COORD, MAX_COORD))
}

/// A plane with every coefficient uniform over its full budget.
pub fn plane(rng: &mut ChaCha8Rng) -> RawPlane {
    loop {
        let n = [0; 3].map(|_| rng.random_range(-MAX_NORMAL..=MAX_NORMAL));
        if n != [0; 3] {
            return (n[0], n[1], n[2], rng.random_range(-MAX_OFFSET..=MAX_OFFSET));
        }
    }
}

/// A plane whose coefficients are drawn from the extremes of the budget:
/// `0, ±1, ±(max − 1), ±max`.
pub fn extreme_plane(rng: &mut ChaCha8Rng) -> RawPlane {
    let n_choices = [
        0,
        1,
        -1,
        MAX_NORMAL,
        -MAX_NORMAL,
        MAX_NORMAL - 1,
        1 - MAX_NORMAL,
    ];
    let d_choices = [
        0,
        1,
        -1,
        MAX_OFFSET,
        -MAX_OFFSET,
        MAX_OFFSET - 1,
        1 - MAX_OFFSET,
    ];
    loop {
        let n = [0; 3].map(|_| n_choices[rng.random_range(0..n_choices.len())]);
        if n != [0; 3] {
            return (
                n[0],
                n[1],
                n[2],
                d_choices[rng.random_range(0..d_choices.len())],
            );
        }
    }
}

/// A plane through `p` and two random points, as raw coefficients (`None`
/// when the three happen to be collinear).
pub fn plane_through(rng: &mut ChaCha8Rng, p: [i64; 3]) -> Option<RawPlane> {
    let q = point(rng);
    let r = point(rng);
    let big = |v: [i64; 3]| v.map(|c| c as i128);
    let (p, q, r) = (big(p), big(q), big(r));
    let u = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let v = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    if n == [0; 3] {
        return None;
    }
    let d = -(n[0] * p[0] + n[1] * p[1] + n[2] * p[2]);
    Some((n[0] as i64, n[1] as i64, n[2] as i64, d))
}

/// Three planes whose normals are nearly dependent: `n_r = n_p + n_q + e`
/// with a tiny `e`, so `W = n_p·(n_q × e)` is small and `X/W` is huge.
pub fn nearly_dependent_triple(rng: &mut ChaCha8Rng) -> [RawPlane; 3] {
    let half = MAX_NORMAL / 2 - 2;
    let n = |rng: &mut ChaCha8Rng| [0; 3].map(|_| rng.random_range(-half..=half));
    let np = n(rng);
    let nq = n(rng);
    let e = [0; 3].map(|_| rng.random_range(-2..=2i64));
    let nr = [
        np[0] + nq[0] + e[0],
        np[1] + nq[1] + e[1],
        np[2] + nq[2] + e[2],
    ];
    let d = |rng: &mut ChaCha8Rng| rng.random_range(-MAX_OFFSET..=MAX_OFFSET);
    [
        (np[0], np[1], np[2], d(rng)),
        (nq[0], nq[1], nq[2], d(rng)),
        (nr[0], nr[1], nr[2], d(rng)),
    ]
}

/// Three planes whose normals are exactly dependent: `n_r = α n_p + β n_q`.
pub fn dependent_triple(rng: &mut ChaCha8Rng) -> [RawPlane; 3] {
    let bound = MAX_NORMAL / 8;
    let n = |rng: &mut ChaCha8Rng| [0; 3].map(|_| rng.random_range(-bound..=bound));
    let (np, nq) = (n(rng), n(rng));
    let (alpha, beta) = (rng.random_range(-3..=3i64), rng.random_range(-3..=3i64));
    let mut nr = [0; 3];
    for i in 0..3 {
        nr[i] = alpha * np[i] + beta * nq[i];
    }
    if nr == [0; 3] {
        nr = np;
    }
    let d = |rng: &mut ChaCha8Rng| rng.random_range(-MAX_OFFSET..=MAX_OFFSET);
    [
        (np[0], np[1], np[2], d(rng)),
        (nq[0], nq[1], nq[2], d(rng)),
        (nr[0], nr[1], nr[2], d(rng)),
    ]
}
