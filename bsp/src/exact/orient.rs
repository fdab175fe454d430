//! Orientation predicates on integer points (coordinates within the
//! budget, so every value below fits `i128` exactly).
//!
//! Notation: `orient(a, b, c, d) = ((b − a) × (c − a)) · (d − a)`, positive
//! when `d` lies on the side of triangle `abc` its counter-clockwise normal
//! points to; `|orient| < 3 · 2^(3·(COORD_BITS + 1) + 1) < 2^86`.

/// `a − b`, exact.
#[must_use]
pub fn sub(a: [i64; 3], b: [i64; 3]) -> [i128; 3] {
    [0, 1, 2].map(|i| i128::from(a[i]) - i128::from(b[i]))
}

/// `u × v`, exact for differences of in-budget points (`< 2^56`).
#[must_use]
pub fn cross(u: [i128; 3], v: [i128; 3]) -> [i128; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// `((b − a) × (c − a)) · (d − a)`, exact.
#[must_use]
pub fn orient(a: [i64; 3], b: [i64; 3], c: [i64; 3], d: [i64; 3]) -> i128 {
    let n = cross(sub(b, a), sub(c, a));
    let w = sub(d, a);
    n[0] * w[0] + n[1] * w[1] + n[2] * w[2]
}

/// The 2D orientation of `a, b, c` projected along `axis` (dropping that
/// coordinate, the other two in cyclic order), exact.
#[must_use]
pub fn orient_2d(a: [i64; 3], b: [i64; 3], c: [i64; 3], axis: usize) -> i128 {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let (ab, ac) = (sub(b, a), sub(c, a));
    ab[u] * ac[v] - ab[v] * ac[u]
}
