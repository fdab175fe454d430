//! The boundary of a BSP solid: it encloses exactly the solid's volume, and
//! faces between solid cells are gone (the surface area is the solid's).

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::tree::{BooleanOp, Bsp, EMPTY};
use common::shapes::{self, p};
use common::volume::{Fraction, polygons_volume, volume};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const H: i64 = 1 << 16;
const CUTS: usize = 5;

fn bounds(arena: &mut ConvexArena) -> PolyId {
    arena.add_box(p(-H, -H, -H), p(H, H, H)).unwrap()
}

fn box_bsp(min: [i64; 3], max: [i64; 3]) -> Bsp {
    let mut arena = ConvexArena::new();
    let b = arena
        .add_box(p(min[0], min[1], min[2]), p(max[0], max[1], max[2]))
        .unwrap();
    Bsp::from_convex(&arena, b, 1)
}

fn solid_volume(bsp: &Bsp) -> Fraction {
    let mut arena = ConvexArena::new();
    let b = bounds(&mut arena);
    let mut total = Fraction::zero();
    for cell in bsp.cells(&mut arena, b) {
        if cell.label != EMPTY {
            total = total.add(&volume(&arena, cell.poly));
        }
    }
    total
}

fn boundary_polygons(bsp: &Bsp) -> Vec<Vec<chisel_bsp::exact::Point4>> {
    let mut arena = ConvexArena::new();
    let b = bounds(&mut arena);
    bsp.boundary(&mut arena, b)
        .into_iter()
        .map(|f| f.vertices)
        .collect()
}

fn area(polygons: &[Vec<chisel_bsp::exact::Point4>]) -> f64 {
    polygons
        .iter()
        .map(|poly| {
            let pts: Vec<[f64; 3]> = poly.iter().map(|v| v.to_f64()).collect();
            let mut n = [0.0; 3];
            for k in 1..pts.len() - 1 {
                let (a, b, c) = (pts[0], pts[k], pts[k + 1]);
                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                n[0] += u[1] * v[2] - u[2] * v[1];
                n[1] += u[2] * v[0] - u[0] * v[2];
                n[2] += u[0] * v[1] - u[1] * v[0];
            }
            0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
        })
        .sum()
}

#[test]
fn the_union_of_two_overlapping_boxes_has_no_interior_faces() {
    let a = box_bsp([0, 0, 0], [10, 10, 10]);
    let b = box_bsp([5, 0, 0], [15, 10, 10]);
    let mut arena = ConvexArena::new();
    let bd = bounds(&mut arena);
    let union = a.merge(&b, BooleanOp::Union, &mut arena, bd);
    let faces = boundary_polygons(&union);
    assert_eq!(polygons_volume(&faces).num, 1500.into());
    // The union is the box [0,15]×[0,10]²: area 2·(150 + 150 + 100).
    assert!((area(&faces) - 800.0).abs() < 1e-9, "area {}", area(&faces));
}

#[test]
fn boundaries_enclose_exactly_the_solid_volume() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let convex =
        |rng: &mut ChaCha8Rng| shapes::random_convex_bsp(rng, 1, H / 4, (H / 8, H / 3), CUTS);
    for _ in 0..15 {
        let (a, b) = (convex(&mut rng), convex(&mut rng));
        for single in [&a, &b] {
            let faces = boundary_polygons(single);
            assert_eq!(
                polygons_volume(&faces),
                solid_volume(single),
                "a single convex BSP"
            );
        }
        for op in [
            BooleanOp::Union,
            BooleanOp::Difference,
            BooleanOp::Intersection,
        ] {
            let mut arena = ConvexArena::new();
            let bd = bounds(&mut arena);
            let result = a.merge(&b, op, &mut arena, bd);
            let faces = boundary_polygons(&result);
            assert_eq!(polygons_volume(&faces), solid_volume(&result), "{op:?}");
        }
    }
}
