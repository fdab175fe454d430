//! Octree import from a closed triangle mesh (paper 1 §3.9).
//!
//! Notation: a *piece* is a convex polygon in plane-based form, a triangle
//! clipped exactly to a cell; a *free* cell is a leaf that no piece
//! reaches; `c + ε·a + ε²·b + ε³·e` — a point pushed off `c` by
//! infinitesimal steps along the axes `a`, `b`, `e` (symbolic
//! perturbation).
//!
//! 1. The mesh is checked: every directed edge must be used as often as
//!    its opposite (closed and consistently oriented; edges shared by four
//!    faces, as between voxels touching along an edge, are fine), every
//!    corner inside the cube.
//! 2. A triangle octree: cells with more pieces than the node budget are
//!    split, pieces clipped exactly to the children by the axis planes. A
//!    piece lying in a splitting plane goes to both sides — each side learns
//!    its label from it.
//! 3. Every cell with pieces gets the BSP of its pieces (§3.6), rebuilt
//!    without redundancy inside the cell and split while over the budget.
//! 4. Flood fill: a free cell has one label (no surface crosses it). It is
//!    read off a neighbour across one of its faces: at the face centre `c`,
//!    pushed into the neighbour along the face normal and then along the
//!    two in-face axes, the neighbour's BSP (or uniform label, or the empty
//!    outside of the cube) gives the label there. No surface separates that
//!    point from the free cell: a surface crossing the face would enter the
//!    free cell, and one lying in the face would have been given to it.
//!    Free cells whose neighbours are all free wait for the next round.

use std::collections::HashSet;
use std::sync::Arc;

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::leaf::build_leaf;
use super::mesh_check::check_mesh;
use super::tree::{Leaf, OctNode, Octree, OctreeConfig};
use crate::Error;
use crate::convex::ConvexArena;
use crate::exact::{IntPoint, Plane, Sign, classify_vertex};
use crate::tree::polygon::Polygon;
use crate::tree::{Bsp, EMPTY, Label};

/// Seed of the face order in imported cells.
const IMPORT_SEED: u64 = 0x1A90_27ED_0C7E_0001;

impl Octree {
    /// The solid bounded by a closed triangle mesh (counter-clockwise from
    /// outside), labelled `label`, in the cube at `origin` with edge
    /// `2^size_log2`. Triangles with a repeated corner are ignored.
    ///
    /// # Errors
    /// [`Error::OctreeSize`] for a bad cube, [`Error::OutsideOctree`] for a
    /// corner outside it, [`Error::NotWatertight`] for an open or
    /// inconsistently oriented mesh, [`Error::SelfIntersecting`] for
    /// triangles crossing each other.
    pub fn from_triangles(
        origin: [i64; 3],
        size_log2: u8,
        triangles: &[[IntPoint; 3]],
        label: Label,
        config: OctreeConfig,
    ) -> Result<Octree, Error> {
        let mut octree = Octree::new(origin, size_log2, EMPTY, config)?;
        let root = octree.root_box();
        check_mesh(triangles, &root)?;
        let mut pieces = Vec::with_capacity(triangles.len());
        for t in triangles {
            if let Some(p) = Polygon::triangle(*t)? {
                pieces.push((p, label, EMPTY));
            }
        }
        let (node, free) = build_cell(pieces, CellKey::ROOT, root, &config);
        octree.root = node;
        octree.fill_free_cells(free);
        octree.root = merge_uniform(octree.root.clone());
        Ok(octree)
    }

    /// Labels the free cells by flood fill (see the module notes).
    pub(super) fn fill_free_cells(&mut self, free: Vec<CellKey>) {
        let mut pending: HashSet<CellKey> = free.into_iter().collect();
        while !pending.is_empty() {
            let mut keys: Vec<CellKey> = pending.iter().copied().collect();
            keys.sort_unstable();
            let mut progress = false;
            for key in keys {
                if let Some(label) = self.label_across_faces(key, &pending) {
                    self.set_leaf(key, Leaf::Uniform(label));
                    pending.remove(&key);
                    progress = true;
                }
            }
            if !progress {
                // Unreachable for a cube with a boundary: its outside is
                // known. Label the rest empty rather than loop.
                for key in pending.drain() {
                    self.set_leaf(key, Leaf::Uniform(EMPTY));
                }
            }
        }
    }

    /// The label of free cell `key`, read across the first of its faces
    /// whose neighbour is known.
    fn label_across_faces(&self, key: CellKey, pending: &HashSet<CellKey>) -> Option<Label> {
        let cell = self.cell_box(key);
        let root = self.root_box();
        let mid = cell.mid();
        for axis in 0..3 {
            for outward in [-1i64, 1] {
                let mut c = mid;
                c[axis] = if outward < 0 {
                    cell.min[axis]
                } else {
                    cell.max[axis]
                };
                if c[axis] == root.min[axis] && outward < 0
                    || c[axis] == root.max[axis] && outward > 0
                {
                    return Some(EMPTY);
                }
                let (b, e) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut dir = [0i64; 3];
                dir[axis] = outward;
                dir[b] = 1;
                dir[e] = 1;
                let order = [axis, b, e];
                let (neighbour, leaf) = self.locate(c, dir)?;
                if pending.contains(&neighbour) {
                    continue;
                }
                return Some(match leaf {
                    Leaf::Uniform(l) => *l,
                    Leaf::Bsp(bsp) => bsp.label_near(c.map(|x| 2 * i128::from(x)), dir, order),
                });
            }
        }
        None
    }

    /// The leaf containing `c + ε·dir` (each axis pushed by the sign of
    /// `dir`), or `None` outside the cube.
    fn locate(&self, c: [i64; 3], dir: [i64; 3]) -> Option<(CellKey, &Leaf)> {
        let root = self.root_box();
        let inside = (0..3).all(|a| {
            (root.min[a] < c[a] || root.min[a] == c[a] && dir[a] > 0)
                && (c[a] < root.max[a] || c[a] == root.max[a] && dir[a] < 0)
        });
        if !inside {
            return None;
        }
        let (mut node, mut key, mut cell) = (&self.root, CellKey::ROOT, root);
        loop {
            match node {
                OctNode::Leaf(leaf) => return Some((key, leaf)),
                OctNode::Inner(children) => {
                    let m = cell.mid();
                    let i = (0..3).fold(0, |i, a| {
                        let upper = c[a] > m[a] || c[a] == m[a] && dir[a] > 0;
                        i | usize::from(upper) << a
                    });
                    node = &children[i];
                    key = key.child(i);
                    cell = cell.child(i);
                }
            }
        }
    }

    /// Replaces the leaf at `key` (which must exist), copying the path.
    fn set_leaf(&mut self, key: CellKey, leaf: Leaf) {
        let mut node = &mut self.root;
        for d in 1..=key.depth {
            let OctNode::Inner(children) = node else {
                return;
            };
            let shift = key.depth - d;
            let i = (0..3).fold(0, |i, a| i | (((key.pos[a] >> shift) & 1) as usize) << a);
            node = &mut Arc::make_mut(children)[i];
        }
        *node = OctNode::Leaf(leaf);
    }
}

/// The triangle octree below `key` of faces with the labels behind and in
/// front of each: the node and its free leaves.
pub(super) fn build_cell(
    pieces: Vec<(Polygon, Label, Label)>,
    key: CellKey,
    cell: CellBox,
    config: &OctreeConfig,
) -> (OctNode, Vec<CellKey>) {
    if pieces.is_empty() {
        return (OctNode::Leaf(Leaf::Uniform(EMPTY)), vec![key]);
    }
    if pieces.len() <= config.max_bsp_nodes || key.depth >= config.max_depth || cell.min_edge() < 2
    {
        let bsp = Bsp::from_polygons(pieces, IMPORT_SEED);
        let mut arena = ConvexArena::new();
        let Ok(bounds) = cell.add_to(&mut arena) else {
            return (OctNode::Leaf(Leaf::Uniform(EMPTY)), vec![key]);
        };
        let (node, _) = build_leaf(bsp.simplified(&mut arena, bounds), key, cell, config);
        return (node, Vec::new());
    }
    let children = split_among_children(pieces, cell);
    let built: Vec<(OctNode, Vec<CellKey>)> = children
        .into_par_iter()
        .enumerate()
        .map(|(i, pieces)| build_cell(pieces, key.child(i), cell.child(i), config))
        .collect();
    let mut free = Vec::new();
    let mut nodes = Vec::with_capacity(8);
    for (node, f) in built {
        nodes.push(node);
        free.extend(f);
    }
    let nodes: [OctNode; 8] = nodes
        .try_into()
        .unwrap_or_else(|_| unreachable!("eight children"));
    (OctNode::Inner(Arc::new(nodes)), free)
}

/// The pieces of each child: split by the three axis planes through the
/// centre; a piece lying in a plane goes to both sides.
fn split_among_children(
    pieces: Vec<(Polygon, Label, Label)>,
    cell: CellBox,
) -> Vec<Vec<(Polygon, Label, Label)>> {
    let mid = cell.mid();
    let mut out: Vec<Vec<(Polygon, Label, Label)>> = vec![Vec::new(); 8];
    for (piece, behind, in_front) in pieces {
        let mut parts = vec![(piece, 0usize)];
        for (axis, &m) in mid.iter().enumerate() {
            let mut n = [0i64; 3];
            n[axis] = 1;
            let plane = Plane::new(n[0], n[1], n[2], -i128::from(m))
                .expect("cell centres lie in the coordinate range");
            let mut next = Vec::with_capacity(2 * parts.len());
            for (part, bits) in parts {
                let sides: Vec<Sign> = part
                    .vertices()
                    .iter()
                    .map(|v| classify_vertex(v, &plane))
                    .collect();
                let below = sides.contains(&Sign::Negative);
                let above = sides.contains(&Sign::Positive);
                match (below, above) {
                    (true, true) => {
                        next.push((part.part(&sides, &plane, Sign::Negative), bits));
                        next.push((part.part(&sides, &plane, Sign::Positive), bits | 1 << axis));
                    }
                    (true, false) => next.push((part, bits)),
                    (false, true) => next.push((part, bits | 1 << axis)),
                    (false, false) => {
                        next.push((part.clone(), bits));
                        next.push((part, bits | 1 << axis));
                    }
                }
            }
            parts = next;
        }
        for (part, i) in parts {
            out[i].push((part, behind, in_front));
        }
    }
    out
}

/// Eight uniform children of one label become one leaf, bottom up.
pub(super) fn merge_uniform(node: OctNode) -> OctNode {
    let OctNode::Inner(children) = node else {
        return node;
    };
    let children: [OctNode; 8] = Arc::unwrap_or_clone(children).map(merge_uniform);
    if let OctNode::Leaf(Leaf::Uniform(first)) = children[0]
        && children
            .iter()
            .all(|c| matches!(c, OctNode::Leaf(Leaf::Uniform(l)) if *l == first))
    {
        return OctNode::Leaf(Leaf::Uniform(first));
    }
    OctNode::Inner(Arc::new(children))
}
