//! Figure 10 of paper 1: Booleans of random BSPs, output nodes per second.
//!
//! `cargo bench -p chisel_bsp --bench merge`. Two kinds of operands, each
//! merged inside their bounding box; the reported throughput is output BSP
//! nodes per second:
//!
//! - `random` — the paper's random BSPs: split the leaf holding a random
//!   point of the cube by a plane through that point in a random direction,
//!   until the tree has `N` inner nodes; leaves are randomly solid or empty.
//!   `random/pairs` merges 40 fixed pairs with sizes drawn from 1–200 and a
//!   random operation each (union, intersection or difference), the setting
//!   of the paper's Figure 10, and reports their total output over their
//!   total time.
//! - `convex` — unions of random convex polyhedra (linear BSPs) grown to
//!   about `N` nodes: solids that look like terrain cells, whose merges keep
//!   their output close to linear in the input.
//!
//! Each case is merged two ways, named in its id: `pruned` ([`Bsp::merge`],
//! which cuts `B` into every cell of `A` and keeps only planes that cut)
//! and `grafted` ([`Bsp::merge_grafted`], the paper's merge, which copies
//! `B` whole into those cells, as the paper's figure counts output nodes).

#[path = "../tests/it/common/random_bsp.rs"]
mod random_bsp;

use std::hint::black_box;

use chisel_bsp::convex::{ConvexArena, CutOutcome, NO_TAG};
use chisel_bsp::exact::{IntPoint, plane_from_points};
use chisel_bsp::tree::{BooleanOp, Bsp};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const H: i64 = 1 << 16;

fn p(x: i64, y: i64, z: i64) -> IntPoint {
    IntPoint::new(x, y, z).expect("in budget")
}

fn random_convex(rng: &mut ChaCha8Rng) -> Bsp {
    let mut arena = ConvexArena::new();
    let c = [0; 3].map(|_| rng.random_range(-H / 2..H / 2));
    let r = rng.random_range(H / 8..H / 3);
    let mut poly = arena
        .add_box(
            p(c[0] - r, c[1] - r, c[2] - r),
            p(c[0] + r, c[1] + r, c[2] + r),
        )
        .expect("a box");
    let mut q = || {
        p(
            c[0] + rng.random_range(-r..r),
            c[1] + rng.random_range(-r..r),
            c[2] + rng.random_range(-r..r),
        )
    };
    for _ in 0..4 {
        let Ok(s) = plane_from_points(q(), q(), q()) else {
            continue;
        };
        if let CutOutcome::Split { below, .. } = arena.cut(poly, &s.normalized(), NO_TAG, NO_TAG) {
            poly = below;
        }
    }
    Bsp::from_convex(&arena, poly, 1)
}

/// The merge of `A` and `B` inside the bounding box, one way.
type Merge = fn(&Bsp, &Bsp, BooleanOp) -> Bsp;

fn pruned_merge(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(-H, -H, -H), p(H, H, H)).expect("a box");
    a.merge(b, op, &mut arena, bounds)
}

fn grafted_merge(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(-H, -H, -H), p(H, H, H)).expect("a box");
    a.merge_grafted(b, op, &mut arena, bounds)
}

const MERGES: [(&str, Merge); 2] = [("pruned", pruned_merge), ("grafted", grafted_merge)];

/// A union of random convex polyhedra with at least `nodes` nodes.
fn random_bsp(rng: &mut ChaCha8Rng, nodes: usize) -> Bsp {
    let mut bsp = random_convex(rng);
    while bsp.nodes().len() < nodes {
        bsp = pruned_merge(&bsp, &random_convex(rng), BooleanOp::Union);
    }
    bsp
}

/// A random BSP of the paper's Figure 10 with `splits` inner nodes,
/// solid or empty leaves.
fn paper_random_bsp(rng: &mut ChaCha8Rng, splits: usize) -> Bsp {
    random_bsp::paper_random_bsp(rng, splits, 2, H)
}

const OPS: [(&str, BooleanOp); 3] = [
    ("union", BooleanOp::Union),
    ("intersection", BooleanOp::Intersection),
    ("difference", BooleanOp::Difference),
];

/// The paper's setting: random BSPs of 1–200 inner nodes.
fn figure10_random(c: &mut Criterion) {
    let mut group = c.benchmark_group("random");
    group.sample_size(20);
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for splits in [10, 50, 200] {
        let (a, b) = (
            paper_random_bsp(&mut rng, splits),
            paper_random_bsp(&mut rng, splits),
        );
        for (name, op) in OPS {
            for (way, merge) in MERGES {
                let out = merge(&a, &b, op).nodes().len();
                group.throughput(Throughput::Elements(out as u64));
                let (na, nb) = (a.nodes().len(), b.nodes().len());
                let id = format!("{name}/{way}/{na}+{nb}->{out}");
                group.bench_function(BenchmarkId::from_parameter(id), |bench| {
                    bench.iter(|| black_box(merge(&a, &b, op)))
                });
            }
        }
    }
    let pairs: Vec<(Bsp, Bsp, BooleanOp)> = (0..40)
        .map(|_| {
            let a = rng.random_range(1..=200);
            let b = rng.random_range(1..=200);
            let op = OPS[rng.random_range(0..OPS.len())].1;
            (
                paper_random_bsp(&mut rng, a),
                paper_random_bsp(&mut rng, b),
                op,
            )
        })
        .collect();
    let input: usize = pairs
        .iter()
        .map(|(a, b, _)| a.nodes().len() + b.nodes().len())
        .sum();
    for (way, merge) in MERGES {
        let out: usize = pairs
            .iter()
            .map(|(a, b, op)| merge(a, b, *op).nodes().len())
            .sum();
        group.throughput(Throughput::Elements(out as u64));
        let id = format!("pairs/{way}/40 pairs, {input}->{out}");
        group.bench_function(BenchmarkId::from_parameter(id), |bench| {
            bench.iter(|| {
                for (a, b, op) in &pairs {
                    black_box(merge(a, b, *op));
                }
            })
        });
    }
    group.finish();
}

/// Unions of random convex polyhedra.
fn figure10_convex(c: &mut Criterion) {
    let mut group = c.benchmark_group("convex");
    group.sample_size(20);
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for nodes in [10, 50, 200] {
        let (a, b) = (random_bsp(&mut rng, nodes), random_bsp(&mut rng, nodes));
        for (name, op) in [
            ("union", BooleanOp::Union),
            ("difference", BooleanOp::Difference),
        ] {
            for (way, merge) in MERGES {
                let out = merge(&a, &b, op).nodes().len();
                group.throughput(Throughput::Elements(out as u64));
                let (na, nb) = (a.nodes().len(), b.nodes().len());
                let id = format!("{name}/{way}/{na}+{nb}->{out}");
                group.bench_function(BenchmarkId::from_parameter(id), |bench| {
                    bench.iter(|| black_box(merge(&a, &b, op)))
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, figure10_random, figure10_convex);
criterion_main!(benches);
