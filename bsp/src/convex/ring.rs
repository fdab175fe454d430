//! One-sided cuts through a section with no vertex on the plane, in one
//! walk and one write pass (paper 1 §3.3, Figs. 3–4).
//!
//! Notation: `s` — the cutting plane; `K` — the side of the part kept. The
//! section is *generic* when no vertex lies on `s`. Then it is a ring of
//! `k` faces `f_0 … f_{k−1}`: it enters `f_i` across half-edge `x_i` and
//! leaves it across `y_i`, with `twin(y_i) = x_{i+1}` (indices mod `k`).
//! `A` — the side of the destination of every `x_i` (the march walks the
//! chain of `A` vertices of each face, from `x_i` to `y_i`), `B` — the
//! other side; `m_i` — the new vertex on the edge of `x_i`; `g_i` — the
//! new half-edge of `f_i` in `s`; `c_i` — its twin on the cap.
//!
//! The general split (`split`) lists the faces that meet the section, sorts
//! them, splits every crossing edge into two half-edge pairs, trims the
//! faces and builds the cap from a map of section vertices. Around a ring
//! the kept part needs less: each crossing edge keeps one half of each of
//! its two half-edges, so the half-edge running from `B` to `A` (from the
//! discarded side to the kept one, when `A = K`) or from `A` to `B` (when
//! `A ≠ K`) takes the new vertex as its origin instead of getting a
//! successor; each face gets `g_i`, and the cap edges follow the ring, so
//! `c_i` is followed by `c_{i+1}` (or `c_{i−1}`).
//!
//! Numbering: the new elements are written at indices fixed by the
//! section, not by where the walk started. Each face has a *rank*, its
//! place around the ring from the face of least index in one fixed
//! direction; `g_i` is written at the rank of `f_i`, `c_i` after all of
//! them at the same rank, and the vertex of each crossing edge at the rank
//! of the face holding its half-edge from `+` to `−`. So the result does
//! not depend on where the edge descent met the section, as for the
//! general split.

use super::mesh::{ConvexArena, Face, HalfEdge, Vertex};
use super::scratch::{RingFace, Scratch};
use super::stamp_map::StampMap;
use crate::exact::{Plane, Sign, intersect_3_planes_with};

impl ConvexArena {
    /// Walks the section from half-edge `h`, whose ends lie strictly on
    /// opposite sides of `s`, face to face across crossing edges, into
    /// `scratch.ring`. Returns the side `A` of `h`'s destination when the
    /// walk closes the ring, or `None` when it meets a vertex on `s` (the
    /// section is not generic; the general march takes over, and the sides
    /// classified so far stay valid).
    ///
    /// `BOTH`: for a two-sided split, which needs
    /// [`RingFace::stored_walked`] (false otherwise).
    #[inline(never)]
    pub(super) fn march_ring<const BOTH: bool>(
        &self,
        h: u32,
        s: &Plane,
        scratch: &mut Scratch,
    ) -> Option<Sign> {
        let Scratch { sides, ring, .. } = scratch;
        ring.clear();
        let side_a = self.side_in(self.dest(h), s, sides);
        debug_assert_ne!(side_a, Sign::Zero, "h crosses s");
        let mut x = h;
        loop {
            let face = self.half_edges[x as usize].face;
            let stored = if BOTH {
                self.faces[face as usize].half_edge
            } else {
                u32::MAX
            };
            let (y, stored_walked) = self.ring_exit::<BOTH>(x, stored, side_a, s, sides)?;
            ring.push(RingFace {
                face,
                entry: x,
                exit: y,
                rank: 0,
                stored_walked,
            });
            x = self.half_edges[y as usize].twin;
            if x == h {
                return Some(side_a);
            }
            // A ring visits each face once (convexity); a longer walk can
            // only come from a broken mesh, which the general march reports.
            if ring.len() >= self.faces.len() {
                return None;
            }
        }
    }

    /// Where the section leaves the face of `x` (entered across `x`):
    /// the half-edge after `x` whose destination is the first vertex off
    /// side `side_a`, and whether half-edge `stored` is among those walked
    /// up to it (when `BOTH`); `None` when that vertex lies on `s`.
    #[inline]
    fn ring_exit<const BOTH: bool>(
        &self,
        x: u32,
        stored: u32,
        side_a: Sign,
        s: &Plane,
        sides: &mut StampMap<Sign>,
    ) -> Option<(u32, bool)> {
        let mut h = self.half_edges[x as usize].next;
        let mut e = self.half_edges[h as usize];
        let mut walked = false;
        loop {
            walked |= BOTH && h == stored;
            // Each half-edge is read once: the next one is carried on.
            let next = self.half_edges[e.next as usize];
            let there = self.side_in(next.origin, s, sides);
            if there != side_a {
                return (there != Sign::Zero).then_some((h, walked));
            }
            (h, e) = (e.next, next);
        }
    }

    /// Cuts along the ring in `scratch.ring` (found by
    /// [`ConvexArena::march_ring`], walking side `side_a`), keeping the part
    /// on side `keep`, whose cap gets tag `tag`; returns the cap's first
    /// half-edge (the kept part's id).
    #[inline(never)]
    pub(super) fn split_ring(
        &mut self,
        scratch: &mut Scratch,
        s: &Plane,
        side_a: Sign,
        keep: Sign,
        tag: u32,
    ) -> u32 {
        let ring = &scratch.ring;
        let k = ring.len();
        let (first, step) = ring_order(ring, side_a);
        // Ring positions in rank order.
        let positions = std::iter::successors(Some(first), |&i| {
            Some(if i + step >= k {
                i + step - k
            } else {
                i + step
            })
        })
        .take(k);
        let (h0, v0, p0) = (
            self.half_edges.len() as u32,
            self.vertices.len() as u32,
            self.points.len() as u32,
        );
        let c0 = h0 + k as u32;
        let kept_walked = side_a == keep;
        // The half-edge of each face from `+` to `−`: its entry when `A`
        // is `−`, else its exit. It names the vertex of its edge: the
        // vertex on x_i is the rank of f_i when `A` is `−`, else that of
        // f_{i−1}, which is one rank more (the ranks then run against the
        // ring). So the face of rank `r` meets the section at vertices `r`
        // and `r + 1` (mod `k`, from `v0`), and its new edge runs from
        // `r + 1` to `r` in the part below, from `r` to `r + 1` above, as
        // the part's chain requires.
        let entry_owns = side_a == Sign::Negative;
        let succ = |r: u32| if r as usize + 1 == k { 0 } else { r + 1 };
        let pred = |r: u32| if r == 0 { k as u32 - 1 } else { r - 1 };
        let below = keep == Sign::Negative;
        // The ends of the new edge of rank r, origin first.
        let ends = |r: u32| if below { (succ(r), r) } else { (r, succ(r)) };
        // 1. The new points, in the order of their vertices.
        self.points.reserve(k);
        let (faces, planes, points) = (&self.faces, &self.planes, &mut self.points);
        let plane = |f: u32| &planes[faces[f as usize].plane as usize];
        for i in positions.clone() {
            let owner = ring[i];
            let own = if entry_owns { owner.entry } else { owner.exit };
            let twin_face = self.half_edges[self.half_edges[own as usize].twin as usize].face;
            intersect_3_planes_with(plane(owner.face), plane(twin_face), s, |p| points.push(p))
                .expect("a crossing edge meets the cutting plane in one point");
        }
        // 2. The faces' new edges g (the kept chain runs from the end of g
        // round to its start; the half-edge leaving the discarded side now
        // leaves the new vertex), then their twins c on the cap, each
        // followed by the next rank's below and the previous one's above;
        // then the vertex records, each with the cap half-edge leaving it.
        self.half_edges.reserve(2 * k);
        for (r, i) in (0u32..).zip(positions) {
            let RingFace {
                face, entry, exit, ..
            } = ring[i];
            let (from, to) = ends(r);
            let (leaving, entering) = if kept_walked {
                (entry, exit)
            } else {
                (exit, entry)
            };
            let g = h0 + r;
            self.half_edges[leaving as usize].origin = v0 + to;
            self.half_edges[entering as usize].next = g;
            self.half_edges.push(HalfEdge {
                origin: v0 + from,
                twin: c0 + r,
                next: leaving,
                face,
            });
            self.faces[face as usize].half_edge = g;
        }
        let cap = self.faces.len() as u32;
        for r in 0..k as u32 {
            let (_, to) = ends(r);
            self.half_edges.push(HalfEdge {
                origin: v0 + to,
                twin: h0 + r,
                next: c0 + if below { succ(r) } else { pred(r) },
                face: cap,
            });
        }
        self.vertices.extend((0..k as u32).map(|r| Vertex {
            point: p0 + r,
            half_edge: c0 + if below { r } else { pred(r) },
        }));
        let plane = self.push_plane(if keep == Sign::Negative {
            *s
        } else {
            s.flipped()
        });
        self.faces.push(Face {
            plane,
            half_edge: c0,
            tag,
        });
        c0
    }
}

/// The ranks of the ring's faces: their places around the ring counted
/// from the face of least index, in the direction the walk takes when `A`
/// is `−` (a walk with `A = +` goes the other way round: from the other
/// face of the same crossing edge, it walks the other chain). Both are
/// fixed by the section alone, wherever the walk started. Returns the
/// position of the face of rank 0 and the step from one rank to the next
/// (`1`, or `k − 1` against the walk).
fn ring_order(ring: &[RingFace], side_a: Sign) -> (usize, usize) {
    let k = ring.len();
    let first = ring
        .iter()
        .enumerate()
        .min_by_key(|(_, r)| r.face)
        .map_or(0, |(i, _)| i);
    let step = if side_a == Sign::Negative { 1 } else { k - 1 };
    (first, step)
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{assert_same_arena, cube, random_plane};
    use super::super::{ConvexArena, KeptOutcome, Part, PolyId};
    use crate::exact::Plane;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Element-for-element equality of two polyhedra once extracted.
    fn assert_same_polyhedron(a: &ConvexArena, pa: PolyId, b: &ConvexArena, pb: PolyId) {
        let ((a, ia), (b, ib)) = (a.extract(pa), b.extract(pb));
        assert_eq!(ia, ib);
        assert_same_arena(&a, &b);
    }

    /// Chains of one-sided cuts by random planes (normals of 2^10, where
    /// sections are generic, and of 2^2 with offsets on a coarse grid,
    /// where vertices often lie on the plane), keeping the part below, now
    /// and then the part above (then the chain starts again from a new
    /// box in the same arena): the ring cut gives the general march and
    /// split's polyhedron, element for element once extracted, and a valid
    /// one; and most cuts of the first kind take the ring.
    #[test]
    fn ring_cuts_equal_the_general_split() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut cuts, mut by_ring) = (0, 0);
        for scale in [1024.0, 4.0] {
            let mut arena = ConvexArena::new();
            let mut poly = cube(&mut arena);
            for _ in 0..300 {
                let mut s = random_plane(&mut rng, scale, 0.5..0.99);
                if scale < 8.0 {
                    s = Plane::new(s.a, s.b, s.c, s.d >> 16 << 16).expect("in budget");
                }
                let keep = if rng.random_bool(0.05) {
                    Part::Above
                } else {
                    Part::Below
                };
                let mut general = arena.clone();
                let expected = general.cut_keeping_by(poly, &s, keep, 7, false);
                let before = (arena.half_edges.len(), arena.vertices.len());
                let outcome = arena.cut_keeping(poly, &s, keep, 7);
                match (outcome, expected) {
                    (KeptOutcome::Cut(kept), KeptOutcome::Cut(reference)) => {
                        arena
                            .validate(kept)
                            .unwrap_or_else(|e| panic!("scale {scale}: {e}"));
                        assert_same_polyhedron(&arena, kept, &general, reference);
                        // The ring adds two half-edges per new vertex, the
                        // general split four.
                        let added = (
                            arena.half_edges.len() - before.0,
                            arena.vertices.len() - before.1,
                        );
                        if scale > 8.0 {
                            cuts += 1;
                            by_ring += usize::from(added.0 == 2 * added.1);
                        }
                        poly = kept;
                        if keep == Part::Above {
                            poly = cube(&mut arena);
                        }
                    }
                    (outcome, expected) => assert_eq!(outcome, expected),
                }
            }
        }
        assert!(by_ring * 10 > cuts * 9, "{by_ring} ring cuts of {cuts}");
    }
}
