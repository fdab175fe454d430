//! Figure 9 of paper 1: plane cuts of a convex polyhedron with 50…2,000
//! faces, edge descent and marching against classify-all-vertices.
//!
//! `cargo bench -p chisel_bsp --bench cut`. Two settings:
//! - `extract_linear_bsp/*/N`: the paper's — extracting the convex cell of
//!   a linear BSP of `N` planes tangent to a sphere, i.e. cutting a box by
//!   each plane in turn and keeping the part below. Throughput is in cuts.
//!   `edge_descent` builds both parts of every cut (as BSP merges need),
//!   `one_sided` only the part kept (`cut_keeping`), `classify_all` is the
//!   naive cut building both.
//! - `cut_through_middle/*/N`: one random plane through the central region
//!   of the finished `N`-face polyhedron (a large section), each applied to
//!   a fresh, cache-warm copy.

#[path = "../tests/it/common/fig9.rs"]
mod fig9;

use std::hint::black_box;

use chisel_bsp::convex::{ConvexArena, CutOutcome, KeptOutcome, NO_TAG, Part, PolyId};
use chisel_bsp::exact::{IntPoint, Plane};
use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use fig9::{R, random_direction, tangent_planes};

fn bounding_box(arena: &mut ConvexArena) -> PolyId {
    let corner = |c| IntPoint::new(c, c, c).expect("in budget");
    arena.add_box(corner(-R), corner(R)).expect("a box")
}

/// How [`extract_cell`] cuts.
#[derive(Clone, Copy)]
enum Method {
    /// Edge descent and marching, both parts built.
    EdgeDescent,
    /// Edge descent and marching, only the part below built.
    OneSided,
    /// Every vertex classified, both parts built.
    ClassifyAll,
}

/// The cell of the linear BSP of `planes`: the box cut by each in turn.
fn extract_cell(planes: &[Plane], method: Method) -> (ConvexArena, PolyId) {
    let mut arena = ConvexArena::new();
    let mut poly = bounding_box(&mut arena);
    for plane in planes {
        let below = match method {
            Method::EdgeDescent => match arena.cut(poly, plane, NO_TAG, NO_TAG) {
                CutOutcome::Split { below, .. } => Some(below),
                _ => None,
            },
            Method::OneSided => match arena.cut_keeping(poly, plane, Part::Below, NO_TAG) {
                KeptOutcome::Cut(below) => Some(below),
                _ => None,
            },
            Method::ClassifyAll => match arena.cut_naive(poly, plane, NO_TAG, NO_TAG) {
                CutOutcome::Split { below, .. } => Some(below),
                _ => None,
            },
        };
        if let Some(below) = below {
            poly = below;
        }
    }
    (arena, poly)
}

/// A compact convex polyhedron with about `faces` faces.
fn sphere_polytope(faces: usize, seed: u64) -> (ConvexArena, PolyId) {
    let planes = tangent_planes(4 * faces, seed);
    let mut arena = ConvexArena::new();
    let mut poly = bounding_box(&mut arena);
    for plane in &planes {
        if arena.faces_of(poly).len() >= faces {
            break;
        }
        if let CutOutcome::Split { below, .. } = arena.cut(poly, plane, NO_TAG, NO_TAG) {
            poly = below;
        }
    }
    arena.extract(poly)
}

fn cutting_planes(count: usize, seed: u64) -> Vec<Plane> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let n = random_direction(&mut rng, 65536.0);
            let p = [0; 3].map(|_| rng.random_range(-R / 2..R / 2));
            let d = -(n[0] as i128 * p[0] as i128
                + n[1] as i128 * p[1] as i128
                + n[2] as i128 * p[2] as i128);
            Plane::new(n[0], n[1], n[2], d).expect("in budget")
        })
        .collect()
}

fn figure9(c: &mut Criterion) {
    let mut group = c.benchmark_group("extract_linear_bsp");
    for planes in [50, 250, 1000, 2000] {
        let tangents = tangent_planes(planes, planes as u64);
        group.throughput(Throughput::Elements(planes as u64));
        for (name, method) in [
            ("edge_descent", Method::EdgeDescent),
            ("one_sided", Method::OneSided),
            ("classify_all", Method::ClassifyAll),
        ] {
            group.bench_with_input(BenchmarkId::new(name, planes), &planes, |b, _| {
                b.iter(|| black_box(extract_cell(&tangents, method)))
            });
        }
    }
    group.finish();

    let planes = cutting_planes(64, 9);
    let mut group = c.benchmark_group("cut_through_middle");
    group.throughput(Throughput::Elements(1));
    for faces in [50, 250, 1000, 2000] {
        let (arena, poly) = sphere_polytope(faces, faces as u64);
        let actual = arena.faces_of(poly).len();
        for (name, naive) in [("edge_descent", false), ("classify_all", true)] {
            group.bench_with_input(BenchmarkId::new(name, actual), &actual, |b, _| {
                let mut i = 0;
                b.iter_batched(
                    || {
                        i = (i + 1) % planes.len();
                        let mut copy = arena.clone();
                        copy.reserve(256);
                        (copy, planes[i])
                    },
                    |(mut a, plane)| {
                        let outcome = if naive {
                            a.cut_naive(poly, &plane, NO_TAG, NO_TAG)
                        } else {
                            a.cut(poly, &plane, NO_TAG, NO_TAG)
                        };
                        black_box(outcome);
                        a
                    },
                    BatchSize::PerIteration,
                )
            });
        }
    }
    group.finish();
}

criterion_group!(benches, figure9);
criterion_main!(benches);
