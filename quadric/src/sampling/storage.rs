//! Samples stored in `f32`, with covering bounds widened by the rounding.
//!
//! Notation: `p`, `uv` a sample's position and plane point as computed
//! (`f64`), `p̃` the nearest `f32`s, `ũv = π(p̃)` the plane point the
//! reader derives (`π` = [`Heightfield::project`] in `f64`),
//! `ρ` the radius and `h` the cell half size the sample must cover, `M` a
//! bound on the magnitude of a coordinate, `ε(M) = 2⁻²⁴M + 2⁻¹⁵⁰`, `A` the
//! heightfield's axes and `c` its centre.
//!
//! A run's output is written once, so its bytes are its page faults: a
//! [`Sample`] holds `p̃` and its bounds (28 bytes, not 80); its plane point
//! is derived from `p̃` and its patch's plane, its normal from `p̃` and its
//! quadric ([`outward_normal`]). Rounding to the nearest `f32` moves a
//! coordinate `x` with `|x| ≤ M` by at most `ε(M)` (half the `f32`
//! spacing, at most `2⁻²³|x|` in the normal range and `2⁻¹⁴⁹` below it). A
//! surface point within `ρ` of `p` is within `ρ + |p − p̃|` of `p̃`, and its
//! plane point within `h + |uv − ũv|` of `ũv` along each axis; the stored
//! bounds are those sums rounded up to `f32` (each sum first widened by
//! `2⁻⁵⁰` of itself, more than the `f64` roundings of the sums), so the
//! coverage guarantee holds for the stored sample as it did for the
//! computed one.
//!
//! The errors are bounded once per patch, for positions inside the box
//! `|pᵢ| ≤ Mᵢ` around the bounding sphere (`L¹` norms, which bound the
//! Euclidean one), so the bounds of a fill's cells are rounded once
//! (`Bounds::shared`). For `p = c + A(uv, t)` (lifted in `f64`),
//! `ũvᵢ − uvᵢ = aᵢ·(p̃ − p) + aᵢ·(p − c) − uvᵢ` plus the rounding of `π`:
//! the first term is at most `|aᵢ|·|ε(M)|` (Cauchy–Schwarz over the
//! per-axis bounds), the rest at most `(3d + 2⁻⁴⁵)·4K` with `d` the
//! largest entry of `AᵀA − I` (plus its own rounding) and
//! `K = Σ Mᵢ + |c|₁ ≥ |(uv, t)|` (a dot product of three terms in `f64`
//! loses under `2⁻⁵⁰` of `Σ|aᵢⱼxⱼ|`; the lift and the projection together
//! under `2⁻⁴⁷K`). A sample outside the box, or not lifted from its plane
//! point, gets bounds from its own errors, which are exact in `f64` up to
//! the widening (`x − f64(x̃)` and `π(p̃) − uv` of nearby numbers).

use glam::{DVec2, DVec3, Vec2};

use crate::quadric::Quadric;
use crate::sampling::heightfield::Heightfield;
use crate::sampling::{BoundingSphere, Sample, f32_at_least};

/// `2⁻²⁴`: the largest rounding error to `f32` relative to the magnitude.
const RELATIVE: f64 = 1.0 / (1u64 << 24) as f64;

/// `2⁻¹⁵⁰`: the largest rounding error to `f32` below its normal range.
const ABSOLUTE: f64 = f64::from_bits(((1023 - 150) as u64) << 52);

/// `1 + 2⁻⁵⁰`: the widening of a sum of non-negative `f64` terms that
/// makes it at least the exact sum (each of the few roundings loses at most
/// `2⁻⁵³` of the result).
const WIDEN: f64 = 1.0 + 1.0 / (1u64 << 50) as f64;

/// Magnitude limits above the bounding sphere's box, so that samples
/// rounded onto its rim stay inside.
const LIMIT_SLACK: f64 = 1.0 + 1e-6;

/// How one patch's samples are rounded to `f32`, with the bounds of the
/// rounding errors of positions and derived plane points within the
/// limits.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rounding {
    /// `M` for positions: `|Cᵢ| + R` of the bounding sphere, with slack.
    position_limit: DVec3,
    /// `Σᵢ ε(Mᵢ)`: bounds `|p − p̃|` for positions within the limit.
    position_error: f64,
    /// Bounds `|ũvᵢ − uvᵢ|` for lifted positions within the limit (see
    /// the module notes).
    uv_shift: f64,
}

/// `ε(m)` for `m ≥ 0`.
fn error_bound(m: f64) -> f64 {
    RELATIVE * m + ABSOLUTE
}

/// `2⁻⁴⁵`: a bound, with room, on the relative `f64` rounding of lifting a
/// plane point and projecting it back (see the module notes).
const LIFT_ROUNDING: f64 = 1.0 / (1u64 << 45) as f64;

impl Rounding {
    /// The rounding of the samples of heightfield `hf` inside `sphere`.
    pub(crate) fn new(sphere: &BoundingSphere, hf: &Heightfield) -> Self {
        let position_limit = (sphere.centre.abs() + sphere.radius) * LIMIT_SLACK;
        let per_axis = DVec3::new(
            error_bound(position_limit.x),
            error_bound(position_limit.y),
            error_bound(position_limit.z),
        );
        let position_error = WIDEN * per_axis.element_sum();
        let a = hf.axes;
        let rows = a.transpose();
        let row_norm = rows
            .x_axis
            .length()
            .max(rows.y_axis.length())
            .max(rows.z_axis.length());
        let gram = a.transpose() * a - glam::DMat3::IDENTITY;
        let defect = gram
            .x_axis
            .abs()
            .max(gram.y_axis.abs())
            .max(gram.z_axis.abs())
            .max_element()
            + LIFT_ROUNDING / 32.0;
        let k = position_limit.element_sum() + hf.centre.abs().element_sum();
        let uv_shift = WIDEN
            * (WIDEN * row_norm * per_axis.length() + (3.0 * defect + LIFT_ROUNDING) * 4.0 * k)
            * WIDEN;
        Self {
            position_limit,
            position_error,
            uv_shift,
        }
    }

    /// The stored sample over plane point `uv` of patch `patch`
    /// (heightfield `hf`), covering `bounds`: at `lifted`, the point
    /// `hf.point(uv)`, or at `hf`'s centre where that is `None`.
    #[inline]
    pub(crate) fn store(
        &self,
        hf: &Heightfield,
        lifted: Option<DVec3>,
        uv: DVec2,
        patch: u32,
        bounds: &Bounds,
    ) -> Sample {
        let position = lifted.unwrap_or(hf.centre);
        let stored_position = position.as_vec3();
        let within = lifted.is_some() & position.abs().cmple(self.position_limit).all();
        let (radius, cell) = if within {
            (bounds.stored_radius, bounds.stored_cell)
        } else {
            // The exact rounding errors of this sample.
            let moved = (position - stored_position.as_dvec3()).abs().element_sum();
            let shifted = (hf.project(stored_position.as_dvec3()) - uv).abs();
            widened(bounds.radius, moved, bounds.cell, shifted)
        };
        Sample {
            position: stored_position,
            patch,
            radius,
            cell,
        }
    }
}

/// What lifting a plane point of one patch to a stored sample reads.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lift {
    /// The patch's heightfield.
    pub heightfield: Heightfield,
    /// The patch's index ([`Sample::patch`]).
    pub patch: u32,
    /// The rounding of its samples.
    pub rounding: Rounding,
}

impl Lift {
    /// The stored sample over plane point `uv`, covering `bounds`: the
    /// surface point there (its normal is derived where it is read,
    /// [`outward_normal`]). The lifted point is on the quadric up to `f64` rounding,
    /// far below the `f32` it is stored in (a Newton step onto the quadric
    /// changed no stored sample of the shipped scenes). Inlined into the
    /// fills' loops, which call it once per sample.
    #[inline(always)]
    pub(crate) fn sample(&self, uv: DVec2, bounds: &Bounds) -> Sample {
        self.by_ref().sample(uv, bounds)
    }

    /// The same lifting, reading this copy.
    #[inline(always)]
    pub(crate) fn by_ref(&self) -> LiftRef<'_> {
        LiftRef {
            heightfield: &self.heightfield,
            patch: self.patch,
            rounding: &self.rounding,
        }
    }
}

/// [`Lift`] by reference, for samples lifted one at a time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LiftRef<'a> {
    pub heightfield: &'a Heightfield,
    pub patch: u32,
    pub rounding: &'a Rounding,
}

impl LiftRef<'_> {
    /// See [`Lift::sample`].
    #[inline(always)]
    pub(crate) fn sample(self, uv: DVec2, bounds: &Bounds) -> Sample {
        let hf = self.heightfield;
        self.rounding
            .store(hf, hf.point(uv), uv, self.patch, bounds)
    }
}

/// The solid's outward unit normal at `position` on `quadric`, with
/// `outward_sign` `1` where the solid is inside the quadric and `−1`
/// outside: `±∇Q/|∇Q|`, zero at a singular point. A sample's normal
/// ([`SampleSet::normal_of`](crate::SampleSet::normal_of)) is this at its
/// stored position, computed where it is read, not stored.
#[must_use]
#[inline]
pub fn outward_normal(quadric: &Quadric, outward_sign: f64, position: DVec3) -> DVec3 {
    let g = quadric.gradient(position);
    let g2 = g.length_squared();
    if g2 > 0.0 && g2.is_finite() {
        g * (outward_sign / g2.sqrt())
    } else {
        quadric
            .normal(position)
            .map_or(DVec3::ZERO, |n| n * outward_sign)
    }
}

/// The radius and cell half size a sample must cover, and their stored
/// form for a sample within the limits of its patch's [`Rounding`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bounds {
    radius: f64,
    cell: DVec2,
    stored_radius: f32,
    stored_cell: Vec2,
}

impl Bounds {
    /// The bounds `radius` and `cell` (shared by the cells of a fill: the
    /// stored form is rounded once).
    #[inline]
    pub(crate) fn shared(rounding: &Rounding, radius: f64, cell: DVec2) -> Self {
        let (stored_radius, stored_cell) = widened(
            radius,
            rounding.position_error,
            cell,
            DVec2::splat(rounding.uv_shift),
        );
        Self {
            radius,
            cell,
            stored_radius,
            stored_cell,
        }
    }
}

/// `ρ + moved` and `h + shifted`, widened past the `f64` roundings and
/// rounded up to `f32`.
#[inline]
fn widened(radius: f64, moved: f64, cell: DVec2, shifted: DVec2) -> (f32, Vec2) {
    let cell = (cell + shifted) * WIDEN;
    (
        f32_at_least((radius + moved) * WIDEN),
        Vec2::new(f32_at_least(cell.x), f32_at_least(cell.y)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Quadric;
    use crate::sampling::heightfield::LocalForm;

    /// The constants are the powers of two they stand for.
    #[test]
    fn constants_are_exact_powers_of_two() {
        assert_eq!(RELATIVE, 2f64.powi(-24));
        assert_eq!(ABSOLUTE, 2f64.powi(-150));
        assert_eq!(WIDEN - 1.0, 2f64.powi(-50));
    }

    /// `ε(M)` bounds the rounding of every `f64` of magnitude at most `M`,
    /// also in the subnormal `f32` range, and is not loose by more than 2×
    /// at the top of a binade.
    #[test]
    fn error_bound_holds_and_is_tight() {
        let mut x = 1e-47_f64;
        while x < 1e30 {
            for y in [x, x * (1.0 + 3e-8), x.next_up(), (x * 1.5).next_down()] {
                let err = (y - f64::from(y as f32)).abs();
                assert!(
                    err <= error_bound(y),
                    "{y:e}: {err:e} > {:e}",
                    error_bound(y)
                );
            }
            x *= 1.37;
        }
        // Halfway between two f32s just below 2: the error is 2⁻²⁴.
        let y = 2.0 - 3.0 * 2f64.powi(-24);
        assert_eq!((y - f64::from(y as f32)).abs(), 2f64.powi(-24));
        assert!(error_bound(y) < 2.0 * 2f64.powi(-24));
    }

    /// A stored sample reaches the surface points its computed one
    /// reaches: `ρ̃ ≥ ρ + |p − p̃|`, `h̃ ≥ h + |uv − π(p̃)|`, inside and
    /// outside the limits, and for a sample not lifted from its plane point.
    #[test]
    fn stored_bounds_cover_the_rounding() {
        let q = Quadric::sphere(DVec3::new(3.0, -2.0, 0.5), 50.0).unwrap();
        let hf = LocalForm::new(&q).heightfields()[0];
        // Smaller than the quadric: lifted points beyond it are outside the
        // limits.
        let sphere = BoundingSphere::new(DVec3::new(0.3, -7.0, 1.0), 30.0).unwrap();
        let rounding = Rounding::new(&sphere, &hf);
        let bounds = Bounds::shared(&rounding, 0.25, DVec2::new(0.1, 0.2));
        let mut checked = [0; 2];
        for i in 0..4000 {
            let t = f64::from(i) * 0.618_033_988_7;
            let uv = 49.9 * t.fract().sqrt() * DVec2::new((7.0 * t).cos(), (7.0 * t).sin());
            let Some(position) = hf.point(uv) else {
                continue;
            };
            let s = rounding.store(&hf, Some(position), uv, 3, &bounds);
            let moved = position.distance(s.position.as_dvec3());
            let shifted = (uv - hf.project(s.position.as_dvec3())).abs();
            assert!(f64::from(s.radius) >= 0.25 + moved, "{i}");
            assert!(f64::from(s.cell.x) >= 0.1 + shifted.x, "{i}");
            assert!(f64::from(s.cell.y) >= 0.2 + shifted.y, "{i}");
            assert!(f64::from(s.radius) < 0.25 * (1.0 + 1e-4));
            assert!(f64::from(s.cell.x) < 0.1 * (1.0 + 1e-3));
            let within = position.abs().cmple(rounding.position_limit).all();
            checked[usize::from(within)] += 1;
            assert_eq!(s.patch, 3);
        }
        assert!(checked[0] > 100 && checked[1] > 100, "{checked:?}");
        // The shared bound is within a few times the rounding of the
        // largest coordinate, far below the cells.
        assert!(rounding.uv_shift < 4.0 * rounding.position_error);
        // Not lifted: the centre, with the exact shift from the plane
        // point.
        let uv = DVec2::new(20.0, -3.0);
        let s = rounding.store(&hf, None, uv, 0, &bounds);
        assert_eq!(s.position, hf.centre.as_vec3());
        let shifted = (uv - hf.project(s.position.as_dvec3())).abs();
        assert!(f64::from(s.cell.x) >= 0.1 + shifted.x);
        assert!(f64::from(s.cell.y) >= 0.2 + shifted.y);
    }
}
