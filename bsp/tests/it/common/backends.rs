//! The three implementations of the exact predicates, behind one trait, so
//! that a single conformance suite runs against each of them.

use super::bigint_reference as big;
use chisel_bsp::exact::{self, IntPoint, Plane, Point4, Sign};
use num_bigint::BigInt;

/// One implementation of the Table-1 operations. Inputs are raw integers
/// already inside the bit budget; results are compared as exact big
/// integers or signs.
pub trait Backend {
    type Plane: Clone + std::fmt::Debug;
    type Vertex: Clone + std::fmt::Debug;
    fn plane(a: i64, b: i64, c: i64, d: i128) -> Self::Plane;
    fn plane_from_points(p: [i64; 3], q: [i64; 3], r: [i64; 3]) -> Option<Self::Plane>;
    fn plane_from_points_normalized(p: [i64; 3], q: [i64; 3], r: [i64; 3]) -> Option<Self::Plane>;
    fn plane_coeffs(p: &Self::Plane) -> [BigInt; 4];
    fn flipped(p: &Self::Plane) -> Self::Plane;
    fn parallel(p: &Self::Plane, q: &Self::Plane) -> bool;
    fn intersect(p: &Self::Plane, q: &Self::Plane, r: &Self::Plane) -> Option<Self::Vertex>;
    fn vertex_coords(v: &Self::Vertex) -> [BigInt; 4];
    fn classify(v: &Self::Vertex, s: &Self::Plane) -> Sign;
    fn side_of_point(s: &Self::Plane, p: [i64; 3]) -> Sign;
    fn eval_point(s: &Self::Plane, p: [i64; 3]) -> BigInt;
}

fn point(p: [i64; 3]) -> IntPoint {
    IntPoint::from_array(p).expect("test inputs are inside the budget")
}

fn kernel_plane_coeffs(p: &Plane) -> [BigInt; 4] {
    let [a, b, c] = p.normal();
    [a.into(), b.into(), c.into(), p.offset().into()]
}

fn kernel_vertex_coords(v: &Point4) -> [BigInt; 4] {
    let [x, y, z] = v.xyz();
    [
        to_big(&x.limbs()),
        to_big(&y.limbs()),
        to_big(&z.limbs()),
        to_big(&v.w().limbs()),
    ]
}

/// Two's-complement little-endian limbs to a big integer.
pub fn to_big<const N: usize>(limbs: &[u64; N]) -> BigInt {
    let mut v = BigInt::from(0);
    for &l in limbs.iter().rev() {
        v = (v << 64) + BigInt::from(l);
    }
    if (limbs[N - 1] as i64) < 0 {
        v -= BigInt::from(1) << (64 * N);
    }
    v
}

macro_rules! kernel_backend {
    ($name:ident, $classify:path) => {
        /// The fixed-width kernel with the given classification entry point.
        pub struct $name;
        impl Backend for $name {
            type Plane = Plane;
            type Vertex = Point4;
            fn plane(a: i64, b: i64, c: i64, d: i128) -> Plane {
                Plane::new(a, b, c, d).expect("test planes are inside the budget")
            }
            fn plane_from_points(p: [i64; 3], q: [i64; 3], r: [i64; 3]) -> Option<Plane> {
                exact::plane_from_points(point(p), point(q), point(r)).ok()
            }
            fn plane_from_points_normalized(
                p: [i64; 3],
                q: [i64; 3],
                r: [i64; 3],
            ) -> Option<Plane> {
                exact::plane_from_points_normalized(point(p), point(q), point(r)).ok()
            }
            fn plane_coeffs(p: &Plane) -> [BigInt; 4] {
                kernel_plane_coeffs(p)
            }
            fn flipped(p: &Plane) -> Plane {
                p.flipped()
            }
            fn parallel(p: &Plane, q: &Plane) -> bool {
                exact::are_planes_parallel(p, q)
            }
            fn intersect(p: &Plane, q: &Plane, r: &Plane) -> Option<Point4> {
                exact::intersect_3_planes(p, q, r)
            }
            fn vertex_coords(v: &Point4) -> [BigInt; 4] {
                kernel_vertex_coords(v)
            }
            fn classify(v: &Point4, s: &Plane) -> Sign {
                $classify(v, s)
            }
            fn side_of_point(s: &Plane, p: [i64; 3]) -> Sign {
                s.side_of(point(p))
            }
            fn eval_point(s: &Plane, p: [i64; 3]) -> BigInt {
                s.eval(point(p)).into()
            }
        }
    };
}

kernel_backend!(Filtered, exact::classify_vertex);
kernel_backend!(FixedWidth, exact::classify_vertex_exact);

/// The arbitrary-precision reference.
pub struct Reference;
impl Backend for Reference {
    type Plane = big::BigPlane;
    type Vertex = big::BigVertex;
    fn plane(a: i64, b: i64, c: i64, d: i128) -> big::BigPlane {
        big::big_plane(a, b, c, d)
    }
    fn plane_from_points(p: [i64; 3], q: [i64; 3], r: [i64; 3]) -> Option<big::BigPlane> {
        big::plane_from_points(p, q, r)
    }
    fn plane_from_points_normalized(
        p: [i64; 3],
        q: [i64; 3],
        r: [i64; 3],
    ) -> Option<big::BigPlane> {
        big::plane_from_points(p, q, r).map(|pl| big::normalized(&pl))
    }
    fn plane_coeffs(p: &big::BigPlane) -> [BigInt; 4] {
        [p.n[0].clone(), p.n[1].clone(), p.n[2].clone(), p.d.clone()]
    }
    fn flipped(p: &big::BigPlane) -> big::BigPlane {
        big::BigPlane {
            n: p.n.clone().map(|v| -v),
            d: -p.d.clone(),
        }
    }
    fn parallel(p: &big::BigPlane, q: &big::BigPlane) -> bool {
        big::parallel(p, q)
    }
    fn intersect(
        p: &big::BigPlane,
        q: &big::BigPlane,
        r: &big::BigPlane,
    ) -> Option<big::BigVertex> {
        big::intersect(p, q, r)
    }
    fn vertex_coords(v: &big::BigVertex) -> [BigInt; 4] {
        [
            v.xyz[0].clone(),
            v.xyz[1].clone(),
            v.xyz[2].clone(),
            v.w.clone(),
        ]
    }
    fn classify(v: &big::BigVertex, s: &big::BigPlane) -> Sign {
        big::classify(v, s)
    }
    fn side_of_point(s: &big::BigPlane, p: [i64; 3]) -> Sign {
        big::sign_of(&big::eval(s, p))
    }
    fn eval_point(s: &big::BigPlane, p: [i64; 3]) -> BigInt {
        big::eval(s, p)
    }
}
