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

/// One octave of [`ValueNoise`]: random heights `0..amplitude` on a
/// lattice every `cell` samples, interpolated bilinearly between them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoiseOctave {
    /// Samples between the octave's lattice points (at least 1; smaller
    /// values count as 1).
    pub cell: i64,
    /// Heights are `0..amplitude` grid units (at least 1; smaller values
    /// count as 1).
    pub amplitude: i64,
    /// Chooses the random values.
    pub seed: u64,
}

/// A noise-function source: `base` plus the sum of the octaves, each
/// integer value noise (a hash of the lattice point, interpolated
/// bilinearly with integer arithmetic and rounded down), so every sample
/// is exact and the same on every machine.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValueNoise {
    /// Grid height added to every sample.
    pub base: i64,
    /// The octaves, summed.
    pub octaves: Vec<NoiseOctave>,
}

impl ValueNoise {
    /// The lowest and highest heights the noise can give:
    /// `base ..= base + Σ (amplitude - 1)`.
    #[must_use]
    pub fn range(&self) -> (i64, i64) {
        let spread: i64 = self.octaves.iter().map(|o| o.amplitude.max(1) - 1).sum();
        (self.base, self.base + spread)
    }
}

/// A well-mixed 64-bit hash of a lattice point (SplitMix64's finaliser).
fn lattice_hash(i: i64, j: i64, seed: u64) -> u64 {
    let mut z = (i as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F))
        .wrapping_add(seed);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl WorldSource for ValueNoise {
    fn height(&self, i: i64, j: i64) -> i64 {
        let mut h = i128::from(self.base);
        for octave in &self.octaves {
            let (cell, amplitude) = (octave.cell.max(1), octave.amplitude.max(1));
            let (ci, cj) = (i.div_euclid(cell), j.div_euclid(cell));
            let (fi, fj) = (
                i128::from(i.rem_euclid(cell)),
                i128::from(j.rem_euclid(cell)),
            );
            let c = i128::from(cell);
            let v = |a: i64, b: i64| {
                i128::from(lattice_hash(a, b, octave.seed) % amplitude.unsigned_abs())
            };
            let near = v(ci, cj) * (c - fi) + v(ci.wrapping_add(1), cj) * fi;
            let far = v(ci, cj.wrapping_add(1)) * (c - fi)
                + v(ci.wrapping_add(1), cj.wrapping_add(1)) * fi;
            h += (near * (c - fj) + far * fj).div_euclid(c * c);
        }
        i64::try_from(h).unwrap_or(if h < 0 { i64::MIN } else { i64::MAX })
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
