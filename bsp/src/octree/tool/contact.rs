//! Whether a closed convex tool piece meets a closed box, exactly
//! (separating axis theorem).
//!
//! Notation: `P` — a closed convex polyhedron with integer vertices `v`
//! (a piece of a tool); `B = [lo, hi]` — a closed integer box; `n·x + d`
//! — a face plane of `P` (positive outside, so `P ⊆ {n·x + d ≤ 0}`);
//! `e` — an edge direction `v_j − v_i` of `P`; `x̂_a` — the unit vector of
//! axis `a`; `[u]_S = [min_S u·x, max_S u·x]` — the projection of a set `S`
//! on an axis `u`.
//!
//! Two disjoint compact convex polyhedra are strictly separated by a plane
//! whose normal is a facet normal of their Minkowski difference `P − B`:
//! a face normal of `P` (then `max_P n·x = −d < min_B n·x`), a face normal
//! of `B` (an axis `x̂_a`), or a cross product `e × x̂_a` of an edge of `P`
//! with an edge of `B`. So `P ∩ B = ∅` exactly when one of these axes
//! separates the projections strictly; touching at a vertex, along an
//! edge or on a face counts as meeting. (Paper 1 §3.8 reports the cells an
//! edit can reach; this test narrows them from the tool's bounds to the
//! tool itself.)
//!
//! Bit budget (`exact/budget.rs`): `|v| ≤ v⁺ = 2^26`, so `|e| ≤ 2^27` and
//! `e × x̂_a` has two components of magnitude `≤ 2^27`; `|n| ≤ n⁺ = 2^55`,
//! `|d| ≤ d⁺ = 2^83`. Box corners are any `i64` (`< 2^63`). Hence
//! `|n·x + d| < 3·2^55·2^63 + 2^83 < 2^121` and `|(e × x̂_a)·x| < 2·2^27·2^63
//! = 2^91`: every product and sum below is exact in `i128`, for any box.

use std::sync::OnceLock;

use crate::convex::{ConvexArena, PolyId};
use crate::exact::budget::{MAX_COORD, MAX_NORMAL, MAX_OFFSET};
use crate::octree::CellBox;

/// A closed convex polyhedron with integer vertices, prepared for the
/// exact contact test against boxes.
#[derive(Clone, Debug)]
pub(crate) struct ConvexPiece {
    /// The smallest closed box holding the piece: `[v]` on each axis.
    lo: [i64; 3],
    hi: [i64; 3],
    /// Face planes `(n, d)`, positive outside.
    faces: Vec<([i64; 3], i128)>,
    /// The vertices, each once.
    vertices: Vec<[i64; 3]>,
    /// The edge directions `e`, each edge once.
    edges: Vec<[i64; 3]>,
    /// The axes `e × x̂_a` (non-zero, reduced, first non-zero component
    /// positive, each once) with the piece's projection `[u]_P` on them;
    /// made on the first test that needs them (most boxes are decided by
    /// the box axes, the face planes or a point inside).
    edge_axes: OnceLock<Vec<EdgeAxis>>,
}

/// One axis `u = e × x̂_a` and the piece's projection on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct EdgeAxis {
    u: [i64; 3],
    min: i128,
    max: i128,
}

impl ConvexPiece {
    /// The piece for polyhedron `poly` of `arena`, or `None` when a vertex
    /// is not an integer point within the coordinate budget (the test
    /// then has no exact form here; callers fall back to bounds).
    pub(crate) fn of(arena: &ConvexArena, poly: PolyId) -> Option<ConvexPiece> {
        let face_ids = arena.faces_of(poly);
        let mut ids: Vec<u32> = face_ids
            .iter()
            .flat_map(|&f| arena.face_loop(f))
            .map(|h| arena.half_edges()[h as usize].origin)
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let vertices = ids
            .iter()
            .map(|&v| integer_point(arena, v))
            .collect::<Option<Vec<_>>>()?;
        let CellBox { min: lo, max: hi } = CellBox::enclosing(vertices.iter().copied())?;
        let position = |v: u32| ids.binary_search(&v).ok().map(|i| vertices[i]);
        let mut faces = Vec::with_capacity(face_ids.len());
        let mut edges = Vec::new();
        for &f in &face_ids {
            let plane = arena.face_plane(f);
            debug_assert!(plane.normal().iter().all(|c| c.abs() <= MAX_NORMAL));
            debug_assert!(plane.offset().abs() <= MAX_OFFSET);
            faces.push((plane.normal(), plane.offset()));
            for h in arena.face_loop(f) {
                let (from, to) = (arena.half_edges()[h as usize].origin, arena.dest(h));
                // Each edge is seen from both faces; keep it once.
                if from < to {
                    let (from, to) = (position(from)?, position(to)?);
                    edges.push([0, 1, 2].map(|a| to[a] - from[a]));
                }
            }
        }
        Some(ConvexPiece {
            lo,
            hi,
            faces,
            vertices,
            edges,
            edge_axes: OnceLock::new(),
        })
    }

    /// The axes `e × x̂_a` with the piece's projections.
    fn edge_axes(&self) -> &[EdgeAxis] {
        self.edge_axes.get_or_init(|| {
            let mut axes: Vec<[i64; 3]> = self
                .edges
                .iter()
                .flat_map(|e| {
                    // e × x̂, e × ŷ, e × ẑ.
                    [[0, e[2], -e[1]], [-e[2], 0, e[0]], [e[1], -e[0], 0]]
                })
                .filter_map(reduced)
                .collect();
            axes.sort_unstable();
            axes.dedup();
            axes.into_iter()
                .map(|u| {
                    let (mut min, mut max) = (i128::MAX, i128::MIN);
                    for v in &self.vertices {
                        let p = dot(u, *v);
                        min = min.min(p);
                        max = max.max(p);
                    }
                    EdgeAxis { u, min, max }
                })
                .collect()
        })
    }

    /// Whether the closed piece and the closed box `[lo, hi]` share at
    /// least a point (exact).
    pub(crate) fn touches(&self, lo: [i64; 3], hi: [i64; 3]) -> bool {
        if (0..3).any(|a| self.hi[a] < lo[a] || hi[a] < self.lo[a]) {
            return false;
        }
        // A box around the whole piece (the octree's large cells).
        if (0..3).all(|a| lo[a] <= self.lo[a] && self.hi[a] <= hi[a]) {
            return true;
        }
        // A face plane with the whole box strictly outside.
        if self
            .faces
            .iter()
            .any(|&(n, d)| box_range(n, lo, hi).0 + d > 0)
        {
            return false;
        }
        // Two cheap sufficient conditions decide most boxes that do meet
        // the piece before the edge axes: a vertex of the piece in the box,
        // or the box's centre in the piece (`n·(lo + hi) + 2d ≤ 0` for
        // every face; `|lo + hi| < 2^64`, so each term is `< 2^120`).
        if self
            .vertices
            .iter()
            .any(|v| (0..3).all(|a| lo[a] <= v[a] && v[a] <= hi[a]))
        {
            return true;
        }
        let centre2 = [0, 1, 2].map(|a| i128::from(lo[a]) + i128::from(hi[a]));
        if self
            .faces
            .iter()
            .all(|&(n, d)| (0..3).map(|a| i128::from(n[a]) * centre2[a]).sum::<i128>() + 2 * d <= 0)
        {
            return true;
        }
        !self.edge_axes().iter().any(|axis| {
            let (min, max) = box_range(axis.u, lo, hi);
            max < axis.min || axis.max < min
        })
    }

    /// Whether the piece and the box `[lo, hi]` (with `lo < hi` on every
    /// axis) share volume: their interiors meet (exact). Two
    /// full-dimensional convex polyhedra have disjoint interiors exactly
    /// when a plane separates them weakly, and the same axes as for
    /// [`ConvexPiece::touches`] suffice (the facet normals of `P − B`:
    /// `0` lies outside the interior of `P − B` exactly when it is on or
    /// beyond one of its facets).
    pub(crate) fn shares_volume(&self, lo: [i64; 3], hi: [i64; 3]) -> bool {
        debug_assert!((0..3).all(|a| lo[a] < hi[a]), "a box with volume");
        if (0..3).any(|a| self.hi[a] <= lo[a] || hi[a] <= self.lo[a]) {
            return false;
        }
        // A face plane with the whole box on or outside it.
        if self
            .faces
            .iter()
            .any(|&(n, d)| box_range(n, lo, hi).0 + d >= 0)
        {
            return false;
        }
        // Sufficient: a vertex of the piece strictly inside the box (the
        // piece has volume near each vertex), or the box's centre strictly
        // inside the piece.
        if self
            .vertices
            .iter()
            .any(|v| (0..3).all(|a| lo[a] < v[a] && v[a] < hi[a]))
        {
            return true;
        }
        let centre2 = [0, 1, 2].map(|a| i128::from(lo[a]) + i128::from(hi[a]));
        if self
            .faces
            .iter()
            .all(|&(n, d)| (0..3).map(|a| i128::from(n[a]) * centre2[a]).sum::<i128>() + 2 * d < 0)
        {
            return true;
        }
        !self.edge_axes().iter().any(|axis| {
            let (min, max) = box_range(axis.u, lo, hi);
            max <= axis.min || axis.max <= min
        })
    }
}

/// Vertex `v` of `arena` as an integer point within `±v⁺`, if it is one.
fn integer_point(arena: &ConvexArena, v: u32) -> Option<[i64; 3]> {
    let point = arena.point(v);
    // Fast path: the cached `f64`s are correctly rounded, so `W ≈ 1.0`
    // means the positive integer `W` is 1, and then each `X ≈ x` with
    // `|x| ≤ v⁺ < 2^53` is the integer `X` itself.
    let [x, y, z, w] = point.approx();
    let limit = MAX_COORD as f64;
    if w == 1.0 && [x, y, z].iter().all(|c| c.abs() <= limit) {
        return Some([x, y, z].map(|c| c as i64));
    }
    let w = point.w().to_i128()?;
    let xyz = point.xyz();
    let mut out = [0; 3];
    for a in 0..3 {
        let x = xyz[a].to_i128()?;
        if w <= 0 || x % w != 0 {
            return None;
        }
        let c = i64::try_from(x / w).ok()?;
        if c.abs() > MAX_COORD {
            return None;
        }
        out[a] = c;
    }
    Some(out)
}

/// `u` divided by the gcd of its components, with its first non-zero
/// component positive; `None` for the zero vector.
fn reduced(u: [i64; 3]) -> Option<[i64; 3]> {
    let g = u.iter().fold(0, |g, &c| gcd(g, c.unsigned_abs()));
    if g == 0 {
        return None;
    }
    // g ≤ 2^27 (a component of an edge), so it converts back exactly.
    let g = g as i64;
    let sign = if u.iter().find(|&&c| c != 0).is_some_and(|&c| c < 0) {
        -1
    } else {
        1
    };
    Some(u.map(|c| sign * (c / g)))
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// `u·x`, exact (see the bit budget above).
pub(super) fn dot(u: [i64; 3], x: [i64; 3]) -> i128 {
    (0..3).map(|a| i128::from(u[a]) * i128::from(x[a])).sum()
}

/// `[u]_B` for the box `[lo, hi]` (`lo ≤ hi` on every axis): each term
/// takes the corner coordinate that makes it smallest (largest), `lo` for
/// the minimum where `u_a ≥ 0` and `hi` where `u_a < 0`.
pub(super) fn box_range(u: [i64; 3], lo: [i64; 3], hi: [i64; 3]) -> (i128, i128) {
    debug_assert!((0..3).all(|a| lo[a] <= hi[a]), "an ordered box");
    let (mut min, mut max) = (0i128, 0i128);
    for a in 0..3 {
        let (near, far) = if u[a] >= 0 {
            (lo[a], hi[a])
        } else {
            (hi[a], lo[a])
        };
        min += i128::from(u[a]) * i128::from(near);
        max += i128::from(u[a]) * i128::from(far);
    }
    (min, max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::IntPoint;
    use crate::tools::convex_hull;

    fn piece(points: &[[i64; 3]]) -> ConvexPiece {
        let mut arena = ConvexArena::new();
        let points: Vec<IntPoint> = points
            .iter()
            .map(|&p| IntPoint::from_array(p).unwrap())
            .collect();
        let poly = convex_hull(&mut arena, &points).unwrap();
        ConvexPiece::of(&arena, poly).unwrap()
    }

    #[test]
    fn a_tetrahedron_keeps_its_faces_and_edge_axes() {
        let t = piece(&[[0, 0, 0], [4, 0, 0], [0, 4, 0], [0, 0, 4]]);
        assert_eq!((t.lo, t.hi), ([0; 3], [4; 3]));
        assert_eq!((t.faces.len(), t.vertices.len(), t.edges.len()), (4, 4, 6));
        // Three edges along the axes give two axes each (the axes of the
        // box, already tested as such, once reduced); the three slanted
        // edges give (0, 1, 1), (1, 0, 1), (1, 1, 0) and the box axes.
        let mut us: Vec<[i64; 3]> = t.edge_axes().iter().map(|a| a.u).collect();
        us.sort_unstable();
        assert_eq!(
            us,
            vec![
                [0, 0, 1],
                [0, 1, 0],
                [0, 1, 1],
                [1, 0, 0],
                [1, 0, 1],
                [1, 1, 0]
            ]
        );
        // Projections of the tetrahedron on (1, 1, 0): [0, 4].
        let axis = t.edge_axes().iter().find(|a| a.u == [1, 1, 0]).unwrap();
        assert_eq!((axis.min, axis.max), (0, 4));
    }

    /// Sharing volume with a box, decided from the pieces, agrees with
    /// the tool's BSP cut into cells inside the box: some solid cell (each
    /// has volume) exactly when they share volume. Boxes are small and
    /// on the grid of the hull's points, so many only touch the tool.
    #[test]
    fn shares_volume_agrees_with_the_cells() {
        use rand::{Rng, SeedableRng};
        use rand_chacha::ChaCha8Rng;

        use crate::octree::{CellBox, Tool};
        use crate::tree::EMPTY;

        let mut rng = ChaCha8Rng::seed_from_u64(23);
        let (mut shared, mut touching_only) = (0, 0);
        for _ in 0..200 {
            let points: Vec<IntPoint> = (0..8)
                .map(|_| {
                    IntPoint::from_array([0; 3].map(|_: i64| rng.random_range(0..=8))).unwrap()
                })
                .collect();
            let Ok(tool) = Tool::convex_hull(&points) else {
                continue;
            };
            for _ in 0..10 {
                let min = [0; 3].map(|_: i64| rng.random_range(-3..=8));
                let edge = [0; 3].map(|_: i64| rng.random_range(1..=4));
                let cell = CellBox {
                    min,
                    max: [0, 1, 2].map(|a| min[a] + edge[a]),
                };
                let mut arena = ConvexArena::new();
                let poly = cell.add_to(&mut arena).unwrap();
                let solid = tool
                    .bsp()
                    .cells(&mut arena, poly)
                    .iter()
                    .any(|c| c.label != EMPTY);
                assert_eq!(tool.shares_volume(&cell), Some(solid), "{cell:?}");
                if solid {
                    shared += 1;
                } else if tool.touches(&cell) {
                    touching_only += 1;
                }
            }
        }
        assert!(
            shared > 100 && touching_only > 20,
            "{shared} {touching_only}"
        );
    }

    #[test]
    fn non_integer_vertices_have_no_piece() {
        let mut arena = ConvexArena::new();
        let lo = IntPoint::new(0, 0, 0).unwrap();
        let hi = IntPoint::new(3, 3, 3).unwrap();
        let poly = arena.add_box(lo, hi).unwrap();
        // The plane x + y + z = 4 meets the box's edges at non-integer
        // points only where it crosses them between grid points: use
        // 2x + 2y + 2z = 5 (vertices like (5/2, 0, 0)).
        let plane = crate::exact::Plane::new(2, 2, 2, -5).unwrap();
        let crate::convex::CutOutcome::Split { below, .. } =
            arena.cut(poly, &plane, crate::convex::NO_TAG, crate::convex::NO_TAG)
        else {
            panic!("the plane crosses the box");
        };
        let kept = below;
        assert!(ConvexPiece::of(&arena, kept).is_none());
        let mut arena = ConvexArena::new();
        let poly = arena.add_box(lo, hi).unwrap();
        assert!(ConvexPiece::of(&arena, poly).is_some());
    }
}
