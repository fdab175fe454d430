//! Emptying or keeping chosen convex cells of an octree (paper 1 §3.7,
//! §3.8).
//!
//! Notation: `S(k)` — the BSP leaves chosen in leaf cell `k` (`0` for a
//! uniform leaf); [`Relabel::Remove`] sets their labels to empty,
//! [`Relabel::Keep`] sets every other label to empty and empties the leaves
//! with nothing chosen.
//!
//! Only the paths to the chosen leaves are walked (for keeping, everything
//! else becomes one empty leaf per subtree). A relabelled BSP is rebuilt
//! from its exact boundary inside its cell (§3.7) and split while over the
//! budget; an inner cell whose children changed is combined when they fit
//! the budget together, as an edit does ([`super::apply`]). The regions
//! outside the chosen cells are exactly those of the input, and the result
//! is a pure function of it (children run in parallel).

use std::collections::{BTreeMap, HashSet};
use std::sync::Arc;

use rayon::prelude::*;

use super::apply::Changes;
use super::cell::{CellBox, CellKey};
use super::leaf::{build_leaf, cell_poly, combine};
use super::tree::collect_leaves;
use super::tree::{Leaf, OctNode, Octree, OctreeConfig};
use crate::convex::with_arena;
use crate::tree::{Bsp, EMPTY, Node, NodeId};

/// What happens to the chosen cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Relabel {
    /// They become empty; the rest stays.
    Remove,
    /// They stay; the rest becomes empty.
    Keep,
}

/// The octree's root with the cells `chosen` (BSP leaves by leaf cell,
/// each list sorted) relabelled as `mode` says, and the changes: `None`
/// when nothing changed.
pub(crate) fn relabel(
    octree: &Octree,
    chosen: &BTreeMap<CellKey, Vec<NodeId>>,
    mode: Relabel,
) -> (Option<OctNode>, Changes) {
    let mut above = HashSet::new();
    for key in chosen.keys() {
        let mut k = *key;
        while let Some(parent) = k.parent() {
            if !above.insert(parent) {
                break;
            }
            k = parent;
        }
    }
    let walk = Walk {
        chosen,
        above,
        mode,
        config: octree.config(),
    };
    let (root, mut changes) = walk.node(&octree.root, CellKey::ROOT, octree.root_box());
    changes.changed.sort_unstable();
    changes.removed.sort_unstable();
    (root, changes)
}

struct Walk<'a> {
    chosen: &'a BTreeMap<CellKey, Vec<NodeId>>,
    /// Every strict ancestor of a chosen leaf.
    above: HashSet<CellKey>,
    mode: Relabel,
    config: &'a OctreeConfig,
}

impl Walk<'_> {
    /// The new node (`None` when unchanged) and the changes below it.
    fn node(&self, node: &OctNode, key: CellKey, cell: CellBox) -> (Option<OctNode>, Changes) {
        let chosen = self.chosen.get(&key);
        if chosen.is_none() && !self.above.contains(&key) {
            return match (self.mode, node) {
                (Relabel::Remove, _) | (Relabel::Keep, OctNode::Leaf(Leaf::Uniform(EMPTY))) => {
                    (None, Changes::default())
                }
                (Relabel::Keep, _) => {
                    let mut removed = Vec::new();
                    collect_leaves(node, key, &mut removed);
                    let changes = Changes {
                        changed: vec![key],
                        removed,
                    };
                    (Some(OctNode::Leaf(Leaf::Uniform(EMPTY))), changes)
                }
            };
        }
        match node {
            OctNode::Leaf(leaf) => {
                let nodes = chosen.map_or(&[][..], Vec::as_slice);
                self.leaf(leaf, nodes, key, cell)
            }
            OctNode::Inner(children) => {
                let results: Vec<(Option<OctNode>, Changes)> = (0..8)
                    .into_par_iter()
                    .map(|i| self.node(&children[i], key.child(i), cell.child(i)))
                    .collect();
                let mut changes = Changes::default();
                if results.iter().all(|(n, _)| n.is_none()) {
                    return (None, changes);
                }
                let mut new_children = children.as_ref().clone();
                for (i, (n, c)) in results.into_iter().enumerate() {
                    if let Some(n) = n {
                        new_children[i] = n;
                    }
                    changes.changed.extend(c.changed);
                    changes.removed.extend(c.removed);
                }
                if let Some((combined, _)) = combine(&new_children, cell, self.config, false) {
                    let mut removed = Vec::new();
                    collect_leaves(node, key, &mut removed);
                    let changes = Changes {
                        changed: vec![key],
                        removed,
                    };
                    return (Some(OctNode::Leaf(combined)), changes);
                }
                (Some(OctNode::Inner(Arc::new(new_children))), changes)
            }
        }
    }

    /// The leaf with the BSP leaves `nodes` (sorted) relabelled.
    fn leaf(
        &self,
        leaf: &Leaf,
        nodes: &[NodeId],
        key: CellKey,
        cell: CellBox,
    ) -> (Option<OctNode>, Changes) {
        let keep = |n: NodeId| nodes.binary_search(&n).is_ok() == (self.mode == Relabel::Keep);
        let bsp = match leaf {
            Leaf::Uniform(EMPTY) => return (None, Changes::default()),
            Leaf::Uniform(_) if keep(0) => return (None, Changes::default()),
            Leaf::Uniform(_) => None,
            Leaf::Bsp(bsp) => {
                let relabeled: Vec<Node> = bsp
                    .nodes()
                    .iter()
                    .enumerate()
                    .map(|(i, n)| match *n {
                        Node::Leaf(l) if l != EMPTY && !keep(i as NodeId) => Node::Leaf(EMPTY),
                        n => n,
                    })
                    .collect();
                if relabeled == bsp.nodes() {
                    return (None, Changes::default());
                }
                let solid = relabeled
                    .iter()
                    .any(|n| matches!(n, Node::Leaf(l) if *l != EMPTY));
                solid.then(|| Bsp::from_parts(bsp.planes().to_vec(), relabeled))
            }
        };
        let (node, changed) = match bsp {
            None => (OctNode::Leaf(Leaf::Uniform(EMPTY)), vec![key]),
            Some(bsp) => {
                let simplified = with_arena(|arena| {
                    let poly = cell_poly(arena, cell);
                    bsp.simplified(arena, poly)
                });
                build_leaf(simplified, key, cell, self.config)
            }
        };
        let removed = match node {
            OctNode::Leaf(_) => Vec::new(),
            OctNode::Inner(_) => vec![key],
        };
        (Some(node), Changes { changed, removed })
    }
}
