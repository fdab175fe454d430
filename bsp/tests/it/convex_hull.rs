//! Exact convex hulls of integer points: the result is a valid strictly
//! convex polyhedron whose faces have every input point on or below them,
//! whose vertices are input points, and degenerate inputs are typed errors.

use crate::common;

use chisel_bsp::Error;
use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::exact::{IntPoint, Sign};
use chisel_bsp::tools::convex_hull;
use common::volume::volume;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn p(x: i64, y: i64, z: i64) -> IntPoint {
    IntPoint::new(x, y, z).unwrap()
}

/// Checks that `poly` is the convex hull of `points`.
fn assert_is_hull(arena: &ConvexArena, poly: PolyId, points: &[IntPoint]) {
    arena.validate(poly).unwrap();
    for &f in &arena.faces_of(poly) {
        let plane = arena.face_plane(f);
        for &q in points {
            assert_ne!(
                plane.side_of(q),
                Sign::Positive,
                "a point lies outside face {f}"
            );
        }
    }
    for v in arena.vertices_of(poly) {
        let [x, y, z] = arena.position(v);
        let corner = p(x as i64, y as i64, z as i64);
        assert!(
            points.contains(&corner),
            "vertex {corner:?} is not an input point"
        );
    }
}

#[test]
fn a_cube_with_extra_points_on_its_faces_edges_and_inside() {
    let mut points = Vec::new();
    for x in [0, 5, 10] {
        for y in [0, 5, 10] {
            for z in [0, 5, 10] {
                points.push(p(x, y, z));
            }
        }
    }
    points.push(p(0, 0, 0)); // a duplicate
    let mut arena = ConvexArena::new();
    let hull = convex_hull(&mut arena, &points).unwrap();
    assert_is_hull(&arena, hull, &points);
    assert_eq!(arena.faces_of(hull).len(), 6, "coplanar triangles merged");
    assert_eq!(
        arena.vertices_of(hull).len(),
        8,
        "edge and face points dropped"
    );
    assert_eq!(volume(&arena, hull).num, 1000.into());
}

#[test]
fn random_point_clouds() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for round in 0..40 {
        let n = 4 + round * 3;
        let r = 1 << rng.random_range(3..24);
        let points: Vec<IntPoint> = (0..n)
            .map(|_| {
                p(
                    rng.random_range(-r..=r),
                    rng.random_range(-r..=r),
                    rng.random_range(-r..=r),
                )
            })
            .collect();
        let mut arena = ConvexArena::new();
        match convex_hull(&mut arena, &points) {
            Ok(hull) => assert_is_hull(&arena, hull, &points),
            Err(e) => panic!("random points in general position: {e}"),
        }
    }
}

#[test]
fn points_on_a_small_lattice_have_many_coplanar_faces() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..40 {
        let points: Vec<IntPoint> = (0..30)
            .map(|_| {
                p(
                    rng.random_range(0..4),
                    rng.random_range(0..4),
                    rng.random_range(0..4),
                )
            })
            .collect();
        let mut arena = ConvexArena::new();
        if let Ok(hull) = convex_hull(&mut arena, &points) {
            assert_is_hull(&arena, hull, &points);
        }
    }
}

#[test]
fn degenerate_point_sets_are_typed_errors() {
    let mut arena = ConvexArena::new();
    let err =
        |points: &[IntPoint], arena: &mut ConvexArena| convex_hull(arena, points).unwrap_err();
    assert_eq!(
        err(
            &[p(0, 0, 0), p(1, 0, 0), p(0, 1, 0), p(1, 0, 0)],
            &mut arena
        ),
        Error::DegenerateHull {
            reason: "fewer than four distinct points"
        }
    );
    let line: Vec<_> = (0..10).map(|i| p(i, 2 * i, 3 * i)).collect();
    assert_eq!(
        err(&line, &mut arena),
        Error::DegenerateHull {
            reason: "collinear"
        }
    );
    let plane: Vec<_> = (0..10).map(|i| p(i, i * i, 7)).collect();
    assert_eq!(
        err(&plane, &mut arena),
        Error::DegenerateHull { reason: "coplanar" }
    );
    assert!(arena.faces().is_empty(), "a failed hull adds nothing");
}
