//! The half-edge arena of convex polyhedra.
//!
//! Notation: `h` — a half-edge from `origin(h)` to `dest(h) =
//! origin(twin(h))`; `next(h)` — the following half-edge counter-clockwise
//! around `face(h)` seen from outside; a face's plane has its positive side
//! outside the polyhedron, so the interior is where every face plane is
//! negative.
//!
//! Layout: the exact positions ([`Point4`], 152 bytes) and the face planes
//! ([`Plane`], 80 bytes) live in their own arrays, `points` and `planes`,
//! named by index from the small vertex and face records. Splitting a face
//! or duplicating a section vertex for the upper part of a cut copies an
//! index, never the exact data; a point or plane may be shared by several
//! records (the copies of a section vertex, the halves of a split face).

use std::collections::{HashMap, HashSet};

use super::scratch::Scratch;
use crate::Error;
use crate::exact::{IntPoint, Plane, Point4};
use crate::pool::{PerThread, Pool};

/// The faces of [`ConvexArena::add_box`]: the index of each one's plane
/// (−x, +x, −y, +y, −z, +z) and its corners counter-clockwise seen from
/// outside (corner `i` has x from bit 0 of `i`, y from bit 1, z from bit
/// 2).
const BOX_FACES: [(usize, [u32; 4]); 6] = [
    (0, [0, 4, 6, 2]),
    (1, [1, 3, 7, 5]),
    (2, [0, 1, 5, 4]),
    (3, [2, 6, 7, 3]),
    (4, [0, 2, 3, 1]),
    (5, [4, 5, 7, 6]),
];

/// The twin of each half-edge of a box, relative to its first half-edge
/// (half-edge `4f + k` leaves corner `k` of face `f` of [`BOX_FACES`]):
/// the half-edge between the same corners the other way.
const BOX_TWINS: [u32; 24] = box_twins();

/// Computes [`BOX_TWINS`].
const fn box_twins() -> [u32; 24] {
    /// The corners half-edge `h` joins.
    const fn ends(h: usize) -> (u32, u32) {
        let corners = BOX_FACES[h / 4].1;
        (corners[h % 4], corners[(h % 4 + 1) % 4])
    }
    let mut twins = [u32::MAX; 24];
    let mut h = 0;
    while h < 24 {
        let (a, b) = ends(h);
        let mut g = 0;
        while g < 24 {
            let (c, d) = ends(g);
            if c == b && d == a {
                twins[h] = g as u32;
            }
            g += 1;
        }
        h += 1;
    }
    twins
}

/// Tag of a face with no opposite BSP node.
pub const NO_TAG: u32 = u32::MAX;

/// A vertex: its exact position (an index into the arena's points) and one
/// half-edge leaving it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vertex {
    /// Index of its exact homogeneous position in `ConvexArena::points`.
    pub(crate) point: u32,
    /// A half-edge whose origin is this vertex.
    pub(crate) half_edge: u32,
}

/// A directed edge of one face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HalfEdge {
    /// The vertex it leaves.
    pub origin: u32,
    /// The opposite half-edge, on the neighbouring face.
    pub twin: u32,
    /// The next half-edge around the same face.
    pub next: u32,
    /// The face it bounds.
    pub face: u32,
}

/// A planar convex face; its plane is [`ConvexArena::face_plane`].
#[derive(Clone, Copy, Debug)]
pub struct Face {
    /// Index of its supporting plane (positive side outside) in the
    /// arena's plane array.
    pub(crate) plane: u32,
    /// One half-edge of the face.
    pub half_edge: u32,
    /// The BSP node on the other side of the face, or [`NO_TAG`].
    pub tag: u32,
}

/// Names one polyhedron in an arena by one of its half-edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PolyId(pub u32);

impl Clone for ConvexArena {
    /// A copy of the polyhedra; the working memory of the cuts is not
    /// copied (it may be sized for a much larger arena reused earlier).
    fn clone(&self) -> Self {
        Self {
            vertices: self.vertices.clone(),
            points: self.points.clone(),
            half_edges: self.half_edges.clone(),
            faces: self.faces.clone(),
            planes: self.planes.clone(),
            scratch: None,
        }
    }
}

impl Drop for ConvexArena {
    /// Hands the arrays to this thread's reserve for [`ConvexArena::new`].
    fn drop(&mut self) {
        if self.vertices.capacity() == 0 && self.half_edges.capacity() == 0 {
            return;
        }
        keep_spare(Arrays {
            vertices: std::mem::take(&mut self.vertices),
            points: std::mem::take(&mut self.points),
            half_edges: std::mem::take(&mut self.half_edges),
            faces: std::mem::take(&mut self.faces),
            planes: std::mem::take(&mut self.planes),
            scratch: self.scratch.take(),
        });
    }
}

thread_local! {
    /// The arrays of arenas dropped on this thread, for [`ConvexArena::new`]:
    /// code that builds a fresh arena per operation does not regrow its
    /// arrays, nor fault in new pages, every time.
    static SPARE: Pool<Arrays> = const { Pool::new(SPARE_ARRAYS) };
}

/// Arrays kept per thread for reuse: enough for a few arenas alive at once.
const SPARE_ARRAYS: usize = 4;

/// The arrays of a dropped arena, emptied, with their capacity.
struct Arrays {
    vertices: Vec<Vertex>,
    points: Vec<Point4>,
    half_edges: Vec<HalfEdge>,
    faces: Vec<Face>,
    planes: Vec<Plane>,
    scratch: Option<Box<Scratch>>,
}

/// Arrays of an earlier arena of this thread, if any are kept.
fn take_spare() -> Option<Arrays> {
    SPARE.take()
}

/// Keeps `arrays` for a later arena of this thread (cleared here), unless
/// enough are kept already or the thread is shutting down.
fn keep_spare(mut arrays: Arrays) {
    arrays.vertices.clear();
    arrays.points.clear();
    arrays.half_edges.clear();
    arrays.faces.clear();
    arrays.planes.clear();
    SPARE.keep(arrays);
}

/// The sizes of an arena's arrays at one moment, to discard everything
/// added after it ([`ConvexArena::release_to`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ArenaMark {
    vertices: usize,
    points: usize,
    half_edges: usize,
    faces: usize,
    planes: usize,
}

/// Flat storage for half-edge meshes of convex polyhedra.
#[derive(Debug, Default)]
pub struct ConvexArena {
    pub(crate) vertices: Vec<Vertex>,
    /// Exact vertex positions, named by [`Vertex::point`].
    pub(crate) points: Vec<Point4>,
    pub(crate) half_edges: Vec<HalfEdge>,
    pub(crate) faces: Vec<Face>,
    /// Face planes, named by [`Face::plane`].
    pub(crate) planes: Vec<Plane>,
    /// Reused working memory of the cuts (no part of the geometry), boxed
    /// so that lending it to a cut moves a pointer.
    pub(crate) scratch: Option<Box<Scratch>>,
}

impl ConvexArena {
    /// An empty arena; it reuses the memory of an arena this thread
    /// dropped earlier, if there is one.
    #[must_use]
    pub fn new() -> Self {
        match take_spare() {
            Some(arrays) => Self {
                vertices: arrays.vertices,
                points: arrays.points,
                half_edges: arrays.half_edges,
                faces: arrays.faces,
                planes: arrays.planes,
                scratch: arrays.scratch.map(|mut scratch| {
                    scratch.landmarks.forget();
                    scratch.extremes.forget();
                    scratch
                }),
            },
            None => Self::default(),
        }
    }

    /// Forgets where the next cuts start (see `landmarks`): called by
    /// everything but the cuts that may change which vertices a
    /// polyhedron has.
    #[inline]
    fn forget_landmarks(&mut self) {
        if let Some(scratch) = &mut self.scratch {
            scratch.landmarks.forget();
            scratch.extremes.forget();
        }
    }

    /// Removes every polyhedron, keeping the memory.
    pub fn clear(&mut self) {
        self.forget_landmarks();
        self.vertices.clear();
        self.points.clear();
        self.half_edges.clear();
        self.faces.clear();
        self.planes.clear();
    }

    /// The current sizes, for [`ConvexArena::release_to`].
    #[must_use]
    #[inline]
    pub(crate) fn mark(&self) -> ArenaMark {
        ArenaMark {
            vertices: self.vertices.len(),
            points: self.points.len(),
            half_edges: self.half_edges.len(),
            faces: self.faces.len(),
            planes: self.planes.len(),
        }
    }

    /// Discards every element added since `mark`, keeping the memory. The
    /// caller promises that no polyhedron it still uses was created or cut
    /// since then: cuts modify a polyhedron's elements in place, so one cut
    /// after the mark may now point at discarded elements.
    #[inline]
    pub(crate) fn release_to(&mut self, mark: ArenaMark) {
        self.forget_landmarks();
        self.vertices.truncate(mark.vertices);
        self.points.truncate(mark.points);
        self.half_edges.truncate(mark.half_edges);
        self.faces.truncate(mark.faces);
        self.planes.truncate(mark.planes);
    }

    /// Reserves room for `additional` more vertices, points, faces and
    /// planes and (six times as many) half-edges, so that the next cuts do
    /// not reallocate.
    pub fn reserve(&mut self, additional: usize) {
        self.vertices.reserve(additional);
        self.points.reserve(additional);
        self.faces.reserve(additional);
        self.planes.reserve(additional);
        self.half_edges.reserve(6 * additional);
        self.scratch.get_or_insert_default().reserve(
            self.vertices.len() + additional,
            self.faces.len() + additional,
        );
    }

    /// The number of vertices (of every polyhedron in the arena); vertex
    /// ids are below it.
    #[must_use]
    #[inline]
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// The number of exact points the arena holds: every vertex
    /// construction of a cut adds one (the copies of a section vertex
    /// share it).
    #[must_use]
    #[inline]
    pub fn point_count(&self) -> usize {
        self.points.len()
    }

    /// The exact position of vertex `v`.
    #[must_use]
    #[inline]
    pub fn point(&self, v: u32) -> &Point4 {
        &self.points[self.vertices[v as usize].point as usize]
    }

    /// The position of vertex `v` in `f64` (for export and display only;
    /// see [`Point4::to_f64`]).
    #[must_use]
    #[inline]
    pub fn position(&self, v: u32) -> [f64; 3] {
        self.point(v).to_f64()
    }

    /// A half-edge leaving vertex `v`.
    #[must_use]
    #[inline]
    pub fn vertex_half_edge(&self, v: u32) -> u32 {
        self.vertices[v as usize].half_edge
    }

    /// All half-edges.
    #[must_use]
    pub fn half_edges(&self) -> &[HalfEdge] {
        &self.half_edges
    }

    /// All faces.
    #[must_use]
    pub fn faces(&self) -> &[Face] {
        &self.faces
    }

    /// The supporting plane of face `f`, positive side outside.
    #[must_use]
    #[inline]
    pub fn face_plane(&self, f: u32) -> &Plane {
        &self.planes[self.faces[f as usize].plane as usize]
    }

    /// Adds a vertex at the new exact position `point`.
    #[inline]
    pub(crate) fn push_vertex(&mut self, point: Point4, half_edge: u32) -> u32 {
        let v = self.vertices.len() as u32;
        self.vertices.push(Vertex {
            point: self.points.len() as u32,
            half_edge,
        });
        self.points.push(point);
        v
    }

    /// Adds `plane` to the plane array; returns its index for
    /// [`Face::plane`].
    #[inline]
    pub(crate) fn push_plane(&mut self, plane: Plane) -> u32 {
        self.planes.push(plane);
        self.planes.len() as u32 - 1
    }

    /// The axis-aligned box `[min, max]` as a polyhedron with six faces.
    ///
    /// # Errors
    /// [`Error::DegenerateBox`] unless `min < max` on every axis.
    pub fn add_box(&mut self, min: IntPoint, max: IntPoint) -> Result<PolyId, Error> {
        let (lo, hi) = (min.coords(), max.coords());
        if (0..3).any(|i| lo[i] >= hi[i]) {
            return Err(Error::DegenerateBox { min: lo, max: hi });
        }
        // Outward planes: −x, +x, −y, +y, −z, +z.
        let side = |axis: usize, upper: bool| {
            let mut n = [0i64; 3];
            n[axis] = if upper { 1 } else { -1 };
            let d = if upper { -hi[axis] } else { lo[axis] };
            Plane::new(n[0], n[1], n[2], i128::from(d))
        };
        let planes = [
            side(0, false)?,
            side(0, true)?,
            side(1, false)?,
            side(1, true)?,
            side(2, false)?,
            side(2, true)?,
        ];
        // Vertex i has x from bit 0, y from bit 1, z from bit 2: the point
        // where the planes of its three sides meet, (x, y, z, 1) exactly as
        // `intersect_3_planes` gives it for unit normals.
        let v0 = self.vertices.len() as u32;
        let h0 = self.half_edges.len() as u32;
        for i in 0..8 {
            let pick = |axis: usize| {
                if i >> axis & 1 == 0 {
                    lo[axis]
                } else {
                    hi[axis]
                }
            };
            self.push_vertex(Point4::from_small(pick(0), pick(1), pick(2), 1), u32::MAX);
        }
        for (p, corners) in BOX_FACES {
            self.push_face(v0, planes[p], &corners);
        }
        // The twins `link_twins` would find, known in advance.
        for (e, &twin) in self.half_edges[h0 as usize..].iter_mut().zip(&BOX_TWINS) {
            e.twin = h0 + twin;
        }
        Ok(PolyId(h0))
    }

    /// Adds a closed polyhedron given its vertices and, per face, its plane
    /// and its vertex indices counter-clockwise seen from outside. The input
    /// must be a valid convex polyhedron (see [`ConvexArena::validate`]).
    /// The half-edges are paired by sorting their end pairs (tests; the
    /// hull gives its pairs, [`ConvexArena::add_polyhedron_linked`]).
    #[cfg(test)]
    pub(crate) fn add_polyhedron(
        &mut self,
        points: &[Point4],
        faces: &[(Plane, Vec<u32>)],
    ) -> PolyId {
        let v0 = self.vertices.len() as u32;
        let h0 = self.half_edges.len() as u32;
        for &point in points {
            self.push_vertex(point, u32::MAX);
        }
        for (plane, corners) in faces {
            self.push_face(v0, *plane, corners);
        }
        self.link_twins(h0);
        PolyId(h0)
    }

    /// [`ConvexArena::add_polyhedron`] for faces given as flat arrays:
    /// face `f` lies on `planes[f]` with corners `corners[starts[f]..starts[f
    /// + 1]]`, and `twins[i]` is the corner (index into `corners`) that
    /// starts the opposite of the side from corner `i` to the next, so that
    /// no pairing by sorting is needed. The input must be a valid convex
    /// polyhedron (see [`ConvexArena::validate`]).
    pub(crate) fn add_polyhedron_linked(
        &mut self,
        points: &[Point4],
        planes: &[Plane],
        starts: &[u32],
        corners: &[u32],
        twins: &[u32],
    ) -> PolyId {
        let v0 = self.vertices.len() as u32;
        let h0 = self.half_edges.len() as u32;
        for &point in points {
            self.push_vertex(point, u32::MAX);
        }
        self.half_edges.reserve(corners.len());
        for (f, plane) in planes.iter().enumerate() {
            let face = &corners[starts[f] as usize..starts[f + 1] as usize];
            self.push_face(v0, *plane, face);
        }
        for (h, &twin) in self.half_edges[h0 as usize..].iter_mut().zip(twins) {
            h.twin = h0 + twin;
        }
        PolyId(h0)
    }

    /// Adds a face on `plane` whose corners are the vertices `v0 + c` for
    /// `c` in `corners` (counter-clockwise seen from outside), its
    /// half-edges not yet paired.
    fn push_face(&mut self, v0: u32, plane: Plane, corners: &[u32]) {
        self.forget_landmarks();
        let face = self.faces.len() as u32;
        let first = self.half_edges.len() as u32;
        let n = corners.len() as u32;
        for (k, &c) in (0u32..).zip(corners) {
            self.half_edges.push(HalfEdge {
                origin: v0 + c,
                twin: u32::MAX,
                next: first + (k + 1) % n,
                face,
            });
            self.vertices[(v0 + c) as usize].half_edge = first + k;
        }
        let plane = self.push_plane(plane);
        self.faces.push(Face {
            plane,
            half_edge: first,
            tag: NO_TAG,
        });
    }

    /// Pairs every half-edge from `h0` on with its opposite, the half-edge
    /// between the same vertices the other way (by sorted end pairs).
    #[cfg(test)]
    fn link_twins(&mut self, h0: u32) {
        let edges = &self.half_edges[h0 as usize..];
        let mut ends: Vec<(u32, u32, u32)> = (h0..)
            .zip(edges)
            .map(|(h, e)| (e.origin, edges[(e.next - h0) as usize].origin, h))
            .collect();
        ends.sort_unstable();
        for &(a, b, h) in &ends {
            if let Ok(j) = ends.binary_search_by(|&(u, w, _)| (u, w).cmp(&(b, a))) {
                self.half_edges[h as usize].twin = ends[j].2;
            }
        }
    }

    /// A new arena holding only polyhedron `poly`, compactly renumbered
    /// (faces in [`ConvexArena::faces_of`] order), and its id there.
    #[must_use]
    pub fn extract(&self, poly: PolyId) -> (ConvexArena, PolyId) {
        let faces = self.faces_of(poly);
        let mut out = ConvexArena::new();
        let mut vertex_index: HashMap<u32, u32> = HashMap::new();
        let mut edge_index: HashMap<u32, u32> = HashMap::new();
        for &f in &faces {
            for h in self.face_loop(f) {
                edge_index.insert(h, edge_index.len() as u32);
                let v = self.half_edges[h as usize].origin;
                vertex_index
                    .entry(v)
                    .or_insert_with(|| out.push_vertex(*self.point(v), u32::MAX));
            }
        }
        out.half_edges = vec![
            HalfEdge {
                origin: 0,
                twin: 0,
                next: 0,
                face: 0
            };
            edge_index.len()
        ];
        for (new_face, &f) in faces.iter().enumerate() {
            for h in self.face_loop(f) {
                let e = self.half_edges[h as usize];
                out.half_edges[edge_index[&h] as usize] = HalfEdge {
                    origin: vertex_index[&e.origin],
                    twin: edge_index[&e.twin],
                    next: edge_index[&e.next],
                    face: new_face as u32,
                };
            }
            let face = self.faces[f as usize];
            let plane = out.push_plane(*self.face_plane(f));
            out.faces.push(Face {
                plane,
                half_edge: edge_index[&face.half_edge],
                tag: face.tag,
            });
        }
        for (old, &new) in &vertex_index {
            out.vertices[new as usize].half_edge =
                edge_index[&self.vertices[*old as usize].half_edge];
        }
        (out, PolyId(edge_index[&poly.0]))
    }

    /// The destination vertex of half-edge `h`.
    #[must_use]
    #[inline]
    pub fn dest(&self, h: u32) -> u32 {
        self.half_edges[self.half_edges[h as usize].next as usize].origin
    }

    /// The half-edges around a face, starting at its stored half-edge.
    pub fn face_loop(&self, face: u32) -> impl Iterator<Item = u32> + '_ {
        let first = self.faces[face as usize].half_edge;
        let mut h = Some(first);
        std::iter::from_fn(move || {
            let cur = h?;
            let next = self.half_edges[cur as usize].next;
            h = (next != first).then_some(next);
            Some(cur)
        })
    }

    /// The faces of polyhedron `poly`, in breadth-first order from the face
    /// of its half-edge.
    #[must_use]
    pub fn faces_of(&self, poly: PolyId) -> Vec<u32> {
        let mut order = Vec::new();
        self.faces_of_into(poly, &mut order);
        order
    }

    /// [`ConvexArena::faces_of`] into `order` (cleared first), so that a
    /// caller visiting many polyhedra reuses one buffer.
    pub fn faces_of_into(&self, poly: PolyId, order: &mut Vec<u32>) {
        let start = self.half_edges[poly.0 as usize].face;
        order.clear();
        order.push(start);
        let mut seen = SeenSet::default();
        seen.insert(start);
        let mut i = 0;
        while i < order.len() {
            let face = order[i];
            for h in self.face_loop(face) {
                let neighbour = self.half_edges[self.half_edges[h as usize].twin as usize].face;
                if seen.insert(neighbour) {
                    order.push(neighbour);
                }
            }
            i += 1;
        }
    }

    /// The vertices of polyhedron `poly` (each once, in first-seen order).
    #[must_use]
    pub fn vertices_of(&self, poly: PolyId) -> Vec<u32> {
        let mut seen = SeenSet::default();
        let mut out = Vec::new();
        for face in self.faces_of(poly) {
            for h in self.face_loop(face) {
                let v = self.half_edges[h as usize].origin;
                if seen.insert(v) {
                    out.push(v);
                }
            }
        }
        out
    }

    /// Each face of `poly` as its plane and its vertices' `f64` positions
    /// counter-clockwise from outside (for export and display).
    #[must_use]
    pub fn face_polygons(&self, poly: PolyId) -> Vec<(Plane, Vec<[f64; 3]>)> {
        self.faces_of(poly)
            .into_iter()
            .map(|f| {
                let corners = self
                    .face_loop(f)
                    .map(|h| self.position(self.half_edges[h as usize].origin))
                    .collect();
                (*self.face_plane(f), corners)
            })
            .collect()
    }
}

/// A set of element indices for one traversal: a small open-addressing
/// table on the stack while it is at most half full (cells have tens of
/// faces; a heap hash set costs more than the traversal), a hash set
/// beyond.
struct SeenSet {
    slots: [u32; SeenSet::SLOTS],
    len: usize,
    many: Option<HashSet<u32>>,
}

impl Default for SeenSet {
    fn default() -> Self {
        Self {
            slots: [SeenSet::EMPTY; SeenSet::SLOTS],
            len: 0,
            many: None,
        }
    }
}

impl SeenSet {
    /// Table size, a power of two.
    const SLOTS: usize = 128;
    /// Entries kept in the table before switching to hashing.
    const FEW: usize = Self::SLOTS / 2;
    /// Marks a free slot (no element index is `u32::MAX`).
    const EMPTY: u32 = u32::MAX;

    /// Adds `x`; true when it was not in the set yet.
    #[inline]
    fn insert(&mut self, x: u32) -> bool {
        debug_assert_ne!(x, Self::EMPTY);
        if let Some(many) = &mut self.many {
            return many.insert(x);
        }
        // Fibonacci hashing to 7 bits, then linear probing.
        let mut i = (x.wrapping_mul(0x9E37_79B9) >> 25) as usize;
        loop {
            let slot = self.slots[i];
            if slot == x {
                return false;
            }
            if slot == Self::EMPTY {
                break;
            }
            i = (i + 1) & (Self::SLOTS - 1);
        }
        if self.len == Self::FEW {
            let mut many: HashSet<u32> = self
                .slots
                .iter()
                .copied()
                .filter(|&v| v != Self::EMPTY)
                .collect();
            many.insert(x);
            self.many = Some(many);
        } else {
            self.slots[i] = x;
            self.len += 1;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::{ConvexArena, HalfEdge};
    use crate::exact::IntPoint;

    /// A box gets the twins that pairing its half-edges by their ends
    /// gives, in an arena holding other polyhedra too.
    #[test]
    fn box_twins_are_those_of_the_ends() {
        let mut arena = ConvexArena::new();
        let p = |c| IntPoint::new(c, c, c).expect("in budget");
        arena.add_box(p(0), p(3)).expect("a box");
        let h0 = arena.half_edges.len() as u32;
        arena.add_box(p(-5), p(7)).expect("a box");
        let mut paired = arena.clone();
        for e in &mut paired.half_edges[h0 as usize..] {
            e.twin = u32::MAX;
        }
        paired.link_twins(h0);
        assert!(
            paired
                .half_edges
                .iter()
                .all(|e: &HalfEdge| e.twin != u32::MAX)
        );
        assert_eq!(arena.half_edges, paired.half_edges);
    }
}
