//! Ray–quadric intersection: roots lie on the quadric, agree with brute-force
//! sign sampling along the ray, and degenerate directions (near-zero leading
//! coefficient, rulings) are handled.

use crate::common;

use chisel_quadric::{Quadric, Ray};
use glam::{DVec2, DVec3};

/// `|Q(x)|` small relative to the size of the terms that make it up.
fn on_surface(q: &Quadric, x: DVec3) -> bool {
    let g = q.gradient(x).length();
    q.value(x).abs() <= 1e-9 * (g * (1.0 + x.length()) + q.max_abs_coefficient())
}

#[test]
fn roots_lie_on_the_quadric() {
    let mut rng = common::rng(31);
    let mut roots = 0;
    for _ in 0..5000 {
        let q = common::quadric(&mut rng);
        let ray = Ray::new(common::point(&mut rng, 3.0), common::unit(&mut rng)).unwrap();
        for hit in q.intersect_line(&ray).hits() {
            let x = ray.at(hit.t);
            assert!(on_surface(&q, x), "Q({x}) = {} for {q:?}", q.value(x));
            roots += 1;
        }
    }
    assert!(roots > 3000, "{roots}");
}

#[test]
fn spans_agree_with_brute_force_sampling() {
    let mut rng = common::rng(32);
    const N: usize = 4000;
    const T: f64 = 8.0;
    for case in 0..2000 {
        let q = common::quadric(&mut rng);
        let ray = Ray::new(common::point(&mut rng, 2.0), common::unit(&mut rng)).unwrap();
        let hits = q.intersect_line(&ray);
        let in_range: Vec<f64> = hits
            .hits()
            .iter()
            .map(|h| h.t)
            .filter(|t| t.abs() < T)
            .collect();
        let step = 2.0 * T / N as f64;
        let mut changes = Vec::new();
        let mut prev = q.value(ray.at(-T));
        for k in 1..=N {
            let t = -T + k as f64 * step;
            let v = q.value(ray.at(t));
            if (v < 0.0) != (prev < 0.0) {
                changes.push(t - 0.5 * step);
            }
            // Away from roots, `contains` matches the sign of Q.
            if in_range.iter().all(|r| (r - t).abs() > 1e-6) && v.abs() > 1e-9 {
                assert_eq!(hits.contains(t), v < 0.0, "case {case} at t = {t}");
            }
            prev = v;
        }
        // Every sign change has a computed root within half a step.
        for c in &changes {
            assert!(
                in_range.iter().any(|r| (r - c).abs() <= 0.5 * step + 1e-9),
                "case {case}: sign change near {c}, roots {in_range:?}"
            );
        }
        // Every root well inside the range is a sign change (or a tangency).
        let tangent = hits.spans().iter().any(|s| s.entry == s.exit);
        if !tangent {
            let inner = in_range.iter().filter(|r| r.abs() < T - step).count();
            assert!(
                inner <= changes.len(),
                "case {case}: {in_range:?} vs {changes:?}"
            );
        }
    }
}

#[test]
fn nearly_parallel_to_cylinder_axis() {
    let q = Quadric::cylinder(DVec3::ZERO, DVec3::Z, 1.0).unwrap();
    // Resolvable slopes: a = eps² is above the rounding noise of vᵀAv.
    for eps in [1e-3, 1e-5, 1e-6] {
        let ray = Ray::new(DVec3::new(2.0, 0.0, 0.0), DVec3::new(-eps, 0.0, 1.0)).unwrap();
        let hits = q.intersect_line(&ray).hits();
        assert!(!hits.is_empty(), "eps {eps}");
        let first = hits[0];
        assert!(first.entering);
        assert!(
            (first.t * eps - 1.0).abs() < 1e-6,
            "eps {eps}: t = {}",
            first.t
        );
        if let Some(second) = hits.get(1) {
            assert!((second.t * eps - 3.0).abs() < 1e-6);
        }
    }
    // Below the noise the equation is taken as linear: still one far entry.
    for eps in [1e-9, 1e-12] {
        let ray = Ray::new(DVec3::new(2.0, 0.0, 0.0), DVec3::new(-eps, 0.0, 1.0)).unwrap();
        let first = q.intersect_line(&ray).first_hit_after(0.0).unwrap();
        assert!(first.entering && (0.5..1.5).contains(&(first.t * eps)));
    }
}

#[test]
fn paraboloid_axis_is_linear() {
    let q = Quadric::elliptic_paraboloid(DVec2::ONE).unwrap();
    let ray = Ray::new(DVec3::new(0.5, 0.0, -10.0), DVec3::Z).unwrap();
    let h = q.intersect_line(&ray);
    assert_eq!(h.spans().len(), 1);
    assert!((h.spans()[0].entry - 10.25).abs() < 1e-12);
    assert_eq!(h.spans()[0].exit, f64::INFINITY);
}

#[test]
fn parallel_to_cone_generator() {
    // x² + y² − z² with the line (0,0,1) + t(1,0,1): Q = −1 − 2t.
    let q = Quadric::cone(DVec3::ZERO, DVec3::Z, std::f64::consts::FRAC_PI_4).unwrap();
    let ray = Ray::new(DVec3::Z, DVec3::new(1.0, 0.0, 1.0)).unwrap();
    let h = q.intersect_line(&ray);
    assert_eq!(h.spans().len(), 1);
    assert!((h.spans()[0].entry + 0.5).abs() < 1e-12);
    // Along the generator itself the whole line is in the surface.
    let ruling = Ray::new(DVec3::new(1.0, 0.0, 1.0), DVec3::new(1.0, 0.0, 1.0)).unwrap();
    assert!(q.intersect_line(&ruling).lies_in_surface());
}

#[test]
fn rulings_of_rotated_hyperboloid_and_saddle() {
    let mut rng = common::rng(33);
    for _ in 0..100 {
        let m = common::rigid(&mut rng);
        let h1 = Quadric::hyperboloid_one_sheet(DVec3::ONE)
            .unwrap()
            .transformed(&m)
            .unwrap();
        // (1, 0, 0) + t(0, 1, 1) lies on x² + y² − z² = 1.
        let o = m.transform_point3(DVec3::X);
        let d = m.transform_vector3(DVec3::new(0.0, 1.0, 1.0));
        assert!(
            h1.intersect_line(&Ray::new(o, d).unwrap())
                .lies_in_surface()
        );
        // x² − y² = z contains (s, s, 0) + t(1, −1, ... ): take s = 1:
        // (1 + t)² − (1 − t)² = 4t = z, so the line (1, 1, 0) + t(1, −1, 4).
        let hp = Quadric::hyperbolic_paraboloid(DVec2::ONE)
            .unwrap()
            .transformed(&m)
            .unwrap();
        let o = m.transform_point3(DVec3::new(1.0, 1.0, 0.0));
        let d = m.transform_vector3(DVec3::new(1.0, -1.0, 4.0));
        assert!(
            hp.intersect_line(&Ray::new(o, d).unwrap())
                .lies_in_surface()
        );
    }
}

#[test]
fn tangent_ray_touches_once() {
    let q = Quadric::sphere(DVec3::ZERO, 1.0).unwrap();
    let ray = Ray::new(DVec3::new(-5.0, 1.0, 0.0), DVec3::X).unwrap();
    let h = q.intersect_line(&ray);
    assert_eq!(h.spans().len(), 1);
    assert!((h.spans()[0].entry - 5.0).abs() < 1e-7);
    assert!((h.spans()[0].exit - h.spans()[0].entry).abs() < 1e-7);
}
