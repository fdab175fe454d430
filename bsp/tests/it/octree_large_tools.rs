//! Tools with thousands of faces (a hull of points on a sphere): the
//! restriction of the tool to a cell walks its chain of planes without
//! recursion, a cell crossed by many planes is split before the merge so
//! that memory stays linear in the faces, the result is exact (block
//! volume = result + hull, as exact rationals), and a hull over the point
//! limit is a typed error.

use crate::common;

use chisel_bsp::Error;
use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
use chisel_bsp::tools::{MAX_HULL_POINTS, convex_hull};
use common::octree_reference::octree_volumes;
use common::volume::{Fraction, volume};
use num_bigint::BigInt;

/// `n` integer points near a sphere of radius `r` around `c` (a Fibonacci
/// spiral, rounded): nearly all of them are hull vertices.
fn sphere_points(n: usize, c: i64, r: f64) -> Vec<IntPoint> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            let p = [s * t.cos(), s * t.sin(), z].map(|x| c + (r * x).round() as i64);
            IntPoint::from_array(p).unwrap()
        })
        .collect()
}

#[test]
fn a_hull_of_thousands_of_points_carves_a_block_exactly() {
    let points = sphere_points(5000, 50_000, 30_000.0);
    let tool = Tool::convex_hull(&points).unwrap();
    let block = CellBox {
        min: [0; 3],
        max: [100_000; 3],
    };
    let mut octree = Octree::from_box([0; 3], 17, block, 1, OctreeConfig::default()).unwrap();
    // Before: a recursion as deep as the hull's faces in a worker thread
    // (a stack overflow), and a merge holding cells of up to that many
    // faces each.
    octree.apply(&tool, Edit::Subtract).unwrap();

    let mut arena = ConvexArena::new();
    let hull = convex_hull(&mut arena, &points).unwrap();
    assert!(arena.faces_of(hull).len() > 5000);
    let left = octree_volumes(&octree).remove(&1).unwrap();
    let cube = Fraction::new(BigInt::from(100_000i64).pow(3), BigInt::from(1));
    assert!(left.add(&volume(&arena, hull)) == cube);
    assert!(
        octree
            .leaves()
            .iter()
            .all(|(_, leaf)| leaf.bsp_nodes() <= OctreeConfig::default().max_bsp_nodes)
    );
    let mesh = SurfaceMesh::from_faces(&octree.surface());
    mesh.check_regions_watertight().unwrap();
}

#[test]
fn a_hull_over_the_point_limit_is_refused() {
    let points = sphere_points(MAX_HULL_POINTS + 1, 0, 1e6);
    match Tool::convex_hull(&points) {
        Err(Error::TooManyHullPoints { points, limit }) => {
            assert_eq!((points, limit), (MAX_HULL_POINTS + 1, MAX_HULL_POINTS));
        }
        other => panic!("{other:?}"),
    }
    // At the limit, it is built.
    Tool::convex_hull(&points[..MAX_HULL_POINTS]).unwrap();
}
