//! Debris: solid that an edit cut loose from its anchors, found by a local
//! search and taken out of the octree exactly (paper 1 §3.4 across the
//! cells of §3.8).
//!
//! Notation: *seeds* — the solid cells of the leaves an edit changed;
//! *gap* — a lower bound on a leaf's distance to the nearest anchor
//! ([`Anchors`]); a component is that of [`super::components`].
//!
//! A component an edit cut loose lost a face of positive area where it
//! touched the removed material, so its surface changed there and a leaf
//! holding it is listed in the edit's [`Changes::changed`]: the seeds reach
//! every such component. From each seed not yet classified, a best-first
//! search (smallest gap first; a uniform leaf is one cell however large)
//! stops at the first cell that touches an anchor or was proven anchored
//! before: all it reached is anchored. A search that runs out has reached
//! a whole component with no anchor: debris. Debris is taken out by
//! relabelling its cells empty (`relabel.rs`); each piece becomes an
//! octree of its own over the same cube, built the same way. The search is
//! sequential and every step exact, so results are bit-identical for any
//! thread count.
//!
//! ## Example
//!
//! ```
//! use chisel_bsp::octree::{CellBox, DebrisConfig, Edit, Octree, OctreeConfig, Tool};
//!
//! // A pillar standing on the bottom (y = 0) with a block on top.
//! let cube = |min, max| CellBox { min, max };
//! let pillar = cube([100, 0, 100], [200, 300, 200]);
//! let mut octree = Octree::from_box([0; 3], 10, pillar, 1, OctreeConfig::default())?;
//! octree.apply(&Tool::cuboid(cube([50, 300, 50], [250, 400, 250]))?, Edit::Add(2))?;
//! // Cut the pillar through: everything above the cut falls.
//! let cut = Tool::cuboid(cube([90, 100, 90], [210, 150, 210]))?;
//! let carved = octree.apply_detaching(&cut, Edit::Subtract, &DebrisConfig::default())?;
//! let piece = &carved.detached.pieces[0];
//! assert_eq!(piece.volume().to_f64(), (100.0 * 150.0 * 100.0) + (200.0 * 100.0 * 200.0));
//! assert_eq!(octree.exact_solid_volume().to_f64(), 100.0 * 100.0 * 100.0);
//! assert!(!piece.solid.surface().is_empty());
//! # Ok::<(), chisel_bsp::Error>(())
//! ```

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

use rayon::prelude::*;

use super::apply::{Changes, Edit};
use super::cell::{CellBox, CellKey};
use super::chunk_debris::DebrisLimits;
use super::components::{Anchors, SolidCell, SolidGraph};
use super::exact_volume::ExactVolume;
use super::relabel::{Relabel, relabel};
use super::tool::Tool;
use super::tree::{Leaf, OctNode, Octree};
use crate::Error;
use crate::exact::Plane;
use crate::tree::{EMPTY, Label, NodeId};
use crate::word_hash::WordSet;

/// What holds terrain in place, and how much one call may detach.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DebrisConfig {
    /// The anchors (default: the bottom of the cube, `y = min`).
    pub anchors: Anchors,
    /// The most debris volume, in cubic grid units, one call may detach
    /// (all pieces together); more gives [`Error::TooMuchDebris`].
    pub max_volume: Option<u128>,
    /// The most convex cells one call may detach (all pieces together);
    /// more gives [`Error::TooMuchDebris`].
    pub max_cells: Option<usize>,
}

/// One convex cell of a debris piece: together they are an exact convex
/// decomposition of the piece (for compound convex colliders).
#[derive(Clone, Debug)]
pub struct DebrisCell {
    /// Where it was in the terrain.
    pub cell: SolidCell,
    /// Its material.
    pub label: Label,
    /// Its face planes, outward: the cell is exactly where every plane is
    /// `≤ 0`.
    pub planes: Vec<Plane>,
    /// Its corners in grid units (rounded from the exact vertices).
    pub vertices: Vec<[f64; 3]>,
    /// Its exact volume.
    pub volume: ExactVolume,
}

/// A connected piece of solid that no anchor holds, taken out of the
/// terrain.
#[derive(Clone, Debug)]
pub struct DebrisPiece {
    /// The piece alone, over the terrain's cube and with its config: mesh
    /// it with [`Octree::surface`] or [`Octree::cell_surface`].
    pub solid: Octree,
    /// Its convex cells, sorted by [`DebrisCell::cell`].
    pub cells: Vec<DebrisCell>,
    /// Its exact volume per material.
    pub volumes: BTreeMap<Label, ExactVolume>,
    /// The terrain leaves (before the call) that held part of it, sorted.
    pub leaves: Vec<CellKey>,
    /// An integer box containing it.
    pub bounds: CellBox,
}

impl DebrisPiece {
    /// Its exact volume, all materials together.
    #[must_use]
    pub fn volume(&self) -> ExactVolume {
        ExactVolume::sum_balanced(self.volumes.values().cloned().collect())
    }
}

/// What [`Octree::detach_unanchored`] took out.
#[derive(Clone, Debug, Default)]
pub struct Detached {
    /// The pieces, in the order of their first cells.
    pub pieces: Vec<DebrisPiece>,
    /// The terrain's changes by the call (re-mesh `changed`, drop
    /// `removed`).
    pub changes: Changes,
}

impl Detached {
    /// The exact volume of all pieces together.
    #[must_use]
    pub fn volume(&self) -> ExactVolume {
        ExactVolume::sum_balanced(self.pieces.iter().map(DebrisPiece::volume).collect())
    }
}

/// An edit followed by the detach of the debris it made.
#[derive(Clone, Debug, Default)]
pub struct Carved {
    /// The terrain's changes by both, against the octree before the edit.
    pub changes: Changes,
    /// The debris taken out.
    pub detached: Detached,
}

impl Changes {
    /// The changes of `self` followed by `later` (changes of the octree
    /// `self` left), against the octree before `self`: `changed` lists the
    /// leaves of the final octree either step changed, `removed` the leaves
    /// of the first octree that are no longer leaves. A leaf `later`
    /// removed was a leaf before `self` unless `self` made it, which it did
    /// exactly when `self` removed an ancestor or a descendant of it.
    #[must_use]
    pub fn then(&self, later: &Changes) -> Changes {
        let later_removed: WordSet<CellKey> = later.removed.iter().copied().collect();
        let later_changed: WordSet<CellKey> = later.changed.iter().copied().collect();
        let first_removed: WordSet<CellKey> = self.removed.iter().copied().collect();
        let related = |key: CellKey| {
            let mut k = key;
            while let Some(parent) = k.parent() {
                if first_removed.contains(&parent) {
                    return true;
                }
                k = parent;
            }
            self.removed
                .iter()
                .any(|r| r.depth > key.depth && ancestor_at(*r, key.depth) == key)
        };
        let first_changed: WordSet<CellKey> = self.changed.iter().copied().collect();
        let mut changed: Vec<CellKey> = self
            .changed
            .iter()
            .filter(|k| !later_removed.contains(k))
            .chain(&later.changed)
            .copied()
            .collect();
        let mut removed: Vec<CellKey> = self
            .removed
            .iter()
            .filter(|k| !later_changed.contains(k))
            .chain(
                later
                    .removed
                    .iter()
                    .filter(|k| !first_changed.contains(k) || !related(**k)),
            )
            .copied()
            .collect();
        changed.sort_unstable();
        changed.dedup();
        removed.sort_unstable();
        removed.dedup();
        Changes { changed, removed }
    }
}

/// The ancestor of `key` at `depth` (≤ its own).
fn ancestor_at(key: CellKey, depth: u8) -> CellKey {
    let shift = key.depth - depth;
    CellKey {
        depth,
        pos: key.pos.map(|p| p >> shift),
    }
}

impl Octree {
    /// Finds every connected solid component that no anchor holds and
    /// that has a cell in the leaves `near` (keys of inner cells stand for
    /// the leaves below them, keys below a leaf for that leaf), takes each
    /// out of the octree and hands it back as a [`DebrisPiece`]. Pass the
    /// [`Changes::changed`] of an edit to find all debris the edit made
    /// ([`Octree::detach_after`]). The rest of the terrain keeps exactly
    /// its regions; the volume before equals the volume after plus that of
    /// the pieces, exactly. Deterministic for any thread count.
    ///
    /// # Errors
    /// [`Error::TooMuchDebris`] when the debris is over a limit of
    /// `config`; the octree is then unchanged.
    pub fn detach_unanchored(
        &mut self,
        near: &[CellKey],
        config: &DebrisConfig,
    ) -> Result<Detached, Error> {
        let found = {
            let mut graph = SolidGraph::new(self, &config.anchors);
            let mut seeds: Vec<SolidCell> = Vec::new();
            for &key in near {
                for leaf in self.leaves_meeting(key) {
                    seeds.extend(graph.solid_cells(leaf));
                }
            }
            seeds.sort_unstable();
            seeds.dedup();
            find_debris(&mut graph, &seeds, config)?
        };
        if found.is_empty() {
            return Ok(Detached::default());
        }
        let mut all: BTreeMap<CellKey, Vec<NodeId>> = BTreeMap::new();
        for cell in found.iter().flat_map(|(cells, _)| cells) {
            all.entry(cell.cell.key).or_default().push(cell.cell.node);
        }
        // Pieces share leaves: their cells there come in piece order.
        all.values_mut().for_each(|nodes| nodes.sort_unstable());
        let pieces: Vec<DebrisPiece> = found
            .into_par_iter()
            .map(|(cells, volumes)| self.piece(cells, volumes))
            .collect();
        let (root, changes) = relabel(self, &all, Relabel::Remove);
        if let Some(root) = root {
            self.root = root;
        }
        Ok(Detached { pieces, changes })
    }

    /// [`Octree::detach_unanchored`] near the leaves an edit changed,
    /// with the edit's `carve` changes folded in ([`Changes::then`]): the
    /// call a background job makes after [`Octree::apply`].
    ///
    /// # Errors
    /// As [`Octree::detach_unanchored`]; the octree is then unchanged.
    pub fn detach_after(
        &mut self,
        carve: &Changes,
        config: &DebrisConfig,
    ) -> Result<Carved, Error> {
        let detached = self.detach_unanchored(&carve.changed, config)?;
        Ok(Carved {
            changes: carve.then(&detached.changes),
            detached,
        })
    }

    /// [`Octree::apply`] followed by [`Octree::detach_after`], as one
    /// step: when either fails (too much debris), the octree is unchanged.
    ///
    /// # Errors
    /// As [`Octree::apply`] and [`Octree::detach_unanchored`].
    pub fn apply_detaching(
        &mut self,
        tool: &Tool,
        edit: Edit,
        config: &DebrisConfig,
    ) -> Result<Carved, Error> {
        let before = self.root.clone();
        let carve = self.apply(tool, edit)?;
        self.detach_after(&carve, config).inspect_err(|_| {
            self.root = before;
        })
    }

    /// The leaves of this octree that meet the cell `key`: the leaf at
    /// `key`, the one holding it, or the leaves below it.
    pub(super) fn leaves_meeting(&self, key: CellKey) -> Vec<CellKey> {
        let mut node = &self.root;
        let mut at = CellKey::ROOT;
        while at.depth < key.depth {
            let OctNode::Inner(children) = node else {
                return vec![at];
            };
            let child = ancestor_at(key, at.depth + 1);
            let i = (0..3).fold(0, |i, a| i | ((child.pos[a] & 1) as usize) << a);
            node = &children[i];
            at = child;
        }
        let mut out = Vec::new();
        super::tree::collect_leaves(node, at, &mut out);
        out
    }

    /// The piece of these cells as an octree of its own.
    pub(super) fn piece(
        &self,
        cells: Vec<DebrisCell>,
        volumes: BTreeMap<Label, ExactVolume>,
    ) -> DebrisPiece {
        let mut chosen: BTreeMap<CellKey, Vec<NodeId>> = BTreeMap::new();
        for cell in &cells {
            chosen
                .entry(cell.cell.key)
                .or_default()
                .push(cell.cell.node);
        }
        let mut solid = self.clone();
        if let (Some(root), _) = relabel(self, &chosen, Relabel::Keep) {
            solid.root = root;
        }
        let mut bounds: Option<CellBox> = None;
        for cell in &cells {
            let leaf = self.cell_box(cell.cell.key);
            let own = CellBox::enclosing(cell.vertices.iter().map(|v| {
                [0, 1, 2].map(|a| (v[a].floor() as i64 - 1).clamp(leaf.min[a], leaf.max[a]))
            }))
            .zip(CellBox::enclosing(cell.vertices.iter().map(|v| {
                [0, 1, 2].map(|a| (v[a].ceil() as i64 + 1).clamp(leaf.min[a], leaf.max[a]))
            })))
            .map_or(leaf, |(lo, hi)| CellBox {
                min: lo.min,
                max: hi.max,
            });
            bounds = Some(match bounds {
                None => own,
                Some(b) => CellBox {
                    min: [0, 1, 2].map(|a| b.min[a].min(own.min[a])),
                    max: [0, 1, 2].map(|a| b.max[a].max(own.max[a])),
                },
            });
        }
        let leaves = chosen.keys().copied().collect();
        DebrisPiece {
            solid,
            cells,
            volumes,
            leaves,
            bounds: bounds.unwrap_or_else(|| self.root_box()),
        }
    }
}

/// The cells of one unanchored component (sorted) and its volume per
/// material.
type Found = (Vec<DebrisCell>, BTreeMap<Label, ExactVolume>);

/// The unanchored components with a cell among `seeds` (sorted), each as
/// its cells (sorted) and its volume per material, in the order of their
/// first cells.
///
/// # Errors
/// [`Error::TooMuchDebris`] as soon as the debris found is over a limit.
fn find_debris(
    graph: &mut SolidGraph<'_>,
    seeds: &[SolidCell],
    config: &DebrisConfig,
) -> Result<Vec<Found>, Error> {
    let mut anchored: WordSet<SolidCell> = WordSet::default();
    let mut debris: WordSet<SolidCell> = WordSet::default();
    let mut out = Vec::new();
    let (mut total_cells, mut total_volume) = (0usize, ExactVolume::zero());
    let mut next = Vec::new();
    for &seed in seeds {
        if anchored.contains(&seed) || debris.contains(&seed) {
            continue;
        }
        let mut reached: WordSet<SolidCell> = WordSet::default();
        reached.insert(seed);
        let mut order = vec![seed];
        let mut heap = BinaryHeap::from([Reverse((graph.gap(seed.key), seed))]);
        let mut held = false;
        while let Some(Reverse((_, cell))) = heap.pop() {
            next.clear();
            // The neighbours of an anchored cell are anchored too: they
            // join the search before it stops.
            held = graph.expand(cell, &mut next);
            for &n in &next {
                held |= anchored.contains(&n);
                if reached.insert(n) {
                    order.push(n);
                    heap.push(Reverse((graph.gap(n.key), n)));
                }
            }
            if held {
                break;
            }
        }
        if held {
            anchored.extend(order);
            continue;
        }
        order.sort_unstable();
        total_cells += order.len();
        let too_many = config.max_cells.is_some_and(|m| total_cells > m);
        let cells: Vec<DebrisCell> = if too_many {
            Vec::new()
        } else {
            order
                .iter()
                .filter_map(|&c| debris_cell(graph, c))
                .collect()
        };
        let volumes = volumes_by_label(&cells);
        for v in volumes.values() {
            total_volume += v;
        }
        check_limits(config.into(), too_many, total_cells, &total_volume)?;
        debris.extend(order.iter().copied());
        out.push((cells, volumes));
    }
    Ok(out)
}

/// The exact volume per material of `cells`.
pub(super) fn volumes_by_label(cells: &[DebrisCell]) -> BTreeMap<Label, ExactVolume> {
    let mut by_label: BTreeMap<Label, Vec<ExactVolume>> = BTreeMap::new();
    for cell in cells {
        by_label
            .entry(cell.label)
            .or_default()
            .push(cell.volume.clone());
    }
    by_label
        .into_iter()
        .map(|(l, v)| (l, ExactVolume::sum_balanced(v)))
        .collect()
}

/// [`Error::TooMuchDebris`] when the debris found so far, `cells` convex
/// cells (`too_many`: over `limits` already) of `volume`, is over `limits`.
pub(super) fn check_limits(
    limits: DebrisLimits,
    too_many: bool,
    cells: usize,
    volume: &ExactVolume,
) -> Result<(), Error> {
    if too_many || limits.max_volume.is_some_and(|m| volume.exceeds(m)) {
        return Err(Error::TooMuchDebris {
            cells,
            volume: volume.to_f64(),
            max_cells: limits.max_cells,
            max_volume: limits.max_volume,
        });
    }
    Ok(())
}

/// The convex cell `cell` with its planes, corners and exact volume.
pub(super) fn debris_cell(graph: &mut SolidGraph<'_>, cell: SolidCell) -> Option<DebrisCell> {
    let cells = graph.leaf_cells(cell.key)?;
    let (label, poly) = cells.find(cell.node)?;
    let arena = &cells.arena;
    let planes = arena
        .faces_of(poly)
        .into_iter()
        .map(|f| *arena.face_plane(f))
        .collect();
    let vertices = arena
        .vertices_of(poly)
        .into_iter()
        .map(|v| arena.position(v))
        .collect();
    debug_assert!(label != EMPTY);
    debug_assert!(!matches!(cells.leaf, Leaf::Uniform(EMPTY)));
    Some(DebrisCell {
        cell,
        label,
        planes,
        vertices,
        volume: cells.volume(poly),
    })
}
