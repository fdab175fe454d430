//! Exact volume of a convex polyhedron with homogeneous vertices, as a
//! reduced fraction of big integers (tests only).
//!
//! Notation: a face with vertices `p_0 … p_{n−1}` (counter-clockwise from
//! outside) contributes the signed volumes of the tetrahedra
//! `(0, p_0, p_k, p_{k+1})`; with `p = X/W`,
//! `det(p_a, p_b, p_c) = det(X_a, X_b, X_c) / (W_a W_b W_c)`, and the volume
//! is the sum over all faces divided by 6.

use chisel_bsp::convex::{ConvexArena, PolyId};
use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Signed, Zero};

use super::backends::to_big;

/// A fraction `num / den` with `den > 0`, kept reduced.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fraction {
    pub num: BigInt,
    pub den: BigInt,
}

impl Fraction {
    pub fn zero() -> Self {
        Self {
            num: BigInt::zero(),
            den: BigInt::one(),
        }
    }

    pub fn new(num: BigInt, den: BigInt) -> Self {
        let (num, den) = if den.is_negative() {
            (-num, -den)
        } else {
            (num, den)
        };
        let g = num.gcd(&den);
        if g.is_zero() || g.is_one() {
            Self { num, den }
        } else {
            Self {
                num: num / &g,
                den: den / g,
            }
        }
    }

    pub fn add(&self, other: &Self) -> Self {
        Self::new(
            &self.num * &other.den + &other.num * &self.den,
            &self.den * &other.den,
        )
    }

    /// Close to the nearest `f64` (within a few ulps).
    pub fn to_f64(&self) -> f64 {
        use num_traits::ToPrimitive;
        // q = num / den scaled to about 60 bits, then scaled back.
        let e = self.num.bits() as i64 - self.den.bits() as i64;
        let q: BigInt = if e <= 60 {
            (&self.num << (60 - e) as usize) / &self.den
        } else {
            &self.num / (&self.den << (e - 60) as usize)
        };
        q.to_f64().unwrap_or(f64::NAN) * 2f64.powi((e - 60) as i32)
    }

    pub fn is_positive(&self) -> bool {
        self.num.is_positive()
    }
}

/// The exact volume of polyhedron `poly`.
pub fn volume(arena: &ConvexArena, poly: PolyId) -> Fraction {
    let faces: Vec<Vec<chisel_bsp::exact::Point4>> = arena
        .faces_of(poly)
        .into_iter()
        .map(|f| {
            arena
                .face_loop(f)
                .map(|h| *arena.point(arena.half_edges()[h as usize].origin))
                .collect()
        })
        .collect();
    polygons_volume(&faces)
}

/// The exact volume enclosed by outward polygons with exact vertices
/// (divergence theorem: fan tetrahedra from the origin).
pub fn polygons_volume(polygons: &[Vec<chisel_bsp::exact::Point4>]) -> Fraction {
    let point = |p: &chisel_bsp::exact::Point4| -> ([BigInt; 3], BigInt) {
        let [x, y, z] = p.xyz();
        (
            [to_big(&x.limbs()), to_big(&y.limbs()), to_big(&z.limbs())],
            to_big(&p.w().limbs()),
        )
    };
    let det = |a: &[BigInt; 3], b: &[BigInt; 3], c: &[BigInt; 3]| -> BigInt {
        &a[0] * (&b[1] * &c[2] - &b[2] * &c[1]) - &a[1] * (&b[0] * &c[2] - &b[2] * &c[0])
            + &a[2] * (&b[0] * &c[1] - &b[1] * &c[0])
    };
    let mut total = Fraction::zero();
    for polygon in polygons {
        let corners: Vec<_> = polygon.iter().map(point).collect();
        let (x0, w0) = &corners[0];
        for k in 1..corners.len() - 1 {
            let (x1, w1) = &corners[k];
            let (x2, w2) = &corners[k + 1];
            total = total.add(&Fraction::new(det(x0, x1, x2), w0 * w1 * w2));
        }
    }
    Fraction::new(total.num, total.den * 6)
}
