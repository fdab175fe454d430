//! Paper 2, Table 1: single-core cost of the basic operations (ns/op).
//!
//! Each benchmark runs its operation over a fixed batch of 1024 seeded
//! random inputs, so the reported time per iteration divided by 1024 is the
//! cost per operation.
//!
//! Two harnesses: `table1` hides every input from the optimizer
//! (`black_box` per element, which stores and reloads it, and sums the
//! results in one dependent chain); `table1_batch` hides only the batch and
//! writes each result to an output slot, the throughput the paper's
//! operations per second give (independent operations in flight at once).
//! Each output slot holds the operation's whole result (both distortion
//! bounds, the full line hits), except the one row that times the minimum
//! distortion alone, as the paper's row does.
//!
//! `TABLE1_FIXED=BATCHES cargo bench -p chisel_quadric --bench operations
//! -- NAME` runs the batch operations whose names contain `NAME` a fixed
//! number of times instead (see [`fixed`]), for callgrind and for medians
//! of many short rounds.

use chisel_quadric::sampling::heightfield::{Heightfield, LocalForm};
use chisel_quadric::{Quadric, QuadricDistance, Ray};
use criterion::{Criterion, Throughput, criterion_group};
use glam::{DVec2, DVec3};
use std::hint::black_box;

const BATCH: usize = 1024;

/// A small deterministic generator (no extra dependency in the bench).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        // 53 random bits to [-1, 1).
        #[allow(clippy::cast_precision_loss)]
        let u = (self.0 >> 11) as f64 / (1u64 << 53) as f64;
        2.0 * u - 1.0
    }

    fn vec3(&mut self) -> DVec3 {
        DVec3::new(self.next(), self.next(), self.next())
    }
}

/// The seeded inputs of every operation.
struct Inputs {
    quadric: Quadric,
    points: Vec<DVec3>,
    uvs: Vec<DVec2>,
    rays: Vec<Ray>,
    distance: QuadricDistance,
    hf: Heightfield,
}

impl Inputs {
    fn new() -> Self {
        let mut rng = Lcg(7);
        let quadric = Quadric::ellipsoid(DVec3::new(0.1, -0.2, 0.3), DVec3::new(1.0, 0.7, 0.5))
            .unwrap()
            .transformed(&glam::DMat4::from_rotation_y(0.4))
            .unwrap();
        let points: Vec<DVec3> = (0..BATCH).map(|_| rng.vec3() * 2.0).collect();
        let uvs: Vec<DVec2> = (0..BATCH)
            .map(|_| DVec2::new(rng.next(), rng.next()) * 0.6)
            .collect();
        let rays: Vec<Ray> = (0..BATCH)
            .map(|_| Ray::new(rng.vec3() * 3.0, rng.vec3() + DVec3::splat(1e-3)).unwrap())
            .collect();
        let distance = QuadricDistance::new(&quadric);
        let hf = LocalForm::new(&quadric).heightfields()[0];
        Self {
            quadric,
            points,
            uvs,
            rays,
            distance,
            hf,
        }
    }
}

fn operations(c: &mut Criterion) {
    let inputs = Inputs::new();
    let Inputs {
        quadric,
        points,
        uvs,
        rays,
        distance,
        hf,
    } = &inputs;
    let mut group = c.benchmark_group("table1");
    group.throughput(Throughput::Elements(BATCH as u64));
    group.bench_function("quadric_value", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|p| quadric.value(black_box(*p)))
                .sum::<f64>()
        });
    });
    group.bench_function("quadric_normal", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|p| quadric.normal(black_box(*p)).unwrap_or(DVec3::ZERO))
                .sum::<DVec3>()
        });
    });
    group.bench_function("heightfield_value", |b| {
        b.iter(|| {
            uvs.iter()
                .map(|p| hf.height(black_box(*p)).unwrap_or(0.0))
                .sum::<f64>()
        });
    });
    group.bench_function("heightfield_distortion", |b| {
        b.iter(|| {
            uvs.iter()
                .map(|p| hf.distortion(black_box(*p)))
                .sum::<f64>()
        });
    });
    group.bench_function("heightfield_distortion_bounds", |b| {
        b.iter(|| {
            uvs.iter()
                .map(|p| {
                    let lo = black_box(*p).abs();
                    let (min, max) = hf.distortion_bounds(lo, lo + DVec2::splat(0.05));
                    min + max
                })
                .sum::<f64>()
        });
    });
    group.bench_function("heightfield_min_distortion", |b| {
        b.iter(|| {
            uvs.iter()
                .map(|p| {
                    let lo = black_box(*p).abs();
                    hf.distortion_bounds(lo, lo + DVec2::splat(0.05)).0
                })
                .sum::<f64>()
        });
    });
    group.bench_function("line_intersection", |b| {
        b.iter(|| {
            // The whole result through `black_box`, so that no part of
            // the intersection is left out for the span count alone.
            rays.iter()
                .map(|r| {
                    black_box(quadric.intersect_line(black_box(r)))
                        .spans()
                        .len()
                })
                .sum::<usize>()
        });
    });
    group.bench_function("conservative_distance", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|p| distance.distance(black_box(*p)))
                .sum::<f64>()
        });
    });
    group.finish();

    let mut group = c.benchmark_group("table1_batch");
    group.throughput(Throughput::Elements(BATCH as u64));
    for (name, mut op) in batch_operations(&inputs) {
        group.bench_function(name, |b| b.iter(&mut op));
    }
    group.finish();
}

/// One batch operation: a name and a closure that runs it over the batch.
type BatchOperation<'a> = (&'static str, Box<dyn FnMut() + 'a>);

/// The `table1_batch` operations: each hides only its input batch from the
/// optimizer and writes each result to its own output slot.
fn batch_operations(inputs: &Inputs) -> Vec<BatchOperation<'_>> {
    let Inputs {
        quadric,
        points,
        uvs,
        rays,
        distance,
        hf,
    } = inputs;
    let mut ops: Vec<BatchOperation<'_>> = Vec::new();
    let mut out = vec![0.0; BATCH];
    ops.push((
        "quadric_value",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(points)) {
                *o = quadric.value(*p);
            }
            black_box(&mut out);
        }),
    ));
    let mut out = vec![DVec3::ZERO; BATCH];
    ops.push((
        "quadric_normal",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(points)) {
                *o = quadric.normal(*p).unwrap_or(DVec3::ZERO);
            }
            black_box(&mut out);
        }),
    ));
    let mut out = vec![0.0; BATCH];
    ops.push((
        "heightfield_value",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(uvs)) {
                *o = hf.height(*p).unwrap_or(0.0);
            }
            black_box(&mut out);
        }),
    ));
    let mut out = vec![0.0; BATCH];
    ops.push((
        "heightfield_distortion",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(uvs)) {
                *o = hf.distortion(*p);
            }
            black_box(&mut out);
        }),
    ));
    let mut out = vec![(0.0, 0.0); BATCH];
    ops.push((
        "heightfield_distortion_bounds",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(uvs)) {
                let lo = p.abs();
                *o = hf.distortion_bounds(lo, lo + DVec2::splat(0.05));
            }
            black_box(&mut out);
        }),
    ));
    // Paper 2, Table 1 times the minimum alone (`min_R δ`): the same
    // function with only its first result kept.
    let mut out = vec![0.0; BATCH];
    ops.push((
        "heightfield_min_distortion",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(uvs)) {
                let lo = p.abs();
                *o = hf.distortion_bounds(lo, lo + DVec2::splat(0.05)).0;
            }
            black_box(&mut out);
        }),
    ));
    // The whole result of each intersection (spans and flags) is written,
    // so none of its computation can be left out.
    let mut out = vec![quadric.intersect_line(&rays[0]); BATCH];
    ops.push((
        "line_intersection",
        Box::new(move || {
            for (o, r) in out.iter_mut().zip(black_box(rays)) {
                *o = quadric.intersect_line(r);
            }
            black_box(&mut out);
        }),
    ));
    let mut out = vec![0.0; BATCH];
    ops.push((
        "conservative_distance",
        Box::new(move || {
            for (o, p) in out.iter_mut().zip(black_box(points)) {
                *o = distance.distance(*p);
            }
            black_box(&mut out);
        }),
    ));
    ops
}

/// `TABLE1_FIXED=BATCHES`: runs each batch operation whose name contains
/// the first argument `BATCHES` times after as many for warming up, in
/// 101 timed rounds (short ones, so that most are not preempted on a loaded machine), and prints the median and the fastest round in ns per
/// operation. A fixed amount of work, so that instruction counts
/// (callgrind) of two values of `BATCHES` give the count per operation.
fn fixed(batches: usize, filter: &str) {
    let inputs = Inputs::new();
    for (name, mut op) in batch_operations(&inputs) {
        if !name.contains(filter) {
            continue;
        }
        run(&mut op, batches);
        let mut rounds: Vec<f64> = (0..101)
            .map(|_| {
                let start = std::time::Instant::now();
                run(&mut op, batches);
                #[allow(clippy::cast_precision_loss)]
                let per_op = start.elapsed().as_secs_f64() * 1e9 / (batches * BATCH) as f64;
                per_op
            })
            .collect();
        rounds.sort_by(f64::total_cmp);
        println!(
            "{name}: median {:.2} ns/op, fastest {:.2} ns/op",
            rounds[rounds.len() / 2],
            rounds[0]
        );
    }
}

/// `batches` runs of `op` (a function of its own, for callgrind's
/// `--toggle-collect`).
#[inline(never)]
fn run(op: &mut dyn FnMut(), batches: usize) {
    for _ in 0..batches {
        op();
    }
}

criterion_group!(benches, operations);

fn main() {
    if let Some(batches) = std::env::var("TABLE1_FIXED")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        // The first argument that is not a flag (cargo passes `--bench`).
        let args: Vec<String> = std::env::args().skip(1).collect();
        let filter = args
            .iter()
            .find(|a| !a.starts_with('-'))
            .map_or("", String::as_str);
        fixed(batches, filter);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
