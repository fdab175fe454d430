//! Cutting a convex polyhedron by a plane, exactly and in place
//! (paper 1 §3.3, Figs. 3–4).
//!
//! Notation: `s` — the cutting plane; a vertex is `+`, `0` or `−` by
//! [`classify_vertex`] against `s`; *crossing* edges join a `+` and a `−`
//! vertex; the *section* is the polygon `s ∩ P`.
//!
//! A cut is *proper* when both parts have volume, i.e. some vertex is `+`
//! and some is `−`. Then:
//! 1. every crossing edge is split at its exact intersection with `s`
//!    (the new vertex is the meet of the edge's two face planes and `s`);
//! 2. every face with `+` and `−` vertices now has exactly two `0`
//!    vertices, and is split by a new edge between them;
//! 3. the section boundary (new edges and old edges lying in `s`) gets two
//!    cap faces, `s` for the lower part and `−s` for the upper part, and its
//!    vertices are duplicated so the parts share nothing.
//!
//! [`ConvexArena::cut_naive`] finds the crossing edges by classifying every
//! vertex; the edge-descent search of the paper replaces only that step.

use std::collections::HashMap;

use super::mesh::{ConvexArena, Face, HalfEdge, PolyId, Vertex};
use crate::exact::{Plane, Sign, classify_vertex, intersect_3_planes};

/// The result of cutting a polyhedron `P` by a plane `s`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CutOutcome {
    /// `P` was split in place into the part below `s` (`n·x + d ≤ 0`) and
    /// the part above.
    Split {
        /// The part in the negative half-space of `s`.
        below: PolyId,
        /// The part in the positive half-space of `s`.
        above: PolyId,
    },
    /// No proper intersection: `P` lies in the closed negative half-space.
    Below,
    /// No proper intersection: `P` lies in the closed positive half-space.
    Above,
}

impl ConvexArena {
    /// Cuts `poly` by `s`, classifying every vertex to find the crossing
    /// edges (the reference for the edge-descent cut). New cap faces get
    /// tags `below_tag` (the lower part's cap, whose outside is above `s`)
    /// and `above_tag`.
    pub fn cut_naive(
        &mut self,
        poly: PolyId,
        s: &Plane,
        below_tag: u32,
        above_tag: u32,
    ) -> CutOutcome {
        let vertices = self.vertices_of(poly);
        let sides: HashMap<u32, Sign> = vertices
            .iter()
            .map(|&v| (v, classify_vertex(&self.vertices[v as usize].point, s)))
            .collect();
        let any = |sign: Sign| sides.values().any(|&x| x == sign);
        match (any(Sign::Negative), any(Sign::Positive)) {
            (true, true) => {}
            (false, _) => return CutOutcome::Above,
            (true, false) => return CutOutcome::Below,
        }
        let faces = self.faces_of(poly);
        let mut sides = sides;
        // 1. Split crossing edges (each once: from its + end).
        let mut crossing = Vec::new();
        for &f in &faces {
            for h in self.face_loop(f) {
                let e = self.half_edges[h as usize];
                if sides[&e.origin] == Sign::Positive && sides[&self.dest(h)] == Sign::Negative {
                    crossing.push(h);
                }
            }
        }
        for h in crossing {
            let m = self.split_edge(h, s);
            sides.insert(m, Sign::Zero);
        }
        // 2. Split straddling faces.
        let mut all_faces = faces.clone();
        for &f in &faces {
            let has = |sign| {
                self.face_loop(f)
                    .any(|h| sides[&self.half_edges[h as usize].origin] == sign)
            };
            if has(Sign::Positive) && has(Sign::Negative) {
                all_faces.push(self.split_face(f, &sides));
            }
        }
        // 3. Caps from the half-edges lying in s.
        self.add_caps(&all_faces, &sides, s, below_tag, above_tag)
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

    /// Splits face `f` (with `+` and `−` vertices and exactly two `0`
    /// vertices) along the segment between its `0` vertices. The half of
    /// the loop on the `+` side gets a new face, which is returned.
    fn split_face(&mut self, f: u32, sides: &HashMap<u32, Sign>) -> u32 {
        let loop_: Vec<u32> = self.face_loop(f).collect();
        let n = loop_.len();
        let origin = |k: usize| self.half_edges[loop_[k % n] as usize].origin;
        let zeros: Vec<usize> = (0..n)
            .filter(|&k| sides[&origin(k)] == Sign::Zero)
            .collect();
        debug_assert_eq!(
            zeros.len(),
            2,
            "a straddling face has two vertices on the plane"
        );
        let (i, j) = (zeros[0], zeros[1]);
        // Chain i..j (half-edges loop_[i], …, loop_[j−1]) and chain j..i.
        let chain_ij_positive = sides[&origin(i + 1)] == Sign::Positive;
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
        self.half_edges[loop_[(j + n - 1) % n] as usize].next = a;
        self.half_edges[loop_[(i + n - 1) % n] as usize].next = b;
        for &h in &loop_[i..j] {
            self.half_edges[h as usize].face = face_ij;
        }
        for k in j..i + n {
            self.half_edges[loop_[k % n] as usize].face = face_ji;
        }
        self.faces.push(Face {
            plane,
            half_edge: if chain_ij_positive { a } else { b },
            tag,
        });
        self.faces[f as usize].half_edge = if chain_ij_positive { b } else { a };
        new_face
    }

    /// Builds the two caps along the section and separates the parts;
    /// `faces` lists every face of both parts.
    fn add_caps(
        &mut self,
        faces: &[u32],
        sides: &HashMap<u32, Sign>,
        s: &Plane,
        below_tag: u32,
        above_tag: u32,
    ) -> CutOutcome {
        // A face is on the + side when one of its vertices is +.
        let face_side = |arena: &Self, f: u32| -> Sign {
            arena
                .face_loop(f)
                .map(|h| sides[&arena.half_edges[h as usize].origin])
                .find(|&x| x != Sign::Zero)
                .unwrap_or(Sign::Zero)
        };
        // The half-edges lying in s, with the side of their face.
        let mut section: Vec<(u32, Sign)> = Vec::new();
        for &f in faces {
            let side = face_side(self, f);
            for h in self.face_loop(f) {
                let e = self.half_edges[h as usize];
                if sides[&e.origin] == Sign::Zero && sides[&self.dest(h)] == Sign::Zero {
                    section.push((h, side));
                }
            }
        }
        // Duplicate the section vertices for the upper part.
        let mut upper_copy: HashMap<u32, u32> = HashMap::new();
        for &(h, side) in &section {
            if side == Sign::Positive {
                for v in [self.half_edges[h as usize].origin, self.dest(h)] {
                    upper_copy.entry(v).or_insert_with(|| {
                        self.vertices.push(self.vertices[v as usize]);
                        self.vertices.len() as u32 - 1
                    });
                }
            }
        }
        for &f in faces {
            if face_side(self, f) == Sign::Positive {
                for h in self.face_loop(f).collect::<Vec<_>>() {
                    let o = self.half_edges[h as usize].origin;
                    if let Some(&copy) = upper_copy.get(&o) {
                        self.half_edges[h as usize].origin = copy;
                        self.vertices[copy as usize].half_edge = h;
                    }
                }
            } else {
                for h in self.face_loop(f).collect::<Vec<_>>() {
                    let o = self.half_edges[h as usize].origin;
                    if upper_copy.contains_key(&o) {
                        self.vertices[o as usize].half_edge = h;
                    }
                }
            }
        }
        // One cap per side: for each section half-edge u→v on a face of that
        // side, the cap gets v→u, and cap edges chain by shared vertices.
        let mut caps = [
            (Sign::Negative, *s, below_tag),
            (Sign::Positive, s.flipped(), above_tag),
        ]
        .map(|(side, plane, tag)| (side, plane, tag, u32::MAX));
        for (side, plane, tag, cap_edge) in caps.iter_mut() {
            let cap = self.faces.len() as u32;
            let mut starting_at: HashMap<u32, u32> = HashMap::new();
            let mut cap_edges = Vec::new();
            for &(h, hside) in &section {
                if hside != *side {
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
                starting_at.insert(v, c);
                cap_edges.push((c, u));
            }
            for &(c, u) in &cap_edges {
                self.half_edges[c as usize].next = starting_at[&u];
            }
            self.faces.push(Face {
                plane: *plane,
                half_edge: cap_edges[0].0,
                tag: *tag,
            });
            *cap_edge = cap_edges[0].0;
        }
        CutOutcome::Split {
            below: PolyId(caps[0].3),
            above: PolyId(caps[1].3),
        }
    }
}
