//! Convex polygons in plane-based form (paper 1 §3.6, inset).
//!
//! Notation: a polygon is its supporting plane `s` (outward) and its edge
//! planes `e_0 … e_{n−1}`, each containing one edge with its positive side
//! outside the polygon within `s`; vertex `k` is the exact meet of `s`,
//! `e_{k−1}` and `e_k`. Splitting by a plane `p` keeps the edges reaching
//! each side and closes each part with `p` (below) or `−p` (above): no new
//! plane is ever constructed, and every vertex stays exact.

use crate::Error;
use crate::exact::{
    IntPoint, Plane, Point4, Sign, classify_vertex, intersect_3_planes, plane_from_points,
};

/// Polygons with at most this many corners are split without allocating
/// working memory.
const SMALL: usize = 32;

/// A convex polygon in plane-based form, with its corners computed once
/// (a split computes only the corners it creates).
#[derive(Clone, Debug)]
pub(crate) struct Polygon {
    pub(crate) support: Plane,
    pub(crate) edges: Vec<Plane>,
    corners: Vec<Point4>,
}

impl Polygon {
    /// The triangle `a, b, c` (counter-clockwise from outside), or `None`
    /// when it is degenerate. Edge `i` runs from corner `i` to corner
    /// `i + 1`; its plane contains the coordinate axis most normal to the
    /// triangle, so its coefficients stay small (`|n| ≤ 2^27`).
    pub(crate) fn triangle(corners: [IntPoint; 3]) -> Result<Option<Self>, Error> {
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
        Ok(Some(Self::new(support, edges)))
    }

    /// The polygon with these planes; its corners are computed.
    pub(crate) fn new(support: Plane, edges: Vec<Plane>) -> Self {
        let n = edges.len();
        let corners = (0..n)
            .map(|k| meet(&support, &edges[(k + n - 1) % n], &edges[k]))
            .collect();
        Self {
            support,
            edges,
            corners,
        }
    }

    /// The polygon with these planes and corners (corner `k` at the meet
    /// of `support`, `edges[k − 1]` and `edges[k]`).
    pub(crate) fn with_corners(support: Plane, edges: Vec<Plane>, corners: Vec<Point4>) -> Self {
        debug_assert_eq!(edges.len(), corners.len());
        Self {
            support,
            edges,
            corners,
        }
    }

    /// The exact corners, in order.
    pub(crate) fn vertices(&self) -> &[Point4] {
        &self.corners
    }

    /// The support, edge planes and corners, taken.
    pub(crate) fn into_parts(self) -> (Plane, Vec<Plane>, Vec<Point4>) {
        (self.support, self.edges, self.corners)
    }

    /// The part on side `keep` (Negative or Positive) of `p`, given the
    /// sides of the vertices; it is closed by `p` oriented outward.
    pub(crate) fn part(&self, sides: &[Sign], p: &Plane, keep: Sign) -> Self {
        let n = self.edges.len();
        let reaches = |k: usize| sides[k] == keep || sides[(k + 1) % n] == keep;
        let closing = if keep == Sign::Negative {
            *p
        } else {
            p.flipped()
        };
        // The boundary leaves the kept side after edge k when the next
        // vertex is strictly across `p`, or on `p` with the next edge going
        // across; that is where `p` closes the part. Each kept edge remembers
        // its index, so corners between two consecutive original edges are
        // reused and only those on `p` are computed.
        let across = -keep;
        let mut edges = Vec::with_capacity(n + 1);
        // The original index of each kept edge (NONE for the closing one),
        // on the stack for the usual small polygon.
        const NONE: usize = usize::MAX;
        let (mut stack, mut heap) = ([NONE; SMALL + 1], Vec::new());
        let origin: &mut [usize] = if n <= SMALL {
            &mut stack
        } else {
            heap.resize(n + 1, NONE);
            &mut heap
        };
        let mut m = 0;
        for k in 0..n {
            if reaches(k) {
                edges.push(self.edges[k]);
                origin[m] = k;
                m += 1;
                let next = (k + 1) % n;
                if sides[next] == across || !reaches(next) {
                    edges.push(closing);
                    origin[m] = NONE;
                    m += 1;
                }
            }
        }
        let corners = (0..m)
            .map(|j| {
                let prev = (j + m - 1) % m;
                match (origin[prev], origin[j]) {
                    (a, b) if a != NONE && b != NONE && b == (a + 1) % n => self.corners[b],
                    _ => meet(&self.support, &edges[prev], &edges[j]),
                }
            })
            .collect();
        Self {
            support: self.support,
            edges,
            corners,
        }
    }

    /// The parts below and above `p`. A polygon lying in `p` goes to the
    /// side its outward normal points to (the region in front of it).
    pub(crate) fn split(self, p: &Plane) -> (Option<Self>, Option<Self>) {
        let n = self.corners.len();
        let (mut stack, mut heap) = ([Sign::Zero; SMALL], Vec::new());
        let sides: &mut [Sign] = if n <= SMALL {
            &mut stack[..n]
        } else {
            heap.resize(n, Sign::Zero);
            &mut heap
        };
        let (mut below, mut above) = (false, false);
        for (side, v) in sides.iter_mut().zip(&self.corners) {
            *side = classify_vertex(v, p);
            below |= *side == Sign::Negative;
            above |= *side == Sign::Positive;
        }
        let sides = &*sides;
        match (below, above) {
            (true, true) => (
                Some(self.part(sides, p, Sign::Negative)),
                Some(self.part(sides, p, Sign::Positive)),
            ),
            (true, false) => (Some(self), None),
            (false, true) => (None, Some(self)),
            (false, false) => {
                // Coplanar: the supports are positive multiples of ±p.
                let same = p
                    .normal()
                    .iter()
                    .zip(self.support.normal())
                    .all(|(a, b)| a.signum() == b.signum());
                if same {
                    (None, Some(self))
                } else {
                    (Some(self), None)
                }
            }
        }
    }
}

/// The corner where the support and two edge planes meet.
fn meet(support: &Plane, a: &Plane, b: &Plane) -> Point4 {
    intersect_3_planes(support, a, b).expect("edge planes meet the support plane in a point")
}
