//! Building a BSP from a closed polygon soup (paper 1 §3.6).
//!
//! Notation: a convex polygon is kept in plane-based form — its supporting
//! plane `s` (outward) and its edge planes `e_0 … e_{n−1}` (each containing
//! one edge, positive side outside the polygon within `s`); vertex `k` is
//! the exact meet of `s`, `e_{k−1}` and `e_k`. Splitting by a plane `p`
//! keeps the edges that reach each side and closes each part with `p` (for
//! the part below) or `−p` (above), so no new plane is ever constructed and
//! every vertex stays exact.
//!
//! Faces are inserted in a seeded random order. At a leaf a face becomes a
//! split by its supporting plane, material below and empty above; at an
//! inner node it descends into the side(s) it reaches, split if it straddles
//! the plane, and is dropped if it lies in the plane.

use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use crate::Error;
use crate::exact::{
    IntPoint, Plane, Point4, Sign, classify_vertex, intersect_3_planes, plane_from_points,
};

/// A convex polygon in plane-based form.
#[derive(Clone, Debug)]
struct Polygon {
    support: Plane,
    edges: Vec<Plane>,
}

impl Polygon {
    /// The triangle `a, b, c` (counter-clockwise from outside), or `None`
    /// when it is degenerate. Edge `i` runs from corner `i` to corner
    /// `i + 1`; its plane contains the coordinate axis most normal to the
    /// triangle, so its coefficients stay small (`|n| ≤ 2^27`).
    fn triangle(corners: [IntPoint; 3]) -> Result<Option<Self>, Error> {
        let Ok(support) = plane_from_points(corners[0], corners[1], corners[2]) else {
            return Ok(None);
        };
        let support = support.normalized();
        let n = support.normal();
        let axis = (0..3).max_by_key(|&i| n[i].unsigned_abs()).unwrap_or(2);
        let mut edges = Vec::with_capacity(3);
        for i in 0..3 {
            let (a, b) = (corners[i].coords(), corners[(i + 1) % 3].coords());
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let mut e = [0i64; 3];
            e[axis] = 1;
            let m = [
                u[1] * e[2] - u[2] * e[1],
                u[2] * e[0] - u[0] * e[2],
                u[0] * e[1] - u[1] * e[0],
            ];
            let d = -(m[0] as i128 * a[0] as i128
                + m[1] as i128 * a[1] as i128
                + m[2] as i128 * a[2] as i128);
            let plane = Plane::new(m[0], m[1], m[2], d)?;
            // Outside is where the third corner is not.
            let plane = if plane.side_of(corners[(i + 2) % 3]) == Sign::Positive {
                plane.flipped()
            } else {
                plane
            };
            edges.push(plane);
        }
        Ok(Some(Self { support, edges }))
    }

    fn vertices(&self) -> Vec<Point4> {
        let n = self.edges.len();
        (0..n)
            .map(|k| {
                intersect_3_planes(&self.support, &self.edges[(k + n - 1) % n], &self.edges[k])
                    .expect("edge planes meet the support plane in a point")
            })
            .collect()
    }

    /// The part on side `keep` (Negative or Positive) of `p`, given the
    /// sides of the vertices; it is closed by `p` oriented outward.
    fn part(&self, sides: &[Sign], p: &Plane, keep: Sign) -> Self {
        let n = self.edges.len();
        let reaches = |k: usize| sides[k] == keep || sides[(k + 1) % n] == keep;
        let closing = if keep == Sign::Negative {
            *p
        } else {
            p.flipped()
        };
        let mut edges = Vec::with_capacity(n + 1);
        for k in 0..n {
            if reaches(k) {
                edges.push(self.edges[k]);
                if !reaches((k + 1) % n) {
                    edges.push(closing);
                }
            }
        }
        Self {
            support: self.support,
            edges,
        }
    }
}

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
        let mut planes: Vec<Plane> = Vec::new();
        let mut nodes = vec![Node::Leaf(EMPTY)];
        for polygon in polygons {
            insert(&mut planes, &mut nodes, polygon, label);
        }
        Ok(Bsp::from_parts(planes, nodes))
    }
}

fn insert(planes: &mut Vec<Plane>, nodes: &mut Vec<Node>, polygon: Polygon, label: Label) {
    let mut stack: Vec<(NodeId, Polygon)> = vec![(0, polygon)];
    while let Some((n, polygon)) = stack.pop() {
        match nodes[n as usize] {
            Node::Leaf(_) => {
                planes.push(polygon.support);
                let below = nodes.len() as NodeId;
                nodes.push(Node::Leaf(label));
                nodes.push(Node::Leaf(EMPTY));
                nodes[n as usize] = Node::Split {
                    plane: planes.len() as u32 - 1,
                    below,
                    above: below + 1,
                };
            }
            Node::Split {
                plane,
                below,
                above,
            } => {
                let p = planes[plane as usize];
                let sides: Vec<Sign> = polygon
                    .vertices()
                    .iter()
                    .map(|v| classify_vertex(v, &p))
                    .collect();
                let (neg, pos) = (
                    sides.contains(&Sign::Negative),
                    sides.contains(&Sign::Positive),
                );
                match (neg, pos) {
                    (false, false) => {} // in the plane: already represented
                    (true, false) => stack.push((below, polygon)),
                    (false, true) => stack.push((above, polygon)),
                    (true, true) => {
                        stack.push((below, polygon.part(&sides, &p, Sign::Negative)));
                        stack.push((above, polygon.part(&sides, &p, Sign::Positive)));
                    }
                }
            }
        }
    }
}
