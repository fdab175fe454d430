//! Carving (`scene::carve`) and its partial re-sampling
//! (`sampling::partial`): a dent re-samples a small fraction of the
//! regions, the kept ones are those of before, the re-sampled ones those
//! of a full sampling, and the result covers the carved surface.

use crate::common;
use crate::partial_resampling::{assert_valid, compare_with_full};

use chisel_quadric::csg::{Literal, Side};
use chisel_quadric::sampling::partial::RegionSamples;
use chisel_quadric::scene::carve::Carve;
use chisel_quadric::{Quadric, Sample, SampleOptions, Scene};
use glam::DVec3;
use std::collections::HashMap;

/// The scene, its options at `R / divisor`, and its sampling.
fn sampled(name: &str, divisor: f64) -> (Scene, SampleOptions, RegionSamples) {
    let scene = common::scene(name);
    let sphere = scene.bounds.unwrap();
    let options = SampleOptions::new(sphere.radius / divisor, sphere).unwrap();
    let regions = RegionSamples::sample(&scene.dnf().unwrap(), &options).unwrap();
    (scene, options, regions)
}

/// A surface point of the sampling: its middle sample.
fn surface_point(regions: &RegionSamples) -> DVec3 {
    let set = regions.to_sample_set();
    set.samples[set.samples.len() / 2].position.as_dvec3()
}

/// A dent of radius `R / 12` at a surface point re-samples a small
/// fraction of the old literals' regions, and its result is that of a
/// full sampling where re-sampled, that of before where kept, and covers
/// the carved surface.
#[test]
fn a_dent_resamples_a_small_fraction() {
    for (name, divisor) in [
        ("three_spheres", 30.0),
        ("classic", 30.0),
        ("machine80", 30.0),
    ] {
        let (scene, options, old) = sampled(name, divisor);
        let centre = surface_point(&old);
        let tool = Quadric::sphere(centre, options.bounds.radius / 12.0).unwrap();
        let carved = scene.carved(&[Carve::new(tool, [0.2; 3])]).unwrap();
        let dnf = carved.dnf().unwrap();
        let (partial, report) = old.resample(&dnf).unwrap();
        assert!(!report.full, "{name}");
        assert!(report.changed_quadrics.is_empty(), "{name}");
        let tool_index = scene.dnf().unwrap().quadrics().len();
        assert_eq!(
            report.appended_literals,
            [Literal {
                quadric: tool_index,
                side: Side::Outside
            }],
            "{name}"
        );
        let full = RegionSamples::sample(&dnf, &options).unwrap();
        assert_eq!(partial.region_count(), full.region_count());
        assert_eq!(
            partial.region_count(),
            report.regions_kept + report.regions_resampled + report.regions_empty
        );
        // Every old region is kept or re-sampled; the tool's are new, and
        // run or proven empty.
        let new_regions = partial.region_count() - old.region_count();
        assert!(report.regions_empty > 0, "{name}: {report:?}");
        let old_resampled = report.regions_resampled + report.regions_empty - new_regions;
        assert_eq!(report.regions_kept, old.region_count() - old_resampled);
        assert!(old_resampled > 0, "{name}: the dent touches the surface");
        assert!(
            old_resampled * 5 < old.region_count(),
            "{name}: {old_resampled} of {} old regions re-sampled",
            old.region_count()
        );
        let differ = compare_with_full(name, &partial, &old, &full);
        eprintln!(
            "{name} carve r=R/{divisor}: {old_resampled} of {} old regions and {} of \
             {new_regions} tool regions re-sampled, {} kept ({differ} differ from the full \
             sampling's), {} of {} samples kept",
            old.region_count(),
            new_regions - report.regions_empty,
            report.regions_kept,
            report.samples_kept,
            partial.to_sample_set().samples.len(),
        );
        assert_valid(name, &dnf, &partial.to_sample_set());
        // The dent removed surface and added the tool's.
        let set = partial.to_sample_set();
        let on_tool = set
            .samples
            .iter()
            .filter(|s| set.patch_of(s).quadric as usize == tool_index)
            .count();
        assert!(on_tool > 0, "{name}: no sample on the dent");
    }
}

/// Carves one after another: each re-samples from the last, and two
/// carves at once give the same solid as one after the other.
#[test]
fn carves_in_sequence_keep_the_guarantee() {
    let (scene, options, mut regions) = sampled("machine80", 20.0);
    let mut rng = common::rng(41);
    let mut carves = Vec::new();
    for i in 0..3 {
        let set = regions.to_sample_set();
        let pick = rand::Rng::random_range(&mut rng, 0..set.samples.len());
        let centre = set.samples[pick].position.as_dvec3();
        let radii = DVec3::new(4.0, 6.0, 3.0) + common::point(&mut rng, 2.0).abs();
        carves.push(Carve::new(
            Quadric::ellipsoid(centre, radii).unwrap(),
            [0.1, 0.1, 0.1],
        ));
        let dnf = scene.carved(&carves).unwrap().dnf().unwrap();
        let (next, report) = regions.resample(&dnf).unwrap();
        assert!(!report.full, "carve {i}");
        assert_eq!(report.appended_literals.len(), 1, "carve {i}");
        let full = RegionSamples::sample(&dnf, &options).unwrap();
        compare_with_full("machine80", &next, &regions, &full);
        assert_valid("machine80", &dnf, &next.to_sample_set());
        regions = next;
    }
    // All three at once from the uncarved sampling: three appended literals.
    let (_, _, uncarved) = sampled("machine80", 20.0);
    let dnf = scene.carved(&carves).unwrap().dnf().unwrap();
    let (at_once, report) = uncarved.resample(&dnf).unwrap();
    assert_eq!(report.appended_literals.len(), 3);
    assert_valid("machine80", &dnf, &at_once.to_sample_set());
}

/// A tool far from the solid keeps every old region and its samples, and
/// its own regions give no sample.
#[test]
fn a_tool_off_the_solid_keeps_every_sample() {
    let (scene, _, old) = sampled("classic", 30.0);
    let sphere = scene.bounds.unwrap();
    let centre = sphere.centre + DVec3::new(0.95 * sphere.radius, 0.0, 0.0);
    let tool = Quadric::sphere(centre, 0.03 * sphere.radius).unwrap();
    let dnf = scene
        .carved(&[Carve::new(tool, [0.0; 3])])
        .unwrap()
        .dnf()
        .unwrap();
    let (partial, report) = old.resample(&dnf).unwrap();
    assert!(!report.full);
    assert_eq!(report.regions_kept, old.region_count());
    // Patches are renumbered (each product has the tool's too): compare
    // by region key.
    let strip =
        |s: &[Sample]| -> Vec<Sample> { s.iter().map(|s| Sample { patch: 0, ..*s }).collect() };
    let before: HashMap<_, _> = old.regions().map(|(k, s)| (k, strip(s))).collect();
    for (key, samples) in partial.regions() {
        match before.get(&key) {
            Some(b) => assert_eq!(&strip(samples), b, "{key:?}"),
            None => assert!(samples.is_empty(), "tool region {key:?}"),
        }
    }
    assert_eq!(
        partial.to_sample_set().samples.len(),
        old.to_sample_set().samples.len()
    );
}

/// Not a carve: a changed quadric together with an appended literal falls
/// back to a full sampling.
#[test]
fn a_carve_with_another_edit_is_sampled_in_full() {
    let (_, options, old) = sampled("three_spheres", 20.0);
    let text = std::fs::read_to_string(format!(
        "{}/../assets/scenes/three_spheres.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let edited = Scene::from_ron(&text.replacen(
        "Sphere(center: (0, 0, 30), radius: 25)",
        "Sphere(center: (0, 3, 32), radius: 24)",
        1,
    ))
    .unwrap();
    let tool = Quadric::sphere(surface_point(&old), 5.0).unwrap();
    let dnf = edited
        .carved(&[Carve::new(tool, [0.0; 3])])
        .unwrap()
        .dnf()
        .unwrap();
    let (partial, report) = old.resample(&dnf).unwrap();
    assert!(report.full);
    assert_eq!(
        partial.to_sample_set(),
        RegionSamples::sample(&dnf, &options)
            .unwrap()
            .to_sample_set()
    );
}

/// A dent's partial re-sample against a full sampling of the carved
/// scene, medians of 15 runs on one thread (machine80, dent of radius
/// `R / 12` on a surface point): `--ignored --nocapture`.
#[test]
#[ignore = "timing"]
fn carve_timing() {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let time = |f: &dyn Fn()| {
        let mut t: Vec<f64> = (0..15)
            .map(|_| {
                let s = std::time::Instant::now();
                f();
                s.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    };
    for divisor in [30.0, 100.0] {
        let (scene, options, old) = sampled("machine80", divisor);
        let same = scene.dnf().unwrap();
        let tool = Quadric::sphere(surface_point(&old), options.bounds.radius / 12.0).unwrap();
        let dnf = scene
            .carved(&[Carve::new(tool, [0.2; 3])])
            .unwrap()
            .dnf()
            .unwrap();
        let unchanged = time(&|| {
            one.install(|| old.resample(&same).unwrap());
        });
        let partial = time(&|| {
            one.install(|| old.resample(&dnf).unwrap());
        });
        let full = time(&|| {
            one.install(|| RegionSamples::sample(&dnf, &options).unwrap());
        });
        let normal_form = time(&|| {
            scene
                .carved(&[Carve::new(tool, [0.2; 3])])
                .unwrap()
                .dnf()
                .unwrap();
        });
        eprintln!(
            "machine80 r=R/{divisor} medians: full {full:.2} ms, partial {partial:.2} ms \
             ({:.1}x), resample of the unchanged scene {unchanged:.2} ms, carved normal form \
             {normal_form:.3} ms",
            full / partial
        );
    }
}
