//! The memory limit of sampling: the tables [`sample`] builds before its
//! first sample are counted up front ([`sampling_cost`]), grow linearly
//! with the normal form, and a normal form that needs more than
//! `SampleOptions::max_memory` is refused before anything is allocated.

use crate::common;

use chisel_quadric::{DEFAULT_MAX_MEMORY, Error, SampleOptions, Scene, sample, sampling_cost};

/// `n` unions of two spheres under one intersection: `2ⁿ` products of
/// `n` literals each in normal form, from a scene file of `2n` spheres.
fn crossed_unions(n: usize) -> Scene {
    let mut primitives = String::new();
    let mut factors = Vec::new();
    for i in 0..n {
        let offset = 0.1 * (i + 1) as f64;
        primitives.push_str(&format!(
            "(name: \"a{i}\", shape: Sphere(center: ({offset}, 0, 0), radius: 50)),\n\
             (name: \"b{i}\", shape: Sphere(center: (0, {offset}, 0), radius: 50)),\n"
        ));
        factors.push(format!("Union([Ref(\"a{i}\"), Ref(\"b{i}\")])"));
    }
    let text = format!(
        "Scene(primitives: [{primitives}], root: Intersection([{}]), bounds: (0, 0, 0, 60))",
        factors.join(", ")
    );
    Scene::from_ron(&text).unwrap()
}

#[test]
fn a_normal_form_of_32768_products_is_refused_before_allocating() {
    // Before: `chisel sample` on this scene grew its job list past 5 GB and
    // aborted trying to allocate 9.1 GB more.
    let scene = crossed_unions(15);
    let dnf = scene.dnf().unwrap();
    assert_eq!(dnf.products().len(), 32_768);
    let sphere = scene.bounds.unwrap();
    let cost = sampling_cost(&dnf, sphere);
    assert_eq!(cost.literals, 15 * 32_768);
    assert!(cost.bytes > DEFAULT_MAX_MEMORY, "{cost:?}");
    let options = SampleOptions::new(2.0, sphere).unwrap();
    let result = sample(&dnf, &options);
    let Err(e) = &result else {
        panic!(
            "expected SamplingTooLarge, got {} samples",
            result.map_or(0, |s| s.samples.len())
        );
    };
    assert_eq!(
        *e,
        Error::SamplingTooLarge {
            products: 32_768,
            literals: cost.literals,
            regions: cost.regions,
            needed: cost.bytes,
            limit: DEFAULT_MAX_MEMORY,
        }
    );
    let message = e.to_string();
    assert!(message.contains("--max-memory-mb"), "{message}");
    assert!(message.contains("SampleOptions::max_memory"), "{message}");
}

#[test]
fn the_tables_grow_linearly_with_the_normal_form() {
    let per_literal = |n: usize| {
        let scene = crossed_unions(n);
        let dnf = scene.dnf().unwrap();
        let cost = sampling_cost(&dnf, scene.bounds.unwrap());
        assert_eq!(cost.literals, (n << n) as u64);
        (
            cost.regions / cost.literals,
            cost.bytes as f64 / cost.literals as f64,
        )
    };
    let (regions_8, bytes_8) = per_literal(8);
    let (regions_12, bytes_12) = per_literal(12);
    // Every literal instance has the same heightfields and basic regions.
    assert_eq!(regions_8, regions_12);
    // Before: 272 bytes per job and 168 per result slot, 72 regions per
    // literal instance here: about 33 KB per literal instance. Now a job is
    // 12 bytes and a result slot 24 (about 4.2 KB with the six heightfields),
    // and the distance tables belong to the threads, not to the literals.
    for bytes in [bytes_8, bytes_12] {
        assert!(bytes < 6_000.0, "{bytes} bytes per literal instance");
    }
    assert!(
        (bytes_12 / bytes_8 - 1.0).abs() < 0.25,
        "{bytes_8} {bytes_12}"
    );
}

#[test]
fn the_estimate_counts_what_sample_builds() {
    for name in ["three_spheres", "classic", "sharp8", "machine80"] {
        let scene = common::scene(name);
        let dnf = scene.dnf().unwrap();
        let sphere = scene.bounds.unwrap();
        let cost = sampling_cost(&dnf, sphere);
        // The shipped scenes need a few MB at most.
        assert!(cost.bytes < DEFAULT_MAX_MEMORY / 100, "{name}: {cost:?}");
        let options = SampleOptions::new(sphere.radius / 8.0, sphere).unwrap();
        let set = sample(&dnf, &options).unwrap();
        assert_eq!(cost.patches, set.patches.len() as u64, "{name}");
        assert_eq!(cost.regions, set.stats.basic_regions, "{name}");
    }
}

#[test]
fn a_lowered_limit_refuses_a_small_scene() {
    let scene = common::scene("classic");
    let dnf = scene.dnf().unwrap();
    let sphere = scene.bounds.unwrap();
    let mut options = SampleOptions::new(2.0, sphere).unwrap();
    options.max_memory = 1000;
    assert!(matches!(
        sample(&dnf, &options),
        Err(Error::SamplingTooLarge { limit: 1000, .. })
    ));
    options.max_memory = sampling_cost(&dnf, sphere).bytes;
    assert!(sample(&dnf, &options).is_ok());
}
