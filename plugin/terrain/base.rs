//! What a terrain starts from: a box, a heightfield with material layers by
//! depth, or a closed triangle mesh — all on the integer grid, so that
//! building the octree from a [`TerrainBase`] is a pure, exact function
//! (a saved terrain stores its base as the record of what it was built
//! from, beside the octree itself).
//!
//! Axes: grid axes are the terrain's local axes; heights run along `+y`.

use std::collections::{BTreeSet, HashSet};

use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::import_layers::LayeredHeightfield;
use chisel_bsp::octree::{Anchors, CellBox, CubeSide, DebrisConfig, Octree, OctreeConfig};
use chisel_bsp::tree::Label;

use super::error::TerrainError;

/// A heightfield on the grid: samples `heights[i + j·nx]` at
/// `(corner.x + i·spacing, heights[..], corner.z + j·spacing)`, a flat
/// bottom at `y = bottom`, the solid between labelled `label`, and bands
/// of other materials below the surface.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GridHeightfield {
    /// Grid position of sample `(0, 0)` in x and z (y unused).
    pub corner: [i64; 3],
    /// Samples along x and along z (at least 2 each).
    pub samples: [u32; 2],
    /// Grid distance between neighbouring samples (positive).
    pub spacing: i64,
    /// Grid y of every sample, row by row (x fastest).
    pub heights: Vec<i64>,
    /// Grid y of the flat bottom, below every sample.
    pub bottom: i64,
    /// The material of the solid below the bands.
    pub label: Label,
    /// Bands `(depth, label)`: everything less than `depth` below the
    /// surface (vertically, measured at the samples and, in between, from
    /// the lower hull of each square's corners) is `label`; shallower
    /// bands lie over deeper ones. Built in one pass with the solid
    /// ([`Octree::from_layered_heightfield`]).
    pub layers: Vec<(i64, Label)>,
}

/// The solid a terrain starts from, inside the octree cube at `origin`
/// with edge `2^size_log2` (grid units).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TerrainBase {
    /// A box of one material.
    Box {
        /// Lower corner of the octree cube.
        origin: [i64; 3],
        /// The cube's edge is `2^size_log2`.
        size_log2: u8,
        /// The solid box.
        solid: CellBox,
        /// Its material.
        label: Label,
    },
    /// A heightfield with layers.
    Heightfield {
        /// Lower corner of the octree cube.
        origin: [i64; 3],
        /// The cube's edge is `2^size_log2`.
        size_log2: u8,
        /// The heightfield.
        field: GridHeightfield,
    },
    /// A closed triangle mesh of one material (counter-clockwise from
    /// outside).
    Triangles {
        /// Lower corner of the octree cube.
        origin: [i64; 3],
        /// The cube's edge is `2^size_log2`.
        size_log2: u8,
        /// The triangles, in grid units.
        triangles: Vec<[[i64; 3]; 3]>,
        /// Their solid's material.
        label: Label,
    },
}

impl TerrainBase {
    /// The octree of this base.
    ///
    /// # Errors
    /// [`TerrainError::Kernel`] for a bad cube, out-of-range input or an
    /// open mesh; [`TerrainError::InvalidHeightfield`] for a malformed field.
    pub fn build(&self, config: OctreeConfig) -> Result<Octree, TerrainError> {
        match self {
            TerrainBase::Box {
                origin,
                size_log2,
                solid,
                label,
            } => Ok(Octree::from_box(
                *origin, *size_log2, *solid, *label, config,
            )?),
            TerrainBase::Triangles {
                origin,
                size_log2,
                triangles,
                label,
            } => {
                let triangles = to_points(triangles)?;
                Ok(Octree::from_triangles(
                    *origin, *size_log2, &triangles, *label, config,
                )?)
            }
            TerrainBase::Heightfield {
                origin,
                size_log2,
                field,
            } => {
                field.check()?;
                let layered = LayeredHeightfield {
                    corner: [field.corner[0], field.corner[2]],
                    samples: field.samples,
                    spacing: field.spacing,
                    heights: &field.heights,
                    bottom: field.bottom,
                    label: field.label,
                    bands: &field.layers,
                };
                Ok(Octree::from_layered_heightfield(
                    *origin, *size_log2, &layered, config,
                )?)
            }
        }
    }

    /// The materials the base is made of: its solid's label and, for a
    /// heightfield, every band's.
    #[must_use]
    pub fn labels(&self) -> BTreeSet<Label> {
        match self {
            TerrainBase::Box { label, .. } | TerrainBase::Triangles { label, .. } => {
                BTreeSet::from([*label])
            }
            TerrainBase::Heightfield { field, .. } => std::iter::once(field.label)
                .chain(field.layers.iter().map(|&(_, label)| label))
                .collect(),
        }
    }

    /// The lowest grid layer of the solid: everything with volume in it is
    /// anchored ([`chisel_bsp::octree::Anchors`]), so debris is what a carve
    /// separates from the ground the terrain stands on.
    #[must_use]
    pub fn floor(&self) -> CellBox {
        let (origin, size_log2) = self.cube();
        let edge = 1i64 << size_log2;
        let bottom = match self {
            TerrainBase::Box { solid, .. } => solid.min[1],
            TerrainBase::Heightfield { field, .. } => field.bottom,
            TerrainBase::Triangles { triangles, .. } => triangles
                .iter()
                .flatten()
                .map(|p| p[1])
                .min()
                .unwrap_or(origin[1]),
        };
        CellBox {
            min: [origin[0], bottom, origin[2]],
            max: [origin[0] + edge, bottom + 1, origin[2] + edge],
        }
    }

    /// The debris settings of a terrain on this base: anchored by
    /// [`TerrainBase::floor`] and the cube's bottom, no limit.
    #[must_use]
    pub fn debris_config(&self) -> DebrisConfig {
        DebrisConfig {
            anchors: Anchors {
                sides: vec![CubeSide::BOTTOM],
                boxes: vec![self.floor()],
            },
            max_volume: None,
            max_cells: None,
        }
    }

    /// The octree cube: lower corner and edge exponent.
    #[must_use]
    pub fn cube(&self) -> ([i64; 3], u8) {
        match self {
            TerrainBase::Box {
                origin, size_log2, ..
            }
            | TerrainBase::Heightfield {
                origin, size_log2, ..
            }
            | TerrainBase::Triangles {
                origin, size_log2, ..
            } => (*origin, *size_log2),
        }
    }
}

fn to_points(triangles: &[[[i64; 3]; 3]]) -> Result<Vec<[IntPoint; 3]>, TerrainError> {
    triangles
        .iter()
        .map(|t| {
            Ok([
                IntPoint::from_array(t[0])?,
                IntPoint::from_array(t[1])?,
                IntPoint::from_array(t[2])?,
            ])
        })
        .collect()
}

/// The smallest power-of-two cube holding `[min, max]` with `margin`
/// around it: `(origin, size_log2)`.
#[must_use]
pub fn cube_around(min: [i64; 3], max: [i64; 3], margin: i64) -> ([i64; 3], u8) {
    let lo = min.map(|m| m - margin);
    let extent = (0..3).map(|a| max[a] + margin - lo[a]).max().unwrap_or(1);
    let mut size_log2 = 1u8;
    while (1i64 << size_log2) < extent && size_log2 < 27 {
        size_log2 += 1;
    }
    (lo, size_log2)
}

impl GridHeightfield {
    fn check(&self) -> Result<(), TerrainError> {
        let bad = |reason: String| Err(TerrainError::InvalidHeightfield { reason });
        let [nx, nz] = self.samples;
        if nx < 2 || nz < 2 {
            return bad(format!("needs at least 2×2 samples, got {nx}×{nz}"));
        }
        if self.heights.len() != nx as usize * nz as usize {
            return bad(format!(
                "{} heights for {nx}×{nz} samples",
                self.heights.len()
            ));
        }
        if self.spacing <= 0 {
            return bad(format!("spacing {} is not positive", self.spacing));
        }
        if let Some(h) = self.heights.iter().find(|&&h| h <= self.bottom) {
            return bad(format!(
                "height {h} is not above the bottom {}; lower the bottom",
                self.bottom
            ));
        }
        if let Some(&(depth, _)) = self.layers.iter().find(|&&(d, _)| d <= 0) {
            return bad(format!("layer depth {depth} is not positive"));
        }
        Ok(())
    }

    fn top(&self, i: u32, j: u32) -> [i64; 3] {
        let h = self.heights[(i + j * self.samples[0]) as usize];
        self.at(i, j, h)
    }

    fn at(&self, i: u32, j: u32, y: i64) -> [i64; 3] {
        [
            self.corner[0] + i64::from(i) * self.spacing,
            y,
            self.corner[2] + i64::from(j) * self.spacing,
        ]
    }

    /// The closed surface: the top (two triangles per square), a flat
    /// bottom with the same squares, and walls along the border.
    ///
    /// # Errors
    /// [`TerrainError::InvalidHeightfield`] for a malformed field.
    pub fn closed_mesh(&self) -> Result<Vec<[[i64; 3]; 3]>, TerrainError> {
        self.check()?;
        let [nx, nz] = self.samples;
        let squares = (nx as usize - 1) * (nz as usize - 1);
        let mut out = Vec::with_capacity(2 * squares);
        let mut under = Vec::with_capacity(2 * squares);
        let bottom = |i, j| self.at(i, j, self.bottom);
        for j in 0..nz - 1 {
            for i in 0..nx - 1 {
                let (p00, p10) = (self.top(i, j), self.top(i + 1, j));
                let (p01, p11) = (self.top(i, j + 1), self.top(i + 1, j + 1));
                out.push([p00, p01, p10]);
                out.push([p10, p01, p11]);
                let (b00, b10) = (bottom(i, j), bottom(i + 1, j));
                let (b01, b11) = (bottom(i, j + 1), bottom(i + 1, j + 1));
                under.push([b00, b10, b01]);
                under.push([b10, b11, b01]);
            }
        }
        // Walls under every border edge of the top, which is an edge whose
        // opposite no top triangle uses.
        let top_edges: HashSet<([i64; 3], [i64; 3])> = out
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect();
        let mut walls = Vec::new();
        for &(u, v) in &top_edges {
            if top_edges.contains(&(v, u)) {
                continue;
            }
            let (ub, vb) = ([u[0], self.bottom, u[2]], [v[0], self.bottom, v[2]]);
            walls.push([v, u, ub]);
            walls.push([v, ub, vb]);
        }
        // Hash order is not deterministic; the triangle order must be.
        walls.sort_unstable();
        out.extend(under);
        out.extend(walls);
        Ok(out)
    }
}
