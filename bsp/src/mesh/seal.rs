//! Meshes sealed against their neighbours (paper 1 §3.4, T-junction
//! removal carried across octree cells).
//!
//! Notation: a *wall* is one of up to eight planes bounding the region a
//! mesh is built in (the six faces of an octree cell's box); a *wall
//! vertex* lies on a wall; a *border edge* is an original edge whose two
//! ends lie on a common wall; *extra points* are exact points handed in
//! from outside (the wall vertices of the neighbouring meshes); *seam
//! points* are the extra points that become corners.
//!
//! # Why border edges suffice
//!
//! The region is a closed convex box and the extra points lie on its
//! boundary. A point strictly inside an edge `ab` of the mesh that lies on
//! a wall `W` (with the box on one side of `W`, and `a`, `b` in the box)
//! forces `a` and `b` onto `W` too: otherwise the segment would cross `W`.
//! So only border edges can hold an extra point, and the seam points are
//! exactly the extra points strictly inside a border edge.
//!
//! # Why border edges are never matched whole
//!
//! Within one mesh, an edge used once in each direction by polygons of
//! the same materials is left unsplit ([`super::tjunction`]): both sides
//! would get the same corners. A border edge may still hold a vertex of a
//! neighbouring mesh (two solids touching along it), so it is always
//! split, at its own vertices and the extra points alike; both polygons
//! at it get the same corners, so the mesh stays as closed as it was.
//!
//! When every mesh is split at the wall vertices of every mesh whose
//! region touches its own (vertices before splitting: the seam points are
//! another mesh's own wall vertices, found directly there), no vertex of
//! one mesh lies strictly inside an edge of another, and neighbouring
//! meshes meet edge to edge with identical exact vertices.

use super::SurfaceMesh;
use super::weld::Welder;
use crate::exact::{Plane, Point4, Sign, classify_vertex};
use crate::tree::BoundaryFace;

/// Most walls one mesh can have (one bit each in a `u8`).
pub const MAX_WALLS: usize = 8;

/// An original edge lying on a wall, as the planes that decide whether a
/// point lies strictly inside it (see [`super::tjunction`]): the face's
/// support `s`, the edge's own plane `e_k` and the planes of the edges
/// before and after it, `e_{k−1}` and `e_{k+1}`; and a box in `f64` that
/// holds every such point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BorderEdge {
    /// The face's support plane `s`.
    pub support: Plane,
    /// The edge's plane `e_k`.
    pub edge: Plane,
    /// The plane of the edge before, `e_{k−1}`.
    pub previous: Plane,
    /// The plane of the edge after, `e_{k+1}`.
    pub next: Plane,
    /// The box of the edge's ends in `f64`, widened by far more than the
    /// rounding of exact positions (`2^-40` of the largest coordinate,
    /// against under `2^-51` relative).
    pub span: ([f64; 3], [f64; 3]),
}

impl BorderEdge {
    /// Whether the `f64` position `q` of a point (within `2^-51` relative)
    /// may lie strictly inside the edge: false only when it certainly
    /// does not.
    #[must_use]
    #[inline]
    pub fn may_hold(&self, q: [f64; 3]) -> bool {
        let (lo, hi) = &self.span;
        (0..3).all(|a| lo[a] <= q[a] && q[a] <= hi[a])
    }

    /// Whether `w` lies strictly inside the edge, exactly (cheap
    /// rejections first).
    #[must_use]
    pub fn holds_strictly(&self, w: &Point4) -> bool {
        self.may_hold(w.to_f64())
            && classify_vertex(w, &self.previous) == Sign::Negative
            && classify_vertex(w, &self.next) == Sign::Negative
            && classify_vertex(w, &self.edge) == Sign::Zero
            && classify_vertex(w, &self.support) == Sign::Zero
    }
}

/// A mesh welded and merged but not yet split at T-junctions, with the
/// walls each vertex lies on: what [`UnsealedMesh::seal`] needs, and what
/// the neighbouring meshes need from it ([`UnsealedMesh::wall_vertices`]).
#[derive(Clone, Debug)]
pub struct UnsealedMesh {
    mesh: SurfaceMesh,
    /// Per vertex, one bit per wall it lies on.
    walls: Vec<u8>,
}

impl UnsealedMesh {
    /// The faces welded exactly and merged ([`SurfaceMesh::merge_coplanar`]),
    /// with the walls of every vertex found exactly.
    ///
    /// # Panics
    /// As [`SurfaceMesh::from_faces`], or with more than [`MAX_WALLS`]
    /// walls.
    #[must_use]
    pub fn new(faces: Vec<BoundaryFace>, walls: &[Plane]) -> Self {
        assert!(walls.len() <= MAX_WALLS, "{} walls", walls.len());
        let mut mesh = SurfaceMesh::welded_owned(faces);
        mesh.merge_coplanar();
        let walls = mesh
            .vertices
            .iter()
            .map(|v| {
                walls.iter().enumerate().fold(0u8, |mask, (i, wall)| {
                    if classify_vertex(v, wall) == Sign::Zero {
                        mask | 1 << i
                    } else {
                        mask
                    }
                })
            })
            .collect();
        Self { mesh, walls }
    }

    /// The vertices lying on a wall, in vertex order: what every
    /// neighbouring mesh is split at.
    pub fn wall_vertices(&self) -> impl Iterator<Item = &Point4> + '_ {
        self.mesh
            .vertices
            .iter()
            .zip(&self.walls)
            .filter(|&(_, &w)| w != 0)
            .map(|(v, _)| v)
    }

    /// The numbers of the vertices lying on a wall, in vertex order (those
    /// of [`Self::wall_vertices`]); a sealed mesh keeps them.
    #[must_use]
    pub fn wall_vertex_indices(&self) -> Vec<u32> {
        (0..self.walls.len() as u32)
            .filter(|&v| self.walls[v as usize] != 0)
            .collect()
    }

    /// Number of vertices: those of the sealed mesh from here on are seam
    /// points ([`Self::seal`]).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.mesh.vertices.len()
    }

    /// The original edges whose two ends lie on a common wall, polygon by
    /// polygon, edge by edge.
    #[must_use]
    pub fn border_edges(&self) -> Vec<BorderEdge> {
        Self::border_edges_of(&self.mesh, &self.walls)
    }

    /// [`Self::border_edges`] of `mesh` with vertex walls `walls`.
    fn border_edges_of(mesh: &SurfaceMesh, walls: &[u8]) -> Vec<BorderEdge> {
        let mut out = Vec::new();
        for polygon in &mesh.polygons {
            let n = polygon.original_len();
            let corner = |k: usize| polygon.corners[polygon.originals[k % n] as usize];
            for k in 0..n {
                let (a, b) = (corner(k), corner(k + 1));
                if walls[a as usize] & walls[b as usize] != 0 {
                    out.push(BorderEdge {
                        support: polygon.plane,
                        edge: polygon.edges[k],
                        previous: polygon.edges[(k + n - 1) % n],
                        next: polygon.edges[(k + 1) % n],
                        span: span(mesh.position(a), mesh.position(b)),
                    });
                }
            }
        }
        out
    }

    /// The polygons lying in a wall (every corner on it), each as the
    /// wall's index and the `f64` box of its corners.
    #[must_use]
    pub fn wall_polygons(&self) -> Vec<(usize, [f64; 3], [f64; 3])> {
        let mut out = Vec::new();
        for polygon in &self.mesh.polygons {
            let common = polygon
                .corners
                .iter()
                .fold(u8::MAX, |m, &c| m & self.walls[c as usize]);
            if common == 0 {
                continue;
            }
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &c in &polygon.corners {
                let p = self.mesh.position(c);
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            out.push((common.trailing_zeros() as usize, lo, hi));
        }
        out
    }

    /// Whether the mesh has no polygon.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.mesh.polygons.is_empty()
    }

    /// The mesh with every T-junction removed ([`SurfaceMesh::split_t_junctions`],
    /// border edges never matched whole) and every border edge also split
    /// at each point of `extra` strictly inside it; the extra points that
    /// became no corner are dropped again. Also hands back the seam
    /// points: the extra points that became corners and are no vertex of
    /// the mesh's own, once each, in order of first appearance in `extra`.
    #[must_use]
    pub fn seal<'a>(
        self,
        extra: impl IntoIterator<Item = &'a Point4>,
    ) -> (SurfaceMesh, Vec<Point4>) {
        let edges = self.border_edges();
        self.seal_with_edges(extra, &edges)
    }

    /// [`Self::seal`] with the mesh's border edges `edges` already at
    /// hand: they must be [`Self::border_edges`] (checked in debug
    /// builds).
    #[must_use]
    pub fn seal_with_edges<'a>(
        self,
        extra: impl IntoIterator<Item = &'a Point4>,
        edges: &[BorderEdge],
    ) -> (SurfaceMesh, Vec<Point4>) {
        debug_assert!(
            edges == self.border_edges().as_slice(),
            "the border edges handed in are not this mesh's"
        );
        let Self { mut mesh, walls } = self;
        if mesh.polygons.is_empty() {
            return (mesh, Vec::new());
        }
        let own = mesh.vertices.len();
        let extra: Vec<&Point4> = extra
            .into_iter()
            .filter(|p| {
                let q = p.to_f64();
                edges.iter().any(|e| e.may_hold(q))
            })
            .collect();
        if !extra.is_empty() {
            // The mesh's vertices are welded, so distinct.
            let vertices = std::mem::take(&mut mesh.vertices);
            let mut welder = Welder::from_distinct(vertices, extra.len());
            for p in extra {
                welder.index(p);
            }
            mesh.vertices = welder.into_vertices();
        }
        super::tjunction::split_sealed(&mesh.vertices, &mut mesh.polygons, &walls);
        let mut used = vec![false; mesh.vertices.len() - own];
        for polygon in &mesh.polygons {
            for &c in &polygon.corners {
                if let Some(u) = (c as usize).checked_sub(own) {
                    used[u] = true;
                }
            }
        }
        let seams = mesh.vertices[own..]
            .iter()
            .zip(&used)
            .filter(|&(_, &u)| u)
            .map(|(v, _)| *v)
            .collect();
        mesh.drop_unused_vertices();
        (mesh, seams)
    }
}

/// The box of the segment `p q`, widened by `2^-40` of its largest
/// coordinate: far more than the rounding of exact positions.
fn span(p: [f64; 3], q: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let slack = (0..3)
        .map(|i| p[i].abs().max(q[i].abs()))
        .fold(f64::MIN_POSITIVE, f64::max)
        * f64::powi(2.0, -40);
    (
        [0, 1, 2].map(|i| p[i].min(q[i]) - slack),
        [0, 1, 2].map(|i| p[i].max(q[i]) + slack),
    )
}

impl SurfaceMesh {
    /// As [`SurfaceMesh::from_face_vec`], for a mesh whose region is
    /// bounded by `walls` (a cell's six box planes): no border edge is
    /// matched whole, and every border edge is also split at each point of
    /// `extra` strictly inside it (the wall vertices of the neighbouring
    /// meshes, [`UnsealedMesh::wall_vertices`]). See the module docs.
    ///
    /// # Panics
    /// As [`UnsealedMesh::new`].
    #[must_use]
    pub fn from_face_vec_sealed(
        faces: Vec<BoundaryFace>,
        walls: &[Plane],
        extra: &[Point4],
    ) -> Self {
        UnsealedMesh::new(faces, walls).seal(extra).0
    }

    /// The meshes as one: their vertices welded exactly, their polygons
    /// one after the other, nothing split. For checks of meshes built
    /// apart (sealed cell meshes should together be closed) and for export.
    #[must_use]
    pub fn welded_union<'a>(meshes: impl IntoIterator<Item = &'a SurfaceMesh>) -> Self {
        let mut welder = Welder::with_capacity(0);
        let mut polygons = Vec::new();
        for mesh in meshes {
            let index: Vec<u32> = mesh.vertices.iter().map(|v| welder.index(v)).collect();
            polygons.extend(mesh.polygons.iter().map(|p| {
                let mut p = p.clone();
                for c in &mut p.corners {
                    *c = index[*c as usize];
                }
                p
            }));
        }
        Self {
            vertices: welder.into_vertices(),
            polygons,
        }
    }
}
