//! Building a BSP from a closed polygon soup (paper 1 §3.6).
//!
//! Faces are convex polygons in plane-based form (`tree/polygon/`), so
//! splitting them is exact and constructs no new plane.
//!
//! Faces are inserted in a seeded random order. At a leaf a face becomes a
//! split by its supporting plane, material below and empty above; at an
//! inner node it descends into the side(s) it reaches, split if it straddles
//! the plane, and is dropped if it lies in the plane.

use super::boundary::BoundaryFace;
use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use super::polygon::{Polygon, Sides, classify_polygon_corners};
use crate::Error;
use crate::exact::{IntPoint, Plane};

/// Deterministic shuffle (xorshift64*), so imports are reproducible.
fn shuffle<T>(items: &mut [T], seed: u64) {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for i in (1..items.len()).rev() {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        let j = (state.wrapping_mul(0x2545_F491_4F6C_DD1D) % (i as u64 + 1)) as usize;
        items.swap(i, j);
    }
}

impl Bsp {
    /// The solid bounded by a closed, consistently oriented (outward,
    /// counter-clockwise) triangle soup, labelled `label`; faces are
    /// inserted in an order shuffled by `seed`. Degenerate triangles are
    /// skipped.
    ///
    /// # Errors
    /// Out-of-budget coordinates (the points are checked by [`IntPoint`]).
    pub fn from_triangles(
        triangles: &[[IntPoint; 3]],
        label: Label,
        seed: u64,
    ) -> Result<Bsp, Error> {
        let mut polygons = Vec::with_capacity(triangles.len());
        for t in triangles {
            if let Some(p) = Polygon::triangle(*t)? {
                polygons.push(p);
            }
        }
        shuffle(&mut polygons, seed);
        let mut tree = Builder::default();
        for polygon in polygons {
            tree.insert(polygon, label, EMPTY);
        }
        Ok(tree.finish())
    }
}

impl Bsp {
    /// A BSP from convex polygons with the labels behind and in front of
    /// each, inserted in an order shuffled by `seed`.
    pub(crate) fn from_polygons(mut polygons: Vec<(Polygon, Label, Label)>, seed: u64) -> Bsp {
        shuffle(&mut polygons, seed);
        let mut tree = Builder::default();
        for (polygon, behind, in_front) in polygons {
            tree.insert(polygon, behind, in_front);
        }
        tree.finish()
    }

    /// [`Bsp::from_polygons`] of the faces' polygons with their labels
    /// (behind, in front), the same tree, when it has at most `max_splits`
    /// splits, else `None`: the tree only grows as faces are inserted, so
    /// the building stops as soon as it has more. A face is read in place
    /// until it must be split, so a face that reaches a leaf whole is never
    /// copied.
    pub(crate) fn from_faces_within<'a>(
        faces: impl Iterator<Item = &'a BoundaryFace>,
        seed: u64,
        max_splits: usize,
    ) -> Option<Bsp> {
        let mut faces: Vec<&BoundaryFace> = faces.collect();
        shuffle(&mut faces, seed);
        let mut tree = Builder::default();
        for face in faces {
            tree.insert_face(face);
            if tree.splits() > max_splits {
                return None;
            }
        }
        Some(tree.finish())
    }
}

/// A tree being built face by face, with working memory reused between
/// faces.
struct Builder {
    planes: Vec<Plane>,
    nodes: Vec<Node>,
    stack: Vec<(NodeId, Polygon)>,
    sides: Sides,
}

/// Room reserved in a new builder for planes (twice as many nodes): the
/// tree's vectors then skip their smallest sizes, which nearly every
/// rebuild outgrows, and end with the capacity they would have grown to.
const FIRST_PLANES: usize = 8;

impl Default for Builder {
    fn default() -> Self {
        let mut nodes = Vec::with_capacity(2 * FIRST_PLANES);
        nodes.push(Node::Leaf(EMPTY));
        Self {
            planes: Vec::with_capacity(FIRST_PLANES),
            nodes,
            stack: Vec::new(),
            sides: Sides::default(),
        }
    }
}

impl Builder {
    fn finish(self) -> Bsp {
        Bsp::from_parts(self.planes, self.nodes)
    }

    /// The number of splits so far (each adds two nodes to the root).
    fn splits(&self) -> usize {
        self.nodes.len() / 2
    }

    /// [`Builder::insert`] of the face's polygon, with the face's labels:
    /// the face is followed in place down to the leaf it reaches, or to the
    /// first split it straddles, where its polygon goes on from.
    fn insert_face(&mut self, face: &BoundaryFace) {
        let (behind, in_front) = (face.label, face.outside);
        let mut n = 0;
        loop {
            match self.nodes[n as usize] {
                Node::Leaf(_) => {
                    self.planes.push(face.plane);
                    let plane = self.planes.len() as u32 - 1;
                    self.make_split(n, plane, behind, in_front);
                    return;
                }
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let p = &self.planes[plane as usize];
                    let sides = self.sides.for_corners(face.vertices.len());
                    n = match classify_polygon_corners(
                        &face.plane,
                        &face.edges,
                        &face.vertices,
                        p,
                        sides,
                    ) {
                        (false, false) => return, // in the plane: already represented
                        (true, false) => below,
                        (false, true) => above,
                        (true, true) => {
                            self.insert_at(n, face.polygon(), behind, in_front);
                            return;
                        }
                    };
                }
            }
        }
    }

    /// Turns leaf `n` into a split by palette entry `plane` with new leaves
    /// `behind` below and `in_front` above.
    fn make_split(&mut self, n: NodeId, plane: u32, behind: Label, in_front: Label) {
        let below = self.nodes.len() as NodeId;
        self.nodes.push(Node::Leaf(behind));
        self.nodes.push(Node::Leaf(in_front));
        self.nodes[n as usize] = Node::Split {
            plane,
            below,
            above: below + 1,
        };
    }

    /// Inserts one face: where it reaches a leaf, that leaf becomes a split
    /// by the face's plane with `behind` below and `in_front` above.
    fn insert(&mut self, polygon: Polygon, behind: Label, in_front: Label) {
        self.insert_at(0, polygon, behind, in_front);
    }

    /// [`Builder::insert`] of a face that reaches node `start` whole.
    fn insert_at(&mut self, start: NodeId, polygon: Polygon, behind: Label, in_front: Label) {
        let Self {
            planes,
            nodes,
            stack,
            sides,
        } = self;
        // Every piece of the face shares its plane: one palette entry.
        let mut palette_index = None;
        // A piece that is not split goes on without passing through the
        // stack; of two parts, the one above goes first.
        let mut current = Some((start, polygon));
        while let Some((n, polygon)) = current.take().or_else(|| stack.pop()) {
            match nodes[n as usize] {
                Node::Leaf(_) => {
                    let plane = *palette_index.get_or_insert_with(|| {
                        planes.push(polygon.support);
                        planes.len() as u32 - 1
                    });
                    let below = nodes.len() as NodeId;
                    nodes.push(Node::Leaf(behind));
                    nodes.push(Node::Leaf(in_front));
                    nodes[n as usize] = Node::Split {
                        plane,
                        below,
                        above: below + 1,
                    };
                }
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let p = &planes[plane as usize];
                    let sides = sides.for_corners(polygon.vertices().len());
                    let (support, edges) = (&polygon.support, &polygon.edges);
                    match classify_polygon_corners(support, edges, polygon.vertices(), p, sides) {
                        (false, false) => {} // in the plane: already represented
                        (true, false) => current = Some((below, polygon)),
                        (false, true) => current = Some((above, polygon)),
                        (true, true) => {
                            let (b, a) = polygon.split_straddling(sides, p);
                            stack.push((below, b));
                            current = Some((above, a));
                        }
                    }
                }
            }
        }
    }
}
