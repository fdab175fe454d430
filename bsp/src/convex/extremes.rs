//! Extreme vertices in fixed directions, as start vertices of the edge
//! descent (paper 1 §3.3).
//!
//! Notation: `P` — the polyhedron a cut splits, named by its id; `s` — the
//! cutting plane, `n` its normal; `u_i` — one of the six axis directions
//! `±x, ±y, ±z`; `e_i` — a vertex of `P` that is (by the `f64` estimates)
//! farthest in direction `u_i`.
//!
//! A plane near tangent to `P` cuts off a small cap around the vertices
//! farthest in the direction of its normal, so the descent started from
//! `e_i` for the `u_i` closest to `n` (or to `−n`) is short; and the march
//! then walks the chain of that cap's side first (`Scratch::chain`).
//! After a cut, `e_i` stays extreme in the part that keeps it (a part is a
//! subset of `P`); a part that loses it has its extreme in direction `u_i`
//! on its cap (or tied with another vertex of `P`), so only the cap is
//! scanned, when the part is cut next. The extremes are estimates: any
//! start vertex gives the same section, only the walk is longer. As the
//! landmarks, only the parts of the last cut have extremes, and a part
//! gets them only when the descent of its cut was long; a polyhedron with
//! extremes starts from them instead of landmarks.

use super::mesh::{ConvexArena, PolyId};
use super::scratch::Scratch;
use super::starts::{ALL, DIRECTIONS, EXTREME_DESCENT, HALF, closest_direction, projections};
use crate::exact::{Plane, Sign};

impl ConvexArena {
    /// Makes the extremes of `poly` current when it is a part of the last
    /// cut (finding those it lost on its cap, or all of them), and forgets
    /// the parts. Returns whether `poly` has extremes.
    pub(super) fn take_extremes(&self, poly: PolyId, scratch: &mut Scratch) -> bool {
        let marks = &mut scratch.extremes;
        marks.has_current = false;
        if marks.parts == [u32::MAX; 2] {
            return false;
        }
        let valid = if marks.parts[0] == poly.0 {
            marks.valid[0]
        } else if marks.parts[1] == poly.0 {
            marks.valid[1]
        } else {
            marks.forget();
            return false;
        };
        marks.forget();
        if valid != ALL {
            self.find_extremes(poly, valid, scratch);
        }
        scratch.extremes.has_current = true;
        true
    }

    /// Finds `e_i` for the directions not in `valid`: over the cap of
    /// `poly` (its face) when some are valid, else over all its vertices
    /// (face by face, breadth first, each vertex once).
    #[inline(never)]
    fn find_extremes(&self, poly: PolyId, valid: u16, scratch: &mut Scratch) {
        // A valid direction starts at +∞, which no vertex passes: the
        // visits need not test `valid`.
        let mut best: [f64; DIRECTIONS] = core::array::from_fn(|i| {
            if valid & (1 << i) == 0 {
                f64::NEG_INFINITY
            } else {
                f64::INFINITY
            }
        });
        let Scratch {
            extremes: marks,
            faces,
            vertices: seen,
            on_plane: order,
            ..
        } = scratch;
        let mut visit = |v: u32| {
            let approx = self.point(v).approx;
            let p = projections(approx);
            for i in 0..HALF {
                let j = i + HALF;
                if p[i] > best[i] {
                    best[i] = p[i];
                    marks.set(i, v, approx);
                }
                if -p[i] > best[j] {
                    best[j] = -p[i];
                    marks.set(j, v, approx);
                }
            }
        };
        let first = self.half_edges[poly.0 as usize].face;
        order.clear();
        order.push(first);
        faces.insert(first, true);
        let mut k = 0;
        while k < order.len() {
            let f = order[k];
            k += 1;
            let start = self.faces[f as usize].half_edge;
            let mut h = start;
            loop {
                let e = self.half_edges[h as usize];
                // Over all the faces, a vertex is met on each face around
                // it and visited the first time.
                if valid != 0 || seen.insert(e.origin, true) {
                    visit(e.origin);
                }
                let g = self.half_edges[e.twin as usize].face;
                if valid == 0 && faces.insert(g, true) {
                    order.push(g);
                }
                h = e.next;
                if h == start {
                    break;
                }
            }
        }
        // The march counts on finding no face or vertex marked.
        faces.clear();
        if valid == 0 {
            seen.clear();
        }
    }

    /// The extremes in the direction closest to `n` and to `−n`, when the
    /// polyhedron being cut has extremes.
    #[inline]
    pub(super) fn extreme_candidates(&self, s: &Plane, scratch: &Scratch) -> Option<[u32; 2]> {
        let marks = &scratch.extremes;
        if !marks.has_current {
            return None;
        }
        let i = closest_direction(s.approx);
        let opposite = if i < HALF { i + HALF } else { i - HALF };
        Some([marks.vertices[i], marks.vertices[opposite]])
    }

    /// Keeps the extremes of `poly`, which the cut left unchanged.
    #[inline]
    pub(super) fn keep_extremes(&self, poly: PolyId, scratch: &mut Scratch) {
        let marks = &mut scratch.extremes;
        if marks.has_current {
            marks.parts[0] = poly.0;
            marks.valid[0] = ALL;
        } else if scratch.descent_steps >= EXTREME_DESCENT {
            marks.parts[0] = poly.0;
            marks.valid[0] = 0;
        }
    }

    /// Records the extremes of the parts of a proper cut: `parts[0]` (a
    /// half-edge of its cap) keeps the extremes strictly below `s` and
    /// `parts[1]` those strictly above, or with `keep`, the one part built
    /// (`parts[0]`) those strictly on side `keep`.
    #[inline]
    pub(super) fn pass_extremes(
        &self,
        s: &Plane,
        parts: [u32; 2],
        keep: Option<Sign>,
        scratch: &mut Scratch,
    ) {
        let marks = &mut scratch.extremes;
        if !marks.worth_keeping(scratch.descent_steps) {
            return;
        }
        // A part that lost all its extremes is searched whole.
        marks.valid = match (marks.has_current, keep) {
            (false, _) => [0, 0],
            (true, None) => {
                let (below, above) = marks.sides(s);
                [below, above]
            }
            (true, Some(side)) => [marks.strictly_on(s, side), 0],
        };
        marks.parts = parts;
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{R, tangent_plane};
    use super::super::{ConvexArena, CutOutcome, NO_TAG};
    use super::{DIRECTIONS, HALF, projections};
    use crate::exact::IntPoint;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The offset of vertex `v` of `arena` along direction `i`.
    fn offset(arena: &ConvexArena, v: u32, i: usize) -> f64 {
        let p = projections(arena.point(v).approx);
        if i < HALF { p[i] } else { -p[i - HALF] }
    }

    /// Along chains of two-sided cuts going on with either part, the
    /// extremes the next cut of a part starts from are vertices of that
    /// part, each farthest in its direction (the offsets of distinct
    /// vertices of these polyhedra differ far beyond `f64` rounding); and
    /// the extremes are in use for most cuts.
    #[test]
    fn extremes_are_the_farthest_vertices_of_the_part() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut arena = ConvexArena::new();
        let corner = |c| IntPoint::new(c, c, c).expect("in budget");
        let mut poly = arena.add_box(corner(-R), corner(R)).expect("a box");
        let (mut cuts, mut in_use) = (0, 0);
        for step in 0..300 {
            let s = tangent_plane(&mut rng);
            if let CutOutcome::Split { below, above } = arena.cut(poly, &s, NO_TAG, NO_TAG) {
                poly = if step % 50 == 49 { above } else { below };
            }
            // A copy of the scratch, so that the chain goes on as it was.
            let mut scratch = arena.scratch.clone().expect("a cut lends the scratch");
            // As a cut does first.
            scratch.clear();
            if arena.take_extremes(poly, &mut scratch) {
                let vertices = arena.vertices_of(poly);
                for i in 0..DIRECTIONS {
                    let e = scratch.extremes.vertices[i];
                    assert!(vertices.contains(&e), "step {step}: e_{i} not in the part");
                    let farthest = vertices
                        .iter()
                        .map(|&v| offset(&arena, v, i))
                        .fold(f64::NEG_INFINITY, f64::max);
                    assert_eq!(offset(&arena, e, i), farthest, "step {step}, direction {i}");
                }
            }
            in_use += usize::from(arena.scratch.as_ref().is_some_and(|s| s.extremes.in_use()));
            cuts += 1;
        }
        assert!(in_use * 2 > cuts, "{in_use} of {cuts}");
    }
}
