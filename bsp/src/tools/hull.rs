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

use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::orient::{cross, orient, sub};
use crate::exact::{IntPoint, Plane, Point4};

/// The most distinct points of one convex hull. The incremental hull takes
/// time of about points × faces, and an edit with a tool of `F` faces about
/// `F²` (each cell it crosses is tested against every face): a hull of
/// 4,500 points on a sphere (9,000 faces) carves a block in about 20 s on
/// one core, with memory linear in the faces (the octree splits a cell
/// crossed by many faces before merging the tool into it).
pub const MAX_HULL_POINTS: usize = 8192;

/// Adds the convex hull of `points` to `arena` as a strictly convex
/// polyhedron and returns it. Duplicate and interior points are ignored.
///
/// # Errors
/// [`Error::DegenerateHull`] when the points span no volume,
/// [`Error::TooManyHullPoints`] for more than [`MAX_HULL_POINTS`]
/// distinct points.
pub fn convex_hull(arena: &mut ConvexArena, points: &[IntPoint]) -> Result<PolyId, Error> {
    let mut pts: Vec<[i64; 3]> = points.iter().map(|p| p.coords()).collect();
    pts.sort_unstable();
    pts.dedup();
    if pts.len() > MAX_HULL_POINTS {
        return Err(Error::TooManyHullPoints {
            points: pts.len(),
            limit: MAX_HULL_POINTS,
        });
    }
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
    let faces = Incremental::new(&pts, first).run(&pts, [a, b, c, d]);
    Ok(build_polyhedron(arena, &pts, &faces))
}

/// The triangulated hull under construction (notation as the module's).
///
/// Faces live in one list in order of creation; a face seen by a new point
/// is marked dead rather than removed, so the living faces keep the order
/// "kept faces in order, then the new ones" of the textbook construction,
/// and the result does not depend on this bookkeeping.
///
/// Finding the faces a point sees takes time of about their number, not
/// the hull's: every point yet to come remembers one face it sees (its
/// *conflict*); the faces it sees are connected across edges, so a search
/// through neighbours from the conflict finds all of them. When a point's
/// conflict dies it is tested against the faces that replace it; if it
/// sees none of them it lies inside ([`Incremental::reassign`]), and stays
/// inside as the hull grows.
struct Incremental {
    faces: Vec<Triangle>,
    /// Whether each face is still on the hull.
    alive: Vec<bool>,
    /// `neighbour[f][k]`: the face across edge `k` of `f` (edge `k` runs
    /// from corner `k` to corner `k + 1`).
    neighbour: Vec<[u32; 3]>,
    /// Per point, a living face it sees, or [`NONE`] (inside, or done).
    conflict: Vec<u32>,
}

/// No face.
const NONE: u32 = u32::MAX;

impl Incremental {
    fn new(pts: &[[i64; 3]], first: [[usize; 3]; 4]) -> Self {
        let faces: Vec<Triangle> = first.iter().map(|&f| Triangle::new(f, pts)).collect();
        let mut hull = Self {
            alive: vec![true; 4],
            neighbour: vec![[NONE; 3]; 4],
            conflict: vec![NONE; pts.len()],
            faces,
        };
        for f in 0..4 {
            for k in 0..3 {
                let v = hull.faces[f].corners;
                let (u, w) = (v[k], v[(k + 1) % 3]);
                hull.neighbour[f][k] = (0..4)
                    .find(|&g| g != f && hull.edge_slot(g, w, u).is_some())
                    .map_or(NONE, |g| g as u32);
            }
        }
        for (q, p) in pts.iter().enumerate() {
            hull.conflict[q] = (0..4u32)
                .find(|&f| hull.faces[f as usize].sees(*p))
                .unwrap_or(NONE);
        }
        hull
    }

    /// The slot `k` of face `f` whose edge runs from `u` to `w`.
    fn edge_slot(&self, f: usize, u: usize, w: usize) -> Option<usize> {
        let v = self.faces[f].corners;
        (0..3).find(|&k| v[k] == u && v[(k + 1) % 3] == w)
    }

    /// Adds the points in order (the tetrahedron's corners `skip` are on
    /// the hull already) and returns the living faces in order.
    fn run(mut self, pts: &[[i64; 3]], skip: [usize; 4]) -> Vec<Triangle> {
        let (mut visible, mut stack, mut starts) = (Vec::new(), Vec::new(), Vec::new());
        for p in 0..pts.len() {
            if skip.contains(&p) {
                continue;
            }
            let seed = self.conflict[p];
            if seed == NONE {
                continue;
            }
            // Every face `p` sees, in list order.
            visible.clear();
            stack.clear();
            stack.push(seed);
            self.alive[seed as usize] = false;
            while let Some(f) = stack.pop() {
                visible.push(f);
                for g in self.neighbour[f as usize] {
                    if self.alive[g as usize] && self.faces[g as usize].sees(pts[p]) {
                        self.alive[g as usize] = false;
                        stack.push(g);
                    }
                }
            }
            visible.sort_unstable();
            // Cone the horizon (edges of visible faces across which the
            // neighbour is not visible) to `p`, in the visible faces' order.
            let first_new = self.faces.len() as u32;
            starts.clear();
            for &f in &visible {
                let v = self.faces[f as usize].corners;
                for k in 0..3 {
                    let g = self.neighbour[f as usize][k];
                    if !self.alive[g as usize] {
                        continue;
                    }
                    let (u, w) = (v[k], v[(k + 1) % 3]);
                    let t = self.faces.len() as u32;
                    self.faces.push(Triangle::new([u, w, p], pts));
                    self.alive.push(true);
                    self.neighbour.push([g, NONE, NONE]);
                    if let Some(j) = self.edge_slot(g as usize, w, u) {
                        self.neighbour[g as usize][j] = t;
                    }
                    starts.push((u, t));
                }
            }
            // New faces meet along edges to `p`: face `(u, w, p)` has the
            // face starting at `w` across `(w, p)`.
            starts.sort_unstable();
            for i in 0..starts.len() {
                let (_, t) = starts[i];
                let w = self.faces[t as usize].corners[1];
                if let Ok(j) = starts.binary_search_by_key(&w, |&(u, _)| u) {
                    let s = starts[j].1;
                    self.neighbour[t as usize][1] = s;
                    self.neighbour[s as usize][2] = t;
                }
            }
            self.reassign(pts, p, first_new);
        }
        self.faces
            .iter()
            .zip(&self.alive)
            .filter(|&(_, &alive)| alive)
            .map(|(f, _)| *f)
            .collect()
    }

    /// New conflicts for the points after `p` whose conflict died, among
    /// the new faces (from `first_new` on).
    ///
    /// A point `q` that sees a face `f` seen by `p`, but none of the new
    /// faces, lies in the new hull `H' = conv(H ∪ {p})`: the segment from
    /// `p` to `q` lies strictly above `f`, hence outside `H`, and below or
    /// on every new face (they all pass through `p`). Near its vertex `p`,
    /// `H'` is the cone of the new faces, so the segment starts inside
    /// `H'`; were `q` outside, it would leave `H'` through a kept face `g`
    /// with `p` strictly below it (an affine function zero at `p` and at
    /// the exit would be zero all along), and `H' ∩ plane(g)` lies in `H`.
    /// So no other face needs testing (checked in debug builds).
    fn reassign(&mut self, pts: &[[i64; 3]], p: usize, first_new: u32) {
        let total = self.faces.len() as u32;
        let (faces, alive) = (&self.faces, &self.alive);
        for (q, c) in pts.iter().zip(self.conflict.iter_mut()).skip(p + 1) {
            if *c == NONE || alive[*c as usize] {
                continue;
            }
            let seen = |f: &u32| alive[*f as usize] && faces[*f as usize].sees(*q);
            let found = (first_new..total).find(seen);
            debug_assert!(found.is_some() || !(0..first_new).any(|f| seen(&f)));
            *c = found.unwrap_or(NONE);
        }
    }
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

    /// `orient(a, b, c, d)`: positive when `d` lies strictly outside.
    #[inline]
    fn side(&self, d: [i64; 3]) -> i128 {
        let n = self.normal;
        let w = [0, 1, 2].map(|i| d[i] - self.origin[i]);
        (0..3)
            .map(|i| i128::from(n[i]) * i128::from(w[i]))
            .sum::<i128>()
    }

    /// Whether `d` lies strictly outside (`orient(a, b, c, d) > 0`).
    #[inline]
    fn sees(&self, d: [i64; 3]) -> bool {
        self.side(d) > 0
    }

    /// The supporting plane, as [`crate::exact::plane_from_points`] of the
    /// corners.
    fn plane(&self) -> Plane {
        let [a, b, c] = self.normal;
        let [x, y, z] = self.origin.map(i128::from);
        Plane::new_unchecked(
            a,
            b,
            c,
            -(i128::from(a) * x + i128::from(b) * y + i128::from(c) * z),
        )
    }
}

/// Merges coplanar neighbouring triangles and adds the polyhedron.
///
/// Faces are the groups of coplanar triangles (connected on a convex
/// hull), in the order of their first triangle; each face's corners run
/// from its smallest vertex index, and vertices are numbered in order of
/// first appearance.
fn build_polyhedron(arena: &mut ConvexArena, pts: &[[i64; 3]], faces: &[Triangle]) -> PolyId {
    let groups = coplanar_groups(pts, faces);
    let mut index_of = vec![u32::MAX; pts.len()];
    let mut used: Vec<usize> = Vec::new();
    let mut polygons: Vec<(Plane, Vec<u32>)> = Vec::with_capacity(groups.len());
    let (mut edges, mut boundary) = (Vec::new(), Vec::new());
    for group in &groups {
        let first = &faces[group[0]];
        let corners: Vec<usize> = if let [_] = group[..] {
            // One triangle: its corners from the smallest.
            let v = first.corners;
            let k = (0..3).min_by_key(|&k| v[k]).unwrap_or(0);
            vec![v[k], v[(k + 1) % 3], v[(k + 2) % 3]]
        } else {
            boundary_loop(pts, faces, group, &mut edges, &mut boundary)
        };
        let loop_ids = corners
            .iter()
            .map(|&c| {
                if index_of[c] == u32::MAX {
                    index_of[c] = used.len() as u32;
                    used.push(c);
                }
                index_of[c]
            })
            .collect();
        polygons.push((first.plane().normalized(), loop_ids));
    }
    let points: Vec<Point4> = used
        .iter()
        .map(|&i| Point4::from(IntPoint::from_array(pts[i]).expect("input points are in budget")))
        .collect();
    arena.add_polyhedron(&points, &polygons)
}

/// The triangles grouped by supporting plane (indices into `faces`), in
/// order of each group's first triangle: neighbours across an edge are
/// joined when the one's far corner lies in the other's plane.
fn coplanar_groups(pts: &[[i64; 3]], faces: &[Triangle]) -> Vec<Vec<usize>> {
    // Directed edges (from, to, triangle), sorted: the neighbour across
    // `(u, w)` holds `(w, u)`.
    let mut ends: Vec<(usize, usize, usize)> = faces
        .iter()
        .enumerate()
        .flat_map(|(t, f)| {
            let v = f.corners;
            [(v[0], v[1], t), (v[1], v[2], t), (v[2], v[0], t)]
        })
        .collect();
    ends.sort_unstable();
    let mut root: Vec<usize> = (0..faces.len()).collect();
    fn find(root: &mut [usize], mut t: usize) -> usize {
        while root[t] != t {
            root[t] = root[root[t]];
            t = root[t];
        }
        t
    }
    for &(u, w, t) in &ends {
        if u > w {
            continue; // each undirected edge once
        }
        let i = ends.partition_point(|&(x, y, _)| (x, y) < (w, u));
        let Some(&(_, _, s)) = ends.get(i).filter(|&&(x, y, _)| (x, y) == (w, u)) else {
            continue;
        };
        let far = faces[s]
            .corners
            .into_iter()
            .find(|&k| k != u && k != w)
            .unwrap_or(u);
        if faces[t].side(pts[far]) == 0 {
            let (rt, rs) = (find(&mut root, t), find(&mut root, s));
            root[rt.max(rs)] = rt.min(rs);
        }
    }
    let mut group_of = vec![usize::MAX; faces.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for t in 0..faces.len() {
        let r = find(&mut root, t);
        if group_of[r] == usize::MAX {
            group_of[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of[r]].push(t);
    }
    groups
}

/// The corners of a group of coplanar triangles: its boundary loop from
/// its smallest vertex, without vertices in the middle of a straight side.
fn boundary_loop(
    pts: &[[i64; 3]],
    faces: &[Triangle],
    group: &[usize],
    edges: &mut Vec<(usize, usize)>,
    boundary: &mut Vec<(usize, usize)>,
) -> Vec<usize> {
    edges.clear();
    edges.extend(group.iter().flat_map(|&t| {
        let v = faces[t].corners;
        [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])]
    }));
    edges.sort_unstable();
    // The group's boundary, sorted by first vertex: one edge leaves each
    // boundary vertex of a convex polygon.
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
    let start = boundary.first().expect("a face has a boundary").0;
    let mut ring = vec![start];
    let mut v = after(start);
    while v != start {
        ring.push(v);
        v = after(v);
    }
    let n = ring.len();
    (0..n)
        .filter(|&k| {
            let (prev, cur, next) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
            cross(sub(pts[cur], pts[prev]), sub(pts[next], pts[cur])) != [0; 3]
        })
        .map(|k| ring[k])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The textbook construction the conflict search replaces: every point
    /// tested against every face, the horizon found by a scan of the
    /// visible faces' edges.
    fn by_scanning(pts: &[[i64; 3]], first: [[usize; 3]; 4], skip: [usize; 4]) -> Vec<[usize; 3]> {
        let mut faces: Vec<Triangle> = first.iter().map(|&f| Triangle::new(f, pts)).collect();
        for p in 0..pts.len() {
            if skip.contains(&p) {
                continue;
            }
            let (mut next, mut edges) = (Vec::new(), Vec::new());
            for f in &faces {
                if f.sees(pts[p]) {
                    let v = f.corners;
                    edges.extend([(v[0], v[1]), (v[1], v[2]), (v[2], v[0])]);
                } else {
                    next.push(*f);
                }
            }
            for &(u, w) in &edges {
                if !edges.contains(&(w, u)) {
                    next.push(Triangle::new([u, w, p], pts));
                }
            }
            faces = next;
        }
        faces.iter().map(|f| f.corners).collect()
    }

    /// Both constructions on `pts` (sorted, distinct, spanning a volume).
    fn same_triangles(mut pts: Vec<[i64; 3]>) {
        pts.sort_unstable();
        pts.dedup();
        let (a, b) = (0, 1);
        let Some(c) =
            (2..pts.len()).find(|&i| cross(sub(pts[b], pts[a]), sub(pts[i], pts[a])) != [0; 3])
        else {
            return;
        };
        let Some(d) = (2..pts.len()).find(|&i| orient(pts[a], pts[b], pts[c], pts[i]) != 0) else {
            return;
        };
        let first: [[usize; 3]; 4] = if orient(pts[a], pts[b], pts[c], pts[d]) < 0 {
            [[a, b, c], [a, d, b], [b, d, c], [c, d, a]]
        } else {
            [[a, c, b], [a, b, d], [b, c, d], [c, a, d]]
        };
        let fast: Vec<[usize; 3]> = Incremental::new(&pts, first)
            .run(&pts, [a, b, c, d])
            .iter()
            .map(|f| f.corners)
            .collect();
        assert_eq!(fast, by_scanning(&pts, first, [a, b, c, d]), "{pts:?}");
    }

    #[test]
    fn conflicts_give_the_triangles_of_the_scan_in_its_order() {
        let mut rng = ChaCha8Rng::seed_from_u64(24);
        for round in 0..300 {
            let n = rng.random_range(4..90);
            // Small grids (many coplanar and collinear points), spheres
            // and wide random clouds.
            let pts: Vec<[i64; 3]> = match round % 3 {
                0 => (0..n)
                    .map(|_| [0; 3].map(|_| rng.random_range(-3..=3)))
                    .collect(),
                1 => (0..n)
                    .map(|_| {
                        let (u, v): (f64, f64) = (rng.random(), rng.random());
                        let (t, z) = (u * std::f64::consts::TAU, 2.0 * v - 1.0);
                        let r = (1.0 - z * z).sqrt() * 1e6;
                        [r * t.cos(), r * t.sin(), z * 1e6].map(|x| x.round() as i64)
                    })
                    .collect(),
                _ => (0..n)
                    .map(|_| [0; 3].map(|_| rng.random_range(-(1 << 26)..=1 << 26)))
                    .collect(),
            };
            same_triangles(pts);
        }
    }
}
