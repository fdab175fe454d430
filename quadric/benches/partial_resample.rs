//! Partial re-sampling against a full re-sample (paper 2, §8), on one
//! core: one primitive of a shipped scene edited (the edits of
//! `tests/it/partial_resampling.rs`), then the edited scene sampled in full
//! (`sample`) or only where the edit can change it
//! (`RegionSamples::resample`). `cargo bench -p chisel_quadric --bench
//! partial_resample`.
//!
//! Carves (`carve/…`): a sphere of radius `R / 12` centred on a surface
//! point (the middle sample of the scene's sampling) cut from the scene
//! (`Scene::carved`), then the carved scene sampled in full or with
//! `RegionSamples::resample` from the uncarved sampling.
//!
//! Before the timings, one line per configuration on stderr gives the
//! regions and samples kept.

use chisel_quadric::sampling::partial::RegionSamples;
use chisel_quadric::scene::carve::Carve;
use chisel_quadric::{Quadric, SampleOptions, Scene, sample};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// `(scene, text replaced, replacement)`.
const EDITS: [(&str, &str, &str); 2] = [
    (
        "three_spheres",
        "Sphere(center: (0, 0, 30), radius: 25)",
        "Sphere(center: (0, 3, 32), radius: 24)",
    ),
    (
        "machine80",
        "(name: \"bolt0_head\", shape: Cylinder(point: (-45, -25, 0), axis: (0, 0, 1), radius: 8)",
        "(name: \"bolt0_head\", shape: Cylinder(point: (-45, -25, 0), axis: (0, 0, 1), radius: 9)",
    ),
];

fn partial(c: &mut Criterion) {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let mut group = c.benchmark_group("partial_resample");
    group.sample_size(10);
    for (name, from, to) in EDITS {
        let path = format!(
            "{}/../assets/scenes/{name}.quadric.ron",
            env!("CARGO_MANIFEST_DIR")
        );
        let text = std::fs::read_to_string(path).expect("shipped scene");
        let before = Scene::from_ron(&text).expect("scene");
        let after = Scene::from_ron(&text.replacen(from, to, 1)).expect("edited scene");
        let sphere = before.bounds.expect("shipped scenes give bounds");
        let (before, after) = (before.dnf().expect("dnf"), after.dnf().expect("dnf"));
        for (label, divisor) in [("medium", 30.0), ("small", 100.0)] {
            let options = SampleOptions::new(sphere.radius / divisor, sphere).expect("options");
            let old = one
                .install(|| RegionSamples::sample(&before, &options))
                .expect("sampling");
            let (_, report) = one.install(|| old.resample(&after)).expect("re-sampling");
            eprintln!(
                "{name} {label} (r = {:.2}): {} of {} regions kept, {} samples kept",
                options.radius,
                report.regions_kept,
                old.region_count(),
                report.samples_kept
            );
            group.bench_function(format!("{name}/{label}/full"), |b| {
                b.iter(|| one.install(|| sample(black_box(&after), &options)));
            });
            group.bench_function(format!("{name}/{label}/partial"), |b| {
                b.iter(|| one.install(|| old.resample(black_box(&after))));
            });
        }
    }
    group.finish();
}

fn carve(c: &mut Criterion) {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    let mut group = c.benchmark_group("partial_resample");
    group.sample_size(10);
    for name in ["three_spheres", "machine80"] {
        let path = format!(
            "{}/../assets/scenes/{name}.quadric.ron",
            env!("CARGO_MANIFEST_DIR")
        );
        let scene = Scene::load(path).expect("scene");
        let sphere = scene.bounds.expect("shipped scenes give bounds");
        let before = scene.dnf().expect("dnf");
        for (label, divisor) in [("medium", 30.0), ("small", 100.0)] {
            let options = SampleOptions::new(sphere.radius / divisor, sphere).expect("options");
            let old = one
                .install(|| RegionSamples::sample(&before, &options))
                .expect("sampling");
            let set = old.to_sample_set();
            let centre = set.samples[set.samples.len() / 2].position.as_dvec3();
            let tool = Quadric::sphere(centre, sphere.radius / 12.0).expect("tool");
            let after = scene
                .carved(&[Carve::new(tool, [0.2; 3])])
                .expect("carve")
                .dnf()
                .expect("dnf");
            let (new, report) = one.install(|| old.resample(&after)).expect("re-sampling");
            eprintln!(
                "{name} carve {label} (r = {:.2}): {} of {} old regions kept, {} of {} tool \
                 regions run, {} of {} samples kept",
                options.radius,
                report.regions_kept,
                old.region_count(),
                new.region_count() - old.region_count() - report.regions_empty,
                new.region_count() - old.region_count(),
                report.samples_kept,
                new.to_sample_set().samples.len()
            );
            group.bench_function(format!("carve/{name}/{label}/full"), |b| {
                b.iter(|| one.install(|| sample(black_box(&after), &options)));
            });
            group.bench_function(format!("carve/{name}/{label}/partial"), |b| {
                b.iter(|| one.install(|| old.resample(black_box(&after))));
            });
        }
    }
    group.finish();
}

criterion_group!(benches, partial, carve);
criterion_main!(benches);
