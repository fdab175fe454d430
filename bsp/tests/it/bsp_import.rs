//! BSPs from closed triangle soups: the imported solid has exactly the
//! volume of the mesh, for any insertion order, and the same seed gives the
//! identical tree.

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::exact::IntPoint;
use chisel_bsp::tools::convex_hull;
use chisel_bsp::tree::{Bsp, EMPTY};
use common::volume::{Fraction, volume};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const H: i64 = 1 << 20;

fn p(x: i64, y: i64, z: i64) -> IntPoint {
    IntPoint::new(x, y, z).unwrap()
}

/// The faces of `poly` (integer vertices) as a fan-triangulated soup.
fn triangles(arena: &ConvexArena, poly: PolyId) -> Vec<[IntPoint; 3]> {
    let mut out = Vec::new();
    for f in arena.faces_of(poly) {
        let corners: Vec<IntPoint> = arena
            .face_loop(f)
            .map(|h| {
                let [x, y, z] = arena.position(arena.half_edges()[h as usize].origin);
                p(x as i64, y as i64, z as i64)
            })
            .collect();
        for k in 1..corners.len() - 1 {
            out.push([corners[0], corners[k], corners[k + 1]]);
        }
    }
    out
}

fn solid_volume(bsp: &Bsp) -> Fraction {
    bsp.validate().unwrap();
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(-H, -H, -H), p(H, H, H)).unwrap();
    let mut total = Fraction::zero();
    for cell in bsp.cells(&mut arena, bounds) {
        if cell.label != EMPTY {
            total = total.add(&volume(&arena, cell.poly));
        }
    }
    total
}

#[test]
fn a_cube_soup_imports_to_the_cube() {
    let mut arena = ConvexArena::new();
    let cube = arena.add_box(p(0, 0, 0), p(10, 10, 10)).unwrap();
    let soup = triangles(&arena, cube);
    assert_eq!(soup.len(), 12);
    for seed in 0..5 {
        let bsp = Bsp::from_triangles(&soup, 4, seed).unwrap();
        assert_eq!(solid_volume(&bsp).num, 1000.into());
        assert!(
            bsp.nodes().len() <= 2 * 6 + 1,
            "coplanar triangles share one node"
        );
    }
}

#[test]
fn convex_hull_soups_keep_their_exact_volume_in_any_order() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    for _ in 0..15 {
        let r = 1 << 16;
        let points: Vec<IntPoint> = (0..30)
            .map(|_| {
                p(
                    rng.random_range(-r..r),
                    rng.random_range(-r..r),
                    rng.random_range(-r..r),
                )
            })
            .collect();
        let mut arena = ConvexArena::new();
        let hull = convex_hull(&mut arena, &points).unwrap();
        let expected = volume(&arena, hull);
        let soup = triangles(&arena, hull);
        for seed in [1, 2] {
            let bsp = Bsp::from_triangles(&soup, 1, seed).unwrap();
            assert_eq!(solid_volume(&bsp), expected);
        }
        assert_eq!(
            Bsp::from_triangles(&soup, 1, 9).unwrap(),
            Bsp::from_triangles(&soup, 1, 9).unwrap()
        );
    }
}

#[test]
fn two_disjoint_solids() {
    let mut arena = ConvexArena::new();
    let a = arena.add_box(p(0, 0, 0), p(10, 10, 10)).unwrap();
    let b = arena.add_box(p(20, 0, 0), p(30, 5, 5)).unwrap();
    let mut soup = triangles(&arena, a);
    soup.extend(triangles(&arena, b));
    let bsp = Bsp::from_triangles(&soup, 2, 3).unwrap();
    assert_eq!(solid_volume(&bsp).num, (1000 + 250).into());
}
