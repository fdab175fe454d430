//! Splitting a convex polyhedron along its section with a plane, once the
//! faces that meet the section are known (paper 1 §3.3, Fig. 4).
//!
//! Notation as in [`super::cut`]: `s` — the cutting plane; vertices are
//! `+`, `0` or `−`; a *crossing* edge joins `+` and `−`; a face is
//! *straddling* when it has `+` and `−` vertices, *touching* when it lies
//! on one side with an edge in `s`.
//!
//! Each face that meets the section has been walked once, before anything
//! changes (by the march, or by the naive cut's survey), and comes with
//! what that walk found (`survey`): its kind, its crossing edge and its
//! edge in `s`. Then crossing edges are split (the only exact constructions), straddling
//! faces are split between their two `0` vertices (the new face takes the
//! `+` half), and the section edges, known by now without another walk,
//! get the two caps.
//!
//! A one-sided split (*kept side* `k`, for [`ConvexArena::cut_keeping`])
//! builds only the part on side `k`: a straddling face keeps its `k` half,
//! faces on the other side are left as they are, and only the cap of that
//! part is built, on the section vertices themselves.

use super::mesh::{ConvexArena, Face, HalfEdge, Vertex};
use super::scratch::FaceInfo;
use super::scratch::Scratch;
use super::stamp_map::StampMap;
use super::survey::FaceSurvey;
use crate::exact::{Plane, Sign, intersect_3_planes_with};

impl ConvexArena {
    /// Splits along the section, given the faces that meet it in
    /// `scratch.relevant` with their vertices classified; `tags` are those
    /// of the lower and upper part's caps. Builds both parts, or with
    /// `keep`, only the part on that side. Returns the first half-edge of
    /// each part's cap (`u32::MAX` for a part not built).
    pub(super) fn split_along(
        &mut self,
        scratch: &mut Scratch,
        s: &Plane,
        tags: [u32; 2],
        keep: Option<Sign>,
    ) -> [u32; 2] {
        // The scratch lists are borrowed in place (they are apart from the
        // arena's arrays), not taken out and put back.
        // Sorted, so the result does not depend on how the faces were found.
        sort_by_face(&mut scratch.relevant);
        let relevant = &scratch.relevant;
        let counts = Counts::of(relevant);
        let two_sided = keep.is_none();
        let built = [
            keep.is_none_or(|k| k == Sign::Negative),
            keep.is_none_or(|k| k == Sign::Positive),
        ];
        // The section half-edges of each part built, one per cap half-edge.
        let sizes = [0, 1].map(|k| {
            if built[k] {
                counts.straddling + counts.touching[k]
            } else {
                0
            }
        });
        // Every half-edge, face and vertex the split adds, in the order
        // they are made: the halves of the crossing edges, then of the
        // straddling faces (and the new faces), then the caps; the crossing
        // vertices, then the copies of the section vertices for the upper
        // part.
        let (h0, f0, v0) = (self.half_edges.len(), self.faces.len(), self.vertices.len());
        let face_halves = if two_sided { 2 } else { 1 };
        let new_faces = if two_sided { counts.straddling } else { 0 };
        let caps = usize::from(built[0]) + usize::from(built[1]);
        let copies = if two_sided { sizes[1] } else { 0 };
        self.grow(
            2 * counts.crossings + face_halves * counts.straddling + sizes[0] + sizes[1],
            new_faces + caps,
            counts.crossings + copies,
        );
        // 1. Split crossing edges.
        self.split_edges(relevant, counts.crossings, s, h0 as u32, v0 as u32);
        // 2. Split (or trim) straddling faces, listing the section edges of
        // each part: `section[0]` in face order, `section[1]` the touching
        // faces' first, then those of the new faces.
        let section = &mut scratch.section;
        for list in section.iter_mut() {
            list.clear();
        }
        if built[1] {
            section[1].resize(counts.touching[1], u32::MAX);
        }
        let mut next = Next {
            half_edge: (h0 + 2 * counts.crossings) as u32,
            face: f0 as u32,
        };
        split_faces(
            &mut self.half_edges,
            &mut self.faces,
            relevant,
            keep,
            section,
            &mut next,
        );
        debug_assert_eq!([section[0].len(), section[1].len()], sizes);
        // 3. Caps.
        let mut first_cap_edge = [u32::MAX; 2];
        for k in 0..2 {
            if !built[k] {
                continue;
            }
            let plane = self.push_plane(if k == 0 { *s } else { s.flipped() });
            let cap = next.face;
            next.face += 1;
            self.faces[cap as usize] = Face {
                plane,
                half_edge: next.half_edge,
                tag: tags[k],
            };
            first_cap_edge[k] = next.half_edge;
            // The lower part (or the only part built) keeps the section
            // vertices; the upper part gets copies.
            let keeps_vertices = k == 0 || !two_sided;
            add_cap(
                &mut self.half_edges,
                &mut self.vertices,
                &mut scratch.cap_starts,
                &section[k],
                cap,
                next.half_edge,
                keeps_vertices,
            );
            next.half_edge += section[k].len() as u32;
        }
        debug_assert_eq!(next.half_edge as usize, self.half_edges.len());
        debug_assert_eq!(next.face as usize, self.faces.len());
        first_cap_edge
    }

    /// Splits the crossing edges of the straddling faces in `relevant` (in
    /// that order), `crossings` of them, at their intersections with `s`:
    /// crossing `i` gets vertex `v0 + i` and half-edges `h0 + 2i` (after
    /// the half-edge split) and `h0 + 2i + 1` (after its twin), whose slots
    /// are there already.
    fn split_edges(
        &mut self,
        relevant: &[(u32, FaceInfo)],
        crossings: usize,
        s: &Plane,
        h0: u32,
        v0: u32,
    ) {
        let crossing_edges = relevant.iter().filter_map(|&(_, info)| match info {
            FaceInfo::Straddling { crossing, .. } if crossing != u32::MAX => Some(crossing),
            _ => None,
        });
        let p0 = self.points.len() as u32;
        self.points.reserve(crossings);
        for (i, h) in (0u32..).zip(crossing_edges) {
            self.split_crossing(h, s, h0 + 2 * i, v0 + i, p0 + i);
        }
    }

    /// Splits the edge of half-edge `h` (from `+` to `−`) at its meet with
    /// `s` (of the planes of the edge's two faces and `s`): new vertex `m`
    /// at point `p` (pushed: the next point), half-edges `h2 = first` after
    /// `h` and `t2 = first + 1` after its twin `t`, whose slots are there
    /// already. Both splits (`split_ring_both` too) split edges this way.
    #[inline(always)]
    pub(super) fn split_crossing(&mut self, h: u32, s: &Plane, first: u32, m: u32, p: u32) {
        let (h2, t2) = (first, first + 1);
        let e = self.half_edges[h as usize];
        let t = self.half_edges[e.twin as usize];
        let (faces, planes, points) = (&self.faces, &self.planes, &mut self.points);
        let plane = |f: u32| &planes[faces[f as usize].plane as usize];
        debug_assert_eq!(points.len() as u32, p);
        intersect_3_planes_with(plane(e.face), plane(t.face), s, |point| points.push(point))
            .expect("a crossing edge meets the cutting plane in one point");
        self.vertices[m as usize] = Vertex {
            point: p,
            half_edge: h2,
        };
        // h: a→b becomes a→m, h2: m→b; twin t: b→a becomes b→m, t2: m→a.
        self.half_edges[h2 as usize] = HalfEdge {
            origin: m,
            twin: e.twin,
            next: e.next,
            face: e.face,
        };
        self.half_edges[t2 as usize] = HalfEdge {
            origin: m,
            twin: h,
            next: t.next,
            face: t.face,
        };
        let old = &mut self.half_edges[h as usize];
        (old.next, old.twin) = (h2, t2);
        let old_twin = &mut self.half_edges[e.twin as usize];
        (old_twin.next, old_twin.twin) = (t2, h2);
    }

    /// Grows the half-edge, face and vertex arrays by the given counts, for
    /// a split to write the new elements at known indices.
    #[inline]
    pub(super) fn grow(&mut self, half_edges: usize, faces: usize, vertices: usize) {
        let half_edge = HalfEdge {
            origin: 0,
            twin: 0,
            next: 0,
            face: 0,
        };
        self.half_edges
            .resize(self.half_edges.len() + half_edges, half_edge);
        let face = Face {
            plane: 0,
            half_edge: 0,
            tag: 0,
        };
        self.faces.resize(self.faces.len() + faces, face);
        let vertex = Vertex {
            point: 0,
            half_edge: 0,
        };
        self.vertices.resize(self.vertices.len() + vertices, vertex);
    }

    /// What the split needs to know about face `f` (all vertices
    /// classified), from one walk around it; `None` when it does not meet
    /// the section.
    pub(super) fn survey_face(&self, f: u32, scratch: &Scratch) -> Option<FaceInfo> {
        let side = |h: u32| Self::known_side(self.half_edges[h as usize].origin, scratch);
        let first = self.faces[f as usize].half_edge;
        let first_side = side(first);
        let mut survey = FaceSurvey::new();
        let (mut h, mut before, mut here) = (first, u32::MAX, first_side);
        loop {
            let next = self.half_edges[h as usize].next;
            let there = if next == first {
                first_side
            } else {
                side(next)
            };
            if here != there || here == Sign::Zero {
                survey.step(h, before, here, there);
            }
            if next == first {
                break;
            }
            (before, h, here) = (h, next, there);
        }
        survey.finish(h)
    }
}

/// How many faces of each kind meet the section.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    /// Straddling faces.
    straddling: usize,
    /// Straddling faces with a crossing half-edge (from `+` to `−`).
    crossings: usize,
    /// Touching faces on the lower and on the upper side.
    touching: [usize; 2],
}

impl Counts {
    /// The counts of the faces in `relevant`.
    #[inline]
    fn of(relevant: &[(u32, FaceInfo)]) -> Self {
        let mut counts = Counts::default();
        for (_, info) in relevant {
            match *info {
                FaceInfo::Straddling { crossing, .. } => {
                    counts.straddling += 1;
                    counts.crossings += usize::from(crossing != u32::MAX);
                }
                FaceInfo::Touching { side, .. } => {
                    counts.touching[usize::from(side == Sign::Positive)] += 1;
                }
            }
        }
        counts
    }
}

/// The indices of the next half-edge and face the split writes.
#[derive(Clone, Copy, Debug)]
struct Next {
    half_edge: u32,
    face: u32,
}

/// Step 2 of the split, on the arrays grown to their final sizes: splits
/// each straddling face of `relevant` (crossing edges split) between its
/// two `0` vertices — the face keeps its `−` half and a new face gets the
/// `+` half — or with `keep`, trims it to its half on that side; lists the
/// section half-edges in `section` (those of touching faces above first,
/// in the slots `section[1]` has for them).
fn split_faces(
    half_edges: &mut [HalfEdge],
    faces: &mut [Face],
    relevant: &[(u32, FaceInfo)],
    keep: Option<Sign>,
    section: &mut [Vec<u32>; 2],
    next: &mut Next,
) {
    // `section[1]` holds a slot for each touching face above already.
    let [below, above] = section;
    let mut n_touching = 0;
    for &(f, info) in relevant {
        match info {
            FaceInfo::Straddling {
                enter, first_chain, ..
            } => {
                // The half-edges leaving the two `0` vertices.
                let leave = enter.map(|e| half_edges[e as usize].next);
                match keep {
                    None => {
                        let (kept, new) =
                            split_face(half_edges, faces, f, enter, leave, first_chain, next);
                        below.push(kept);
                        above.push(new);
                    }
                    Some(side) => {
                        // Listed where the two-sided split lists them, so
                        // that the kept part comes out the same.
                        let edge = next.half_edge;
                        next.half_edge += 1;
                        // The kept chain runs from zero k to zero 1 − k;
                        // the new half-edge closes it, from zero 1 − k
                        // back to zero k.
                        let k = usize::from(first_chain != side);
                        half_edges[edge as usize] = HalfEdge {
                            origin: half_edges[leave[1 - k] as usize].origin,
                            twin: u32::MAX,
                            next: leave[k],
                            face: f,
                        };
                        half_edges[enter[1 - k] as usize].next = edge;
                        faces[f as usize].half_edge = edge;
                        if side == Sign::Negative {
                            below.push(edge);
                        } else {
                            above.push(edge);
                        }
                    }
                }
            }
            FaceInfo::Touching { side, edge } => {
                if keep.is_none_or(|k| k == side) {
                    if side == Sign::Positive {
                        above[n_touching] = edge;
                        n_touching += 1;
                    } else {
                        below.push(edge);
                    }
                }
            }
        }
    }
}

/// Splits straddling face `f` along the segment between its two `0`
/// vertices, entered by half-edges `enter` and left by `leave` in loop
/// order: `f` keeps the `−` half and a new face gets the `+` half. Returns
/// the new half-edge in `s` of each half, `f`'s first.
#[inline]
fn split_face(
    half_edges: &mut [HalfEdge],
    faces: &mut [Face],
    f: u32,
    enter: [u32; 2],
    leave: [u32; 2],
    first_chain: Sign,
    next: &mut Next,
) -> (u32, u32) {
    let (z1, z2) = (
        half_edges[leave[0] as usize].origin,
        half_edges[leave[1] as usize].origin,
    );
    // Chain 0 runs from z1 to z2 (half-edges leave[0] … enter[1]), chain 1
    // from z2 to z1; a: z2→z1 closes chain 0, b: z1→z2 closes chain 1.
    // Twins are set when the caps are built.
    let chain_0_positive = first_chain == Sign::Positive;
    let (a, b) = (next.half_edge, next.half_edge + 1);
    next.half_edge += 2;
    let new_face = next.face;
    next.face += 1;
    let (face_0, face_1) = if chain_0_positive {
        (new_face, f)
    } else {
        (f, new_face)
    };
    // The `+` chain moves to the new face (before the loop is cut).
    let (start, end) = if chain_0_positive {
        (leave[0], enter[1])
    } else {
        (leave[1], enter[0])
    };
    let mut h = start;
    loop {
        let e = &mut half_edges[h as usize];
        e.face = new_face;
        if h == end {
            break;
        }
        h = e.next;
    }
    half_edges[a as usize] = HalfEdge {
        origin: z2,
        twin: u32::MAX,
        next: leave[0],
        face: face_0,
    };
    half_edges[b as usize] = HalfEdge {
        origin: z1,
        twin: u32::MAX,
        next: leave[1],
        face: face_1,
    };
    half_edges[enter[1] as usize].next = a;
    half_edges[enter[0] as usize].next = b;
    let (kept, new) = if chain_0_positive { (b, a) } else { (a, b) };
    let face = faces[f as usize];
    faces[new_face as usize] = Face {
        half_edge: new,
        ..face
    };
    faces[f as usize].half_edge = kept;
    (kept, new)
}

/// Builds the cap face `cap` on the half-edges from `first` on, one per
/// section half-edge of `section` (a closed loop): for `h` from `u` to
/// `v`, the cap gets its twin from `v` to `u`, and cap half-edges chain by
/// shared vertices. The part keeps the section vertices with
/// `keeps_vertices`, else gets copies (appended to `vertices`, whose slots
/// are there already), sharing their exact points.
fn add_cap(
    half_edges: &mut [HalfEdge],
    vertices: &mut [Vertex],
    starts: &mut StampMap<u32>,
    section: &[u32],
    cap: u32,
    first: u32,
    keeps_vertices: bool,
) {
    starts.clear();
    let count = section.len() as u32;
    for (c, &h) in (first..).zip(section) {
        let e = half_edges[h as usize];
        let v = half_edges[e.next as usize].origin;
        half_edges[h as usize].twin = c;
        starts.insert(v, c);
        // `next` holds `u` until every start is known.
        half_edges[c as usize] = HalfEdge {
            origin: v,
            twin: h,
            next: e.origin,
            face: cap,
        };
        if keeps_vertices {
            vertices[v as usize].half_edge = c;
        }
    }
    for c in first..first + count {
        let e = &mut half_edges[c as usize];
        e.next = starts.get(e.next).expect("the section is a closed loop");
    }
    if keeps_vertices {
        return;
    }
    // The copies take the last slots, in the order of the cap: rotate
    // around each section vertex through the upper part's half-edges (now
    // closed off by the cap) and re-point their origins.
    let copies = vertices.len() as u32 - count;
    for (c, copy) in (first..first + count).zip(copies..) {
        let v = half_edges[c as usize].origin;
        vertices[copy as usize] = Vertex {
            point: vertices[v as usize].point,
            half_edge: c,
        };
        let mut h = c;
        loop {
            half_edges[h as usize].origin = copy;
            h = half_edges[half_edges[h as usize].twin as usize].next;
            if h == c {
                break;
            }
        }
    }
}

/// Sorts the faces that meet the section by face index. A plane meets few
/// faces of a convex polyhedron (a handful, typically), where an insertion
/// sort costs less than the general sort's set-up; long lists go to the
/// general sort. Face indices are distinct, so both give the same order.
pub(super) fn sort_by_face(relevant: &mut [(u32, FaceInfo)]) {
    const SHORT: usize = 24;
    if relevant.len() > SHORT {
        relevant.sort_unstable_by_key(|&(f, _)| f);
        return;
    }
    for i in 1..relevant.len() {
        // An entry above its predecessor stays where it is: only the keys
        // are read, not the whole entry.
        if relevant[i - 1].0 < relevant[i].0 {
            continue;
        }
        let item = relevant[i];
        let mut j = i;
        while j > 0 && relevant[j - 1].0 > item.0 {
            relevant[j] = relevant[j - 1];
            j -= 1;
        }
        relevant[j] = item;
    }
}
