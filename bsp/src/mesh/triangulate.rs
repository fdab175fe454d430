//! Polygons to triangles, and the `f32` output meshes.
//!
//! Notation: a polygon of the [`SurfaceMesh`] is strictly convex in its
//! original corners `C_0 … C_{n−1}`, with extra *inserted* corners (valence
//! 2, from T-junctions) strictly inside some original edges. Three distinct
//! boundary points of a strictly convex polygon are collinear exactly when
//! they lie on one original edge (a line meets the boundary in at most two
//! points unless it contains an edge), so a triangle of corners is
//! degenerate exactly when its three corners share an original edge: an
//! original corner `C_k` lies on edges `k − 1` and `k`, an inserted corner
//! on its edge only. This is decided by indices alone, no arithmetic.
//!
//! # The triangulation
//!
//! 1. Fan from the original corner `C_a` whose two edges carry the fewest
//!    inserted corners: triangles `(C_a, C_{a+j}, C_{a+j+1})`, each side an
//!    original edge (with its inserted corners) or a diagonal (none).
//! 2. While a triangle has a corner `P` inserted strictly inside one of its
//!    sides `v_j v_{j+1}`, split it by the segment from `P` to the opposite
//!    corner `v_{j+2}` into `(v_j, P, v_{j+2})` and `(P, v_{j+1}, v_{j+2})`.
//!    Both are non-degenerate (`P` is strictly between `v_j` and `v_{j+1}`,
//!    and `v_{j+2}` is off their line), keep the orientation, and the new
//!    side `P v_{j+2}` is a diagonal without inserted corners.
//!
//! Every corner of the polygon is used (so the triangle mesh keeps the
//! watertightness of the polygon mesh), no Steiner point is added, a
//! polygon of `m` corners gives `m − 2` triangles, and none has zero area.

use super::{MeshPolygon, SurfaceMesh};
use crate::tree::{EMPTY, Label};

/// A surface as `f32` triangles over shared vertices, with one exact face
/// normal and the materials per triangle. Built by
/// [`SurfaceMesh::triangles`]; filter with [`TriangleMesh::filtered`] or
/// [`TriangleMesh::without_interfaces`], and duplicate vertices for flat
/// shading with [`TriangleMesh::flat_shaded`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions (the nearest `f32` of each `f64` coordinate).
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub indices: Vec<[u32; 3]>,
    /// Per triangle: the unit normal of its polygon's exact plane, pointing
    /// outside.
    pub normals: Vec<[f32; 3]>,
    /// Per triangle: the material behind it.
    pub labels: Vec<Label>,
    /// Per triangle: the material in front of it ([`EMPTY`] except on
    /// interfaces between two materials).
    pub outside: Vec<Label>,
    /// Per triangle: whether it lies on the bounds of the extraction.
    pub on_bounds: Vec<bool>,
    /// Per triangle: the index of its polygon in the [`SurfaceMesh`] it
    /// came from.
    pub polygons: Vec<u32>,
}

/// Triangles with their own three vertices each, for flat-shaded
/// rendering: triangle `t` is vertices `3t, 3t + 1, 3t + 2`, and each of
/// them carries the triangle's face normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatShadedMesh {
    /// Vertex positions, three per triangle.
    pub positions: Vec<[f32; 3]>,
    /// Vertex normals (the face normal of the vertex's triangle).
    pub normals: Vec<[f32; 3]>,
    /// Per triangle: the material behind it.
    pub labels: Vec<Label>,
}

impl MeshPolygon {
    /// The polygon's triangles as vertex indices (see the module docs):
    /// `corners.len() − 2` of them, counter-clockwise, none degenerate,
    /// using every corner.
    ///
    /// # Panics
    /// When `originals` does not fit `corners` (see the invariants on
    /// [`MeshPolygon`]; polygons of a [`SurfaceMesh`] always fit).
    #[must_use]
    pub fn triangulate(&self) -> Vec<[u32; 3]> {
        let mut out = Vec::with_capacity(self.corners.len().saturating_sub(2));
        self.triangulate_into(&mut out, &mut Vec::new());
        out
    }

    /// [`Self::triangulate`], appending the triangles to `out`; `stack` is
    /// working memory (left empty).
    fn triangulate_into(&self, out: &mut Vec<[u32; 3]>, stack: &mut Vec<Pending>) {
        let n = self.original_len();
        if n < 3 {
            return;
        }
        let inserted = |k: usize| self.inserted_on_edge(k % n);
        let apex = (0..n)
            .min_by_key(|&a| inserted(a).len() + inserted(a + n - 1).len())
            .unwrap_or(0);
        let corner = |k: usize| self.corners[self.originals[k % n] as usize];
        let none = 0..0;
        stack.clear();
        stack.extend((1..n - 1).rev().map(|j| Pending {
            corners: [corner(apex), corner(apex + j), corner(apex + j + 1)],
            sides: [
                if j == 1 { inserted(apex) } else { none.clone() },
                inserted(apex + j),
                if j == n - 2 {
                    inserted(apex + n - 1)
                } else {
                    none.clone()
                },
            ],
        }));
        while let Some(t) = stack.pop() {
            let Some(j) = (0..3).find(|&j| !t.sides[j].is_empty()) else {
                out.push(t.corners);
                continue;
            };
            let side = t.sides[j].clone();
            let middle = side.start + side.len() / 2;
            let p = self.corners[middle];
            let [vj, vn, vo] = [t.corners[j], t.corners[(j + 1) % 3], t.corners[(j + 2) % 3]];
            let [sn, so] = [t.sides[(j + 1) % 3].clone(), t.sides[(j + 2) % 3].clone()];
            stack.push(Pending {
                corners: [p, vn, vo],
                sides: [middle + 1..side.end, sn, none.clone()],
            });
            stack.push(Pending {
                corners: [vj, p, vo],
                sides: [side.start..middle, none.clone(), so],
            });
        }
    }

    /// The unit outward normal of the exact plane, in `f64`.
    #[must_use]
    pub fn unit_normal(&self) -> [f64; 3] {
        let n = self.plane.normal().map(|c| c as f64);
        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        n.map(|c| c / length)
    }
}

/// A triangle still to be split: corners and, per side `j` (from corner `j`
/// to `j + 1`), the positions in the polygon's corners of the corners
/// inserted strictly inside it, in order.
struct Pending {
    corners: [u32; 3],
    sides: [core::ops::Range<usize>; 3],
}

impl SurfaceMesh {
    /// All polygons as `f32` triangles: `positions[i]` is vertex `i` of
    /// [`SurfaceMesh::vertices`] (so indices are vertex indices), and per
    /// triangle the exact face normal, materials and source polygon.
    #[must_use]
    pub fn triangles(&self) -> TriangleMesh {
        let mut mesh = TriangleMesh {
            positions: self
                .vertices()
                .iter()
                .map(|v| v.to_f64().map(|c| c as f32))
                .collect(),
            ..TriangleMesh::default()
        };
        // A polygon of m corners gives m − 2 triangles.
        let triangles: usize = self
            .polygons()
            .iter()
            .map(|p| p.corners.len().saturating_sub(2))
            .sum();
        mesh.indices.reserve_exact(triangles);
        mesh.normals.reserve_exact(triangles);
        mesh.labels.reserve_exact(triangles);
        mesh.outside.reserve_exact(triangles);
        mesh.on_bounds.reserve_exact(triangles);
        mesh.polygons.reserve_exact(triangles);
        let mut stack = Vec::new();
        for (f, polygon) in self.polygons().iter().enumerate() {
            let start = mesh.indices.len();
            polygon.triangulate_into(&mut mesh.indices, &mut stack);
            let count = mesh.indices.len() - start;
            let normal = polygon.unit_normal().map(|c| c as f32);
            mesh.normals.extend(core::iter::repeat_n(normal, count));
            mesh.labels
                .extend(core::iter::repeat_n(polygon.label, count));
            mesh.outside
                .extend(core::iter::repeat_n(polygon.outside, count));
            mesh.on_bounds
                .extend(core::iter::repeat_n(polygon.on_bounds, count));
            mesh.polygons.extend(core::iter::repeat_n(f as u32, count));
        }
        mesh
    }
}

impl TriangleMesh {
    /// Number of triangles.
    #[must_use]
    #[inline]
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether there are no triangles.
    #[must_use]
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The triangles `t` for which `keep(t)` is true, with the vertices
    /// they use (renumbered in order of first use).
    #[must_use]
    pub fn filtered(&self, mut keep: impl FnMut(usize) -> bool) -> TriangleMesh {
        let mut out = TriangleMesh::default();
        let mut remap = vec![u32::MAX; self.positions.len()];
        for t in 0..self.len() {
            if !keep(t) {
                continue;
            }
            let triangle = self.indices[t].map(|v| {
                let slot = &mut remap[v as usize];
                if *slot == u32::MAX {
                    *slot = out.positions.len() as u32;
                    out.positions.push(self.positions[v as usize]);
                }
                *slot
            });
            out.indices.push(triangle);
            out.normals.push(self.normals[t]);
            out.labels.push(self.labels[t]);
            out.outside.push(self.outside[t]);
            out.on_bounds.push(self.on_bounds[t]);
            out.polygons.push(self.polygons[t]);
        }
        out
    }

    /// The visible surface: triangles in front of empty space only (material
    /// interfaces dropped; faces on the bounds kept, see
    /// [`TriangleMesh::on_bounds`]).
    #[must_use]
    pub fn without_interfaces(&self) -> TriangleMesh {
        self.filtered(|t| self.outside[t] == EMPTY)
    }

    /// The triangles with their vertices duplicated, each carrying its
    /// triangle's normal (for rendering with flat shading).
    #[must_use]
    pub fn flat_shaded(&self) -> FlatShadedMesh {
        let mut out = FlatShadedMesh {
            positions: Vec::with_capacity(3 * self.len()),
            normals: Vec::with_capacity(3 * self.len()),
            labels: self.labels.clone(),
        };
        for (triangle, normal) in self.indices.iter().zip(&self.normals) {
            for &v in triangle {
                out.positions.push(self.positions[v as usize]);
                out.normals.push(*normal);
            }
        }
        out
    }
}

impl FlatShadedMesh {
    /// Number of triangles.
    #[must_use]
    #[inline]
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Whether there are no triangles.
    #[must_use]
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }
}
