//! The sampling guarantees of §4.2 on the shipped scenes: coverage (every
//! traced surface point has a sample on the same quadric within the splat
//! radius), soundness (samples lie on their quadric and on the CSG surface),
//! and thread-count independence.

use crate::common;

use chisel_quadric::csg::Dnf;
use chisel_quadric::{SampleOptions, SampleSet, sample, trace_image};
use glam::DVec3;

/// The shipped scenes, sampled inside the bounds their files give.
const SCENES: [&str; 4] = ["three_spheres", "classic", "sharp8", "machine80"];

/// A scene's bounding sphere as `(centre, radius)`.
fn bounds(name: &str) -> (DVec3, f64) {
    let b = common::scene(name)
        .bounds
        .expect("shipped scenes give bounds");
    (b.centre, b.radius)
}

fn sampled(name: &str, radius: f64) -> (Dnf, SampleSet) {
    let scene = common::scene(name);
    let dnf = scene.dnf().unwrap();
    let sphere = scene.bounds.unwrap();
    let options = SampleOptions::new(radius, sphere).unwrap();
    let set = sample(&dnf, &options).unwrap();
    (dnf, set)
}

#[test]
fn traced_surface_is_covered() {
    for name in SCENES {
        let (centre, bound) = bounds(name);
        for radius in [bound / 8.0, bound / 25.0] {
            let (dnf, set) = sampled(name, radius);
            assert!(!set.samples.is_empty(), "{name}: no samples");
            let grid = common::SampleGrid::new(&set, radius);
            let sphere = set.options.bounds;
            let (mut checked, mut missed) = (0, 0);
            for camera in common::cameras(centre, 2.5 * bound, 48) {
                let image = trace_image(&dnf, &camera);
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
                        eprintln!("{name} r={radius}: uncovered {p} on quadric {q}");
                    }
                }
            }
            assert!(checked > 1000, "{name}: only {checked} reference points");
            assert_eq!(
                missed, 0,
                "{name} r={radius}: {missed} of {checked} uncovered"
            );
        }
    }
}

#[test]
fn samples_lie_on_the_csg_surface() {
    for name in SCENES {
        let (_, bound) = bounds(name);
        let (dnf, set) = sampled(name, bound / 25.0);
        for s in &set.samples {
            let q = &dnf.quadrics()[set.patch_of(s).quadric as usize].quadric;
            let (p, n) = (s.position.as_dvec3(), set.normal_of(&dnf, s));
            // Stored in f32: on the surface up to that rounding.
            let rounding = common::f32_rounding(p);
            let eps = 1e-7 * bound + 4.0 * rounding;
            let g = q.gradient(p).length();
            assert!(
                q.value(p).abs() <= g * (1e-12 * bound + rounding),
                "{name}: sample {p} off its quadric"
            );
            assert!(s.radius > 0.0 && f64::from(s.radius) <= common::largest_radius(&set));
            assert!(set.options.bounds.signed_distance(p) <= eps);
            // On the CSG surface: inside on one side, outside on the other,
            // unless the normal is degenerate (a cone's apex).
            if n != DVec3::ZERO {
                let inside = dnf.contains(p - n * eps);
                let outside = !dnf.contains(p + n * eps);
                assert!(inside && outside, "{name}: sample {p} not on the surface");
            }
        }
    }
}

#[test]
fn output_is_independent_of_thread_count() {
    for name in SCENES {
        let (_, bound) = bounds(name);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| sampled(name, bound / 20.0).1)
        };
        assert_eq!(run(1), run(2), "{name}");
    }
}

/// Samples are stored in `f32`: bounds that reach past
/// [`MAX_COORDINATE`](chisel_quadric::MAX_COORDINATE) are refused with a
/// typed error before anything is sampled; the same solid in bounds near
/// the origin is sampled.
#[test]
fn bounds_beyond_the_f32_range_of_samples_are_refused() {
    use chisel_quadric::{BoundingSphere, CsgDag, Error, MAX_COORDINATE, Quadric};
    let mut dag = CsgDag::new();
    let ball = dag.primitive(Quadric::sphere(DVec3::ZERO, 1.0).unwrap(), [0.8; 3]);
    let dnf = Dnf::from_dag(&dag, ball).unwrap();
    let sampled = |centre: DVec3| {
        let bounds = BoundingSphere::new(centre, 1.5).unwrap();
        sample(&dnf, &SampleOptions::new(0.1, bounds).unwrap())
    };
    let far = DVec3::new(0.0, -3.0 * MAX_COORDINATE, 0.0);
    assert!(
        matches!(sampled(far), Err(Error::CoverageNotReached { .. })),
        "{:?}",
        sampled(far).map(|s| s.samples.len())
    );
    assert!(!sampled(DVec3::ZERO).unwrap().samples.is_empty());
}
