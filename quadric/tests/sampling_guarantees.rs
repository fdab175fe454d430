//! The sampling guarantees of §4.2 on the shipped scenes: coverage (every
//! traced surface point has a sample on the same quadric within the splat
//! radius), soundness (samples lie on their quadric and on the CSG surface),
//! and thread-count independence.

mod common;

use chisel_quadric::csg::Dnf;
use chisel_quadric::{BoundingSphere, SampleOptions, SampleSet, sample, trace_image};
use glam::DVec3;

/// `(scene, bounding centre, bounding radius)`.
const SCENES: [(&str, [f64; 3], f64); 4] = [
    ("three_spheres", [0.0, 0.0, 10.0], 75.0),
    ("classic", [0.0, 0.0, 0.0], 90.0),
    ("sharp8", [0.0, 0.0, 0.0], 60.0),
    ("machine80", [0.0, 0.0, 35.0], 110.0),
];

fn sampled(name: &str, centre: [f64; 3], bound: f64, radius: f64) -> (Dnf, SampleSet) {
    let dnf = common::scene(name).dnf().unwrap();
    let sphere = BoundingSphere::new(DVec3::from(centre), bound).unwrap();
    let options = SampleOptions::new(radius, sphere).unwrap();
    let set = sample(&dnf, &options).unwrap();
    (dnf, set)
}

#[test]
fn traced_surface_is_covered() {
    for (name, centre, bound) in SCENES {
        for radius in [bound / 8.0, bound / 25.0] {
            let (dnf, set) = sampled(name, centre, bound, radius);
            assert!(!set.samples.is_empty(), "{name}: no samples");
            let grid = common::SampleGrid::new(&set, radius);
            let sphere = set.options.bounds;
            let (mut checked, mut missed) = (0, 0);
            for camera in common::cameras(DVec3::from(centre), 2.5 * bound, 48) {
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
    for (name, centre, bound) in SCENES {
        let (dnf, set) = sampled(name, centre, bound, bound / 25.0);
        let eps = 1e-7 * bound;
        for s in &set.samples {
            let q = &dnf.quadrics()[s.quadric as usize].quadric;
            let g = q.gradient(s.position).length();
            assert!(
                q.value(s.position).abs() <= 1e-12 * g * bound,
                "{name}: sample {} off its quadric",
                s.position
            );
            assert!(s.radius > 0.0 && s.radius <= set.options.radius);
            assert!(set.options.bounds.signed_distance(s.position) <= eps);
            // On the CSG surface: inside on one side, outside on the other,
            // unless the normal is degenerate (a cone's apex).
            if s.normal != DVec3::ZERO {
                let inside = dnf.contains(s.position - s.normal * eps);
                let outside = !dnf.contains(s.position + s.normal * eps);
                assert!(
                    inside && outside,
                    "{name}: sample {} not on the surface",
                    s.position
                );
            }
        }
    }
}

#[test]
fn output_is_independent_of_thread_count() {
    for (name, centre, bound) in SCENES {
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| sampled(name, centre, bound, bound / 20.0).1)
        };
        assert_eq!(run(1), run(2), "{name}");
    }
}
