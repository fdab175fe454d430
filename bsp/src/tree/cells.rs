//! The convex cells of a BSP's leaves (paper 1 §3.4, first step).
//!
//! Starting from a bounding polyhedron at the root, every inner node cuts
//! the current cell by its plane ([`ConvexArena::cut`]) and recurses into
//! the children the cell reaches; each leaf reached yields a cell. The cap
//! faces a cut creates are tagged with the node on their other side (the
//! sibling subtree), which the later interior-face removal needs.

use super::bsp::{Bsp, Label, Node, NodeId};
use crate::convex::{ConvexArena, CutOutcome, PolyId};

/// The cell of one leaf inside the bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    /// The convex polyhedron, in the arena passed to [`Bsp::cells`].
    pub poly: PolyId,
    /// The leaf it belongs to.
    pub leaf: NodeId,
    /// The leaf's label.
    pub label: Label,
}

impl Bsp {
    /// The non-empty cells of all leaves inside `bounds` (a polyhedron of
    /// `arena`, which is cut up in place), in depth-first order, below
    /// before above.
    pub fn cells(&self, arena: &mut ConvexArena, bounds: PolyId) -> Vec<Cell> {
        let mut cells = Vec::new();
        let mut stack = vec![(0 as NodeId, bounds)];
        while let Some((n, poly)) = stack.pop() {
            match self.nodes()[n as usize] {
                Node::Leaf(label) => cells.push(Cell {
                    poly,
                    leaf: n,
                    label,
                }),
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let s = self.planes()[plane as usize];
                    match arena.cut(poly, &s, above, below) {
                        CutOutcome::Split { below: b, above: a } => {
                            stack.push((above, a));
                            stack.push((below, b));
                        }
                        CutOutcome::Below => stack.push((below, poly)),
                        CutOutcome::Above => stack.push((above, poly)),
                    }
                }
            }
        }
        cells
    }
}
