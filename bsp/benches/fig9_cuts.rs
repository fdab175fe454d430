//! A fixed driver of the Figure 9 extraction of paper 1 for instruction
//! counting: the cell of a linear BSP of `N` planes tangent to a sphere
//! (the box cut by each plane in turn, keeping the part below), the same
//! planes as `benches/cut.rs`, repeated `R` times in one reused arena.
//!
//! ```sh
//! cargo bench -p chisel_bsp --bench fig9_cuts -- two 250 10
//! cargo bench -p chisel_bsp --bench fig9_cuts --no-run   # prints the binary's path
//! valgrind --tool=callgrind target/release/deps/fig9_cuts-HASH --bench two 250 10
//! ```
//!
//! It runs only with `--bench` among its arguments (`cargo bench` passes
//! it; `cargo test --all-targets` does not, and then it prints one line
//! and exits). Arguments after the flags: `two` (both parts built, [`ConvexArena::cut`]), `one`
//! ([`ConvexArena::cut_keeping`]) or `naive` (both parts, every vertex
//! classified, [`ConvexArena::cut_naive`]), the number of planes `N` (250)
//! and the repetitions `R` (10; at least 1). Instructions per cut are the difference between
//! two runs with different `R`, divided by `N` times the difference of `R`
//! (that removes the fixed start-up cost). It prints a checksum of the
//! cell's vertices so that two builds can be compared, and what a cut
//! takes on average (Figure 9's measures, [`ConvexArena::last_cut_stats`]):
//! vertices classified, edge-descent steps and exact vertex constructions.

#[path = "../tests/it/common/fig9.rs"]
mod fig9;

use chisel_bsp::convex::{ConvexArena, CutOutcome, CutStats, KeptOutcome, NO_TAG, Part, PolyId};
use chisel_bsp::exact::{IntPoint, Plane};
use fig9::{R, tangent_planes};

/// How the cell is cut.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    TwoSided,
    OneSided,
    Naive,
}

/// What the cuts of one extraction took in all.
#[derive(Default)]
struct Totals {
    stats: CutStats,
    constructions: usize,
}

/// The cell of the linear BSP of `planes` in `arena` (cleared first); with
/// `totals`, also what the cuts took (counting scans the arena after each
/// cut, so the timed rounds go without).
fn extract_cell(
    arena: &mut ConvexArena,
    planes: &[Plane],
    mode: Mode,
    mut totals: Option<&mut Totals>,
) -> PolyId {
    arena.clear();
    let corner = |c| IntPoint::new(c, c, c).expect("in budget");
    let mut poly = arena.add_box(corner(-R), corner(R)).expect("a box");
    for plane in planes {
        let points_before = arena.point_count();
        let below = match mode {
            Mode::TwoSided => match arena.cut(poly, plane, NO_TAG, NO_TAG) {
                CutOutcome::Split { below, .. } => Some(below),
                _ => None,
            },
            Mode::Naive => match arena.cut_naive(poly, plane, NO_TAG, NO_TAG) {
                CutOutcome::Split { below, .. } => Some(below),
                _ => None,
            },
            Mode::OneSided => match arena.cut_keeping(poly, plane, Part::Below, NO_TAG) {
                KeptOutcome::Cut(below) => Some(below),
                _ => None,
            },
        };
        if let Some(totals) = totals.as_deref_mut() {
            let stats = arena.last_cut_stats();
            totals.stats.classified += stats.classified;
            totals.stats.descent_steps += stats.descent_steps;
            totals.constructions += arena.point_count() - points_before;
        }
        if let Some(below) = below {
            poly = below;
        }
    }
    poly
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !args.iter().any(|a| a == "--bench") {
        println!("fig9_cuts: not run as a benchmark (no --bench argument); skipped");
        return;
    }
    // The positional arguments, after cargo's flags are set aside.
    let args: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let mode = match args.first().copied() {
        Some("one") => Mode::OneSided,
        Some("naive") => Mode::Naive,
        _ => Mode::TwoSided,
    };
    let count = args.get(1).and_then(|n| n.parse().ok()).unwrap_or(250);
    let repeats: usize = args.get(2).and_then(|n| n.parse().ok()).unwrap_or(10);
    // Seeded by the count, as in `benches/cut.rs`.
    let planes = tangent_planes(count, count as u64);
    let mut arena = ConvexArena::new();
    let mut totals = Totals::default();
    extract_cell(&mut arena, &planes, mode, Some(&mut totals));
    let mut poly = PolyId(0);
    for _ in 0..repeats.max(1) {
        poly = extract_cell(&mut arena, &planes, mode, None);
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
    let name = match mode {
        Mode::TwoSided => "two-sided",
        Mode::OneSided => "one-sided",
        Mode::Naive => "naive",
    };
    println!("{name}, {count} planes x {repeats}: {faces} faces, checksum {checksum:016x}");
    let per_cut = |total: usize| total as f64 / count as f64;
    println!(
        "per cut: {:.1} vertices classified, {:.2} descent steps, {:.2} vertex constructions",
        per_cut(totals.stats.classified),
        per_cut(totals.stats.descent_steps as usize),
        per_cut(totals.constructions),
    );
}
