//! Two-sided cuts through a section with no vertex on the plane, built
//! from its ring (paper 1 §3.3, Fig. 4).
//!
//! Notation as in [`super::ring`]: the ring's faces `f_i`, entered across
//! `x_i` and left across `y_i`, the walked side `A`; `r_i` — the rank of
//! `f_i` by face index among the ring's faces; `k` — their number. A
//! crossing edge is *owned* by the face holding its half-edge from `+` to
//! `−` (every ring face owns one: `x_i` when `A` is `−`, else `y_i`).
//!
//! The result is the general split's (`split`), array for array: the same
//! elements at the same indices, which the general split numbers by face
//! index — for the crossing edge owned by the face of rank `r`, vertex
//! `v0 + r` and the half-edges `h0 + 2r` (after the owned half-edge) and
//! `h0 + 2r + 1` (after its twin); for the face of rank `r`, the new face
//! `f0 + r` and the section half-edges `h0 + 2k + 2r` and `h0 + 2k + 2r + 1`;
//! then the lower cap (face `f0 + k`, half-edges from `h0 + 4k`), the upper
//! cap (face `f0 + k + 1`, half-edges from `h0 + 5k`) and the copies of
//! the section vertices for the upper part (from `v0 + k`). What the ring
//! saves is the general march's bookkeeping, the survey of each face and
//! the sort of the faces' records: the ring already holds, for each face,
//! the two half-edges where the section crosses it and which comes first.

use super::mesh::{ConvexArena, Face, HalfEdge, Vertex};
use super::scratch::RingFace;
use super::scratch::Scratch;
use crate::exact::{Plane, Sign};

/// The most ring faces ranked by counting (more go to the general sort).
const FEW_FACES: usize = 8;

impl ConvexArena {
    /// Splits along the ring in `scratch.ring` (found by
    /// `ConvexArena::march_ring`, walking side `side_a`) into the part
    /// below and the part above, whose caps get `tags`; returns the first
    /// half-edge of each part's cap, as the general split does.
    #[inline(never)]
    #[allow(clippy::needless_range_loop)] // `i` also names the neighbours
    pub(super) fn split_ring_both(
        &mut self,
        scratch: &mut Scratch,
        s: &Plane,
        side_a: Sign,
        tags: [u32; 2],
    ) -> [u32; 2] {
        let Scratch {
            ring, queue, order, ..
        } = scratch;
        rank_by_face(ring, queue, order);
        let k = ring.len();
        let k32 = k as u32;
        let (h0, f0, v0) = (
            self.half_edges.len() as u32,
            self.faces.len() as u32,
            self.vertices.len() as u32,
        );
        let p0 = self.points.len() as u32;
        let entry_owns = side_a == Sign::Negative;
        let prev = |i: usize| if i == 0 { k - 1 } else { i - 1 };
        let next = |i: usize| if i + 1 == k { 0 } else { i + 1 };
        // The rank of the owner of the crossing edge of x_i.
        let entry_rank = |i: usize| {
            if entry_owns {
                ring[i].rank
            } else {
                ring[prev(i)].rank
            }
        };
        self.grow(6 * k, k + 2, 2 * k);
        // 1. Split the crossing edges, the points in the order of their
        // vertices.
        self.points.reserve(k);
        for (r, &i) in (0u32..).zip(order.iter()) {
            let owner = ring[i as usize];
            let h = if entry_owns { owner.entry } else { owner.exit };
            self.split_crossing(h, s, h0 + 2 * r, v0 + r, p0 + r);
        }
        // 2. Split the faces: f keeps its `−` half, f0 + r gets the `+` half.
        let (below, above) = (h0 + 4 * k32, h0 + 5 * k32);
        for i in 0..k {
            let RingFace {
                face,
                entry,
                exit,
                rank,
                stored_walked,
            } = ring[i];
            let (er, xr) = (entry_rank(i), entry_rank(next(i)));
            // The second halves of x_i and y_i, and the vertices on them.
            let entry_rest = h0 + 2 * er + u32::from(!entry_owns);
            let exit_rest = h0 + 2 * xr + u32::from(entry_owns);
            let (m_in, m_out) = (v0 + er, v0 + xr);
            // In loop order from the face's stored half-edge.
            let (enter, leave, z, first_chain) = if stored_walked {
                (
                    [exit, entry],
                    [exit_rest, entry_rest],
                    [m_out, m_in],
                    -side_a,
                )
            } else {
                (
                    [entry, exit],
                    [entry_rest, exit_rest],
                    [m_in, m_out],
                    side_a,
                )
            };
            let new_face = f0 + rank;
            let (a, b) = (h0 + 2 * k32 + 2 * rank, h0 + 2 * k32 + 2 * rank + 1);
            let chain_0_positive = first_chain == Sign::Positive;
            let (face_0, face_1, start, end) = if chain_0_positive {
                (new_face, face, leave[0], enter[1])
            } else {
                (face, new_face, leave[1], enter[0])
            };
            // The `+` chain moves to the new face.
            let mut h = start;
            loop {
                let e = &mut self.half_edges[h as usize];
                e.face = new_face;
                if h == end {
                    break;
                }
                h = e.next;
            }
            // a: z2 → z1 closes chain 0, b: z1 → z2 closes chain 1; their
            // twins are the cap half-edges of the same rank.
            let (kept, new) = if chain_0_positive { (b, a) } else { (a, b) };
            let cap_twin = |edge: u32| (if edge == kept { below } else { above }) + rank;
            self.half_edges[a as usize] = HalfEdge {
                origin: z[1],
                twin: cap_twin(a),
                next: leave[0],
                face: face_0,
            };
            self.half_edges[b as usize] = HalfEdge {
                origin: z[0],
                twin: cap_twin(b),
                next: leave[1],
                face: face_1,
            };
            self.half_edges[enter[1] as usize].next = a;
            self.half_edges[enter[0] as usize].next = b;
            let old = self.faces[face as usize];
            self.faces[new_face as usize] = Face {
                half_edge: new,
                ..old
            };
            self.faces[face as usize].half_edge = kept;
            // 3. The cap half-edges twinned with them (`next` below), and
            // the section vertices' half-edges on the lower cap.
            // The ends of each, origin first; its cap twin runs back.
            let ends = |edge: u32| if edge == a { [z[1], z[0]] } else { z };
            let (z_kept, z_new) = (ends(kept), ends(new));
            self.half_edges[(below + rank) as usize] = HalfEdge {
                origin: z_kept[1],
                twin: kept,
                next: z_kept[0],
                face: f0 + k32,
            };
            self.half_edges[(above + rank) as usize] = HalfEdge {
                origin: z_new[1],
                twin: new,
                next: z_new[0],
                face: f0 + k32 + 1,
            };
            self.vertices[z_kept[1] as usize] = Vertex {
                point: p0 + (z_kept[1] - v0),
                half_edge: below + rank,
            };
        }
        // Each cap half-edge's `next` holds the vertex it ends at: the cap
        // half-edge leaving that vertex, by the vertex's place among the
        // new ones.
        let starts = order;
        for cap in [below, above] {
            for c in cap..cap + k32 {
                starts[(self.half_edges[c as usize].origin - v0) as usize] = c;
            }
            for c in cap..cap + k32 {
                let e = &mut self.half_edges[c as usize];
                e.next = starts[(e.next - v0) as usize];
            }
        }
        // The upper part's copies of the section vertices, in the order of
        // its cap, sharing their points.
        for (c, copy) in (above..above + k32).zip(v0 + k32..) {
            let v = self.half_edges[c as usize].origin;
            self.vertices[copy as usize] = Vertex {
                point: self.vertices[v as usize].point,
                half_edge: c,
            };
            let mut h = c;
            loop {
                self.half_edges[h as usize].origin = copy;
                h = self.half_edges[self.half_edges[h as usize].twin as usize].next;
                if h == c {
                    break;
                }
            }
        }
        for (cap, plane, tag) in [(below, *s, tags[0]), (above, s.flipped(), tags[1])] {
            let plane = self.push_plane(plane);
            let index = if cap == below { f0 + k32 } else { f0 + k32 + 1 };
            self.faces[index as usize] = Face {
                plane,
                half_edge: cap,
                tag,
            };
        }
        [below, above]
    }
}

/// Sets each ring face's rank by face index and lists the ring positions
/// in rank order in `order`. Up to [`FEW_FACES`] faces, each rank is
/// counted without branches (comparisons of face indices are
/// unpredictable, and a sort branches on each); more go to the general
/// sort, through `pairs`.
#[inline]
fn rank_by_face(ring: &mut [RingFace], pairs: &mut Vec<(u32, u32)>, order: &mut Vec<u32>) {
    let k = ring.len();
    order.clear();
    order.resize(k, 0);
    if k <= FEW_FACES {
        // Padding never ranks below a face: face indices are below MAX.
        let mut faces = [u32::MAX; FEW_FACES];
        for (slot, r) in faces.iter_mut().zip(ring.iter()) {
            *slot = r.face;
        }
        for i in 0..k {
            let face = faces[i];
            let rank: u32 = faces.iter().map(|&g| u32::from(g < face)).sum();
            ring[i].rank = rank;
            order[rank as usize] = i as u32;
        }
        return;
    }
    pairs.clear();
    pairs.extend(ring.iter().zip(0u32..).map(|(r, i)| (r.face, i)));
    pairs.sort_unstable();
    for (rank, &(_, i)) in (0u32..).zip(pairs.iter()) {
        ring[i as usize].rank = rank;
        order[rank as usize] = i;
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{assert_same_arena, cube, random_plane};
    use super::super::{ConvexArena, CutOutcome, PolyId};
    use crate::exact::Plane;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Cuts `poly` by `s` with and without the ring split and checks that
    /// they leave the arena element for element the same, with both parts
    /// valid; returns the outcome and the ring's length when it was used.
    fn checked_cut(
        arena: &mut ConvexArena,
        poly: PolyId,
        s: &Plane,
    ) -> (CutOutcome, Option<usize>) {
        let mut general = arena.clone();
        let expected = general.cut_by(poly, s, [3, 5], false);
        let before = arena.half_edges.len();
        let outcome = arena.cut_by(poly, s, [3, 5], true);
        assert_eq!(outcome, expected);
        assert_same_arena(arena, &general);
        let CutOutcome::Split { below, above } = outcome else {
            return (outcome, None);
        };
        arena
            .validate(below)
            .unwrap_or_else(|e| panic!("below: {e}"));
        arena
            .validate(above)
            .unwrap_or_else(|e| panic!("above: {e}"));
        // The ring holds this cut's faces when it was used: six half-edges
        // per face.
        let ring = arena.scratch.as_ref().expect("lent back").ring.len();
        let used = before + 6 * ring == arena.half_edges.len();
        (outcome, used.then_some(ring))
    }

    /// Chains of two-sided cuts of a box by random planes (normals of
    /// 2^10, where sections are generic, and of 2^2 with offsets on a coarse
    /// grid, where vertices often lie on the plane), going on with the part
    /// below, then cuts of the last polyhedron through its middle (long
    /// rings, beyond the counted ranks): the ring split leaves the arena
    /// element for element as the general march and split do, both parts
    /// valid, and most generic cuts take the ring.
    #[test]
    fn ring_splits_equal_the_general_split() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let (mut cuts, mut by_ring, mut longest) = (0, 0, 0);
        for scale in [1024.0, 4.0] {
            let mut arena = ConvexArena::new();
            let mut poly: PolyId = cube(&mut arena);
            for _ in 0..150 {
                let mut s = random_plane(&mut rng, scale, 0.8..0.99);
                if scale < 8.0 {
                    s = Plane::new(s.a, s.b, s.c, s.d >> 16 << 16).expect("in budget");
                }
                let (outcome, ring) = checked_cut(&mut arena, poly, &s);
                if let CutOutcome::Split { below, .. } = outcome {
                    poly = below;
                    if scale > 8.0 {
                        cuts += 1;
                        by_ring += usize::from(ring.is_some());
                    }
                }
            }
            for _ in 0..20 {
                let s = random_plane(&mut rng, 1024.0, 0.0..0.2);
                let mut copy = arena.clone();
                let (_, ring) = checked_cut(&mut copy, poly, &s);
                longest = longest.max(ring.unwrap_or(0));
            }
        }
        assert!(by_ring * 10 > cuts * 9, "{by_ring} ring cuts of {cuts}");
        assert!(
            longest > super::FEW_FACES,
            "rings of {longest} faces at most"
        );
    }
}
