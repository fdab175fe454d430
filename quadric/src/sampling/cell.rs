//! Grid cells of a fill whose shape follows the heightfield's stretch
//! (paper 2, §4.2: the fill of a region on the surface).
//!
//! Notation: `h = (hₓ, h_y)` a cell's half size in the plane, `S = (Sₓ, S_y)`
//! bounds of the slopes `|∂t/∂x|`, `|∂t/∂y|` over the region
//! ([`Heightfield::slope_bounds`]), `δ₊` its distortion bound, `r` the splat
//! radius.
//!
//! A plane vector `v` lifts to a surface path of length at most
//! `√(|v|² + (∇t·v)²)`, and `(∇t·v)² ≤ min((Sₓ|vₓ| + S_y|v_y|)², (δ₊² − 1)|v|²)`
//! (the second since `|∇t|² = δ² − 1`). A cell centre therefore reaches
//! every point of the cell within [`reach`]`(h)`. The square cell of the
//! isotropic bound (`hₓ = h_y = r/(√2 δ₊)`) ignores the direction of the
//! stretch; the cell of largest area with `√(|h|² + (S·h)²) = r` has
//! `h ∝ (1/√(1 + Sₓ²), 1/√(1 + S_y²))` (Lagrange), up to `δ` times larger
//! where the surface tilts along one axis. [`half_size`] takes the larger
//! of the two.
//!
//! [`Heightfield::slope_bounds`]: crate::sampling::heightfield::Heightfield::slope_bounds

use glam::DVec2;

/// The half size `h` of the fill cell of largest area (of the two shapes in
/// the module notes) whose [`reach`] is at most `radius`.
#[must_use]
pub fn half_size(radius: f64, delta: f64, slopes: DVec2) -> DVec2 {
    let iso = DVec2::splat(radius / (std::f64::consts::SQRT_2 * delta));
    if !slopes.is_finite() {
        return iso;
    }
    let shape = DVec2::new(
        1.0 / (1.0 + slopes.x * slopes.x).sqrt(),
        1.0 / (1.0 + slopes.y * slopes.y).sqrt(),
    );
    let lifted = shape.length_squared() + slopes.dot(shape).powi(2);
    let aniso = shape * (radius / lifted.sqrt());
    if aniso.x * aniso.y > iso.x * iso.y && reach(aniso, delta, slopes) <= radius {
        aniso
    } else {
        iso
    }
}

/// The longest surface path from a cell's centre to a point of the cell,
/// for half size `h` (see the module notes).
#[must_use]
pub fn reach(h: DVec2, delta: f64, slopes: DVec2) -> f64 {
    let plane = h.length_squared();
    let by_axes = slopes.dot(h).powi(2);
    let by_delta = (delta * delta - 1.0).max(0.0) * plane;
    (plane + by_axes.min(by_delta)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_surface_gets_the_square_cell_of_the_isotropic_bound() {
        let h = half_size(1.0, 1.0, DVec2::ZERO);
        assert!(
            (h - DVec2::splat(std::f64::consts::FRAC_1_SQRT_2))
                .abs()
                .max_element()
                < 1e-15
        );
        assert!((reach(h, 1.0, DVec2::ZERO) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn a_tilt_along_x_shortens_only_x_and_gains_its_distortion_in_area() {
        // t = x: slope 1 along x, distortion √2.
        let delta = std::f64::consts::SQRT_2;
        let h = half_size(1.0, delta, DVec2::new(1.0, 0.0));
        let iso = 1.0 / (std::f64::consts::SQRT_2 * delta);
        assert!((h.x * h.y / (iso * iso) - delta).abs() < 1e-12);
        assert!(h.x < h.y);
        // The lifted half-diagonal is exactly the radius.
        assert!((reach(h, delta, DVec2::new(1.0, 0.0)) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn unbounded_slopes_fall_back_to_the_distortion_bound() {
        let h = half_size(2.0, 1.5, DVec2::new(f64::INFINITY, 0.3));
        assert_eq!(h.x, h.y);
        assert!((reach(h, 1.5, DVec2::new(f64::INFINITY, 0.3)) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn reach_bounds_the_lifted_length_of_every_cell_point() {
        // Surface t = 0.8 x + 0.3 y² over [0, 1]²: slopes ≤ (0.8, 0.6).
        let slopes = DVec2::new(0.8, 0.6);
        let delta = (1.0_f64 + 0.64 + 0.36).sqrt();
        let h = half_size(0.1, delta, slopes);
        let lift = |p: DVec2| glam::DVec3::new(p.x, p.y, 0.8 * p.x + 0.3 * p.y * p.y);
        let centre = DVec2::new(0.5, 0.5);
        let bound = reach(h, delta, slopes);
        assert!(bound <= 0.1 + 1e-15);
        for i in 0..=10 {
            for j in 0..=10 {
                let q = centre + h * DVec2::new(f64::from(i) / 5.0 - 1.0, f64::from(j) / 5.0 - 1.0);
                assert!(lift(q).distance(lift(centre)) <= bound + 1e-15);
            }
        }
    }
}
