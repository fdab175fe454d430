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

use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::orient::{cross, orient, sub};
use crate::exact::{IntPoint, Plane, Point4, plane_from_points};

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
    let mut faces: Vec<[usize; 3]> = if orient(pts[a], pts[b], pts[c], pts[d]) < 0 {
        vec![[a, b, c], [a, d, b], [b, d, c], [c, d, a]]
    } else {
        vec![[a, c, b], [a, b, d], [b, c, d], [c, a, d]]
    };
    for p in 0..pts.len() {
        if [a, b, c, d].contains(&p) {
            continue;
        }
        let visible: Vec<bool> = faces
            .iter()
            .map(|f| orient(pts[f[0]], pts[f[1]], pts[f[2]], pts[p]) > 0)
            .collect();
        if !visible.contains(&true) {
            continue;
        }
        // Horizon: directed edges of visible faces whose reverse belongs to
        // a face that is not visible, i.e. is not an edge of a visible face
        // (the visible faces are few: a short list beats a map).
        let visible_edges: Vec<(usize, usize)> = faces
            .iter()
            .zip(&visible)
            .filter(|&(_, &v)| v)
            .flat_map(|(f, _)| (0..3).map(move |k| (f[k], f[(k + 1) % 3])))
            .collect();
        let mut next_faces = Vec::with_capacity(faces.len() + 4);
        for (f, &v) in faces.iter().zip(&visible) {
            if !v {
                next_faces.push(*f);
            }
        }
        for &(u, w) in &visible_edges {
            if !visible_edges.contains(&(w, u)) {
                next_faces.push([u, w, p]);
            }
        }
        faces = next_faces;
    }
    Ok(build_polyhedron(arena, &pts, &faces))
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
    let mut group_of_plane: HashMap<Plane, usize> = HashMap::new();
    for f in faces {
        let plane = plane_of(f);
        let g = *group_of_plane.entry(plane).or_insert_with(|| {
            groups.push((plane, Vec::new()));
            groups.len() - 1
        });
        groups[g].1.push(*f);
    }
    let mut used: Vec<usize> = Vec::new();
    let mut index_of: HashMap<usize, u32> = HashMap::new();
    let mut polygons: Vec<(Plane, Vec<u32>)> = Vec::new();
    for (plane, tris) in &groups {
        let mut edges: HashMap<(usize, usize), ()> = HashMap::new();
        for t in tris {
            for k in 0..3 {
                edges.insert((t[k], t[(k + 1) % 3]), ());
            }
        }
        let boundary: HashMap<usize, usize> = edges
            .keys()
            .filter(|(u, w)| !edges.contains_key(&(*w, *u)))
            .map(|&(u, w)| (u, w))
            .collect();
        // Walk the loop from its smallest vertex, dropping straight-through
        // vertices.
        let start = *boundary.keys().min().expect("a face has a boundary");
        let mut ring = vec![start];
        let mut v = boundary[&start];
        while v != start {
            ring.push(v);
            v = boundary[&v];
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
