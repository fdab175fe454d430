//! The surface around a vertex as exact wedges: what smooth shading needs
//! to give one normal per point and plane, however polygons, pieces and
//! octree cells split the surface there.
//!
//! Notation: `s` — a surface polygon's support plane, `n_s` its normal
//! (outward); `e_k` — its edge planes, the polygon on their negative
//! sides; `c_k` — its corners, counter-clockwise seen from outside; a
//! *ray* — a direction as coprime integers ([`Ray`]); a *wedge*
//! `(n, from, to)` — the part of the plane with primitive normal `n`
//! through the vertex swept counter-clockwise about `n` from ray `from` to
//! ray `to` ([`Wedge`]).
//!
//! Edge `k` runs from `c_k` to `c_{k+1}` along `t_k = n_s × n_{e_k}`. The
//! polygon lies to the left of each edge, so `t_k × n_s` is the edge's
//! outward normal in `s`; and `(n_s × n_{e_k}) × n_s = |n_s|² n_{e_k} −
//! (n_s · n_{e_k}) n_s` is the part of `n_{e_k}` across `s`, outward too
//! (the polygon is on the negative side of `e_k`). As `x ↦ x × n_s` is
//! one-to-one on the plane, `t_k` is a positive multiple of `n_s × n_{e_k}`.
//! The corner at `c_k` is the wedge from `t_k` to `−t_{k−1}`; a vertex
//! strictly inside edge `k` (a corner inserted there) sees the half-plane
//! from `t_k` to `−t_k`.
//!
//! Two planes through one vertex with the same primitive normal are the
//! same plane, so a wedge names its plane by that normal. Rays are exact
//! and reduced, so the same line gives the same ray whichever planes cut
//! it, and wedges on one plane that share a ray chain into one
//! ([`merge_wedges`]): the merged wedges around a vertex depend only on
//! the surface near it as a point set. Bits: `|n| ≤ 2^55`, so the cross
//! products have at most 111 bits (`i128`), and a 2 × 2 determinant of
//! rays at most 223 (`I256`). Floats are the rendering edge's business
//! (`bevy_chisel`'s cell meshes turn wedges into angle-weighted normals);
//! nothing here rounds.

use super::{MeshPolygon, SurfaceMesh};
use crate::exact::{I128, I256, Plane, Sign, gcd_u64, gcd_u128};
use crate::tree::EMPTY;

/// A direction as three coprime integers (not all zero), or
/// [`Ray::NONE`] in a [`Wedge`] that is a whole plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Ray(pub [i128; 3]);

impl Ray {
    /// No direction: both rays of a whole plane ([`Turn::Full`]).
    pub const NONE: Ray = Ray([0; 3]);

    /// The direction of the line `s ∩ e` that keeps the polygon of `s` on
    /// the negative side of `e` to its left: `n_s × n_e`, reduced.
    ///
    /// # Panics
    /// In debug builds, when the planes are parallel.
    #[must_use]
    pub fn along(s: &Plane, e: &Plane) -> Ray {
        let (a, b) = (s.normal().map(i128::from), e.normal().map(i128::from));
        let cross = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        debug_assert!(cross != [0; 3], "the edge plane is parallel to the face");
        Ray(reduced(cross))
    }

    /// The opposite direction.
    #[must_use]
    pub fn reversed(self) -> Ray {
        Ray(self.0.map(|c| -c))
    }
}

/// How far a wedge turns: less than, exactly or more than half a turn, or
/// a whole turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Turn {
    /// Less than `π` (every polygon's own corner).
    Convex,
    /// Exactly `π`: `to = −from`.
    Straight,
    /// More than `π`, less than `2π`.
    Reflex,
    /// The whole plane around the vertex (`from = to =` [`Ray::NONE`]).
    Full,
}

/// The part of an oriented plane through a vertex swept counter-clockwise
/// (seen from the plane's positive side) from one ray to another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Wedge {
    /// The plane's normal as coprime integers (outward): the plane
    /// through the vertex with that normal.
    pub normal: [i64; 3],
    /// Where the sweep starts.
    pub from: Ray,
    /// Where it ends.
    pub to: Ray,
    /// How far it turns, exactly.
    pub turn: Turn,
}

impl Wedge {
    /// The wedge of the plane with primitive `normal` from `from` to `to`,
    /// both lying in the plane, its turn decided exactly.
    #[must_use]
    pub fn new(normal: [i64; 3], from: Ray, to: Ray) -> Self {
        let turn = if from == to {
            Turn::Full
        } else if to == from.reversed() {
            Turn::Straight
        } else {
            match turn_sign(normal, &from, &to) {
                Sign::Positive => Turn::Convex,
                Sign::Negative => Turn::Reflex,
                // Parallel rays in the same direction are equal rays.
                Sign::Zero => Turn::Full,
            }
        };
        let (from, to) = if turn == Turn::Full {
            (Ray::NONE, Ray::NONE)
        } else {
            (from, to)
        };
        Self {
            normal,
            from,
            to,
            turn,
        }
    }
}

/// The sign of `(from × to) · n` for rays lying in the plane of normal
/// `n`: positive when `to` is less than half a turn counter-clockwise from
/// `from`. The cross product of two vectors in the plane is parallel to
/// `n`, so its component along the largest component of `n` decides (a
/// 2 × 2 determinant of 111-bit numbers, exact in 256 bits).
fn turn_sign(n: [i64; 3], from: &Ray, to: &Ray) -> Sign {
    let m = (0..3)
        .max_by_key(|&i| n[i].unsigned_abs())
        .expect("three axes");
    let (i, j) = ((m + 1) % 3, (m + 2) % 3);
    let wide = |v: i128| I128::from_i128(v);
    let left: I256 = wide(from.0[i]).wrapping_mul(&wide(to.0[j]));
    let right: I256 = wide(from.0[j]).wrapping_mul(&wide(to.0[i]));
    let sign = left.wrapping_sub(&right).sign();
    if n[m] < 0 { -sign } else { sign }
}

/// The normal of `plane` divided by the gcd of its components: what a
/// [`Wedge`] of the plane names it by.
#[must_use]
pub fn primitive_normal(plane: &Plane) -> [i64; 3] {
    let n = plane.normal();
    let [x, y, z] = n.map(i64::unsigned_abs);
    let g = gcd_u64(x, y);
    let g = if g == 1 { 1 } else { gcd_u64(g, z) };
    if g <= 1 { n } else { n.map(|c| c / g as i64) }
}

/// `v` divided by the gcd of its components (`v` itself when zero).
fn reduced(v: [i128; 3]) -> [i128; 3] {
    let g = if v.iter().all(|c| c.unsigned_abs() <= u128::from(u64::MAX)) {
        let [x, y, z] = v.map(|c| c.unsigned_abs() as u64);
        let g = gcd_u64(x, y);
        u128::from(if g == 1 { 1 } else { gcd_u64(g, z) })
    } else {
        let [x, y, z] = v.map(i128::unsigned_abs);
        let g = gcd_u128(x, y);
        if g == 1 { 1 } else { gcd_u128(g, z) }
    };
    if g <= 1 { v } else { v.map(|c| c / g as i128) }
}

impl MeshPolygon {
    /// The wedges of the polygon at each of its corners, in corner order:
    /// an original corner's own angle, or the half-plane at a corner
    /// inserted inside an edge (see the module docs).
    #[must_use]
    pub fn corner_wedges(&self) -> Vec<Wedge> {
        let mut out = Vec::with_capacity(self.corners.len());
        self.for_corner_wedges(&mut Vec::new(), |_| true, |_, w| out.push(w));
        out
    }

    /// Calls `visit` with the vertex and wedge of each corner at a vertex
    /// `wanted`, in corner order ([`Self::corner_wedges`]); `rays` is
    /// scratch space.
    fn for_corner_wedges(
        &self,
        rays: &mut Vec<Ray>,
        wanted: impl Fn(u32) -> bool,
        mut visit: impl FnMut(u32, Wedge),
    ) {
        let n = self.original_len();
        let corner = |k: usize| self.corners[self.originals[k] as usize];
        // Edge k's ray is needed by corners k and k + 1 and the corners
        // inserted in it.
        rays.clear();
        rays.resize(n, Ray::NONE);
        let mut any = false;
        let s = self.plane;
        for (k, ray) in rays.iter_mut().enumerate() {
            let needed = wanted(corner(k))
                || wanted(corner((k + 1) % n))
                || self.corners[self.inserted_on_edge(k)]
                    .iter()
                    .any(|&v| wanted(v));
            if needed {
                *ray = Ray::along(&s, &self.edges[k]);
                any = true;
            }
        }
        if !any {
            return;
        }
        let normal = primitive_normal(&s);
        for k in 0..n {
            let v = corner(k);
            if wanted(v) {
                let before = rays[(k + n - 1) % n].reversed();
                debug_assert_eq!(
                    turn_sign(normal, &rays[k], &before),
                    Sign::Positive,
                    "a corner of a strictly convex polygon"
                );
                visit(
                    v,
                    Wedge {
                        normal,
                        from: rays[k],
                        to: before,
                        turn: Turn::Convex,
                    },
                );
            }
            for &v in &self.corners[self.inserted_on_edge(k)] {
                if wanted(v) {
                    visit(
                        v,
                        Wedge {
                            normal,
                            from: rays[k],
                            to: rays[k].reversed(),
                            turn: Turn::Straight,
                        },
                    );
                }
            }
        }
    }
}

/// Merges the wedges of one vertex: on each plane, wedges where one ends
/// and the next starts chain into one (a closed chain into the whole
/// plane), and the result is sorted. The same surface near the vertex
/// gives the same list, however it was split.
pub fn merge_wedges(wedges: &mut Vec<Wedge>) {
    if wedges.len() < 2 {
        return;
    }
    let mut out = Vec::with_capacity(wedges.len());
    merge_into(wedges, &mut out);
    *wedges = out;
}

/// [`merge_wedges`] of `wedges` (reordered), appended to `out`.
fn merge_into(wedges: &mut [Wedge], out: &mut Vec<Wedge>) {
    if wedges.len() < 2 {
        out.extend_from_slice(wedges);
        return;
    }
    wedges.sort_unstable();
    let first = out.len();
    let mut start = 0;
    while start < wedges.len() {
        let normal = wedges[start].normal;
        let end = start
            + wedges[start..]
                .iter()
                .take_while(|w| w.normal == normal)
                .count();
        merge_on_plane(&wedges[start..end], out);
        start = end;
    }
    debug_assert!(out[first..].is_sorted(), "merged in order");
}

/// Most wedges of one plane chained without a heap buffer.
const SMALL: usize = 16;

/// Chains the wedges of one plane (sorted by `from`), appending the
/// merged ones to `out`.
fn merge_on_plane(group: &[Wedge], out: &mut Vec<Wedge>) {
    if group.len() == 1 {
        out.push(group[0]);
        return;
    }
    if let Some(full) = group.iter().find(|w| w.turn == Turn::Full) {
        // A whole plane already covers everything else on it.
        out.push(*full);
        return;
    }
    if let [a, b] = group {
        // The common case (two faces of one plane at a vertex), without
        // the chain search.
        match (a.to == b.from, b.to == a.from) {
            (true, true) => out.push(Wedge::new(a.normal, Ray::NONE, Ray::NONE)),
            (true, false) => out.push(Wedge::new(a.normal, a.from, b.to)),
            (false, true) => out.push(Wedge::new(a.normal, b.from, a.to)),
            (false, false) => out.extend_from_slice(group),
        }
        return;
    }
    let next_of = |w: &Wedge| group.binary_search_by(|x| x.from.cmp(&w.to)).ok();
    let (mut small_prev, mut small_used) = ([false; SMALL], [false; SMALL]);
    let (mut heap_prev, mut heap_used) = (Vec::new(), Vec::new());
    let (has_previous, used): (&mut [bool], &mut [bool]) = if group.len() <= SMALL {
        (
            &mut small_prev[..group.len()],
            &mut small_used[..group.len()],
        )
    } else {
        heap_prev.resize(group.len(), false);
        heap_used.resize(group.len(), false);
        (&mut heap_prev, &mut heap_used)
    };
    for w in group {
        if let Some(j) = next_of(w) {
            has_previous[j] = true;
        }
    }
    if has_previous.iter().all(|&h| h) {
        // Every wedge has one before it: the chains close around the
        // vertex (more than one such chain would overlap).
        out.push(Wedge::new(group[0].normal, Ray::NONE, Ray::NONE));
        return;
    }
    // Open chains, each from its first wedge, in order: the merged wedges
    // come out sorted.
    for first in 0..group.len() {
        if has_previous[first] {
            continue;
        }
        let mut at = first;
        used[at] = true;
        while let Some(j) = next_of(&group[at]).filter(|&j| !used[j]) {
            used[j] = true;
            at = j;
        }
        out.push(if at == first {
            group[first]
        } else {
            Wedge::new(group[first].normal, group[first].from, group[at].to)
        });
    }
}

/// Per vertex of a [`SurfaceMesh`], the merged wedges of its surface
/// polygons (those in front of empty space) there
/// ([`SurfaceMesh::surface_around`]), and possibly of other meshes'
/// polygons at the same point ([`SurfaceAround::add`]). A vertex may
/// have none: one of no surface polygon, or one left out
/// ([`SurfaceMesh::surface_around_at`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceAround {
    /// Vertex `v`'s wedges are `wedges[spans[v].0..][..spans[v].1]`.
    spans: Vec<(u32, u32)>,
    wedges: Vec<Wedge>,
}

impl SurfaceAround {
    /// The merged wedges at vertex `v`, sorted (empty for a vertex left
    /// out or out of range).
    #[must_use]
    pub fn of_vertex(&self, v: u32) -> &[Wedge] {
        match self.spans.get(v as usize) {
            Some(&(start, len)) => &self.wedges[start as usize..(start + len) as usize],
            None => &[],
        }
    }

    /// Number of vertices.
    #[must_use]
    pub fn vertices(&self) -> usize {
        self.spans.len()
    }

    /// Adds wedges of other meshes at some vertices, `(vertex, wedges)`
    /// (a vertex may come more than once; out of range: ignored), and
    /// merges each such vertex's list again.
    pub fn add(&mut self, mut more: Vec<(u32, &[Wedge])>) {
        more.retain(|(v, _)| (*v as usize) < self.vertices());
        more.sort_by_key(|(v, _)| *v);
        self.wedges
            .reserve(more.iter().map(|(_, w)| w.len()).sum::<usize>() + 2 * more.len());
        let mut scratch = Vec::new();
        let mut next = more.iter().peekable();
        while let Some(&&(v, _)) = next.peek() {
            scratch.clear();
            scratch.extend_from_slice(self.of_vertex(v));
            while let Some((_, theirs)) = next.next_if(|(w, _)| *w == v) {
                scratch.extend_from_slice(theirs);
            }
            // The merged list goes after the others; the old one stays
            // unused.
            let start = self.wedges.len();
            merge_into(&mut scratch, &mut self.wedges);
            self.spans[v as usize] = (start as u32, (self.wedges.len() - start) as u32);
        }
    }
}

impl SurfaceMesh {
    /// The surface around every vertex: the merged corner wedges of the
    /// polygons in front of empty space ([`MeshPolygon::corner_wedges`],
    /// [`merge_wedges`]).
    #[must_use]
    pub fn surface_around(&self) -> SurfaceAround {
        self.surface_around_where(|_| true)
    }

    /// [`Self::surface_around`] at the vertices `at` only (the others get
    /// no wedges).
    #[must_use]
    pub fn surface_around_at(&self, at: &[u32]) -> SurfaceAround {
        let mut wanted = vec![false; self.vertices.len()];
        for &v in at {
            if let Some(w) = wanted.get_mut(v as usize) {
                *w = true;
            }
        }
        self.surface_around_where(|v| wanted[v as usize])
    }

    fn surface_around_where(&self, wanted: impl Fn(u32) -> bool + Copy) -> SurfaceAround {
        let n = self.vertices.len();
        // The corner wedges in polygon order, and per vertex, theirs.
        let mut count = vec![0u32; n + 1];
        // Room for a corner at every vertex asked for, and a few more.
        let room = (0..n as u32).filter(|&v| wanted(v)).count() * 3;
        let mut raw: Vec<Wedge> = Vec::with_capacity(room);
        let mut at: Vec<u32> = Vec::with_capacity(room);
        let mut rays = Vec::new();
        for polygon in self.polygons.iter().filter(|p| p.outside == EMPTY) {
            polygon.for_corner_wedges(&mut rays, wanted, |v, wedge| {
                raw.push(wedge);
                at.push(v);
                count[v as usize + 1] += 1;
            });
        }
        for v in 0..n {
            count[v + 1] += count[v];
        }
        let mut order = vec![0u32; raw.len()];
        let mut fill = count.clone();
        for (i, &v) in at.iter().enumerate() {
            order[fill[v as usize] as usize] = i as u32;
            fill[v as usize] += 1;
        }
        let mut spans = Vec::with_capacity(n);
        let mut wedges = Vec::with_capacity(raw.len());
        let mut scratch = Vec::new();
        for v in 0..n {
            let start = wedges.len();
            let mine = &order[count[v] as usize..count[v + 1] as usize];
            if mine.len() == 1 {
                wedges.push(raw[mine[0] as usize]);
            } else if !mine.is_empty() {
                scratch.clear();
                scratch.extend(mine.iter().map(|&i| raw[i as usize]));
                merge_into(&mut scratch, &mut wedges);
            }
            spans.push((start as u32, (wedges.len() - start) as u32));
        }
        SurfaceAround { spans, wedges }
    }
}
