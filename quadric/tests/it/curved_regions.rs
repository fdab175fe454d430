//! The curved basic regions of §4.1 (elliptic and hyperbolic triangles) on
//! trimmed scenes: they are built and filled, dense reference points inside
//! each of them that lie on the CSG surface are covered by a sample on the
//! same quadric, traced surface points are covered, and every sample lies
//! on its quadric and on the CSG surface.

use crate::common;

use chisel_quadric::csg::Dnf;
use chisel_quadric::sampling::basic::basic_regions;
use chisel_quadric::sampling::regions::{Region, RegionKind};
use chisel_quadric::{
    NO_HIT, QuadricDistance, SampleOptions, SampleSet, Scene, sample, trace_image,
};
use glam::{DVec2, DVec3};

/// A unit ball cut by a slanted cylinder: the ball's caps are trimmed
/// across its elliptic triangles (the cylinder passes through them).
const BALL_IN_CYLINDER: &str = r#"Scene(
    primitives: [
        (name: "ball", shape: Sphere(center: (0, 0, 0), radius: 1)),
        (name: "tube", shape: Cylinder(point: (0.05, 0, 0), axis: (0.2, 0.1, 1), radius: 0.8)),
    ],
    root: Intersection([Ref("ball"), Ref("tube")]),
    bounds: (0, 0, 0, 1.5),
)"#;

/// A one-sheet hyperboloid between two planes, with a bore across: the
/// side planes' hyperbolic triangles are trimmed by the bore and the planes.
const BORED_TOWER: &str = r#"Scene(
    primitives: [
        (name: "tower", shape: HyperboloidOneSheet(radii: (1, 1, 0.7))),
        (name: "top", shape: HalfSpace(normal: (0, 0, 1), offset: 1.2)),
        (name: "bottom", shape: HalfSpace(normal: (0, 0, -1), offset: 1.2)),
        (name: "bore", shape: Cylinder(point: (0, 0, 0.3), axis: (1, 0.2, 0), radius: 0.4)),
    ],
    root: Difference([Intersection([Ref("tower"), Ref("top"), Ref("bottom")]), Ref("bore")]),
    bounds: (0, 0, 0, 3),
)"#;

fn sampled(text: &str, radius: f64) -> (Dnf, SampleSet) {
    // Scenes here are written in this file.
    let scene = Scene::from_ron(text).unwrap();
    let dnf = scene.dnf().unwrap();
    let options = SampleOptions::new(radius, scene.bounds.unwrap()).unwrap();
    let set = sample(&dnf, &options).unwrap();
    (dnf, set)
}

/// Every sample lies on its quadric, in the bounds and on the CSG surface.
fn check_sound(dnf: &Dnf, set: &SampleSet, what: &str) {
    let bound = set.options.bounds.radius;
    for s in &set.samples {
        let q = &dnf.quadrics()[set.patch_of(s).quadric as usize].quadric;
        let (p, n) = (s.position.as_dvec3(), set.normal_of(dnf, s));
        // Stored in f32: on the surface up to that rounding.
        let rounding = common::f32_rounding(p);
        let g = q.gradient(p).length();
        assert!(
            q.value(p).abs() <= g * (1e-12 * bound + rounding),
            "{what}: sample {p} off its quadric"
        );
        assert!(s.radius > 0.0 && f64::from(s.radius) <= common::largest_radius(set));
        assert!(set.options.bounds.signed_distance(p) <= 1e-9 * bound + rounding);
        if n != DVec3::ZERO {
            let eps = 1e-7 * bound + 4.0 * rounding;
            assert!(
                dnf.contains(p - n * eps) && !dnf.contains(p + n * eps),
                "{what}: sample {p} not on the CSG surface"
            );
        }
    }
}

/// Dense points in every curved basic region of every sampled heightfield;
/// those on the CSG surface, away from the trimming curves by more than the
/// paper's threshold, must be covered by a sample of the same quadric.
/// Returns the number of points checked per kind.
fn check_curved_coverage(dnf: &Dnf, set: &SampleSet, what: &str) -> [usize; RegionKind::COUNT] {
    let r = set.options.radius;
    let sphere = set.options.bounds;
    let grid = common::SampleGrid::new(set, r);
    let distances: Vec<QuadricDistance> = dnf
        .quadrics()
        .iter()
        .map(|q| QuadricDistance::new(&q.quadric))
        .collect();
    let mut checked = [0; RegionKind::COUNT];
    for patch in &set.patches {
        let hf = &patch.heightfield;
        let c = hf.project(sphere.centre);
        let (lo, hi) = (
            c - DVec2::splat(sphere.radius),
            c + DVec2::splat(sphere.radius),
        );
        let q = &dnf.quadrics()[patch.quadric as usize].quadric;
        for (region, kind) in basic_regions(hf, lo, hi) {
            let Region::Curved(tri) = region else {
                continue;
            };
            let [a, b, w] = *tri.warped();
            let n = 40;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (s, t) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
                    let uv = tri.warp().from_w(a + (b - a) * s + (w - a) * t);
                    let Some(p) = hf.point(uv) else {
                        continue;
                    };
                    if sphere.signed_distance(p) > -0.01 * r {
                        continue;
                    }
                    let near_feature = distances
                        .iter()
                        .enumerate()
                        .any(|(k, d)| k != patch.quadric as usize && d.distance(p).abs() < 0.2 * r);
                    if near_feature {
                        continue;
                    }
                    let Some(normal) = q.normal(p) else {
                        continue;
                    };
                    let eps = 1e-6 * sphere.radius;
                    if dnf.contains(p - normal * eps) == dnf.contains(p + normal * eps) {
                        continue; // not on the CSG surface
                    }
                    checked[kind.index()] += 1;
                    assert!(
                        grid.covered(patch.quadric, p, 1e-9),
                        "{what}: {p} in a {kind:?} of quadric {} uncovered",
                        patch.quadric
                    );
                }
            }
        }
    }
    checked
}

/// Traced surface points inside the bounds are covered by a sample of the
/// same quadric; returns how many were checked.
fn check_traced_coverage(dnf: &Dnf, set: &SampleSet, what: &str) -> usize {
    let sphere = set.options.bounds;
    let grid = common::SampleGrid::new(set, set.options.radius);
    let mut checked = 0;
    for camera in common::cameras(sphere.centre, 2.5 * sphere.radius, 48) {
        let image = trace_image(dnf, &camera);
        for (i, &q) in image.quadric.iter().enumerate() {
            if q == NO_HIT {
                continue;
            }
            let ray = camera.ray(i as u32 % camera.width, i as u32 / camera.width);
            let p = ray.at(image.depth[i]);
            if sphere.signed_distance(p) > -1e-9 * sphere.radius {
                continue;
            }
            checked += 1;
            assert!(grid.covered(q, p, 1e-9), "{what}: traced {p} uncovered");
        }
    }
    checked
}

#[test]
fn trimmed_elliptic_triangles_are_covered_and_sound() {
    for radius in [0.12, 0.04] {
        let (dnf, set) = sampled(BALL_IN_CYLINDER, radius);
        let what = format!("ball in cylinder, r = {radius}");
        let elliptic = RegionKind::EllipticTriangle.index();
        assert!(set.stats.kinds[elliptic] > 0, "{what}: {:?}", set.stats);
        assert!(
            set.stats.kind_samples[elliptic] > 0,
            "{what}: {:?}",
            set.stats
        );
        check_sound(&dnf, &set, &what);
        let checked = check_curved_coverage(&dnf, &set, &what);
        eprintln!("{what}: {checked:?} {:?}", set.stats);
        assert!(checked[elliptic] > 500, "{what}: {checked:?}");
        assert!(check_traced_coverage(&dnf, &set, &what) > 5000);
    }
}

#[test]
fn trimmed_hyperbolic_triangles_are_covered_and_sound() {
    for radius in [0.2, 0.06] {
        let (dnf, set) = sampled(BORED_TOWER, radius);
        let what = format!("bored tower, r = {radius}");
        let hyperbolic = RegionKind::HyperbolicTriangle.index();
        assert!(set.stats.kinds[hyperbolic] > 0, "{what}: {:?}", set.stats);
        assert!(
            set.stats.kind_samples[hyperbolic] > 0,
            "{what}: {:?}",
            set.stats
        );
        check_sound(&dnf, &set, &what);
        let checked = check_curved_coverage(&dnf, &set, &what);
        eprintln!("{what}: {checked:?} {:?}", set.stats);
        assert!(checked[hyperbolic] > 500, "{what}: {checked:?}");
        assert!(check_traced_coverage(&dnf, &set, &what) > 5000);
    }
}

#[test]
fn whole_curved_triangles_are_covered_and_sound() {
    // Untrimmed surfaces: basic regions are filled as a whole, where their
    // distortion varies most (from about 1.2 to √3 on a sphere).
    let scenes = [
        (
            "ellipsoid",
            "Ellipsoid(center: (0, 0, 0), radii: (1, 0.8, 1.3))",
            2.0,
        ),
        ("tower", "HyperboloidOneSheet(radii: (1, 0.9, 0.7))", 2.5),
        ("paraboloid", "EllipticParaboloid(radii: (0.7, 1))", 2.5),
    ];
    for (name, shape, bound) in scenes {
        let text = format!(
            "Scene(primitives: [(name: \"q\", shape: {shape})], root: Ref(\"q\"), \
             bounds: (0.1, -0.2, 0.1, {bound}))"
        );
        for radius in [0.1, 0.03] {
            let (dnf, set) = sampled(&text, radius);
            let what = format!("{name}, r = {radius}");
            check_sound(&dnf, &set, &what);
            let checked = check_curved_coverage(&dnf, &set, &what);
            let curved = checked[RegionKind::EllipticTriangle.index()]
                + checked[RegionKind::HyperbolicTriangle.index()]
                + checked[RegionKind::ParabolicTriangle.index()];
            assert!(curved > 5000, "{what}: {checked:?}");
        }
    }
}

#[test]
fn curved_output_is_independent_of_thread_count() {
    for text in [BALL_IN_CYLINDER, BORED_TOWER] {
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| sampled(text, 0.05).1)
        };
        assert_eq!(run(1), run(2));
    }
}
