//! CPU reference ray tracer of a CSG solid in normal form (paper 2, §7.2).
//!
//! Per ray: every quadric's inside spans, one-dimensional CSG over the
//! products ([`intervals`]), and the first boundary of the solid in front of
//! the camera. Its depth, normal and quadric-id images are the ground truth
//! for the splat renderer.
//!
//! Conventions: [`TraceImage::depth`] is the Euclidean distance from the
//! camera (the ray parameter of a unit direction), `+∞` where nothing is hit;
//! normals are the solid's outward unit normals; ids are indices into
//! [`Dnf::quadrics`], [`NO_HIT`] for the background. Row 0 is the top.
//!
//! ```
//! use chisel_quadric::{Camera, CsgDag, Dnf, NO_HIT, Quadric, trace_image};
//! use glam::DVec3;
//!
//! let mut dag = CsgDag::new();
//! let ball = dag.primitive(Quadric::sphere(DVec3::ZERO, 1.0)?, [0.8; 3]);
//! let dnf = Dnf::from_dag(&dag, ball)?;
//! let camera = Camera::new(DVec3::new(0.0, -5.0, 0.0), DVec3::ZERO, 30.0, 33, 33)?;
//! let image = trace_image(&dnf, &camera);
//! let centre = 16 * 33 + 16;
//! assert!((image.depth[centre] - 4.0).abs() < 1e-9);
//! assert_eq!(image.quadric[0], NO_HIT);
//! # Ok::<(), chisel_quadric::Error>(())
//! ```

pub mod intervals;

use glam::DVec3;
use rayon::prelude::*;

use crate::csg::Dnf;
use crate::error::{Error, Result};
use crate::ray::Ray;

/// The id of background pixels.
pub const NO_HIT: u32 = u32::MAX;

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: DVec3,
    /// The point the camera looks at.
    pub look_at: DVec3,
    /// The world's up direction (not parallel to the view direction).
    pub up: DVec3,
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub fov_y_degrees: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `position` looking at `look_at` with `+z` up (or `+y` if
    /// the view is vertical).
    ///
    /// Errors: [`Error::NonFinite`], [`Error::ZeroDirection`] (eye at the
    /// target), [`Error::AngleOutOfRange`], [`Error::NonPositive`] (size 0).
    pub fn new(
        position: DVec3,
        look_at: DVec3,
        fov_y_degrees: f64,
        width: u32,
        height: u32,
    ) -> Result<Self> {
        if !position.is_finite() || !look_at.is_finite() || !fov_y_degrees.is_finite() {
            return Err(Error::NonFinite { what: "camera" });
        }
        let forward = (look_at - position)
            .try_normalize()
            .ok_or(Error::ZeroDirection {
                what: "camera view direction",
            })?;
        if !(fov_y_degrees > 0.0 && fov_y_degrees < 180.0) {
            return Err(Error::AngleOutOfRange {
                degrees: fov_y_degrees,
            });
        }
        if width == 0 || height == 0 {
            return Err(Error::NonPositive {
                what: "image size",
                value: 0.0,
            });
        }
        let up = if forward.cross(DVec3::Z).length() > 1e-6 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        Ok(Self {
            position,
            look_at,
            up,
            fov_y_degrees,
            width,
            height,
        })
    }

    /// The unit ray through the centre of pixel `(x, y)` (row 0 at the top).
    #[must_use]
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let half = (0.5 * self.fov_y_degrees.to_radians()).tan();
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let sx = (2.0 * (f64::from(x) + 0.5) / w - 1.0) * half * w / h;
        let sy = (1.0 - 2.0 * (f64::from(y) + 0.5) / h) * half;
        Ray {
            origin: self.position,
            direction: (forward + right * sx + up * sy).normalize(),
        }
    }
}

/// The first boundary of the solid along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceHit {
    /// Ray parameter (distance for a unit direction).
    pub t: f64,
    /// The hit point.
    pub point: DVec3,
    /// The solid's outward unit normal (zero at a singular point).
    pub normal: DVec3,
    /// Index into [`Dnf::quadrics`].
    pub quadric: u32,
}

/// The first boundary of the solid of `dnf` along `ray` with `t > t_min`.
#[must_use]
pub fn trace_ray(dnf: &Dnf, ray: &Ray, t_min: f64) -> Option<TraceHit> {
    let merged = intervals::solid_intervals(dnf, ray);
    let bound = merged.iter().find_map(|iv| {
        if iv.entry.t > t_min {
            Some(iv.entry)
        } else if iv.exit.t > t_min {
            Some(iv.exit)
        } else {
            None
        }
    })?;
    if !bound.t.is_finite() || bound.quadric == NO_HIT {
        return None;
    }
    let point = ray.at(bound.t);
    let quadric = &dnf.quadrics()[bound.quadric as usize].quadric;
    let normal = quadric
        .normal(point)
        .map_or(DVec3::ZERO, |n| n * bound.sign);
    Some(TraceHit {
        t: bound.t,
        point,
        normal,
        quadric: bound.quadric,
    })
}

/// Depth, normal and quadric-id images of one view.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Distance from the camera per pixel, row-major, `+∞` for background.
    pub depth: Vec<f64>,
    /// Outward unit normal per pixel (zero for background).
    pub normal: Vec<DVec3>,
    /// Quadric index per pixel, [`NO_HIT`] for background.
    pub quadric: Vec<u32>,
}

/// Ray traces `dnf` from `camera` (rows in parallel, deterministic).
#[must_use]
pub fn trace_image(dnf: &Dnf, camera: &Camera) -> TraceImage {
    let rows: Vec<Vec<Option<TraceHit>>> = (0..camera.height)
        .into_par_iter()
        .map(|y| {
            (0..camera.width)
                .map(|x| trace_ray(dnf, &camera.ray(x, y), 0.0))
                .collect()
        })
        .collect();
    let n = rows.len() * camera.width as usize;
    let mut image = TraceImage {
        width: camera.width,
        height: camera.height,
        depth: Vec::with_capacity(n),
        normal: Vec::with_capacity(n),
        quadric: Vec::with_capacity(n),
    };
    for hit in rows.into_iter().flatten() {
        image.depth.push(hit.map_or(f64::INFINITY, |h| h.t));
        image.normal.push(hit.map_or(DVec3::ZERO, |h| h.normal));
        image.quadric.push(hit.map_or(NO_HIT, |h| h.quadric));
    }
    image
}
