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

/// Working memory of [`Survey`]: index maps from an arena's elements to
/// their copies and the elements of the surveyed polyhedron, reused
/// between surveys (map entries are written before they are read, so they
/// are never cleared).
#[derive(Default)]
pub(crate) struct Survey {
    half_edge_map: Vec<u32>,
    vertex_map: Vec<u32>,
    face_map: Vec<u32>,
    /// The survey that last reached each vertex and face.
    vertex_stamp: Vec<u32>,
    face_stamp: Vec<u32>,
    stamp: u32,
    faces: Vec<u32>,
    vertices: Vec<u32>,
}

impl Survey {
    /// Lists the faces and vertices of `poly` (faces in depth-first order
    /// over their neighbours, vertices as first met).
    pub(crate) fn survey(&mut self, arena: &ConvexArena, poly: PolyId) {
        let (nh, nv, nf) = (
            arena.half_edges.len(),
            arena.vertices.len(),
            arena.faces.len(),
        );
        if self.half_edge_map.len() < nh {
            self.half_edge_map.resize(nh, u32::MAX);
        }
        if self.vertex_map.len() < nv {
            self.vertex_map.resize(nv, u32::MAX);
            self.vertex_stamp.resize(nv, 0);
        }
        if self.face_map.len() < nf {
            self.face_map.resize(nf, u32::MAX);
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
            let first = arena.faces[self.faces[i] as usize].half_edge;
            let mut h = first;
            loop {
                let e = arena.half_edges[h as usize];
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

    /// Appends a copy of the surveyed polyhedron `poly` to `arena` and
    /// returns it: the same faces (planes and tags), loops and vertices, so
    /// that every traversal ([`ConvexArena::faces_of`],
    /// [`ConvexArena::face_loop`]) visits the copy exactly as it visits the
    /// original.
    pub(crate) fn copy(&mut self, arena: &mut ConvexArena, poly: PolyId) -> PolyId {
        let (h0, v0, f0) = (
            arena.half_edges.len() as u32,
            arena.vertices.len() as u32,
            arena.faces.len() as u32,
        );
        for (k, &v) in self.vertices.iter().enumerate() {
            self.vertex_map[v as usize] = v0 + k as u32;
        }
        let mut next = h0;
        for (k, &f) in self.faces.iter().enumerate() {
            self.face_map[f as usize] = f0 + k as u32;
            let first = arena.faces[f as usize].half_edge;
            let mut h = first;
            loop {
                self.half_edge_map[h as usize] = next;
                next += 1;
                h = arena.half_edges[h as usize].next;
                if h == first {
                    break;
                }
            }
        }
        for &v in &self.vertices {
            let vertex = arena.vertices[v as usize];
            arena.vertices.push(Vertex {
                half_edge: self.half_edge_map[vertex.half_edge as usize],
                ..vertex
            });
        }
        for &f in &self.faces {
            let face = arena.faces[f as usize];
            let mut h = face.half_edge;
            loop {
                let e = arena.half_edges[h as usize];
                arena.half_edges.push(HalfEdge {
                    origin: self.vertex_map[e.origin as usize],
                    twin: self.half_edge_map[e.twin as usize],
                    next: self.half_edge_map[e.next as usize],
                    face: self.face_map[e.face as usize],
                });
                h = e.next;
                if h == face.half_edge {
                    break;
                }
            }
            arena.faces.push(Face {
                half_edge: self.half_edge_map[face.half_edge as usize],
                ..face
            });
        }
        debug_assert_eq!(arena.half_edges.len() as u32, next);
        PolyId(self.half_edge_map[poly.0 as usize])
    }
}
