//! Tools on the wire: a client's float tool ([`WireTool::World`], the
//! numbers of a [`CarveTool`]) or a tool already on the grid
//! ([`WireTool::Grid`]), and their conversions.

use bevy::prelude::*;
use serde::{Deserialize, Serialize};

use crate::terrain::{CarveShape, CarveTool, GridTool, MAX_ROUND_CORNERS, ToolPiece};

/// A pose in world units: translation, rotation quaternion `[x, y, z, w]`
/// and scale, as in a Bevy `Transform`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WirePose {
    /// Translation.
    pub translation: [f32; 3],
    /// Rotation quaternion `[x, y, z, w]`.
    pub rotation: [f32; 4],
    /// Scale per axis.
    pub scale: [f32; 3],
}

impl From<&Transform> for WirePose {
    fn from(t: &Transform) -> Self {
        Self {
            translation: t.translation.to_array(),
            rotation: t.rotation.to_array(),
            scale: t.scale.to_array(),
        }
    }
}

impl From<&WirePose> for Transform {
    fn from(p: &WirePose) -> Self {
        Transform {
            translation: Vec3::from_array(p.translation),
            rotation: Quat::from_array(p.rotation),
            scale: Vec3::from_array(p.scale),
        }
    }
}

/// A [`CarveShape`] on the wire.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum WireShape {
    /// [`CarveShape::Dodecahedron`].
    Dodecahedron {
        /// Circumradius.
        radius: f32,
    },
    /// [`CarveShape::Cuboid`].
    Cuboid {
        /// Half edge lengths.
        half_size: [f32; 3],
    },
    /// [`CarveShape::Prism`].
    Prism {
        /// Sides.
        sides: u32,
        /// Circumradius.
        radius: f32,
        /// Length along `+z`.
        length: f32,
    },
    /// [`CarveShape::Hull`].
    Hull(Vec<[f32; 3]>),
    /// [`CarveShape::Sphere`] (variants are only ever appended, so older
    /// encodings keep their meaning).
    Sphere {
        /// Radius.
        radius: f32,
        /// Tolerance in world units; `None` for the default.
        tolerance: Option<f32>,
    },
    /// [`CarveShape::Cylinder`].
    Cylinder {
        /// Radius.
        radius: f32,
        /// Half of the length along `y`.
        half_height: f32,
        /// Tolerance in world units; `None` for the default.
        tolerance: Option<f32>,
    },
    /// [`CarveShape::Capsule`].
    Capsule {
        /// Radius.
        radius: f32,
        /// Half of the segment's length along `y`.
        half_height: f32,
        /// Tolerance in world units; `None` for the default.
        tolerance: Option<f32>,
    },
}

/// One [`ToolPiece`] on the wire.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WirePiece {
    /// The shape in its own frame.
    pub shape: WireShape,
    /// Where it is placed.
    pub pose: WirePose,
    /// The end pose of a sweep.
    pub sweep_to: Option<WirePose>,
}

/// The tool of a carve request.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum WireTool {
    /// A [`CarveTool`]'s numbers; the server rounds it to the grid.
    World(Vec<WirePiece>),
    /// A tool already on the terrain's grid.
    Grid(GridTool),
}

impl From<&CarveTool> for WireTool {
    fn from(tool: &CarveTool) -> Self {
        WireTool::World(
            tool.pieces
                .iter()
                .map(|piece| WirePiece {
                    shape: match &piece.shape {
                        CarveShape::Dodecahedron { radius } => {
                            WireShape::Dodecahedron { radius: *radius }
                        }
                        CarveShape::Cuboid { half_size } => WireShape::Cuboid {
                            half_size: half_size.to_array(),
                        },
                        CarveShape::Prism {
                            sides,
                            radius,
                            length,
                        } => WireShape::Prism {
                            sides: *sides,
                            radius: *radius,
                            length: *length,
                        },
                        CarveShape::Hull(points) => {
                            WireShape::Hull(points.iter().map(|p| p.to_array()).collect())
                        }
                        CarveShape::Sphere { radius, tolerance } => WireShape::Sphere {
                            radius: *radius,
                            tolerance: *tolerance,
                        },
                        CarveShape::Cylinder {
                            radius,
                            half_height,
                            tolerance,
                        } => WireShape::Cylinder {
                            radius: *radius,
                            half_height: *half_height,
                            tolerance: *tolerance,
                        },
                        CarveShape::Capsule {
                            radius,
                            half_height,
                            tolerance,
                        } => WireShape::Capsule {
                            radius: *radius,
                            half_height: *half_height,
                            tolerance: *tolerance,
                        },
                    },
                    pose: WirePose::from(&piece.pose),
                    sweep_to: piece.sweep_to.as_ref().map(WirePose::from),
                })
                .collect(),
        )
    }
}

impl WireTool {
    /// Pieces and the most points of one piece (a hull's points; a fixed
    /// shape counts its corners), for the server's size limits before any
    /// geometry is built.
    #[must_use]
    pub fn size(&self) -> (usize, usize) {
        match self {
            WireTool::World(pieces) => (
                pieces.len(),
                pieces
                    .iter()
                    .map(|p| match &p.shape {
                        WireShape::Hull(points) => points.len(),
                        WireShape::Prism { sides, .. } => 2 * *sides as usize,
                        // The most a round shape may take: its corners
                        // depend on the grid, known only to the server.
                        WireShape::Sphere { .. }
                        | WireShape::Cylinder { .. }
                        | WireShape::Capsule { .. } => MAX_ROUND_CORNERS,
                        WireShape::Dodecahedron { .. } | WireShape::Cuboid { .. } => 20,
                    })
                    .max()
                    .unwrap_or(0),
            ),
            WireTool::Grid(tool) => (
                tool.pieces.len(),
                tool.pieces.iter().map(Vec::len).max().unwrap_or(0),
            ),
        }
    }

    /// The tool on `grid`: a float tool rounded, a grid tool as sent. The
    /// one rounding of a carve: the server's, and the one a client that
    /// predicts its own carves applies ([`super::super::NetClientSettings`]),
    /// so that its prediction is the carve the server orders.
    ///
    /// # Errors
    /// [`super::RejectReason::Invalid`] for a float tool with no pieces or
    /// one that does not round (non-finite numbers, a degenerate shape).
    pub fn to_grid(
        &self,
        grid: &chisel_bsp::tools::Quantization,
    ) -> Result<GridTool, super::RejectReason> {
        match self {
            WireTool::Grid(grid_tool) => Ok(grid_tool.clone()),
            WireTool::World(_) => self
                .to_carve_tool()
                .ok_or_else(|| super::RejectReason::Invalid("no tool".into()))?
                .to_grid(grid)
                .map_err(|e| super::RejectReason::Invalid(e.to_string())),
        }
    }

    /// The float tool of a [`WireTool::World`] (`None` for a grid tool).
    #[must_use]
    pub fn to_carve_tool(&self) -> Option<CarveTool> {
        let WireTool::World(pieces) = self else {
            return None;
        };
        Some(CarveTool {
            pieces: pieces
                .iter()
                .map(|piece| ToolPiece {
                    shape: match &piece.shape {
                        WireShape::Dodecahedron { radius } => {
                            CarveShape::Dodecahedron { radius: *radius }
                        }
                        WireShape::Cuboid { half_size } => CarveShape::Cuboid {
                            half_size: Vec3::from_array(*half_size),
                        },
                        WireShape::Prism {
                            sides,
                            radius,
                            length,
                        } => CarveShape::Prism {
                            sides: *sides,
                            radius: *radius,
                            length: *length,
                        },
                        WireShape::Hull(points) => {
                            CarveShape::Hull(points.iter().map(|&p| Vec3::from_array(p)).collect())
                        }
                        WireShape::Sphere { radius, tolerance } => CarveShape::Sphere {
                            radius: *radius,
                            tolerance: *tolerance,
                        },
                        WireShape::Cylinder {
                            radius,
                            half_height,
                            tolerance,
                        } => CarveShape::Cylinder {
                            radius: *radius,
                            half_height: *half_height,
                            tolerance: *tolerance,
                        },
                        WireShape::Capsule {
                            radius,
                            half_height,
                            tolerance,
                        } => CarveShape::Capsule {
                            radius: *radius,
                            half_height: *half_height,
                            tolerance: *tolerance,
                        },
                    },
                    pose: Transform::from(&piece.pose),
                    sweep_to: piece.sweep_to.as_ref().map(Transform::from),
                })
                .collect(),
        })
    }
}
