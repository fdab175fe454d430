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
use crate::tools::hull::HullPolygons;

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

    /// The piece of a convex hull of integer points, from its polygons:
    /// the piece [`ConvexPiece::of`] makes of the same polyhedron added to
    /// an arena (vertices in the arena's order, faces in
    /// [`ConvexArena::faces_of`] order), without the arena.
    pub(crate) fn from_hull(hull: &HullPolygons) -> Option<ConvexPiece> {
        let CellBox { min: lo, max: hi } = CellBox::enclosing(hull.vertices.iter().copied())?;
        let mut faces = Vec::with_capacity(hull.face_count());
        let mut edges = Vec::with_capacity(hull.corners.len() / 2);
        for &f in &hull.breadth_first {
            let plane = hull.planes[f as usize];
            faces.push((plane.normal(), plane.offset()));
            let corners = hull.face(f as usize);
            for (k, &from) in corners.iter().enumerate() {
                let to = corners[(k + 1) % corners.len()];
                // Each edge is seen from both faces; keep it once.
                if from < to {
                    let (from, to) = (hull.vertices[from as usize], hull.vertices[to as usize]);
                    edges.push([to[0] - from[0], to[1] - from[1], to[2] - from[2]]);
                }
            }
        }
        Some(ConvexPiece {
            lo,
            hi,
            faces,
            vertices: hull.vertices.clone(),
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
            // `u = e × x̂_a` has `u_a = 0`, so `u·v` depends only on `v`
            // projected along `x̂_a`, and a linear function on a point set
            // takes its extremes at vertices of the set's convex hull: the
            // vertices whose projections are the corners of that outline
            // give the same `[u]_P` as all of them (hundreds of axes, each
            // scanned over a few outline vertices instead of every one).
            let outlines = [0, 1, 2].map(|a| outline(&self.vertices, a));
            axes.into_iter()
                .map(|u| {
                    let a = (0..3)
                        .find(|&a| u[a] == 0)
                        .unwrap_or_else(|| unreachable!("an axis e × x̂_a has a zero component"));
                    let (mut min, mut max) = (i128::MAX, i128::MIN);
                    for v in &outlines[a] {
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

/// The points of `vertices` whose projections along axis `a` (onto the
/// other two coordinates) are the corners of the projections' convex hull,
/// each once (Andrew's monotone chain; points on an edge of the hull or
/// repeated are left out). Every linear function of the other two
/// coordinates takes the same least and greatest value on them as on all
/// of `vertices`. Exact: cross products of differences of in-budget
/// coordinates (`< 2^28`) fit `i128` with room to spare.
fn outline(vertices: &[[i64; 3]], a: usize) -> Vec<[i64; 3]> {
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    let mut points: Vec<[i64; 3]> = vertices.to_vec();
    points.sort_unstable_by_key(|v| (v[b], v[c]));
    points.dedup_by_key(|v| (v[b], v[c]));
    if points.len() < 3 {
        return points;
    }
    // Whether `r` lies strictly left of the ray from `p` through `q`.
    let left = |p: &[i64; 3], q: &[i64; 3], r: &[i64; 3]| {
        let (ux, uy) = (i128::from(q[b] - p[b]), i128::from(q[c] - p[c]));
        let (vx, vy) = (i128::from(r[b] - p[b]), i128::from(r[c] - p[c]));
        ux * vy - uy * vx > 0
    };
    // The lower chain left to right and the upper one right to left, each
    // turning left at every corner; each chain's last point starts the
    // other.
    let chain = |ordered: &mut dyn Iterator<Item = &[i64; 3]>| {
        let mut chain: Vec<[i64; 3]> = Vec::new();
        for p in ordered {
            while let [.., o, q] = chain[..]
                && !left(&o, &q, p)
            {
                chain.pop();
            }
            chain.push(*p);
        }
        chain.pop();
        chain
    };
    let mut hull = chain(&mut points.iter());
    hull.extend(chain(&mut points.iter().rev()));
    hull
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

    /// The outline along each axis gives every direction with a zero
    /// component there the same extremes as all the points, on random
    /// point sets with repeated, collinear and coplanar projections, and
    /// keeps only points of the set, each once.
    #[test]
    fn outlines_keep_the_extremes() {
        use rand::{Rng, SeedableRng};
        use rand_chacha::ChaCha8Rng;

        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let mut dropped = 0;
        for round in 0..300 {
            let range = 1 + round % 12;
            let n = 1 + round % 40;
            let points: Vec<[i64; 3]> = (0..n)
                .map(|_| [0; 3].map(|_: i64| rng.random_range(-range..=range) << (round % 20)))
                .collect();
            for a in 0..3 {
                let kept = outline(&points, a);
                assert!(kept.iter().all(|k| points.contains(k)));
                let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                let mut keys: Vec<_> = kept.iter().map(|v| (v[b], v[c])).collect();
                keys.sort_unstable();
                keys.dedup();
                assert_eq!(keys.len(), kept.len(), "a projection kept twice");
                dropped += points.len() - kept.len();
                for _ in 0..20 {
                    let mut u = [0; 3].map(|_: i64| rng.random_range(-1000..=1000));
                    u[a] = 0;
                    let range = |set: &[[i64; 3]]| {
                        let values = set.iter().map(|v| dot(u, *v));
                        (values.clone().min(), values.max())
                    };
                    assert_eq!(range(&kept), range(&points), "{points:?} along {a}, {u:?}");
                }
            }
        }
        assert!(dropped > 1000, "only {dropped} points left out");
    }
}
