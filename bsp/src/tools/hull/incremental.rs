//! The incremental construction of a convex hull's triangles.
//!
//! Notation: `orient(a, b, c, d) = (b − a) × (c − a) · (d − a)`, exact in
//! `i128` for coordinates within the budget (`|·| ≤ 6·2^81`); `d` is
//! *visible* from face `(a, b, c)` (counter-clockwise from outside) when
//! `orient(a, b, c, d) > 0`.
//!
//! Points are added one by one to a triangulated hull: the faces a point
//! sees are removed and the horizon is coned to it.

use crate::exact::Plane;

/// The triangulated hull under construction (notation as the module's),
/// with its working memory, reused from one hull to the next.
///
/// Faces live in one list in order of creation; a face seen by a new point
/// is marked dead rather than removed, so the living faces keep the order
/// "kept faces in order, then the new ones" of the textbook construction,
/// and the result does not depend on this bookkeeping.
///
/// Finding the faces a point sees takes time of about their number, not
/// the hull's: the faces a point sees are connected across edges, so a
/// search through neighbours from one of them (a *seed*) finds all of
/// them. The points come in lexicographic order, so after the tetrahedron
/// (from point `late = max(c, d) + 1` on, `c` and `d` its last corners)
/// each point `p` is greater than every point of the hull, and it sees a
/// face at the hull's greatest vertex `p − 1`
/// ([`Incremental::seed_at_previous`]): the seed is among the faces made
/// for `p − 1`. Before, a point may lie inside; each such early point
/// remembers one face it sees (its *conflict*), on that face's list. When
/// a face dies the points of its list are tested against the faces that
/// replace it; one that sees none of them lies inside
/// ([`Incremental::reassign`]), and stays inside as the hull grows.
#[derive(Default)]
pub(super) struct Incremental {
    /// Every face made, living or dead, in order of creation.
    pub(super) faces: Vec<Triangle>,
    /// Per early point, a living face it sees, or [`NONE`] (inside, or
    /// done).
    conflict: Vec<u32>,
    /// Per face, the first point whose conflict it is, or [`NONE`]; per
    /// point, the next point of its conflict's list.
    first_point: Vec<u32>,
    next_point: Vec<u32>,
    /// The faces the current point sees, and the search's stack.
    visible: Vec<u32>,
    stack: Vec<u32>,
    /// Per horizon vertex `u`, the new face `(u, w, p)` starting there.
    new_face_from: Vec<u32>,
}

/// No face.
pub(super) const NONE: u32 = u32::MAX;

impl Incremental {
    /// The hull of `pts` from the tetrahedron `first` (faces
    /// counter-clockwise from outside; its corners `skip`), adding the
    /// other points in order. Afterwards the living faces, in order, are
    /// the hull's triangles.
    pub(super) fn build(&mut self, pts: &[[i64; 3]], first: [[usize; 3]; 4], skip: [usize; 4]) {
        let late = skip.iter().max().map_or(0, |&m| m + 1);
        self.start(pts, first, late);
        self.run(pts, skip, late);
    }

    /// The tetrahedron, and the conflicts of the points before `late`.
    fn start(&mut self, pts: &[[i64; 3]], first: [[usize; 3]; 4], late: usize) {
        // About 2 faces a hull vertex live, 7 made per point added.
        let expected = 8 * pts.len() + 8;
        self.faces.clear();
        self.faces.reserve(expected);
        self.faces
            .extend(first.iter().map(|&f| Triangle::new(f, pts)));
        for f in 0..4 {
            for k in 0..3 {
                let v = self.faces[f].corners;
                let (u, w) = (v[k], v[(k + 1) % 3]);
                self.faces[f].neighbour[k] = (0..4)
                    .find(|&g| g != f && self.edge_slot(g, w, u).is_some())
                    .map_or(NONE, |g| g as u32);
            }
        }
        self.conflict.clear();
        self.first_point.clear();
        self.first_point.reserve(expected);
        self.first_point.extend([NONE; 4]);
        self.next_point.clear();
        self.next_point.resize(pts.len(), NONE);
        for (q, &p) in pts.iter().enumerate().take(late) {
            let c = (0..4u32)
                .find(|&f| self.faces[f as usize].sees(p))
                .unwrap_or(NONE);
            self.conflict.push(c);
            if c != NONE {
                self.add_to_list(q, c);
            }
        }
        self.new_face_from.clear();
        self.new_face_from.resize(pts.len(), NONE);
    }

    /// The slot `k` of face `f` whose edge runs from `u` to `w`.
    fn edge_slot(&self, f: usize, u: usize, w: usize) -> Option<usize> {
        let v = self.faces[f].corners;
        (0..3).find(|&k| v[k] == u && v[(k + 1) % 3] == w)
    }

    /// Adds the points in order (the tetrahedron's corners `skip` are on
    /// the hull already).
    fn run(&mut self, pts: &[[i64; 3]], skip: [usize; 4], late: usize) {
        // The faces made for the point added last, and that point.
        let (mut made, mut last_added) = (0..0, usize::MAX);
        for p in 0..pts.len() {
            if skip.contains(&p) {
                continue;
            }
            let seed = if p < late {
                self.conflict[p]
            } else {
                let at_previous = if last_added == p - 1 {
                    made.clone()
                } else {
                    0..0
                };
                self.seed_at_previous(pts[p], at_previous)
            };
            if seed == NONE {
                continue;
            }
            // Every face `p` sees, in list order.
            self.visible.clear();
            self.stack.clear();
            self.stack.push(seed);
            self.faces[seed as usize].alive = false;
            while let Some(f) = self.stack.pop() {
                self.visible.push(f);
                for g in self.faces[f as usize].neighbour {
                    if self.faces[g as usize].alive && self.faces[g as usize].sees(pts[p]) {
                        self.faces[g as usize].alive = false;
                        self.stack.push(g);
                    }
                }
            }
            self.visible.sort_unstable();
            // Cone the horizon (edges of visible faces across which the
            // neighbour is not visible) to `p`, in the visible faces' order.
            let first_new = self.faces.len() as u32;
            for i in 0..self.visible.len() {
                let f = self.visible[i] as usize;
                let v = self.faces[f].corners;
                for k in 0..3 {
                    let g = self.faces[f].neighbour[k];
                    if !self.faces[g as usize].alive {
                        continue;
                    }
                    let (u, w) = (v[k], v[(k + 1) % 3]);
                    let t = self.faces.len() as u32;
                    let mut new = Triangle::new([u, w, p], pts);
                    new.neighbour[0] = g;
                    self.faces.push(new);
                    if p < late {
                        self.first_point.push(NONE);
                    }
                    // `g` has `f` across the same edge (two faces of a
                    // hull share at most one edge).
                    let across = &mut self.faces[g as usize].neighbour;
                    if let Some(j) = across.iter().position(|&h| h == f as u32) {
                        across[j] = t;
                    }
                    self.new_face_from[u] = t;
                }
            }
            // New faces meet along edges to `p`: face `(u, w, p)` has the
            // face starting at `w` across `(w, p)` (the horizon is one
            // cycle, so one new face starts at each of its vertices).
            for t in first_new..self.faces.len() as u32 {
                let w = self.faces[t as usize].corners[1];
                let s = self.new_face_from[w];
                self.faces[t as usize].neighbour[1] = s;
                self.faces[s as usize].neighbour[2] = t;
            }
            if p < late {
                self.reassign(pts, p, first_new);
            }
            (made, last_added) = (first_new..self.faces.len() as u32, p);
        }
    }

    /// A face the late point `d` sees: one of `at_previous` (the faces at
    /// the vertex `p − 1`, when it was added last), else any.
    ///
    /// Let `v = p − 1`, the greatest point of the hull `H` (a vertex; every
    /// point of `H` is lexicographically at most `v`), and `e = d − v`,
    /// lexicographically positive. Then `v + εe` lies outside `H` for small
    /// `ε > 0`: it is greater than `v` in the first coordinate where `e`
    /// is not zero, and equal before. Near `v`, `H` is the intersection of
    /// the half-spaces below the faces at `v`, so `v + εe` lies strictly
    /// above one of them, `f`; `orient_f` is affine and zero at `v`, so
    /// `d = v + e` lies strictly above `f` too. The scan of every living
    /// face covers the point after a tetrahedron corner (checked in debug
    /// builds to find one).
    fn seed_at_previous(&self, d: [i64; 3], at_previous: std::ops::Range<u32>) -> u32 {
        let sees = |f: &u32| self.faces[*f as usize].alive && self.faces[*f as usize].sees(d);
        let empty = at_previous.is_empty();
        at_previous
            .clone()
            .find(sees)
            .or_else(|| {
                debug_assert!(empty, "a late point sees a face made for the one before");
                (0..self.faces.len() as u32).find(sees)
            })
            .unwrap_or(NONE)
    }

    /// The living faces' corners, in order (tests).
    #[cfg(test)]
    fn living_corners(&self) -> Vec<[usize; 3]> {
        self.faces
            .iter()
            .filter(|f| f.alive)
            .map(|f| f.corners)
            .collect()
    }

    /// Puts point `q` on the list of face `f`.
    fn add_to_list(&mut self, q: usize, f: u32) {
        self.next_point[q] = self.first_point[f as usize];
        self.first_point[f as usize] = q as u32;
    }

    /// New conflicts for the points after `p` whose conflict died (the
    /// points on the lists of the faces `p` sees), among the new faces
    /// (from `first_new` on).
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
        for i in 0..self.visible.len() {
            let f = self.visible[i] as usize;
            let mut q = std::mem::replace(&mut self.first_point[f], NONE);
            while q != NONE {
                let point = q as usize;
                q = self.next_point[point];
                if point == p {
                    continue;
                }
                let faces = &self.faces;
                let found = (first_new..total).find(|&t| faces[t as usize].sees(pts[point]));
                debug_assert!(
                    found.is_some()
                        || !(0..first_new).any(|t| {
                            faces[t as usize].alive && faces[t as usize].sees(pts[point])
                        })
                );
                self.conflict[point] = found.unwrap_or(NONE);
                if let Some(t) = found {
                    self.add_to_list(point, t);
                }
            }
        }
    }
}

/// A hull triangle with its (unnormalised, exact) outward normal, so that
/// testing a point costs one dot product: `orient(a, b, c, d) = n · (d − a)`.
/// In the coordinate budget (`|x| ≤ 2^26`) differences fit 28 bits and the
/// normal's components 56 bits, so both are `i64` and each product is one
/// `64 × 64 → 128` multiply. It keeps its place in the construction
/// (neighbours, whether still on the hull) beside it, so that a step of the
/// construction reads and writes one record per face.
#[derive(Clone, Copy)]
pub(super) struct Triangle {
    /// The corners `a, b, c` (point indices), counter-clockwise from outside.
    pub(super) corners: [usize; 3],
    /// The first corner's coordinates.
    origin: [i64; 3],
    /// `(b − a) × (c − a)`.
    normal: [i64; 3],
    /// `neighbour[k]`: the face across edge `k` (from corner `k` to corner
    /// `k + 1`), or [`NONE`] while not linked yet.
    pub(super) neighbour: [u32; 3],
    /// Whether the face is still on the hull.
    pub(super) alive: bool,
}

impl Triangle {
    /// The triangle on corners `corners` of `pts` (in the budget).
    pub(super) fn new(corners: [usize; 3], pts: &[[i64; 3]]) -> Self {
        let [a, b, c] = corners.map(|i| pts[i]);
        // |b − a|, |c − a| ≤ 2^27: each product ≤ 2^54, each component
        // (a difference of two) ≤ 2^55, all in `i64`.
        let (u, v) = (
            [0, 1, 2].map(|i| b[i] - a[i]),
            [0, 1, 2].map(|i| c[i] - a[i]),
        );
        let normal = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        Self {
            corners,
            origin: a,
            normal,
            neighbour: [NONE; 3],
            alive: true,
        }
    }

    /// `orient(a, b, c, d)`: positive when `d` lies strictly outside.
    #[inline]
    pub(super) fn side(&self, d: [i64; 3]) -> i128 {
        let (n, o) = (self.normal, self.origin);
        // Each product is one `64 × 64 → 128` multiply.
        i128::from(n[0]) * i128::from(d[0] - o[0])
            + i128::from(n[1]) * i128::from(d[1] - o[1])
            + i128::from(n[2]) * i128::from(d[2] - o[2])
    }

    /// Whether `d` lies strictly outside (`orient(a, b, c, d) > 0`).
    #[inline]
    pub(super) fn sees(&self, d: [i64; 3]) -> bool {
        self.side(d) > 0
    }

    /// The supporting plane reduced: [`Plane::normalized`] of
    /// [`Triangle::plane`].
    pub(super) fn reduced_plane(&self) -> Plane {
        Plane::reduced_through(self.normal, self.origin)
    }

    /// The supporting plane, as [`crate::exact::plane_from_points`] of the
    /// corners.
    #[cfg(test)]
    pub(super) fn plane(&self) -> Plane {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::orient::{cross, orient, sub};
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
        let mut fast = Incremental::default();
        fast.build(&pts, first, [a, b, c, d]);
        assert_eq!(
            fast.living_corners(),
            by_scanning(&pts, first, [a, b, c, d]),
            "{pts:?}"
        );
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
