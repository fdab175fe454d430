//! Splitting a convex polyhedron along its section with a plane, once the
//! faces that meet the section are known (paper 1 §3.3, Fig. 4).
//!
//! Notation as in [`super::cut`]: `s` — the cutting plane; vertices are
//! `+`, `0` or `−`; a *crossing* edge joins `+` and `−`; a face is
//! *straddling* when it has `+` and `−` vertices, *touching* when it lies
//! on one side with an edge in `s`.
//!
//! Each face that meets the section is walked once, before anything
//! changes, to learn its kind, its crossing edges and its edge in `s`. Then
//! crossing edges are split (the only exact constructions), straddling
//! faces are split between their two `0` vertices (the new face takes the
//! `+` half), and the section edges, known by now without another walk,
//! get the two caps.

use super::cut::CutOutcome;
use super::mesh::{ConvexArena, Face, HalfEdge, PolyId, Vertex};
use super::scratch::{FaceInfo, Scratch};
use crate::exact::{Plane, Sign, intersect_3_planes};

impl ConvexArena {
    /// Splits along the section, given the faces that meet it in
    /// `scratch.relevant` with their vertices classified.
    pub(super) fn split_along(
        &mut self,
        scratch: &mut Scratch,
        s: &Plane,
        below_tag: u32,
        above_tag: u32,
    ) -> CutOutcome {
        let mut relevant = std::mem::take(&mut scratch.relevant);
        let mut info = std::mem::take(&mut scratch.relevant_info);
        let mut crossing = std::mem::take(&mut scratch.crossing);
        let mut section = std::mem::take(&mut scratch.section);
        let mut section_new = std::mem::take(&mut scratch.section_new);
        // Sorted, so the result does not depend on how the faces were found.
        relevant.sort_unstable();
        info.clear();
        crossing.clear();
        for &f in &relevant {
            info.push(self.survey_face(f, scratch, &mut crossing));
        }
        // 1. Split crossing edges.
        for &h in &crossing {
            let m = self.split_edge(h, s);
            scratch.sides.insert(m, Sign::Zero);
        }
        // 2. Split straddling faces; list the section edges, those of the
        // new faces last.
        section.clear();
        section_new.clear();
        for (&f, &kind) in relevant.iter().zip(&info) {
            match kind {
                FaceInfo::Straddling => {
                    let (kept, new) = self.split_face(f, scratch);
                    section.push((kept, Sign::Negative));
                    section_new.push((new, Sign::Positive));
                }
                FaceInfo::Touching { side, edge } => section.push((edge, side)),
            }
        }
        section.extend_from_slice(&section_new);
        // 3. Caps.
        let outcome = self.add_caps(&section, scratch, s, below_tag, above_tag);
        scratch.relevant = relevant;
        scratch.relevant_info = info;
        scratch.crossing = crossing;
        scratch.section = section;
        scratch.section_new = section_new;
        outcome
    }

    /// One walk around face `f` (all vertices classified): its kind, and
    /// its crossing half-edges (from their `+` end) appended to `crossing`.
    fn survey_face(&self, f: u32, scratch: &Scratch, crossing: &mut Vec<u32>) -> FaceInfo {
        let side = |h: u32| Self::known_side(self.half_edges[h as usize].origin, scratch);
        let first = self.faces[f as usize].half_edge;
        let first_side = side(first);
        let (mut h, mut here) = (first, first_side);
        let (mut plus, mut minus, mut in_plane) = (false, false, u32::MAX);
        loop {
            let next = self.half_edges[h as usize].next;
            let there = if next == first {
                first_side
            } else {
                side(next)
            };
            plus |= here == Sign::Positive;
            minus |= here == Sign::Negative;
            if here == Sign::Positive && there == Sign::Negative {
                crossing.push(h);
            } else if here == Sign::Zero && there == Sign::Zero {
                debug_assert_eq!(in_plane, u32::MAX, "a face has one edge in the plane");
                in_plane = h;
            }
            if next == first {
                break;
            }
            (h, here) = (next, there);
        }
        if plus && minus {
            FaceInfo::Straddling
        } else {
            debug_assert_ne!(in_plane, u32::MAX, "the face meets the section");
            FaceInfo::Touching {
                side: if plus { Sign::Positive } else { Sign::Negative },
                edge: in_plane,
            }
        }
    }

    /// Splits the edge of half-edge `h` at its intersection with `s`;
    /// returns the new vertex, which `h` now ends at.
    fn split_edge(&mut self, h: u32, s: &Plane) -> u32 {
        let e = self.half_edges[h as usize];
        let t = self.half_edges[e.twin as usize];
        let point = intersect_3_planes(
            &self.faces[e.face as usize].plane,
            &self.faces[t.face as usize].plane,
            s,
        )
        .expect("a crossing edge meets the cutting plane in one point");
        let m = self.vertices.len() as u32;
        let (h2, t2) = (
            self.half_edges.len() as u32,
            self.half_edges.len() as u32 + 1,
        );
        // h: a→b becomes a→m, h2: m→b; twin t: b→a becomes b→m, t2: m→a.
        self.half_edges.push(HalfEdge {
            origin: m,
            twin: e.twin,
            next: e.next,
            face: e.face,
        });
        self.half_edges.push(HalfEdge {
            origin: m,
            twin: h,
            next: t.next,
            face: t.face,
        });
        self.half_edges[h as usize].next = h2;
        self.half_edges[h as usize].twin = t2;
        self.half_edges[e.twin as usize].next = t2;
        self.half_edges[e.twin as usize].twin = h2;
        self.vertices.push(Vertex {
            point,
            half_edge: h2,
        });
        m
    }

    /// Splits straddling face `f` (now with exactly two `0` vertices) along
    /// the segment between them: `f` keeps the `−` half and a new face gets
    /// the `+` half. Returns the new half-edge in `s` of each half, `f`'s
    /// first.
    fn split_face(&mut self, f: u32, scratch: &mut Scratch) -> (u32, u32) {
        let mut loop_ = std::mem::take(&mut scratch.face_loop);
        loop_.clear();
        let (mut i, mut j) = (usize::MAX, usize::MAX);
        let first = self.faces[f as usize].half_edge;
        let mut h = first;
        loop {
            if Self::known_side(self.half_edges[h as usize].origin, scratch) == Sign::Zero {
                if i == usize::MAX {
                    i = loop_.len();
                } else if j == usize::MAX {
                    j = loop_.len();
                }
            }
            loop_.push(h);
            h = self.half_edges[h as usize].next;
            if h == first {
                break;
            }
        }
        assert!(
            j != usize::MAX,
            "a straddling face has two vertices on the plane"
        );
        let n = loop_.len();
        let origin = |k: usize| self.half_edges[loop_[k] as usize].origin;
        // Chain i..j (half-edges loop_[i], …, loop_[j−1]) and chain j..i;
        // each has a vertex off the plane, so i + 1 < j.
        let chain_ij_positive = Self::known_side(origin(i + 1), scratch) == Sign::Positive;
        let (z1, z2) = (origin(i), origin(j));
        let (a, b) = (
            self.half_edges.len() as u32,
            self.half_edges.len() as u32 + 1,
        );
        // a: z2→z1 closes chain i..j; b: z1→z2 closes chain j..i. Twins are
        // set when the caps are built.
        let new_face = self.faces.len() as u32;
        let plane = self.faces[f as usize].plane;
        let tag = self.faces[f as usize].tag;
        let (face_ij, face_ji) = if chain_ij_positive {
            (new_face, f)
        } else {
            (f, new_face)
        };
        self.half_edges.push(HalfEdge {
            origin: z2,
            twin: u32::MAX,
            next: loop_[i],
            face: face_ij,
        });
        self.half_edges.push(HalfEdge {
            origin: z1,
            twin: u32::MAX,
            next: loop_[j],
            face: face_ji,
        });
        self.half_edges[loop_[j - 1] as usize].next = a;
        self.half_edges[loop_[if i == 0 { n - 1 } else { i - 1 }] as usize].next = b;
        if chain_ij_positive {
            for &h in &loop_[i..j] {
                self.half_edges[h as usize].face = new_face;
            }
        } else {
            for &h in loop_[j..].iter().chain(&loop_[..i]) {
                self.half_edges[h as usize].face = new_face;
            }
        }
        let (kept, new) = if chain_ij_positive { (b, a) } else { (a, b) };
        self.faces.push(Face {
            plane,
            half_edge: new,
            tag,
        });
        self.faces[f as usize].half_edge = kept;
        scratch.face_loop = loop_;
        (kept, new)
    }

    /// Builds the two caps along the section and separates the parts;
    /// `section` lists every half-edge lying in `s` with the side of its
    /// face.
    fn add_caps(
        &mut self,
        section: &[(u32, Sign)],
        scratch: &mut Scratch,
        s: &Plane,
        below_tag: u32,
        above_tag: u32,
    ) -> CutOutcome {
        // One cap per side: for each section half-edge u→v on a face of that
        // side, the cap gets v→u, and cap edges chain by shared vertices.
        let mut cap_edges = std::mem::take(&mut scratch.cap_edges);
        let mut first_cap_edge = [u32::MAX; 2];
        for (k, (side, plane, tag)) in [
            (Sign::Negative, *s, below_tag),
            (Sign::Positive, s.flipped(), above_tag),
        ]
        .into_iter()
        .enumerate()
        {
            let cap = self.faces.len() as u32;
            let first = self.half_edges.len() as u32;
            scratch.cap_starts.clear();
            cap_edges.clear();
            for &(h, hside) in section {
                if hside != side {
                    continue;
                }
                let (u, v) = (self.half_edges[h as usize].origin, self.dest(h));
                let c = self.half_edges.len() as u32;
                self.half_edges.push(HalfEdge {
                    origin: v,
                    twin: h,
                    next: u32::MAX,
                    face: cap,
                });
                self.half_edges[h as usize].twin = c;
                scratch.cap_starts.insert(v, c);
                cap_edges.push((c, u));
            }
            for &(c, u) in &cap_edges {
                self.half_edges[c as usize].next = scratch
                    .cap_starts
                    .get(u)
                    .expect("the section is a closed loop");
            }
            self.faces.push(Face {
                plane,
                half_edge: first,
                tag,
            });
            first_cap_edge[k] = first;
            if side == Sign::Negative {
                // The lower part keeps the section vertices.
                for &(c, _) in &cap_edges {
                    let v = self.half_edges[c as usize].origin;
                    self.vertices[v as usize].half_edge = c;
                }
            } else {
                // The upper part gets copies: rotate around each section
                // vertex through the upper part's half-edges (now closed off
                // by the cap) and re-point their origins.
                for &(c, _) in &cap_edges {
                    let v = self.half_edges[c as usize].origin;
                    let copy = self.vertices.len() as u32;
                    self.vertices.push(Vertex {
                        point: self.vertices[v as usize].point,
                        half_edge: c,
                    });
                    let mut h = c;
                    loop {
                        self.half_edges[h as usize].origin = copy;
                        h = self.half_edges[self.half_edges[h as usize].twin as usize].next;
                        if h == c {
                            break;
                        }
                    }
                }
            }
        }
        scratch.cap_edges = cap_edges;
        CutOutcome::Split {
            below: PolyId(first_cap_edge[0]),
            above: PolyId(first_cap_edge[1]),
        }
    }
}
