//! The split as it was first written, step by step (test only): the
//! reference that `split` must reproduce element for element.

use super::mesh::{ConvexArena, Face, HalfEdge, Vertex};
use super::scratch::FaceInfo;
use super::scratch::Scratch;
use super::split::sort_by_face;
use crate::exact::{Plane, Sign, intersect_3_planes};

impl ConvexArena {
    /// Splits along the section, given the faces that meet it in
    /// `scratch.relevant` with their vertices classified; `tags` are those
    /// of the lower and upper part's caps. Builds both parts, or with
    /// `keep`, only the part on that side. Returns the first half-edge of
    /// each part's cap (`u32::MAX` for a part not built).
    pub(super) fn split_along_reference(
        &mut self,
        scratch: &mut Scratch,
        s: &Plane,
        tags: [u32; 2],
        keep: Option<Sign>,
    ) -> [u32; 2] {
        let mut relevant = std::mem::take(&mut scratch.relevant);
        let mut section = std::mem::take(&mut scratch.section);
        let mut section_new = Vec::new();
        // Sorted, so the result does not depend on how the faces were found.
        sort_by_face(&mut relevant);
        // 1. Split crossing edges.
        for &(_, info) in &relevant {
            if let FaceInfo::Straddling { crossing, .. } = info
                && crossing != u32::MAX
            {
                // The new vertex lies on s; nothing reads sides from here on.
                self.split_edge_reference(crossing, s);
            }
        }
        // 2. Split straddling faces; list the section edges by the side of
        // their face, those of the new faces (all `+`) last.
        for list in &mut section {
            list.clear();
        }
        section_new.clear();
        for &(f, info) in &relevant {
            match (info, keep) {
                (
                    FaceInfo::Straddling {
                        enter, first_chain, ..
                    },
                    None,
                ) => {
                    let (kept, new) = self
                        .split_face_reference(f, &self.face_zeros_reference(enter, first_chain));
                    section[0].push(kept);
                    section_new.push(new);
                }
                (
                    FaceInfo::Straddling {
                        enter, first_chain, ..
                    },
                    Some(side),
                ) => {
                    // Listed where the two-sided split lists them, so that
                    // the kept part comes out the same.
                    let edge = self.trim_face_reference(
                        f,
                        side,
                        &self.face_zeros_reference(enter, first_chain),
                    );
                    if side == Sign::Negative {
                        section[0].push(edge);
                    } else {
                        section_new.push(edge);
                    }
                }
                (FaceInfo::Touching { side, edge }, _) => {
                    if keep.is_none_or(|k| k == side) {
                        section[usize::from(side == Sign::Positive)].push(edge);
                    }
                }
            }
        }
        section[1].extend_from_slice(&section_new);
        // 3. Caps.
        let outcome = self.add_caps_reference(&section, scratch, s, tags, keep);
        scratch.relevant = relevant;
        scratch.section = section;
        outcome
    }

    /// Splits the edge of half-edge `h` at its intersection with `s`;
    /// returns the new vertex, which `h` now ends at.
    /// Adds a vertex where the planes of faces `f` and `g` meet `s`;
    /// `None` when the three planes do not meet in one point.
    fn push_meet_vertex(&mut self, f: u32, g: u32, s: &Plane, half_edge: u32) -> Option<u32> {
        let point = intersect_3_planes(self.face_plane(f), self.face_plane(g), s)?;
        Some(self.push_vertex(point, half_edge))
    }

    fn split_edge_reference(&mut self, h: u32, s: &Plane) -> u32 {
        let e = self.half_edges[h as usize];
        let t = self.half_edges[e.twin as usize];
        let (h2, t2) = (
            self.half_edges.len() as u32,
            self.half_edges.len() as u32 + 1,
        );
        let m = self
            .push_meet_vertex(e.face, t.face, s, h2)
            .expect("a crossing edge meets the cutting plane in one point");
        // h: a→b becomes a→m, h2: m→b; twin t: b→a becomes b→m, t2: m→a.
        self.half_edges.extend_from_slice(&[
            HalfEdge {
                origin: m,
                twin: e.twin,
                next: e.next,
                face: e.face,
            },
            HalfEdge {
                origin: m,
                twin: h,
                next: t.next,
                face: t.face,
            },
        ]);
        let old = &mut self.half_edges[h as usize];
        (old.next, old.twin) = (h2, t2);
        let old_twin = &mut self.half_edges[e.twin as usize];
        (old_twin.next, old_twin.twin) = (t2, h2);
        m
    }

    /// The two `0` vertices of a straddling face once its crossing edges
    /// are split, from what the survey of the face found.
    fn face_zeros_reference(&self, enter: [u32; 2], first_chain: Sign) -> FaceZeros {
        FaceZeros {
            leave: enter.map(|e| self.half_edges[e as usize].next),
            enter,
            first_chain,
        }
    }

    /// Trims straddling face `f` to its half on side `keep` by one new
    /// half-edge between its two `0` vertices (the other half's half-edges
    /// are left unused); returns the new half-edge, which lies in `s`.
    fn trim_face_reference(&mut self, f: u32, keep: Sign, z: &FaceZeros) -> u32 {
        // The kept chain runs from zero k to zero 1 − k; the new half-edge
        // closes it, from zero 1 − k back to zero k.
        let k = usize::from(z.first_chain != keep);
        let new = self.half_edges.len() as u32;
        self.half_edges.push(HalfEdge {
            origin: self.half_edges[z.leave[1 - k] as usize].origin,
            twin: u32::MAX,
            next: z.leave[k],
            face: f,
        });
        self.half_edges[z.enter[1 - k] as usize].next = new;
        self.faces[f as usize].half_edge = new;
        new
    }

    /// Splits straddling face `f` (now with exactly two `0` vertices) along
    /// the segment between them: `f` keeps the `−` half and a new face gets
    /// the `+` half. Returns the new half-edge in `s` of each half, `f`'s
    /// first.
    fn split_face_reference(&mut self, f: u32, z: &FaceZeros) -> (u32, u32) {
        let (z1, z2) = (
            self.half_edges[z.leave[0] as usize].origin,
            self.half_edges[z.leave[1] as usize].origin,
        );
        // Chain 0 runs from z1 to z2 (half-edges leave[0] … enter[1]),
        // chain 1 from z2 to z1; a: z2→z1 closes chain 0, b: z1→z2 closes
        // chain 1. Twins are set when the caps are built.
        let chain_0_positive = z.first_chain == Sign::Positive;
        let (a, b) = (
            self.half_edges.len() as u32,
            self.half_edges.len() as u32 + 1,
        );
        let new_face = self.faces.len() as u32;
        let face = self.faces[f as usize];
        let (face_0, face_1) = if chain_0_positive {
            (new_face, f)
        } else {
            (f, new_face)
        };
        // The `+` chain moves to the new face (before the loop is cut).
        let (start, end) = if chain_0_positive {
            (z.leave[0], z.enter[1])
        } else {
            (z.leave[1], z.enter[0])
        };
        let mut h = start;
        loop {
            self.half_edges[h as usize].face = new_face;
            if h == end {
                break;
            }
            h = self.half_edges[h as usize].next;
        }
        self.half_edges.extend_from_slice(&[
            HalfEdge {
                origin: z2,
                twin: u32::MAX,
                next: z.leave[0],
                face: face_0,
            },
            HalfEdge {
                origin: z1,
                twin: u32::MAX,
                next: z.leave[1],
                face: face_1,
            },
        ]);
        self.half_edges[z.enter[1] as usize].next = a;
        self.half_edges[z.enter[0] as usize].next = b;
        let (kept, new) = if chain_0_positive { (b, a) } else { (a, b) };
        self.faces.push(Face {
            half_edge: new,
            ..face
        });
        self.faces[f as usize].half_edge = kept;
        (kept, new)
    }

    /// Builds the two caps along the section and separates the parts, or
    /// with `keep` only the cap of that side's part; `section[k]` lists the
    /// half-edges lying in `s` on faces of the lower (`k = 0`) and upper
    /// part (of the kept side only, with `keep`). Returns the first
    /// half-edge of each cap (`u32::MAX` for a cap not built).
    fn add_caps_reference(
        &mut self,
        section: &[Vec<u32>; 2],
        scratch: &mut Scratch,
        s: &Plane,
        tags: [u32; 2],
        keep: Option<Sign>,
    ) -> [u32; 2] {
        // One cap per side: for each section half-edge u→v on a face of that
        // side, the cap gets v→u, and cap edges chain by shared vertices.
        let mut cap_edges = Vec::new();
        let mut first_cap_edge = [u32::MAX; 2];
        for (k, side) in [Sign::Negative, Sign::Positive].into_iter().enumerate() {
            if keep.is_some_and(|kept| kept != side) {
                continue;
            }
            let plane = self.push_plane(if side == Sign::Negative {
                *s
            } else {
                s.flipped()
            });
            let cap = self.faces.len() as u32;
            let first = self.half_edges.len() as u32;
            scratch.cap_starts.clear();
            cap_edges.clear();
            // The cap half-edges get the indices from `first` on, in the
            // order of the section list: pair them and note where each
            // starts before writing them all at once.
            for (c, &h) in (first..).zip(&section[k]) {
                let e = self.half_edges[h as usize];
                let (u, v) = (e.origin, self.half_edges[e.next as usize].origin);
                self.half_edges[h as usize].twin = c;
                scratch.cap_starts.insert(v, c);
                cap_edges.push((u, v));
            }
            let starts = &scratch.cap_starts;
            self.half_edges
                .extend(
                    section[k]
                        .iter()
                        .zip(&cap_edges)
                        .map(|(&h, &(u, v))| HalfEdge {
                            origin: v,
                            twin: h,
                            next: starts.get(u).expect("the section is a closed loop"),
                            face: cap,
                        }),
                );
            self.faces.push(Face {
                plane,
                half_edge: first,
                tag: tags[k],
            });
            first_cap_edge[k] = first;
            if side == Sign::Negative || keep.is_some() {
                // The lower part (or the only part built) keeps the section
                // vertices.
                for (c, &(_, v)) in (first..).zip(&cap_edges) {
                    self.vertices[v as usize].half_edge = c;
                }
            } else {
                // The upper part gets copies (sharing the exact point):
                // rotate around each section
                // vertex through the upper part's half-edges (now closed off
                // by the cap) and re-point their origins.
                for (c, &(_, v)) in (first..).zip(&cap_edges) {
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
        first_cap_edge
    }
}

/// The two `0` vertices of a straddling face, in the order its loop from
/// its stored half-edge meets them (crossing edges split).
struct FaceZeros {
    /// The half-edge of the face leaving each.
    leave: [u32; 2],
    /// The half-edge of the face entering each.
    enter: [u32; 2],
    /// The side of the vertices on the chain from the first to the second.
    first_chain: Sign,
}

#[cfg(test)]
mod tests {
    use super::super::{ConvexArena, PolyId};
    use super::Scratch;
    use crate::exact::{IntPoint, Plane, Sign};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A split: the split or its reference.
    type Split = fn(&mut ConvexArena, &mut Scratch, &Plane, [u32; 2], Option<Sign>) -> [u32; 2];

    /// Cuts `poly` by `s` classifying every vertex, then splits with
    /// `split` (the split or its reference); `None` when the cut is not
    /// proper.
    fn cut_with(
        arena: &mut ConvexArena,
        poly: PolyId,
        s: &Plane,
        keep: Option<Sign>,
        split: Split,
    ) -> Option<[u32; 2]> {
        arena.with_scratch(|arena, scratch| {
            if arena.classify_all(poly, s, scratch) != (true, true) {
                return None;
            }
            Some(split(arena, scratch, s, [7, 9], keep))
        })
    }

    /// Every array of both arenas, element for element.
    fn assert_same(a: &ConvexArena, b: &ConvexArena) {
        assert_eq!(a.half_edges, b.half_edges);
        assert_eq!(a.planes, b.planes);
        assert_eq!(a.faces.len(), b.faces.len());
        for (x, y) in a.faces.iter().zip(&b.faces) {
            assert_eq!((x.plane, x.half_edge, x.tag), (y.plane, y.half_edge, y.tag));
        }
        assert_eq!(a.vertices.len(), b.vertices.len());
        for (x, y) in a.vertices.iter().zip(&b.vertices) {
            assert_eq!((x.point, x.half_edge), (y.point, y.half_edge));
        }
        assert_eq!(a.points.len(), b.points.len());
        for (p, q) in a.points.iter().zip(&b.points) {
            assert_eq!((p.xyz_digits, p.w_digits), (q.xyz_digits, q.w_digits));
        }
    }

    /// Chains of cuts, two-sided and keeping either part, by random planes
    /// with small coefficients (many through vertices and along edges, so
    /// that touching faces and `0` vertices are common) and by planes
    /// tangent to a sphere (many faces): the split gives the reference's
    /// arrays, element for element.
    #[test]
    fn the_split_equals_its_reference() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (mut proper, mut touching) = (0, 0);
        for chain in 0..200 {
            let mut arena = ConvexArena::new();
            let r = if chain % 2 == 0 { 6 } else { 1 << 20 };
            let corner = |c| IntPoint::new(c, c, c).expect("in budget");
            let mut poly = arena.add_box(corner(-r), corner(r)).expect("a box");
            for _ in 0..40 {
                let s = if chain % 2 == 0 {
                    let n = [0; 3].map(|_| rng.random_range(-2..=2i64));
                    let Ok(s) = Plane::new(n[0], n[1], n[2], rng.random_range(-8..=8)) else {
                        continue;
                    };
                    s
                } else {
                    let v = [0; 3].map(|_| rng.random_range(-1000..=1000i64));
                    let norm = ((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) as f64).sqrt();
                    let d = -(rng.random_range(0.8..0.99) * r as f64 * norm) as i128;
                    let Ok(s) = Plane::new(v[0], v[1], v[2], d) else {
                        continue;
                    };
                    s
                };
                let keep =
                    [None, Some(Sign::Negative), Some(Sign::Positive)][rng.random_range(0..3usize)];
                let mut reference = arena.clone();
                let expected = cut_with(
                    &mut reference,
                    poly,
                    &s,
                    keep,
                    ConvexArena::split_along_reference,
                );
                touching += usize::from(reference.scratch.as_ref().is_some_and(|scratch| {
                    scratch
                        .relevant
                        .iter()
                        .any(|(_, info)| matches!(info, super::FaceInfo::Touching { .. }))
                }));
                let got = cut_with(&mut arena, poly, &s, keep, ConvexArena::split_along);
                assert_eq!(got, expected);
                assert_same(&arena, &reference);
                if let Some(parts) = got {
                    proper += 1;
                    let k = usize::from(keep == Some(Sign::Positive) || rng.random_bool(0.2));
                    let part = if keep.is_some() {
                        parts[usize::from(keep == Some(Sign::Positive))]
                    } else {
                        parts[k]
                    };
                    poly = PolyId(part);
                    arena.validate(poly).expect("a valid part");
                }
            }
        }
        assert!(proper > 1000 && touching > 25, "{proper} {touching}");
    }
}
