//! One part of a polygon split by a plane (paper 1 §3.6), built directly
//! from the sides of its corners: the edges reaching the kept side, closed
//! by the plane; corners between two kept original edges are reused, and
//! only those on the plane are computed.
//!
//! Notation as in the parent module: edge planes `e_k`, corner `k` the
//! meet of `s`, `e_{k−1}` and `e_k`; `p` the splitting plane.

use super::{Polygon, SMALL, meet};
use crate::exact::{Plane, Sign};

impl Polygon {
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
}
