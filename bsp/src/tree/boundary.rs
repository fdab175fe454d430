//! The boundary of a BSP's solid, without interior faces (paper 1 §3.4,
//! second step).
//!
//! Notation: a *solid cell* is a leaf cell with a non-empty label; each of
//! its faces carries the BSP node on its other side (its tag, set when the
//! face was cut) or none when it lies on the bounds.
//!
//! Each face of a solid cell is clipped against the subtree on its other
//! side, as a plane-based polygon ([`super::polygon`]): at an inner node the
//! pieces go to the side(s) they reach, split exactly when they straddle;
//! at a leaf a piece is kept when that leaf is empty (a solid–empty
//! transition) and dropped otherwise (solid–solid). Faces on the bounds are
//! kept: outside the bounds is empty. T-junction splitting is not done yet.

use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use super::polygon::Polygon;
use crate::convex::{ConvexArena, NO_TAG, PolyId};
use crate::exact::{Plane, Point4, Sign, classify_vertex};

/// One boundary polygon: outward plane, exact vertices counter-clockwise
/// from outside, and the label of the solid behind it.
#[derive(Clone, Debug)]
pub struct BoundaryFace {
    /// Supporting plane, positive side outside the solid.
    pub plane: Plane,
    /// Exact corners, counter-clockwise seen from outside.
    pub vertices: Vec<Point4>,
    /// The material behind the face.
    pub label: Label,
}

impl Bsp {
    /// The boundary of the solid inside `bounds` (a polyhedron of `arena`,
    /// cut up in place): every solid–empty face piece, none between solid
    /// cells.
    pub fn boundary(&self, arena: &mut ConvexArena, bounds: PolyId) -> Vec<BoundaryFace> {
        let mut out = Vec::new();
        for cell in self.cells(arena, bounds) {
            if cell.label == EMPTY {
                continue;
            }
            for f in arena.faces_of(cell.poly) {
                let face = arena.faces()[f as usize];
                let polygon = Polygon {
                    support: face.plane,
                    edges: arena
                        .face_loop(f)
                        .map(|h| {
                            let twin = arena.half_edges()[h as usize].twin;
                            arena.faces()[arena.half_edges()[twin as usize].face as usize].plane
                        })
                        .collect(),
                };
                if face.tag == NO_TAG {
                    out.push(BoundaryFace {
                        plane: face.plane,
                        vertices: polygon.vertices(),
                        label: cell.label,
                    });
                } else {
                    self.clip(face.tag, polygon, cell.label, &mut out);
                }
            }
        }
        out
    }

    /// Clips `polygon` against the subtree at `n`, keeping the pieces that
    /// reach empty leaves.
    fn clip(&self, n: NodeId, polygon: Polygon, label: Label, out: &mut Vec<BoundaryFace>) {
        let mut stack = vec![(n, polygon)];
        while let Some((n, polygon)) = stack.pop() {
            match self.nodes()[n as usize] {
                Node::Leaf(other) => {
                    if other == EMPTY {
                        out.push(BoundaryFace {
                            plane: polygon.support,
                            vertices: polygon.vertices(),
                            label,
                        });
                    }
                }
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let p = self.planes()[plane as usize];
                    let sides: Vec<Sign> = polygon
                        .vertices()
                        .iter()
                        .map(|v| classify_vertex(v, &p))
                        .collect();
                    match (
                        sides.contains(&Sign::Negative),
                        sides.contains(&Sign::Positive),
                    ) {
                        (true, true) => {
                            stack.push((below, polygon.part(&sides, &p, Sign::Negative)));
                            stack.push((above, polygon.part(&sides, &p, Sign::Positive)));
                        }
                        (true, false) => stack.push((below, polygon)),
                        (false, true) => stack.push((above, polygon)),
                        // In the plane: the side across it is the one facing
                        // away from the solid, i.e. where the face normal
                        // points.
                        (false, false) => {
                            let same = p
                                .normal()
                                .iter()
                                .zip(polygon.support.normal())
                                .all(|(a, b)| (*a as i128).signum() == (b as i128).signum());
                            stack.push((if same { above } else { below }, polygon));
                        }
                    }
                }
            }
        }
    }
}
