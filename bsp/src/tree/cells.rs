//! The convex cells of a BSP's leaves (paper 1 §3.4, first step).
//!
//! Starting from a bounding polyhedron at the root, every inner node cuts
//! the current cell by its plane ([`ConvexArena::cut`]) and recurses into
//! the children the cell reaches; each leaf reached yields a cell. The cap
//! faces a cut creates are tagged with the node on their other side (the
//! sibling subtree), which the later interior-face removal needs.

use super::bsp::{Bsp, Label, Node, NodeId};
use crate::convex::mesh::Vertex;
use crate::convex::{ConvexArena, CutOutcome, Face, HalfEdge, PolyId};
use crate::exact::{Plane, Sign, classify_vertex};

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

/// The sides of a plane a polyhedron has vertices strictly on, as a cut
/// would find them ([`CutOutcome`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Reach {
    /// Both: the cut is proper.
    Both,
    /// The closed negative half-space holds it.
    Below,
    /// The closed positive half-space holds it.
    Above,
}

/// Working memory of [`Survey`]: the elements of the surveyed polyhedron
/// and the survey that last reached each vertex and face, reused between
/// surveys; and a stack of saved polyhedra ([`Survey::save`]).
#[derive(Default)]
pub(crate) struct Survey {
    /// The survey that last reached each vertex and face.
    vertex_stamp: Vec<u32>,
    face_stamp: Vec<u32>,
    stamp: u32,
    faces: Vec<u32>,
    vertices: Vec<u32>,
    /// Saved records with their indices, innermost save last.
    saved_half_edges: Vec<(u32, HalfEdge)>,
    saved_vertices: Vec<(u32, Vertex)>,
    saved_faces: Vec<(u32, Face)>,
}

/// Where one save starts on the stacks of saved records.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Saved {
    half_edges: usize,
    vertices: usize,
    faces: usize,
}

impl Survey {
    /// Lists the faces and vertices of `poly` (faces in depth-first order
    /// over their neighbours, vertices as first met).
    pub(crate) fn survey(&mut self, arena: &ConvexArena, poly: PolyId) {
        self.walk::<false>(arena, poly);
    }

    /// [`Survey::survey`] and [`Survey::save`] in one walk over `poly`:
    /// the same lists and the same saved records, in the same order.
    pub(crate) fn survey_and_save(&mut self, arena: &ConvexArena, poly: PolyId) -> Saved {
        let saved = self.saved_lengths();
        self.walk::<true>(arena, poly);
        self.saved_vertices.extend(
            self.vertices
                .iter()
                .map(|&v| (v, arena.vertices[v as usize])),
        );
        saved
    }

    /// Lists the faces and vertices of `poly`; with `SAVE`, also pushes
    /// the records of its faces and half-edges as [`Survey::save`] does.
    fn walk<const SAVE: bool>(&mut self, arena: &ConvexArena, poly: PolyId) {
        let (nv, nf) = (arena.vertices.len(), arena.faces.len());
        if self.vertex_stamp.len() < nv {
            self.vertex_stamp.resize(nv, 0);
        }
        if self.face_stamp.len() < nf {
            self.face_stamp.resize(nf, 0);
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.vertex_stamp.fill(0);
            self.face_stamp.fill(0);
            self.stamp = 1;
        }
        self.faces.clear();
        self.vertices.clear();
        let start = arena.half_edges[poly.0 as usize].face;
        self.face_stamp[start as usize] = self.stamp;
        self.faces.push(start);
        let mut i = 0;
        while i < self.faces.len() {
            let f = self.faces[i];
            let face = arena.faces[f as usize];
            if SAVE {
                self.saved_faces.push((f, face));
            }
            let first = face.half_edge;
            let mut h = first;
            loop {
                let e = arena.half_edges[h as usize];
                if SAVE {
                    self.saved_half_edges.push((h, e));
                }
                if self.vertex_stamp[e.origin as usize] != self.stamp {
                    self.vertex_stamp[e.origin as usize] = self.stamp;
                    self.vertices.push(e.origin);
                }
                let across = arena.half_edges[e.twin as usize].face;
                if self.face_stamp[across as usize] != self.stamp {
                    self.face_stamp[across as usize] = self.stamp;
                    self.faces.push(across);
                }
                h = e.next;
                if h == first {
                    break;
                }
            }
            i += 1;
        }
    }

    /// The vertices of the surveyed polyhedron.
    pub(crate) fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// Which sides of `s` the surveyed polyhedron reaches: [`Reach::Both`]
    /// exactly when cutting it by `s` is proper.
    pub(crate) fn reach(&self, arena: &ConvexArena, s: &Plane) -> Reach {
        let (mut below, mut above) = (false, false);
        for &v in &self.vertices {
            match classify_vertex(arena.point(v), s) {
                Sign::Negative => below = true,
                Sign::Positive => above = true,
                Sign::Zero => {}
            }
            if below && above {
                return Reach::Both;
            }
        }
        // As a cut decides: no vertex below is above (closed half-spaces).
        if below { Reach::Below } else { Reach::Above }
    }

    /// Saves the records (faces, their half-edges, vertices) of the
    /// surveyed polyhedron, so that [`Survey::restore`] can undo the cuts
    /// that change them in place. Saves nest: the last one is restored or
    /// dropped first.
    pub(crate) fn save(&mut self, arena: &ConvexArena) -> Saved {
        let saved = self.saved_lengths();
        for &f in &self.faces {
            let face = arena.faces[f as usize];
            self.saved_faces.push((f, face));
            let mut h = face.half_edge;
            loop {
                let e = arena.half_edges[h as usize];
                self.saved_half_edges.push((h, e));
                h = e.next;
                if h == face.half_edge {
                    break;
                }
            }
        }
        self.saved_vertices.extend(
            self.vertices
                .iter()
                .map(|&v| (v, arena.vertices[v as usize])),
        );
        saved
    }

    /// Where a save made now starts on the stacks of saved records.
    fn saved_lengths(&self) -> Saved {
        Saved {
            half_edges: self.saved_half_edges.len(),
            vertices: self.saved_vertices.len(),
            faces: self.saved_faces.len(),
        }
    }

    /// Writes the records of `saved` (the last save not yet restored or
    /// dropped) back into `arena`, whose elements added since the save the
    /// caller has released: the polyhedron is again exactly as it was
    /// saved, element for element.
    pub(crate) fn restore(&mut self, arena: &mut ConvexArena, saved: Saved) {
        for &(h, e) in &self.saved_half_edges[saved.half_edges..] {
            arena.half_edges[h as usize] = e;
        }
        for &(v, vertex) in &self.saved_vertices[saved.vertices..] {
            arena.vertices[v as usize] = vertex;
        }
        for &(f, face) in &self.saved_faces[saved.faces..] {
            arena.faces[f as usize] = face;
        }
        self.drop_saved(saved);
    }

    /// Drops the records of `saved` (the last save not yet restored or
    /// dropped).
    pub(crate) fn drop_saved(&mut self, saved: Saved) {
        self.saved_half_edges.truncate(saved.half_edges);
        self.saved_vertices.truncate(saved.vertices);
        self.saved_faces.truncate(saved.faces);
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::convex::NO_TAG;
    use crate::exact::IntPoint;

    /// The saved records of one save, comparable.
    type Records = (
        Vec<(u32, HalfEdge)>,
        Vec<(u32, [u32; 2])>,
        Vec<(u32, [u32; 3])>,
    );

    fn records(survey: &Survey, saved: Saved) -> Records {
        (
            survey.saved_half_edges[saved.half_edges..].to_vec(),
            survey.saved_vertices[saved.vertices..]
                .iter()
                .map(|&(v, x)| (v, [x.point, x.half_edge]))
                .collect(),
            survey.saved_faces[saved.faces..]
                .iter()
                .map(|&(f, x)| (f, [x.plane, x.half_edge, x.tag]))
                .collect(),
        )
    }

    /// One walk surveying and saving lists the same faces and vertices
    /// and saves the same records, in the same order, as a survey and a
    /// save; restoring either save after a cut gives back the cell
    /// element for element.
    #[test]
    fn survey_and_save_is_a_survey_then_a_save() {
        let mut rng = ChaCha8Rng::seed_from_u64(41);
        let mut saves = 0;
        for _ in 0..60 {
            let mut arena = ConvexArena::new();
            let lo = IntPoint::new(-50, -50, -50).unwrap();
            let hi = IntPoint::new(50, 50, 50).unwrap();
            let mut cells = vec![arena.add_box(lo, hi).unwrap()];
            for _ in 0..6 {
                let n = [0; 3].map(|_: i64| rng.random_range(-9..=9));
                if n == [0; 3] {
                    continue;
                }
                let s = Plane::new(n[0], n[1], n[2], rng.random_range(-200..=200)).unwrap();
                let poly = cells.swap_remove(rng.random_range(0..cells.len()));
                match arena.cut(poly, &s, NO_TAG, NO_TAG) {
                    CutOutcome::Split { below, above } => cells.extend([below, above]),
                    CutOutcome::Below | CutOutcome::Above => cells.push(poly),
                }
            }
            for &poly in &cells {
                let (mut one, mut two) = (Survey::default(), Survey::default());
                one.survey(&arena, poly);
                let first = one.save(&arena);
                let second = two.survey_and_save(&arena, poly);
                assert_eq!(one.faces, two.faces);
                assert_eq!(one.vertices(), two.vertices());
                assert_eq!(records(&one, first), records(&two, second));
                // Cut the cell, then undo the cut with the one-walk save.
                let before: Vec<HalfEdge> = arena.half_edges().to_vec();
                let mark = arena.mark();
                let s = Plane::new(1, 2, 3, 0).unwrap();
                if let CutOutcome::Split { .. } = arena.cut(poly, &s, NO_TAG, NO_TAG) {
                    saves += 1;
                    arena.release_to(mark);
                    two.restore(&mut arena, second);
                    assert_eq!(arena.half_edges(), &before[..]);
                    one.survey(&arena, poly);
                    assert_eq!(one.vertices(), two.vertices());
                } else {
                    two.drop_saved(second);
                }
                assert!(two.saved_half_edges.is_empty() && two.saved_faces.is_empty());
            }
        }
        assert!(saves > 20, "{saves}");
    }
}
