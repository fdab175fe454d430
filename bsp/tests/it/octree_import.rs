//! Octree import from closed triangle meshes (§3.9): exact volumes of
//! boxes, convex hulls and random voxel solids (whose free inner cells are
//! labelled by the flood fill), typed errors for open or misoriented
//! meshes and for input outside the cube, and quantization at the edge.

use crate::common;

use chisel_bsp::Error;
use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{Octree, OctreeConfig};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::EMPTY;
use common::shapes::p;
use common::volume::{Fraction, volume};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 10;

fn config(budget: usize) -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: budget,
        max_depth: 8,
    }
}

/// Exact volume of all material, over all leaves.
fn solid_volume(octree: &Octree) -> Fraction {
    let mut total = Fraction::zero();
    for (key, leaf) in octree.leaves() {
        let mut arena = ConvexArena::new();
        let cell = octree.cell_box(key).add_to(&mut arena).unwrap();
        for c in leaf.to_bsp().cells(&mut arena, cell) {
            if c.label != EMPTY {
                total = total.add(&volume(&arena, c.poly));
            }
        }
    }
    total
}

fn int(n: i64) -> Fraction {
    Fraction::new(n.into(), 1.into())
}

/// Outward unit-cube faces of the filled voxels that border empty ones.
fn voxel_mesh(
    filled: &dyn Fn(i64, i64, i64) -> bool,
    n: i64,
    size: i64,
    at: i64,
) -> Vec<[IntPoint; 3]> {
    let mut out = Vec::new();
    for x in 0..n {
        for y in 0..n {
            for z in 0..n {
                if !filled(x, y, z) {
                    continue;
                }
                for axis in 0..3 {
                    for dir in [-1i64, 1] {
                        let mut nb = [x, y, z];
                        nb[axis] += dir;
                        if filled(nb[0], nb[1], nb[2]) {
                            continue;
                        }
                        // The face's four corners, counter-clockwise from
                        // outside.
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        let mut base = [x, y, z];
                        if dir > 0 {
                            base[axis] += 1;
                        }
                        let corner = |du: i64, dv: i64| {
                            let mut c = base;
                            c[u] += du;
                            c[v] += dv;
                            p(at + c[0] * size, at + c[1] * size, at + c[2] * size)
                        };
                        let q = if dir > 0 {
                            [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        } else {
                            [corner(0, 0), corner(0, 1), corner(1, 1), corner(1, 0)]
                        };
                        out.push([q[0], q[1], q[2]]);
                        out.push([q[0], q[2], q[3]]);
                    }
                }
            }
        }
    }
    out
}

#[test]
fn a_box_imports_with_its_exact_volume() {
    let filled =
        |x: i64, y: i64, z: i64| (0..1).contains(&x) && (0..1).contains(&y) && (0..1).contains(&z);
    let mesh = voxel_mesh(&filled, 1, 300, 100);
    for budget in [2, 4, 150] {
        let octree = Octree::from_triangles([0; 3], K, &mesh, 1, config(budget)).unwrap();
        assert_eq!(
            solid_volume(&octree),
            int(300 * 300 * 300),
            "budget {budget}"
        );
    }
}

#[test]
fn random_voxel_solids_import_exactly() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for case in 0..12 {
        let n = 6;
        let cells: Vec<bool> = (0..n * n * n).map(|_| rng.random_bool(0.45)).collect();
        let filled = |x: i64, y: i64, z: i64| {
            (0..n).contains(&x)
                && (0..n).contains(&y)
                && (0..n).contains(&z)
                && cells[(x * n * n + y * n + z) as usize]
        };
        let count = cells.iter().filter(|&&c| c).count() as i64;
        let size = rng.random_range(20..120);
        let at = rng.random_range(0..(1 << K) - n * size);
        let mesh = voxel_mesh(&filled, n, size, at);
        let octree = Octree::from_triangles([0; 3], K, &mesh, 1, config(12)).unwrap();
        assert_eq!(
            solid_volume(&octree),
            int(count * size * size * size),
            "case {case}"
        );
        assert!(octree.stats().leaves > 1);
    }
}

#[test]
fn convex_hulls_import_with_the_volume_of_their_bsp() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for case in 0..20 {
        // Integer-cornered convex solids: hulls of random integer points.
        let pts: Vec<IntPoint> = (0..12)
            .map(|_| {
                p(
                    rng.random_range(100..900),
                    rng.random_range(100..900),
                    rng.random_range(100..900),
                )
            })
            .collect();
        let mut arena = ConvexArena::new();
        let Ok(hull) = chisel_bsp::tools::convex_hull(&mut arena, &pts) else {
            continue;
        };
        let expected = volume(&arena, hull);
        let mut mesh = Vec::new();
        for f in arena.faces_of(hull) {
            let corners: Vec<IntPoint> = arena
                .face_loop(f)
                .map(|h| {
                    let q = arena.position(arena.half_edges()[h as usize].origin);
                    p(q[0] as i64, q[1] as i64, q[2] as i64)
                })
                .collect();
            for k in 1..corners.len() - 1 {
                mesh.push([corners[0], corners[k], corners[k + 1]]);
            }
        }
        let octree = Octree::from_triangles([0; 3], K, &mesh, 3, config(6)).unwrap();
        assert_eq!(solid_volume(&octree), expected, "case {case}");
    }
}

#[test]
fn open_or_misoriented_meshes_are_errors() {
    let filled = |x: i64, y: i64, z: i64| x == 0 && y == 0 && z == 0;
    let mesh = voxel_mesh(&filled, 1, 100, 50);
    let mut open = mesh.clone();
    open.pop();
    assert!(matches!(
        Octree::from_triangles([0; 3], K, &open, 1, config(150)),
        Err(Error::NotWatertight { .. })
    ));
    let mut flipped = mesh.clone();
    flipped[3].swap(1, 2);
    let err = Octree::from_triangles([0; 3], K, &flipped, 1, config(150)).unwrap_err();
    assert!(matches!(err, Error::NotWatertight { open_edges, .. } if open_edges > 0));
    assert!(err.to_string().contains("not watertight"));
    let outside = voxel_mesh(&filled, 1, 100, (1 << K) - 50);
    assert!(matches!(
        Octree::from_triangles([0; 3], K, &outside, 1, config(150)),
        Err(Error::OutsideOctree { .. })
    ));
}

#[test]
fn self_intersecting_meshes_are_errors() {
    let cube =
        |x: i64, y: i64, z: i64| (0..1).contains(&x) && (0..1).contains(&y) && (0..1).contains(&z);
    let a = voxel_mesh(&cube, 1, 200, 100);
    // Two closed boxes that interpenetrate.
    let mut two = a.clone();
    two.extend(voxel_mesh(&cube, 1, 200, 200));
    let err = Octree::from_triangles([0; 3], K, &two, 1, config(150)).unwrap_err();
    assert!(matches!(err, Error::SelfIntersecting { .. }), "{err}");
    assert!(err.to_string().contains("intersects itself"));
    // Apart, they are fine.
    let mut apart = a.clone();
    apart.extend(voxel_mesh(&cube, 1, 200, 400));
    let octree = Octree::from_triangles([0; 3], K, &apart, 1, config(150)).unwrap();
    assert_eq!(solid_volume(&octree), int(2 * 200 * 200 * 200));
    // A corner pushed through the opposite face: still closed, but folded.
    let corner = p(300, 300, 300);
    let folded: Vec<[IntPoint; 3]> = a
        .iter()
        .map(|t| t.map(|q| if q == corner { p(300, 300, 50) } else { q }))
        .collect();
    assert!(matches!(
        Octree::from_triangles([0; 3], K, &folded, 1, config(150)),
        Err(Error::SelfIntersecting { .. })
    ));
}

#[test]
fn quantization_rounds_and_rejects_bad_input() {
    let q = Quantization::new(0.001, [1.0, 2.0, 3.0]).unwrap();
    assert_eq!(
        q.to_grid([1.0015, 2.0, 2.9994]).unwrap().coords(),
        [2, 0, -1]
    );
    assert_eq!(q.to_world([1000.0, 0.0, 0.0]), [2.0, 2.0, 3.0]);
    assert!(matches!(
        q.to_grid([f64::NAN, 0.0, 0.0]),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        q.to_grid([1e9, 0.0, 0.0]),
        Err(Error::CoordinateOutOfRange { .. })
    ));
    assert!(matches!(
        Quantization::new(0.0, [0.0; 3]),
        Err(Error::InvalidUnit { .. })
    ));
    assert!(matches!(
        Quantization::new(f64::INFINITY, [0.0; 3]),
        Err(Error::InvalidUnit { .. })
    ));
}
