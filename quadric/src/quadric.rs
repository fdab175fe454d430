//! The quadric type: a symmetric 4×4 matrix stored as ten coefficients.
//!
//! Notation (paper 2, §3, eqs. 1–4):
//! - `Q = [[A, -b], [-bᵀ, c]]`, `A` symmetric 3×3, `b ∈ ℝ³`, `c ∈ ℝ`.
//! - `Q(x) = xᵀAx − 2xᵀb + c` for a point `x` (homogeneous `w = 1`).
//! - `∇Q(x) = 2(Ax − b)`; the normal is `∇Q / |∇Q|`.
//! - Sign convention: `Q(x) < 0` is *inside*, `Q(x) > 0` *outside*.
//! - Transform by an affine `M`: `Q' = M⁻ᵀ Q M⁻¹` (eq. 17), so that
//!   `Q'(M x) = Q(x)` exactly (up to rounding).

use glam::{DMat3, DMat4, DVec3, DVec4};

use crate::error::{Error, Result};

/// A quadric surface `Q(x) = 0`, inside where `Q(x) < 0`.
///
/// Stored as the upper triangle of the symmetric 4×4 matrix, row by row:
/// `[q00, q01, q02, q03, q11, q12, q13, q22, q23, q33]` — the layout of the
/// renderer's quadric buffer. Every constructor checks its input, so a
/// `Quadric` always has finite coefficients and a non-zero quadratic or
/// linear part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quadric {
    coeffs: [f64; 10],
}

/// Index of the coefficient `(row, col)` in the packed upper triangle.
const fn packed(row: usize, col: usize) -> usize {
    let (r, c) = if row <= col { (row, col) } else { (col, row) };
    // Rows start at 0, 4, 7, 9.
    let start = match r {
        0 => 0,
        1 => 4,
        2 => 7,
        _ => 9,
    };
    start + (c - r)
}

impl Quadric {
    /// Builds a quadric from its ten packed coefficients
    /// `[q00, q01, q02, q03, q11, q12, q13, q22, q23, q33]`.
    ///
    /// Errors: [`Error::NonFinite`] for NaN or infinities,
    /// [`Error::ZeroQuadric`] when the quadratic and linear parts are all zero
    /// (a constant, which has no surface).
    pub fn from_coefficients(coeffs: [f64; 10]) -> Result<Self> {
        if coeffs.iter().any(|c| !c.is_finite()) {
            return Err(Error::NonFinite {
                what: "quadric coefficient",
            });
        }
        // Everything but q33 = c.
        if coeffs[..9].iter().all(|&c| c == 0.0) {
            return Err(Error::ZeroQuadric);
        }
        Ok(Self { coeffs })
    }

    /// Builds a quadric from a raw symmetric 4×4 matrix.
    ///
    /// The matrix must be symmetric up to a relative tolerance of `1e-12`
    /// (the two triangles are averaged). Errors as
    /// [`from_coefficients`](Self::from_coefficients), plus
    /// [`Error::NotSymmetric`].
    pub fn from_matrix(m: DMat4) -> Result<Self> {
        let scale = m
            .to_cols_array()
            .iter()
            .fold(0.0_f64, |s, x| s.max(x.abs()));
        let mut coeffs = [0.0; 10];
        for row in 0..4 {
            for col in row..4 {
                let upper = m.col(col)[row];
                let lower = m.col(row)[col];
                if !upper.is_finite() || !lower.is_finite() {
                    return Err(Error::NonFinite {
                        what: "quadric matrix entry",
                    });
                }
                if (upper - lower).abs() > 1e-12 * scale {
                    return Err(Error::NotSymmetric { row, col });
                }
                coeffs[packed(row, col)] = 0.5 * (upper + lower);
            }
        }
        Self::from_coefficients(coeffs)
    }

    /// Builds the quadric `xᵀAx − 2xᵀb + c` from its parts (eq. 3).
    ///
    /// `a` must be symmetric; errors as [`from_matrix`](Self::from_matrix).
    pub fn from_parts(a: DMat3, b: DVec3, c: f64) -> Result<Self> {
        let m = DMat4::from_cols(
            a.x_axis.extend(-b.x),
            a.y_axis.extend(-b.y),
            a.z_axis.extend(-b.z),
            (-b).extend(c),
        );
        Self::from_matrix(m)
    }

    /// The ten packed coefficients `[q00, q01, q02, q03, q11, q12, q13, q22, q23, q33]`.
    #[must_use]
    pub fn coefficients(&self) -> [f64; 10] {
        self.coeffs
    }

    /// The coefficient at `(row, col)` of the symmetric 4×4 matrix.
    ///
    /// Precondition: `row < 4` and `col < 4` (panics otherwise; indices are
    /// never user data).
    #[must_use]
    pub fn entry(&self, row: usize, col: usize) -> f64 {
        assert!(row < 4 && col < 4, "quadric matrix index out of range");
        self.coeffs[packed(row, col)]
    }

    /// The full symmetric 4×4 matrix `Q`.
    #[must_use]
    pub fn matrix(&self) -> DMat4 {
        let col = |c: usize| {
            DVec4::new(
                self.entry(0, c),
                self.entry(1, c),
                self.entry(2, c),
                self.entry(3, c),
            )
        };
        DMat4::from_cols(col(0), col(1), col(2), col(3))
    }

    /// The symmetric quadratic part `A` (eq. 2).
    #[must_use]
    pub fn a(&self) -> DMat3 {
        let k = &self.coeffs;
        DMat3::from_cols(
            DVec3::new(k[0], k[1], k[2]),
            DVec3::new(k[1], k[4], k[5]),
            DVec3::new(k[2], k[5], k[7]),
        )
    }

    /// The linear part `b` (eq. 2; note the sign: `Q` stores `−b`).
    #[must_use]
    pub fn b(&self) -> DVec3 {
        let k = &self.coeffs;
        -DVec3::new(k[3], k[6], k[8])
    }

    /// The constant part `c` (eq. 2).
    #[must_use]
    pub fn c(&self) -> f64 {
        self.coeffs[9]
    }

    /// The value `Q(x) = xᵀAx − 2xᵀb + c`: negative inside, positive outside.
    #[must_use]
    #[inline]
    pub fn value(&self, x: DVec3) -> f64 {
        let k = &self.coeffs;
        let DVec3 { x: px, y, z } = x;
        px * (k[0] * px + 2.0 * (k[1] * y + k[2] * z + k[3]))
            + y * (k[4] * y + 2.0 * (k[5] * z + k[6]))
            + z * (k[7] * z + 2.0 * k[8])
            + k[9]
    }

    /// Half the gradient, `Ax − b`.
    #[must_use]
    #[inline]
    pub fn half_gradient(&self, x: DVec3) -> DVec3 {
        let k = &self.coeffs;
        DVec3::new(
            k[0] * x.x + k[1] * x.y + k[2] * x.z + k[3],
            k[1] * x.x + k[4] * x.y + k[5] * x.z + k[6],
            k[2] * x.x + k[5] * x.y + k[7] * x.z + k[8],
        )
    }

    /// The gradient `∇Q(x) = 2(Ax − b)` (eq. 4); it points outwards.
    #[must_use]
    #[inline]
    pub fn gradient(&self, x: DVec3) -> DVec3 {
        2.0 * self.half_gradient(x)
    }

    /// The outward unit normal `∇Q / |∇Q|` (eq. 4), or `None` where the
    /// gradient vanishes (a cone's apex, a quadric's centre).
    #[must_use]
    #[inline]
    pub fn normal(&self, x: DVec3) -> Option<DVec3> {
        self.half_gradient(x).try_normalize()
    }

    /// The complement: same surface, inside and outside swapped (`−Q`).
    #[must_use]
    pub fn complement(&self) -> Self {
        Self {
            coeffs: self.coeffs.map(|c| -c),
        }
    }

    /// The largest absolute coefficient, a scale for tolerances.
    #[must_use]
    pub fn max_abs_coefficient(&self) -> f64 {
        self.coeffs.iter().fold(0.0_f64, |s, c| s.max(c.abs()))
    }

    /// The same quadric scaled so that its largest coefficient is ±1.
    ///
    /// Scaling by a positive factor changes neither the surface nor the sign.
    #[must_use]
    pub fn normalized(&self) -> Self {
        let s = 1.0 / self.max_abs_coefficient();
        Self {
            coeffs: self.coeffs.map(|c| c * s),
        }
    }

    /// The quadric moved by the affine transform `m`: `Q' = M⁻ᵀ Q M⁻¹`
    /// (eq. 17), so that `Q'(m·x) = Q(x)`.
    ///
    /// Errors: [`Error::NonFinite`], [`Error::NotAffine`] (last row not
    /// `0 0 0 1`), [`Error::SingularTransform`].
    pub fn transformed(&self, m: &DMat4) -> Result<Self> {
        let inv = affine_inverse(m)?;
        let q = inv.transpose() * self.matrix() * inv;
        // Re-symmetrize: rounding makes the product slightly asymmetric.
        let sym = DMat4::from_cols_array(&q.to_cols_array())
            .add_mat4(&q.transpose())
            .mul_scalar(0.5);
        Self::from_matrix(sym)
    }
}

/// Largest deviation of a matrix's last row from `0 0 0 1` still taken as
/// affine (rounding in computed matrices, e.g. an inverse); the row is then
/// snapped to exactly `0 0 0 1`.
pub const AFFINE_TOLERANCE: f64 = 1e-12;

/// Checks that `m` is a finite, invertible affine transform and returns its inverse.
///
/// A last row within [`AFFINE_TOLERANCE`] of `0 0 0 1` counts as affine and
/// is snapped. Errors: [`Error::NonFinite`], [`Error::NotAffine`],
/// [`Error::SingularTransform`].
pub fn affine_inverse(m: &DMat4) -> Result<DMat4> {
    let m = snap_affine(m)?;
    let linear = DMat3::from_mat4(m);
    let scale = linear
        .to_cols_array()
        .iter()
        .fold(0.0_f64, |s, x| s.max(x.abs()));
    let det = linear.determinant();
    if scale == 0.0 || det.abs() <= 1e-12 * scale * scale * scale {
        return Err(Error::SingularTransform);
    }
    let inv = m.inverse();
    if !inv.is_finite() {
        return Err(Error::SingularTransform);
    }
    Ok(inv)
}

/// `m` with its last row set to exactly `0 0 0 1`, if it is affine.
///
/// Errors: [`Error::NonFinite`], [`Error::NotAffine`].
pub fn snap_affine(m: &DMat4) -> Result<DMat4> {
    if !m.is_finite() {
        return Err(Error::NonFinite {
            what: "transform matrix",
        });
    }
    if (m.row(3) - DVec4::W).abs().max_element() > AFFINE_TOLERANCE {
        return Err(Error::NotAffine);
    }
    let mut s = *m;
    s.x_axis.w = 0.0;
    s.y_axis.w = 0.0;
    s.z_axis.w = 0.0;
    s.w_axis.w = 1.0;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_layout_matches_matrix() {
        let q = Quadric::from_coefficients([1., 2., 3., 4., 5., 6., 7., 8., 9., 10.]).unwrap();
        let m = q.matrix();
        assert_eq!(m.col(0), DVec4::new(1., 2., 3., 4.));
        assert_eq!(m.col(1), DVec4::new(2., 5., 6., 7.));
        assert_eq!(m.col(2), DVec4::new(3., 6., 8., 9.));
        assert_eq!(m.col(3), DVec4::new(4., 7., 9., 10.));
        assert_eq!(Quadric::from_matrix(m).unwrap(), q);
        assert_eq!(q.b(), DVec3::new(-4., -7., -9.));
    }

    #[test]
    fn value_matches_matrix_product() {
        let q = Quadric::from_coefficients([1., 2., 3., 4., 5., 6., 7., 8., 9., 10.]).unwrap();
        let x = DVec3::new(0.3, -1.7, 2.2);
        let h = x.extend(1.0);
        let expect = h.dot(q.matrix() * h);
        assert!((q.value(x) - expect).abs() < 1e-12 * expect.abs().max(1.0));
        let parts = x.dot(q.a() * x) - 2.0 * x.dot(q.b()) + q.c();
        assert!((q.value(x) - parts).abs() < 1e-12 * parts.abs().max(1.0));
    }

    #[test]
    fn rejects_bad_input() {
        assert_eq!(
            Quadric::from_coefficients([0.0; 10]),
            Err(Error::ZeroQuadric)
        );
        let mut k = [0.0; 10];
        k[9] = 1.0;
        assert_eq!(Quadric::from_coefficients(k), Err(Error::ZeroQuadric));
        k[0] = f64::NAN;
        assert!(matches!(
            Quadric::from_coefficients(k),
            Err(Error::NonFinite { .. })
        ));
        let mut m = DMat4::IDENTITY;
        m.x_axis.y = 1.0;
        assert_eq!(
            Quadric::from_matrix(m),
            Err(Error::NotSymmetric { row: 0, col: 1 })
        );
    }

    #[test]
    fn transform_errors() {
        let q = Quadric::from_coefficients([1., 0., 0., 0., 1., 0., 0., 1., 0., -1.]).unwrap();
        let flat = DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0));
        assert_eq!(q.transformed(&flat), Err(Error::SingularTransform));
        let mut proj = DMat4::IDENTITY;
        proj.x_axis.w = 0.5;
        assert_eq!(q.transformed(&proj), Err(Error::NotAffine));
        let nan = DMat4::from_translation(DVec3::new(f64::NAN, 0.0, 0.0));
        assert!(matches!(q.transformed(&nan), Err(Error::NonFinite { .. })));
    }
}
