//! The invariants of a convex polyhedron, checked exactly.
//!
//! Combinatorial: twins are mutual and reversed, face loops close (at least
//! three edges), every half-edge of a face names that face, vertices point
//! at a half-edge leaving them, vertices and faces name an existing point
//! and plane, and `V − E + F = 2`. Geometric (exact): each
//! vertex lies on the plane of every face around it, strictly inside the
//! plane of every other face, and no two neighbouring faces are coplanar —
//! the polyhedron is strictly convex.

use std::collections::HashSet;

use super::mesh::{ConvexArena, PolyId};
use crate::exact::{Sign, are_planes_parallel, classify_vertex};

/// A broken invariant: always a bug in the kernel, never bad input.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("convex polyhedron invariant broken: {0}")]
pub struct InvariantError(pub String);

macro_rules! ensure {
    ($cond:expr, $($msg:tt)*) => {
        if !$cond {
            return Err(InvariantError(format!($($msg)*)));
        }
    };
}

impl ConvexArena {
    /// Checks every invariant of polyhedron `poly` (cost `O(V·F)`).
    ///
    /// # Errors
    /// The first broken invariant found.
    pub fn validate(&self, poly: PolyId) -> Result<(), InvariantError> {
        let faces = self.faces_of(poly);
        let face_set: HashSet<u32> = faces.iter().copied().collect();
        let mut half_edge_count = 0usize;
        let mut vertex_set = HashSet::new();
        for &f in &faces {
            ensure!(
                (self.faces[f as usize].plane as usize) < self.planes.len(),
                "face {f} names no plane"
            );
        }
        for &f in &faces {
            let mut len = 0;
            for h in self.face_loop(f) {
                len += 1;
                ensure!(len <= self.half_edges.len(), "face {f} does not close");
                let e = self.half_edges[h as usize];
                ensure!(
                    e.face == f,
                    "half-edge {h} in loop of face {f} names face {}",
                    e.face
                );
                let t = self.half_edges[e.twin as usize];
                ensure!(t.twin == h, "twin of twin of {h} is not {h}");
                ensure!(
                    t.origin == self.dest(h),
                    "twin of {h} does not run backwards"
                );
                ensure!(
                    face_set.contains(&t.face),
                    "twin of {h} leaves the polyhedron"
                );
                ensure!(
                    t.face != f,
                    "half-edge {h} and its twin bound the same face"
                );
                let v = &self.vertices[e.origin as usize];
                ensure!(
                    self.half_edges[v.half_edge as usize].origin == e.origin,
                    "vertex {} points at a half-edge that does not leave it",
                    e.origin
                );
                ensure!(
                    face_set.contains(&self.half_edges[v.half_edge as usize].face),
                    "vertex {} points into another polyhedron",
                    e.origin
                );
                ensure!(
                    (v.point as usize) < self.points.len(),
                    "vertex {} names no point",
                    e.origin
                );
                ensure!(
                    classify_vertex(self.point(e.origin), self.face_plane(f)) == Sign::Zero,
                    "vertex {} is not on the plane of face {f}",
                    e.origin
                );
                ensure!(
                    !are_planes_parallel(self.face_plane(f), self.face_plane(t.face)),
                    "neighbouring faces {f} and {} have parallel planes",
                    t.face
                );
                vertex_set.insert(e.origin);
            }
            ensure!(len >= 3, "face {f} has {len} edges");
            half_edge_count += len;
        }
        ensure!(
            half_edge_count.is_multiple_of(2),
            "odd number of half-edges"
        );
        let (v, e, f) = (
            vertex_set.len() as i64,
            half_edge_count as i64 / 2,
            faces.len() as i64,
        );
        ensure!(
            v - e + f == 2,
            "Euler characteristic V − E + F = {v} − {e} + {f} ≠ 2"
        );
        // Strict convexity: each vertex is strictly inside every face plane
        // it is not on.
        for &f in &faces {
            let plane = self.face_plane(f);
            let on_face: HashSet<u32> = self
                .face_loop(f)
                .map(|h| self.half_edges[h as usize].origin)
                .collect();
            for &vtx in &vertex_set {
                if !on_face.contains(&vtx) {
                    ensure!(
                        classify_vertex(self.point(vtx), plane) == Sign::Negative,
                        "vertex {vtx} is not strictly inside face {f}"
                    );
                }
            }
        }
        Ok(())
    }
}
