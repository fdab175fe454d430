//! The boundary of a BSP's solid, without interior faces (paper 1 §3.4,
//! second step).
//!
//! Notation: a *solid cell* is a leaf cell with a non-empty label; each of
//! its faces carries the BSP node on its other side (its tag, set when the
//! face was cut) or none when it lies on the bounds.
//!
//! Each face of a solid cell is clipped against the subtree on its other
//! side, as a plane-based polygon (`tree/polygon/`): at an inner node the
//! pieces go to the side(s) they reach, split exactly when they straddle;
//! at a leaf a piece is kept when that leaf's label differs (a transition)
//! and dropped otherwise (same material on both sides). A transition
//! between two materials is reported once, from the side with the larger
//! label, so solid–empty faces always face out of the solid. Faces on the
//! bounds are kept and marked: what lies outside the bounds is not known
//! here. T-junctions are removed later, on the assembled surface
//! ([`crate::mesh`]). A split whose one side is a leaf that would drop its
//! piece builds only the other piece.

use std::slice;

use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use super::cells::Cell;
use super::polygon::{Polygon, Sides, faces_along, side_of, spare_buffers};
use crate::convex::{ConvexArena, NO_TAG, PolyId};
use crate::exact::{Plane, Point4, Sign};

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

/// Room reserved for the faces of one cell and the corners of one face:
/// more than most have.
const FEW_FACES: usize = 32;

/// Room reserved per cell for its faces: more than most have.
const FACES_PER_CELL: usize = 8;

/// Working memory of [`Bsp::clip_cell_face`], reused from face to face.
struct FaceWork {
    /// The sides of the face's corners of the plane it is tested against.
    sides: Vec<Sign>,
    /// The face's half-edges, in order (half-edge `k` leaves corner `k`).
    halves: Vec<u32>,
    /// The pieces still to clip, with the node each has reached.
    stack: Vec<(NodeId, Polygon)>,
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
        // The faces of the solid cells are gathered first: their number
        // bounds the pieces kept in nearly every case (most faces are kept
        // whole or dropped, few are split), so `out` rarely grows.
        let mut faces = Vec::with_capacity(FEW_FACES);
        let mut solid_faces: Vec<(Label, u32)> = Vec::with_capacity(FACES_PER_CELL * cells.len());
        for cell in cells.iter().filter(|c| c.label != EMPTY) {
            arena.faces_of_into(cell.poly, &mut faces);
            solid_faces.extend(faces.iter().map(|&f| (cell.label, f)));
        }
        let mut out = Vec::with_capacity(solid_faces.len());
        let mut work = FaceWork {
            sides: Vec::with_capacity(FEW_FACES),
            halves: Vec::with_capacity(FEW_FACES),
            stack: Vec::new(),
        };
        for &(label, f) in &solid_faces {
            if arena.faces()[f as usize].tag != NO_TAG {
                self.clip_cell_face(arena, f, label, &mut work, &mut out);
            } else if bounds == Bounds::Keep {
                out.push(BoundaryFace::new(cell_face(arena, f), label, EMPTY, true));
            }
        }
        out
    }

    /// Clips face `f` of a solid cell of `label` against the subtree on its
    /// other side, keeping the pieces that reach leaves with a smaller
    /// label: [`Bsp::clip_polygon`], but the face is read in place in the
    /// arena until it must be split or kept, so a face that falls whole
    /// into a leaf of the same material is never copied.
    fn clip_cell_face(
        &self,
        arena: &ConvexArena,
        f: u32,
        label: Label,
        work: &mut FaceWork,
        out: &mut Vec<BoundaryFace>,
    ) {
        let FaceWork {
            sides,
            halves,
            stack,
        } = work;
        let face = &arena.faces()[f as usize];
        let mut n = face.tag;
        loop {
            match self.nodes()[n as usize] {
                Node::Leaf(other) => {
                    if other < label {
                        out.push(BoundaryFace::new(cell_face(arena, f), label, other, false));
                    }
                    return;
                }
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let p = &self.planes()[plane as usize];
                    sides.clear();
                    halves.clear();
                    let (mut neg, mut pos) = (false, false);
                    for h in arena.face_loop(f) {
                        let origin = arena.half_edges()[h as usize].origin;
                        let side = side_of(arena.point(origin), p);
                        neg |= side == Sign::Negative;
                        pos |= side == Sign::Positive;
                        sides.push(side);
                        halves.push(h);
                    }
                    // The choices of [`Polygon::split`].
                    n = match (neg, pos) {
                        (true, true) => {
                            let wanted = self.wanted(label, below, above);
                            if wanted == [false, false] {
                                return;
                            }
                            // Only the wanted parts are built, from the
                            // arena: the face is never copied whole.
                            let half = |k: usize| arena.half_edges()[halves[k] as usize];
                            let (b, a) = Polygon::parts_of(
                                arena.face_plane(f),
                                |k| {
                                    arena.face_plane(arena.half_edges()[half(k).twin as usize].face)
                                },
                                |k| arena.point(half(k).origin),
                                sides,
                                p,
                                wanted,
                            );
                            let mut keep = |piece, other| {
                                if other < label {
                                    out.push(BoundaryFace::new(piece, label, other, false));
                                }
                            };
                            match (b, a) {
                                (Some(b), a) => {
                                    stack.extend(a.map(|a| (above, a)));
                                    self.clip_pieces(below, b, stack, Some(label), &mut keep);
                                }
                                (None, Some(a)) => {
                                    self.clip_pieces(above, a, stack, Some(label), &mut keep)
                                }
                                (None, None) => {}
                            }
                            return;
                        }
                        (true, false) => below,
                        (false, true) => above,
                        (false, false) if faces_along(arena.face_plane(f), p) => above,
                        (false, false) => below,
                    };
                }
            }
        }
    }

    /// Splits `polygon` exactly among the leaves of the subtree at `n`,
    /// calling `emit(piece, leaf label)` for each piece that reaches a leaf
    /// with a label smaller than `kept_below` (the other pieces are not
    /// built). A piece lying in a node's plane goes to the side its outward
    /// normal points to (the region in front of it). `stack` is working
    /// memory (left empty), reused by callers that clip many polygons.
    pub(crate) fn clip_polygon(
        &self,
        n: NodeId,
        polygon: Polygon,
        kept_below: Label,
        stack: &mut Vec<(NodeId, Polygon)>,
        emit: &mut impl FnMut(Polygon, Label),
    ) {
        self.clip_pieces(n, polygon, stack, Some(kept_below), emit);
    }

    /// Whether [`Bsp::clip_polygon`] of `polygon` at the root, keeping
    /// pieces below `kept_below`, would certainly hand nothing on: the
    /// polygon is followed down whole, to both sides of every plane it
    /// straddles, and no leaf it reaches has a smaller label. Every piece of
    /// the clip is part of the polygon and goes only to sides the polygon
    /// goes to, so it reaches only leaves reached here. `false` does not
    /// mean that something is kept. `stack` is working memory (left empty).
    pub(crate) fn drops_whole(
        &self,
        polygon: &Polygon,
        kept_below: Label,
        stack: &mut Vec<NodeId>,
    ) -> bool {
        stack.clear();
        stack.push(0);
        while let Some(n) = stack.pop() {
            let (plane, below, above) = match self.nodes()[n as usize] {
                Node::Leaf(other) if other < kept_below => {
                    stack.clear();
                    return false;
                }
                Node::Leaf(_) => continue,
                Node::Split {
                    plane,
                    below,
                    above,
                } => (plane, below, above),
            };
            let plane = &self.planes()[plane as usize];
            // Only the sides that can keep a piece are asked about: where
            // one side alone can, whether the polygon reaches it (it stops
            // at the first corner strictly there); where neither can, nothing.
            match self.wanted(kept_below, below, above) {
                [true, true] => match polygon.side_of_plane(plane) {
                    Some(false) => stack.push(below),
                    Some(true) => stack.push(above),
                    None => stack.extend([above, below]),
                },
                [true, false] => stack.extend(polygon.reaches_side(plane, false).then_some(below)),
                [false, true] => stack.extend(polygon.reaches_side(plane, true).then_some(above)),
                [false, false] => {}
            }
        }
        true
    }

    /// Which sides (below, above) of a split with these children can keep
    /// a piece of a face of `label`: not a leaf whose label is `label` or
    /// more (the piece would be dropped there).
    #[inline]
    fn wanted(&self, label: Label, below: NodeId, above: NodeId) -> [bool; 2] {
        [below, above].map(|n| !matches!(self.nodes()[n as usize], Node::Leaf(o) if o >= label))
    }

    /// [`Bsp::clip_polygon`] of `polygon` at `n` and then of the pieces on
    /// `stack`, depth first, below before above. A piece that is not split
    /// goes on without passing through the stack. With `kept_below`, only
    /// pieces reaching leaves with a smaller label are handed to `emit`
    /// (others are not built).
    fn clip_pieces(
        &self,
        n: NodeId,
        polygon: Polygon,
        stack: &mut Vec<(NodeId, Polygon)>,
        kept_below: Option<Label>,
        emit: &mut impl FnMut(Polygon, Label),
    ) {
        let mut room = Sides::default();
        let mut first = Some((n, polygon));
        while let Some((mut n, mut polygon)) = first.take().or_else(|| stack.pop()) {
            // Down the tree with one piece, in place while it is not split.
            loop {
                let (plane, below, above) = match self.nodes()[n as usize] {
                    Node::Leaf(other) => {
                        emit(polygon, other);
                        break;
                    }
                    Node::Split {
                        plane,
                        below,
                        above,
                    } => (plane, below, above),
                };
                let p = &self.planes()[plane as usize];
                let wanted = kept_below.map_or([true; 2], |l| self.wanted(l, below, above));
                let sides = room.for_corners(polygon.vertices().len());
                match polygon.whole_side(p, sides) {
                    Some(false) if wanted[0] => n = below,
                    Some(true) if wanted[1] => n = above,
                    Some(_) => break,
                    None => {
                        (n, polygon) = match polygon.split_known(sides, p, wanted) {
                            (Some(b), Some(a)) => {
                                stack.push((above, a));
                                (below, b)
                            }
                            (Some(b), None) => (below, b),
                            (None, Some(a)) => (above, a),
                            (None, None) => break,
                        };
                    }
                }
            }
        }
    }
}

/// Face `f` of the arena as a plane-based polygon. Half-edge k lies in the
/// face across it (edge plane k) and leaves corner k, the meet of edge
/// planes k − 1 and k.
pub(crate) fn cell_face(arena: &ConvexArena, f: u32) -> Polygon {
    let (mut edges, mut corners) = spare_buffers(arena.face_loop(f).count());
    for h in arena.face_loop(f) {
        let half = arena.half_edges()[h as usize];
        let across = arena.half_edges()[half.twin as usize].face;
        // Copied straight from the arena into the buffers: a `push` would
        // first copy each value to the stack.
        edges.extend_from_slice(slice::from_ref(arena.face_plane(across)));
        corners.extend_from_slice(slice::from_ref(arena.point(half.origin)));
    }
    Polygon::with_corners(*arena.face_plane(f), edges, corners)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::exact::IntPoint;
    use crate::tree::BooleanOp;

    fn point(x: i64, y: i64, z: i64) -> IntPoint {
        IntPoint::new(x, y, z).expect("in budget")
    }

    /// A box with corners `lo` and `hi` filled with `label`.
    fn solid_box(lo: [i64; 3], hi: [i64; 3], label: Label) -> Bsp {
        let mut arena = ConvexArena::new();
        let poly = arena
            .add_box(point(lo[0], lo[1], lo[2]), point(hi[0], hi[1], hi[2]))
            .expect("in budget");
        Bsp::from_convex(&arena, poly, label)
    }

    /// A box of random size (edges 4 to 19) and place inside `[-40, 40]³`.
    fn random_box(rng: &mut ChaCha8Rng, label: Label) -> Bsp {
        let lo = [0; 3].map(|_| rng.random_range(-40..20));
        let hi = lo.map(|l| l + rng.random_range(4..20));
        solid_box(lo, hi, label)
    }

    /// A block of material 1 with a box of material 2 and box holes, and
    /// small triangles inside it: every triangle that [`Bsp::drops_whole`]
    /// drops has no piece kept by the exact clip, and both answers occur,
    /// also for triangles the tree's planes cut.
    #[test]
    fn drops_whole_only_when_the_clip_keeps_nothing() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut dropped, mut dropped_cut, mut kept) = (0, 0, 0);
        for _ in 0..40 {
            let mut bsp = solid_box([-40; 3], [40; 3], 1);
            for i in 0..4 {
                let (other, op) = match i {
                    0 => (random_box(&mut rng, 2), BooleanOp::Union),
                    _ => (random_box(&mut rng, 1), BooleanOp::Difference),
                };
                let mut arena = ConvexArena::new();
                let bounds = arena
                    .add_box(point(-64, -64, -64), point(64, 64, 64))
                    .expect("in budget");
                bsp = bsp.merge(&other, op, &mut arena, bounds);
            }
            for _ in 0..50 {
                let centre = [0; 3].map(|_| rng.random_range(-36..36));
                let corners = [0; 3].map(|_| {
                    let mut c = |i: usize| centre[i] + rng.random_range(-8..8);
                    point(c(0), c(1), c(2))
                });
                let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
                    continue;
                };
                let label = rng.random_range(1..=2);
                let mut sides = [Sign::Zero; 3];
                let cut = bsp
                    .planes()
                    .iter()
                    .any(|p| triangle.whole_side(p, &mut sides).is_none());
                let mut nodes = Vec::new();
                let drops = bsp.drops_whole(&triangle, label, &mut nodes);
                assert!(nodes.is_empty());
                let mut pieces = 0;
                let mut stack = Vec::new();
                bsp.clip_polygon(0, triangle, label, &mut stack, &mut |_, _| pieces += 1);
                if drops {
                    assert_eq!(pieces, 0, "a dropped triangle has kept pieces");
                    dropped += 1;
                    dropped_cut += usize::from(cut);
                } else {
                    kept += usize::from(pieces > 0);
                }
            }
        }
        assert!(
            dropped > 100 && kept > 100,
            "{dropped} dropped, {kept} kept"
        );
        assert!(
            dropped_cut > 10,
            "only {dropped_cut} dropped triangles were cut"
        );
    }
}
