//! The persistent octree of BSPs.
//!
//! Inner cells share their children through [`Arc`]s, so cloning an
//! octree is cheap and an edit copies only the path to the cells it
//! changes: keeping the previous octree is an undo step.

use std::sync::Arc;

use super::cell::{CellBox, CellKey};
use crate::Error;
use crate::convex::ConvexArena;
use crate::exact::budget::MAX_COORD;
use crate::exact::{IntPoint, Plane};
use crate::tree::{Bsp, EMPTY, Label, Node};

/// How the octree trades cell count against BSP size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OctreeConfig {
    /// A leaf whose BSP has more inner nodes than this is split into eight;
    /// eight leaf children whose combined BSP fits are merged. The paper
    /// finds 100–200 best (§4.5) and the default is 150; carving many small
    /// tools runs faster here with 20–40 (BENCHMARKS.md, "Octree budget").
    pub max_bsp_nodes: usize,
    /// No cell is split below this depth (or below an edge of 2 units),
    /// whatever its BSP size.
    pub max_depth: u8,
}

impl OctreeConfig {
    /// The smallest [`OctreeConfig::max_bsp_nodes`] an octree file may
    /// store: smaller budgets split cells down to the depth limit, with
    /// memory far beyond what the solid needs.
    pub const MIN_BSP_NODES: usize = 8;
}

impl Default for OctreeConfig {
    fn default() -> Self {
        Self {
            max_bsp_nodes: 150,
            max_depth: 20,
        }
    }
}

/// What a leaf cell holds.
#[derive(Clone, Debug)]
pub enum Leaf {
    /// One label everywhere in the cell.
    Uniform(Label),
    /// A BSP, meaningful inside the cell's box only.
    Bsp(Arc<Bsp>),
}

impl Leaf {
    /// Inner BSP nodes (0 for a uniform leaf).
    #[must_use]
    pub fn bsp_nodes(&self) -> usize {
        match self {
            Leaf::Uniform(_) => 0,
            Leaf::Bsp(bsp) => bsp.nodes().len() / 2,
        }
    }

    /// The leaf as a BSP.
    #[must_use]
    pub fn to_bsp(&self) -> Bsp {
        match self {
            Leaf::Uniform(label) => Bsp::uniform(*label),
            Leaf::Bsp(bsp) => Bsp::clone(bsp),
        }
    }

    /// Whether the two leaves are the same stored value (not merely equal):
    /// an unchanged cell keeps its leaf across edits.
    #[must_use]
    pub fn same_as(&self, other: &Leaf) -> bool {
        match (self, other) {
            (Leaf::Uniform(a), Leaf::Uniform(b)) => a == b,
            (Leaf::Bsp(a), Leaf::Bsp(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }
}

/// An octree node: a leaf or eight shared children.
#[derive(Clone, Debug)]
pub(crate) enum OctNode {
    Leaf(Leaf),
    Inner(Arc<[OctNode; 8]>),
}

/// Sizes of an octree, for reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OctreeStats {
    /// Leaf cells.
    pub leaves: usize,
    /// Leaf cells holding a BSP (the others are uniform).
    pub bsp_leaves: usize,
    /// Inner BSP nodes over all leaves.
    pub bsp_nodes: usize,
    /// Planes over all leaf palettes.
    pub planes: usize,
    /// Deepest leaf.
    pub depth: u8,
    /// Bytes held by the BSPs (nodes and planes).
    pub bsp_bytes: usize,
}

/// A persistent octree of BSPs over the cube `[origin, origin + 2^size_log2]³`.
#[derive(Clone, Debug)]
pub struct Octree {
    origin: [i64; 3],
    size_log2: u8,
    config: OctreeConfig,
    pub(crate) root: OctNode,
}

impl Octree {
    /// The cube at `origin` with edge `2^size_log2`, filled with `fill`.
    ///
    /// # Errors
    /// [`Error::OctreeSize`] when the edge is not between 2 and 2^27 or the
    /// cube leaves the exact coordinate range ±2^26.
    pub fn new(
        origin: [i64; 3],
        size_log2: u8,
        fill: Label,
        config: OctreeConfig,
    ) -> Result<Self, Error> {
        if !(1..=27).contains(&size_log2)
            || origin
                .iter()
                .any(|&o| o < -MAX_COORD || o > MAX_COORD - (1i64 << size_log2))
        {
            return Err(Error::OctreeSize { origin, size_log2 });
        }
        Ok(Self {
            origin,
            size_log2,
            config,
            root: OctNode::Leaf(Leaf::Uniform(fill)),
        })
    }

    /// The cube with the box `solid` filled with `label` (clipped to the
    /// cube) and empty elsewhere.
    ///
    /// # Errors
    /// As [`Octree::new`], or an empty or out-of-range `solid`.
    pub fn from_box(
        origin: [i64; 3],
        size_log2: u8,
        solid: CellBox,
        label: Label,
        config: OctreeConfig,
    ) -> Result<Self, Error> {
        let mut arena = ConvexArena::new();
        let poly = solid.add_to(&mut arena)?;
        Self::from_bsp(
            origin,
            size_log2,
            &Bsp::from_convex(&arena, poly, label),
            config,
        )
    }

    /// An octree from its leaves (a saved file, a network message),
    /// checked: the cells must tile the cube exactly — every inner cell has
    /// all eight children, no leaf lies inside another, none lies outside.
    ///
    /// # Errors
    /// As [`Octree::new`], or [`Error::InvalidOctree`] naming the defect.
    pub fn from_leaves(
        origin: [i64; 3],
        size_log2: u8,
        config: OctreeConfig,
        leaves: impl IntoIterator<Item = (CellKey, Leaf)>,
    ) -> Result<Self, Error> {
        let mut octree = Self::new(origin, size_log2, EMPTY, config)?;
        let mut pending: std::collections::HashMap<CellKey, Leaf> =
            std::collections::HashMap::new();
        for (key, leaf) in leaves {
            let edge = 1u64 << (size_log2 - key.depth.min(size_log2));
            if key.depth > size_log2
                || key
                    .pos
                    .iter()
                    .any(|&p| (u64::from(p) + 1) * edge > 1u64 << size_log2)
            {
                return Err(Error::InvalidOctree {
                    reason: "a leaf lies outside the cube",
                });
            }
            if pending.insert(key, leaf).is_some() {
                return Err(Error::InvalidOctree {
                    reason: "a leaf is given twice",
                });
            }
        }
        let total = pending.len();
        let mut used = 0;
        octree.root = assemble(CellKey::ROOT, size_log2, &mut pending, &mut used)?;
        if used != total {
            return Err(Error::InvalidOctree {
                reason: "a leaf lies inside another leaf",
            });
        }
        Ok(octree)
    }

    /// Lower corner of the root cube.
    #[must_use]
    pub fn origin(&self) -> [i64; 3] {
        self.origin
    }

    /// The root cube's edge is `2^size_log2`.
    #[must_use]
    pub fn size_log2(&self) -> u8 {
        self.size_log2
    }

    /// The splitting and combining parameters.
    #[must_use]
    pub fn config(&self) -> &OctreeConfig {
        &self.config
    }

    /// The root cube.
    #[must_use]
    pub fn root_box(&self) -> CellBox {
        self.cell_box(CellKey::ROOT)
    }

    /// The box of any cell key (whether or not the cell exists).
    #[must_use]
    pub fn cell_box(&self, key: CellKey) -> CellBox {
        let edge = 1i64 << (self.size_log2 - key.depth.min(self.size_log2));
        let min = [0, 1, 2].map(|a| self.origin[a] + key.pos[a] as i64 * edge);
        CellBox {
            min,
            max: min.map(|m| m + edge),
        }
    }

    /// Every leaf cell with its content, depth first, children in order.
    #[must_use]
    pub fn leaves(&self) -> Vec<(CellKey, &Leaf)> {
        let mut out = Vec::new();
        let mut stack = vec![(CellKey::ROOT, &self.root)];
        while let Some((key, node)) = stack.pop() {
            match node {
                OctNode::Leaf(leaf) => out.push((key, leaf)),
                OctNode::Inner(children) => {
                    for i in (0..8).rev() {
                        stack.push((key.child(i), &children[i]));
                    }
                }
            }
        }
        out
    }

    /// The leaf at `key`, if that cell is a leaf.
    #[must_use]
    pub fn leaf(&self, key: CellKey) -> Option<&Leaf> {
        let mut node = &self.root;
        for d in 1..=key.depth {
            let OctNode::Inner(children) = node else {
                return None;
            };
            let shift = key.depth - d;
            let i = (0..3).fold(0, |i, a| i | (((key.pos[a] >> shift) & 1) as usize) << a);
            node = &children[i];
        }
        match node {
            OctNode::Leaf(leaf) => Some(leaf),
            OctNode::Inner(_) => None,
        }
    }

    /// Sizes, for reports.
    #[must_use]
    pub fn stats(&self) -> OctreeStats {
        let mut stats = OctreeStats::default();
        for (key, leaf) in self.leaves() {
            stats.leaves += 1;
            stats.depth = stats.depth.max(key.depth);
            if let Leaf::Bsp(bsp) = leaf {
                stats.bsp_leaves += 1;
                stats.bsp_nodes += leaf.bsp_nodes();
                stats.planes += bsp.planes().len();
                stats.bsp_bytes +=
                    std::mem::size_of_val(bsp.nodes()) + std::mem::size_of_val(bsp.planes());
            }
        }
        stats
    }

    /// The label at an integer point strictly inside a cell (points on a
    /// BSP plane or a cell border report the side above / the upper cell).
    ///
    /// # Errors
    /// Out-of-range coordinates.
    pub fn label_at(&self, point: [i64; 3]) -> Result<Option<Label>, Error> {
        let p = IntPoint::from_array(point)?;
        let root = self.root_box();
        if (0..3).any(|a| point[a] < root.min[a] || point[a] > root.max[a]) {
            return Ok(None);
        }
        let mut node = &self.root;
        let mut cell = root;
        loop {
            match node {
                OctNode::Inner(children) => {
                    let mid = cell.mid();
                    let i = (0..3).fold(0, |i, a| i | usize::from(point[a] >= mid[a]) << a);
                    node = &children[i];
                    cell = cell.child(i);
                }
                OctNode::Leaf(Leaf::Uniform(label)) => return Ok(Some(*label)),
                OctNode::Leaf(Leaf::Bsp(bsp)) => {
                    let mut n = 0;
                    loop {
                        match bsp.nodes()[n as usize] {
                            Node::Leaf(label) => return Ok(Some(label)),
                            Node::Split {
                                plane,
                                below,
                                above,
                            } => {
                                let s: &Plane = &bsp.planes()[plane as usize];
                                n = if s.eval(p) < 0 { below } else { above };
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The node at `key` from the pending leaves: the leaf itself, or eight
/// children assembled the same way.
fn assemble(
    key: CellKey,
    size_log2: u8,
    pending: &mut std::collections::HashMap<CellKey, Leaf>,
    used: &mut usize,
) -> Result<OctNode, Error> {
    if let Some(leaf) = pending.remove(&key) {
        *used += 1;
        return Ok(OctNode::Leaf(leaf));
    }
    if key.depth >= size_log2 || pending.is_empty() {
        return Err(Error::InvalidOctree {
            reason: "the leaves leave part of the cube uncovered",
        });
    }
    let mut children = Vec::with_capacity(8);
    for i in 0..8 {
        children.push(assemble(key.child(i), size_log2, pending, used)?);
    }
    let children: [OctNode; 8] = children
        .try_into()
        .unwrap_or_else(|_| unreachable!("eight children"));
    Ok(OctNode::Inner(Arc::new(children)))
}

/// Appends the key of every leaf under `node` (at `key`) to `out`.
pub(crate) fn collect_leaves(node: &OctNode, key: CellKey, out: &mut Vec<CellKey>) {
    match node {
        OctNode::Leaf(_) => out.push(key),
        OctNode::Inner(children) => {
            for (i, child) in children.iter().enumerate() {
                collect_leaves(child, key.child(i), out);
            }
        }
    }
}
