//! Arbitrary-precision reference of the Table-1 operations (num-bigint).
//!
//! Written independently of the fixed-width kernel: vertices come from
//! full 3×3 determinants by Cramer's rule (not the shared cross products),
//! classification from the plain 4D dot product. Tests compare the kernel
//! against it; benchmarks time it beside the kernel.

use chisel_bsp::exact::Sign;
use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{Signed, Zero};

/// A plane `a·x + b·y + c·z + d = 0` in arbitrary precision.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BigPlane {
    pub n: [BigInt; 3],
    pub d: BigInt,
}

/// A homogeneous vertex `(X, Y, Z, W)` with `W > 0`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BigVertex {
    pub xyz: [BigInt; 3],
    pub w: BigInt,
}

pub fn sign_of(v: &BigInt) -> Sign {
    if v.is_zero() {
        Sign::Zero
    } else if v.is_positive() {
        Sign::Positive
    } else {
        Sign::Negative
    }
}

pub fn big_plane(a: i64, b: i64, c: i64, d: i128) -> BigPlane {
    BigPlane {
        n: [a.into(), b.into(), c.into()],
        d: d.into(),
    }
}

pub fn plane_from_points(p: [i64; 3], q: [i64; 3], r: [i64; 3]) -> Option<BigPlane> {
    let big = |v: [i64; 3]| v.map(BigInt::from);
    let (p, q, r) = (big(p), big(q), big(r));
    let u: Vec<BigInt> = (0..3).map(|i| &q[i] - &p[i]).collect();
    let v: Vec<BigInt> = (0..3).map(|i| &r[i] - &p[i]).collect();
    let n = [
        &u[1] * &v[2] - &u[2] * &v[1],
        &u[2] * &v[0] - &u[0] * &v[2],
        &u[0] * &v[1] - &u[1] * &v[0],
    ];
    if n.iter().all(Zero::is_zero) {
        return None;
    }
    let d = -(&n[0] * &p[0] + &n[1] * &p[1] + &n[2] * &p[2]);
    Some(BigPlane { n, d })
}

pub fn normalized(plane: &BigPlane) -> BigPlane {
    let g = plane
        .n
        .iter()
        .chain(std::iter::once(&plane.d))
        .fold(BigInt::zero(), |g, v| g.gcd(v));
    BigPlane {
        n: plane.n.clone().map(|v| v / &g),
        d: &plane.d / &g,
    }
}

pub fn parallel(p: &BigPlane, q: &BigPlane) -> bool {
    let (a, b) = (&p.n, &q.n);
    &a[1] * &b[2] == &a[2] * &b[1]
        && &a[2] * &b[0] == &a[0] * &b[2]
        && &a[0] * &b[1] == &a[1] * &b[0]
}

fn det3(m: [[&BigInt; 3]; 3]) -> BigInt {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Cramer's rule on `A x = −d`: `x_i = |A_i| / |A|`, `A_i` = `A` with column
/// `i` replaced by `−d`.
pub fn intersect(p: &BigPlane, q: &BigPlane, r: &BigPlane) -> Option<BigVertex> {
    let rows = [p, q, r];
    let neg_d: Vec<BigInt> = rows.iter().map(|pl| -&pl.d).collect();
    let a = |i: usize, j: usize| &rows[i].n[j];
    let det_a = det3([
        [a(0, 0), a(0, 1), a(0, 2)],
        [a(1, 0), a(1, 1), a(1, 2)],
        [a(2, 0), a(2, 1), a(2, 2)],
    ]);
    if det_a.is_zero() {
        return None;
    }
    let col = |i: usize, j: usize, k: usize| if j == k { &neg_d[i] } else { a(i, j) };
    let mut xyz: [BigInt; 3] = Default::default();
    for (k, x) in xyz.iter_mut().enumerate() {
        *x = det3([
            [col(0, 0, k), col(0, 1, k), col(0, 2, k)],
            [col(1, 0, k), col(1, 1, k), col(1, 2, k)],
            [col(2, 0, k), col(2, 1, k), col(2, 2, k)],
        ]);
    }
    if det_a.is_negative() {
        Some(BigVertex {
            xyz: xyz.map(|v| -v),
            w: -det_a,
        })
    } else {
        Some(BigVertex { xyz, w: det_a })
    }
}

pub fn classify(v: &BigVertex, s: &BigPlane) -> Sign {
    let t = &v.xyz[0] * &s.n[0] + &v.xyz[1] * &s.n[1] + &v.xyz[2] * &s.n[2] + &v.w * &s.d;
    sign_of(&t)
}

pub fn eval(s: &BigPlane, p: [i64; 3]) -> BigInt {
    &s.n[0] * p[0] + &s.n[1] * p[1] + &s.n[2] * p[2] + &s.d
}
