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
//! Both hand the faces that meet the section to `split`, which
//! does steps 1–3. [`ConvexArena::cut_keeping`] is the edge-descent cut for
//! callers that keep one part: step 3 builds only that part's cap and copies
//! no vertices, and the faces of the other part are not split. When the
//! descent meets the section at a crossing edge and no vertex lies on `s`
//! (the common case), the edge-descent cuts walk the section's ring of
//! faces instead (`ring`, `ring_both`) and split from it with less
//! bookkeeping: the same arrays for [`ConvexArena::cut`], the same
//! polyhedron once extracted for [`ConvexArena::cut_keeping`].

use super::mesh::{ConvexArena, PolyId};
use super::scratch::Scratch;
use super::stamp_map::StampMap;
use super::survey::{FaceSurvey, SectionExit};
use crate::exact::{FilteredDot, Plane, Sign, classify_vertex, compare_offsets, offset_estimate};

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

/// What the last cut of an arena took ([`ConvexArena::last_cut_stats`]),
/// the measures of paper 1's Figure 9.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CutStats {
    /// Vertices classified against the cutting plane (each once).
    pub classified: usize,
    /// Steps of the edge descent.
    pub descent_steps: u32,
}

/// The part of a cut polyhedron that [`ConvexArena::cut_keeping`] builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The part in the negative half-space of the cutting plane.
    Below,
    /// The part in the positive half-space of the cutting plane.
    Above,
}

/// The result of cutting a polyhedron `P` by a plane `s` and keeping one
/// part ([`ConvexArena::cut_keeping`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeptOutcome {
    /// `P` was cut in place into the kept part; the elements only the other
    /// part used stay in the arena, unused.
    Cut(PolyId),
    /// No proper intersection: `P` lies in the closed negative half-space
    /// and is unchanged.
    Below,
    /// No proper intersection: `P` lies in the closed positive half-space
    /// and is unchanged.
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
            match arena.classify_all(poly, s, scratch) {
                (true, true) => {}
                (false, _) => return CutOutcome::Above,
                (true, false) => return CutOutcome::Below,
            }
            let [below, above] = arena.split_along(scratch, s, [below_tag, above_tag], None);
            CutOutcome::Split {
                below: PolyId(below),
                above: PolyId(above),
            }
        })
    }

    /// Classifies every vertex of `poly` against `s` (forgetting the
    /// landmarks and extremes of the previous cut) and returns whether any
    /// lies below and whether any lies above it. When both do, the faces
    /// that meet the section are listed in `scratch.relevant` with their
    /// surveys, ready for the split.
    pub(super) fn classify_all(
        &self,
        poly: PolyId,
        s: &Plane,
        scratch: &mut Scratch,
    ) -> (bool, bool) {
        scratch.landmarks.forget();
        scratch.extremes.forget();
        let faces = self.faces_of(poly);
        let (mut plus, mut minus) = (false, false);
        for &f in &faces {
            for h in self.face_loop(f) {
                let side = self.side(self.half_edges[h as usize].origin, s, scratch);
                plus |= side == Sign::Positive;
                minus |= side == Sign::Negative;
            }
        }
        if minus && plus {
            let mut relevant = std::mem::take(&mut scratch.relevant);
            relevant.clear();
            relevant.extend(
                faces
                    .into_iter()
                    .filter_map(|f| Some((f, self.survey_face(f, scratch)?))),
            );
            scratch.relevant = relevant;
        }
        (minus, plus)
    }

    /// Cuts `poly` by `s` by edge descent and marching (paper 1 §3.3):
    /// walks from vertex to neighbouring vertex towards the far side of `s`
    /// until it finds the section or proves there is none (a vertex with no
    /// neighbour closer to the far side is a global extremum on a convex
    /// polyhedron), then marches around the section, classifying only the
    /// vertices of faces it visits. The result is identical, element for
    /// element, to [`ConvexArena::cut_naive`].
    pub fn cut(&mut self, poly: PolyId, s: &Plane, below_tag: u32, above_tag: u32) -> CutOutcome {
        self.cut_by(poly, s, [below_tag, above_tag], true)
    }

    /// [`ConvexArena::cut`] with cap tags `tags`, splitting a section with
    /// no vertex on `s` from its ring when `by_ring` (always but in the
    /// tests that compare it with the general march and split).
    #[inline(always)]
    pub(super) fn cut_by(
        &mut self,
        poly: PolyId,
        s: &Plane,
        tags: [u32; 2],
        by_ring: bool,
    ) -> CutOutcome {
        self.with_scratch(|arena, scratch| {
            let start = arena.start_vertex(poly, s, scratch);
            let seed = match arena.locate_section(start, s, scratch) {
                Ok(seed) => seed,
                Err(outcome) => {
                    arena.keep_landmarks(poly, scratch);
                    arena.keep_extremes(poly, scratch);
                    return outcome;
                }
            };
            // Most sections have no vertex on s: their ring gives the
            // general split's arrays with less work.
            let ring = match seed {
                Seed::Edge(h) if by_ring => arena.march_ring::<true>(h, s, scratch),
                _ => None,
            };
            let parts = match ring {
                Some(side_a) => arena.split_ring_both(scratch, s, side_a, tags),
                None => {
                    arena.march(seed, s, scratch);
                    arena.split_along(scratch, s, tags, None)
                }
            };
            arena.pass_extremes(s, parts, None, scratch);
            for (k, side) in [Sign::Negative, Sign::Positive].into_iter().enumerate() {
                arena.pass_landmarks(k, parts[k], side, scratch);
            }
            CutOutcome::Split {
                below: PolyId(parts[0]),
                above: PolyId(parts[1]),
            }
        })
    }

    /// Cuts `poly` by `s` like [`ConvexArena::cut`] but builds only the
    /// part `keep`, whose cap face gets tag `cap_tag`: the same polyhedron,
    /// element for element once extracted ([`ConvexArena::extract`]), as
    /// that part of [`ConvexArena::cut`], for less work.
    pub fn cut_keeping(
        &mut self,
        poly: PolyId,
        s: &Plane,
        keep: Part,
        cap_tag: u32,
    ) -> KeptOutcome {
        self.cut_keeping_by(poly, s, keep, cap_tag, true)
    }

    /// [`ConvexArena::cut_keeping`], cutting a section with no vertex on
    /// `s` around its ring when `by_ring` (always but in the tests that
    /// compare it with the general march and split).
    #[inline(always)]
    pub(super) fn cut_keeping_by(
        &mut self,
        poly: PolyId,
        s: &Plane,
        keep: Part,
        cap_tag: u32,
        by_ring: bool,
    ) -> KeptOutcome {
        self.with_scratch(|arena, scratch| {
            let start = arena.start_vertex(poly, s, scratch);
            let seed = match arena.locate_section(start, s, scratch) {
                Ok(seed) => seed,
                Err(outcome) => {
                    arena.keep_landmarks(poly, scratch);
                    arena.keep_extremes(poly, scratch);
                    return match outcome {
                        CutOutcome::Above => KeptOutcome::Above,
                        CutOutcome::Below | CutOutcome::Split { .. } => KeptOutcome::Below,
                    };
                }
            };
            let side = match keep {
                Part::Below => Sign::Negative,
                Part::Above => Sign::Positive,
            };
            // Most sections have no vertex on s: their ring is cut in one
            // pass; the others go through the general march and split.
            let ring = match seed {
                Seed::Edge(h) if by_ring => arena.march_ring::<false>(h, s, scratch),
                _ => None,
            };
            let kept = match ring {
                Some(side_a) => arena.split_ring(scratch, s, side_a, side, cap_tag),
                None => {
                    arena.march(seed, s, scratch);
                    let [below, above] = arena.split_along(scratch, s, [cap_tag; 2], Some(side));
                    match keep {
                        Part::Below => below,
                        Part::Above => above,
                    }
                }
            };
            arena.pass_landmarks(0, kept, side, scratch);
            arena.pass_extremes(s, [kept, u32::MAX], Some(side), scratch);
            KeptOutcome::Cut(PolyId(kept))
        })
    }

    /// Edge descent from vertex `v0`: where the march around the section
    /// starts when the cut is proper, else the outcome
    /// ([`CutOutcome::Below`] or [`CutOutcome::Above`]).
    fn locate_section(
        &self,
        v0: u32,
        s: &Plane,
        scratch: &mut Scratch,
    ) -> Result<Seed, CutOutcome> {
        // Walk towards the side v0 is not on; a step onto that side
        // brackets the section. From a vertex on s, both sides must exist
        // for a proper cut, and v0 itself is on the section.
        let seed = match self.side(v0, s, scratch) {
            Sign::Positive => match self.descend(v0, s, Sign::Negative, scratch) {
                Some(h) => self.seed_at(h, Sign::Negative, scratch),
                None => return Err(CutOutcome::Above),
            },
            Sign::Negative => match self.descend(v0, s, Sign::Positive, scratch) {
                Some(h) => self.seed_at(h, Sign::Positive, scratch),
                None => return Err(CutOutcome::Below),
            },
            Sign::Zero => {
                if self.descend(v0, s, Sign::Negative, scratch).is_none() {
                    return Err(CutOutcome::Above);
                }
                if self.descend(v0, s, Sign::Positive, scratch).is_none() {
                    return Err(CutOutcome::Below);
                }
                Seed::Vertex(v0)
            }
        };
        Ok(seed)
    }

    /// Where the march starts after the descent stepped along `h` onto the
    /// far side: around the origin of `h` when it lies on `s`, else at the
    /// two faces of `h`, whose edge crosses `s`: from `h` (its end on side
    /// `target`), or from its twin when the chain on the other side is the
    /// one to walk (`scratch.chain`).
    fn seed_at(&self, h: u32, target: Sign, scratch: &Scratch) -> Seed {
        let from = self.half_edges[h as usize].origin;
        if Self::known_side(from, scratch) == Sign::Zero {
            Seed::Vertex(from)
        } else if scratch.chain.is_some_and(|chain| chain != target) {
            Seed::Edge(self.half_edges[h as usize].twin)
        } else {
            Seed::Edge(h)
        }
    }

    /// What the last cut took (zero before any): counted from the cut's
    /// working memory after the fact, at a cost proportional to the
    /// arena's size, so that the cuts themselves count nothing.
    #[must_use]
    pub fn last_cut_stats(&self) -> CutStats {
        self.scratch
            .as_ref()
            .map_or_else(CutStats::default, |scratch| CutStats {
                classified: scratch.sides.count(),
                descent_steps: scratch.descent_steps,
            })
    }

    /// Runs `op` with the arena's scratch space, cleared.
    pub(super) fn with_scratch<T>(&mut self, op: impl FnOnce(&mut Self, &mut Scratch) -> T) -> T {
        let mut scratch = self.scratch.take().unwrap_or_default();
        scratch.clear();
        let out = op(self, &mut scratch);
        self.scratch = Some(scratch);
        out
    }

    /// The side of vertex `v`, classified once per operation.
    #[inline]
    pub(super) fn side(&self, v: u32, s: &Plane, scratch: &mut Scratch) -> Sign {
        self.side_in(v, s, &mut scratch.sides)
    }

    /// [`ConvexArena::side`] with the map of sides alone, for callers that
    /// hold other parts of the scratch space at the same time.
    #[inline]
    pub(super) fn side_in(&self, v: u32, s: &Plane, sides: &mut StampMap<Sign>) -> Sign {
        sides.get(v).unwrap_or_else(|| {
            let side = classify_vertex(self.point(v), s);
            sides.insert(v, side);
            side
        })
    }

    /// The side of an already classified vertex.
    #[inline]
    pub(super) fn known_side(v: u32, scratch: &Scratch) -> Sign {
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
    /// `target` of `s`: returns a half-edge whose destination is on side
    /// `target` and whose origin is not, or `None` when no vertex is on
    /// that side.
    ///
    /// Each step moves to the first neighbour (turning around the vertex)
    /// certified to lie strictly closer to the target side — by the `f64`
    /// estimates and their error bounds, or else by exact comparison — so
    /// the walk never cycles, and it stops only at a vertex no neighbour
    /// improves on: a global extremum of the (linear) offset over the
    /// convex polyhedron. Taking the first such neighbour rather than the
    /// closest looks at fewer neighbours for about as many steps.
    fn descend(&self, start: u32, s: &Plane, target: Sign, scratch: &mut Scratch) -> Option<u32> {
        use core::cmp::Ordering;
        // Gains towards the target side: `flip·(a − b)` is exactly
        // `toward(a) − toward(b)` (negation is exact).
        let flip = if target == Sign::Negative { -1.0 } else { 1.0 };
        let wanted = if target == Sign::Negative {
            Ordering::Less
        } else {
            Ordering::Greater
        };
        let mut cur = start;
        let (mut cur_value, mut cur_error) = offset_estimate(self.point(cur), s);
        // The side of `cur`, to record when the walk stops there (the
        // caller has recorded that of `start`).
        let mut cur_side: Option<Sign> = None;
        // The outgoing half-edges of `cur` to look at: from `first`, turning
        // around `cur`, up to `stop` (excluded; all of them when equal).
        let first_out = self.vertices[cur as usize].half_edge;
        let (mut first, mut stop) = (first_out, first_out);
        loop {
            let mut h = first;
            // The step: the half-edge to the neighbour certified closer,
            // with that neighbour's offset estimate and side.
            let (n, value, error, side) = loop {
                let twin = self.half_edges[self.half_edges[h as usize].twin as usize];
                let n = twin.origin;
                let point = self.point(n);
                // One f64 evaluation gives both the side and the offset;
                // the side is recorded only for the vertices the walk
                // stops at (the march classifies the others it needs).
                let dot = FilteredDot::new(point, s);
                let side = match dot.sign() {
                    Some(side) => side,
                    None => self.side(n, s, scratch),
                };
                if side == target {
                    // The march needs the sides of both ends of `h`.
                    scratch.sides.insert(n, side);
                    if let Some(cur_side) = cur_side {
                        scratch.sides.insert(cur, cur_side);
                    }
                    return Some(h);
                }
                let (value, error) = dot.offset(point);
                let gain = flip * (value - cur_value);
                let bound = error + cur_error;
                if gain > bound
                    || (gain >= -bound && compare_offsets(point, self.point(cur), s) == wanted)
                {
                    // Certified closer: by the estimates, or when too
                    // close to call in f64, exactly.
                    break (n, value, error, side);
                }
                h = twin.next;
                if h == stop {
                    // No neighbour is closer: `cur` is an extremum.
                    scratch.descent_steps += 1;
                    return None;
                }
            };
            scratch.descent_steps += 1;
            (cur, cur_value, cur_error, cur_side) = (n, value, error, Some(side));
            let e = self.half_edges[h as usize];
            // Around the new vertex from the half-edge after the one back
            // to the vertex the walk came from, which is not on side
            // `target` (no vertex the walk visits is) and is certified
            // farther from it: it can end the walk no more than it can be
            // its next step.
            (first, stop) = (e.next, e.twin);
        }
    }

    /// Marches around the section from the faces at `seed`: visits the
    /// faces that meet the section, crossing from one to the next through
    /// crossing edges, edges in `s` and vertices on `s`, and leaves them in
    /// `scratch.relevant`. A face entered through a crossing edge is walked
    /// only as far as the section's other end on it
    /// (`survey_from_crossing`); the others all around.
    fn march(&self, seed: Seed, s: &Plane, scratch: &mut Scratch) {
        // The parts of the scratch space are borrowed apart, in place.
        let Scratch {
            sides,
            faces,
            vertices,
            queue,
            relevant,
            on_plane,
            ..
        } = scratch;
        queue.clear();
        relevant.clear();
        // Queue entries: a face and the crossing half-edge it is entered
        // by, or `u32::MAX` to walk it all around.
        let around = |v: u32,
                      queue: &mut Vec<(u32, u32)>,
                      vertices: &mut StampMap<bool>,
                      faces: &mut StampMap<bool>| {
            if vertices.insert(v, true) {
                for h in self.outgoing(v) {
                    let f = self.half_edges[h as usize].face;
                    if faces.insert(f, true) {
                        queue.push((f, u32::MAX));
                    }
                }
            }
        };
        // From a seed edge h, the march starts on the face of h and goes
        // around from there, so that every face is entered the same way as
        // that one: its walk runs along the chain on the side the descent
        // ended on, which is usually the smaller part (the descent starts
        // from a vertex of the larger part more often than not). The face
        // of h's twin is walked last, and only if the march has not reached
        // it by then through the other end of the section on it.
        let mut deferred = None;
        match seed {
            Seed::Vertex(v) => around(v, queue, vertices, faces),
            Seed::Edge(h) => {
                faces.insert(self.half_edges[h as usize].face, true);
                queue.push((self.half_edges[h as usize].face, h));
                deferred = Some(self.half_edges[h as usize].twin);
            }
        }
        loop {
            let (f, entry) = match queue.pop() {
                Some(next) => next,
                None => match deferred.take() {
                    Some(t) => {
                        let g = self.half_edges[t as usize].face;
                        if !faces.insert(g, true) {
                            continue;
                        }
                        (g, t)
                    }
                    None => break,
                },
            };
            if entry != u32::MAX {
                // Along the section from face to face across crossing
                // edges, straight on (what the queue would give next).
                let (mut f, mut entry) = (f, entry);
                loop {
                    let (info, exit) = self.survey_from_crossing(f, entry, s, sides);
                    relevant.push((f, info));
                    match exit {
                        SectionExit::Crossing(y) => {
                            let t = self.half_edges[y as usize].twin;
                            let g = self.half_edges[t as usize].face;
                            if faces.insert(g, true) {
                                (f, entry) = (g, t);
                                continue;
                            }
                        }
                        SectionExit::Vertex(z) => around(z, queue, vertices, faces),
                    }
                    break;
                }
                continue;
            }
            // Classify the face's vertices, noting whether it meets the
            // section (vertices on both sides, or an edge in s); the march
            // goes on across its crossing edges and edges in s, and around
            // its vertices on s.
            on_plane.clear();
            let first = self.faces[f as usize].half_edge;
            let mut e = self.half_edges[first as usize];
            let first_side = self.side_in(e.origin, s, sides);
            let mut survey = FaceSurvey::new();
            let (mut h, mut before, mut here) = (first, u32::MAX, first_side);
            loop {
                // Each half-edge is read once: the next one is carried on.
                let next = self.half_edges[e.next as usize];
                let there = if e.next == first {
                    first_side
                } else {
                    self.side_in(next.origin, s, sides)
                };
                // Runs along one side (most half-edges) need nothing more.
                if here != there || here == Sign::Zero {
                    survey.step(h, before, here, there);
                    let crossing = here.as_i32() * there.as_i32() < 0;
                    if crossing || (here == Sign::Zero && there == Sign::Zero) {
                        // A crossing edge or an edge in s: f meets the
                        // section, so the march goes on across it.
                        let g = self.half_edges[e.twin as usize].face;
                        if faces.insert(g, true) {
                            queue.push((g, if crossing { e.twin } else { u32::MAX }));
                        }
                    }
                    if here == Sign::Zero {
                        on_plane.push(e.origin);
                    }
                }
                if e.next == first {
                    break;
                }
                (before, h, e, here) = (h, e.next, next, there);
            }
            let Some(info) = survey.finish(h) else {
                continue;
            };
            relevant.push((f, info));
            // Around its vertices on s, now that f is known to meet the
            // section (a face touching s at one vertex only does not).
            for &v in on_plane.iter() {
                around(v, queue, vertices, faces);
            }
        }
    }
}

/// Where the march around the section starts.
#[derive(Clone, Copy, Debug)]
enum Seed {
    /// Every face around a vertex on the cutting plane.
    Vertex(u32),
    /// The two faces of a half-edge whose edge crosses the cutting plane.
    Edge(u32),
}
