//! A fixed driver of the Figure 9 extraction of paper 1 for instruction
//! counting: the cell of a linear BSP of `N` planes tangent to a sphere
//! (the box cut by each plane in turn, keeping the part below), the same
//! planes as `benches/cut.rs`, repeated `R` times in one reused arena.
//!
//! ```sh
//! cargo build --profile bench -p chisel_bsp --example fig9_cuts
//! valgrind --tool=callgrind target/release/examples/fig9_cuts two 250 10
//! ```
//!
//! Arguments: `two` (both parts built, [`ConvexArena::cut`]) or `one`
//! ([`ConvexArena::cut_keeping`]), the number of planes `N` (250) and the
//! repetitions `R` (10; at least 1). Instructions per cut are the difference between
//! two runs with different `R`, divided by `N` times the difference of `R`
//! (that removes the fixed start-up cost). It prints a checksum of the
//! cell's vertices so that two builds can be compared.

#[path = "../tests/common/fig9.rs"]
mod fig9;

use chisel_bsp::convex::{ConvexArena, CutOutcome, KeptOutcome, NO_TAG, Part, PolyId};
use chisel_bsp::exact::{IntPoint, Plane};
use fig9::{R, tangent_planes};

/// The cell of the linear BSP of `planes` in `arena` (cleared first).
fn extract_cell(arena: &mut ConvexArena, planes: &[Plane], two_sided: bool) -> PolyId {
    arena.clear();
    let corner = |c| IntPoint::new(c, c, c).expect("in budget");
    let mut poly = arena.add_box(corner(-R), corner(R)).expect("a box");
    for plane in planes {
        let below = if two_sided {
            match arena.cut(poly, plane, NO_TAG, NO_TAG) {
                CutOutcome::Split { below, .. } => Some(below),
                _ => None,
            }
        } else {
            match arena.cut_keeping(poly, plane, Part::Below, NO_TAG) {
                KeptOutcome::Cut(below) => Some(below),
                _ => None,
            }
        };
        if let Some(below) = below {
            poly = below;
        }
    }
    poly
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let two_sided = args.get(1).is_none_or(|m| m != "one");
    let count = args.get(2).and_then(|n| n.parse().ok()).unwrap_or(250);
    let repeats: usize = args.get(3).and_then(|n| n.parse().ok()).unwrap_or(10);
    // Seeded by the count, as in `benches/cut.rs`.
    let planes = tangent_planes(count, count as u64);
    let mut arena = ConvexArena::new();
    let mut poly = extract_cell(&mut arena, &planes, two_sided);
    for _ in 1..repeats {
        poly = extract_cell(&mut arena, &planes, two_sided);
    }
    let (cell, _) = arena.extract(poly);
    let faces = cell.faces().len();
    let mut checksum = faces as u64;
    for v in 0..cell.vertex_count() as u32 {
        let point = cell.point(v);
        let [x, y, z] = point.xyz();
        for limb in [x, y, z]
            .iter()
            .flat_map(|c| c.limbs())
            .chain(point.w().limbs())
        {
            checksum = checksum.rotate_left(7) ^ limb.wrapping_mul(0x9e37_79b9_7f4a_7c15);
        }
    }
    let mode = if two_sided { "two-sided" } else { "one-sided" };
    println!("{mode}, {count} planes x {repeats}: {faces} faces, checksum {checksum:016x}");
}
