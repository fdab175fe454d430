//! Convex polygons in plane-based form (paper 1 §3.6, inset).
//!
//! Notation: a polygon is its supporting plane `s` (outward) and its edge
//! planes `e_0 … e_{n−1}`, each containing one edge with its positive side
//! outside the polygon within `s`; vertex `k` is the exact meet of `s`,
//! `e_{k−1}` and `e_k`. Splitting by a plane `p` keeps the edges reaching
//! each side and closes each part with `p` (below) or `−p` (above): no new
//! plane is ever constructed, and every vertex stays exact.

use std::mem;
use std::slice;

use crate::Error;
use crate::exact::{
    IntPoint, Plane, Point4, Sign, classify_vertex_exact, classify_vertex_filtered,
    intersect_3_planes, plane_from_points,
};
use crate::pool::{PerThread, Pool};

/// Polygons with at most this many corners are split without allocating
/// working memory.
const SMALL: usize = 32;

/// Polygons with at most this many corners are laid out for a split in
/// working memory on the stack: few polygons have more, and a larger
/// buffer costs its filling at every split.
const FEW_CORNERS: usize = 12;

/// Working memory for the layouts of a split ([`layout`]): `M` entries on
/// the stack, enough for polygons of up to [`FEW_CORNERS`] corners, and the
/// heap beyond.
struct LayoutMemory<const M: usize> {
    stack: [u32; M],
    heap: Vec<u32>,
}

impl<const M: usize> LayoutMemory<M> {
    fn new() -> Self {
        Self {
            stack: [NONE; M],
            heap: Vec::new(),
        }
    }

    /// `len` entries, on the stack when they fit.
    fn entries(&mut self, len: usize) -> &mut [u32] {
        if len <= M {
            &mut self.stack[..len]
        } else {
            self.heap.resize(len, NONE);
            &mut self.heap
        }
    }
}

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

    /// The parts below and above `p`. A polygon lying in `p` goes to the
    /// side its outward normal points to (the region in front of it).
    pub(crate) fn split(self, p: &Plane) -> (Option<Self>, Option<Self>) {
        self.split_wanted(p, [true; 2])
    }

    /// [`Self::split`], building only the parts `wanted` (below, above):
    /// a part not wanted is `None`, a part wanted is the one `split` gives.
    pub(crate) fn split_wanted(self, p: &Plane, wanted: [bool; 2]) -> (Option<Self>, Option<Self>) {
        let mut sides = Sides::default();
        let sides = sides.for_corners(self.corners.len());
        let [want_below, want_above] = wanted;
        match self.whole_side(p, sides) {
            Some(false) => (want_below.then_some(self), None),
            Some(true) => (None, want_above.then_some(self)),
            None => self.split_known(sides, p, wanted),
        }
    }

    /// The side of `p` the polygon lies on whole (`false` below, `true`
    /// above; a polygon lying in `p` goes to the side it faces, as in
    /// [`Self::split`]), or `None` when it has corners on both sides; the
    /// sides of the corners are written to `sides` (one per corner).
    #[inline]
    pub(crate) fn whole_side(&self, p: &Plane, sides: &mut [Sign]) -> Option<bool> {
        let (mut below, mut above) = (false, false);
        for (k, side) in sides.iter_mut().enumerate() {
            *side = self.corner_side(k, p);
            below |= *side == Sign::Negative;
            above |= *side == Sign::Positive;
        }
        self.side_from_corners(below, above, p)
    }

    /// The side of `p` a polygon with corners `below` and `above` it lies
    /// on whole: see [`Self::whole_side`].
    #[inline]
    fn side_from_corners(&self, below: bool, above: bool, p: &Plane) -> Option<bool> {
        match (below, above) {
            (true, true) => None,
            (true, false) => Some(false),
            (false, true) => Some(true),
            (false, false) => Some(faces_along(&self.support, p)),
        }
    }

    /// The side of `p` that corner `k` is on: the filter's answer, else
    /// the exact side ([`corner_side_exact`]).
    #[inline]
    fn corner_side(&self, k: usize, p: &Plane) -> Sign {
        classify_vertex_filtered(&self.corners[k], p)
            .unwrap_or_else(|| corner_side_exact(&self.edges, &self.corners, k, p))
    }

    /// [`Self::whole_side`], without recording the sides of the corners:
    /// it stops at the first corner that shows the polygon straddles `p`.
    #[inline]
    pub(crate) fn side_of_plane(&self, p: &Plane) -> Option<bool> {
        let (mut below, mut above) = (false, false);
        for k in 0..self.corners.len() {
            match self.corner_side(k, p) {
                Sign::Negative => below = true,
                Sign::Positive => above = true,
                Sign::Zero => {}
            }
            if below && above {
                return None;
            }
        }
        self.side_from_corners(below, above, p)
    }

    /// The parts `wanted` (below, above) of a polygon with corners on both
    /// sides of `p` (`sides` as [`Self::whole_side`] wrote them): those
    /// [`Self::split_wanted`] gives.
    pub(crate) fn split_known(
        self,
        sides: &[Sign],
        p: &Plane,
        wanted: [bool; 2],
    ) -> (Option<Self>, Option<Self>) {
        match wanted {
            [true, true] => {
                let (b, a) = self.split_straddling(sides, p);
                (Some(b), Some(a))
            }
            [true, false] => (Some(self.one_part(sides, p, Sign::Negative)), None),
            [false, true] => (None, Some(self.one_part(sides, p, Sign::Positive))),
            [false, false] => (None, None),
        }
    }

    /// The part on side `keep` (Negative or Positive) of `p` of a polygon
    /// with corners on both sides: the part [`Self::split_straddling`]
    /// gives on that side (its corners on `p` are the same exact meets),
    /// rewritten in place when it fits.
    pub(crate) fn one_part(mut self, sides: &[Sign], p: &Plane, keep: Sign) -> Self {
        let n = self.edges.len();
        let mut memory = LayoutMemory::<{ 2 * FEW_CORNERS }>::new();
        let buffer = memory.entries(2 * n);
        let m = layout(sides, keep, buffer);
        let origin = &buffer[..m];
        let closing = if keep == Sign::Negative {
            *p
        } else {
            p.flipped()
        };
        if fits_in_place(origin, n) {
            self.rewrite(origin, &closing, None);
            self
        } else {
            self.assemble(origin, &closing, None)
        }
    }

    /// The parts `wanted` (below, above) of the polygon with support
    /// `support`, edge planes `edge(k)` and corners `corner(k)` for `k` in
    /// `0..sides.len()`, which has corners on both sides of `p` (`sides` as
    /// [`Self::whole_side`] writes them): the parts [`Self::split_known`]
    /// gives, built straight from where the polygon lies (such as a face
    /// read in place in a convex arena) instead of from a copy of it that
    /// would be cut down. A corner on `p` that both parts have is computed
    /// once.
    pub(crate) fn parts_of<'a>(
        support: &Plane,
        edge: impl Fn(usize) -> &'a Plane,
        corner: impl Fn(usize) -> &'a Point4,
        sides: &[Sign],
        p: &Plane,
        wanted: [bool; 2],
    ) -> (Option<Self>, Option<Self>) {
        let n = sides.len();
        let mut memory = LayoutMemory::<{ 4 * FEW_CORNERS }>::new();
        let buffer = memory.entries(4 * n);
        let (low, high) = buffer.split_at_mut(2 * n);
        let build = |origin: &[u32], closing: &Plane, other: Option<Other<'_>>| {
            let plane = |o: u32| match o {
                NONE => closing,
                o => edge(o as usize),
            };
            let m = origin.len();
            let (mut edges, mut corners) = spare_buffers(m);
            for &o in origin {
                edges.extend_from_slice(slice::from_ref(plane(o)));
            }
            for j in 0..m {
                let (prev, o) = (origin[(j + m - 1) % m], origin[j]);
                match reused_corner(prev, o, n) {
                    Some(k) => corners.extend_from_slice(slice::from_ref(corner(k))),
                    None => corners.push(new_corner(
                        support,
                        (prev, plane(prev)),
                        (o, plane(o)),
                        other,
                    )),
                }
            }
            Self {
                support: *support,
                edges,
                corners,
            }
        };
        let below = wanted[0].then(|| {
            let m = layout(sides, Sign::Negative, low);
            build(&low[..m], p, None)
        });
        let above = wanted[1].then(|| {
            let m = layout(sides, Sign::Positive, high);
            let other = below
                .as_ref()
                .map(|b| (&low[..b.corners.len()], &b.corners[..]));
            build(&high[..m], &p.flipped(), other)
        });
        (below, above)
    }

    /// The parts below and above `p` of a polygon with corners on both
    /// sides (`sides` as [`classify_polygon_corners`] gives them): the same as
    /// [`Self::part`] on each side, but each corner on `p` that both parts
    /// share is computed once, runs of kept edges and corners are copied
    /// whole, and one part reuses this polygon's memory.
    pub(crate) fn split_straddling(mut self, sides: &[Sign], p: &Plane) -> (Self, Self) {
        let n = self.edges.len();
        // The layout of each part: the original index of each of its edges
        // (NONE for the closing one). At most 2n entries each (n + 1 for a
        // convex polygon).
        let mut memory = LayoutMemory::<{ 4 * FEW_CORNERS }>::new();
        let buffer = memory.entries(4 * n);
        let (low, high) = buffer.split_at_mut(2 * n);
        let (mb, ma) = (
            layout(sides, Sign::Negative, low),
            layout(sides, Sign::Positive, high),
        );
        let (below, above) = (&low[..mb], &high[..ma]);
        let flipped = p.flipped();
        // The part whose edges all stay at or before their position is
        // rewritten in place, after the other is built into new memory.
        if fits_in_place(below, n) {
            let a = self.assemble(above, &flipped, None);
            self.rewrite(below, p, Some((above, &a.corners)));
            (self, a)
        } else if fits_in_place(above, n) {
            let b = self.assemble(below, p, None);
            self.rewrite(above, &flipped, Some((below, &b.corners)));
            (b, self)
        } else {
            let b = self.assemble(below, p, None);
            let a = self.assemble(above, &flipped, Some((below, &b.corners)));
            (b, a)
        }
    }

    /// The part with edges `origin` (original indices, NONE for
    /// `closing`), in new memory; corners on `p` are taken from `other`
    /// (the other part's layout and corners) where it has them.
    fn assemble(&self, origin: &[u32], closing: &Plane, other: Option<Other<'_>>) -> Self {
        let (n, m) = (self.edges.len(), origin.len());
        let (mut edges, mut corners) = spare_buffers(m);
        let mut j = 0;
        while j < m {
            let o = origin[j];
            if o == NONE {
                edges.push(*closing);
                j += 1;
            } else {
                let end = run_end(origin, j);
                edges.extend_from_slice(&self.edges[o as usize..o as usize + (end - j)]);
                j = end;
            }
        }
        let mut j = 0;
        while j < m {
            let (prev, o) = (origin[(j + m - 1) % m], origin[j]);
            if let Some(k) = reused_corner(prev, o, n) {
                let end = run_end(origin, j);
                corners.extend_from_slice(&self.corners[k..k + (end - j)]);
                j = end;
            } else {
                let plane = |o: u32| match o {
                    NONE => closing,
                    o => &self.edges[o as usize],
                };
                corners.push(new_corner(
                    &self.support,
                    (prev, plane(prev)),
                    (o, plane(o)),
                    other,
                ));
                j += 1;
            }
        }
        Self {
            support: self.support,
            edges,
            corners,
        }
    }

    /// This polygon turned, in place, into the part with edges `origin`
    /// (which [`fits_in_place`]); corners on `p` are taken from `other`
    /// where it has them.
    fn rewrite(&mut self, origin: &[u32], closing: &Plane, other: Option<Other<'_>>) {
        let (n, m) = (self.edges.len(), origin.len());
        // Entry j reads original position origin[j] ≥ j, not yet written.
        let mut j = 0;
        while j < m {
            let o = origin[j];
            if o == NONE {
                self.edges[j] = *closing;
                j += 1;
            } else {
                let end = run_end(origin, j);
                if o as usize != j {
                    self.edges
                        .copy_within(o as usize..o as usize + (end - j), j);
                }
                j = end;
            }
        }
        // The edges are final; corner j lies between edges j − 1 and j.
        let mut j = 0;
        while j < m {
            let (prev, o) = (origin[(j + m - 1) % m], origin[j]);
            if let Some(k) = reused_corner(prev, o, n) {
                let end = run_end(origin, j);
                if k != j {
                    self.corners.copy_within(k..k + (end - j), j);
                }
                j = end;
            } else {
                self.corners[j] = new_corner(
                    &self.support,
                    (prev, &self.edges[(j + m - 1) % m]),
                    (o, &self.edges[j]),
                    other,
                );
                j += 1;
            }
        }
        self.edges.truncate(m);
        self.corners.truncate(m);
    }
}

/// Room for the sides of a polygon's corners: on the stack for the usual
/// small polygon.
pub(crate) struct Sides {
    small: [Sign; SMALL],
    large: Vec<Sign>,
}

impl Default for Sides {
    fn default() -> Self {
        Self {
            small: [Sign::Zero; SMALL],
            large: Vec::new(),
        }
    }
}

impl Sides {
    /// Room for the sides of `n` corners.
    #[inline]
    pub(crate) fn for_corners(&mut self, n: usize) -> &mut [Sign] {
        if n <= SMALL {
            &mut self.small[..n]
        } else {
            self.large.resize(n, Sign::Zero);
            &mut self.large
        }
    }
}

/// The other part of a split, already built: its layout and corners.
type Other<'a> = (&'a [u32], &'a [Point4]);

/// The end of the run of consecutive original edges starting at position
/// `j` of a layout (`origin[j]` is not NONE); inside the run the corners
/// are the original ones too.
#[inline]
fn run_end(origin: &[u32], j: usize) -> usize {
    let mut end = j + 1;
    while end < origin.len() && origin[end] == origin[end - 1].wrapping_add(1) {
        end += 1;
    }
    end
}

/// The corner of a part between its edges `(prev, plane)` and `(o,
/// plane)` (original indices, NONE for the closing plane) that is not an
/// original corner: the one `other` has between the same original edge and
/// its closing plane (the same exact vertex: the homogeneous coordinates of
/// a three-plane meet change only by a common sign when the planes are
/// reordered or one is flipped, and the sign is normalised), else the meet.
#[inline]
fn new_corner(
    support: &Plane,
    (prev, a): (u32, &Plane),
    (o, b): (u32, &Plane),
    other: Option<Other<'_>>,
) -> Point4 {
    let key = match (prev, o) {
        (NONE, NONE) => None,
        (NONE, k) | (k, NONE) => Some(k),
        _ => None,
    };
    if let (Some(key), Some((origin, corners))) = (key, other) {
        let m = origin.len();
        for (j, &o) in origin.iter().enumerate() {
            if o != NONE {
                continue;
            }
            let next = (j + 1) % m;
            let found = if origin[(j + m - 1) % m] == key {
                &corners[j]
            } else if origin[next] == key {
                &corners[next]
            } else {
                continue;
            };
            // Tested against a fresh `meet` in `split_parts_keep_exact_corners`.
            return *found;
        }
    }
    meet(support, a, b)
}

/// Whether two vertices have the same digits and `f64`s.
#[cfg(test)]
fn same_digits(a: &Point4, b: &Point4) -> bool {
    a.xyz_digits == b.xyz_digits
        && a.w_digits == b.w_digits
        && a.approx.map(f64::to_bits) == b.approx.map(f64::to_bits)
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

thread_local! {
    /// Edge buffers of dropped polygons and of boundary faces given to a
    /// mesh, for the next polygons built on the same thread: clipping and
    /// rebuilding drop about as many pieces as they create, so most splits
    /// allocate nothing.
    static SPARE_EDGES: Pool<Vec<Plane>> = const { Pool::new(MAX_SPARE) };
    /// Corner buffers of dropped polygons, kept apart from the edge buffers
    /// (a boundary face given to a mesh keeps its edge planes but hands
    /// back its corners).
    static SPARE_CORNERS: Pool<Vec<Point4>> = const { Pool::new(MAX_SPARE) };
}

/// Spare buffers of each kind kept per thread.
const MAX_SPARE: usize = 1024;

/// Hands `edges` and `corners` (either may be empty) to the spare buffers
/// of this thread. When the pool is full, or the thread is ending, the
/// buffers are simply freed.
#[inline(never)]
pub(crate) fn give_back_buffers(mut edges: Vec<Plane>, mut corners: Vec<Point4>) {
    if edges.capacity() != 0 {
        edges.clear();
        SPARE_EDGES.keep(edges);
    }
    if corners.capacity() != 0 {
        corners.clear();
        SPARE_CORNERS.keep(corners);
    }
}

/// Hands the edge buffers `buffers` yields to the spare buffers of this
/// thread while there is room, and stops asking for more when the pool is
/// full (what is left is the caller's to free).
pub(crate) fn give_back_edge_buffers(buffers: impl Iterator<Item = Vec<Plane>>) {
    SPARE_EDGES.keep_while_room(buffers.filter(|e| e.capacity() != 0).map(|mut e| {
        e.clear();
        e
    }));
}

/// Room for corners in new buffers, at least: most polygons have fewer,
/// so spare buffers usually fit the next polygon.
const MIN_CAPACITY: usize = 8;

/// Empty edge and corner buffers with room for `m` of each: spare ones
/// when they are large enough, else new ones (growing a spare buffer would
/// copy its stale contents).
pub(crate) fn spare_buffers(m: usize) -> (Vec<Plane>, Vec<Point4>) {
    let capacity = m.max(MIN_CAPACITY);
    (
        SPARE_EDGES
            .take()
            .filter(|e| e.capacity() >= m)
            .unwrap_or_else(|| Vec::with_capacity(capacity)),
        SPARE_CORNERS
            .take()
            .filter(|c| c.capacity() >= m)
            .unwrap_or_else(|| Vec::with_capacity(capacity)),
    )
}

/// An empty edge buffer with room for `m` planes: a spare one when it is
/// large enough, else a new one.
pub(crate) fn spare_edge_buffer(m: usize) -> Vec<Plane> {
    SPARE_EDGES
        .take()
        .filter(|e| e.capacity() >= m)
        .unwrap_or_else(|| Vec::with_capacity(m.max(MIN_CAPACITY)))
}

/// Marks the closing plane in a part's layout.
const NONE: u32 = u32::MAX;

/// Whether a polygon with support `support` lying in `p` faces along `p`
/// (the supports are positive multiples of each other, not opposite).
#[inline]
pub(crate) fn faces_along(support: &Plane, p: &Plane) -> bool {
    p.normal()
        .iter()
        .zip(support.normal())
        .all(|(a, b)| a.signum() == b.signum())
}

/// The side of `p` that `v` is on ([`crate::exact::classify_vertex`], with
/// the filter inlined).
#[inline]
pub(crate) fn side_of(v: &Point4, p: &Plane) -> Sign {
    classify_vertex_filtered(v, p).unwrap_or_else(|| classify_vertex_exact(v, p))
}

/// The sides of `corners` with respect to `p`, written to `sides`, and
/// whether any is below and any above.
#[cfg(test)]
pub(crate) fn classify_corners(corners: &[Point4], p: &Plane, sides: &mut [Sign]) -> (bool, bool) {
    let (mut below, mut above) = (false, false);
    for (side, v) in sides.iter_mut().zip(corners) {
        *side = side_of(v, p);
        below |= *side == Sign::Negative;
        above |= *side == Sign::Positive;
    }
    (below, above)
}

/// The sides of the corners of a polygon in plane-based form (support
/// `support`, edge planes `edges`, corners `corners`) with respect to `p`,
/// written to `sides`, and whether any is below and any above: the sides
/// [`side_of`] gives, but a polygon lying in `p` (its support is
/// `p`, as given or flipped) and a corner where one of its edge planes is
/// `p` are found on `p` without arithmetic — as where the polygon is a
/// piece of a face already in a tree, or was cut by `p`.
#[inline]
pub(crate) fn classify_polygon_corners(
    support: &Plane,
    edges: &[Plane],
    corners: &[Point4],
    p: &Plane,
    sides: &mut [Sign],
) -> (bool, bool) {
    if same_plane_either_way(support, p) {
        sides.fill(Sign::Zero);
        return (false, false);
    }
    let (mut below, mut above) = (false, false);
    for (k, side) in sides.iter_mut().enumerate() {
        *side = classify_vertex_filtered(&corners[k], p)
            .unwrap_or_else(|| corner_side_exact(edges, corners, k, p));
        below |= *side == Sign::Negative;
        above |= *side == Sign::Positive;
    }
    (below, above)
}

/// The exact side of `p` that corner `k` of a polygon with edge planes
/// `edges` and corners `corners` is on: zero without arithmetic when `p`
/// is one of the two edge planes meeting there (as given, or flipped).
#[cold]
#[inline(never)]
fn corner_side_exact(edges: &[Plane], corners: &[Point4], k: usize, p: &Plane) -> Sign {
    let n = edges.len();
    if same_plane_either_way(&edges[k], p) || same_plane_either_way(&edges[(k + n - 1) % n], p) {
        Sign::Zero
    } else {
        classify_vertex_exact(&corners[k], p)
    }
}

/// Whether `e` has the coefficients of `p` or of `p` flipped.
#[inline]
fn same_plane_either_way(e: &Plane, p: &Plane) -> bool {
    (e.a, e.b, e.c, e.d) == (p.a, p.b, p.c, p.d) || (e.a, e.b, e.c, e.d) == (-p.a, -p.b, -p.c, -p.d)
}

/// Writes the layout of the part on side `keep` into `origin` (as
/// [`Polygon::part`] builds it: the original index of each kept edge, NONE
/// where the closing plane goes) and returns its length.
fn layout(sides: &[Sign], keep: Sign, origin: &mut [u32]) -> usize {
    let n = sides.len();
    let reaches = |k: usize| sides[k] == keep || sides[(k + 1) % n] == keep;
    let across = -keep;
    let mut m = 0;
    for k in 0..n {
        if reaches(k) {
            origin[m] = k as u32;
            m += 1;
            let next = (k + 1) % n;
            if sides[next] == across || !reaches(next) {
                origin[m] = NONE;
                m += 1;
            }
        }
    }
    m
}

/// The original corner a part reuses between its edges `prev` and `o`
/// (consecutive original edges), if any.
#[inline]
fn reused_corner(prev: u32, o: u32, n: usize) -> Option<usize> {
    (prev != NONE && o != NONE && o as usize == (prev as usize + 1) % n).then_some(o as usize)
}

/// Whether the part with this layout can be written over the original
/// polygon front to back: no more edges, none moving to a later position.
fn fits_in_place(origin: &[u32], n: usize) -> bool {
    origin.len() <= n
        && origin
            .iter()
            .enumerate()
            .all(|(j, &o)| o == NONE || o as usize >= j)
}

/// The corner where the support and two edge planes meet.
fn meet(support: &Plane, a: &Plane, b: &Plane) -> Point4 {
    intersect_3_planes(support, a, b).expect("edge planes meet the support plane in a point")
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn random_point(rng: &mut ChaCha8Rng) -> IntPoint {
        let mut c = || rng.random_range(-1000..=1000);
        IntPoint::new(c(), c(), c()).expect("in budget")
    }

    /// A plane with a small random normal through `x`.
    fn plane_through(rng: &mut ChaCha8Rng, x: IntPoint) -> Option<Plane> {
        let n = [0; 3].map(|_| rng.random_range(-20i64..=20));
        let d = -(0..3)
            .map(|i| i128::from(n[i]) * i128::from(x.coords()[i]))
            .sum::<i128>();
        (n != [0; 3]).then(|| Plane::new(n[0], n[1], n[2], d).expect("small coefficients"))
    }

    /// The parts of `triangle` after `rounds` splits by random planes, every
    /// `corner_every`-th through one of its `corners` (so corners land on
    /// the plane), and the planes used with their flips.
    fn split_repeatedly(
        rng: &mut ChaCha8Rng,
        triangle: Polygon,
        corners: [IntPoint; 3],
        rounds: usize,
        corner_every: usize,
    ) -> (Vec<Polygon>, Vec<Plane>) {
        let mut pieces = vec![triangle];
        let mut planes = Vec::new();
        for round in 0..rounds {
            let x = if round % corner_every == 0 {
                corners[rng.random_range(0..3)]
            } else {
                random_point(rng)
            };
            let Some(plane) = plane_through(rng, x) else {
                continue;
            };
            planes.extend([plane, plane.flipped()]);
            pieces = pieces
                .into_iter()
                .flat_map(|piece| {
                    let (below, above) = piece.split(&plane);
                    below.into_iter().chain(above)
                })
                .collect();
        }
        (pieces, planes)
    }

    /// Every corner of every part, after repeated splits by random planes
    /// (some through corners, so corners land on the plane), has exactly
    /// the digits of a fresh meet of its planes: the corners a split takes
    /// over from the original or from the other part are the right ones.
    #[test]
    fn split_parts_keep_exact_corners() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut checked = 0;
        for _ in 0..300 {
            let corners = [0; 3].map(|_| random_point(&mut rng));
            let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
                continue;
            };
            let (pieces, _) = split_repeatedly(&mut rng, triangle, corners, 6, 3);
            for piece in &pieces {
                let n = piece.edges.len();
                assert_eq!(piece.vertices().len(), n);
                for k in 0..n {
                    let fresh = meet(
                        &piece.support,
                        &piece.edges[(k + n - 1) % n],
                        &piece.edges[k],
                    );
                    assert!(
                        same_digits(&piece.vertices()[k], &fresh),
                        "corner {k} of {n}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 3000, "only {checked} corners checked");
    }

    /// [`Polygon::parts_of`] a polygon read in place gives the parts
    /// [`Polygon::split_known`] gives, plane for plane and corner for
    /// corner, for every choice of wanted parts, for the parts of repeated
    /// splits cut by random planes (some through corners).
    #[test]
    fn parts_of_agree_with_split_known() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let same = |a: &Option<Polygon>, b: &Option<Polygon>| match (a, b) {
            (Some(a), Some(b)) => {
                a.support == b.support
                    && a.edges == b.edges
                    && a.corners.len() == b.corners.len()
                    && a.corners
                        .iter()
                        .zip(&b.corners)
                        .all(|(x, y)| same_digits(x, y))
            }
            (None, None) => true,
            _ => false,
        };
        let mut checked = 0;
        for _ in 0..200 {
            let corners = [0; 3].map(|_| random_point(&mut rng));
            let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
                continue;
            };
            let (pieces, _) = split_repeatedly(&mut rng, triangle, corners, 4, 2);
            for piece in &pieces {
                let x = if rng.random_range(0..3) == 0 {
                    corners[rng.random_range(0..3)]
                } else {
                    random_point(&mut rng)
                };
                let Some(p) = plane_through(&mut rng, x) else {
                    continue;
                };
                let mut sides = vec![Sign::Zero; piece.vertices().len()];
                if piece.whole_side(&p, &mut sides).is_some() {
                    continue;
                }
                for wanted in [[true, true], [true, false], [false, true], [false, false]] {
                    let direct = Polygon::parts_of(
                        &piece.support,
                        |k| &piece.edges[k],
                        |k| &piece.corners[k],
                        &sides,
                        &p,
                        wanted,
                    );
                    let split = piece.clone().split_known(&sides, &p, wanted);
                    assert!(same(&direct.0, &split.0) && same(&direct.1, &split.1));
                    checked += 1;
                }
            }
        }
        assert!(checked > 500, "only {checked} splits checked");
    }

    /// [`Polygon::whole_side`] and [`Polygon::side_of_plane`] agree with
    /// classifying every corner in full, for the parts of repeated splits
    /// against the splitting planes (on which the parts have corners, found
    /// without arithmetic) and their flips.
    #[test]
    fn whole_side_agrees_with_full_classification() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (mut checked, mut touching) = (0, 0);
        for _ in 0..200 {
            let corners = [0; 3].map(|_| random_point(&mut rng));
            let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
                continue;
            };
            let (pieces, planes) = split_repeatedly(&mut rng, triangle, corners, 5, 2);
            for piece in &pieces {
                let n = piece.vertices().len();
                let (mut sides, mut exact) = (vec![Sign::Zero; n], vec![Sign::Zero; n]);
                for p in &planes {
                    // Every corner classified in full, as the reference.
                    let (below, above) = classify_corners(piece.vertices(), p, &mut exact);
                    let expected = piece.side_from_corners(below, above, p);
                    assert_eq!(piece.whole_side(p, &mut sides), expected);
                    assert_eq!(sides, exact);
                    assert_eq!(piece.side_of_plane(p), expected);
                    touching += usize::from(exact.contains(&Sign::Zero));
                    checked += 1;
                }
            }
        }
        assert!(
            checked > 2000 && touching > 500,
            "{checked} checked, {touching} touching"
        );
    }
}
