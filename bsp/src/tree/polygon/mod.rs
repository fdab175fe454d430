//! Convex polygons in plane-based form (paper 1 §3.6, inset).
//!
//! Notation: a polygon is its supporting plane `s` (outward) and its edge
//! planes `e_0 … e_{n−1}`, each containing one edge with its positive side
//! outside the polygon within `s`; vertex `k` is the exact meet of `s`,
//! `e_{k−1}` and `e_k`. Splitting by a plane `p` keeps the edges reaching
//! each side and closes each part with `p` (below) or `−p` (above): no new
//! plane is ever constructed, and every vertex stays exact.
//!
//! - `classify` — which side of a plane a polygon and its corners are on.
//! - `part` — one part, built directly from the sides of the corners.
//! - `layout` — the layout of a part: which original edges it keeps and
//!   where the closing plane goes, shared by the two splits below.
//! - `split` — splitting a polygon it owns, in place where a part fits.
//! - `parts_of` — splitting a polygon read where it lies (a face in a
//!   convex arena), without a copy.
//! - `spare` — the per-thread spare edge and corner buffers.

use std::mem;

use crate::Error;
use crate::exact::{IntPoint, Plane, Point4, Sign, intersect_3_planes, plane_from_points};

mod classify;
mod layout;
mod part;
mod parts_of;
mod spare;
mod split;
#[cfg(test)]
mod tests;

pub(crate) use classify::{Sides, classify_polygon_corners, faces_along, side_of};
pub(crate) use spare::{
    give_back_buffers, give_back_edge_buffers, spare_buffers, spare_edge_buffer,
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
    pub(crate) fn into_parts(mut self) -> (Plane, Vec<Plane>, Vec<Point4>) {
        (
            self.support,
            mem::take(&mut self.edges),
            mem::take(&mut self.corners),
        )
    }
}

impl Drop for Polygon {
    /// Hands the polygon's memory to the spare buffers of this thread.
    fn drop(&mut self) {
        if self.corners.capacity() == 0 {
            return;
        }
        give_back_buffers(mem::take(&mut self.edges), mem::take(&mut self.corners));
    }
}

/// The corner where the support and two edge planes meet.
fn meet(support: &Plane, a: &Plane, b: &Plane) -> Point4 {
    intersect_3_planes(support, a, b).expect("edge planes meet the support plane in a point")
}
