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

/// A convex polygon in plane-based form.
#[derive(Clone, Debug)]
pub(crate) struct Polygon {
    pub(crate) support: Plane,
    pub(crate) edges: Vec<Plane>,
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
        Ok(Some(Self { support, edges }))
    }

    pub(crate) fn vertices(&self) -> Vec<Point4> {
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
        // across; that is where `p` closes the part.
        let across = -keep;
        let mut edges = Vec::with_capacity(n + 1);
        for k in 0..n {
            if reaches(k) {
                edges.push(self.edges[k]);
                let next = (k + 1) % n;
                if sides[next] == across || !reaches(next) {
                    edges.push(closing);
                }
            }
        }
        Self {
            support: self.support,
            edges,
        }
    }

    /// The parts below and above `p`. A polygon lying in `p` goes to the
    /// side its outward normal points to (the region in front of it).
    pub(crate) fn split(self, p: &Plane) -> (Option<Self>, Option<Self>) {
        let sides: Vec<Sign> = self
            .vertices()
            .iter()
            .map(|v| classify_vertex(v, p))
            .collect();
        match (
            sides.contains(&Sign::Negative),
            sides.contains(&Sign::Positive),
        ) {
            (true, true) => (
                Some(self.part(&sides, p, Sign::Negative)),
                Some(self.part(&sides, p, Sign::Positive)),
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
