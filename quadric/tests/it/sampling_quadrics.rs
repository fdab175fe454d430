//! Sampling single quadrics of every kind (degenerate frames included) and
//! degenerate trees: coverage against the reference tracer, soundness, and
//! no panics.

use crate::common;

use chisel_quadric::csg::{CsgDag, Dnf};
use chisel_quadric::{
    BoundingSphere, Error, NO_HIT, Quadric, SampleOptions, SplatSet, sample, trace_image,
};
use glam::{DVec2, DVec3};

fn dnf_of(q: Quadric) -> Dnf {
    let mut dag = CsgDag::new();
    let root = dag.primitive(q, [1.0; 3]);
    Dnf::from_dag(&dag, root).unwrap()
}

/// Samples `dnf` in the sphere of radius 2 at the origin with radius `r`
/// and checks soundness and coverage of the traced surface.
fn check(dnf: &Dnf, r: f64, what: &str) -> usize {
    let sphere = BoundingSphere::new(DVec3::ZERO, 2.0).unwrap();
    let options = SampleOptions::new(r, sphere).unwrap();
    let set = sample(dnf, &options).unwrap();
    for s in &set.samples {
        let q = &dnf.quadrics()[set.patch_of(s).quadric as usize].quadric;
        let (p, n) = (s.position.as_dvec3(), set.normal_of(dnf, s));
        // Stored in f32: on the surface up to that rounding.
        let rounding = common::f32_rounding(p);
        let g = q.gradient(p).length();
        assert!(
            q.value(p).abs() <= 1e-10 * g.max(1e-3) + g * rounding,
            "{what}: sample {p} off its quadric"
        );
        assert!(sphere.signed_distance(p) <= 1e-9 + rounding);
        // On the CSG surface: inside just behind, outside just in front.
        if n != DVec3::ZERO {
            let eps = 1e-9 + 4.0 * rounding;
            assert!(
                dnf.contains(p - n * eps) && !dnf.contains(p + n * eps),
                "{what}: sample {p} not on the CSG surface"
            );
        }
    }
    let grid = common::SampleGrid::new(&set, r);
    let mut checked = 0;
    for camera in common::cameras(DVec3::ZERO, 6.0, 32) {
        let image = trace_image(dnf, &camera);
        for (i, &q) in image.quadric.iter().enumerate() {
            if q == NO_HIT {
                continue;
            }
            let ray = camera.ray(i as u32 % camera.width, i as u32 / camera.width);
            let p = ray.at(image.depth[i]);
            if sphere.signed_distance(p) > -1e-6 {
                continue;
            }
            checked += 1;
            assert!(grid.covered(q, p, 1e-9), "{what}: uncovered {p}");
        }
    }
    checked
}

#[test]
fn every_kind_is_covered() {
    let mut rng = common::rng(77);
    let mut checked = 0;
    for kind in 0..common::KINDS * 3 {
        let q = common::quadric_of_kind(&mut rng, kind);
        checked += check(&dnf_of(q), 0.15, &format!("kind {kind}"));
    }
    assert!(checked > 20_000, "{checked}");
}

#[test]
fn named_degenerate_quadrics() {
    let shapes = [
        ("plane", Quadric::half_space(DVec3::new(1.0, 2.0, 2.0), 0.3)),
        ("cylinder", Quadric::cylinder(DVec3::ZERO, DVec3::Z, 0.7)),
        (
            "cone",
            Quadric::cone(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0), 0.5),
        ),
        (
            "paraboloid",
            Quadric::elliptic_paraboloid(DVec2::new(0.5, 1.0)),
        ),
        (
            "saddle",
            Quadric::hyperbolic_paraboloid(DVec2::new(0.7, 1.0)),
        ),
        (
            "tiny sphere",
            Quadric::sphere(DVec3::new(0.3, 0.2, 0.1), 0.01),
        ),
        (
            "tangent sphere",
            Quadric::sphere(DVec3::new(3.0, 0.0, 0.0), 1.0),
        ),
    ];
    for (name, q) in shapes {
        check(&dnf_of(q.unwrap()), 0.1, name);
    }
    // The tiny sphere (radius r/10) still gets a sample.
    let tiny = dnf_of(Quadric::sphere(DVec3::ZERO, 0.01).unwrap());
    let sphere = BoundingSphere::new(DVec3::ZERO, 2.0).unwrap();
    let set = sample(&tiny, &SampleOptions::new(0.1, sphere).unwrap()).unwrap();
    assert!(!set.samples.is_empty());
}

#[test]
fn empty_and_surfaceless_trees_give_nothing() {
    let sphere = BoundingSphere::new(DVec3::ZERO, 2.0).unwrap();
    let options = SampleOptions::new(0.1, sphere).unwrap();
    // A ∩ ¬A: no products.
    let mut dag = CsgDag::new();
    let a = dag.primitive(Quadric::sphere(DVec3::ZERO, 1.0).unwrap(), [1.0; 3]);
    let not_a = dag.complement(a).unwrap();
    let root = dag.intersection(&[a, not_a]).unwrap();
    let empty = Dnf::from_dag(&dag, root).unwrap();
    let set = sample(&empty, &options).unwrap();
    assert!(set.samples.is_empty());
    assert!(SplatSet::new(&empty, &dag, &set).splats.is_empty());
    let camera = chisel_quadric::Camera::new(DVec3::splat(5.0), DVec3::ZERO, 40.0, 8, 8).unwrap();
    assert!(
        trace_image(&empty, &camera)
            .quadric
            .iter()
            .all(|&q| q == NO_HIT)
    );
    // x² + 1 < 0: no real surface.
    let none = Quadric::from_coefficients([1., 0., 0., 0., 0., 0., 0., 0., 0., 1.]).unwrap();
    assert!(sample(&dnf_of(none), &options).unwrap().samples.is_empty());
    // A sphere far outside the bounding sphere.
    let far = Quadric::sphere(DVec3::splat(10.0), 1.0).unwrap();
    assert!(sample(&dnf_of(far), &options).unwrap().samples.is_empty());
    // Two disjoint spheres intersected.
    let mut dag = CsgDag::new();
    let a = dag.primitive(Quadric::sphere(DVec3::ZERO, 0.5).unwrap(), [1.0; 3]);
    let b = dag.primitive(Quadric::sphere(DVec3::X, 0.4).unwrap(), [1.0; 3]);
    let root = dag.intersection(&[a, b]).unwrap();
    let disjoint = Dnf::from_dag(&dag, root).unwrap();
    assert!(sample(&disjoint, &options).unwrap().samples.is_empty());
}

#[test]
fn bad_options_are_errors() {
    assert!(matches!(
        BoundingSphere::new(DVec3::ZERO, 0.0),
        Err(Error::NonPositive { .. })
    ));
    assert!(matches!(
        BoundingSphere::new(DVec3::splat(f64::NAN), 1.0),
        Err(Error::NonFinite { .. })
    ));
    let sphere = BoundingSphere::new(DVec3::ZERO, 1.0).unwrap();
    assert!(SampleOptions::new(-1.0, sphere).is_err());
    assert!(SampleOptions::new(f64::NAN, sphere).is_err());
    let mut options = SampleOptions::new(0.1, sphere).unwrap();
    options.min_region_fraction = f64::NAN;
    let dnf = dnf_of(Quadric::sphere(DVec3::ZERO, 0.5).unwrap());
    assert!(sample(&dnf, &options).is_err());
}

#[test]
fn shared_surfaces_are_covered() {
    // A bore through two unioned, overlapping blocks: its wall in the
    // overlap belongs to both products (the same literal twice).
    let mut dag = CsgDag::new();
    let a = dag
        .cuboid(
            DVec3::new(-1.5, -1.0, -1.0),
            DVec3::new(0.2, 1.0, 1.0),
            [1.0; 3],
        )
        .unwrap();
    let b = dag
        .cuboid(
            DVec3::new(-0.2, -1.0, -1.0),
            DVec3::new(1.5, 1.0, 1.0),
            [1.0; 3],
        )
        .unwrap();
    let bore = dag.primitive(
        Quadric::cylinder(DVec3::ZERO, DVec3::X, 0.5).unwrap(),
        [1.0; 3],
    );
    let blocks = dag.union(&[a, b]).unwrap();
    let root = dag.difference(blocks, &[bore]).unwrap();
    let dnf = Dnf::from_dag(&dag, root).unwrap();
    assert_eq!(dnf.products().len(), 2);
    assert!(check(&dnf, 0.03, "shared bore") > 1000);
}

#[test]
fn random_trees_are_covered_and_sound() {
    use rand::Rng;
    let mut rng = common::rng(2024);
    let mut checked = 0;
    for case in 0..64 {
        let mut dag = CsgDag::new();
        let mut terms = Vec::new();
        for _ in 0..2 {
            let mut factors = Vec::new();
            for _ in 0..rng.random_range(1..=3) {
                let q = common::quadric(&mut rng);
                let mut node = dag.primitive(q, [1.0; 3]);
                if rng.random_bool(0.3) {
                    node = dag.complement(node).unwrap();
                }
                factors.push(node);
            }
            terms.push(dag.intersection(&factors).unwrap());
        }
        let root = dag.union(&terms).unwrap();
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        checked += check(&dnf, 0.12, &format!("random tree {case}"));
    }
    assert!(checked > 10_000, "{checked}");
}
