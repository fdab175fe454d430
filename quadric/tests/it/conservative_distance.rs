//! Conservative distance (eq. 12) never over-estimates: checked against
//! dense surface samples; and the CSG-relative distance (eq. 22) keeps its
//! classification within its radius.

use crate::common;

use chisel_quadric::csg::{CsgDistance, Dnf};
use chisel_quadric::{Quadric, QuadricDistance, Ray, Scene};
use glam::DVec3;
use rand_chacha::ChaCha8Rng;

/// Surface points of `q` near the origin: hits of many random lines.
fn surface_samples(rng: &mut ChaCha8Rng, q: &Quadric, lines: usize) -> Vec<DVec3> {
    let mut out = Vec::new();
    for _ in 0..lines {
        let ray = Ray::new(common::point(rng, 3.0), common::unit(rng)).unwrap();
        for h in q.intersect_line(&ray).hits() {
            let x = ray.at(h.t);
            if x.length() < 6.0 {
                out.push(x);
            }
        }
    }
    out
}

#[test]
fn never_over_estimates() {
    let mut rng = common::rng(51);
    let mut useful = 0;
    for kind in 0..common::KINDS * 4 {
        let q = common::quadric_of_kind(&mut rng, kind);
        let samples = surface_samples(&mut rng, &q, 3000);
        if samples.is_empty() {
            continue;
        }
        let d = QuadricDistance::new(&q);
        for _ in 0..300 {
            let x = common::point(&mut rng, 3.0);
            let bound = d.distance(x);
            let nearest = samples
                .iter()
                .map(|s| (*s - x).length())
                .fold(f64::INFINITY, f64::min);
            assert!(
                bound.abs() <= nearest * (1.0 + 1e-9) + 1e-9,
                "kind {kind}: bound {bound} > nearest sample {nearest} at {x}"
            );
            let value = q.value(x);
            assert!(bound == 0.0 || (bound < 0.0) == (value < 0.0));
            if bound.abs() > 0.2 * nearest {
                useful += 1;
            }
        }
    }
    // The bound is not trivially zero: mostly within a factor 5 of the truth.
    assert!(useful > 48 * 300 / 2, "{useful}");
}

#[test]
fn csg_distance_is_conservative() {
    let scene = Scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/scenes/classic.quadric.ron"
    ))
    .unwrap();
    let dnf = scene.dnf().unwrap();
    let dist = CsgDistance::new(&dnf);
    let mut rng = common::rng(52);
    for _ in 0..2000 {
        let p = common::point(&mut rng, 80.0);
        let d = dist.distance(p);
        if d != 0.0 {
            assert_eq!(d < 0.0, dnf.contains(p), "sign of d(S) at {p}");
        }
        // No classification change within |d| along random directions.
        for _ in 0..8 {
            let q = p + common::unit(&mut rng) * d.abs() * 0.999;
            assert_eq!(dnf.contains(q), dnf.contains(p), "at {p}, d = {d}");
        }
    }
}

/// Whether surface point `x` of literal `(a, b)` belongs to the CSG surface:
/// inside every other literal of product `a`, in no other product.
fn on_csg_surface(dnf: &Dnf, a: usize, b: usize, x: DVec3) -> bool {
    let holds = |l| dnf.literal_quadric(l).value(x) < 0.0;
    let own = dnf.products()[a]
        .iter()
        .enumerate()
        .all(|(j, &l)| j == b || holds(l));
    let elsewhere = dnf
        .products()
        .iter()
        .enumerate()
        .any(|(i, p)| i != a && p.iter().all(|&l| holds(l)));
    own && !elsewhere
}

#[test]
fn relative_distance_keeps_classification_within_radius() {
    let mut rng = common::rng(53);
    for file in ["three_spheres.quadric.ron", "classic.quadric.ron"] {
        let path = format!("{}/../assets/scenes/{file}", env!("CARGO_MANIFEST_DIR"));
        let dnf = Scene::load(path).unwrap().dnf().unwrap();
        let dist = CsgDistance::new(&dnf);
        let mut decided = 0;
        for (a, product) in dnf.products().iter().enumerate() {
            for (b, &literal) in product.iter().enumerate() {
                let q = dnf.literal_quadric(literal);
                let mut samples = Vec::new();
                for _ in 0..4000 {
                    let ray =
                        Ray::new(common::point(&mut rng, 70.0), common::unit(&mut rng)).unwrap();
                    samples.extend(q.intersect_line(&ray).hits().iter().map(|h| ray.at(h.t)));
                }
                samples.retain(|x| x.length() < 120.0);
                for (k, &p) in samples.iter().enumerate().step_by(7) {
                    let d = dist.relative_distance(a, b, p);
                    if !d.is_finite() || d == 0.0 {
                        continue;
                    }
                    let class = on_csg_surface(&dnf, a, b, p);
                    assert_eq!(d < 0.0, class, "{file}: sign of d_ab at {p}");
                    for &s in samples.iter().skip(k % 5).step_by(5) {
                        if (s - p).length() < d.abs() * 0.999 {
                            assert_eq!(on_csg_surface(&dnf, a, b, s), class, "{file}");
                            decided += 1;
                        }
                    }
                }
            }
        }
        assert!(decided > 1000, "{file}: {decided}");
    }
}
