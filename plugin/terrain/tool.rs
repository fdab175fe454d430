//! Carving tools in world units, and their exact integer form.
//!
//! A [`CarveTool`] is a union of convex pieces, each a [`CarveShape`] in its
//! own frame placed by a [`Transform`] (or swept from one transform to
//! another). [`CarveTool::to_grid`] maps every corner into the terrain's
//! grid ([`Quantization`]) and rounds it — the only rounding of a carve. The
//! result, a [`GridTool`], is a list of integer point sets whose exact
//! convex hulls make the kernel's tool; it is also what a saved terrain
//! records, so replaying it is bit-exact.

use bevy::prelude::*;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::Tool;
use chisel_bsp::tools::{Quantization, dodecahedron_corners, prism_corners};

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
}

impl CarveShape {
    /// The shape's corners in its own frame (`f64`).
    ///
    /// # Errors
    /// [`TerrainError::InvalidTool`] for non-finite or non-positive sizes.
    pub fn corners(&self) -> Result<Vec<[f64; 3]>, TerrainError> {
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
            let corners = piece.shape.corners()?;
            let mut points = Vec::with_capacity(corners.len() * 2);
            for pose in std::iter::once(&piece.pose).chain(piece.sweep_to.as_ref()) {
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
