//! Merging coplanar fragments (`SurfaceMesh::merge_coplanar`): exact
//! integrals before = after, watertight after T-junction splitting, no
//! merge of non-convex unions, and a property test on random BSP surfaces.

use crate::common;

use std::collections::HashMap;

use chisel_bsp::exact::{Plane, intersect_3_planes};
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::tree::{BooleanOp, BoundaryFace, Bsp, EMPTY, Label};
use common::backends::to_big;
use common::shapes;
use common::surface::{H, boundary, box_bsp, corners, merge, polygons_volume_of};
use common::volume::Fraction;
use num_bigint::BigInt;
use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The mesh without merging: welded, then T-junctions split.
fn unmerged(faces: &[BoundaryFace]) -> SurfaceMesh {
    let mut mesh = SurfaceMesh::welded(faces);
    mesh.split_t_junctions();
    mesh
}

/// The exact vector area `½ Σ p_k × p_{k+1}` of every group of polygons
/// with the same plane and materials (a rational vector per group): equal
/// before and after merging exactly when every plane's region is unchanged
/// in area.
fn vector_areas(mesh: &SurfaceMesh) -> HashMap<(Plane, Label, Label), [Fraction; 3]> {
    let mut out: HashMap<_, [Fraction; 3]> = HashMap::new();
    for polygon in mesh.polygons() {
        let points: Vec<([BigInt; 3], BigInt)> = corners(mesh, &polygon.corners)
            .iter()
            .map(|v| {
                let [x, y, z] = v.xyz();
                (
                    [to_big(&x.limbs()), to_big(&y.limbs()), to_big(&z.limbs())],
                    to_big(&v.w().limbs()),
                )
            })
            .collect();
        let total = out
            .entry((polygon.plane, polygon.label, polygon.outside))
            .or_insert_with(|| [Fraction::zero(), Fraction::zero(), Fraction::zero()]);
        for k in 0..points.len() {
            let ((a, wa), (b, wb)) = (&points[k], &points[(k + 1) % points.len()]);
            let cross = [
                &a[1] * &b[2] - &a[2] * &b[1],
                &a[2] * &b[0] - &a[0] * &b[2],
                &a[0] * &b[1] - &a[1] * &b[0],
            ];
            for (t, c) in total.iter_mut().zip(cross) {
                *t = t.add(&Fraction::new(c, wa * wb * 2));
            }
        }
    }
    out
}

fn triangle_count(mesh: &SurfaceMesh) -> usize {
    mesh.polygons().iter().map(|p| p.corners.len() - 2).sum()
}

/// Everything merging must keep, for the boundary of `bsp`; returns the
/// polygon counts without and with merging.
fn check_merge(bsp: &Bsp, what: &str) -> (usize, usize) {
    let faces = boundary(bsp);
    let before = unmerged(&faces);
    let after = SurfaceMesh::from_faces(&faces);
    after.validate().unwrap_or_else(|e| panic!("{what}: {e}"));
    let owned = SurfaceMesh::from_face_vec(faces.clone());
    assert_eq!(owned.polygons(), after.polygons(), "{what}: owned faces");
    assert_eq!(owned.triangles(), after.triangles(), "{what}: owned faces");
    // Welded in uneven batches (an empty one, single faces, the rest):
    // the same vertices in the same order, so the same mesh.
    let mut rest = faces.clone();
    let tail = rest.split_off(rest.len().min(3));
    let mut batches: Vec<Vec<_>> = vec![Vec::new()];
    batches.extend(rest.into_iter().map(|face| vec![face]));
    batches.push(tail);
    let batched = SurfaceMesh::from_face_batches(batches);
    let same_vertices = batched.vertices().len() == after.vertices().len()
        && (0..after.vertices().len() as u32)
            .all(|v| batched.position(v).map(f64::to_bits) == after.position(v).map(f64::to_bits));
    assert!(same_vertices, "{what}: batches");
    assert_eq!(batched.polygons(), after.polygons(), "{what}: batches");
    assert_eq!(batched.triangles(), after.triangles(), "{what}: batches");
    after
        .check_closed()
        .unwrap_or_else(|e| panic!("{what}: not closed: {e}"));
    if before.check_watertight().is_ok() {
        after
            .check_watertight()
            .unwrap_or_else(|e| panic!("{what}: {e}"));
    }
    assert_eq!(
        polygons_volume_of(&after),
        polygons_volume_of(&before),
        "{what}: volume"
    );
    assert_eq!(
        vector_areas(&after),
        vector_areas(&before),
        "{what}: areas per plane"
    );
    assert!(after.polygons().len() <= before.polygons().len(), "{what}");
    assert!(triangle_count(&after) <= triangle_count(&before), "{what}");
    assert!(after.vertices().len() <= before.vertices().len(), "{what}");
    // Every vertex left is used by a polygon.
    let mut used = vec![false; after.vertices().len()];
    for p in after.polygons() {
        for &c in &p.corners {
            used[c as usize] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "{what}: unused vertex");
    // Merging again changes nothing.
    let mut again = after.clone();
    again.merge_coplanar();
    again.split_t_junctions();
    assert_eq!(again.polygons(), after.polygons(), "{what}: idempotence");
    (before.polygons().len(), after.polygons().len())
}

/// The square-cornered polygon with corners `xy` (counter-clockwise seen
/// from `+z`) on the plane `z = 0`, facing `+z`, as a boundary face.
fn face(xy: &[[i64; 2]]) -> BoundaryFace {
    let plane = Plane::new(0, 0, 1, 0).unwrap();
    let n = xy.len();
    let edges: Vec<Plane> = (0..n)
        .map(|k| {
            let ([ux, uy], [vx, vy]) = (xy[k], xy[(k + 1) % n]);
            // Outward in the plane: the edge direction turned clockwise.
            let (a, b) = (vy - uy, ux - vx);
            Plane::new(a, b, 0, -i128::from(a * ux + b * uy)).unwrap()
        })
        .collect();
    let vertices = (0..n)
        .map(|k| intersect_3_planes(&plane, &edges[(k + n - 1) % n], &edges[k]).unwrap())
        .collect();
    BoundaryFace {
        plane,
        edges,
        vertices,
        label: 1,
        outside: EMPTY,
        on_bounds: false,
    }
}

#[test]
fn a_square_and_a_triangle_merge_when_their_union_is_convex() {
    let square = face(&[[0, 0], [1, 0], [1, 1], [0, 1]]);
    // Across the square's edge x = 1: the union is the quadrilateral
    // (0,0) (2,0) (1,1) (0,1), and (1,0) is no corner any more.
    let convex = face(&[[1, 0], [2, 0], [1, 1]]);
    let mut mesh = SurfaceMesh::welded(&[square.clone(), convex]);
    let areas = vector_areas(&mesh);
    mesh.merge_coplanar();
    mesh.validate().unwrap();
    assert_eq!(mesh.polygons().len(), 1);
    assert_eq!(mesh.polygons()[0].corners.len(), 4);
    assert_eq!(mesh.vertices().len(), 4, "the straight corner is gone");
    assert_eq!(vector_areas(&mesh), areas);
    // Across the same edge, but reaching over (1,1): a reflex corner there.
    let reflex = face(&[[1, 0], [2, 2], [1, 1]]);
    let mut mesh = SurfaceMesh::welded(&[square.clone(), reflex]);
    mesh.merge_coplanar();
    assert_eq!(mesh.polygons().len(), 2, "a non-convex union is not merged");
    // Two squares side by side: one rectangle, four corners.
    let right = face(&[[1, 0], [2, 0], [2, 1], [1, 1]]);
    let mut mesh = SurfaceMesh::welded(&[square, right]);
    mesh.merge_coplanar();
    assert_eq!(mesh.polygons().len(), 1);
    assert_eq!(mesh.polygons()[0].corners.len(), 4);
}

#[test]
fn an_l_of_three_squares_keeps_a_non_convex_union_apart() {
    let squares = [
        face(&[[0, 0], [1, 0], [1, 1], [0, 1]]),
        face(&[[1, 0], [2, 0], [2, 1], [1, 1]]),
        face(&[[0, 1], [1, 1], [1, 2], [0, 2]]),
    ];
    let mut mesh = SurfaceMesh::welded(&squares);
    let areas = vector_areas(&mesh);
    mesh.merge_coplanar();
    mesh.validate().unwrap();
    // One of the two convex pairs merges; the L itself never does.
    assert_eq!(mesh.polygons().len(), 2);
    assert_eq!(vector_areas(&mesh), areas);
    // The corner (1, 1) of the third square now lies inside an edge of
    // the merged rectangle, or the other way round: T-junction splitting
    // puts it back.
    mesh.split_t_junctions();
    mesh.validate().unwrap();
    let inserted: usize = mesh
        .polygons()
        .iter()
        .map(|p| p.corners.len() - p.original_len())
        .sum();
    assert_eq!(inserted, 1);
}

#[test]
fn different_materials_or_planes_never_merge() {
    let square = face(&[[0, 0], [1, 0], [1, 1], [0, 1]]);
    let mut other = face(&[[1, 0], [2, 0], [2, 1], [1, 1]]);
    other.label = 2;
    let mut mesh = SurfaceMesh::welded(&[square.clone(), other]);
    mesh.merge_coplanar();
    assert_eq!(mesh.polygons().len(), 2);
    let mut across = face(&[[1, 0], [2, 0], [2, 1], [1, 1]]);
    across.outside = 3;
    let mut mesh = SurfaceMesh::welded(&[square, across]);
    mesh.merge_coplanar();
    assert_eq!(mesh.polygons().len(), 2);
}

#[test]
fn boxes_cut_by_many_planes_merge_back() {
    // A box minus a small box in one corner: the faces of the big box are
    // split by the small box's planes, and the pieces merge back.
    let solid = merge(
        &box_bsp([0, 0, 0], [1000, 1000, 1000], 1),
        &box_bsp([-10, -10, -10], [300, 300, 300], 1),
        BooleanOp::Difference,
    );
    let (before, after) = check_merge(&solid, "notched box");
    assert!(after < before, "{before} → {after} polygons");
}

#[test]
fn random_booleans_merge_with_exact_integrals() {
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let (mut before, mut after) = (0, 0);
    for round in 0..10 {
        let mut solid = box_bsp([-H / 2; 3], [H / 2; 3], 1);
        for step in 0..4 {
            let tool = shapes::random_convex_bsp(&mut rng, 1, H / 2, (H / 10, H / 4), 5);
            solid = merge(&solid, &tool, BooleanOp::Difference);
            let (b, a) = check_merge(&solid, &format!("round {round}, step {step}"));
            before += b;
            after += a;
        }
    }
    assert!(after < before, "{before} → {after} polygons");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Booleans of random convex solids and grid boxes: merged surfaces
    /// keep volume and per-plane areas exactly, stay closed (and
    /// watertight where they were).
    #[test]
    fn merged_surfaces_of_random_bsps_are_exact(seed in any::<u64>(), boxes in 1usize..4) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut solid = shapes::random_convex_bsp(&mut rng, 1, H / 4, (H / 8, H / 3), 5);
        for i in 0..boxes {
            let tool = shapes::random_convex_bsp(&mut rng, 1, H / 3, (H / 10, H / 4), 5);
            let op = if i % 2 == 0 { BooleanOp::Difference } else { BooleanOp::Union };
            solid = merge(&solid, &tool, op);
        }
        check_merge(&solid, &format!("seed {seed}"));
    }
}
