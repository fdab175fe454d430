//! The exact convex hull of recorded tools: the 72 points of a swept
//! 18-sided cutter (`chisel cutter --path helix --sides 18`, its first 8
//! steps) and the 40 points of the fluted bit's swept core (`chisel
//! fluted`, 8 steps), from `data/hull_tools.txt` (1 µm grid).
//!
//! ```sh
//! cargo bench -p chisel_bsp --bench hull                 # criterion
//! cargo bench -p chisel_bsp --bench hull -- count 100 [helix72|fluted40]  # the driver
//! cargo bench -p chisel_bsp --bench hull --no-run        # prints the binary's path
//! valgrind --tool=callgrind target/release/deps/hull-HASH --bench count 100 helix72
//! ```
//!
//! Criterion times, per tool, [`Tool::convex_hull`] (the hull with the
//! tool's BSP and contact piece, what a `chisel cutter` step builds) and
//! [`convex_hull`] into a reused arena (the hull alone).
//!
//! With `count R [LABEL]` among the arguments it runs no criterion: it
//! builds every recorded tool (or those labelled `LABEL`) `R` times both
//! ways and prints a hash of every
//! result (equal hashes before and after a change mean the same faces,
//! order, planes, BSP and contact data). Instructions per tool are the
//! difference between two runs with different `R`, divided by the
//! difference of `R` and the number of tools (that removes start-up).

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::hint::black_box;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::Tool;
use chisel_bsp::tools::convex_hull;
use criterion::Criterion;

/// The recorded tools: a label (`helix72`, `fluted40`) and the points.
fn recorded_tools() -> Vec<(&'static str, Vec<IntPoint>)> {
    include_str!("data/hull_tools.txt")
        .lines()
        .filter(|line| !line.starts_with('#') && !line.trim().is_empty())
        .map(|line| {
            let mut words = line.split_whitespace();
            let label = words.next().expect("a label");
            let points = words
                .map(|p| {
                    let c: Vec<i64> = p
                        .split(',')
                        .map(|x| x.parse().expect("an integer"))
                        .collect();
                    IntPoint::new(c[0], c[1], c[2]).expect("in budget")
                })
                .collect();
            (label, points)
        })
        .collect()
}

/// A hash of everything a tool holds, and of the hull's polyhedron.
fn result_hash(points: &[IntPoint], arena: &mut ConvexArena) -> u64 {
    let mut hasher = DefaultHasher::new();
    let tool = Tool::convex_hull(points).expect("a solid");
    format!("{tool:?}").hash(&mut hasher);
    arena.clear();
    let poly = convex_hull(arena, points).expect("a solid");
    for f in arena.faces_of(poly) {
        format!("{:?}", arena.face_plane(f)).hash(&mut hasher);
        for h in arena.face_loop(f) {
            let v = arena.half_edges()[h as usize].origin;
            (v, format!("{:?}", arena.point(v))).hash(&mut hasher);
        }
    }
    hasher.finish()
}

/// The driver: every tool (or those labelled `only`) `rounds` times both
/// ways, then the hashes of all.
fn count(rounds: usize, only: Option<&str>) {
    let tools = recorded_tools();
    let mut arena = ConvexArena::new();
    for _ in 0..rounds {
        for (_, points) in tools.iter().filter(|(l, _)| only.is_none_or(|o| o == *l)) {
            black_box(Tool::convex_hull(black_box(points)).expect("a solid"));
            arena.clear();
            black_box(convex_hull(&mut arena, black_box(points)).expect("a solid"));
        }
    }
    for label in ["helix72", "fluted40"] {
        let mut hasher = DefaultHasher::new();
        for (_, points) in tools.iter().filter(|(l, _)| *l == label) {
            result_hash(points, &mut arena).hash(&mut hasher);
        }
        println!("{label}: hash {:016x}", hasher.finish());
    }
}

fn criterion_benches(c: &mut Criterion) {
    let tools = recorded_tools();
    for label in ["helix72", "fluted40"] {
        let set: Vec<&Vec<IntPoint>> = tools
            .iter()
            .filter(|(l, _)| *l == label)
            .map(|(_, p)| p)
            .collect();
        let mut next = 0;
        c.bench_function(&format!("hull/tool/{label}"), |b| {
            b.iter(|| {
                next = (next + 1) % set.len();
                Tool::convex_hull(black_box(set[next])).expect("a solid")
            });
        });
        let mut arena = ConvexArena::new();
        c.bench_function(&format!("hull/polyhedron/{label}"), |b| {
            b.iter(|| {
                next = (next + 1) % set.len();
                arena.clear();
                convex_hull(&mut arena, black_box(set[next])).expect("a solid")
            });
        });
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if !args.iter().any(|a| a == "--bench") {
        println!("hull: run with `cargo bench` (see the file's docs)");
        return;
    }
    if let Some(i) = args.iter().position(|a| a == "count") {
        let rounds = args.get(i + 1).and_then(|r| r.parse().ok()).unwrap_or(100);
        count(rounds, args.get(i + 2).map(String::as_str));
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    criterion_benches(&mut c);
    c.final_summary();
}
