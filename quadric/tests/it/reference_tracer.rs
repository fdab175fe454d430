//! The reference ray tracer agrees with brute-force point classification:
//! no point before the hit is inside the solid, the point just after an
//! entry is, and a missed ray stays outside.

use crate::common;

use chisel_quadric::{Camera, NO_HIT, Ray, trace_image, trace_ray};
use glam::DVec3;

const SCENES: [(&str, [f64; 3], f64); 4] = [
    ("three_spheres", [0.0, 0.0, 10.0], 75.0),
    ("classic", [0.0, 0.0, 0.0], 90.0),
    ("sharp8", [0.0, 0.0, 0.0], 60.0),
    ("machine80", [0.0, 0.0, 35.0], 110.0),
];

#[test]
fn hits_agree_with_point_classification() {
    let mut rng = common::rng(5);
    for (name, centre, bound) in SCENES {
        let dnf = common::scene(name).dnf().unwrap();
        let centre = DVec3::from(centre);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..400 {
            let eye = centre + common::unit(&mut rng) * 2.5 * bound;
            let target = centre + common::point(&mut rng, 0.6 * bound);
            let ray = Ray::new(eye, (target - eye).normalize()).unwrap();
            let eps = 1e-7 * bound;
            let far = 4.0 * bound;
            let steps = 2000;
            match trace_ray(&dnf, &ray, 0.0) {
                Some(hit) => {
                    hits += 1;
                    assert!(
                        dnf.contains(ray.at(hit.t + eps)),
                        "{name}: not inside after hit"
                    );
                    for k in 0..steps {
                        let t = (hit.t - eps) * f64::from(k) / f64::from(steps);
                        assert!(!dnf.contains(ray.at(t)), "{name}: inside before the hit");
                    }
                    let q = &dnf.quadrics()[hit.quadric as usize].quadric;
                    let g = q.gradient(hit.point).length();
                    assert!(q.value(hit.point).abs() <= 1e-9 * g * bound);
                    assert!(
                        hit.normal.dot(ray.direction) < 0.0,
                        "{name}: normal faces away"
                    );
                    assert!((hit.point - ray.at(hit.t)).length() < 1e-9 * bound);
                }
                None => {
                    misses += 1;
                    for k in 0..steps {
                        let t = far * f64::from(k) / f64::from(steps);
                        assert!(!dnf.contains(ray.at(t)), "{name}: missed ray passes inside");
                    }
                }
            }
        }
        assert!(
            hits > 50 && misses > 10,
            "{name}: {hits} hits, {misses} misses"
        );
    }
}

#[test]
fn images_match_single_rays() {
    let dnf = common::scene("classic").dnf().unwrap();
    let camera = Camera::new(DVec3::new(180.0, 120.0, 90.0), DVec3::ZERO, 45.0, 40, 30).unwrap();
    let image = trace_image(&dnf, &camera);
    assert_eq!(image.depth.len(), 40 * 30);
    let mut hit = 0;
    for y in 0..30 {
        for x in 0..40 {
            let i = (y * 40 + x) as usize;
            match trace_ray(&dnf, &camera.ray(x, y), 0.0) {
                Some(h) => {
                    hit += 1;
                    assert_eq!(image.depth[i], h.t);
                    assert_eq!(image.quadric[i], h.quadric);
                    assert_eq!(image.normal[i], h.normal);
                }
                None => {
                    assert_eq!(image.quadric[i], NO_HIT);
                    assert!(image.depth[i].is_infinite());
                }
            }
        }
    }
    // The object fills the middle of the view but not the corners.
    assert!(hit > 200 && hit < 40 * 30);
    assert_eq!(image.quadric[0], NO_HIT);
}

#[test]
fn camera_inside_sees_the_exit() {
    let dnf = common::scene("three_spheres").dnf().unwrap();
    let ray = Ray::new(DVec3::new(0.0, 0.0, 30.0), DVec3::Z).unwrap();
    let hit = trace_ray(&dnf, &ray, 0.0).unwrap();
    // Sphere C: centre (0, 0, 30), radius 25.
    assert!((hit.t - 25.0).abs() < 1e-9);
    assert!(hit.normal.dot(DVec3::Z) > 0.99);
    assert!(Camera::new(DVec3::ZERO, DVec3::ZERO, 40.0, 4, 4).is_err());
    assert!(Camera::new(DVec3::ONE, DVec3::ZERO, 0.0, 4, 4).is_err());
    assert!(Camera::new(DVec3::ONE, DVec3::ZERO, 40.0, 0, 4).is_err());
}
