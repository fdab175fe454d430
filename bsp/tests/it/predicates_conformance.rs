//! One conformance suite for the exact predicates, run against every
//! implementation: the filtered kernel (the default entry points), the
//! fixed-width exact path alone, and the num-bigint reference.
//!
//! Each backend must reproduce the fixtures, satisfy the geometric
//! identities, and agree *exactly* (same big integers, same signs) with the
//! reference on random full-budget and adversarial inputs.

use crate::common;

use chisel_bsp::exact::Sign;
use common::backends::{Backend, Filtered, FixedWidth, Reference};
use common::inputs::{self, RawPlane};
use num_bigint::BigInt;

/// Random cases per randomized check (per backend).
const CASES: usize = 4_000;

fn plane<B: Backend>(p: RawPlane) -> B::Plane {
    B::plane(p.0, p.1, p.2, p.3)
}

fn big4(v: [i128; 4]) -> [BigInt; 4] {
    v.map(BigInt::from)
}

fn fixtures<B: Backend>() {
    let pl = |a, b, c, d| B::plane(a, b, c, d);
    // plane_from_points: orientation and exact coefficients.
    let p = B::plane_from_points([0, 0, 0], [1, 0, 0], [0, 1, 0]).unwrap();
    assert_eq!(B::plane_coeffs(&p), big4([0, 0, 1, 0]));
    let p = B::plane_from_points([1, 2, 3], [4, 6, 8], [-2, 5, 1]).unwrap();
    assert_eq!(B::plane_coeffs(&p), big4([-23, -9, 21, -22]));
    // Normalized: divided by gcd(0, 0, 4, -8) = 4.
    let p = B::plane_from_points_normalized([2, 0, 2], [4, 0, 2], [2, 2, 2]).unwrap();
    assert_eq!(B::plane_coeffs(&p), big4([0, 0, 1, -2]));
    let p = B::plane_from_points([2, 0, 2], [4, 0, 2], [2, 2, 2]).unwrap();
    assert_eq!(B::plane_coeffs(&p), big4([0, 0, 4, -8]));
    // Collinear and coincident points define no plane.
    assert!(B::plane_from_points([0, 0, 0], [1, 1, 1], [2, 2, 2]).is_none());
    assert!(B::plane_from_points([5, 5, 5], [5, 5, 5], [1, 2, 3]).is_none());

    // intersect: axis planes x = 1, y = 2, z = 3, in both orientations.
    let (px, py, pz) = (pl(1, 0, 0, -1), pl(0, 1, 0, -2), pl(0, 0, 1, -3));
    let v = B::intersect(&px, &py, &pz).unwrap();
    assert_eq!(B::vertex_coords(&v), big4([1, 2, 3, 1]));
    let v = B::intersect(&py, &px, &pz).unwrap();
    assert_eq!(
        B::vertex_coords(&v),
        big4([1, 2, 3, 1]),
        "W is normalised to > 0"
    );
    // A fractional vertex: 2x = 1, 3y = 1, z = 0 meet at (1/2, 1/3, 0) = (3, 2, 0) / 6.
    let half = B::intersect(&pl(2, 0, 0, -1), &pl(0, 3, 0, -1), &pl(0, 0, 1, 0)).unwrap();
    assert_eq!(B::vertex_coords(&half), big4([3, 2, 0, 6]));
    // Classification of the fractional vertex.
    assert_eq!(B::classify(&half, &pl(6, 0, 0, -3)), Sign::Zero);
    assert_eq!(B::classify(&half, &pl(6, 0, 0, -2)), Sign::Positive);
    assert_eq!(B::classify(&half, &pl(0, 3, 0, -2)), Sign::Negative);
    assert_eq!(B::classify(&half, &pl(2, 3, 7, -2)), Sign::Zero);
    // Dependent normals: two parallel planes, or three sharing a direction.
    assert!(B::intersect(&px, &pl(-3, 0, 0, 7), &pz).is_none());
    assert!(B::intersect(&px, &py, &pl(1, 1, 0, -1)).is_none());
    // Parallelism ignores orientation and offset.
    assert!(B::parallel(&pl(1, 2, 3, 0), &pl(-2, -4, -6, 5)));
    assert!(!B::parallel(&pl(1, 2, 3, 0), &pl(1, 2, 4, 0)));
    // Side of an input point.
    let s = pl(1, 1, 1, -6);
    assert_eq!(B::side_of_point(&s, [1, 2, 3]), Sign::Zero);
    assert_eq!(B::side_of_point(&s, [0, 0, 0]), Sign::Negative);
    assert_eq!(B::side_of_point(&s, [10, 0, 0]), Sign::Positive);
    assert_eq!(B::eval_point(&s, [10, 0, 0]), BigInt::from(4));
}

fn vertices_lie_on_their_planes<B: Backend>(seed: u64) {
    let mut rng = inputs::rng(seed);
    let mut checked = 0;
    while checked < CASES {
        let [p, q, r] = [0; 3].map(|_| plane::<B>(inputs::plane(&mut rng)));
        let Some(v) = B::intersect(&p, &q, &r) else {
            continue;
        };
        for s in [&p, &q, &r] {
            assert_eq!(B::classify(&v, s), Sign::Zero);
        }
        // Every permutation gives the identical exact representation.
        let coords = B::vertex_coords(&v);
        for (a, b, c) in [
            (&q, &r, &p),
            (&r, &p, &q),
            (&q, &p, &r),
            (&p, &r, &q),
            (&r, &q, &p),
        ] {
            assert_eq!(B::vertex_coords(&B::intersect(a, b, c).unwrap()), coords);
        }
        checked += 1;
    }
}

fn flipping_a_plane_flips_the_side<B: Backend>(seed: u64) {
    let mut rng = inputs::rng(seed);
    for _ in 0..CASES {
        let [p, q, r, s] = [0; 4].map(|_| plane::<B>(inputs::plane(&mut rng)));
        let Some(v) = B::intersect(&p, &q, &r) else {
            continue;
        };
        assert_eq!(B::classify(&v, &B::flipped(&s)), -B::classify(&v, &s));
    }
}

/// Compares every operation with the reference on the given planes and points.
fn assert_matches_reference<B: Backend>(planes: [RawPlane; 4], points: [[i64; 3]; 3]) {
    type R = Reference;
    let [p, q, r, s] = planes.map(plane::<B>);
    let [rp, rq, rr, rs] = planes.map(plane::<R>);
    assert_eq!(B::parallel(&p, &q), R::parallel(&rp, &rq), "{planes:?}");
    let v = B::intersect(&p, &q, &r);
    let rv = R::intersect(&rp, &rq, &rr);
    assert_eq!(v.is_some(), rv.is_some(), "{planes:?}");
    if let (Some(v), Some(rv)) = (v, rv) {
        assert_eq!(B::vertex_coords(&v), R::vertex_coords(&rv), "{planes:?}");
        assert_eq!(B::classify(&v, &s), R::classify(&rv, &rs), "{planes:?}");
    }
    let [a, b, c] = points;
    let fp = B::plane_from_points(a, b, c);
    let rfp = R::plane_from_points(a, b, c);
    assert_eq!(
        fp.as_ref().map(B::plane_coeffs),
        rfp.as_ref().map(R::plane_coeffs),
        "{points:?}"
    );
    let fpn = B::plane_from_points_normalized(a, b, c);
    let rfpn = R::plane_from_points_normalized(a, b, c);
    assert_eq!(
        fpn.as_ref().map(B::plane_coeffs),
        rfpn.as_ref().map(R::plane_coeffs),
        "{points:?}"
    );
    assert_eq!(B::eval_point(&s, a), R::eval_point(&rs, a));
    assert_eq!(B::side_of_point(&s, b), R::side_of_point(&rs, b));
}

fn matches_reference_at_full_budget<B: Backend>(seed: u64) {
    let mut rng = inputs::rng(seed);
    for _ in 0..CASES {
        let planes = [0; 4].map(|_| inputs::plane(&mut rng));
        let points = [0; 3].map(|_| inputs::point(&mut rng));
        assert_matches_reference::<B>(planes, points);
    }
}

fn matches_reference_at_extreme_magnitudes<B: Backend>(seed: u64) {
    let mut rng = inputs::rng(seed);
    let corner = |rng: &mut inputs::Rng| {
        use chisel_bsp::exact::budget::MAX_COORD;
        let c = [MAX_COORD, -MAX_COORD, MAX_COORD - 1, 0, 1];
        [0; 3].map(|_| c[rand::Rng::random_range(rng, 0..c.len())])
    };
    for _ in 0..CASES {
        let planes = [0; 4].map(|_| inputs::extreme_plane(&mut rng));
        let points = [0; 3].map(|_| corner(&mut rng));
        assert_matches_reference::<B>(planes, points);
    }
}

fn nearly_and_exactly_dependent_triples<B: Backend>(seed: u64) {
    let mut rng = inputs::rng(seed);
    for _ in 0..CASES {
        let [p, q, r] = inputs::nearly_dependent_triple(&mut rng);
        let s = inputs::plane(&mut rng);
        assert_matches_reference::<B>([p, q, r, s], [[0; 3], [1, 0, 0], [0, 1, 0]]);
        let [p, q, r] = inputs::dependent_triple(&mut rng).map(plane::<B>);
        assert!(B::intersect(&p, &q, &r).is_none());
    }
}

/// Four planes through one integer point at the edge of the coordinate
/// budget: the vertex of any three is that point exactly, lies exactly on
/// the fourth, and moving the fourth by one unit of `d` puts it strictly on
/// one side — the cases a floating-point filter must never decide.
fn points_exactly_on_planes<B: Backend>(seed: u64) {
    use chisel_bsp::exact::budget::MAX_COORD;
    let mut rng = inputs::rng(seed);
    let mut checked = 0;
    while checked < CASES {
        let centre = [MAX_COORD - 3, -MAX_COORD + 5, MAX_COORD];
        let p = inputs::point_near(&mut rng, centre, 1 << 10);
        let Some(planes) = [0; 4]
            .map(|_| inputs::plane_through(&mut rng, p))
            .into_iter()
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let [a, b, c, s] = [planes[0], planes[1], planes[2], planes[3]].map(plane::<B>);
        let Some(v) = B::intersect(&a, &b, &c) else {
            continue;
        };
        let [x, y, z, w] = B::vertex_coords(&v);
        assert_eq!([x, y, z], p.map(|c| BigInt::from(c) * &w));
        assert_eq!(B::classify(&v, &s), Sign::Zero);
        let (sa, sb, sc, sd) = planes[3];
        assert_eq!(
            B::classify(&v, &B::plane(sa, sb, sc, sd + 1)),
            Sign::Positive
        );
        assert_eq!(
            B::classify(&v, &B::plane(sa, sb, sc, sd - 1)),
            Sign::Negative
        );
        assert_eq!(B::side_of_point(&s, p), Sign::Zero);
        checked += 1;
    }
}

fn points_lie_on_their_plane_with_consistent_orientation<B: Backend>(seed: u64) {
    let mut rng = inputs::rng(seed);
    for _ in 0..CASES {
        let [a, b, c, e] = [0; 4].map(|_| inputs::point(&mut rng));
        let Some(p) = B::plane_from_points(a, b, c) else {
            continue;
        };
        for x in [a, b, c] {
            assert_eq!(B::side_of_point(&p, x), Sign::Zero);
        }
        // Cyclic order keeps the plane; swapping two points flips it.
        let cyclic = B::plane_from_points(b, c, a).unwrap();
        assert_eq!(B::plane_coeffs(&cyclic), B::plane_coeffs(&p));
        let swapped = B::plane_from_points(b, a, c).unwrap();
        assert_eq!(B::side_of_point(&swapped, e), -B::side_of_point(&p, e));
        let n = B::plane_from_points_normalized(a, b, c).unwrap();
        assert_eq!(B::side_of_point(&n, e), B::side_of_point(&p, e));
    }
}

macro_rules! conformance_suite {
    ($name:ident, $backend:ty) => {
        mod $name {
            use super::*;
            #[test]
            fn fixtures() {
                super::fixtures::<$backend>();
            }
            #[test]
            fn vertices_lie_on_their_planes() {
                super::vertices_lie_on_their_planes::<$backend>(1);
            }
            #[test]
            fn flipping_a_plane_flips_the_side() {
                super::flipping_a_plane_flips_the_side::<$backend>(2);
            }
            #[test]
            fn matches_reference_at_full_budget() {
                super::matches_reference_at_full_budget::<$backend>(3);
            }
            #[test]
            fn matches_reference_at_extreme_magnitudes() {
                super::matches_reference_at_extreme_magnitudes::<$backend>(4);
            }
            #[test]
            fn nearly_and_exactly_dependent_triples() {
                super::nearly_and_exactly_dependent_triples::<$backend>(5);
            }
            #[test]
            fn points_exactly_on_planes() {
                super::points_exactly_on_planes::<$backend>(6);
            }
            #[test]
            fn points_lie_on_their_plane_with_consistent_orientation() {
                super::points_lie_on_their_plane_with_consistent_orientation::<$backend>(7);
            }
        }
    };
}

conformance_suite!(filtered, Filtered);
conformance_suite!(fixed_width, FixedWidth);
conformance_suite!(bigint_reference, Reference);
