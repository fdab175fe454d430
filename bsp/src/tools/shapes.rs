//! Convex tool shapes: regular prisms, dodecahedra and swept volumes, as
//! exact hulls of their quantized corner points.
//!
//! Shapes are described in `f64` (the edge of the kernel), then every
//! corner is rounded to the integer grid and the tool is the exact convex
//! hull of those integer points — so a tool is exactly what its corners say,
//! on every machine.

use super::hull::convex_hull;
use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::IntPoint;

/// A rigid placement: rotation (row-major 3×3) then translation, in grid
/// units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation matrix, row-major; applied as `R·p`.
    pub rotation: [[f64; 3]; 3],
    /// Translation added after rotating.
    pub translation: [f64; 3],
}

impl Pose {
    /// A pure translation.
    #[must_use]
    pub fn at(translation: [f64; 3]) -> Self {
        Self {
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            translation,
        }
    }

    /// `R·p + t`, not rounded.
    #[must_use]
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| {
            self.rotation[i][0] * p[0]
                + self.rotation[i][1] * p[1]
                + self.rotation[i][2] * p[2]
                + self.translation[i]
        })
    }

    /// Rounds `R·p + t` to the integer grid.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::CoordinateOutOfRange`].
    pub fn place(&self, p: [f64; 3]) -> Result<IntPoint, Error> {
        let mut out = [0i64; 3];
        for (o, v) in out.iter_mut().zip(self.apply(p)) {
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    what: "tool coordinate",
                });
            }
            // Saturating cast: anything beyond i64 fails the budget check.
            *o = v.round() as i64;
        }
        IntPoint::from_array(out)
    }
}

/// The corners of a regular `sides`-gon prism along `+z`: circumradius
/// `radius`, from `z = 0` to `z = length`, corner `k` at angle `k·2π/sides`.
#[must_use]
pub fn prism_corners(sides: usize, radius: f64, length: f64) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(2 * sides);
    for z in [0.0, length] {
        for k in 0..sides {
            let a = k as f64 * std::f64::consts::TAU / sides as f64;
            out.push([radius * a.cos(), radius * a.sin(), z]);
        }
    }
    out
}

/// The 20 corners of a regular dodecahedron centred at the origin, scaled
/// so its circumradius is `√3 · scale` (cube corners `±scale`).
#[must_use]
pub fn dodecahedron_corners(scale: f64) -> Vec<[f64; 3]> {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let (a, b) = (scale / phi, scale * phi);
    let mut out = Vec::with_capacity(20);
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                out.push([sx * scale, sy * scale, sz * scale]);
            }
            out.push([0.0, sx * a, sy * b]);
            out.push([sx * a, sy * b, 0.0]);
            out.push([sx * b, 0.0, sy * a]);
        }
    }
    out
}

/// The tool with `corners` placed at `pose`: the exact hull of the rounded
/// corners.
///
/// # Errors
/// Non-finite or out-of-range coordinates, or corners that round to a
/// degenerate (flat) set.
pub fn placed_tool(
    arena: &mut ConvexArena,
    corners: &[[f64; 3]],
    pose: &Pose,
) -> Result<PolyId, Error> {
    convex_hull(arena, &placed_points(corners, pose)?)
}

/// The points whose hull is [`placed_tool`]: `corners` placed at `pose`
/// and rounded.
///
/// # Errors
/// Non-finite or out-of-range coordinates.
pub(crate) fn placed_points(corners: &[[f64; 3]], pose: &Pose) -> Result<Vec<IntPoint>, Error> {
    corners.iter().map(|&c| pose.place(c)).collect()
}

/// The hull of a convex tool's corners at pose `a` and at pose `b`: exactly
/// the volume the tool sweeps from one to the other when they differ by a
/// translation. For poses that also turn it only approximates that volume:
/// it misses slivers where corners travel along arcs, and takes in some
/// space between them.
///
/// # Errors
/// As [`placed_tool`].
pub fn swept_tool(
    arena: &mut ConvexArena,
    corners: &[[f64; 3]],
    a: &Pose,
    b: &Pose,
) -> Result<PolyId, Error> {
    convex_hull(arena, &swept_points(corners, a, b)?)
}

/// The points whose hull is [`swept_tool`]: each corner placed at `a` and
/// at `b`, rounded.
///
/// # Errors
/// Non-finite or out-of-range coordinates.
pub(crate) fn swept_points(
    corners: &[[f64; 3]],
    a: &Pose,
    b: &Pose,
) -> Result<Vec<IntPoint>, Error> {
    corners
        .iter()
        .flat_map(|&c| [a.place(c), b.place(c)])
        .collect()
}
