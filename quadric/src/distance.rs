//! Conservative signed distance to a quadric surface (paper 2, §3.3, eqs. 8–12).
//!
//! Notation: `x₀` the query point, `Q₀ = Q(x₀)`, `g = |Ax₀ − b|` (half the
//! gradient's length), `λ₋ ≤ λ₊` the extreme eigenvalues of `A`. For a unit
//! direction `v`, `Q(x₀ + tv) = Q₀ + 2t(Ax₀ − b)ᵀv + t²vᵀAv` (eq. 9) is
//! bounded by
//!
//! - `Q⁺(t) = Q₀ + 2tg + t²λ₊` from above (eq. 10),
//! - `Q⁻(t) = Q₀ − 2tg + t²λ₋` from below (eq. 11).
//!
//! Inside (`Q₀ < 0`) no surface point is nearer than the first positive root
//! of `Q⁺`; outside (`Q₀ > 0`) than the first positive root of `Q⁻` (eq. 12).
//! Both roots have the cancellation-free form
//!
//! `t₀ = |Q₀| / (g + √(g² − λ Q₀))`, with `λ = λ₊` inside, `λ₋` outside,
//!
//! and `t₀ = +∞` when the discriminant is negative or the denominator is
//! zero (the bound never reaches zero: no surface in that direction at all).
//! The sign of the result is the sign of `Q₀`: negative inside. For a plane
//! (`A = 0`) the bound is the exact distance `Q₀ / |∇Q|`, evaluated as
//! `n·x₀ + c` with the unit normal `n`.

use glam::DVec3;

use crate::eigen::SymmetricEigen;
use crate::quadric::Quadric;

/// A quadric with the eigenvalue bounds needed for its conservative distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricDistance {
    quadric: Quadric,
    /// `λ₋`, padded down by the eigen solver's error bound.
    lambda_min: f64,
    /// `λ₊`, padded up by the eigen solver's error bound.
    lambda_max: f64,
    /// For a plane (`A = 0`): the unit normal `n` and offset `c` with
    /// `Q(x) / |∇Q| = n·x + c`, the exact signed distance.
    plane: Option<(DVec3, f64)>,
}

impl QuadricDistance {
    /// Prepares `quadric` for distance queries (one eigen decomposition).
    #[must_use]
    pub fn new(quadric: &Quadric) -> Self {
        let a = quadric.a();
        let eig = SymmetricEigen::new(a);
        // Jacobi's eigenvalues are exact to a few ulps of ‖A‖; pad outwards
        // so that the bounds of eqs. 10–11 stay bounds.
        let norm = a.to_cols_array().iter().map(|x| x * x).sum::<f64>().sqrt();
        let pad = 16.0 * f64::EPSILON * norm;
        let k = quadric.coefficients();
        let linear = DVec3::new(k[3], k[6], k[8]);
        let plane = (norm == 0.0 && linear.length() > 0.0).then(|| {
            // Q(x) = 2 l·x + c, ∇Q = 2l.
            let len = linear.length();
            (linear / len, k[9] / (2.0 * len))
        });
        Self {
            quadric: *quadric,
            lambda_min: eig.min_value() - pad,
            lambda_max: eig.max_value() + pad,
            plane,
        }
    }

    /// The quadric these bounds belong to.
    #[must_use]
    pub fn quadric(&self) -> &Quadric {
        &self.quadric
    }

    /// The same bounds for the complement `−Q` (inside and outside swapped):
    /// `d(−Q, x) = −d(Q, x)`.
    #[must_use]
    pub fn complement(&self) -> Self {
        Self {
            quadric: self.quadric.complement(),
            lambda_min: -self.lambda_max,
            lambda_max: -self.lambda_min,
            plane: self.plane.map(|(n, c)| (-n, -c)),
        }
    }

    /// The conservative signed distance `d(x₀)` of eq. 12: negative inside,
    /// positive outside, zero on the surface, and no surface point lies
    /// closer to `x₀` than `|d(x₀)|`. May be `±∞` where no surface can be
    /// reached.
    #[must_use]
    #[inline]
    pub fn distance(&self, x0: DVec3) -> f64 {
        if let Some((n, c)) = self.plane {
            return n.dot(x0) + c;
        }
        // Q(x) = x·(Ax − b) − b·x + c: the value from the half gradient.
        let h = self.quadric.half_gradient(x0);
        let k = self.quadric.coefficients();
        let q0 = x0.dot(h) + (k[3] * x0.x + k[6] * x0.y + k[8] * x0.z) + k[9];
        if q0 == 0.0 {
            return 0.0;
        }
        let g = h.length();
        let lambda = if q0 < 0.0 {
            self.lambda_max
        } else {
            self.lambda_min
        };
        let disc = g * g - lambda * q0;
        let denom = g + disc.max(0.0).sqrt();
        let t = if disc < 0.0 || denom <= 0.0 {
            f64::INFINITY
        } else {
            q0.abs() / denom
        };
        t.copysign(q0)
    }
}

/// The conservative signed distance from `x0` to `quadric` (eq. 12).
///
/// Convenience for one query; use [`QuadricDistance`] to amortize the eigen
/// decomposition over many.
#[must_use]
pub fn conservative_distance(quadric: &Quadric, x0: DVec3) -> f64 {
    QuadricDistance::new(quadric).distance(x0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_planes() {
        let q = Quadric::half_space(DVec3::new(0.0, 3.0, 4.0), 5.0).unwrap();
        let d = QuadricDistance::new(&q);
        assert!((d.distance(DVec3::new(7.0, 0.0, 0.0)) + 1.0).abs() < 1e-12);
        assert!((d.distance(DVec3::new(0.0, 3.0, 4.0)) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn exact_for_spheres() {
        let q = Quadric::sphere(DVec3::ZERO, 2.0).unwrap();
        let d = QuadricDistance::new(&q);
        assert!((d.distance(DVec3::new(5.0, 0.0, 0.0)) - 3.0).abs() < 1e-12);
        assert!((d.distance(DVec3::new(0.0, 0.5, 0.0)) + 1.5).abs() < 1e-12);
        assert_eq!(d.distance(DVec3::new(0.0, 2.0, 0.0)), 0.0);
        assert!((d.complement().distance(DVec3::new(5.0, 0.0, 0.0)) + 3.0).abs() < 1e-12);
    }

    #[test]
    fn complement_and_unreachable_surfaces() {
        // Outside of a unit sphere's complement, seen from (10, 0, 0): inside −Q.
        let q = Quadric::sphere(DVec3::ZERO, 1.0).unwrap().complement();
        let v = QuadricDistance::new(&q).distance(DVec3::new(10.0, 0.0, 0.0));
        assert!(v < 0.0 && (v + 9.0).abs() < 1e-12);
        // x² + 1 has no real surface: from its centre the bound is huge (it
        // is infinite but for the eigenvalue padding).
        let none = Quadric::from_coefficients([1., 0., 0., 0., 0., 0., 0., 0., 0., 1.]).unwrap();
        assert!(QuadricDistance::new(&none).distance(DVec3::ZERO) > 1e6);
        // Two-sheet hyperboloid from its centre: exactly 1 to the vertices.
        let h2 = Quadric::hyperboloid_two_sheets(DVec3::ONE).unwrap();
        assert!((QuadricDistance::new(&h2).distance(DVec3::ZERO) - 1.0).abs() < 1e-12);
    }
}
