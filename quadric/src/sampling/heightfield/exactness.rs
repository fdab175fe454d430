//! The evaluation forms of [`Heightfield`] against the formulas they
//! replace: bit for bit, over the heightfields of every kind of quadric
//! and boxes in every position (inside the domain, across the rim,
//! outside it, across an axis).
//!
//! The references are the straightforward forms: `height` and
//! `distortion` by kind with a branch for the domain,
//! `distortion_bounds_at` folding the distortion of each vertex, and
//! `distortion_bounds` deciding the corner form from the separable parts
//! on every call and folding `f64::min`/`f64::max` over the corners.

use glam::{DMat4, DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{HeightKind, Heightfield, LocalForm, Quad1};
use crate::quadric::Quadric;

fn reference_height(h: &Heightfield, p: DVec2) -> Option<f64> {
    let v = h.value.value(p);
    match h.kind {
        HeightKind::Polynomial => Some(v),
        HeightKind::Root { positive } => {
            (v >= 0.0).then(|| if positive { v.sqrt() } else { -v.sqrt() })
        }
    }
}

fn reference_distortion(h: &Heightfield, p: DVec2) -> f64 {
    let sx = h.value.x.slope(p.x);
    let sy = h.value.y.slope(p.y);
    match h.kind {
        HeightKind::Polynomial => (1.0 + sx * sx + sy * sy).sqrt(),
        HeightKind::Root { .. } => {
            let r = h.value.value(p);
            if r <= 0.0 {
                f64::INFINITY
            } else {
                (1.0 + (sx * sx + sy * sy) / (4.0 * r)).sqrt()
            }
        }
    }
}

fn reference_in_affine_cell(h: &Heightfield, lo: DVec2, hi: DVec2) -> bool {
    let square = [h.value.x.a != 0.0, h.value.y.a != 0.0];
    let affine = |q: &Quad1, square: bool| if square { q.b == 0.0 } else { q.a == 0.0 };
    let one_side = |square: bool, lo: f64, hi: f64| !square || lo >= 0.0 || hi <= 0.0;
    one_side(square[0], lo.x, hi.x)
        && one_side(square[1], lo.y, hi.y)
        && [&h.value, &h.owns_x, &h.owns_y]
            .iter()
            .all(|f| affine(&f.x, square[0]) && affine(&f.y, square[1]))
}

fn reference_distortion_bounds(h: &Heightfield, lo: DVec2, hi: DVec2) -> (f64, f64) {
    let slopes = || {
        let (ax0, ax1) = h.value.x.slope_squared_range(lo.x, hi.x);
        let (ay0, ay1) = h.value.y.slope_squared_range(lo.y, hi.y);
        (ax0, ax1, ay0, ay1)
    };
    match h.kind {
        HeightKind::Polynomial => {
            let (ax0, ax1, ay0, ay1) = slopes();
            ((1.0 + ax0 + ay0).sqrt(), (1.0 + ax1 + ay1).sqrt())
        }
        HeightKind::Root { .. } => {
            let (fx, fy) = (&h.value.x, &h.value.y);
            let corner_form = reference_in_affine_cell(h, lo, hi);
            let vx = [fx.value(lo.x), fx.value(hi.x)];
            let vy = [fy.value(lo.y), fy.value(hi.y)];
            let (r0, r1) = if corner_form {
                (
                    vx[0].min(vx[1]) + vy[0].min(vy[1]),
                    vx[0].max(vx[1]) + vy[0].max(vy[1]),
                )
            } else {
                h.value.range(lo, hi)
            };
            if r1 <= 0.0 {
                return (f64::INFINITY, f64::INFINITY);
            }
            if r0 > 0.0 && corner_form {
                let sx = [fx.slope(lo.x), fx.slope(hi.x)].map(|s| s * s);
                let sy = [fy.slope(lo.y), fy.slope(hi.y)].map(|s| s * s);
                let mut min = f64::INFINITY;
                let mut max = 0.0_f64;
                for (i, j) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
                    let d2 = 1.0 + (sx[i] + sy[j]) / (4.0 * (vx[i] + vy[j]));
                    min = min.min(d2);
                    max = max.max(d2);
                }
                return (min.sqrt(), max.sqrt());
            }
            let (ax0, ax1, ay0, ay1) = slopes();
            let min = (1.0 + (ax0 + ay0) / (4.0 * r1)).sqrt();
            let max = if r0 > 0.0 {
                (1.0 + (ax1 + ay1) / (4.0 * r0)).sqrt()
            } else {
                f64::INFINITY
            };
            (min, max)
        }
    }
}

/// Equal bits (any NaN equals any NaN).
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// The quadrics of every kind, posed in general position and axis-aligned.
fn quadrics() -> Vec<Quadric> {
    let shapes = [
        Quadric::sphere(DVec3::new(0.3, -0.2, 0.1), 1.3),
        Quadric::ellipsoid(DVec3::new(0.1, -0.2, 0.3), DVec3::new(1.0, 0.7, 0.5)),
        Quadric::cylinder(DVec3::new(0.2, 0.0, -0.1), DVec3::new(0.0, 0.0, 1.0), 0.8),
        Quadric::cone(DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0), 0.5),
        Quadric::elliptic_paraboloid(DVec2::new(0.7, 1.2)),
        Quadric::hyperbolic_paraboloid(DVec2::new(0.9, 0.6)),
        Quadric::hyperboloid_one_sheet(DVec3::new(0.8, 0.6, 1.1)),
        Quadric::hyperboloid_two_sheets(DVec3::new(0.5, 0.9, 0.7)),
        Quadric::half_space(DVec3::new(1.0, 2.0, 2.0), 0.4),
    ];
    let pose = DMat4::from_rotation_y(0.4) * DMat4::from_rotation_x(-0.7);
    let mut out = Vec::new();
    for q in shapes {
        let q = q.expect("valid shape");
        out.push(q);
        out.push(q.transformed(&pose).expect("invertible pose"));
    }
    out
}

#[test]
fn evaluation_forms_match_the_reference_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let mut paths = [0usize; 5];
    for q in quadrics() {
        for h in LocalForm::new(&q).heightfields() {
            for _ in 0..4000 {
                // Boxes of sizes from a splat to a basic region; a third
                // of them centred on an axis.
                let size = DVec2::new(rng.random_range(0.0..0.6), rng.random_range(0.0..0.6));
                let mut lo = DVec2::new(rng.random_range(-1.5..1.5), rng.random_range(-1.5..1.5));
                if rng.random_range(0..3) == 0 {
                    lo.x = -0.5 * size.x;
                }
                let hi = lo + size;
                let p = lo + size * 0.5;
                let (height, reference) = (h.height(p), reference_height(&h, p));
                assert!(
                    height.is_some() == reference.is_some()
                        && same(height.unwrap_or(0.0), reference.unwrap_or(0.0)),
                    "height {h:?} at {p}"
                );
                assert!(same(h.distortion(p), reference_distortion(&h, p)));
                let vertices = [lo, hi, p];
                let (min, max) = h.distortion_bounds_at(&vertices);
                let (rmin, rmax) = vertices
                    .iter()
                    .map(|v| reference_distortion(&h, *v))
                    .fold((f64::INFINITY, 0.0_f64), |(lo, hi), d| {
                        (lo.min(d), hi.max(d))
                    });
                assert!(same(min, rmin) && same(max, rmax), "{h:?} at {vertices:?}");
                let (min, max) = h.distortion_bounds(lo, hi);
                let (rmin, rmax) = reference_distortion_bounds(&h, lo, hi);
                assert!(
                    same(min, rmin) && same(max, rmax),
                    "{h:?} on [{lo}, {hi}]: ({min}, {max}) against ({rmin}, {rmax})"
                );
                // Which paths the boxes took: polynomial, across cells,
                // inside the domain, across the rim, outside it.
                let path = if h.kind == HeightKind::Polynomial {
                    0
                } else if !reference_in_affine_cell(&h, lo, hi) {
                    1
                } else if max.is_finite() {
                    2
                } else if min.is_finite() {
                    3
                } else {
                    4
                };
                paths[path] += 1;
            }
        }
    }
    assert!(paths.iter().all(|&n| n > 100), "paths taken: {paths:?}");
}
