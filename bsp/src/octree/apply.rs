//! Applying a tool to an octree (paper 1 §3.8).
//!
//! Notation: `C` — a cell's box; `T` — the tool, `bounds(T)` its integer
//! box; `f` — the label function of the edit ([`BooleanOp`]).
//!
//! The walk descends only into cells whose closed box the closed tool
//! meets ([`Tool::touches`]: `bounds(T)` first, then exactly); children run
//! in parallel. At a leaf, `T` is first restricted to `C` (its splits whose
//! planes cut `C`; the merge finds the same tree with it). When that leaves
//! one region, `C` lies outside `T` or inside it — inside, where the edit
//! maps every label of the leaf to empty, the leaf becomes empty without a
//! cut. Otherwise an exact test (the tool's convex pieces against `C` by
//! separating axes, [`Tool::shares_volume`]; where a piece is off the
//! integer grid, a corner of `C` strictly inside `T`, else cutting `C` by
//! the tool's planes) decides whether `T` has volume in `C`;
//! if so, a convex `T` with many faces is cut down to the planes of the
//! facets of `T ∩ C` (`tool/facets.rs`: the same regions in `C`, far fewer
//! planes for a many-faced tool crossing a small cell), and the leaf's BSP
//! is merged
//! with `T` inside `C` (§3.5), rebuilt
//! without redundancy (§3.7) and, when still over the budget, split into
//! eight children rebuilt from the pieces of its boundary faces inside
//! each child box (`leaf.rs`, `split.rs`); a rebuild stops as soon as it is over the
//! budget, and is not started where the faces lie in more distinct planes
//! than the budget allows splits. After the
//! children of an inner cell changed, eight leaf children that fit the
//! budget together are combined:
//! their BSPs are grafted under the axis planes (Fig. 8, combine A) and
//! rebuilt inside the cell (combine B). Every step is exact and every
//! result a pure function of its inputs, so the octree is bit-identical
//! for any thread count.

use std::sync::Arc;

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::leaf::{
    CellFaces, build_leaf_faces, cell_poly, combine, may_split, split_leaf, split_limit,
    splits_certainly,
};
use super::tool::{Tool, facet_chain, restricted, solid_at_a_corner};
use super::tree::{Leaf, OctNode, Octree, OctreeConfig, collect_leaves};
use crate::Error;
use crate::convex::{ConvexArena, CutOutcome, KeptOutcome, NO_TAG, Part, PolyId, with_arena};
use crate::tree::boundary::Bounds;
use crate::tree::{BooleanOp, Bsp, EMPTY, Label, Node, NodeId};

/// What an edit does where the tool is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Edit {
    /// Remove all material inside the tool.
    Subtract,
    /// Fill the tool's empty space with this material (existing material
    /// stays).
    Add(Label),
    /// Repaint the material inside the tool with this one.
    Paint(Label),
    /// Keep only the material inside the tool.
    Intersect,
}

impl Edit {
    fn op(self) -> BooleanOp {
        match self {
            Edit::Subtract => BooleanOp::Difference,
            Edit::Add(_) => BooleanOp::Union,
            Edit::Paint(label) => BooleanOp::Paint(label),
            Edit::Intersect => BooleanOp::Intersection,
        }
    }

    fn tool_label(self) -> Label {
        match self {
            Edit::Add(label) => label,
            _ => 1,
        }
    }
}

/// The cells an edit touched.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Changes {
    /// Leaf cells of the new octree whose surface may differ: their content
    /// was replaced, or they hold material and the closed tool meets their
    /// closed box (faces on their border may have been exposed or covered:
    /// the regions across them changed only inside the tool). A leaf not
    /// listed has the same surface ([`Octree::cell_surface`]) as before the
    /// edit. Sorted.
    pub changed: Vec<CellKey>,
    /// Leaf cells of the previous octree that are no longer leaves (split
    /// or combined). Sorted.
    pub removed: Vec<CellKey>,
}

impl Changes {
    fn leaf(key: CellKey) -> Self {
        Self {
            changed: vec![key],
            removed: Vec::new(),
        }
    }

    fn append(&mut self, other: Changes) {
        self.changed.extend(other.changed);
        self.removed.extend(other.removed);
    }
}

/// The changes below a node, with the faces of the replaced leaves there.
#[derive(Default)]
struct Edited {
    changes: Changes,
    faces: CellFaces,
}

impl From<Changes> for Edited {
    fn from(changes: Changes) -> Self {
        Self {
            changes,
            faces: Vec::new(),
        }
    }
}

impl Edited {
    fn append(&mut self, other: Edited) {
        self.changes.append(other.changes);
        self.faces.extend(other.faces);
    }
}

/// The edit, prepared once for the whole walk.
struct Walk<'a> {
    /// The tool, for the exact contact test with cell boxes.
    solid: &'a Tool,
    /// The tool's solid labelled for the edit.
    tool: Bsp,
    /// The label of the tool's solid.
    tool_label: Label,
    bounds: CellBox,
    op: BooleanOp,
    /// Whether `f(l, EMPTY) ≠ l` for some label, so that cells the tool
    /// misses change too (intersection empties them).
    changes_outside: bool,
    config: &'a OctreeConfig,
    /// Whether to hand back the faces of replaced leaves.
    keep_faces: bool,
}

impl Octree {
    /// Applies `edit` with `tool`, touching only the cells the tool can
    /// reach (all cells for [`Edit::Intersect`], which empties the rest).
    /// Cells run in parallel; the result does not depend on the thread
    /// count. Keep a clone of the octree first to undo (cloning is cheap).
    ///
    /// # Errors
    /// [`Error::InvalidEdit`] for adding or painting the empty label; the
    /// octree is then unchanged.
    pub fn apply(&mut self, tool: &Tool, edit: Edit) -> Result<Changes, Error> {
        self.edit(tool, edit, false).map(|edited| edited.changes)
    }

    /// [`Octree::apply`], also handing back, for each leaf whose content
    /// the edit rebuilt (a key in [`Changes::changed`]: an edited leaf, a
    /// new child of a leaf split over the budget, or a leaf combined from
    /// children that were not all one uniform label), the boundary faces
    /// the rebuild extracted there: its surface
    /// inside the cell, with the faces on the cell's box marked
    /// [`crate::tree::BoundaryFace::on_bounds`] (for the children of a split leaf, the
    /// pieces of the leaf's faces: on a wall between two of them only
    /// where a face of the leaf lies, the material elsewhere being the
    /// same on both sides). [`Octree::cell_surface_from`] finishes
    /// them into what [`Octree::cell_surface`] would give — the same exact
    /// surface, possibly in different pieces — without cutting the cell's
    /// BSP again. Sorted by key; deterministic for any thread count.
    ///
    /// # Errors
    /// As [`Octree::apply`].
    pub fn apply_with_faces(
        &mut self,
        tool: &Tool,
        edit: Edit,
    ) -> Result<(Changes, CellFaces), Error> {
        self.edit(tool, edit, true)
            .map(|edited| (edited.changes, edited.faces))
    }

    fn edit(&mut self, tool: &Tool, edit: Edit, keep_faces: bool) -> Result<Edited, Error> {
        if matches!(edit, Edit::Add(EMPTY) | Edit::Paint(EMPTY)) {
            return Err(Error::InvalidEdit {
                reason: "adding or painting needs a non-empty material label",
            });
        }
        let op = edit.op();
        let walk = Walk {
            solid: tool,
            tool: tool.labelled(edit.tool_label()),
            tool_label: edit.tool_label(),
            bounds: tool.bounds(),
            op,
            changes_outside: (0..=Label::MAX).any(|l| op.apply(l, EMPTY) != l),
            config: self.config(),
            keep_faces,
        };
        let root_box = self.root_box();
        let (root, mut edited) = walk.node(&self.root, CellKey::ROOT, root_box);
        if let Some(root) = root {
            self.root = root;
        }
        edited.changes.changed.sort_unstable();
        edited.changes.removed.sort_unstable();
        edited.faces.sort_unstable_by_key(|(key, _)| *key);
        Ok(edited)
    }
}

impl Walk<'_> {
    /// The new node (`None` when unchanged) and the changes below it.
    fn node(&self, node: &OctNode, key: CellKey, cell: CellBox) -> (Option<OctNode>, Edited) {
        // Where the closed tool misses the closed box, it has no volume in
        // any cell below, and no border face there changes.
        let touches = self.solid.touches(&cell);
        if !self.changes_outside && !touches {
            return (None, Edited::default());
        }
        match node {
            OctNode::Leaf(leaf) => self.leaf(leaf, key, cell, touches),
            OctNode::Inner(children) => {
                let results: Vec<(Option<OctNode>, Edited)> = (0..8)
                    .into_par_iter()
                    .map(|i| self.node(&children[i], key.child(i), cell.child(i)))
                    .collect();
                if results.iter().all(|(n, _)| n.is_none()) {
                    let mut changes = Edited::default();
                    results.into_iter().for_each(|(_, c)| changes.append(c));
                    return (None, changes);
                }
                let mut changes = Edited::default();
                let mut new_children = children.as_ref().clone();
                for (i, (n, c)) in results.into_iter().enumerate() {
                    if let Some(n) = n {
                        new_children[i] = n;
                    }
                    changes.append(c);
                }
                if let Some((combined, faces)) =
                    combine(&new_children, cell, self.config, self.keep_faces)
                {
                    let mut removed = Vec::new();
                    collect_leaves(node, key, &mut removed);
                    // The children's faces are dropped with them; the
                    // combined leaf has those of its rebuild.
                    let changes = Changes {
                        changed: vec![key],
                        removed,
                    };
                    let faces = faces.map(|f| vec![(key, f)]).unwrap_or_default();
                    return (Some(OctNode::Leaf(combined)), Edited { changes, faces });
                }
                (Some(OctNode::Inner(Arc::new(new_children))), changes)
            }
        }
    }

    /// The new leaf (`None` when unchanged) and the changes; `touches`
    /// tells whether the closed tool meets the closed `cell`.
    fn leaf(
        &self,
        leaf: &Leaf,
        key: CellKey,
        cell: CellBox,
        touches: bool,
    ) -> (Option<OctNode>, Edited) {
        // With its content unchanged, a leaf's surface can change only where
        // the regions across its border faces changed: inside the closed
        // tool. An empty uniform leaf has no surface at all.
        let surface_may_change = touches && !matches!(leaf, Leaf::Uniform(EMPTY));
        let touched = || {
            if surface_may_change {
                Changes::leaf(key)
            } else {
                Changes::default()
            }
        };
        if let Leaf::Uniform(label) = *leaf {
            // Carving empty space, adding where the cell is full, …: the
            // edit maps this label to itself inside and outside the tool.
            if self.op.apply(label, self.tool_label) == label
                && self.op.apply(label, EMPTY) == label
            {
                return (None, touched().into());
            }
        }
        // The tool restricted to the cell: the merge gives the same tree
        // with it, and when it is one region the cell lies in that region.
        let tool = (touches && cell.overlaps(&self.bounds)).then(|| restricted(&self.tool, &cell));
        let meets = tool.as_ref().is_some_and(|tool| match tool.nodes() {
            [Node::Leaf(l)] => *l != EMPTY,
            // For a BSP leaf, an exact test first spares the merge and the
            // rebuild where the tool misses the cell; for a uniform leaf
            // the merge itself is that test.
            _ => {
                matches!(leaf, Leaf::Uniform(_))
                    // From the tool's convex pieces without a cut; the
                    // cuts decide where a piece is off the integer grid.
                    || self.solid.shares_volume(&cell).unwrap_or_else(|| {
                        solid_at_a_corner(tool, &cell)
                            || with_arena(|arena| {
                                let poly = cell_poly(arena, cell);
                                tool_meets(tool, arena, poly)
                            })
                    })
            }
        });
        if !meets {
            // The tool has no volume here: only labels outside it change.
            let relabeled = if self.changes_outside {
                relabel_outside(leaf, self.op)
            } else {
                None
            };
            let changes = if surface_may_change || relabeled.is_some() {
                Changes::leaf(key)
            } else {
                Changes::default()
            };
            return (relabeled.map(OctNode::Leaf), changes.into());
        }
        let tool = tool.expect("the tool meets the cell");
        // A many-faced convex tool keeps only the planes of its facets in
        // the cell. Not in a uniform leaf: the merge cuts its one region by
        // the tool's planes once, as the pruning would.
        let tool = match leaf {
            Leaf::Bsp(_) if self.tool.planes().len() >= FACET_MIN_TOOL_PLANES => {
                with_arena(|arena| {
                    let poly = cell_poly(arena, cell);
                    facet_chain(&tool, arena, poly)
                })
                .unwrap_or(tool)
            }
            _ => tool,
        };
        // A tool with many planes across the cell (a hull of thousands of
        // points) is not merged into it whole: each cell of that merge
        // would hold up to as many faces, on a stack as deep, so memory
        // would grow with the square of the planes. The leaf is split
        // first and the edit applied to its children, each crossed by
        // fewer of the planes.
        if tool.nodes().len() / 2 > presplit_planes(self.config)
            && may_split(key, cell, self.config)
        {
            return self.presplit(leaf, key, cell);
        }
        // The whole cell inside the tool, every label mapped to empty
        // there: what the merge and the rebuild would find, without a cut.
        if let [Node::Leaf(t)] = tool.nodes()
            && leaf_labels(leaf).all(|l| self.op.apply(l, *t) == EMPTY)
        {
            let faces = if self.keep_faces {
                vec![(key, Vec::new())]
            } else {
                Vec::new()
            };
            let edited = Edited {
                changes: Changes::leaf(key),
                faces,
            };
            return (Some(OctNode::Leaf(Leaf::Uniform(EMPTY))), edited);
        }
        // The faces are kept also when not handed back: a leaf over the
        // budget is split from them. Only what is handed back needs the
        // faces on the cell's box: the children are rebuilt from the
        // inner pieces.
        let on_bounds = if self.keep_faces {
            Bounds::Keep
        } else {
            Bounds::Skip
        };
        let merged = with_arena(|arena| {
            let poly = cell_poly(arena, cell);
            let uniform;
            let bsp = match leaf {
                Leaf::Bsp(bsp) => bsp.as_ref(),
                Leaf::Uniform(label) => {
                    uniform = Bsp::uniform(*label);
                    &uniform
                }
            };
            bsp.merge_boundary(&tool, self.op, arena, poly, on_bounds)
        });
        // Over the budget, the leaf is split without finishing its rebuild
        // (nor starting it where the faces' planes show it): the merged
        // tree labels the children without surface.
        let rebuilt = if splits_certainly(&merged.faces, key, cell, self.config) {
            Err(merged)
        } else {
            merged.rebuilt_within(split_limit(key, cell, self.config))
        };
        let (simplified, faces) = match rebuilt {
            Ok(rebuilt) => rebuilt,
            Err(merged) => {
                let (node, leaves, faces) = split_leaf(
                    &merged.merged,
                    merged.faces,
                    key,
                    cell,
                    self.config,
                    self.keep_faces,
                );
                let changes = Changes {
                    changed: leaves,
                    removed: vec![key],
                };
                return (Some(node), Edited { changes, faces });
            }
        };
        if let (Leaf::Uniform(label), [crate::tree::Node::Leaf(new)]) = (leaf, simplified.nodes())
            && label == new
        {
            return (None, touched().into());
        }
        let (node, leaves, faces) = build_leaf_faces(
            simplified,
            Some(faces),
            key,
            cell,
            self.config,
            self.keep_faces,
        );
        let removed = match node {
            OctNode::Leaf(_) => Vec::new(),
            OctNode::Inner(_) => vec![key],
        };
        let changes = Changes {
            changed: leaves,
            removed,
        };
        (Some(node), Edited { changes, faces })
    }
}

impl Walk<'_> {
    /// The edit applied to `leaf` split into its eight children first (the
    /// same regions: a uniform leaf's label in each child, a BSP leaf's
    /// children rebuilt from its boundary), then combined again where the
    /// children fit the budget. The changes name the leaves of the result
    /// and `key` as removed when the result is split.
    fn presplit(&self, leaf: &Leaf, key: CellKey, cell: CellBox) -> (Option<OctNode>, Edited) {
        let split = match leaf {
            Leaf::Uniform(label) => OctNode::Inner(Arc::new(std::array::from_fn(|_| {
                OctNode::Leaf(Leaf::Uniform(*label))
            }))),
            Leaf::Bsp(bsp) => {
                let faces = with_arena(|arena| {
                    let poly = cell_poly(arena, cell);
                    bsp.boundary(arena, poly)
                });
                split_leaf(bsp, faces, key, cell, self.config, false).0
            }
        };
        let (node, mut edited) = self.node(&split, key, cell);
        let node = node.unwrap_or(split);
        let mut changed = Vec::new();
        collect_leaves(&node, key, &mut changed);
        let removed = match node {
            OctNode::Leaf(_) => Vec::new(),
            OctNode::Inner(_) => vec![key],
        };
        edited.changes = Changes { changed, removed };
        (Some(node), edited)
    }
}

/// The most planes of a tool restricted to a cell that is merged into the
/// cell whole; a cell crossed by more, and which may split, is split first
/// ([`Walk::presplit`]). At least the budget, so that ordinary tools (a
/// few dozen planes) are never split for.
fn presplit_planes(config: &OctreeConfig) -> usize {
    config.max_bsp_nodes.max(PRESPLIT_MIN_PLANES)
}

/// The least value of [`presplit_planes`].
const PRESPLIT_MIN_PLANES: usize = 64;

/// The least planes of a tool that is cut down to its facets in each cell
/// ([`facet_chain`]) before the merge. The long faces of a many-faced
/// swept cutter cross many cells with their planes, which the pruning
/// drops (`cutter`, 108 planes: 4.7% fewer instructions); the planes of a
/// small tool (`crater_job`, 36-faced hulls) mostly carry facets of each
/// cell's part, and cutting the box by them cost 2.9% more instructions
/// than the merge saved.
const FACET_MIN_TOOL_PLANES: usize = 64;

/// Whether `tool`'s solid has volume in `cell` (a polyhedron of
/// `arena`, cut up in place): whether [`Bsp::cells`] of the tool there
/// has a non-empty cell, found with the same cuts but stopping at the
/// first such cell, and building only the part of a cut whose other
/// side is an empty leaf.
fn tool_meets(tool: &Bsp, arena: &mut ConvexArena, cell: PolyId) -> bool {
    let nodes = tool.nodes();
    let mut stack = vec![(0 as NodeId, cell)];
    while let Some((n, poly)) = stack.pop() {
        let (plane, below, above) = match nodes[n as usize] {
            Node::Leaf(label) if label != EMPTY => return true,
            Node::Leaf(_) => continue,
            Node::Split {
                plane,
                below,
                above,
            } => (plane, below, above),
        };
        let s = &tool.planes()[plane as usize];
        let empty = |n: NodeId| nodes[n as usize] == Node::Leaf(EMPTY);
        let keep = match (empty(below), empty(above)) {
            (true, true) => continue,
            (false, true) => Some((Part::Below, below)),
            (true, false) => Some((Part::Above, above)),
            (false, false) => None,
        };
        if let Some((part, child)) = keep {
            match arena.cut_keeping(poly, s, part, NO_TAG) {
                KeptOutcome::Cut(kept) => stack.push((child, kept)),
                KeptOutcome::Below => stack.extend((part == Part::Below).then_some((below, poly))),
                KeptOutcome::Above => stack.extend((part == Part::Above).then_some((above, poly))),
            }
        } else {
            match arena.cut(poly, s, NO_TAG, NO_TAG) {
                CutOutcome::Split { below: b, above: a } => {
                    stack.push((above, a));
                    stack.push((below, b));
                }
                CutOutcome::Below => stack.push((below, poly)),
                CutOutcome::Above => stack.push((above, poly)),
            }
        }
    }
    false
}

/// The labels of the leaf's regions (with repeats).
fn leaf_labels(leaf: &Leaf) -> impl Iterator<Item = Label> + '_ {
    let (uniform, nodes) = match leaf {
        Leaf::Uniform(label) => (Some(*label), &[][..]),
        Leaf::Bsp(bsp) => (None, bsp.nodes()),
    };
    uniform
        .into_iter()
        .chain(nodes.iter().filter_map(|n| match n {
            Node::Leaf(l) => Some(*l),
            Node::Split { .. } => None,
        }))
}

/// The leaf with every label `l` replaced by `f(l, EMPTY)`, or `None` when
/// that changes nothing.
fn relabel_outside(leaf: &Leaf, op: BooleanOp) -> Option<Leaf> {
    match leaf {
        Leaf::Uniform(l) => {
            let new = op.apply(*l, EMPTY);
            (new != *l).then_some(Leaf::Uniform(new))
        }
        Leaf::Bsp(bsp) => {
            let relabeled = bsp.relabeled(|l| op.apply(l, EMPTY));
            if relabeled.nodes() == bsp.nodes() {
                None
            } else if relabeled.nodes().iter().all(|n| {
                matches!(n, crate::tree::Node::Split { .. }) || *n == crate::tree::Node::Leaf(EMPTY)
            }) {
                Some(Leaf::Uniform(EMPTY))
            } else {
                Some(Leaf::Bsp(Arc::new(relabeled)))
            }
        }
    }
}
