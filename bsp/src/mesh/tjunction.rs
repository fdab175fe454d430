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
//! # Candidates
//!
//! A uniform grid over the `f64` positions of the vertices, about `√V`
//! cells per axis (a surface of `V` vertices then has about one per
//! occupied cell). Each edge visits the cells near it in steps of at most
//! one cell, every step's box widened by a tolerance far above the rounding
//! of the positions (each within `2^-51` relative, see [`super::weld`]), so
//! a vertex exactly on the segment is always found; the exact test decides.

use std::collections::HashMap;

use super::MeshPolygon;
use crate::exact::{Point4, Sign, classify_vertex, compare_offsets};

/// Inserts every T-junction into every polygon (see the module docs).
pub(crate) fn split(vertices: &[Point4], polygons: &mut [MeshPolygon]) {
    let positions: Vec<[f64; 3]> = vertices.iter().map(Point4::to_f64).collect();
    let grid = Grid::new(&positions);
    let mut candidates = Vec::new();
    let mut inside = Vec::new();
    for polygon in polygons.iter_mut() {
        let n = polygon.original_len();
        let originals: Vec<u32> = polygon
            .originals
            .iter()
            .map(|&o| polygon.corners[o as usize])
            .collect();
        let mut corners = Vec::with_capacity(n);
        let mut positions_of_originals = Vec::with_capacity(n);
        for k in 0..n {
            let (a, b) = (originals[k], originals[(k + 1) % n]);
            positions_of_originals.push(corners.len() as u32);
            corners.push(a);
            candidates.clear();
            grid.near_segment(
                positions[a as usize],
                positions[b as usize],
                &mut candidates,
            );
            inside.clear();
            inside.extend(
                candidates
                    .iter()
                    .copied()
                    .filter(|&w| w != a && w != b)
                    .filter(|&w| strictly_inside_edge(&vertices[w as usize], polygon, k)),
            );
            let previous = polygon.edges[(k + n - 1) % n];
            inside.sort_by(|&p, &q| {
                compare_offsets(&vertices[q as usize], &vertices[p as usize], &previous)
            });
            corners.extend_from_slice(&inside);
        }
        polygon.corners = corners;
        polygon.originals = positions_of_originals;
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

/// A uniform grid of vertex indices by `f64` position.
struct Grid {
    origin: [f64; 3],
    cell: f64,
    tolerance: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    fn new(positions: &[[f64; 3]]) -> Self {
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
        let extent = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f64::max);
        let magnitude = (0..3)
            .map(|i| lo[i].abs().max(hi[i].abs()))
            .fold(0.0, f64::max);
        let per_axis = (positions.len() as f64).sqrt().ceil().clamp(1.0, 4096.0);
        // Cells no finer than the tolerance, so stepping stays bounded.
        let tolerance = magnitude * f64::powi(2.0, -40) + f64::MIN_POSITIVE;
        let cell = (extent / per_axis).max(tolerance * 1024.0);
        let mut grid = Self {
            origin: lo,
            cell,
            tolerance,
            cells: HashMap::with_capacity(positions.len()),
        };
        for (i, &p) in positions.iter().enumerate() {
            let key = grid.key(p);
            grid.cells.entry(key).or_default().push(i as u32);
        }
        grid
    }

    fn key(&self, p: [f64; 3]) -> [i64; 3] {
        [0, 1, 2].map(|i| ((p[i] - self.origin[i]) / self.cell).floor() as i64)
    }

    /// Appends (sorted, without repeats) every vertex whose position lies in
    /// a cell near the segment `a b`.
    fn near_segment(&self, a: [f64; 3], b: [f64; 3], out: &mut Vec<u32>) {
        let length = (0..3).map(|i| (b[i] - a[i]).abs()).fold(0.0, f64::max);
        let steps = (length / self.cell).ceil().clamp(1.0, 1e6) as usize;
        let point = |t: f64| [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t);
        let mut keys: Vec<[i64; 3]> = Vec::new();
        for s in 0..steps {
            let (p, q) = (
                point(s as f64 / steps as f64),
                point((s + 1) as f64 / steps as f64),
            );
            let lo = self.key([0, 1, 2].map(|i| p[i].min(q[i]) - self.tolerance));
            let hi = self.key([0, 1, 2].map(|i| p[i].max(q[i]) + self.tolerance));
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        keys.push([x, y, z]);
                    }
                }
            }
        }
        keys.sort_unstable();
        keys.dedup();
        for key in &keys {
            if let Some(list) = self.cells.get(key) {
                out.extend_from_slice(list);
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}
