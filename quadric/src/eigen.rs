//! Symmetric 3×3 eigen decomposition by cyclic Jacobi rotations.
//!
//! Notation (paper 2, §3.2): `A = U Λ Uᵀ` with `Λ = diag(λ₁, λ₂, λ₃)` and the
//! principal axes `uᵢ` the columns of `U`.
//!
//! Jacobi applies plane rotations `A ← Jᵀ A J`, `U ← U J`, each zeroing one
//! off-diagonal entry, until the off-diagonal mass is below `ε·‖A‖`. Since
//! `U` is a product of exact rotations (up to rounding) it is orthonormal for
//! every input, including singular `A` (cylinders, cones, planes: zero
//! eigenvalues) and repeated eigenvalues (spheres: any basis is valid). The
//! result is re-orthonormalized and made right-handed at the end.

use glam::{DMat3, DVec3};

/// Eigenvalues and an orthonormal, right-handed eigenbasis of a symmetric 3×3 matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SymmetricEigen {
    /// The eigenvalues in ascending order `λ₁ ≤ λ₂ ≤ λ₃`.
    pub values: DVec3,
    /// The eigenvectors as columns, in the order of [`values`](Self::values):
    /// `A · vectors.col(i) = values[i] · vectors.col(i)`.
    pub vectors: DMat3,
}

/// Sweeps after which Jacobi is abandoned; 3×3 converges in 4–6.
const MAX_SWEEPS: usize = 32;

impl SymmetricEigen {
    /// Decomposes the symmetric matrix `a` (only its upper triangle is read).
    ///
    /// Precondition: `a` is finite (every [`Quadric`](crate::Quadric) is).
    /// For non-finite input the result is not meaningful but still has an
    /// orthonormal basis.
    #[must_use]
    pub fn new(a: DMat3) -> Self {
        // m[r][c], symmetric copy from the upper triangle.
        let mut m = [[0.0_f64; 3]; 3];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                let (i, j) = if r <= c { (r, c) } else { (c, r) };
                *v = a.col(j)[i];
            }
        }
        let mut u = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let norm = m.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
        if norm.is_finite() && norm > 0.0 {
            for _ in 0..MAX_SWEEPS {
                let off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
                if off.sqrt() <= f64::EPSILON * 1e-2 * norm {
                    break;
                }
                for (p, q) in [(0, 1), (0, 2), (1, 2)] {
                    rotate(&mut m, &mut u, p, q);
                }
            }
        }
        let mut pairs = [0, 1, 2].map(|i| (m[i][i], DVec3::new(u[0][i], u[1][i], u[2][i])));
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let vectors = orthonormalize(pairs[0].1, pairs[1].1);
        Self {
            values: DVec3::new(pairs[0].0, pairs[1].0, pairs[2].0),
            vectors,
        }
    }

    /// The smallest eigenvalue `λ₁`.
    #[must_use]
    pub fn min_value(&self) -> f64 {
        self.values.x
    }

    /// The largest eigenvalue `λ₃`.
    #[must_use]
    pub fn max_value(&self) -> f64 {
        self.values.z
    }
}

/// One Jacobi rotation zeroing `m[p][q]` (Golub & Van Loan, Alg. 8.5.1).
fn rotate(m: &mut [[f64; 3]; 3], u: &mut [[f64; 3]; 3], p: usize, q: usize) {
    let apq = m[p][q];
    if apq == 0.0 {
        return;
    }
    let theta = (m[q][q] - m[p][p]) / (2.0 * apq);
    // t = tan of the rotation angle, the smaller root; stable for large θ.
    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
    let t = if theta.is_finite() { t } else { 0.0 };
    let c = 1.0 / (t * t + 1.0).sqrt();
    let s = t * c;
    for row in m.iter_mut() {
        let (mkp, mkq) = (row[p], row[q]);
        row[p] = c * mkp - s * mkq;
        row[q] = s * mkp + c * mkq;
    }
    let (rp, rq) = (m[p], m[q]);
    m[p] = core::array::from_fn(|k| c * rp[k] - s * rq[k]);
    m[q] = core::array::from_fn(|k| s * rp[k] + c * rq[k]);
    m[p][q] = 0.0;
    m[q][p] = 0.0;
    for row in u.iter_mut() {
        let (up, uq) = (row[p], row[q]);
        row[p] = c * up - s * uq;
        row[q] = s * up + c * uq;
    }
}

/// Gram–Schmidt on two columns, the third as their cross product: an exactly
/// right-handed orthonormal frame even when rounding disturbed the inputs.
fn orthonormalize(a: DVec3, b: DVec3) -> DMat3 {
    let x = a.try_normalize().unwrap_or(DVec3::X);
    let b = b - x * x.dot(b);
    let y = b
        .try_normalize()
        .unwrap_or_else(|| x.any_orthonormal_vector());
    let z = x.cross(y);
    DMat3::from_cols(x, y, z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(a: DMat3) -> SymmetricEigen {
        let e = SymmetricEigen::new(a);
        let u = e.vectors;
        let gram = u.transpose() * u;
        assert!(
            gram.abs_diff_eq(DMat3::IDENTITY, 1e-14),
            "not orthonormal: {gram:?}"
        );
        assert!((u.determinant() - 1.0).abs() < 1e-14);
        let scale = a
            .to_cols_array()
            .iter()
            .fold(1.0_f64, |s, x| s.max(x.abs()));
        for i in 0..3 {
            let v = u.col(i);
            let r = a * v - v * e.values[i];
            assert!(r.length() <= 1e-13 * scale, "residual {r:?} for λ{i}");
        }
        assert!(e.values.x <= e.values.y && e.values.y <= e.values.z);
        e
    }

    #[test]
    fn diagonal_and_zero() {
        let e = check(DMat3::from_diagonal(DVec3::new(3.0, -1.0, 2.0)));
        assert_eq!(e.values, DVec3::new(-1.0, 2.0, 3.0));
        let z = check(DMat3::ZERO);
        assert_eq!(z.values, DVec3::ZERO);
    }

    #[test]
    fn dense_symmetric() {
        let a = DMat3::from_cols(
            DVec3::new(4.0, 1.0, -2.0),
            DVec3::new(1.0, 2.0, 0.5),
            DVec3::new(-2.0, 0.5, 3.0),
        );
        let e = check(a);
        let trace = e.values.x + e.values.y + e.values.z;
        assert!((trace - 9.0).abs() < 1e-12);
    }
}
