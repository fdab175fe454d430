//! Figure 10 of paper 1: Booleans of random BSPs, output nodes per second.
//!
//! `cargo bench -p chisel_bsp --bench merge`. Operands are unions of random
//! convex polyhedra (each a linear BSP) grown to about `N` nodes; each
//! measured operation merges two of them inside their bounding box. The
//! reported throughput is output BSP nodes per second.

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

fn merged(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(-H, -H, -H), p(H, H, H)).expect("a box");
    a.merge(b, op, &mut arena, bounds)
}

/// A union of random convex polyhedra with at least `nodes` nodes.
fn random_bsp(rng: &mut ChaCha8Rng, nodes: usize) -> Bsp {
    let mut bsp = random_convex(rng);
    while bsp.nodes().len() < nodes {
        bsp = merged(&bsp, &random_convex(rng), BooleanOp::Union);
    }
    bsp
}

fn figure10(c: &mut Criterion) {
    let mut group = c.benchmark_group("merge");
    group.sample_size(20);
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for nodes in [10, 50, 200] {
        let (a, b) = (random_bsp(&mut rng, nodes), random_bsp(&mut rng, nodes));
        for (name, op) in [
            ("union", BooleanOp::Union),
            ("difference", BooleanOp::Difference),
        ] {
            let out = merged(&a, &b, op).nodes().len();
            group.throughput(Throughput::Elements(out as u64));
            let id = format!("{name}/{}+{}->{out}", a.nodes().len(), b.nodes().len());
            group.bench_function(BenchmarkId::from_parameter(id), |bench| {
                bench.iter(|| black_box(merged(&a, &b, op)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, figure10);
criterion_main!(benches);
