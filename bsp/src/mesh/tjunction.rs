//! T-junction removal (paper 1 §3.4, last paragraph): every welded vertex
//! lying strictly inside an edge of a polygon becomes a corner of it.
//!
//! Notation as in [`super`]: face plane `s`, edge planes `e_k`, corners
//! `c_k = s ∩ e_{k−1} ∩ e_k`, edge `k` = segment `c_k c_{k+1}` on the line
//! `L_k = s ∩ e_k`.
//!
//! # The exact test
//!
//! A vertex `w` lies strictly inside edge `k` iff
//!
//! ```text
//!     s(w) = 0,   e_k(w) = 0,   e_{k−1}(w) < 0,   e_{k+1}(w) < 0.
//! ```
//!
//! The first two put `w` on `L_k`. `e_{k−1}` is not parallel to `L_k`
//! (otherwise `s, e_{k−1}, e_k` would not meet in the single point `c_k`),
//! so along `L_k` it is affine and strictly monotone, zero exactly at `c_k`;
//! the polygon lies on its negative side and `c_{k+1} ≠ c_k` is on `L_k`, so
//! `e_{k−1} < 0` is the open half-line from `c_k` through `c_{k+1}`. In the
//! same way `e_{k+1} < 0` is the open half-line from `c_{k+1}` through
//! `c_k`; both together are the open segment. For a triangle `k − 1` and
//! `k + 1` are the two other edges (indices `k + 2` and `k + 1` mod 3, never
//! equal), so the test holds for every `n ≥ 3`.
//!
//! Inserted vertices are ordered along the edge by their exact distance to
//! `e_{k−1}` ([`compare_offsets`]): all are negative, the nearest to `c_k`
//! is the largest. Distinct points on `L_k` never tie, since `e_{k−1}` is
//! strictly monotone along it.
//!
//! # Edges matched whole
//!
//! An original edge `a → b` used by exactly one polygon, whose opposite
//! `b → a` is also an original edge of exactly one polygon with the same
//! materials on both sides, is left as it is: splitting would insert the same vertices (those strictly inside the
//! segment `ab`) into both, in opposite orders, and the pieces would pair
//! up again. Leaving both whole removes equally many uses of each piece
//! and of its opposite, so every directed edge is still used as often as
//! its opposite, and a directed edge used once with its opposite once
//! stays so: the mesh is closed whenever the fully split one is, and
//! watertight whenever that one is. As both polygons have the same materials, keeping
//! polygons by material ([`super::SurfaceMesh::retain`], e.g. the outer
//! surface) keeps both or neither, and the same holds for what is kept. Most edges between faces of one cell are matched whole,
//! and skip the search below. A mesh sealed against its neighbours
//! ([`super::seal`]) matches no edge lying in a wall of its cell.
//!
//! # Candidates
//!
//! Up to `SCAN_MAX` vertices (the surface of one octree cell), every
//! vertex whose `f64` x lies in the edge's box widened by the tolerance
//! below (the vertices sorted by x once, two binary searches per edge);
//! above, a dense uniform grid over the `f64` positions of the
//! vertices, about `2∛V` cells per axis (`8V` cells in all, stored as one
//! offset array and one index array), where each edge visits the cells
//! near it in steps of at most one cell, every step's box widened by a
//! tolerance (`2^-40` of the largest coordinate) far above the rounding of
//! the positions (each within `2^-51` relative, see [`super::weld`]). A
//! cheap `f64` test then drops vertices certainly off the segment, with
//! the same margin. So a vertex exactly on the segment always reaches the
//! exact test, which decides: both ways find the same vertices.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use super::MeshPolygon;
use crate::exact::{Point4, Sign, classify_vertex, compare_offsets};
use crate::pool::{PerThread, Pool};
use crate::word_hash::WordHasher;

/// Directed edge `(from, to)` packed into one word.
#[inline]
fn edge_key(from: u32, to: u32) -> u64 {
    (u64::from(from) << 32) | u64::from(to)
}

/// Inserts every T-junction into every polygon, except on edges matched
/// whole (see the module docs).
pub(crate) fn split(vertices: &[Point4], polygons: &mut [MeshPolygon]) {
    split_with(vertices, polygons, SCAN_MAX, &[]);
}

/// [`split`], but no edge whose two ends share a wall (a set bit of
/// `walls[v]`, one bit per wall plane, per vertex `v`) is matched whole:
/// points of a neighbouring mesh may lie inside it (see
/// [`super::seal`]). Vertices past the end of `walls` lie on no wall.
pub(crate) fn split_sealed(vertices: &[Point4], polygons: &mut [MeshPolygon], walls: &[u8]) {
    split_with(vertices, polygons, SCAN_MAX, walls);
}

/// [`split_sealed`], scanning every vertex for every edge up to
/// `scan_max` vertices, with a grid above.
fn split_with(vertices: &[Point4], polygons: &mut [MeshPolygon], scan_max: usize, walls: &[u8]) {
    let mut scratch = Scratch::take();
    split_in(vertices, polygons, scan_max, walls, &mut scratch);
    scratch.give_back();
}

/// Working memory of [`split`], kept per thread: a game re-meshes a few
/// cells after every edit, each surface about as large as the last, so
/// these buffers are reused rather than grown anew for every cell.
#[derive(Default)]
struct Scratch {
    /// The one polygon using each original directed edge, or `SHARED`.
    owners: HashMap<u64, u32, BuildHasherDefault<WordHasher>>,
    /// Per original edge of every polygon: whether it is matched whole.
    whole: Vec<bool>,
    /// The `f64` position of every vertex.
    positions: Vec<[f64; 3]>,
    /// Per vertex, the last edge whose grid candidates included it.
    seen: Vec<u64>,
    /// Vertices near the edge: in the grid's cells, or within the edge's
    /// box along x (scan).
    candidates: Vec<u32>,
    /// Without a grid, the vertices by `f64` x, and their x in that order.
    by_x: Vec<u32>,
    xs: Vec<f64>,
    /// Vertices strictly inside the edge, in order along it.
    inside: Vec<u32>,
    /// The polygon's original corners, its new corners and the positions
    /// of the original ones among them.
    originals: Vec<u32>,
    corners: Vec<u32>,
    positions_of_originals: Vec<u32>,
}

thread_local! {
    /// The [`Scratch`] of this thread, between calls.
    static SCRATCH: Pool<Scratch> = const { Pool::new(1) };
}

/// Vertices above which the working memory is freed rather than kept
/// (after a whole-surface mesh).
const KEEP_MAX: usize = 1 << 12;

impl Scratch {
    /// The working memory of this thread, or a new one when it is in use.
    fn take() -> Self {
        SCRATCH.take().unwrap_or_default()
    }

    /// Keeps the working memory for the next call on this thread, unless
    /// it grew large.
    fn give_back(self) {
        if self.positions.capacity() <= KEEP_MAX {
            SCRATCH.keep(self);
        }
    }
}

/// [`split_with`] with the working memory `scratch`.
fn split_in(
    vertices: &[Point4],
    polygons: &mut [MeshPolygon],
    scan_max: usize,
    walls: &[u8],
    scratch: &mut Scratch,
) {
    let Scratch {
        owners,
        whole,
        positions,
        seen,
        candidates,
        by_x,
        xs,
        inside,
        originals,
        corners,
        positions_of_originals,
    } = scratch;
    matched_whole(polygons, owners, whole);
    if !walls.is_empty() {
        unmatch_wall_edges(polygons, walls, whole);
    }
    let mut edge_index = 0;
    positions.clear();
    positions.extend(vertices.iter().map(Point4::to_f64));
    let grid = Grid::new(positions, scan_max);
    seen.clear();
    by_x.clear();
    xs.clear();
    if grid.is_dense() {
        seen.resize(positions.len(), u64::MAX);
    } else {
        by_x.extend(0..positions.len() as u32);
        by_x.sort_unstable_by(|&p, &q| {
            positions[p as usize][0].total_cmp(&positions[q as usize][0])
        });
        xs.extend(by_x.iter().map(|&v| positions[v as usize][0]));
    }
    let mut edge_number = 0u64;
    for polygon in polygons.iter_mut() {
        let n = polygon.original_len();
        originals.clear();
        originals.extend(
            polygon
                .originals
                .iter()
                .map(|&o| polygon.corners[o as usize]),
        );
        corners.clear();
        positions_of_originals.clear();
        for k in 0..n {
            let (a, b) = (originals[k], originals[(k + 1) % n]);
            positions_of_originals.push(corners.len() as u32);
            corners.push(a);
            edge_index += 1;
            if whole[edge_index - 1] {
                continue;
            }
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            let segment = Segment::new(pa, pb, grid.tolerance);
            let on_edge = |&w: &u32| {
                w != a
                    && w != b
                    && segment.may_hold(positions[w as usize])
                    && strictly_inside_edge(&vertices[w as usize], polygon, k)
            };
            inside.clear();
            candidates.clear();
            if grid.is_dense() {
                grid.near_segment(pa, pb, edge_number, seen, candidates);
                edge_number += 1;
            } else {
                // Every vertex whose x lies in the edge's widened box: the
                // others fail `Segment::may_hold`.
                let start = xs.partition_point(|&x| x < segment.lo[0]);
                let end = start + xs[start..].partition_point(|&x| x <= segment.hi[0]);
                candidates.extend_from_slice(&by_x[start..end]);
            }
            inside.extend(candidates.iter().copied().filter(on_edge));
            let previous = polygon.edges[(k + n - 1) % n];
            inside.sort_by(|&p, &q| {
                compare_offsets(&vertices[q as usize], &vertices[p as usize], &previous)
            });
            corners.extend_from_slice(inside);
        }
        // Reuse the polygon's own storage (most polygons are unchanged).
        if polygon.corners != *corners {
            polygon.corners.clone_from(corners);
            polygon.originals.clone_from(positions_of_originals);
        }
    }
}

/// Per original edge of every polygon (in order): whether it is matched
/// whole (see the module docs), into `whole`; `owners` is working memory.
fn matched_whole(
    polygons: &[MeshPolygon],
    owners: &mut HashMap<u64, u32, BuildHasherDefault<WordHasher>>,
    whole: &mut Vec<bool>,
) {
    const SHARED: u32 = u32::MAX;
    let original = |polygon: &MeshPolygon, k: usize| {
        let n = polygon.original_len();
        polygon.corners[polygon.originals[k % n] as usize]
    };
    // The one polygon using each original directed edge, or SHARED.
    owners.clear();
    owners.reserve(polygons.len() * 5);
    for (f, polygon) in polygons.iter().enumerate() {
        for k in 0..polygon.original_len() {
            let key = edge_key(original(polygon, k), original(polygon, k + 1));
            owners
                .entry(key)
                .and_modify(|owner| *owner = SHARED)
                .or_insert(f as u32);
        }
    }
    whole.clear();
    for polygon in polygons {
        for k in 0..polygon.original_len() {
            let (a, b) = (original(polygon, k), original(polygon, k + 1));
            let opposite = match (owners.get(&edge_key(a, b)), owners.get(&edge_key(b, a))) {
                (Some(&own), Some(&other)) if own != SHARED && other != SHARED => {
                    Some(&polygons[other as usize])
                }
                _ => None,
            };
            whole.push(opposite.is_some_and(|o| {
                (o.label, o.outside, o.on_bounds)
                    == (polygon.label, polygon.outside, polygon.on_bounds)
            }));
        }
    }
}

/// Clears `whole` (per original edge, as [`matched_whole`] fills it) for
/// every edge whose two ends share a wall bit in `walls`.
fn unmatch_wall_edges(polygons: &[MeshPolygon], walls: &[u8], whole: &mut [bool]) {
    let wall = |v: u32| walls.get(v as usize).copied().unwrap_or(0);
    let mut edge = 0;
    for polygon in polygons {
        let n = polygon.original_len();
        for k in 0..n {
            let a = polygon.corners[polygon.originals[k] as usize];
            let b = polygon.corners[polygon.originals[(k + 1) % n] as usize];
            if wall(a) & wall(b) != 0 {
                whole[edge] = false;
            }
            edge += 1;
        }
    }
}

/// Whether `w` lies strictly inside original edge `k` of `polygon`, exactly
/// (the test in the module docs; cheap rejections first).
#[must_use]
pub(crate) fn strictly_inside_edge(w: &Point4, polygon: &MeshPolygon, k: usize) -> bool {
    let n = polygon.edges.len();
    classify_vertex(w, &polygon.edges[(k + n - 1) % n]) == Sign::Negative
        && classify_vertex(w, &polygon.edges[(k + 1) % n]) == Sign::Negative
        && classify_vertex(w, &polygon.edges[k]) == Sign::Zero
        && classify_vertex(w, &polygon.plane) == Sign::Zero
}

/// A segment `a b` with what [`Segment::may_hold`] needs, computed once
/// per edge.
struct Segment {
    /// The segment's box, widened by the slack.
    lo: [f64; 3],
    hi: [f64; 3],
    a: [f64; 3],
    /// `b − a`.
    u: [f64; 3],
    /// `slack² · |u|²`.
    bound: f64,
}

impl Segment {
    /// The segment `a b`, tested with twice the grid's `tolerance` as
    /// slack.
    #[inline]
    fn new(a: [f64; 3], b: [f64; 3], tolerance: f64) -> Self {
        let slack = 2.0 * tolerance;
        let u = [0, 1, 2].map(|i| b[i] - a[i]);
        let length2: f64 = u.iter().map(|c| c * c).sum();
        Self {
            lo: [0, 1, 2].map(|i| a[i].min(b[i]) - slack),
            hi: [0, 1, 2].map(|i| a[i].max(b[i]) + slack),
            a,
            u,
            bound: slack * slack * length2,
        }
    }

    /// False only when `p` is certainly off the segment: outside its box,
    /// or farther from its line than the tolerance (twice over). The
    /// rounding of the positions and of this arithmetic is below `2^-48`
    /// of the magnitude, far inside the tolerance of `2^-40`, so a vertex
    /// exactly on the segment always passes.
    #[inline]
    fn may_hold(&self, p: [f64; 3]) -> bool {
        if (0..3).any(|i| p[i] < self.lo[i] || p[i] > self.hi[i]) {
            return false;
        }
        let (a, u) = (self.a, self.u);
        let v = [0, 1, 2].map(|i| p[i] - a[i]);
        let cross = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let cross2: f64 = cross.iter().map(|c| c * c).sum();
        cross2 <= self.bound
    }
}

/// Up to this many vertices, the candidates of an edge are the vertices
/// within its widened box along x (tested with [`Segment::may_hold`]):
/// cheaper than building a grid and walking its cells, as for the surface
/// of one octree cell.
const SCAN_MAX: usize = 64;

/// A dense uniform grid of vertex indices by `f64` position: the vertices
/// of cell `c` are `items[start[c]..start[c + 1]]` (for few vertices none
/// are stored, and every vertex is a candidate).
struct Grid {
    origin: [f64; 3],
    cell: f64,
    dims: [usize; 3],
    tolerance: f64,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    /// The grid of `positions`, holding none (every vertex a candidate)
    /// up to `scan_max` of them.
    fn new(positions: &[[f64; 3]], scan_max: usize) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in positions {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        if positions.is_empty() {
            (lo, hi) = ([0.0; 3], [0.0; 3]);
        }
        let magnitude = (0..3)
            .map(|i| lo[i].abs().max(hi[i].abs()))
            .fold(0.0, f64::max);
        let tolerance = magnitude * f64::powi(2.0, -40) + f64::MIN_POSITIVE;
        if positions.len() <= scan_max {
            // No cells: their size is never asked for.
            return Self {
                origin: lo,
                cell: 0.0,
                dims: [0; 3],
                tolerance,
                start: Vec::new(),
                items: Vec::new(),
            };
        }
        let extent = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
        let per_axis = (2.0 * (positions.len() as f64).cbrt())
            .ceil()
            .clamp(1.0, 1024.0);
        // Cells no finer than the tolerance, so stepping stays bounded.
        let cell = (extent / per_axis).max(tolerance * 1024.0);
        let dims = [0, 1, 2].map(|i| (((hi[i] - lo[i]) / cell).floor() as usize + 1).min(1025));
        let mut grid = Self {
            origin: lo,
            cell,
            dims,
            tolerance,
            start: vec![0; dims[0] * dims[1] * dims[2] + 1],
            items: vec![0; positions.len()],
        };
        let cells: Vec<usize> = positions.iter().map(|&p| grid.index(grid.key(p))).collect();
        for &c in &cells {
            grid.start[c + 1] += 1;
        }
        for c in 0..grid.start.len() - 1 {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill = grid.start.clone();
        for (v, &c) in cells.iter().enumerate() {
            grid.items[fill[c] as usize] = v as u32;
            fill[c] += 1;
        }
        grid
    }

    /// Whether the grid holds the vertices in cells: else every vertex is
    /// a candidate of every edge (few vertices).
    #[inline]
    fn is_dense(&self) -> bool {
        !self.start.is_empty()
    }

    /// The cell of `p`, clamped into the grid (a superset for queries).
    /// The saturating cast truncates, which is the floor for the positive
    /// values it keeps, and gives 0 below 1 and for NaN.
    #[inline]
    fn key(&self, p: [f64; 3]) -> [usize; 3] {
        let axis =
            |i: usize| (((p[i] - self.origin[i]) / self.cell) as usize).min(self.dims[i] - 1);
        [axis(0), axis(1), axis(2)]
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// Appends every vertex whose position lies in a cell near the segment
    /// `a b`, once (`seen[v] == mark` after it is appended).
    fn near_segment(
        &self,
        a: [f64; 3],
        b: [f64; 3],
        mark: u64,
        seen: &mut [u64],
        out: &mut Vec<u32>,
    ) {
        let length = (0..3).map(|i| (b[i] - a[i]).abs()).fold(0.0, f64::max);
        let steps = (length / self.cell).ceil().clamp(1.0, 4096.0) as usize;
        let point = |t: f64| [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t);
        for s in 0..steps {
            let (p, q) = (
                point(s as f64 / steps as f64),
                point((s + 1) as f64 / steps as f64),
            );
            let lo = self.key([0, 1, 2].map(|i| p[i].min(q[i]) - self.tolerance));
            let hi = self.key([0, 1, 2].map(|i| p[i].max(q[i]) + self.tolerance));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let c = self.index([x, y, z]);
                        for &v in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                            if seen[v as usize] != mark {
                                seen[v as usize] = mark;
                                out.push(v);
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::convex::ConvexArena;
    use crate::exact::IntPoint;
    use crate::mesh::SurfaceMesh;
    use crate::tree::{BooleanOp, Bsp};

    fn point(c: [i64; 3]) -> IntPoint {
        IntPoint::from_array(c).expect("in budget")
    }

    /// A box of random size and place inside `[-24, 24]³`, of `label`.
    fn random_box(rng: &mut ChaCha8Rng, label: u8) -> Bsp {
        let lo = [0; 3].map(|_| rng.random_range(-24..12));
        let hi = lo.map(|l| l + rng.random_range(2..12));
        let mut arena = ConvexArena::new();
        let poly = arena.add_box(point(lo), point(hi)).expect("in budget");
        Bsp::from_convex(&arena, poly, label)
    }

    /// Unions and differences of boxes (faces meeting in T-junctions), cut
    /// by random bounds so that the meshes are open and small or large:
    /// scanning every vertex and walking the grid insert exactly the same
    /// corners, and corners are inserted.
    #[test]
    fn scanning_every_vertex_finds_what_the_grid_finds() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (mut inserted, mut small) = (0, 0);
        for _ in 0..60 {
            let mut bsp = random_box(&mut rng, 1);
            for i in 0..rng.random_range(1..8) {
                let op = if i % 3 == 2 {
                    BooleanOp::Difference
                } else {
                    BooleanOp::Union
                };
                let label = rng.random_range(1..3);
                let other = random_box(&mut rng, label);
                let mut arena = ConvexArena::new();
                let bounds = arena.add_box(point([-32; 3]), point([32; 3])).unwrap();
                bsp = bsp.merge(&other, op, &mut arena, bounds);
            }
            let lo = [0; 3].map(|_| rng.random_range(-30..0));
            let hi = lo.map(|l| l + rng.random_range(8..40));
            let mut arena = ConvexArena::new();
            let bounds = arena.add_box(point(lo), point(hi)).unwrap();
            let faces = bsp.boundary(&mut arena, bounds);
            if faces.is_empty() {
                continue;
            }
            let mut mesh = SurfaceMesh::welded(&faces);
            mesh.merge_coplanar();
            small += usize::from(mesh.vertices.len() <= SCAN_MAX);
            let mut scanned = mesh.polygons.clone();
            let mut gridded = mesh.polygons.clone();
            split_with(&mesh.vertices, &mut scanned, usize::MAX, &[]);
            split_with(&mesh.vertices, &mut gridded, 0, &[]);
            assert_eq!(scanned, gridded);
            inserted += scanned
                .iter()
                .map(|p| p.corners.len() - p.original_len())
                .sum::<usize>();
        }
        assert!(inserted > 20, "only {inserted} corners inserted");
        assert!(small > 5, "only {small} meshes of few vertices");
    }
}
