//! The exact convex hull of integer points (incremental construction).
//!
//! Notation: `orient(a, b, c, d) = (b − a) × (c − a) · (d − a)`, exact in
//! `i128` for coordinates within the budget (`|·| ≤ 6·2^81`); `d` is
//! *visible* from face `(a, b, c)` (counter-clockwise from outside) when
//! `orient(a, b, c, d) > 0`.
//!
//! Points are added one by one to a triangulated hull: the faces a point
//! sees are removed and the horizon is coned to it. Finally coplanar
//! neighbouring triangles are merged into convex polygons, vertices in the
//! middle of a straight boundary are dropped, and the result becomes a
//! strictly convex polyhedron of a [`ConvexArena`].

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::orient::{cross, orient, sub};
use crate::exact::{IntPoint, Plane, Point4, plane_from_points};
use crate::word_hash::WordHasher;

/// Adds the convex hull of `points` to `arena` as a strictly convex
/// polyhedron and returns it. Duplicate and interior points are ignored.
///
/// # Errors
/// [`Error::DegenerateHull`] when the points span no volume.
pub fn convex_hull(arena: &mut ConvexArena, points: &[IntPoint]) -> Result<PolyId, Error> {
    let mut pts: Vec<[i64; 3]> = points.iter().map(|p| p.coords()).collect();
    pts.sort_unstable();
    pts.dedup();
    if pts.len() < 4 {
        return Err(Error::DegenerateHull {
            reason: "fewer than four distinct points",
        });
    }
    // An initial tetrahedron: a, b distinct; c off line ab; d off plane abc.
    let (a, b) = (0, 1);
    let c = (2..pts.len())
        .find(|&i| cross(sub(pts[b], pts[a]), sub(pts[i], pts[a])) != [0; 3])
        .ok_or(Error::DegenerateHull {
            reason: "collinear",
        })?;
    let d = (2..pts.len())
        .find(|&i| orient(pts[a], pts[b], pts[c], pts[i]) != 0)
        .ok_or(Error::DegenerateHull { reason: "coplanar" })?;
    // Faces as vertex triples, counter-clockwise from outside.
    let first: [[usize; 3]; 4] = if orient(pts[a], pts[b], pts[c], pts[d]) < 0 {
        [[a, b, c], [a, d, b], [b, d, c], [c, d, a]]
    } else {
        [[a, c, b], [a, b, d], [b, c, d], [c, a, d]]
    };
    let mut faces: Vec<Triangle> = first.iter().map(|&f| Triangle::new(f, &pts)).collect();
    let (mut next_faces, mut visible_edges, mut sorted_edges) =
        (Vec::new(), Vec::new(), Vec::new());
    let mut sees = Vec::new();
    for p in 0..pts.len() {
        if [a, b, c, d].contains(&p) {
            continue;
        }
        sees.clear();
        sees.extend(faces.iter().map(|f| f.sees(pts[p])));
        if !sees.contains(&true) {
            continue;
        }
        // Horizon: directed edges of visible faces whose reverse belongs to
        // a face that is not visible, i.e. is not an edge of a visible face
        // (looked up in a sorted copy; new faces follow the visible faces'
        // order).
        visible_edges.clear();
        next_faces.clear();
        for (f, &seen) in faces.iter().zip(&sees) {
            if seen {
                let v = f.corners;
                visible_edges.extend((0..3).map(|k| (v[k], v[(k + 1) % 3])));
            } else {
                next_faces.push(*f);
            }
        }
        sorted_edges.clear();
        sorted_edges.extend_from_slice(&visible_edges);
        sorted_edges.sort_unstable();
        for &(u, w) in &visible_edges {
            if sorted_edges.binary_search(&(w, u)).is_err() {
                next_faces.push(Triangle::new([u, w, p], &pts));
            }
        }
        std::mem::swap(&mut faces, &mut next_faces);
    }
    let faces: Vec<[usize; 3]> = faces.iter().map(|f| f.corners).collect();
    Ok(build_polyhedron(arena, &pts, &faces))
}

/// A hull triangle with its (unnormalised, exact) outward normal, so that
/// testing a point costs one dot product: `orient(a, b, c, d) = n · (d − a)`.
/// In the coordinate budget (`|x| ≤ 2^26`) differences fit 28 bits and the
/// normal's components 56 bits, so both are `i64` and each product is one
/// `64 × 64 → 128` multiply.
#[derive(Clone, Copy)]
struct Triangle {
    corners: [usize; 3],
    /// The first corner's coordinates.
    origin: [i64; 3],
    /// `(b − a) × (c − a)`.
    normal: [i64; 3],
}

impl Triangle {
    fn new(corners: [usize; 3], pts: &[[i64; 3]]) -> Self {
        let [a, b, c] = corners.map(|i| pts[i]);
        let normal = cross(sub(b, a), sub(c, a))
            .map(|x| i64::try_from(x).expect("in-budget normals fit 56 bits"));
        Self {
            corners,
            origin: a,
            normal,
        }
    }

    /// Whether `d` lies strictly outside (`orient(a, b, c, d) > 0`).
    #[inline]
    fn sees(&self, d: [i64; 3]) -> bool {
        let n = self.normal;
        let w = [0, 1, 2].map(|i| d[i] - self.origin[i]);
        let dot = (0..3)
            .map(|i| i128::from(n[i]) * i128::from(w[i]))
            .sum::<i128>();
        dot > 0
    }
}

/// Merges coplanar neighbouring triangles and adds the polyhedron.
fn build_polyhedron(arena: &mut ConvexArena, pts: &[[i64; 3]], faces: &[[usize; 3]]) -> PolyId {
    let point = |i: usize| IntPoint::from_array(pts[i]).expect("input points are in budget");
    let plane_of = |f: &[usize; 3]| -> Plane {
        plane_from_points(point(f[0]), point(f[1]), point(f[2]))
            .expect("hull triangles are not degenerate")
            .normalized()
    };
    // Group triangles by their (canonical) plane; the boundary of a group is
    // its directed edges whose reverse lies in another group.
    let mut groups: Vec<(Plane, Vec<[usize; 3]>)> = Vec::new();
    let mut group_of_plane: HashMap<Plane, usize, BuildHasherDefault<WordHasher>> =
        HashMap::with_capacity_and_hasher(faces.len(), BuildHasherDefault::default());
    for f in faces {
        let plane = plane_of(f);
        let g = *group_of_plane.entry(plane).or_insert_with(|| {
            groups.push((plane, Vec::new()));
            groups.len() - 1
        });
        groups[g].1.push(*f);
    }
    let mut used: Vec<usize> = Vec::new();
    let mut index_of: HashMap<usize, u32, BuildHasherDefault<WordHasher>> =
        HashMap::with_capacity_and_hasher(pts.len(), BuildHasherDefault::default());
    let mut polygons: Vec<(Plane, Vec<u32>)> = Vec::new();
    let (mut edges, mut boundary) = (Vec::new(), Vec::new());
    for (plane, tris) in &groups {
        edges.clear();
        edges.extend(
            tris.iter()
                .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3]))),
        );
        edges.sort_unstable();
        // The group's boundary, sorted by first vertex: one edge leaves
        // each boundary vertex of a convex polygon.
        boundary.clear();
        boundary.extend(
            edges
                .iter()
                .filter(|&&(u, w)| edges.binary_search(&(w, u)).is_err()),
        );
        let after = |v: usize| -> usize {
            let i = boundary
                .binary_search_by_key(&v, |&(u, _)| u)
                .expect("the boundary is a closed loop");
            boundary[i].1
        };
        // Walk the loop from its smallest vertex, dropping straight-through
        // vertices.
        let start = boundary.first().expect("a face has a boundary").0;
        let mut ring = vec![start];
        let mut v = after(start);
        while v != start {
            ring.push(v);
            v = after(v);
        }
        let n = ring.len();
        let corners: Vec<usize> = (0..n)
            .filter(|&k| {
                let (prev, cur, next) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
                cross(sub(pts[cur], pts[prev]), sub(pts[next], pts[cur])) != [0; 3]
            })
            .map(|k| ring[k])
            .collect();
        let loop_ids = corners
            .iter()
            .map(|&c| {
                *index_of.entry(c).or_insert_with(|| {
                    used.push(c);
                    used.len() as u32 - 1
                })
            })
            .collect();
        polygons.push((*plane, loop_ids));
    }
    let points: Vec<Point4> = used.iter().map(|&i| Point4::from(point(i))).collect();
    arena.add_polyhedron(&points, &polygons)
}
