//! Debris across chunks: solid that an edit cut loose from its anchors
//! where the solid is split over several octrees side by side (the chunks
//! of a streamed world), found as one piece made of its parts in every
//! chunk, and taken out of each chunk exactly.
//!
//! Notation: a *chunk* is an octree with its [`Anchors`]
//! ([`ChunkOctree`]); chunks tile space with cubes of one edge, in grid
//! coordinates shared by all of them. A root side of a chunk is *shared*
//! when another chunk of the set has the same cube moved one edge across
//! it: its neighbour. A *part* is the share of a piece in one chunk.
//!
//! Each chunk alone cannot tell whether solid that reaches its side is
//! held: the solid may continue into the neighbour and rest on the ground
//! there, or the neighbour may hold nothing across it. So a chunk on its
//! own lists its sides as anchors (nothing is wrongly detached), and this
//! module joins the chunks into one graph: two solid cells in neighbouring
//! chunks are adjacent when a face of one on the shared side, clipped to
//! the walls of the leaves across it and down their BSPs, keeps a piece of
//! positive area in the other, exactly as cells across a wall inside one
//! octree ([`super::components`]); touching along an edge or at a point
//! (diagonal chunks) does not connect. A shared side never anchors, even
//! when the chunk's anchors list it; a side the anchors list with no
//! neighbour in the set (a chunk not loaded) anchors what touches it, so
//! nothing leans on solid it cannot see. Every other anchor (the bottom,
//! anchor boxes) holds as in one octree.
//!
//! The search is that of [`Octree::detach_unanchored`] over the joined
//! graph: from each seed (cells an edit changed, in any chunk) a
//! best-first search towards the anchors stops at the first anchored cell;
//! a search that runs out has found a whole unanchored component, across
//! as many chunks as it spans (two across a side, four around a corner).
//! Its cells in each chunk become that chunk's part ([`DebrisPiece`], an
//! octree over the chunk's cube), and are removed from the chunk. The
//! limits ([`DebrisLimits`]) count every piece of the call in every chunk
//! together: over them, nothing is removed from any chunk. Exact and
//! sequential: the same chunks and seeds give bit-identical results for
//! any thread count.
//!
//! ## Example
//!
//! ```
//! use chisel_bsp::octree::{
//!     Anchors, CellBox, CellKey, ChunkOctree, DebrisLimits, Edit, Octree, OctreeConfig, Tool,
//!     detach_across_chunks,
//! };
//!
//! // Two chunks of edge 2^10 side by side along x; a slab across their
//! // border rests on a pillar in the first one.
//! let cube = |min, max| CellBox { min, max };
//! let mut chunks: Vec<ChunkOctree> = [0, 1024]
//!     .into_iter()
//!     .map(|x| ChunkOctree {
//!         octree: Octree::new([x, 0, 0], 10, 0, OctreeConfig::default()).unwrap(),
//!         anchors: Anchors::default(),
//!     })
//!     .collect();
//! for chunk in &mut chunks {
//!     for b in [cube([900, 0, 100], [1000, 300, 200]), cube([900, 300, 100], [1100, 400, 200])] {
//!         if b.overlaps(&chunk.octree.root_box()) {
//!             chunk.octree.apply(&Tool::cuboid(b)?, Edit::Add(1))?;
//!         }
//!     }
//! }
//! // Cut the pillar through: the slab and what is left above the cut fall.
//! let cut = Tool::cuboid(cube([890, 100, 90], [1010, 150, 210]))?;
//! let changes = chunks[0].octree.apply(&cut, Edit::Subtract)?;
//! let near: Vec<(usize, CellKey)> = changes.changed.iter().map(|&k| (0, k)).collect();
//! let detached = detach_across_chunks(&mut chunks, &near, DebrisLimits::default())?;
//! assert_eq!(detached.pieces.len(), 1);
//! assert_eq!(detached.pieces[0].parts.len(), 2);
//! let volume = 100.0 * 150.0 * 100.0 + 200.0 * 100.0 * 100.0;
//! assert_eq!(detached.pieces[0].volume().to_f64(), volume);
//! # Ok::<(), chisel_bsp::Error>(())
//! ```

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

use rayon::prelude::*;

use super::apply::Changes;
use super::cell::{CellBox, CellKey};
use super::components::{Anchors, CubeSide, SolidCell, SolidGraph, reach_across};
use super::debris::{
    DebrisCell, DebrisConfig, DebrisPiece, check_limits, debris_cell, volumes_by_label,
};
use super::exact_volume::ExactVolume;
use super::relabel::{Relabel, relabel};
use super::tree::Octree;
use crate::Error;
use crate::tree::{Label, NodeId};
use crate::word_hash::WordSet;

/// One chunk of a world split into octrees side by side.
#[derive(Clone, Debug)]
pub struct ChunkOctree {
    /// Its solid, over its cube.
    pub octree: Octree,
    /// What holds it. A listed side of the cube anchors only where no
    /// chunk of the set lies across it (a neighbour not loaded).
    pub anchors: Anchors,
}

/// How much one [`detach_across_chunks`] may take out, all pieces in all
/// chunks together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DebrisLimits {
    /// The most debris volume, in cubic grid units; more gives
    /// [`Error::TooMuchDebris`].
    pub max_volume: Option<u128>,
    /// The most convex cells; more gives [`Error::TooMuchDebris`].
    pub max_cells: Option<usize>,
}

impl From<&DebrisConfig> for DebrisLimits {
    fn from(config: &DebrisConfig) -> Self {
        Self {
            max_volume: config.max_volume,
            max_cells: config.max_cells,
        }
    }
}

/// The share of a debris piece in one chunk.
#[derive(Clone, Debug)]
pub struct ChunkPart {
    /// The chunk's index in the slice given.
    pub chunk: usize,
    /// Its cells, taken out of that chunk, over that chunk's cube.
    pub piece: DebrisPiece,
}

/// A connected piece of solid that no anchor holds, over one or more
/// chunks.
#[derive(Clone, Debug)]
pub struct ChunkedPiece {
    /// Its parts, one per chunk it reaches, by chunk index.
    pub parts: Vec<ChunkPart>,
}

impl ChunkedPiece {
    /// Its exact volume per material, all parts together.
    #[must_use]
    pub fn volumes(&self) -> BTreeMap<Label, ExactVolume> {
        let mut by_label: BTreeMap<Label, Vec<ExactVolume>> = BTreeMap::new();
        for part in &self.parts {
            for (label, v) in &part.piece.volumes {
                by_label.entry(*label).or_default().push(v.clone());
            }
        }
        by_label
            .into_iter()
            .map(|(label, v)| (label, ExactVolume::sum_balanced(v)))
            .collect()
    }

    /// Its exact volume, all parts and materials together.
    #[must_use]
    pub fn volume(&self) -> ExactVolume {
        ExactVolume::sum_balanced(self.parts.iter().map(|p| p.piece.volume()).collect())
    }
}

/// What [`detach_across_chunks`] took out.
#[derive(Clone, Debug, Default)]
pub struct ChunkedDetached {
    /// The pieces, in the order of their first cells (chunk index, then
    /// leaf, then BSP node).
    pub pieces: Vec<ChunkedPiece>,
    /// Each chunk's changes by the call, by chunk index (empty for a
    /// chunk nothing was taken from).
    pub changes: Vec<Changes>,
    /// The open sides ([`detach_across_chunks_with_open_sides`]) that
    /// components held by open sides alone touch: the chunk and the
    /// side, sorted, each once. Empty from [`detach_across_chunks`].
    pub held_at_open_sides: Vec<(usize, CubeSide)>,
}

impl ChunkedDetached {
    /// The exact volume of all pieces together.
    #[must_use]
    pub fn volume(&self) -> ExactVolume {
        ExactVolume::sum_balanced(self.pieces.iter().map(ChunkedPiece::volume).collect())
    }
}

/// A solid cell of one chunk: the chunk's index and the cell.
type Node = (usize, SolidCell);

/// Finds every connected solid component across `chunks` that no anchor
/// holds and that has a cell in the leaves `near` (`(chunk, key)`: keys
/// of inner cells stand for the leaves below them, as in
/// [`Octree::detach_unanchored`]), takes each out of the chunks it spans
/// and hands it back as a [`ChunkedPiece`]. Pass the
/// [`Changes::changed`] of an edit in each chunk it touched. The volume
/// of all chunks before equals their volume after plus that of the
/// pieces, exactly. Deterministic for any thread count.
///
/// # Errors
/// [`Error::InvalidChunks`] when two chunks' cubes overlap or a seed
/// names no chunk; [`Error::TooMuchDebris`] when the debris is over
/// `limits`. The chunks are then unchanged.
pub fn detach_across_chunks(
    chunks: &mut [ChunkOctree],
    near: &[(usize, CellKey)],
    limits: DebrisLimits,
) -> Result<ChunkedDetached, Error> {
    detach_across_chunks_with_open_sides(chunks, near, limits, &[])
}

/// [`detach_across_chunks`], where a side in `open` that a chunk lists as
/// an anchor and that no chunk of the set lies across (an *open* side:
/// the chunk across is not loaded) does not stop a search from a seed:
/// it goes on towards the other anchors. A component that only open sides
/// hold stays, as with [`detach_across_chunks`], and the open sides it
/// touches are listed in [`ChunkedDetached::held_at_open_sides`]: load
/// the chunks across them and search again to know whether it falls.
/// The pieces taken out, and the chunks left, are those
/// [`detach_across_chunks`] gives: a component stays in both when any
/// anchor, open or not, holds it.
///
/// # Errors
/// As [`detach_across_chunks`].
pub fn detach_across_chunks_with_open_sides(
    chunks: &mut [ChunkOctree],
    near: &[(usize, CellKey)],
    limits: DebrisLimits,
    open: &[CubeSide],
) -> Result<ChunkedDetached, Error> {
    let neighbours = neighbours(chunks)?;
    if let Some(&(chunk, _)) = near.iter().find(|(c, _)| *c >= chunks.len()) {
        return Err(Error::InvalidChunks {
            reason: format!("a seed names chunk {chunk} of {}", chunks.len()),
        });
    }
    let (found, held_at_open_sides) = {
        // The anchors of each chunk without its shared sides, and its
        // open sides apart.
        let unshared = |chunk: &ChunkOctree, across: &[(CubeSide, usize)]| {
            (chunk.anchors.sides.iter())
                .filter(|s| !across.iter().any(|(t, _)| t == *s))
                .copied()
                .collect::<Vec<CubeSide>>()
        };
        let (anchors, opened): (Vec<Anchors>, Vec<Vec<CubeSide>>) = chunks
            .iter()
            .zip(&neighbours)
            .map(|(chunk, across)| {
                let (opened, sides) = unshared(chunk, across)
                    .into_iter()
                    .partition(|s| open.contains(s));
                let anchors = Anchors {
                    sides,
                    boxes: chunk.anchors.boxes.clone(),
                };
                (anchors, opened)
            })
            .unzip();
        let mut graphs: Vec<SolidGraph<'_>> = chunks
            .iter()
            .zip(&anchors)
            .zip(&neighbours)
            .zip(opened)
            .map(|(((chunk, anchors), across), opened)| {
                SolidGraph::new(&chunk.octree, anchors)
                    .passing(across.iter().map(|(side, _)| *side).collect())
                    .noting(opened)
            })
            .collect();
        let mut seeds: Vec<Node> = Vec::new();
        for &(chunk, key) in near {
            for leaf in chunks[chunk].octree.leaves_meeting(key) {
                let cells = graphs[chunk].solid_cells(leaf);
                seeds.extend(cells.into_iter().map(|cell| (chunk, cell)));
            }
        }
        seeds.sort_unstable();
        seeds.dedup();
        let octrees: Vec<&Octree> = chunks.iter().map(|c| &c.octree).collect();
        let mut held_at: Vec<(usize, CubeSide)> = Vec::new();
        let found = find_joined(
            &mut graphs,
            &octrees,
            &neighbours,
            &seeds,
            limits,
            &mut held_at,
        )?;
        held_at.sort_unstable_by_key(|&(chunk, side)| (chunk, side.axis, side.upper));
        held_at.dedup();
        (found, held_at)
    };
    let mut changes = vec![Changes::default(); chunks.len()];
    if found.is_empty() {
        return Ok(ChunkedDetached {
            pieces: Vec::new(),
            changes,
            held_at_open_sides,
        });
    }
    let pieces: Vec<ChunkedPiece> = found
        .into_par_iter()
        .map(|parts| ChunkedPiece {
            parts: parts
                .into_iter()
                .map(|(chunk, cells, volumes)| ChunkPart {
                    chunk,
                    piece: chunks[chunk].octree.piece(cells, volumes),
                })
                .collect(),
        })
        .collect();
    let mut removed: BTreeMap<usize, BTreeMap<CellKey, Vec<NodeId>>> = BTreeMap::new();
    for part in pieces.iter().flat_map(|p| &p.parts) {
        let cells = removed.entry(part.chunk).or_default();
        for cell in &part.piece.cells {
            cells.entry(cell.cell.key).or_default().push(cell.cell.node);
        }
    }
    for (chunk, mut cells) in removed {
        cells.values_mut().for_each(|nodes| nodes.sort_unstable());
        let octree = &mut chunks[chunk].octree;
        let (root, chunk_changes) = relabel(octree, &cells, Relabel::Remove);
        if let Some(root) = root {
            octree.root = root;
        }
        changes[chunk] = chunk_changes;
    }
    Ok(ChunkedDetached {
        pieces,
        changes,
        held_at_open_sides,
    })
}

/// For each chunk, its shared sides with the neighbour across each,
/// sorted by side.
///
/// # Errors
/// [`Error::InvalidChunks`] when two chunks' cubes overlap.
fn neighbours(chunks: &[ChunkOctree]) -> Result<Vec<Vec<(CubeSide, usize)>>, Error> {
    let boxes: Vec<CellBox> = chunks.iter().map(|c| c.octree.root_box()).collect();
    let mut by_corner: BTreeMap<[i64; 3], usize> = BTreeMap::new();
    for (i, b) in boxes.iter().enumerate() {
        if let Some(j) = (0..i).find(|&j| boxes[j].overlaps(b)) {
            return Err(Error::InvalidChunks {
                reason: format!("the cubes of chunks {j} and {i} overlap"),
            });
        }
        by_corner.insert(b.min, i);
    }
    Ok(boxes
        .iter()
        .map(|b| {
            let edge = b.max[0] - b.min[0];
            let mut out = Vec::new();
            for axis in 0..3 {
                for upper in [false, true] {
                    let mut corner = b.min;
                    corner[axis] += if upper { edge } else { -edge };
                    let Some(&j) = by_corner.get(&corner) else {
                        continue;
                    };
                    if boxes[j].max[axis] - boxes[j].min[axis] == edge {
                        out.push((CubeSide { axis, upper }, j));
                    }
                }
            }
            out.sort_unstable_by_key(|(side, _)| (side.axis, side.upper));
            out
        })
        .collect())
}

/// One unanchored component as its part in each chunk: the chunk, its
/// cells there (sorted) and their volume per material; parts by chunk.
type Joined = Vec<(usize, Vec<DebrisCell>, BTreeMap<Label, ExactVolume>)>;

/// The unanchored components of the joined graph with a cell among
/// `seeds` (sorted), in the order of their first cells. A component that
/// no anchor holds but that touches open sides (the graphs' noted sides)
/// is held; those sides go to `held_at`.
///
/// # Errors
/// [`Error::TooMuchDebris`] as soon as the debris found is over `limits`.
fn find_joined(
    graphs: &mut [SolidGraph<'_>],
    octrees: &[&Octree],
    neighbours: &[Vec<(CubeSide, usize)>],
    seeds: &[Node],
    limits: DebrisLimits,
    held_at: &mut Vec<(usize, CubeSide)>,
) -> Result<Vec<Joined>, Error> {
    let mut anchored: WordSet<Node> = WordSet::default();
    let mut debris: WordSet<Node> = WordSet::default();
    let mut out = Vec::new();
    let (mut total_cells, mut total_volume) = (0usize, ExactVolume::zero());
    let (mut next, mut joined) = (Vec::new(), Vec::new());
    for &seed in seeds {
        if anchored.contains(&seed) || debris.contains(&seed) {
            continue;
        }
        let mut reached: WordSet<Node> = WordSet::default();
        reached.insert(seed);
        let mut order = vec![seed];
        let gap = |graphs: &[SolidGraph<'_>], (chunk, cell): Node| graphs[chunk].gap(cell.key);
        let mut heap = BinaryHeap::from([Reverse((gap(graphs, seed), seed))]);
        let mut held = false;
        let mut open_sides: Vec<(usize, CubeSide)> = Vec::new();
        while let Some(Reverse((_, (chunk, cell)))) = heap.pop() {
            next.clear();
            joined.clear();
            // The neighbours of an anchored cell are anchored too: they
            // join the search before it stops.
            held = graphs[chunk].expand(cell, &mut next);
            open_sides.extend(graphs[chunk].touched.iter().map(|&side| (chunk, side)));
            joined.extend(next.iter().map(|&n| (chunk, n)));
            let box_of_leaf = octrees[chunk].cell_box(cell.key);
            for (side, face) in std::mem::take(&mut graphs[chunk].border) {
                let Some(&(_, other)) = neighbours[chunk].iter().find(|(s, _)| *s == side) else {
                    continue;
                };
                let keys = octrees[other].leaves_across(&box_of_leaf, side.axis, side.upper);
                reach_across(
                    octrees[other],
                    &keys,
                    &box_of_leaf,
                    side.axis,
                    &face,
                    &mut |n| joined.push((other, n)),
                );
            }
            for &n in &joined {
                held |= anchored.contains(&n);
                if reached.insert(n) {
                    order.push(n);
                    heap.push(Reverse((gap(graphs, n), n)));
                }
            }
            if held {
                break;
            }
        }
        if held || !open_sides.is_empty() {
            if !held {
                held_at.extend(open_sides);
            }
            anchored.extend(order);
            continue;
        }
        order.sort_unstable();
        order.dedup();
        total_cells += order.len();
        let too_many = limits.max_cells.is_some_and(|m| total_cells > m);
        let mut parts: Joined = Vec::new();
        if !too_many {
            for &(chunk, cell) in &order {
                let Some(cell) = debris_cell(&mut graphs[chunk], cell) else {
                    continue;
                };
                if parts.last().is_none_or(|p| p.0 != chunk) {
                    parts.push((chunk, Vec::new(), BTreeMap::new()));
                }
                if let Some(part) = parts.last_mut() {
                    part.1.push(cell);
                }
            }
        }
        for (_, cells, volumes) in &mut parts {
            *volumes = volumes_by_label(cells);
            for v in volumes.values() {
                total_volume += v;
            }
        }
        check_limits(limits, too_many, total_cells, &total_volume)?;
        debris.extend(order.iter().copied());
        out.push(parts);
    }
    Ok(out)
}
