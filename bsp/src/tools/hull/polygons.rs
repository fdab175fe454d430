//! The faces of a triangulated convex hull: coplanar neighbouring
//! triangles merged into convex polygons.
//!
//! Notation: `T` — the hull's living triangles in the construction's order,
//! each with its neighbour across each edge; a *group* — the triangles
//! connected through edges whose two triangles are coplanar (on a convex
//! hull, all the triangles of one plane); its *boundary* — the edges whose
//! neighbour is in another group, one leaving each of its boundary
//! vertices (a convex polygon).
//!
//! Faces are the groups, in the order of their first triangle; each face
//! is its boundary loop from its smallest point index, without vertices in
//! the middle of a straight side, on the plane of its first triangle
//! (normalized); vertices are numbered in order of first appearance. Every
//! step follows the triangles' adjacency, so no list is sorted.

use super::incremental::{Incremental, NONE, Triangle};
use crate::exact::Plane;

/// A convex hull as strictly convex polygons, in the arrays a polyhedron
/// is built from (the order of [`super::convex_hull`]'s faces).
#[derive(Default, Debug)]
pub(crate) struct HullPolygons {
    /// The vertices' coordinates, in order of first appearance.
    pub(crate) vertices: Vec<[i64; 3]>,
    /// Per face, its supporting plane (normalized, positive outside).
    pub(crate) planes: Vec<Plane>,
    /// Face `f`'s corners are `corners[starts[f]..starts[f + 1]]`.
    pub(crate) starts: Vec<u32>,
    /// Vertex indices, counter-clockwise from outside, per face from its
    /// smallest point index.
    pub(crate) corners: Vec<u32>,
    /// Per corner, the face across the side from it to the next corner.
    pub(crate) across: Vec<u32>,
    /// The faces breadth first from face 0, each face's neighbours in the
    /// order of its sides: the order of `ConvexArena::faces_of` for the
    /// polyhedron these arrays make.
    pub(crate) breadth_first: Vec<u32>,
}

impl HullPolygons {
    /// The number of faces.
    pub(crate) fn face_count(&self) -> usize {
        self.planes.len()
    }

    /// The corners of face `f` (vertex indices).
    pub(crate) fn face(&self, f: usize) -> &[u32] {
        &self.corners[self.starts[f] as usize..self.starts[f + 1] as usize]
    }

    /// Per corner of face `f`, the face across the side that starts there.
    #[cfg(test)]
    pub(crate) fn face_across(&self, f: usize) -> &[u32] {
        &self.across[self.starts[f] as usize..self.starts[f + 1] as usize]
    }
}

/// The working memory of [`Merge::polygons`], reused between hulls.
#[derive(Default)]
pub(super) struct Merge {
    /// Per face id of the construction, its group, or [`NONE`].
    group_of: Vec<u32>,
    /// The flood fill's stack of face ids.
    stack: Vec<u32>,
    /// Per point index, the next boundary vertex of the current group and
    /// the triangle across that boundary edge.
    next_on_boundary: Vec<u32>,
    triangle_across: Vec<u32>,
    /// The current group's boundary loop (point indices).
    ring: Vec<u32>,
    /// Per point index, its vertex index, or [`NONE`].
    vertex_of: Vec<u32>,
    /// Per corner, the triangle across its side (resolved to a face last).
    across_triangle: Vec<u32>,
    /// Breadth-first search: seen faces.
    seen: Vec<bool>,
}

impl Merge {
    /// The polygons of the living faces of `hull` over `pts`, into `out`.
    pub(super) fn polygons(
        &mut self,
        pts: &[[i64; 3]],
        hull: &Incremental,
        out: &mut HullPolygons,
    ) {
        let faces = &hull.faces;
        out.vertices.clear();
        out.planes.clear();
        out.starts.clear();
        out.corners.clear();
        out.across.clear();
        self.across_triangle.clear();
        self.group_of.clear();
        self.group_of.resize(faces.len(), NONE);
        self.next_on_boundary.clear();
        self.next_on_boundary.resize(pts.len(), NONE);
        self.triangle_across.clear();
        self.triangle_across.resize(pts.len(), NONE);
        self.vertex_of.clear();
        self.vertex_of.resize(pts.len(), NONE);
        out.starts.push(0);
        for first in 0..faces.len() {
            if !faces[first].alive || self.group_of[first] != NONE {
                continue;
            }
            let group = out.planes.len() as u32;
            out.planes.push(faces[first].reduced_plane());
            // The group by flood fill; its boundary edges as links.
            let (mut start, mut joined) = (usize::MAX, 0);
            self.group_of[first] = group;
            self.stack.clear();
            self.stack.push(first as u32);
            while let Some(t) = self.stack.pop() {
                let t = t as usize;
                let v = faces[t].corners;
                for k in 0..3 {
                    let s = faces[t].neighbour[k];
                    if self.group_of[s as usize] == group {
                        continue;
                    }
                    if self.group_of[s as usize] == NONE
                        && coplanar_across(pts, &faces[t], &faces[s as usize], v[k], v[(k + 1) % 3])
                    {
                        self.group_of[s as usize] = group;
                        self.stack.push(s);
                        joined += 1;
                    } else {
                        self.next_on_boundary[v[k]] = v[(k + 1) % 3] as u32;
                        self.triangle_across[v[k]] = s;
                        start = start.min(v[k]);
                    }
                }
            }
            if joined == 0 {
                // A lone triangle: its corners from the smallest.
                let (v, across) = (faces[first].corners, faces[first].neighbour);
                let k0 = if v[0] < v[1] { 0 } else { 1 };
                let k0 = if v[2] < v[k0] { 2 } else { k0 };
                for k in [k0, (k0 + 1) % 3, (k0 + 2) % 3] {
                    self.push_corner(pts, v[k], across[k], out);
                }
                out.starts.push(out.corners.len() as u32);
                continue;
            }
            // The boundary loop from its smallest point.
            self.ring.clear();
            let mut u = start;
            loop {
                self.ring.push(u as u32);
                u = self.next_on_boundary[u] as usize;
                if u == start {
                    break;
                }
            }
            let n = self.ring.len();
            let mut prev = self.ring[n - 1] as usize;
            for k in 0..n {
                let cur = self.ring[k] as usize;
                let next = self.ring[if k + 1 < n { k + 1 } else { 0 }] as usize;
                let straight = collinear(pts[prev], pts[cur], pts[next]);
                prev = cur;
                if straight {
                    continue;
                }
                // The side from `cur` to the next kept corner lies along
                // one neighbouring face: the one across its first edge.
                self.push_corner(pts, cur, self.triangle_across[cur], out);
            }
            out.starts.push(out.corners.len() as u32);
        }
        out.across.extend(
            self.across_triangle
                .iter()
                .map(|&t| self.group_of[t as usize]),
        );
        self.breadth_first(out);
    }

    /// Adds point `p` as the next corner of the current face, with the
    /// triangle across the side that starts there.
    fn push_corner(&mut self, pts: &[[i64; 3]], p: usize, across: u32, out: &mut HullPolygons) {
        if self.vertex_of[p] == NONE {
            self.vertex_of[p] = out.vertices.len() as u32;
            out.vertices.push(pts[p]);
        }
        out.corners.push(self.vertex_of[p]);
        self.across_triangle.push(across);
    }

    /// [`HullPolygons::breadth_first`]: from face 0, the neighbours of
    /// each face in the order of its sides, each face once.
    fn breadth_first(&mut self, out: &mut HullPolygons) {
        let HullPolygons {
            breadth_first: order,
            ..
        } = out;
        order.clear();
        self.seen.clear();
        self.seen.resize(out.planes.len(), false);
        order.push(0);
        self.seen[0] = true;
        let mut i = 0;
        while i < order.len() {
            let f = order[i] as usize;
            let sides = out.starts[f] as usize..out.starts[f + 1] as usize;
            for &g in &out.across[sides] {
                if !self.seen[g as usize] {
                    self.seen[g as usize] = true;
                    order.push(g);
                }
            }
            i += 1;
        }
    }
}

/// Whether triangle `s`, across the edge `(u, w)` of `t`, lies in `t`'s
/// plane: its corner off that edge has `orient = 0`.
fn coplanar_across(pts: &[[i64; 3]], t: &Triangle, s: &Triangle, u: usize, w: usize) -> bool {
    let far = s
        .corners
        .into_iter()
        .find(|&k| k != u && k != w)
        .unwrap_or(u);
    t.side(pts[far]) == 0
}

/// Whether `cur` lies on the line through `prev` and `next` (on a convex
/// polygon's boundary: in the middle of a straight side).
fn collinear(prev: [i64; 3], cur: [i64; 3], next: [i64; 3]) -> bool {
    // Differences < 2^28, products < 2^56: exact in `i64`.
    let u = [0, 1, 2].map(|i| cur[i] - prev[i]);
    let v = [0, 1, 2].map(|i| next[i] - cur[i]);
    u[1] * v[2] == u[2] * v[1] && u[2] * v[0] == u[0] * v[2] && u[0] * v[1] == u[1] * v[0]
}
