//! What a world's surface comes from ([`WorldSource`]) and how the world
//! is cut into chunks ([`WorldLayout`]): the base of every chunk, exact and
//! on the grid.
//!
//! Notation: the world's samples lie on a square lattice in x and z;
//! sample `(i, j)` is at grid `(i·s, h(i, j), j·s)` with `s` the spacing
//! (`2^spacing_log2` grid units) and `h` the source. Chunk `(cx, cz)` is
//! the octree cube of edge `E = 2^chunk_log2` at grid
//! `(cx·E, floor, cz·E)`; its base is the heightfield of the samples
//! `cx·n ..= (cx+1)·n` by `cz·n ..= (cz+1)·n`, `n = E / s`, whose walls
//! lie exactly on the cube's sides. Two neighbouring chunks read the same
//! samples on their shared side and split every square along the same
//! diagonal, so their surfaces meet there exactly.

use std::sync::Arc;

use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::Label;

use super::super::base::{GridHeightfield, TerrainBase};
use super::super::error::TerrainError;
use super::super::spawn::Heightfield;
use super::ChunkCoord;

/// A world's surface: the grid height of every lattice sample. It must be
/// exact and deterministic (the same integer for the same sample, on every
/// run and thread): a chunk is rebuilt from it whenever it streams in
/// unedited, and chunks that share a side read the same samples.
///
/// Any `Fn(i64, i64) -> i64` closure is a source (a noise function
/// rounded to the grid, say); [`HeightArray`] is one from sampled heights.
pub trait WorldSource: Send + Sync + 'static {
    /// The grid y of the surface at lattice sample `(i, j)`, which lies at
    /// grid x `i·spacing`, grid z `j·spacing`.
    fn height(&self, i: i64, j: i64) -> i64;
}

impl<F: Fn(i64, i64) -> i64 + Send + Sync + 'static> WorldSource for F {
    fn height(&self, i: i64, j: i64) -> i64 {
        self(i, j)
    }
}

/// Heights sampled in advance (a heightfield image, an array): sample
/// `(i, j)` of the world is `heights[(i - origin.0) + (j - origin.1)·nx]`;
/// samples outside the array repeat the nearest edge sample.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HeightArray {
    /// The world sample index of the array's first sample.
    pub origin: [i64; 2],
    /// Samples along x and along z (at least 1 each).
    pub samples: [u32; 2],
    /// Grid heights, row by row (x fastest).
    pub heights: Vec<i64>,
}

impl HeightArray {
    /// A height array from a world-unit [`Heightfield`] (for example
    /// [`Heightfield::from_image`]): its spacing must round to the
    /// layout's and its corner must lie on the layout's lattice.
    ///
    /// # Errors
    /// [`TerrainError::InvalidHeightfield`] when the spacing or corner do
    /// not match the layout, or as [`Heightfield::to_grid`].
    pub fn from_heightfield(
        field: &Heightfield,
        layout: &WorldLayout,
    ) -> Result<Self, TerrainError> {
        let grid = field.to_grid(&layout.quantization)?;
        let spacing = layout.spacing();
        let bad = |reason: String| Err(TerrainError::InvalidHeightfield { reason });
        if grid.spacing != spacing {
            return bad(format!(
                "the heightfield's spacing is {} grid units, the world's {spacing}",
                grid.spacing
            ));
        }
        if grid.corner[0] % spacing != 0 || grid.corner[2] % spacing != 0 {
            return bad(format!(
                "the heightfield's corner (grid x {}, z {}) is not on the world's lattice",
                grid.corner[0], grid.corner[2]
            ));
        }
        Ok(Self {
            origin: [grid.corner[0] / spacing, grid.corner[2] / spacing],
            samples: grid.samples,
            heights: grid.heights,
        })
    }
}

impl WorldSource for HeightArray {
    fn height(&self, i: i64, j: i64) -> i64 {
        let [nx, nz] = self.samples.map(i64::from);
        if nx == 0 || nz == 0 || self.heights.is_empty() {
            return 0;
        }
        let x = (i - self.origin[0]).clamp(0, nx - 1);
        let z = (j - self.origin[1]).clamp(0, nz - 1);
        self.heights
            .get(usize::try_from(x + z * nx).unwrap_or(0))
            .copied()
            .unwrap_or(0)
    }
}

/// How a world is cut into chunks, and what its solid is made of.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldLayout {
    /// The grid of every chunk (all chunks share it, so a tool rounds to
    /// the same grid tool in each).
    pub quantization: Quantization,
    /// The edge of a chunk's cube is `2^chunk_log2` grid units.
    pub chunk_log2: u8,
    /// Lattice samples are `2^spacing_log2` grid units apart (less than
    /// the chunk edge).
    pub spacing_log2: u8,
    /// Grid y of every chunk cube's bottom, and of the solid's flat bottom.
    /// Heights must lie above it and at most one chunk edge higher.
    pub floor: i64,
    /// The material below the bands.
    pub label: Label,
    /// Bands `(depth, label)` under the surface, in grid units, as
    /// [`GridHeightfield::layers`].
    pub layers: Vec<(i64, Label)>,
}

impl WorldLayout {
    /// Grid units between lattice samples.
    #[must_use]
    pub fn spacing(&self) -> i64 {
        1i64 << self.spacing_log2
    }

    /// The edge of a chunk, in grid units.
    #[must_use]
    pub fn chunk_edge(&self) -> i64 {
        1i64 << self.chunk_log2
    }

    /// The edge of a chunk, in world units.
    #[must_use]
    pub fn chunk_edge_world(&self) -> f64 {
        self.chunk_edge() as f64 * self.quantization.unit()
    }

    /// Checks the sizes.
    ///
    /// # Errors
    /// [`TerrainError::InvalidWorld`] naming the bad size.
    pub fn check(&self) -> Result<(), TerrainError> {
        let bad = |reason: String| Err(TerrainError::InvalidWorld { reason });
        if self.spacing_log2 >= self.chunk_log2 {
            return bad(format!(
                "the sample spacing 2^{} must be less than the chunk edge 2^{}",
                self.spacing_log2, self.chunk_log2
            ));
        }
        if self.chunk_log2 > 26 {
            return bad(format!(
                "the chunk edge 2^{} is more than the grid's 2^26",
                self.chunk_log2
            ));
        }
        if self.layers.iter().any(|&(depth, _)| depth <= 0) {
            return bad("every layer depth must be positive".into());
        }
        Ok(())
    }

    /// The chunk holding grid position `(x, z)` (chunks are half-open:
    /// `[cx·E, (cx+1)·E)`).
    #[must_use]
    pub fn chunk_at(&self, x: i64, z: i64) -> ChunkCoord {
        ChunkCoord {
            x: x.div_euclid(self.chunk_edge()),
            z: z.div_euclid(self.chunk_edge()),
        }
    }

    /// The lower corner of chunk `coord`'s cube, in grid units.
    #[must_use]
    pub fn chunk_origin(&self, coord: ChunkCoord) -> [i64; 3] {
        let edge = self.chunk_edge();
        [coord.x * edge, self.floor, coord.z * edge]
    }

    /// The base of chunk `coord`: the source's heightfield over the chunk,
    /// its walls on the cube's sides.
    ///
    /// # Errors
    /// [`TerrainError::InvalidWorld`] for a sample at or below the floor
    /// or above the cube's top; [`TerrainError::InvalidHeightfield`] as
    /// [`GridHeightfield`] checks.
    pub fn chunk_base(
        &self,
        source: &dyn WorldSource,
        coord: ChunkCoord,
    ) -> Result<TerrainBase, TerrainError> {
        self.check()?;
        let n = 1i64 << (self.chunk_log2 - self.spacing_log2);
        let (i0, j0) = (coord.x * n, coord.z * n);
        let top = self.floor + self.chunk_edge();
        let side = u32::try_from(n + 1).map_err(|_| TerrainError::InvalidWorld {
            reason: format!("{} samples per chunk side do not fit", n + 1),
        })?;
        let mut heights = Vec::with_capacity((side as usize) * (side as usize));
        for j in j0..=j0 + n {
            for i in i0..=i0 + n {
                let h = source.height(i, j);
                if h <= self.floor || h > top {
                    return Err(TerrainError::InvalidWorld {
                        reason: format!(
                            "the source's height {h} at sample ({i}, {j}) is not above the \
                             floor {} and at most the chunk top {top}",
                            self.floor
                        ),
                    });
                }
                heights.push(h);
            }
        }
        let origin = self.chunk_origin(coord);
        Ok(TerrainBase::Heightfield {
            origin,
            size_log2: self.chunk_log2,
            field: GridHeightfield {
                corner: origin,
                samples: [side, side],
                spacing: self.spacing(),
                heights,
                bottom: self.floor,
                label: self.label,
                layers: self.layers.clone(),
            },
        })
    }
}

/// A shared source, as the world and its chunk builds hold it.
pub type SharedSource = Arc<dyn WorldSource>;
