//! Property tests of the exact predicates (proptest, shrinking to a
//! minimal counter-example on failure).

use chisel_bsp::Error;
use chisel_bsp::exact::budget::{MAX_COORD, MAX_NORMAL, MAX_OFFSET};
use chisel_bsp::exact::{
    IntPoint, Plane, Point4, Sign, classify_vertex, classify_vertex_exact,
    classify_vertex_filtered, intersect_3_planes, plane_from_points,
};
use proptest::prelude::*;

fn plane_with(max_n: i64, max_d: i128) -> impl Strategy<Value = Plane> {
    (
        -max_n..=max_n,
        -max_n..=max_n,
        -max_n..=max_n,
        -max_d..=max_d,
    )
        .prop_filter_map("zero normal", |(a, b, c, d)| Plane::new(a, b, c, d).ok())
}

fn full_plane() -> impl Strategy<Value = Plane> {
    plane_with(MAX_NORMAL, MAX_OFFSET)
}

fn vertex() -> impl Strategy<Value = Point4> {
    (full_plane(), full_plane(), full_plane()).prop_filter_map("dependent normals", |(p, q, r)| {
        intersect_3_planes(&p, &q, &r)
    })
}

fn int_point() -> impl Strategy<Value = IntPoint> {
    let c = || -MAX_COORD..=MAX_COORD;
    (c(), c(), c()).prop_map(|(x, y, z)| IntPoint::new(x, y, z).unwrap())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3_000))]

    /// The filter is never wrong: when it answers, the exact path agrees.
    #[test]
    fn filter_never_contradicts_exact_path(v in vertex(), s in full_plane()) {
        if let Some(sign) = classify_vertex_filtered(&v, &s) {
            prop_assert_eq!(sign, classify_vertex_exact(&v, &s));
        }
        prop_assert_eq!(classify_vertex(&v, &s), classify_vertex_exact(&v, &s));
    }

    /// Scaling a plane by a positive factor keeps every side.
    #[test]
    fn positive_scaling_keeps_sides(v in vertex(), s in plane_with(MAX_NORMAL / 8, MAX_OFFSET / 8), k in 1i64..=8) {
        let [a, b, c] = s.normal();
        let scaled = Plane::new(a * k, b * k, c * k, s.offset() * k as i128).unwrap();
        prop_assert_eq!(classify_vertex(&v, &scaled), classify_vertex(&v, &s));
    }

    /// The gcd-normalized plane is the same oriented plane.
    #[test]
    fn normalized_plane_keeps_sides(v in vertex(), s in full_plane(), p in int_point()) {
        let n = s.normalized();
        prop_assert_eq!(classify_vertex(&v, &n), classify_vertex(&v, &s));
        prop_assert_eq!(n.side_of(p), s.side_of(p));
        prop_assert_eq!(n.normalized(), n);
    }

    /// The cached f64 coefficients of a plane are the nearest f64s (the
    /// filter's error bound assumes correct rounding).
    #[test]
    fn plane_cache_is_correctly_rounded(s in full_plane()) {
        let [a, b, c] = s.normal();
        prop_assert_eq!(s.approx(), [a as f64, b as f64, c as f64, s.offset() as f64]);
    }

    /// A lifted input point classifies like its exact evaluation.
    #[test]
    fn lifted_points_classify_like_evaluation(p in int_point(), s in full_plane()) {
        prop_assert_eq!(classify_vertex(&Point4::from(p), &s), s.side_of(p));
        prop_assert_eq!(Sign::of_i128(s.eval(p)), s.side_of(p));
    }

    /// A vertex is where its planes meet, whatever their order.
    #[test]
    fn vertex_is_order_independent(p in full_plane(), q in full_plane(), r in full_plane()) {
        if let Some(v) = intersect_3_planes(&p, &q, &r) {
            let u = intersect_3_planes(&r, &p, &q).unwrap();
            prop_assert!(v.same_position(&u));
            let flipped = intersect_3_planes(&p.flipped(), &q, &r.flipped()).unwrap();
            prop_assert!(v.same_position(&flipped));
        }
    }

    /// Integer points that determine a plane lie on it; only collinear
    /// points fail, with the matching error.
    #[test]
    fn plane_from_points_contains_its_points(a in int_point(), b in int_point(), c in int_point()) {
        match plane_from_points(a, b, c) {
            Ok(plane) => {
                for p in [a, b, c] {
                    prop_assert_eq!(plane.eval(p), 0);
                }
            }
            Err(e) => prop_assert_eq!(e, Error::CollinearPoints),
        }
    }
}

#[test]
fn out_of_budget_values_are_typed_errors() {
    assert_eq!(
        IntPoint::new(0, MAX_COORD + 1, 0),
        Err(Error::CoordinateOutOfRange {
            axis: 1,
            value: MAX_COORD + 1
        })
    );
    assert!(IntPoint::new(-MAX_COORD, MAX_COORD, 0).is_ok());
    assert_eq!(
        Plane::new(0, 0, -MAX_NORMAL - 1, 0),
        Err(Error::NormalOutOfRange {
            component: 2,
            value: -MAX_NORMAL - 1
        })
    );
    assert_eq!(
        Plane::new(1, 0, 0, MAX_OFFSET + 1),
        Err(Error::OffsetOutOfRange {
            value: MAX_OFFSET + 1
        })
    );
    assert_eq!(Plane::new(0, 0, 0, 5), Err(Error::ZeroNormal));
    // Messages say what is wrong and how to fix it.
    let msg = IntPoint::new(i64::MAX, 0, 0).unwrap_err().to_string();
    assert!(msg.contains("x=") && msg.contains("quantization"), "{msg}");
}
