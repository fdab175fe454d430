//! Paper 2, Table 2: sampling the four scenes of `assets/scenes/` at three
//! splat radii (1/10, 1/30 and 1/100 of the bounding radius) on one core,
//! plus `machine80` on two cores, and a single sphere (no CSG) for the
//! raw sampling rate.
//!
//! Before the timings, one line per configuration on stderr gives the
//! counts of Table 2: samples, distance queries, clip-index buffer size.

use chisel_quadric::{BoundingSphere, SampleOptions, Scene, SplatSet, sample};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use std::hint::black_box;

/// The shipped scenes, sampled inside the `bounds` their files give.
const SCENES: [&str; 4] = ["three_spheres", "classic", "sharp8", "machine80"];

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn sampling(c: &mut Criterion) {
    let one = pool(1);
    let two = pool(2);
    let mut group = c.benchmark_group("table2");
    group.sample_size(10);
    for name in SCENES {
        let path = format!(
            "{}/../assets/scenes/{name}.quadric.ron",
            env!("CARGO_MANIFEST_DIR")
        );
        let scene = Scene::load(&path).expect("shipped scene");
        let dnf = scene.dnf().expect("normal form");
        let sphere = scene.bounds.expect("shipped scenes give bounds");
        let bound = sphere.radius;
        for (label, divisor) in [("large", 10.0), ("medium", 30.0), ("small", 100.0)] {
            let options = SampleOptions::new(bound / divisor, sphere).expect("options");
            let set = one.install(|| sample(&dnf, &options)).expect("sampling");
            let splats = SplatSet::new(&dnf, &scene.dag, &set);
            eprintln!(
                "{name} {label} (r = {:.2}): {} quadrics, {} samples, {} distance queries, \
                 {} clip indices; basic regions by kind {:?}, their samples {:?}",
                options.radius,
                dnf.quadrics().len(),
                set.samples.len(),
                set.stats.distance_queries,
                splats.clip_indices.len(),
                set.stats.kinds,
                set.stats.kind_samples
            );
            group.throughput(Throughput::Elements(set.samples.len() as u64));
            group.bench_function(format!("{name}/{label}/1-thread"), |b| {
                b.iter(|| one.install(|| sample(black_box(&dnf), &options)));
            });
            if name == "machine80" {
                group.bench_function(format!("{name}/{label}/2-threads"), |b| {
                    b.iter(|| two.install(|| sample(black_box(&dnf), &options)));
                });
            }
        }
    }
    group.finish();

    // A single quadric: no CSG pruning, every region is filled directly.
    let mut group = c.benchmark_group("single_quadric");
    group.sample_size(10);
    let scene = Scene::from_ron(
        r#"Scene(primitives: [(name: "ball", shape: Sphere(center: (0, 0, 0), radius: 50))], root: Ref("ball"))"#,
    )
    .expect("a one-sphere scene");
    let dnf = scene.dnf().expect("normal form");
    let sphere = BoundingSphere::new(DVec3::ZERO, 60.0).expect("sphere");
    for radius in [1.0, 0.25] {
        let options = SampleOptions::new(radius, sphere).expect("options");
        let set = one.install(|| sample(&dnf, &options)).expect("sampling");
        eprintln!(
            "sphere (r = {radius}): {} samples, {} distance queries",
            set.samples.len(),
            set.stats.distance_queries
        );
        group.throughput(Throughput::Elements(set.samples.len() as u64));
        group.bench_function(format!("sphere/r={radius}/1-thread"), |b| {
            b.iter(|| one.install(|| sample(black_box(&dnf), &options)));
        });
    }
    group.finish();
}

criterion_group!(benches, sampling);
criterion_main!(benches);
