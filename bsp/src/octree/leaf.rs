//! Leaves within the node budget (paper 1 §3.8): a BSP over the budget is
//! split into eight children rebuilt from the pieces of its boundary
//! faces inside each child box (`split.rs`), again while over it; eight
//! leaf children that fit the budget together are combined into one, their
//! BSPs grafted under the axis planes (Fig. 8, combine A) and rebuilt
//! inside the cell (combine B).
//!
//! Notation: `C` — a cell's box; a leaf's size is its number of inner BSP
//! nodes, against the budget `OctreeConfig::max_bsp_nodes`.

use std::sync::Arc;

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::graft::axis_graft;
use super::split::{child_bsp_within, split_faces};
use super::tree::{Leaf, OctNode, Octree, OctreeConfig};
use crate::Error;
use crate::convex::{ConvexArena, PolyId, with_arena};
use crate::tree::{BoundaryFace, Bsp, EMPTY};

/// The boundary faces of leaves whose content an edit replaced, by key
/// (see [`Octree::apply_with_faces`]).
pub type CellFaces = Vec<(CellKey, Vec<BoundaryFace>)>;

impl Octree {
    /// The regions of `bsp` inside the cube, split into cells within the
    /// budget (§3.8).
    ///
    /// # Errors
    /// As [`Octree::new`].
    pub fn from_bsp(
        origin: [i64; 3],
        size_log2: u8,
        bsp: &Bsp,
        config: OctreeConfig,
    ) -> Result<Self, Error> {
        let mut octree = Self::new(origin, size_log2, EMPTY, config)?;
        let root_box = octree.root_box();
        let mut arena = ConvexArena::new();
        let bounds = root_box.add_to(&mut arena)?;
        let bsp = bsp.simplified(&mut arena, bounds);
        let (root, _) = build_leaf(bsp, CellKey::ROOT, root_box, &config);
        octree.root = root;
        Ok(octree)
    }
}

/// A leaf for `bsp` inside `cell`, split into children while it is over
/// the budget; also returns the leaf keys created.
pub(crate) fn build_leaf(
    bsp: Bsp,
    key: CellKey,
    cell: CellBox,
    config: &OctreeConfig,
) -> (OctNode, Vec<CellKey>) {
    let (node, leaves, _) = build_leaf_faces(bsp, None, key, cell, config, false);
    (node, leaves)
}

/// [`build_leaf`] from `bsp`'s exact boundary inside `cell` with the faces
/// on the cell's box marked (`faces`; found here when `None` and needed),
/// also returning, when `keep_faces`, the boundary faces of each new leaf
/// (as [`Octree::apply_with_faces`] hands them back): `faces` when `bsp`
/// stays one leaf, else each child's pieces of them ([`split_faces`]).
pub(super) fn build_leaf_faces(
    bsp: Bsp,
    faces: Option<Vec<BoundaryFace>>,
    key: CellKey,
    cell: CellBox,
    config: &OctreeConfig,
    keep_faces: bool,
) -> (OctNode, Vec<CellKey>, CellFaces) {
    let inner = bsp.nodes().len() / 2;
    let own_faces = |faces: Option<Vec<BoundaryFace>>| {
        if keep_faces {
            vec![(key, faces.unwrap_or_default())]
        } else {
            Vec::new()
        }
    };
    if inner == 0 {
        let label = match bsp.nodes()[0] {
            crate::tree::Node::Leaf(label) => label,
            crate::tree::Node::Split { .. } => EMPTY,
        };
        let node = OctNode::Leaf(Leaf::Uniform(label));
        return (node, vec![key], own_faces(faces));
    }
    if inner <= config.max_bsp_nodes || key.depth >= config.max_depth || cell.min_edge() < 2 {
        let node = OctNode::Leaf(Leaf::Bsp(Arc::new(bsp)));
        return (node, vec![key], own_faces(faces));
    }
    let faces = faces.unwrap_or_else(|| {
        with_arena(|arena| {
            let poly = cell_poly(arena, cell);
            bsp.boundary(arena, poly)
        })
    });
    split_leaf(&bsp, faces, key, cell, config, keep_faces)
}

/// Whether a leaf at `key` whose rebuild starts from `faces` (its exact
/// boundary inside `cell`, faces on the box marked) is certainly split
/// by [`build_leaf_faces`]: it may be split, and its rebuild would be over
/// the budget ([`Bsp::rebuild_exceeds`]).
pub(super) fn splits_certainly(
    faces: &[BoundaryFace],
    key: CellKey,
    cell: CellBox,
    config: &OctreeConfig,
) -> bool {
    may_split(key, cell, config) && Bsp::rebuild_exceeds(faces, config.max_bsp_nodes)
}

/// Whether [`build_leaf_faces`] splits a leaf at `key` that is over the
/// budget.
pub(super) fn may_split(key: CellKey, cell: CellBox, config: &OctreeConfig) -> bool {
    key.depth < config.max_depth && cell.min_edge() >= 2
}

/// The most splits a leaf at `key` may have without being split: the
/// budget, or no limit where it is not split.
pub(super) fn split_limit(key: CellKey, cell: CellBox, config: &OctreeConfig) -> usize {
    if may_split(key, cell, config) {
        config.max_bsp_nodes
    } else {
        usize::MAX
    }
}

/// The inner node [`build_leaf_faces`] makes of a leaf over the budget
/// from its exact boundary `faces` inside `cell`: the children rebuilt
/// from their pieces, split again while over the budget. `regions` has the
/// leaf's regions inside `cell` (its rebuild, or the tree it was rebuilt
/// from): it labels the children without surface.
pub(super) fn split_leaf(
    regions: &Bsp,
    faces: Vec<BoundaryFace>,
    key: CellKey,
    cell: CellBox,
    config: &OctreeConfig,
    keep_faces: bool,
) -> (OctNode, Vec<CellKey>, CellFaces) {
    let pieces = split_faces(faces, &cell);
    let built: Vec<(OctNode, Vec<CellKey>, CellFaces)> = pieces
        .into_par_iter()
        .enumerate()
        .map(|(i, pieces)| {
            let (key, child) = (key.child(i), cell.child(i));
            if splits_certainly(&pieces, key, child, config) {
                return split_leaf(regions, pieces, key, child, config, keep_faces);
            }
            let limit = split_limit(key, child, config);
            match child_bsp_within(regions, &pieces, &child, limit) {
                Some(bsp) => build_leaf_faces(bsp, Some(pieces), key, child, config, keep_faces),
                None => split_leaf(regions, pieces, key, child, config, keep_faces),
            }
        })
        .collect();
    let mut leaves = Vec::new();
    let mut faces = Vec::new();
    let mut children = Vec::with_capacity(8);
    for (node, keys, below) in built {
        children.push(node);
        leaves.extend(keys);
        faces.extend(below);
    }
    let children: [OctNode; 8] = children
        .try_into()
        .unwrap_or_else(|_| unreachable!("eight children"));
    (OctNode::Inner(Arc::new(children)), leaves, faces)
}

/// One leaf for eight leaf children that fit the budget together, or
/// `None`; with it, when `keep_faces` and the children were not all one
/// uniform label, the boundary faces its rebuild extracted inside `cell`.
pub(crate) fn combine(
    children: &[OctNode; 8],
    cell: CellBox,
    config: &OctreeConfig,
    keep_faces: bool,
) -> Option<(Leaf, Option<Vec<BoundaryFace>>)> {
    let leaves: Vec<&Leaf> = children
        .iter()
        .map(|c| match c {
            OctNode::Leaf(leaf) => Some(leaf),
            OctNode::Inner(_) => None,
        })
        .collect::<Option<_>>()?;
    if let Leaf::Uniform(first) = leaves[0]
        && leaves
            .iter()
            .all(|l| matches!(l, Leaf::Uniform(x) if x == first))
    {
        return Some((Leaf::Uniform(*first), None));
    }
    if leaves.iter().map(|l| l.bsp_nodes()).sum::<usize>() > combine_limit(config) {
        return None;
    }
    let bsps: Vec<Bsp> = leaves.iter().map(|l| l.to_bsp()).collect();
    let grafted = axis_graft(std::array::from_fn(|i| &bsps[i]), cell.mid());
    let (simplified, faces) = with_arena(|arena| {
        let poly = cell_poly(arena, cell);
        if keep_faces {
            let (simplified, faces) = grafted.simplified_faces(arena, poly);
            (simplified, Some(faces))
        } else {
            (grafted.simplified(arena, poly), None)
        }
    });
    let inner = simplified.nodes().len() / 2;
    if inner > config.max_bsp_nodes {
        return None;
    }
    let leaf = match simplified.nodes()[0] {
        crate::tree::Node::Leaf(label) if inner == 0 => Leaf::Uniform(label),
        _ => Leaf::Bsp(Arc::new(simplified)),
    };
    Some((leaf, faces))
}

/// The most inner BSP nodes eight leaf children may hold together to be
/// combined: half the budget. Combined right up to the budget, a leaf
/// along a tool's path is split again by the next edit that adds a few
/// planes, and combined again after it — each time a rebuild of the whole
/// cell (`cutter --path helix`, 1,500 steps: about 400 splits and 400
/// combines).
pub(crate) fn combine_limit(config: &OctreeConfig) -> usize {
    config.max_bsp_nodes / 2
}

/// The cell's box in `arena`; cells lie inside the root cube, which was
/// checked against the coordinate range when the octree was made.
pub(crate) fn cell_poly(arena: &mut ConvexArena, cell: CellBox) -> PolyId {
    cell.add_to(arena)
        .expect("octree cells lie inside the checked root cube")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::IntPoint;

    /// Eight leaf children of the cube `[0, 64]³`, each a box of material
    /// 1 strictly inside its child cell: 6 inner nodes each, 48 together.
    fn boxed_children() -> [OctNode; 8] {
        let cell = CellBox {
            min: [0; 3],
            max: [64; 3],
        };
        std::array::from_fn(|i| {
            let child = cell.child(i);
            let corner = |at: [i64; 3]| IntPoint::from_array(at).expect("in range");
            let mut arena = ConvexArena::new();
            let poly = arena
                .add_box(
                    corner(child.min.map(|c| c + 4)),
                    corner(child.max.map(|c| c - 4)),
                )
                .expect("a proper box");
            OctNode::Leaf(Leaf::Bsp(Arc::new(Bsp::from_convex(&arena, poly, 1))))
        })
    }

    fn config(max_bsp_nodes: usize) -> OctreeConfig {
        OctreeConfig {
            max_bsp_nodes,
            ..OctreeConfig::default()
        }
    }

    /// Children are combined only when they fit half the budget together:
    /// 48 nodes are combined under a budget of 96, not under 95 (nor 60,
    /// which they would fit whole).
    #[test]
    fn children_combine_within_half_the_budget() {
        let children = boxed_children();
        let sum: usize = children
            .iter()
            .map(|c| match c {
                OctNode::Leaf(leaf) => leaf.bsp_nodes(),
                OctNode::Inner(_) => 0,
            })
            .sum();
        assert_eq!(sum, 48);
        let cell = CellBox {
            min: [0; 3],
            max: [64; 3],
        };
        for (budget, combined) in [(96, true), (95, false), (60, false)] {
            assert_eq!(combine_limit(&config(budget)) >= sum, combined, "{budget}");
            let result = combine(&children, cell, &config(budget), true);
            assert_eq!(result.is_some(), combined, "budget {budget}");
            if let Some((Leaf::Bsp(bsp), Some(faces))) = result {
                // The eight boxes, 6 faces each, and the six axis planes
                // between them gone: 48 inner nodes.
                assert_eq!(faces.len(), 48);
                assert!(bsp.nodes().len() / 2 <= 48, "{}", bsp.nodes().len() / 2);
            } else {
                assert!(!combined, "budget {budget}: not a BSP leaf with faces");
            }
        }
    }
}
