//! The principal frame of a quadric: centre and principal axes (paper 2, §3.2).
//!
//! Notation: `A = U Λ Uᵀ` (see [`eigen`](crate::eigen)), principal axes
//! `uᵢ = U.col(i)`, centre `q` with `Aq = b`. When `A` is singular the centre
//! is not unique (cylinders: a line of centres; planes and paraboloids: no
//! exact solution) and `q` is the minimum-norm least-squares solution
//! `q = Σ_{|λᵢ| > τ} (uᵢ·b / λᵢ) uᵢ`, with `τ = ε_rel · max|λ|`.

use glam::{DMat3, DVec3};

use crate::eigen::SymmetricEigen;
use crate::quadric::Quadric;

/// Eigenvalues with `|λ| ≤ SINGULAR_RELATIVE · max|λ|` count as zero.
pub const SINGULAR_RELATIVE: f64 = 1e-10;

/// A quadric's local coordinate system: centre plus orthonormal principal axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipalFrame {
    /// The centre `q` (minimum-norm solution of `Aq = b`).
    pub centre: DVec3,
    /// The principal axes as orthonormal, right-handed columns, sorted by
    /// ascending eigenvalue.
    pub axes: DMat3,
    /// The eigenvalues of `A` belonging to the columns of [`axes`](Self::axes).
    pub eigenvalues: DVec3,
    /// Which eigenvalues count as zero (`|λ| ≤ SINGULAR_RELATIVE · max|λ|`).
    pub singular: [bool; 3],
}

impl PrincipalFrame {
    /// Computes the frame of `quadric`. Always succeeds: a singular or zero
    /// `A` (planes, cylinders, cones, paraboloids) still yields an
    /// orthonormal frame.
    #[must_use]
    pub fn new(quadric: &Quadric) -> Self {
        let eig = SymmetricEigen::new(quadric.a());
        let b = quadric.b();
        let largest = eig.values.abs().max_element();
        let tau = SINGULAR_RELATIVE * largest;
        let mut centre = DVec3::ZERO;
        let mut singular = [true; 3];
        for (i, flag) in singular.iter_mut().enumerate() {
            let lambda = eig.values[i];
            if largest > 0.0 && lambda.abs() > tau {
                let u = eig.vectors.col(i);
                centre += u * (u.dot(b) / lambda);
                *flag = false;
            }
        }
        Self {
            centre,
            axes: eig.vectors,
            eigenvalues: eig.values,
            singular,
        }
    }

    /// The rank of `A` (number of non-zero eigenvalues): 3 for ellipsoids,
    /// hyperboloids and cones, 2 for cylinders and paraboloids, 0 for planes.
    #[must_use]
    pub fn rank(&self) -> usize {
        self.singular.iter().filter(|s| !**s).count()
    }

    /// Maps local coordinates (along the principal axes, from the centre) to world.
    #[must_use]
    pub fn to_world(&self, local: DVec3) -> DVec3 {
        self.centre + self.axes * local
    }

    /// Maps a world point to local coordinates.
    #[must_use]
    pub fn to_local(&self, world: DVec3) -> DVec3 {
        self.axes.transpose() * (world - self.centre)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_centre() {
        let q = Quadric::sphere(DVec3::new(1.0, -2.0, 3.0), 2.0).unwrap();
        let f = PrincipalFrame::new(&q);
        assert!((f.centre - DVec3::new(1.0, -2.0, 3.0)).length() < 1e-12);
        assert_eq!(f.rank(), 3);
    }

    #[test]
    fn cylinder_centre_is_min_norm_on_axis() {
        let q = Quadric::cylinder(DVec3::new(3.0, 1.0, 7.0), DVec3::Z, 1.0).unwrap();
        let f = PrincipalFrame::new(&q);
        assert!((f.centre - DVec3::new(3.0, 1.0, 0.0)).length() < 1e-12);
        assert_eq!(f.rank(), 2);
        let local = f.to_local(DVec3::new(4.0, 1.0, 2.0));
        assert!((f.to_world(local) - DVec3::new(4.0, 1.0, 2.0)).length() < 1e-12);
    }

    #[test]
    fn plane_has_rank_zero() {
        let q = Quadric::half_space(DVec3::X, 2.0).unwrap();
        let f = PrincipalFrame::new(&q);
        assert_eq!(f.rank(), 0);
        assert_eq!(f.centre, DVec3::ZERO);
    }
}
