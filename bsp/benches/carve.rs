//! One carve on a well-used workpiece (`chisel cheese`, paper 1 §5):
//! a random dodecahedron subtracted from a block that already took
//! `PRIOR` carves, with and without re-extracting the changed cells'
//! surfaces.
//!
//! `cargo bench -p chisel_bsp --bench carve`. Units: 1 µm grid, block
//! `[0, 100 mm]³`, dodecahedra of scale 2–5 mm centred in the top 40 mm.
//! Each iteration applies to a clone of the same workpiece (cloning is a
//! pointer copy), so every measured carve sees the same history.

use std::hint::black_box;

use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const MM: f64 = 1000.0;
const PRIOR: usize = 300;

fn dodecahedron(rng: &mut ChaCha8Rng) -> Tool {
    let scale = rng.random_range(2.0..5.0) * MM;
    let (a, b, c) = (
        rng.random_range(0.0..std::f64::consts::TAU),
        rng.random_range(0.0..std::f64::consts::TAU),
        rng.random_range(0.0..std::f64::consts::TAU),
    );
    let (ca, sa, cb, sb, cc, sc) = (a.cos(), a.sin(), b.cos(), b.sin(), c.cos(), c.sin());
    // Rz(a)·Rx(b)·Rz(c).
    let rotation = [
        [ca * cc - sa * cb * sc, -ca * sc - sa * cb * cc, sa * sb],
        [sa * cc + ca * cb * sc, -sa * sc + ca * cb * cc, -ca * sb],
        [sb * sc, sb * cc, cb],
    ];
    let pose = Pose {
        rotation,
        translation: [
            rng.random_range(0.0..100.0) * MM,
            rng.random_range(0.0..100.0) * MM,
            rng.random_range(60.0..100.0) * MM,
        ],
    };
    Tool::placed(&dodecahedron_corners(scale), &pose).expect("tools are in range")
}

fn carve(c: &mut Criterion) {
    let block = CellBox {
        min: [0; 3],
        max: [100_000; 3],
    };
    let mut octree =
        Octree::from_box([0; 3], 17, block, 1, OctreeConfig::default()).expect("a block");
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..PRIOR {
        octree
            .apply(&dodecahedron(&mut rng), Edit::Subtract)
            .expect("carves");
    }
    let tools: Vec<Tool> = (0..64).map(|_| dodecahedron(&mut rng)).collect();
    let mut group = c.benchmark_group("carve");
    group.sample_size(30);
    let mut k = 0;
    group.bench_function("apply", |b| {
        b.iter_batched(
            || {
                k = (k + 1) % tools.len();
                (octree.clone(), &tools[k])
            },
            |(mut o, tool)| black_box(o.apply(tool, Edit::Subtract).expect("carves")),
            BatchSize::SmallInput,
        );
    });
    group.bench_function("apply_and_surface", |b| {
        b.iter_batched(
            || {
                k = (k + 1) % tools.len();
                (octree.clone(), &tools[k])
            },
            |(mut o, tool)| {
                let changes = o.apply(tool, Edit::Subtract).expect("carves");
                let faces: usize = changes
                    .changed
                    .iter()
                    .map(|&key| o.cell_surface(key).len())
                    .sum();
                black_box(faces)
            },
            BatchSize::SmallInput,
        );
    });
    group.finish();
    let stats = octree.stats();
    eprintln!(
        "workpiece after {PRIOR} carves: {} leaves ({} with a BSP), {} BSP nodes, depth {}",
        stats.leaves, stats.bsp_leaves, stats.bsp_nodes, stats.depth
    );
}

criterion_group!(benches, carve);
criterion_main!(benches);
