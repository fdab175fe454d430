//! Constructors for the named quadric types (paper 2, §3, Fig. 3).
//!
//! Every shape is inside where `Q(x) < 0`. Shapes with a natural placement
//! (sphere, ellipsoid, half-space, cylinder, cone) take it as arguments; the
//! others are built in standard position (centre at the origin, axis `+z`)
//! and placed with [`Quadric::transformed`].

use glam::{DMat3, DVec2, DVec3};

use crate::error::{Error, Result, direction, finite, positive};
use crate::quadric::Quadric;

fn finite_vec(v: DVec3, what: &'static str) -> Result<DVec3> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite { what })
    }
}

fn positive_vec(v: DVec3, what: &'static str) -> Result<DVec3> {
    Ok(DVec3::new(
        positive(v.x, what)?,
        positive(v.y, what)?,
        positive(v.z, what)?,
    ))
}

/// `(x − p)ᵀ A (x − p) + k` as a quadric: `b = A p`, `c = pᵀAp + k`.
fn centred(a: DMat3, p: DVec3, k: f64) -> Result<Quadric> {
    let ap = a * p;
    Quadric::from_parts(a, ap, p.dot(ap) + k)
}

impl Quadric {
    /// The half-space `n·x ≤ offset` (its surface is the plane `n·x = offset`).
    ///
    /// `normal` points outwards and need not be unit; it is normalized so that
    /// `Q(x)` is the signed distance to the plane.
    pub fn half_space(normal: DVec3, offset: f64) -> Result<Self> {
        let len = normal.length();
        let n = direction(normal, "plane normal")?;
        let d = finite(offset, "plane offset")? / len;
        Self::from_parts(DMat3::ZERO, -0.5 * n, -d)
    }

    /// The half-space through `point` whose outward normal is `normal`.
    pub fn half_space_through(point: DVec3, normal: DVec3) -> Result<Self> {
        let n = direction(normal, "plane normal")?;
        let p = finite_vec(point, "plane point")?;
        Self::half_space(n, n.dot(p))
    }

    /// The solid sphere `|x − centre|² ≤ radius²`.
    pub fn sphere(centre: DVec3, radius: f64) -> Result<Self> {
        let c = finite_vec(centre, "sphere centre")?;
        let r = positive(radius, "sphere radius")?;
        centred(DMat3::IDENTITY, c, -r * r)
    }

    /// The solid axis-aligned ellipsoid `Σ ((x − centre)ᵢ / radiiᵢ)² ≤ 1`.
    pub fn ellipsoid(centre: DVec3, radii: DVec3) -> Result<Self> {
        let c = finite_vec(centre, "ellipsoid centre")?;
        let r = positive_vec(radii, "ellipsoid radius")?;
        centred(DMat3::from_diagonal(1.0 / (r * r)), c, -1.0)
    }

    /// The infinite solid circular cylinder of `radius` around the line
    /// through `point` along `axis`.
    pub fn cylinder(point: DVec3, axis: DVec3, radius: f64) -> Result<Self> {
        let p = finite_vec(point, "cylinder point")?;
        let u = direction(axis, "cylinder axis")?;
        let r = positive(radius, "cylinder radius")?;
        let a = DMat3::IDENTITY - outer(u, u);
        centred(a, p, -r * r)
    }

    /// The infinite solid elliptic cylinder `(x/rx)² + (y/ry)² ≤ 1` along `z`.
    pub fn elliptic_cylinder(radii: DVec2) -> Result<Self> {
        let rx = positive(radii.x, "cylinder radius")?;
        let ry = positive(radii.y, "cylinder radius")?;
        let d = DVec3::new(1.0 / (rx * rx), 1.0 / (ry * ry), 0.0);
        Self::from_parts(DMat3::from_diagonal(d), DVec3::ZERO, -1.0)
    }

    /// The solid circular double cone with its apex at `apex`, around `axis`,
    /// with half-opening angle `half_angle` (radians, in `(0, π/2)`).
    pub fn cone(apex: DVec3, axis: DVec3, half_angle: f64) -> Result<Self> {
        let p = finite_vec(apex, "cone apex")?;
        let u = direction(axis, "cone axis")?;
        let theta = finite(half_angle, "cone half-angle")?;
        if !(theta > 0.0 && theta < core::f64::consts::FRAC_PI_2) {
            return Err(Error::AngleOutOfRange {
                degrees: theta.to_degrees(),
            });
        }
        // |x|² − (1 + tan²θ)(u·x)² = radial² − tan²θ · height².
        let sec2 = 1.0 / (theta.cos() * theta.cos());
        let a = DMat3::IDENTITY - outer(u, u) * sec2;
        centred(a, p, 0.0)
    }

    /// The solid elliptic double cone `(x/rx)² + (y/ry)² ≤ z²` along `z`,
    /// apex at the origin; `radii` are the semi-axes at height `|z| = 1`.
    pub fn elliptic_cone(radii: DVec2) -> Result<Self> {
        let rx = positive(radii.x, "cone radius")?;
        let ry = positive(radii.y, "cone radius")?;
        let d = DVec3::new(1.0 / (rx * rx), 1.0 / (ry * ry), -1.0);
        Self::from_parts(DMat3::from_diagonal(d), DVec3::ZERO, 0.0)
    }

    /// The solid elliptic paraboloid `(x/rx)² + (y/ry)² ≤ z` (opening to `+z`).
    pub fn elliptic_paraboloid(radii: DVec2) -> Result<Self> {
        let rx = positive(radii.x, "paraboloid radius")?;
        let ry = positive(radii.y, "paraboloid radius")?;
        let d = DVec3::new(1.0 / (rx * rx), 1.0 / (ry * ry), 0.0);
        Self::from_parts(DMat3::from_diagonal(d), DVec3::new(0.0, 0.0, 0.5), 0.0)
    }

    /// The hyperbolic paraboloid (saddle) `(x/rx)² − (y/ry)² = z`; inside is
    /// `z ≥ (x/rx)² − (y/ry)²`.
    pub fn hyperbolic_paraboloid(radii: DVec2) -> Result<Self> {
        let rx = positive(radii.x, "paraboloid radius")?;
        let ry = positive(radii.y, "paraboloid radius")?;
        let d = DVec3::new(1.0 / (rx * rx), -1.0 / (ry * ry), 0.0);
        Self::from_parts(DMat3::from_diagonal(d), DVec3::new(0.0, 0.0, 0.5), 0.0)
    }

    /// The solid one-sheet hyperboloid `(x/rx)² + (y/ry)² − (z/rz)² ≤ 1`
    /// around `z` (waist semi-axes `rx`, `ry`).
    pub fn hyperboloid_one_sheet(radii: DVec3) -> Result<Self> {
        let r = positive_vec(radii, "hyperboloid radius")?;
        let d = DVec3::new(1.0, 1.0, -1.0) / (r * r);
        Self::from_parts(DMat3::from_diagonal(d), DVec3::ZERO, -1.0)
    }

    /// The solid two-sheet hyperboloid `(z/rz)² − (x/rx)² − (y/ry)² ≥ 1`
    /// (the two sheets open along `±z`, vertices at `z = ±rz`).
    pub fn hyperboloid_two_sheets(radii: DVec3) -> Result<Self> {
        let r = positive_vec(radii, "hyperboloid radius")?;
        let d = DVec3::new(1.0, 1.0, -1.0) / (r * r);
        Self::from_parts(DMat3::from_diagonal(d), DVec3::ZERO, 1.0)
    }

    /// The six half-spaces whose intersection is the box `[min, max]`, in the
    /// order `−x, +x, −y, +y, −z, +z`.
    ///
    /// Errors: [`Error::NonFinite`], [`Error::NonPositive`] for an empty or
    /// flat box (`max ≤ min` on some axis).
    pub fn box_planes(min: DVec3, max: DVec3) -> Result<[Self; 6]> {
        let lo = finite_vec(min, "box corner")?;
        let hi = finite_vec(max, "box corner")?;
        positive_vec(hi - lo, "box size")?;
        Ok([
            Self::half_space(-DVec3::X, -lo.x)?,
            Self::half_space(DVec3::X, hi.x)?,
            Self::half_space(-DVec3::Y, -lo.y)?,
            Self::half_space(DVec3::Y, hi.y)?,
            Self::half_space(-DVec3::Z, -lo.z)?,
            Self::half_space(DVec3::Z, hi.z)?,
        ])
    }
}

/// The outer product `u vᵀ`.
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn sphere_value_is_power_distance() {
        let q = Quadric::sphere(DVec3::new(1.0, 2.0, 3.0), 2.0).unwrap();
        assert!(close(q.value(DVec3::new(1.0, 2.0, 3.0)), -4.0));
        assert!(close(q.value(DVec3::new(3.0, 2.0, 3.0)), 0.0));
        assert!(close(q.value(DVec3::new(4.0, 2.0, 3.0)), 5.0));
        let n = q.normal(DVec3::new(1.0, 2.0, 5.0)).unwrap();
        assert!((n - DVec3::Z).length() < 1e-12);
    }

    #[test]
    fn half_space_value_is_signed_distance() {
        let q = Quadric::half_space(DVec3::new(0.0, 0.0, 2.0), 4.0).unwrap();
        assert!(close(q.value(DVec3::new(5.0, -1.0, 3.0)), 1.0));
        assert!(close(q.value(DVec3::new(0.0, 0.0, 0.0)), -2.0));
        let t = Quadric::half_space_through(DVec3::new(1.0, 1.0, 1.0), -DVec3::X).unwrap();
        assert!(close(t.value(DVec3::new(0.0, 7.0, 7.0)), 1.0));
    }

    #[test]
    fn shapes_have_expected_points() {
        let on = |q: &Quadric, p: DVec3| close(q.value(p), 0.0);
        let cyl = Quadric::cylinder(DVec3::ZERO, DVec3::new(0.0, 0.0, 5.0), 2.0).unwrap();
        assert!(on(&cyl, DVec3::new(2.0, 0.0, 100.0)));
        assert!(cyl.value(DVec3::new(0.0, 1.0, -50.0)) < 0.0);
        let cone = Quadric::cone(DVec3::ZERO, DVec3::Z, 45f64.to_radians()).unwrap();
        assert!(on(&cone, DVec3::new(3.0, 0.0, 3.0)));
        assert!(on(&cone, DVec3::new(0.0, -2.0, -2.0)));
        assert!(cone.value(DVec3::new(0.0, 0.0, 1.0)) < 0.0);
        let ep = Quadric::elliptic_paraboloid(DVec2::new(1.0, 2.0)).unwrap();
        assert!(on(&ep, DVec3::new(1.0, 2.0, 2.0)));
        assert!(ep.value(DVec3::new(0.0, 0.0, 1.0)) < 0.0);
        let hp = Quadric::hyperbolic_paraboloid(DVec2::ONE).unwrap();
        assert!(on(&hp, DVec3::new(2.0, 1.0, 3.0)));
        let h1 = Quadric::hyperboloid_one_sheet(DVec3::ONE).unwrap();
        assert!(on(&h1, DVec3::new(1.0, 0.0, 0.0)));
        assert!(on(&h1, DVec3::new(2f64.sqrt(), 0.0, 1.0)));
        assert!(h1.value(DVec3::ZERO) < 0.0);
        let h2 = Quadric::hyperboloid_two_sheets(DVec3::ONE).unwrap();
        assert!(on(&h2, DVec3::new(0.0, 0.0, 1.0)));
        assert!(h2.value(DVec3::ZERO) > 0.0);
        assert!(h2.value(DVec3::new(0.0, 0.0, -3.0)) < 0.0);
        let ec = Quadric::elliptic_cone(DVec2::new(2.0, 1.0)).unwrap();
        assert!(on(&ec, DVec3::new(4.0, 0.0, 2.0)));
        let el = Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0)).unwrap();
        assert!(on(&el, DVec3::new(0.0, 0.0, 3.0)));
        let ecyl = Quadric::elliptic_cylinder(DVec2::new(1.0, 3.0)).unwrap();
        assert!(on(&ecyl, DVec3::new(0.0, 3.0, 9.0)));
    }

    #[test]
    fn box_planes_bound_the_box() {
        let planes = Quadric::box_planes(DVec3::splat(-1.0), DVec3::new(1.0, 2.0, 3.0)).unwrap();
        let inside = |p: DVec3| planes.iter().all(|q| q.value(p) < 0.0);
        assert!(inside(DVec3::new(0.0, 1.5, 2.5)));
        assert!(!inside(DVec3::new(0.0, 2.5, 0.0)));
        assert!(!inside(DVec3::new(-1.5, 0.0, 0.0)));
        assert!(Quadric::box_planes(DVec3::ONE, DVec3::ONE).is_err());
    }

    #[test]
    fn constructor_errors() {
        assert!(matches!(
            Quadric::sphere(DVec3::ZERO, -1.0),
            Err(Error::NonPositive { .. })
        ));
        assert!(matches!(
            Quadric::sphere(DVec3::new(f64::INFINITY, 0.0, 0.0), 1.0),
            Err(Error::NonFinite { .. })
        ));
        assert!(matches!(
            Quadric::cylinder(DVec3::ZERO, DVec3::ZERO, 1.0),
            Err(Error::ZeroDirection { .. })
        ));
        assert!(matches!(
            Quadric::cone(DVec3::ZERO, DVec3::Z, 2.0),
            Err(Error::AngleOutOfRange { .. })
        ));
        assert!(matches!(
            Quadric::half_space(DVec3::ZERO, 1.0),
            Err(Error::ZeroDirection { .. })
        ));
    }
}
