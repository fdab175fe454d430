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

use super::mesh::{ConvexArena, Face, HalfEdge, PolyId, Vertex};
use super::scratch::Scratch;
use crate::exact::{
    Plane, Sign, classify_vertex, compare_offsets, intersect_3_planes, offset_estimate,
};

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
        self.with_scratch(|arena, scratch| {
            let faces = arena.faces_of(poly);
            let (mut plus, mut minus) = (false, false);
            for &f in &faces {
                for h in arena.face_loop(f) {
                    let side = arena.side(arena.half_edges[h as usize].origin, s, scratch);
                    plus |= side == Sign::Positive;
                    minus |= side == Sign::Negative;
                }
            }
            match (minus, plus) {
                (true, true) => {}
                (false, _) => return CutOutcome::Above,
                (true, false) => return CutOutcome::Below,
            }
            let relevant = faces
                .into_iter()
                .filter(|&f| arena.meets_section(f, scratch))
                .collect();
            arena.split_along(relevant, scratch, s, below_tag, above_tag)
        })
    }

    /// Cuts `poly` by `s` by edge descent and marching (paper 1 §3.3):
    /// walks from vertex to neighbouring vertex towards the far side of `s`
    /// until it finds the section or proves there is none (a vertex with no
    /// neighbour closer to the far side is a global extremum on a convex
    /// polyhedron), then marches around the section, classifying only the
    /// vertices of faces it visits. The result is identical, element for
    /// element, to [`ConvexArena::cut_naive`].
    pub fn cut(&mut self, poly: PolyId, s: &Plane, below_tag: u32, above_tag: u32) -> CutOutcome {
        self.with_scratch(|arena, scratch| {
            let v0 = arena.half_edges[poly.0 as usize].origin;
            // Walk towards the side v0 is not on; a `(from, to)` step onto
            // that side brackets the section. From a vertex on s, both sides
            // must exist for a proper cut, and v0 itself is on the section.
            let seeds = match arena.side(v0, s, scratch) {
                Sign::Positive => match arena.descend(v0, s, Sign::Negative, scratch) {
                    Some((from, to)) => [from, to],
                    None => return CutOutcome::Above,
                },
                Sign::Negative => match arena.descend(v0, s, Sign::Positive, scratch) {
                    Some((from, to)) => [from, to],
                    None => return CutOutcome::Below,
                },
                Sign::Zero => {
                    if arena.descend(v0, s, Sign::Negative, scratch).is_none() {
                        return CutOutcome::Above;
                    }
                    if arena.descend(v0, s, Sign::Positive, scratch).is_none() {
                        return CutOutcome::Below;
                    }
                    [v0, v0]
                }
            };
            let relevant = arena.march(&seeds, s, scratch);
            arena.split_along(relevant, scratch, s, below_tag, above_tag)
        })
    }

    /// Runs `op` with the arena's scratch space, cleared.
    fn with_scratch<T>(&mut self, op: impl FnOnce(&mut Self, &mut Scratch) -> T) -> T {
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        let out = op(self, &mut scratch);
        self.scratch = scratch;
        out
    }

    /// The side of vertex `v`, classified once per operation.
    #[inline]
    fn side(&self, v: u32, s: &Plane, scratch: &mut Scratch) -> Sign {
        scratch.sides.get(v).unwrap_or_else(|| {
            let side = classify_vertex(&self.vertices[v as usize].point, s);
            scratch.sides.insert(v, side);
            side
        })
    }

    /// The side of an already classified vertex.
    #[inline]
    fn known_side(v: u32, scratch: &Scratch) -> Sign {
        scratch.sides.get(v).expect("vertex classified before use")
    }

    /// The outgoing half-edges of vertex `v`.
    fn outgoing(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        let first = self.vertices[v as usize].half_edge;
        let mut h = Some(first);
        std::iter::from_fn(move || {
            let cur = h?;
            let next = self.half_edges[self.half_edges[cur as usize].twin as usize].next;
            h = (next != first).then_some(next);
            Some(cur)
        })
    }

    /// Edge descent from `start` (not on side `target`) towards side
    /// `target` of `s`: returns an adjacent pair `(from, to)` with `to` on
    /// side `target`, or `None` when no vertex is on that side.
    ///
    /// Each step moves to a neighbour certified to lie strictly closer to
    /// the target side — by the `f64` estimates and their error bounds, or
    /// else by exact comparison — so the walk never cycles, and it stops
    /// only at a vertex no neighbour improves on: a global extremum of the
    /// (linear) offset over the convex polyhedron.
    fn descend(
        &self,
        start: u32,
        s: &Plane,
        target: Sign,
        scratch: &mut Scratch,
    ) -> Option<(u32, u32)> {
        use core::cmp::Ordering;
        let toward = |a: f64| if target == Sign::Negative { -a } else { a };
        let wanted = if target == Sign::Negative {
            Ordering::Less
        } else {
            Ordering::Greater
        };
        let mut cur = start;
        loop {
            let (cur_value, cur_error) = offset_estimate(&self.vertices[cur as usize].point, s);
            let mut best: Option<(u32, f64)> = None;
            let mut uncertain: Option<u32> = None;
            for h in self.outgoing(cur) {
                let n = self.dest(h);
                if self.side(n, s, scratch) == target {
                    return Some((cur, n));
                }
                let (value, error) = offset_estimate(&self.vertices[n as usize].point, s);
                let gain = toward(value) - toward(cur_value);
                if gain > error + cur_error {
                    if best.is_none_or(|(_, g)| gain > g) {
                        best = Some((n, gain));
                    }
                } else if gain >= -(error + cur_error)
                    && uncertain.is_none()
                    && compare_offsets(
                        &self.vertices[n as usize].point,
                        &self.vertices[cur as usize].point,
                        s,
                    ) == wanted
                {
                    // Too close to call in f64: exactly closer.
                    uncertain = Some(n);
                }
            }
            cur = best.map(|(n, _)| n).or(uncertain)?;
        }
    }

    /// Marches around the section from the faces around `seeds`: visits the
    /// faces that meet the section, crossing from one to the next through
    /// crossing edges, edges in `s` and vertices on `s`.
    fn march(&self, seeds: &[u32], s: &Plane, scratch: &mut Scratch) -> Vec<u32> {
        let mut queue: Vec<u32> = Vec::with_capacity(64);
        let mut relevant = Vec::with_capacity(64);
        let around = |v: u32, queue: &mut Vec<u32>, scratch: &mut Scratch| {
            if scratch.vertices.insert(v, true) {
                for h in self.outgoing(v) {
                    let f = self.half_edges[h as usize].face;
                    if scratch.faces.insert(f, true) {
                        queue.push(f);
                    }
                }
            }
        };
        for &v in seeds {
            around(v, &mut queue, scratch);
        }
        while let Some(f) = queue.pop() {
            for h in self.face_loop(f) {
                self.side(self.half_edges[h as usize].origin, s, scratch);
            }
            if !self.meets_section(f, scratch) {
                continue;
            }
            relevant.push(f);
            for h in self.face_loop(f) {
                let e = self.half_edges[h as usize];
                let (a, b) = (
                    Self::known_side(e.origin, scratch),
                    Self::known_side(self.dest(h), scratch),
                );
                if a.as_i32() * b.as_i32() < 0 || (a == Sign::Zero && b == Sign::Zero) {
                    let g = self.half_edges[e.twin as usize].face;
                    if scratch.faces.insert(g, true) {
                        queue.push(g);
                    }
                }
                if a == Sign::Zero {
                    around(e.origin, &mut queue, scratch);
                }
            }
        }
        relevant
    }

    /// True when face `f` (all vertices classified) contains a section edge
    /// once crossing edges are split: it has vertices on both sides, or an
    /// edge lying in `s`.
    fn meets_section(&self, f: u32, scratch: &Scratch) -> bool {
        let (mut plus, mut minus, mut in_plane) = (false, false, false);
        for h in self.face_loop(f) {
            let a = Self::known_side(self.half_edges[h as usize].origin, scratch);
            plus |= a == Sign::Positive;
            minus |= a == Sign::Negative;
            in_plane |= a == Sign::Zero && Self::known_side(self.dest(h), scratch) == Sign::Zero;
        }
        (plus && minus) || in_plane
    }

    /// Splits along the section, given the faces that meet it, their
    /// vertices classified (steps 1–3 of the module docs).
    fn split_along(
        &mut self,
        mut relevant: Vec<u32>,
        scratch: &mut Scratch,
        s: &Plane,
        below_tag: u32,
        above_tag: u32,
    ) -> CutOutcome {
        relevant.sort_unstable();
        // 1. Split crossing edges (each once: from its + end).
        let mut crossing = Vec::with_capacity(relevant.len());
        for &f in &relevant {
            for h in self.face_loop(f) {
                let e = self.half_edges[h as usize];
                if Self::known_side(e.origin, scratch) == Sign::Positive
                    && Self::known_side(self.dest(h), scratch) == Sign::Negative
                {
                    crossing.push(h);
                }
            }
        }
        for h in crossing {
            let m = self.split_edge(h, s);
            scratch.sides.insert(m, Sign::Zero);
        }
        // 2. Split straddling faces.
        let mut faces = Vec::with_capacity(2 * relevant.len());
        faces.extend_from_slice(&relevant);
        for &f in &relevant {
            let has = |sign| {
                self.face_loop(f)
                    .any(|h| Self::known_side(self.half_edges[h as usize].origin, scratch) == sign)
            };
            if has(Sign::Positive) && has(Sign::Negative) {
                faces.push(self.split_face(f, scratch));
            }
        }
        // 3. Caps from the half-edges lying in s.
        self.add_caps(&faces, scratch, s, below_tag, above_tag)
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
    fn split_face(&mut self, f: u32, scratch: &mut Scratch) -> u32 {
        let mut loop_ = std::mem::take(&mut scratch.face_loop);
        loop_.clear();
        loop_.extend(self.face_loop(f));
        let n = loop_.len();
        let origin = |k: usize| self.half_edges[loop_[k % n] as usize].origin;
        let side = |k: usize| Self::known_side(origin(k), scratch);
        let mut zeros = (0..n).filter(|&k| side(k) == Sign::Zero);
        let (i, j) = (
            zeros
                .next()
                .expect("a straddling face has a vertex on the plane"),
            zeros
                .next()
                .expect("a straddling face has two vertices on the plane"),
        );
        // Chain i..j (half-edges loop_[i], …, loop_[j−1]) and chain j..i.
        let chain_ij_positive = side(i + 1) == Sign::Positive;
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
        scratch.face_loop = loop_;
        new_face
    }

    /// Builds the two caps along the section and separates the parts;
    /// `faces` lists every face that meets the section.
    fn add_caps(
        &mut self,
        faces: &[u32],
        scratch: &mut Scratch,
        s: &Plane,
        below_tag: u32,
        above_tag: u32,
    ) -> CutOutcome {
        // The half-edges lying in s, with the side of their face (the side
        // of any vertex of the face off s).
        let mut section: Vec<(u32, Sign)> = Vec::with_capacity(2 * faces.len());
        for &f in faces {
            let side = self
                .face_loop(f)
                .map(|h| Self::known_side(self.half_edges[h as usize].origin, scratch))
                .find(|&x| x != Sign::Zero)
                .unwrap_or(Sign::Zero);
            for h in self.face_loop(f) {
                let e = self.half_edges[h as usize];
                if Self::known_side(e.origin, scratch) == Sign::Zero
                    && Self::known_side(self.dest(h), scratch) == Sign::Zero
                {
                    section.push((h, side));
                }
            }
        }
        // One cap per side: for each section half-edge u→v on a face of that
        // side, the cap gets v→u, and cap edges chain by shared vertices.
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
            let mut cap_edges = Vec::with_capacity(section.len());
            for &(h, hside) in &section {
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
        CutOutcome::Split {
            below: PolyId(first_cap_edge[0]),
            above: PolyId(first_cap_edge[1]),
        }
    }
}
