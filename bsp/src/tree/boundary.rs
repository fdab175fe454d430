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
//! at a leaf a piece is kept when that leaf's label differs (a transition)
//! and dropped otherwise (same material on both sides). A transition
//! between two materials is reported once, from the side with the larger
//! label, so solid–empty faces always face out of the solid. Faces on the
//! bounds are kept and marked: what lies outside the bounds is not known
//! here. T-junctions are removed later, on the assembled surface
//! ([`crate::mesh`]).

use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use super::cells::Cell;
use super::polygon::{Polygon, spare_buffers};
use crate::convex::{ConvexArena, NO_TAG, PolyId};
use crate::exact::{Plane, Point4};

/// One boundary polygon: outward plane, exact corners counter-clockwise
/// from outside (with the edge planes that define them), and the labels on
/// both sides.
#[derive(Clone, Debug)]
pub struct BoundaryFace {
    /// Supporting plane, positive side outside (towards [`Self::outside`]).
    pub plane: Plane,
    /// Edge planes: edge `k` runs from corner `k` to corner `k + 1`, lies in
    /// `edges[k]`, and the polygon is on its negative side. Corner `k` is
    /// the meet of `plane`, `edges[k − 1]` and `edges[k]`.
    pub edges: Vec<Plane>,
    /// Exact corners, counter-clockwise seen from outside.
    pub vertices: Vec<Point4>,
    /// The material behind the face (never empty).
    pub label: Label,
    /// The material in front of it: [`EMPTY`] for a surface face, another
    /// material for an interface between two materials. Unknown (reported
    /// as [`EMPTY`]) for faces on the bounds.
    pub outside: Label,
    /// Whether the face lies on the bounds rather than on a BSP plane.
    pub on_bounds: bool,
}

impl BoundaryFace {
    pub(crate) fn new(polygon: Polygon, label: Label, outside: Label, on_bounds: bool) -> Self {
        let (plane, edges, vertices) = polygon.into_parts();
        Self {
            plane,
            edges,
            vertices,
            label,
            outside,
            on_bounds,
        }
    }

    /// The face as a plane-based polygon.
    pub(crate) fn polygon(&self) -> Polygon {
        let (mut edges, mut corners) = spare_buffers(self.edges.len());
        edges.extend_from_slice(&self.edges);
        corners.extend_from_slice(&self.vertices);
        Polygon::with_corners(self.plane, edges, corners)
    }

    /// The face as a plane-based polygon, taken apart without copying.
    pub(crate) fn into_polygon(self) -> Polygon {
        Polygon::with_corners(self.plane, self.edges, self.vertices)
    }
}

/// Whether [`Bsp::boundary_of_cells`] reports the faces on the bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bounds {
    /// Report them, marked [`BoundaryFace::on_bounds`].
    Keep,
    /// Leave them out (nothing is known about what lies beyond).
    Skip,
}

impl Bsp {
    /// The boundary of the solid inside `bounds` (a polyhedron of `arena`,
    /// cut up in place): every solid–empty face piece and every interface
    /// between different materials (once), none between cells of the same
    /// material; pieces of the bounds that enclose solid are included and
    /// marked [`BoundaryFace::on_bounds`].
    pub fn boundary(&self, arena: &mut ConvexArena, bounds: PolyId) -> Vec<BoundaryFace> {
        let cells = self.cells(arena, bounds);
        self.boundary_of_cells(arena, &cells, Bounds::Keep)
    }

    /// The boundary pieces of the given cells (from [`Bsp::cells`] on
    /// `arena`), with or without the pieces on the bounds.
    pub(crate) fn boundary_of_cells(
        &self,
        arena: &ConvexArena,
        cells: &[Cell],
        bounds: Bounds,
    ) -> Vec<BoundaryFace> {
        let mut out = Vec::new();
        let mut stack = Vec::new();
        for cell in cells {
            if cell.label == EMPTY {
                continue;
            }
            for f in arena.faces_of(cell.poly) {
                let face = arena.faces()[f as usize];
                if face.tag == NO_TAG && bounds == Bounds::Skip {
                    continue;
                }
                // Half-edge k lies in the face across it (edge plane k) and
                // leaves corner k, the meet of edge planes k − 1 and k.
                let (mut edges, mut corners) = spare_buffers(arena.face_loop(f).count());
                for h in arena.face_loop(f) {
                    let half = arena.half_edges()[h as usize];
                    let across = arena.half_edges()[half.twin as usize].face;
                    edges.push(arena.faces()[across as usize].plane);
                    corners.push(arena.vertices()[half.origin as usize].point);
                }
                let polygon = Polygon::with_corners(face.plane, edges, corners);
                if face.tag == NO_TAG {
                    out.push(BoundaryFace::new(polygon, cell.label, EMPTY, true));
                } else {
                    self.clip(face.tag, polygon, cell.label, &mut stack, &mut out);
                }
            }
        }
        out
    }

    /// Clips `polygon` against the subtree at `n`, keeping the pieces that
    /// reach leaves with a smaller label.
    fn clip(
        &self,
        n: NodeId,
        polygon: Polygon,
        label: Label,
        stack: &mut Vec<(NodeId, Polygon)>,
        out: &mut Vec<BoundaryFace>,
    ) {
        self.clip_polygon_with(n, polygon, stack, &mut |piece, other| {
            if other < label {
                out.push(BoundaryFace::new(piece, label, other, false));
            }
        });
    }

    /// Splits `polygon` exactly among the leaves of the subtree at `n`,
    /// calling `emit(piece, leaf label)` for each piece. A piece lying in a
    /// node's plane goes to the side its outward normal points to (the
    /// region in front of it).
    pub(crate) fn clip_polygon(
        &self,
        n: NodeId,
        polygon: Polygon,
        emit: &mut impl FnMut(Polygon, Label),
    ) {
        self.clip_polygon_with(n, polygon, &mut Vec::new(), emit);
    }

    /// [`Bsp::clip_polygon`] with a reused (empty) work stack.
    fn clip_polygon_with(
        &self,
        n: NodeId,
        polygon: Polygon,
        stack: &mut Vec<(NodeId, Polygon)>,
        emit: &mut impl FnMut(Polygon, Label),
    ) {
        stack.push((n, polygon));
        while let Some((n, polygon)) = stack.pop() {
            match self.nodes()[n as usize] {
                Node::Leaf(other) => emit(polygon, other),
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let (b, a) = polygon.split(&self.planes()[plane as usize]);
                    if let Some(a) = a {
                        stack.push((above, a));
                    }
                    if let Some(b) = b {
                        stack.push((below, b));
                    }
                }
            }
        }
    }
}
