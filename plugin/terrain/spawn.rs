//! Building terrains from world-unit input: a box, a heightfield (from an
//! image or from samples) with material layers by depth, or a Bevy mesh.
//! Everything is rounded to the grid once, here; the result records its
//! [`TerrainBase`] on the grid.

use std::path::Path;

use bevy::mesh::{Indices, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use chisel_bsp::octree::{CellBox, OctreeConfig};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::Label;

use super::base::{GridHeightfield, TerrainBase, cube_around};
use super::component::Terrain;
use super::error::TerrainError;

/// The octree settings of terrains built by [`Terrain::from_box`],
/// [`Terrain::from_heightfield`] and [`Terrain::from_mesh`]: at most 40
/// inner BSP nodes per cell rather than the kernel's default of 150 (the
/// paper's value), because carving many small tools is faster with small
/// cells (crater carves, apply and re-meshing: median 1.9–2.5 ms at 40
/// against 2.4–2.7 ms at 150, in alternating runs;
/// `benches/results/2026-11-22-terrain-crater.md`).
/// [`Terrain::from_base`] takes any settings.
#[must_use]
pub fn terrain_octree_config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 40,
        ..OctreeConfig::default()
    }
}

/// A band of material under a heightfield's surface.
#[derive(Clone, Copy, Debug, PartialEq, Reflect, serde::Serialize, serde::Deserialize)]
pub struct HeightLayer {
    /// Everything less than this far below the surface (world units)…
    pub depth: f32,
    /// …is this material (shallower layers win).
    pub label: Label,
}

/// A heightfield in world units: `heights[i + j·width]` is the surface
/// height (local `y`) at `(corner.x + i·spacing, corner.z + j·spacing)`.
#[derive(Asset, Clone, Debug, PartialEq, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Heightfield {
    /// Samples along x and z.
    pub size: UVec2,
    /// Surface heights, row by row (x fastest).
    pub heights: Vec<f32>,
    /// Distance between neighbouring samples.
    pub spacing: f32,
    /// Position of sample `(0, 0)` in x and z (`y` ignored).
    pub corner: Vec3,
    /// Height of the flat bottom; below every sample.
    pub bottom: f32,
    /// The material below all layers.
    pub label: Label,
    /// Bands of other materials under the surface.
    pub layers: Vec<HeightLayer>,
}

impl Heightfield {
    /// A heightfield from an image's brightness (16-bit grey keeps all its
    /// precision): black is `low`, white is `high`. The field is centred on
    /// the origin in x and z, with its bottom `depth` below `low`.
    #[must_use]
    pub fn from_image(
        image: &image::DynamicImage,
        spacing: f32,
        low: f32,
        high: f32,
        depth: f32,
        label: Label,
    ) -> Self {
        let grey = image.to_luma16();
        let (w, h) = grey.dimensions();
        let heights = grey
            .pixels()
            .map(|p| low + (high - low) * f32::from(p.0[0]) / f32::from(u16::MAX))
            .collect();
        let half = Vec3::new(
            (w.saturating_sub(1)) as f32,
            0.0,
            (h.saturating_sub(1)) as f32,
        ) * spacing
            / 2.0;
        Self {
            size: UVec2::new(w, h),
            heights,
            spacing,
            corner: -half,
            bottom: low - depth,
            label,
            layers: Vec::new(),
        }
    }

    /// As [`Heightfield::from_image`] for an image file (PNG).
    ///
    /// # Errors
    /// [`TerrainError::InvalidHeightfield`] when the file cannot be read.
    pub fn load_image(
        path: impl AsRef<Path>,
        spacing: f32,
        low: f32,
        high: f32,
        depth: f32,
        label: Label,
    ) -> Result<Self, TerrainError> {
        let path = path.as_ref();
        let image = image::open(path).map_err(|e| TerrainError::InvalidHeightfield {
            reason: format!("cannot read {}: {e}", path.display()),
        })?;
        Ok(Self::from_image(&image, spacing, low, high, depth, label))
    }

    /// With bands of material under the surface.
    #[must_use]
    pub fn with_layers(mut self, layers: impl IntoIterator<Item = HeightLayer>) -> Self {
        self.layers = layers.into_iter().collect();
        self
    }

    /// The heightfield on the grid.
    ///
    /// # Errors
    /// [`TerrainError::InvalidHeightfield`] for non-finite values or sizes
    /// that do not fit the grid; [`TerrainError::Kernel`] for coordinates
    /// out of range.
    pub fn to_grid(&self, q: &Quantization) -> Result<GridHeightfield, TerrainError> {
        let bad = |reason: String| TerrainError::InvalidHeightfield { reason };
        let spacing = (f64::from(self.spacing) / q.unit()).round();
        if !(spacing.is_finite() && spacing >= 1.0 && spacing < (1u64 << 26) as f64) {
            return Err(bad(format!(
                "spacing {} is not a positive number of grid units",
                self.spacing
            )));
        }
        let corner = q
            .to_grid_f32([self.corner.x, self.bottom, self.corner.z])?
            .coords();
        let heights = self
            .heights
            .iter()
            .map(|&h| Ok(q.to_grid_f32([self.corner.x, h, self.corner.z])?.coords()[1]))
            .collect::<Result<Vec<i64>, TerrainError>>()?;
        let layers = self
            .layers
            .iter()
            .map(|l| {
                let d = (f64::from(l.depth) / q.unit()).round();
                if d.is_finite() && d >= 1.0 && d < (1u64 << 27) as f64 {
                    Ok((d as i64, l.label))
                } else {
                    Err(bad(format!("layer depth {} is not positive", l.depth)))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(GridHeightfield {
            corner,
            samples: [self.size.x, self.size.y],
            spacing: spacing as i64,
            heights,
            bottom: corner[1],
            label: self.label,
            layers,
        })
    }
}

impl Terrain {
    /// A box of material `label` from `min` to `max` (local frame), in a
    /// cube with room around it for adding material.
    ///
    /// # Errors
    /// Out-of-range or non-finite corners, or an empty box.
    pub fn from_box(
        quantization: Quantization,
        min: Vec3,
        max: Vec3,
        label: Label,
    ) -> Result<Self, TerrainError> {
        let solid = CellBox {
            min: quantization.to_grid_f32(min.to_array())?.coords(),
            max: quantization.to_grid_f32(max.to_array())?.coords(),
        };
        let extent = (0..3)
            .map(|a| solid.max[a] - solid.min[a])
            .max()
            .unwrap_or(0);
        let (origin, size_log2) = cube_around(solid.min, solid.max, extent / 8 + 1);
        Self::from_base(
            quantization,
            TerrainBase::Box {
                origin,
                size_log2,
                solid,
                label,
            },
            terrain_octree_config(),
        )
    }

    /// A terrain from a heightfield with its layers.
    ///
    /// # Errors
    /// As [`Heightfield::to_grid`] and [`TerrainBase::build`].
    pub fn from_heightfield(
        quantization: Quantization,
        heightfield: &Heightfield,
    ) -> Result<Self, TerrainError> {
        let field = heightfield.to_grid(&quantization)?;
        let [nx, nz] = field.samples;
        let far = [
            field.corner[0] + i64::from(nx.saturating_sub(1)) * field.spacing,
            field.heights.iter().copied().max().unwrap_or(field.bottom),
            field.corner[2] + i64::from(nz.saturating_sub(1)) * field.spacing,
        ];
        let extent = (0..3).map(|a| far[a] - field.corner[a]).max().unwrap_or(0);
        let (origin, size_log2) = cube_around(field.corner, far, extent / 8 + 1);
        Self::from_base(
            quantization,
            TerrainBase::Heightfield {
                origin,
                size_log2,
                field,
            },
            terrain_octree_config(),
        )
    }

    /// The solid bounded by a closed Bevy triangle mesh (counter-clockwise
    /// from outside), labelled `label`.
    ///
    /// # Errors
    /// [`TerrainError::InvalidMesh`] for a mesh that is not a triangle list
    /// with `f32` positions; [`TerrainError::Kernel`] with
    /// [`chisel_bsp::Error::NotWatertight`] for an open mesh (after
    /// rounding to the grid), or out-of-range coordinates.
    pub fn from_mesh(
        quantization: Quantization,
        mesh: &Mesh,
        label: Label,
    ) -> Result<Self, TerrainError> {
        if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
            return Err(TerrainError::InvalidMesh {
                reason: "the topology is not a triangle list",
            });
        }
        let Ok(Some(VertexAttributeValues::Float32x3(positions))) =
            mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
        else {
            return Err(TerrainError::InvalidMesh {
                reason: "no Float32x3 positions (or the mesh lives in the render world only)",
            });
        };
        let points = positions
            .iter()
            .map(|&p| Ok(quantization.to_grid_f32(p)?.coords()))
            .collect::<Result<Vec<[i64; 3]>, TerrainError>>()?;
        let indices: Vec<usize> = match mesh.try_indices_option() {
            Ok(Some(Indices::U16(v))) => v.iter().map(|&i| usize::from(i)).collect(),
            Ok(Some(Indices::U32(v))) => v.iter().map(|&i| i as usize).collect(),
            _ => (0..points.len()).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(TerrainError::InvalidMesh {
                reason: "the index count is not a multiple of 3",
            });
        }
        let triangles = indices
            .chunks_exact(3)
            .map(|t| {
                let corner = |i: usize| {
                    points.get(i).copied().ok_or(TerrainError::InvalidMesh {
                        reason: "an index is past the last vertex",
                    })
                };
                Ok([corner(t[0])?, corner(t[1])?, corner(t[2])?])
            })
            .collect::<Result<Vec<_>, TerrainError>>()?;
        let CellBox { min, max } =
            CellBox::enclosing(points.iter().copied()).ok_or(TerrainError::InvalidMesh {
                reason: "the mesh has no vertices",
            })?;
        let extent = (0..3).map(|a| max[a] - min[a]).max().unwrap_or(0);
        let (origin, size_log2) = cube_around(min, max, extent / 8 + 1);
        Self::from_base(
            quantization,
            TerrainBase::Triangles {
                origin,
                size_log2,
                triangles,
                label,
            },
            terrain_octree_config(),
        )
    }
}
