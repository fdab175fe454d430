//! Carving tools in world units, and their exact integer form.
//!
//! A [`CarveTool`] is a union of convex pieces, each a [`CarveShape`] in its
//! own frame placed by a [`Transform`] (or swept from one transform to
//! another). [`CarveTool::to_grid`] maps every corner into the terrain's
//! grid ([`Quantization`]) and rounds it — the only rounding of a carve. The
//! result, a [`GridTool`], is a list of integer point sets whose exact
//! convex hulls make the kernel's tool; it is also what a saved terrain
//! records, so replaying it is bit-exact.
//!
//! Round shapes ([`CarveShape::Sphere`], [`CarveShape::Cylinder`],
//! [`CarveShape::Capsule`]) are carved as exact polyhedra *circumscribed*
//! about the true shape: the carve removes at least the true shape, and no
//! point of the polyhedron is farther than the shape's tolerance from its
//! surface — after the rounding to the grid, which the corners leave room
//! for ([`chisel_bsp::tools::round`]). The tolerance is in world units; by
//! default it is [`DEFAULT_ROUND_TOLERANCE`] of the radius as placed, but
//! at least [`MIN_DEFAULT_TOLERANCE_STEPS`] grid steps. The polyhedron has
//! the fewest corners that meet it, at most [`MAX_ROUND_CORNERS`]. A pose
//! that scales the shape is allowed (the corners leave room for its least
//! and largest scale); a sweep between two poses that differ by a
//! translation keeps the guarantee for the swept volume.

use bevy::prelude::*;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::Tool;
use chisel_bsp::tools::{
    GRID_ROUNDING, Quantization, capsule_corners, cylinder_corners, dodecahedron_corners,
    prism_corners, sphere_corners,
};

use super::error::TerrainError;

/// A convex shape in its own frame, in world units.
#[derive(Clone, Debug, PartialEq, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CarveShape {
    /// A regular dodecahedron centred at the origin with this circumradius.
    Dodecahedron {
        /// Distance from the centre to every corner.
        radius: f32,
    },
    /// A box centred at the origin.
    Cuboid {
        /// Half of the edge lengths.
        half_size: Vec3,
    },
    /// A regular prism along `+z` from `z = 0` to `z = length` (a drill bit
    /// with `sides` flutes).
    Prism {
        /// Number of sides (at least 3).
        sides: u32,
        /// Circumradius of the cross-section.
        radius: f32,
        /// Length along `+z`.
        length: f32,
    },
    /// The convex hull of points.
    Hull(Vec<Vec3>),
    /// A ball centred at the origin, carved as a circumscribed polyhedron
    /// within `tolerance` of its surface.
    Sphere {
        /// Radius.
        radius: f32,
        /// Largest distance, in world units, from the carved polyhedron to
        /// the sphere; `None` for the default (see the module docs).
        tolerance: Option<f32>,
    },
    /// A cylinder along the local `y` axis (as Bevy's `Cylinder`), centred
    /// at the origin, carved as a circumscribed prism within `tolerance`.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Half of the length along `y`.
        half_height: f32,
        /// As for [`CarveShape::Sphere`].
        tolerance: Option<f32>,
    },
    /// A capsule (as Bevy's `Capsule3d`): the points within `radius` of the
    /// segment from `y = −half_height` to `y = half_height`, carved as a
    /// circumscribed polyhedron within `tolerance`.
    Capsule {
        /// Radius.
        radius: f32,
        /// Half of the length of the segment along `y`.
        half_height: f32,
        /// As for [`CarveShape::Sphere`].
        tolerance: Option<f32>,
    },
}

/// The default tolerance of a round shape, as a fraction of its radius as
/// placed (radius × the pose's largest scale): 2 %.
pub const DEFAULT_ROUND_TOLERANCE: f64 = 0.02;

/// The least default tolerance of a round shape, in grid steps: a
/// polyhedron can only be sure to fit once its tolerance exceeds twice the
/// rounding of its corners (`√3` steps).
pub const MIN_DEFAULT_TOLERANCE_STEPS: f64 = 4.0;

/// The most corners of a round shape (a geodesic sphere of 1,002 points
/// fits; a capsule is two of them). A finer tolerance is a
/// [`chisel_bsp::Error::ToleranceUnreachable`].
pub const MAX_ROUND_CORNERS: usize = 1024;

/// How a round shape is fitted: its tolerance and the rounding of its
/// corners, both in the shape's own frame.
struct RoundFit {
    tolerance: f64,
    rounding: f64,
}

impl RoundFit {
    /// The fit of a shape of `radius` with `tolerance` (world units) on a
    /// grid of step `unit`, placed by poses that scale its frame by
    /// `min_scale` to `max_scale`.
    fn new(
        radius: f32,
        tolerance: Option<f32>,
        unit: f64,
        (min_scale, max_scale): (f64, f64),
    ) -> Result<Self, TerrainError> {
        if !(min_scale.is_finite() && max_scale.is_finite() && min_scale > 0.0) {
            return Err(TerrainError::InvalidTool {
                reason: "a round shape's pose needs a finite, non-zero scale",
            });
        }
        let world = match tolerance {
            Some(t) => f64::from(t),
            None => (f64::from(radius) * max_scale * DEFAULT_ROUND_TOLERANCE)
                .max(MIN_DEFAULT_TOLERANCE_STEPS * unit),
        };
        if !(world.is_finite() && world > 0.0) {
            return Err(TerrainError::InvalidTool {
                reason: "a round shape's tolerance must be positive and finite",
            });
        }
        // Scaling by at most `max_scale` stretches distances from the true
        // shape by at most that; rounding by `GRID_ROUNDING · unit` in the
        // world moves a corner by at most that over `min_scale` in the
        // shape's frame.
        Ok(Self {
            tolerance: world / max_scale,
            rounding: GRID_ROUNDING * unit / min_scale,
        })
    }
}

/// The kernel's round shapes have their axis along `z`; ours along `y`
/// (as Bevy's): the rotation `(x, y, z) → (y, z, x)`.
fn z_axis_to_y(corners: Vec<[f64; 3]>) -> Vec<[f64; 3]> {
    corners.into_iter().map(|[x, y, z]| [y, z, x]).collect()
}

impl CarveShape {
    /// The shape's corners in its own frame (`f64`), with no room left for
    /// rounding (round shapes: as if on a grid of step 0 at scale 1; a
    /// carve uses [`CarveShape::corners_on_grid`]).
    ///
    /// # Errors
    /// As [`CarveShape::corners_on_grid`].
    pub fn corners(&self) -> Result<Vec<[f64; 3]>, TerrainError> {
        self.corners_on_grid(0.0, (1.0, 1.0))
    }

    /// The shape's corners in its own frame (`f64`) for a grid of step
    /// `unit` (world units) and poses that scale the frame by `scales.0` to
    /// `scales.1` (the least and largest absolute scale components). Only
    /// round shapes depend on them: their corners leave room for the
    /// rounding, so that the rounded polyhedron still contains the true
    /// shape and lies within its tolerance.
    ///
    /// # Errors
    /// [`TerrainError::InvalidTool`] for non-finite or non-positive sizes,
    /// tolerances or scales of a round shape;
    /// [`TerrainError::Kernel`] with
    /// [`chisel_bsp::Error::ToleranceUnreachable`] when no polyhedron of
    /// at most [`MAX_ROUND_CORNERS`] corners meets the tolerance.
    pub fn corners_on_grid(
        &self,
        unit: f64,
        scales: (f64, f64),
    ) -> Result<Vec<[f64; 3]>, TerrainError> {
        let positive = |v: f32| v.is_finite() && v > 0.0;
        match self {
            CarveShape::Dodecahedron { radius } => {
                if !positive(*radius) {
                    return Err(TerrainError::InvalidTool {
                        reason: "dodecahedron radius must be positive and finite",
                    });
                }
                Ok(dodecahedron_corners(f64::from(*radius) / 3f64.sqrt()))
            }
            CarveShape::Cuboid { half_size } => {
                if !half_size.to_array().into_iter().all(positive) {
                    return Err(TerrainError::InvalidTool {
                        reason: "cuboid half sizes must be positive and finite",
                    });
                }
                let h = half_size.as_dvec3();
                let mut out = Vec::with_capacity(8);
                for i in 0..8 {
                    let s = |bit: usize| if (i >> bit) & 1 == 1 { 1.0 } else { -1.0 };
                    out.push([s(0) * h.x, s(1) * h.y, s(2) * h.z]);
                }
                Ok(out)
            }
            CarveShape::Prism {
                sides,
                radius,
                length,
            } => {
                if *sides < 3 || !positive(*radius) || !positive(*length) {
                    return Err(TerrainError::InvalidTool {
                        reason: "a prism needs at least 3 sides and a positive radius and length",
                    });
                }
                Ok(prism_corners(
                    *sides as usize,
                    f64::from(*radius),
                    f64::from(*length),
                ))
            }
            CarveShape::Hull(points) => {
                if points.iter().any(|p| !p.is_finite()) {
                    return Err(TerrainError::InvalidTool {
                        reason: "hull points must be finite",
                    });
                }
                Ok(points.iter().map(|p| p.as_dvec3().to_array()).collect())
            }
            CarveShape::Sphere { radius, tolerance } => {
                if !positive(*radius) {
                    return Err(TerrainError::InvalidTool {
                        reason: "a sphere's radius must be positive and finite",
                    });
                }
                let fit = RoundFit::new(*radius, *tolerance, unit, scales)?;
                let round = sphere_corners(
                    f64::from(*radius),
                    fit.tolerance,
                    fit.rounding,
                    MAX_ROUND_CORNERS,
                )?;
                Ok(round.corners)
            }
            CarveShape::Cylinder {
                radius,
                half_height,
                tolerance,
            } => {
                if !positive(*radius) || !positive(*half_height) {
                    return Err(TerrainError::InvalidTool {
                        reason: "a cylinder's radius and half height must be positive and finite",
                    });
                }
                let fit = RoundFit::new(*radius, *tolerance, unit, scales)?;
                let round = cylinder_corners(
                    f64::from(*radius),
                    f64::from(*half_height),
                    fit.tolerance,
                    fit.rounding,
                    MAX_ROUND_CORNERS,
                )?;
                Ok(z_axis_to_y(round.corners))
            }
            CarveShape::Capsule {
                radius,
                half_height,
                tolerance,
            } => {
                if !(positive(*radius) && half_height.is_finite() && *half_height >= 0.0) {
                    return Err(TerrainError::InvalidTool {
                        reason: "a capsule's radius must be positive and its half height \
                                 not negative, both finite",
                    });
                }
                let fit = RoundFit::new(*radius, *tolerance, unit, scales)?;
                let round = capsule_corners(
                    f64::from(*radius),
                    f64::from(*half_height),
                    fit.tolerance,
                    fit.rounding,
                    MAX_ROUND_CORNERS,
                )?;
                Ok(z_axis_to_y(round.corners))
            }
        }
    }
}

/// One convex piece of a [`CarveTool`].
#[derive(Clone, Debug, PartialEq, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ToolPiece {
    /// The shape in its own frame.
    pub shape: CarveShape,
    /// Where the shape is placed, in the terrain's local frame.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_transform"))]
    pub pose: Transform,
    /// When set, the piece is the convex hull of the shape's corners at
    /// `pose` and at this pose: exactly the volume the shape sweeps when
    /// the two poses differ by a translation. Between poses that also
    /// turn, the hull only approximates that sweep: it misses slivers where
    /// corners travel along arcs, and takes in some space between them.
    #[cfg_attr(feature = "serde", serde(with = "crate::serde_transform::option"))]
    pub sweep_to: Option<Transform>,
}

/// A union of convex pieces in world units: what a [`super::Carve`] cuts,
/// adds or paints.
#[derive(Clone, Debug, PartialEq, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CarveTool {
    /// The pieces; the tool is their union.
    pub pieces: Vec<ToolPiece>,
}

impl CarveTool {
    /// One shape at `pose`.
    #[must_use]
    pub fn new(shape: CarveShape, pose: Transform) -> Self {
        Self {
            pieces: vec![ToolPiece {
                shape,
                pose,
                sweep_to: None,
            }],
        }
    }

    /// A dodecahedron of circumradius `radius` centred at `centre`.
    #[must_use]
    pub fn dodecahedron(radius: f32, centre: Vec3) -> Self {
        Self::new(
            CarveShape::Dodecahedron { radius },
            Transform::from_translation(centre),
        )
    }

    /// A sphere of `radius` centred at `centre`, within the default
    /// tolerance (module docs).
    #[must_use]
    pub fn sphere(radius: f32, centre: Vec3) -> Self {
        Self::new(
            CarveShape::Sphere {
                radius,
                tolerance: None,
            },
            Transform::from_translation(centre),
        )
    }

    /// A cylinder of `radius` along the `y` axis of `pose`, `2·half_height`
    /// long and centred at its origin, within the default tolerance.
    #[must_use]
    pub fn cylinder(radius: f32, half_height: f32, pose: Transform) -> Self {
        Self::new(
            CarveShape::Cylinder {
                radius,
                half_height,
                tolerance: None,
            },
            pose,
        )
    }

    /// A capsule of `radius` around the segment from `−half_height` to
    /// `half_height` along the `y` axis of `pose`, within the default
    /// tolerance.
    #[must_use]
    pub fn capsule(radius: f32, half_height: f32, pose: Transform) -> Self {
        Self::new(
            CarveShape::Capsule {
                radius,
                half_height,
                tolerance: None,
            },
            pose,
        )
    }

    /// The convex hull of `shape` at pose `from` and at pose `to`: the
    /// volume it sweeps from one to the other when they differ by a
    /// translation, an approximation of it when they also turn
    /// ([`ToolPiece::sweep_to`]).
    #[must_use]
    pub fn swept(shape: CarveShape, from: Transform, to: Transform) -> Self {
        Self {
            pieces: vec![ToolPiece {
                shape,
                pose: from,
                sweep_to: Some(to),
            }],
        }
    }

    /// The union of several tools.
    #[must_use]
    pub fn union(tools: impl IntoIterator<Item = CarveTool>) -> Self {
        Self {
            pieces: tools.into_iter().flat_map(|t| t.pieces).collect(),
        }
    }

    /// Every corner mapped into the grid of `quantization` and rounded.
    ///
    /// # Errors
    /// [`TerrainError::InvalidTool`] for an empty tool or bad sizes;
    /// [`TerrainError::Kernel`] for non-finite or out-of-range coordinates.
    pub fn to_grid(&self, quantization: &Quantization) -> Result<GridTool, TerrainError> {
        if self.pieces.is_empty() {
            return Err(TerrainError::InvalidTool {
                reason: "a tool needs at least one piece",
            });
        }
        let mut pieces = Vec::with_capacity(self.pieces.len());
        for piece in &self.pieces {
            let poses = || std::iter::once(&piece.pose).chain(piece.sweep_to.as_ref());
            let scales = scale_range(poses());
            let corners = piece.shape.corners_on_grid(quantization.unit(), scales)?;
            let mut points = Vec::with_capacity(corners.len() * 2);
            for pose in poses() {
                let matrix = pose.to_matrix().as_dmat4();
                for &c in &corners {
                    let world = matrix.transform_point3(bevy::math::DVec3::from_array(c));
                    points.push(quantization.to_grid(world.to_array())?.coords());
                }
            }
            pieces.push(points);
        }
        Ok(GridTool { pieces })
    }
}

/// The least and largest absolute scale components of `poses`; `NaN` for
/// both when one is not finite.
fn scale_range<'a>(poses: impl Iterator<Item = &'a Transform>) -> (f64, f64) {
    let scales: Vec<f64> = poses
        .flat_map(|pose| pose.scale.abs().to_array())
        .map(f64::from)
        .collect();
    if scales.iter().any(|s| !s.is_finite()) {
        return (f64::NAN, f64::NAN);
    }
    scales.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &s| {
        (lo.min(s), hi.max(s))
    })
}

/// A tool on the integer grid: the union of the exact convex hulls of
/// integer point sets. What a terrain file records for every carve.
#[derive(Clone, Debug, PartialEq, Eq, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct GridTool {
    /// One point set per convex piece, in grid units.
    pub pieces: Vec<Vec<[i64; 3]>>,
}

impl GridTool {
    /// The kernel's tool: the union of the pieces' exact hulls.
    ///
    /// # Errors
    /// [`TerrainError::Kernel`] for out-of-range points or a piece whose
    /// points span no volume (a degenerate tool).
    pub fn build(&self) -> Result<Tool, TerrainError> {
        let tools = self
            .pieces
            .iter()
            .map(|points| {
                let points = points
                    .iter()
                    .map(|&p| IntPoint::from_array(p))
                    .collect::<Result<Vec<_>, _>>()?;
                Tool::convex_hull(&points)
            })
            .collect::<Result<Vec<_>, _>>()?;
        match tools.len() {
            0 => Err(TerrainError::InvalidTool {
                reason: "a tool needs at least one piece",
            }),
            1 => Ok(tools.into_iter().next().ok_or(TerrainError::InvalidTool {
                reason: "a tool needs at least one piece",
            })?),
            _ => Ok(Tool::union(&tools)?),
        }
    }
}
