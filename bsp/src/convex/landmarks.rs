//! Where the edge descent of the next cut starts (paper 1 §3.3).
//!
//! Notation: `P` — the polyhedron a cut splits, named by its id; `s` — the
//! cutting plane; a *landmark* is a vertex of `P` known from earlier cuts.
//!
//! The descent walks from a start vertex to the section, one neighbour at
//! a time; from an arbitrary vertex of a large polyhedron that takes many
//! steps. A cut leaves, for each part it builds, a few landmarks of that
//! part: the landmarks of `P` that the `f64` filter places strictly on that
//! part's side of `s`, and one vertex of the part's new cap. The next cut
//! of that part (by the id the cut returned) starts from the landmark
//! nearest to its plane by the `f64` estimate of the offset (the vertex
//! of the part's id, on its cap, is among them when there was room). Any
//! start vertex gives the same section, so the result does not depend on
//! the landmarks; only the length of the walk does. A cut of a polyhedron
//! without landmarks leaves some only when its descent was long (small
//! polyhedra do without). Only the parts of the last cut have landmarks:
//! any other change to the arena (another cut, clearing or truncating it,
//! adding polyhedra) forgets them.

use super::mesh::{ConvexArena, PolyId};
use super::scratch::Scratch;
use crate::exact::{FilteredDot, Plane, Sign};

impl ConvexArena {
    /// The vertex the cut of `poly` by `s` starts from: of the extremes of
    /// `poly` in the directions closest to `±n` (see `extremes`), or else
    /// of its landmarks, the one with the smallest estimated distance to
    /// `s`; without either, the vertex of `poly`'s id. Its side is recorded
    /// in `scratch` when the filter tells it.
    #[inline]
    pub(super) fn start_vertex(&self, poly: PolyId, s: &Plane, scratch: &mut Scratch) -> u32 {
        if self.take_extremes(poly, scratch) {
            scratch.landmarks.forget();
        } else if scratch.landmarks.take_for(poly.0) == 0 {
            return self.half_edges[poly.0 as usize].origin;
        }
        self.nearest_landmark(s, scratch)
    }

    /// The current landmark or extreme candidate with the smallest
    /// estimated distance to `s` (`|T̃|/W̃`, compared by
    /// cross-multiplication), with the side of every landmark that the
    /// filter tells; an extreme notes in `scratch.chain` the side whose
    /// chain the march walks first. The extreme in the direction opposite
    /// to `n` is a candidate only when the one closest to `n` is not
    /// below `s`.
    #[inline(never)]
    fn nearest_landmark(&self, s: &Plane, scratch: &mut Scratch) -> u32 {
        let extremes = self.extreme_candidates(s, scratch);
        let marks = &mut scratch.landmarks;
        let (mut nearest, mut nearest_w) = (f64::INFINITY, 1.0);
        let (mut start, mut start_side) = (marks.current[0], None);
        for k in 0..marks.current_count {
            let v = marks.current[k];
            let point = self.point(v);
            let dot = FilteredDot::new(point, s);
            // A landmark the filter cannot place is passed to no part.
            let side = dot.sign();
            marks.current_sides[k] = side;
            let (distance, w) = (dot.sum().abs(), point.approx[3]);
            if distance * nearest_w < nearest * w {
                (nearest, nearest_w, start, start_side) = (distance, w, v, side);
            }
        }
        scratch.chain = None;
        if let Some(candidates) = extremes {
            for (v, chain) in candidates.into_iter().zip([Sign::Positive, Sign::Negative]) {
                let point = self.point(v);
                let dot = FilteredDot::new(point, s);
                let (distance, w) = (dot.sum().abs(), point.approx[3]);
                let side = dot.sign();
                if distance * nearest_w < nearest * w {
                    (nearest, nearest_w, start, start_side) = (distance, w, v, side);
                    scratch.chain = Some(chain);
                }
                if side == Some(Sign::Negative) {
                    // The extreme in the direction closest to `n` is below
                    // `s`: the one in the opposite direction is, as a rule,
                    // lower still, so farther from `s`; only the length of
                    // the descent depends on it.
                    break;
                }
            }
        }
        if let Some(side) = start_side {
            scratch.sides.insert(start, side);
        }
        start
    }

    /// Keeps the landmarks of `poly`, which the cut left unchanged.
    #[inline]
    pub(super) fn keep_landmarks(&self, poly: PolyId, scratch: &mut Scratch) {
        if scratch.landmarks.worth_keeping(scratch.descent_steps) {
            let v0 = self.half_edges[poly.0 as usize].origin;
            scratch.landmarks.set_part(0, poly.0, |_| true, v0);
        }
    }

    /// Records the landmarks of part `k` of a proper cut, the part on side
    /// `side` whose id `part` is a half-edge of its cap: the current ones
    /// the filter placed strictly on that side (a landmark on the plane may
    /// have been copied for the other part), and the vertex of `part`.
    #[inline]
    pub(super) fn pass_landmarks(&self, k: usize, part: u32, side: Sign, scratch: &mut Scratch) {
        if scratch.landmarks.worth_keeping(scratch.descent_steps) {
            let cap_vertex = self.half_edges[part as usize].origin;
            scratch
                .landmarks
                .set_part(k, part, |v| v == Some(side), cap_vertex);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{assert_same_arena, cube, tangent_plane};
    use super::super::{ConvexArena, CutOutcome, KeptOutcome, NO_TAG, Part};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Chains of two-sided cuts of two polyhedra in one arena, in random
    /// order, each going on with the lower part of its last cut (once with
    /// the upper part): every cut,
    /// started from landmarks or extremes, leaves the arena element for
    /// element as the classify-all cut of a copy without them does; and
    /// they are in use for most cuts.
    #[test]
    fn cuts_from_landmarks_equal_the_naive_cut() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut arena = ConvexArena::new();
        let mut polys = [cube(&mut arena), cube(&mut arena)];
        let (mut cuts, mut from_landmarks) = (0, 0);
        for step in 0..400 {
            let i = usize::from(rng.random_bool(0.2));
            let s = tangent_plane(&mut rng);
            let mut reference = arena.clone();
            let expected = reference.cut_naive(polys[i], &s, NO_TAG, NO_TAG);
            let outcome = arena.cut(polys[i], &s, NO_TAG, NO_TAG);
            assert_eq!(outcome, expected);
            assert_same_arena(&arena, &reference);
            let scratch = arena.scratch.as_ref().expect("a cut lends the scratch");
            from_landmarks +=
                usize::from(scratch.landmarks.current_count > 0 || scratch.extremes.in_use());
            cuts += 1;
            if let CutOutcome::Split { below, above } = outcome {
                // The large part, once the cap.
                polys[i] = if step == 300 { above } else { below };
            }
        }
        assert!(from_landmarks * 2 > cuts, "{from_landmarks} of {cuts}");
    }

    /// A chain of one-sided cuts keeping the lower part (once the upper):
    /// every cut, started from landmarks or extremes, leaves the arena
    /// element for element as the same cut of a copy without them does;
    /// and they are in use for most cuts.
    #[test]
    fn one_sided_cuts_from_landmarks_equal_those_without() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let mut arena = ConvexArena::new();
        let mut poly = cube(&mut arena);
        let (mut cuts, mut from_landmarks) = (0, 0);
        for step in 0..400 {
            let s = tangent_plane(&mut rng);
            let part = if step == 300 {
                Part::Above
            } else {
                Part::Below
            };
            let mut reference = arena.clone();
            let expected = reference.cut_keeping(poly, &s, part, NO_TAG);
            let outcome = arena.cut_keeping(poly, &s, part, NO_TAG);
            assert_eq!(outcome, expected);
            assert_same_arena(&arena, &reference);
            let scratch = arena.scratch.as_ref().expect("a cut lends the scratch");
            from_landmarks +=
                usize::from(scratch.landmarks.current_count > 0 || scratch.extremes.in_use());
            cuts += 1;
            if let KeptOutcome::Cut(kept) = outcome {
                poly = kept;
            }
        }
        assert!(from_landmarks * 2 > cuts, "{from_landmarks} of {cuts}");
    }
}
