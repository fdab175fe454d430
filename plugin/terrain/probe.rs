//! Point queries: which material is at a point of a terrain or a world
//! (footstep sounds, spawning, AI, resource probes), exactly.
//!
//! The point is rounded to the terrain's grid first, as a carve's corners
//! are ([`Quantization::to_grid`]: each coordinate to the nearest multiple
//! of the unit from the grid origin, halves away from zero); that is the
//! only rounding. The rounded point is then looked up in the octree and
//! its cells' BSPs with the kernel's integer arithmetic
//! ([`chisel_bsp::exact::Plane::eval`]), so the answer is the terrain's
//! own, not a mesh's.
//!
//! Grid points often lie exactly on a face: a heightfield's surface passes
//! through its samples, and every carve's corners are grid points. A point
//! on a face, an edge or a corner between regions reports the greatest
//! label among the regions that touch it: material over air
//! ([`EMPTY`], 0), and between two materials (a layer boundary, a painted
//! patch) the greater label. So a probe at a surface reports the ground,
//! whatever the orientation of the planes or cells there.
//!
//! [`EMPTY`]: chisel_bsp::tree::EMPTY

use bevy::prelude::*;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{CellKey, Leaf, Octree};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::{Bsp, Label, Node};

use super::component::Terrain;
use super::error::TerrainError;
use super::world::{ChunkCoord, TerrainWorld};

impl Terrain {
    /// The material at `point` in the terrain's local frame (the frame of
    /// [`Terrain::ray_cast`]; for a world's chunk, the world's), rounded to
    /// the grid ([module docs](self)): `Some(label)` inside the terrain's
    /// cube, `Some(`[`EMPTY`](chisel_bsp::tree::EMPTY)`)` for air there
    /// (a crater), `None` outside the cube (its faces count as inside). A
    /// point on a face between regions reports the greatest label touching
    /// it: material over air.
    ///
    /// # Errors
    /// [`TerrainError::Kernel`] for a non-finite coordinate, or one that
    /// rounds beyond the grid's range.
    pub fn material_at(&self, point: Vec3) -> Result<Option<Label>, TerrainError> {
        let grid = to_grid(&self.quantization, point)?;
        Ok(self.material_at_grid(grid))
    }

    /// The material at grid point `p` (see [`Terrain::material_at`]).
    fn material_at_grid(&self, p: IntPoint) -> Option<Label> {
        let octree = &self.octree;
        let coords = p.coords();
        let root = octree.root_box();
        if (0..3).any(|a| coords[a] < root.min[a] || coords[a] > root.max[a]) {
            return None;
        }
        let mut best = None;
        cells_at(octree, CellKey::ROOT, p, &mut best);
        best
    }
}

impl TerrainWorld {
    /// The material at `point` in the world's frame (the world entity's
    /// local space, the frame of [`WorldCarve`](super::WorldCarve) tools),
    /// rounded to the grid, as [`Terrain::material_at`] answers in the
    /// chunk that holds it; `terrain_of` gives a live chunk's
    /// [`Terrain`] from its entity (`|e| terrains.get(e).ok()` with a
    /// `Query<&Terrain>`). `None` below the floor or above the chunks'
    /// cubes, whose material no carve can change. A point on a border
    /// between chunks asks each of them and reports the greatest label,
    /// as on a face within a chunk.
    ///
    /// Only live chunks are asked: a chunk streamed out, being built or
    /// never built is not read from its stored bytes or from the source
    /// (an unedited chunk's material is its octree's, built from the
    /// source's heightfield with its layers: not cheaper than building
    /// the chunk).
    ///
    /// # Errors
    /// [`TerrainError::Kernel`] for a non-finite or out-of-range point;
    /// [`TerrainError::ChunkNotLoaded`] naming a chunk that holds the
    /// point and is not live (or whose terrain `terrain_of` does not
    /// give).
    pub fn material_at<'a>(
        &self,
        point: Vec3,
        terrain_of: impl Fn(Entity) -> Option<&'a Terrain>,
    ) -> Result<Option<Label>, TerrainError> {
        let layout = self.layout();
        let p = to_grid(&layout.quantization, point)?;
        let [x, y, z] = p.coords();
        let edge = layout.chunk_edge();
        if y < layout.floor || y > layout.floor + edge {
            return Ok(None);
        }
        // The chunks whose closed squares hold (x, z): two on a border,
        // four at a corner.
        let span = |v: i64| {
            let c = v.div_euclid(edge);
            if v.rem_euclid(edge) == 0 {
                c - 1..=c
            } else {
                c..=c
            }
        };
        let mut best = None;
        for cx in span(x) {
            for cz in span(z) {
                let coord = ChunkCoord { x: cx, z: cz };
                let terrain = (self.chunk_entity(coord)).and_then(&terrain_of).ok_or(
                    TerrainError::ChunkNotLoaded {
                        chunk: [coord.x, coord.z],
                    },
                )?;
                best = best.max(terrain.material_at_grid(p));
            }
        }
        Ok(best)
    }
}

/// `point` rounded to `quantization`'s grid.
fn to_grid(quantization: &Quantization, point: Vec3) -> Result<IntPoint, TerrainError> {
    Ok(quantization.to_grid(point.as_dvec3().to_array())?)
}

/// Notes in `best` the greatest label of the regions of cell `key` (and
/// the cells below it) whose closures hold `p`.
fn cells_at(octree: &Octree, key: CellKey, p: IntPoint, best: &mut Option<Label>) {
    let cell = octree.cell_box(key);
    let c = p.coords();
    if (0..3).any(|a| c[a] < cell.min[a] || c[a] > cell.max[a]) {
        return;
    }
    match octree.leaf(key) {
        Some(Leaf::Uniform(label)) => *best = (*best).max(Some(*label)),
        Some(Leaf::Bsp(bsp)) => regions_at(bsp, 0, p, best),
        None => (0..8).for_each(|i| cells_at(octree, key.child(i), p, best)),
    }
}

/// Notes in `best` the greatest label of the regions below BSP node
/// `node` whose closures hold `p`: both sides of a plane through it.
fn regions_at(bsp: &Bsp, node: u32, p: IntPoint, best: &mut Option<Label>) {
    match bsp.nodes().get(node as usize) {
        Some(Node::Leaf(label)) => *best = (*best).max(Some(*label)),
        Some(&Node::Split {
            plane,
            below,
            above,
        }) => {
            let Some(plane) = bsp.planes().get(plane as usize) else {
                return;
            };
            let side = plane.eval(p);
            if side <= 0 {
                regions_at(bsp, below, p, best);
            }
            if side >= 0 {
                regions_at(bsp, above, p, best);
            }
        }
        None => {}
    }
}
