//! Partial re-sampling (`sampling::partial`): after an edit of one
//! primitive, the re-sampled regions equal a full sampling's, the kept ones
//! are valid for the edited scene, and the result covers the edited
//! surface on dense reference points.

use crate::common;

use chisel_quadric::csg::Dnf;
use chisel_quadric::sampling::partial::RegionSamples;
use chisel_quadric::{Sample, SampleOptions, SampleSet, Scene, sample, trace_image};
use glam::DVec3;
use std::collections::HashMap;

/// `(scene, text replaced, replacement, quadrics changed)`: primitives
/// moved or resized.
const EDITS: [(&str, &str, &str, usize); 4] = [
    (
        "three_spheres",
        "Sphere(center: (0, 0, 30), radius: 25)",
        "Sphere(center: (0, 3, 32), radius: 24)",
        1,
    ),
    (
        "classic",
        "Cylinder(point: (0, 0, 0), axis: (0, 0, 1), radius: 30)",
        "Cylinder(point: (2, 0, 0), axis: (0, 0, 1), radius: 27)",
        1,
    ),
    (
        "classic",
        "Box(min: (-50, -50, -50), max: (50, 50, 50))",
        "Box(min: (-50, -50, -50), max: (47, 50, 44))",
        2,
    ),
    (
        "machine80",
        "(name: \"bolt0_head\", shape: Cylinder(point: (-45, -25, 0), axis: (0, 0, 1), radius: 8)",
        "(name: \"bolt0_head\", shape: Cylinder(point: (-45, -25, 0), axis: (0, 0, 1), radius: 9)",
        1,
    ),
];

fn scene_text(name: &str) -> String {
    let path = format!(
        "{}/../assets/scenes/{name}.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(path).expect("shipped scene")
}

/// The scene before and after the edit, and the options to sample both.
fn edited(name: &str, from: &str, to: &str, divisor: f64) -> (Dnf, Dnf, SampleOptions) {
    let text = scene_text(name);
    assert!(text.contains(from), "{name}: edit target not found");
    let before = Scene::from_ron(&text).unwrap();
    let after = Scene::from_ron(&text.replacen(from, to, 1)).unwrap();
    let sphere = before.bounds.unwrap();
    let options = SampleOptions::new(sphere.radius / divisor, sphere).unwrap();
    (before.dnf().unwrap(), after.dnf().unwrap(), options)
}

#[test]
fn region_samples_flatten_to_the_full_sampling() {
    for name in ["three_spheres", "classic", "machine80"] {
        let scene = common::scene(name);
        let dnf = scene.dnf().unwrap();
        let sphere = scene.bounds.unwrap();
        let options = SampleOptions::new(sphere.radius / 30.0, sphere).unwrap();
        let regions = RegionSamples::sample(&dnf, &options).unwrap();
        assert_eq!(
            regions.to_sample_set(),
            sample(&dnf, &options).unwrap(),
            "{name}"
        );
    }
}

#[test]
fn an_unchanged_scene_keeps_every_region() {
    let (before, _, options) = edited("classic", "", "", 30.0);
    let regions = RegionSamples::sample(&before, &options).unwrap();
    let (again, report) = regions.resample(&before).unwrap();
    assert!(!report.full && report.changed_quadrics.is_empty());
    assert_eq!(report.regions_resampled, 0);
    assert_eq!(report.regions_kept, regions.region_count());
    assert_eq!(
        again.to_sample_set().samples,
        regions.to_sample_set().samples
    );
}

#[test]
fn a_new_structure_is_sampled_in_full() {
    // A fourth cylinder adds a literal to the product: an appended literal
    // on a new quadric, re-sampled as a carve (`carving.rs`). The reverse
    // edit, a literal taken out, changes the products otherwise.
    let (before, _, options) = edited("classic", "", "", 30.0);
    let text = scene_text("classic")
        .replace(
            "    ],\n    root",
            "        (name: \"bore_w\", shape: Cylinder(point: (0, 0, 0), axis: (1, 1, 0), radius: 10)),\n    ],\n    root",
        )
        .replace("Ref(\"bore_z\"),", "Ref(\"bore_z\"),\n        Ref(\"bore_w\"),");
    let (before, after) = (Scene::from_ron(&text).unwrap().dnf().unwrap(), before);
    assert_ne!(after.products(), before.products());
    let regions = RegionSamples::sample(&before, &options).unwrap();
    let (full, report) = regions.resample(&after).unwrap();
    assert!(report.full && report.regions_kept == 0);
    assert_eq!(full.to_sample_set(), sample(&after, &options).unwrap());
    // Forwards: partial, and valid.
    let regions = RegionSamples::sample(&after, &options).unwrap();
    let (partial, report) = regions.resample(&before).unwrap();
    assert!(
        !report.full && report.appended_literals.len() == 1,
        "{report:?}"
    );
    assert_valid("classic", &before, &partial.to_sample_set());
}

/// Every region holds the full sampling's samples (re-sampled) or those
/// of before (kept; patch indices renumbered). Returns the number of
/// regions whose samples differ from the full sampling's (kept ones).
pub(crate) fn compare_with_full(
    name: &str,
    partial: &RegionSamples,
    before: &RegionSamples,
    full: &RegionSamples,
) -> usize {
    let strip =
        |s: &[Sample]| -> Vec<Sample> { s.iter().map(|s| Sample { patch: 0, ..*s }).collect() };
    let full: HashMap<_, _> = full.regions().collect();
    let before: HashMap<_, _> = before.regions().collect();
    let mut differ = 0;
    for (key, samples) in partial.regions() {
        if samples == full[&key] {
            continue;
        }
        let kept = before.get(&key).is_some_and(|b| strip(b) == strip(samples));
        assert!(
            kept,
            "{name}: region {key:?} is neither the full sampling's nor the old one"
        );
        differ += 1;
    }
    differ
}

/// Every traced point of `dnf`'s surface inside the bounds has a sample on
/// the same quadric within the splat radius; every sample lies on the
/// surface.
pub(crate) fn assert_valid(name: &str, dnf: &Dnf, set: &SampleSet) {
    let sphere = set.options.bounds;
    let (centre, bound) = (sphere.centre, sphere.radius);
    let grid = common::SampleGrid::new(set, set.options.radius);
    let (mut checked, mut missed) = (0, 0);
    for camera in common::cameras(centre, 2.5 * bound, 64) {
        let image = trace_image(dnf, &camera);
        for (i, &q) in image.quadric.iter().enumerate() {
            if q == chisel_quadric::NO_HIT {
                continue;
            }
            let ray = camera.ray(i as u32 % camera.width, i as u32 / camera.width);
            let p = ray.at(image.depth[i]);
            if sphere.signed_distance(p) > -1e-9 * bound {
                continue;
            }
            checked += 1;
            if !grid.covered(q, p, 1e-9) {
                missed += 1;
            }
        }
    }
    assert!(checked > 1000, "{name}: only {checked} reference points");
    assert_eq!(missed, 0, "{name}: {missed} of {checked} uncovered");
    for s in &set.samples {
        let (p, n) = (s.position.as_dvec3(), set.normal_of(dnf, s));
        // Stored in f32: on the surface up to that rounding.
        let eps = 1e-7 * bound + 4.0 * common::f32_rounding(p);
        if n != DVec3::ZERO {
            assert!(
                dnf.contains(p - n * eps) && !dnf.contains(p + n * eps),
                "{name}: sample {p} not on the edited surface"
            );
        }
    }
}

#[test]
fn an_edit_resamples_only_the_regions_it_touches() {
    for (name, from, to, count) in EDITS {
        for divisor in [8.0, 30.0] {
            let (before, after, options) = edited(name, from, to, divisor);
            let old = RegionSamples::sample(&before, &options).unwrap();
            let (partial, report) = old.resample(&after).unwrap();
            let full = RegionSamples::sample(&after, &options).unwrap();
            assert!(!report.full, "{name}");
            assert_eq!(report.changed_quadrics.len(), count, "{name}: {report:?}");
            assert!(report.regions_resampled > 0, "{name}: {report:?}");
            assert!(report.regions_kept > 0, "{name}: {report:?}");
            assert_eq!(partial.region_count(), full.region_count());
            let differ = compare_with_full(name, &partial, &old, &full);
            eprintln!(
                "{name} r=R/{divisor}: {} of {} regions re-sampled, {} kept ({differ} differ from the full sampling's), {} of {} samples kept",
                report.regions_resampled,
                partial.region_count(),
                report.regions_kept,
                report.samples_kept,
                partial.to_sample_set().samples.len(),
            );
            // The kept regions' samples are valid whatever the sampler
            // would do now (the module notes); on these edits they are
            // also exactly what a full sampling of the edited scene gives.
            assert_eq!(
                differ, 0,
                "{name}: kept regions differ from a full sampling"
            );
            assert_valid(name, &after, &partial.to_sample_set());
        }
    }
}

#[test]
fn random_edits_keep_the_guarantee() {
    let text = scene_text("three_spheres");
    let before = Scene::from_ron(&text).unwrap();
    let sphere = before.bounds.unwrap();
    let options = SampleOptions::new(sphere.radius / 20.0, sphere).unwrap();
    let before = before.dnf().unwrap();
    let old = RegionSamples::sample(&before, &options).unwrap();
    let mut rng = common::rng(23);
    for _ in 0..6 {
        let c = common::point(&mut rng, 20.0);
        let r = 10.0 + 20.0 * rand::Rng::random::<f64>(&mut rng);
        let edited = text.replacen(
            "Sphere(center: (0, 0, 30), radius: 25)",
            &format!(
                "Sphere(center: ({}, {}, {}), radius: {r})",
                c.x,
                c.y,
                30.0 + c.z
            ),
            1,
        );
        let after = Scene::from_ron(&edited).unwrap().dnf().unwrap();
        let (partial, report) = old.resample(&after).unwrap();
        assert!(!report.full);
        let full = RegionSamples::sample(&after, &options).unwrap();
        compare_with_full("three_spheres", &partial, &old, &full);
        assert_valid("three_spheres", &after, &partial.to_sample_set());
    }
}
