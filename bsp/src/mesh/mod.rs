//! Exact surface meshes from boundary faces (paper 1 §3.4, T-junction
//! removal), and their triangulation to floats for rendering and export.
//!
//! Notation:
//!
//! - a *face* is one [`BoundaryFace`]: support plane `s` (outward), edge
//!   planes `e_0 … e_{n−1}` and exact corners `c_0 … c_{n−1}`, where
//!   `c_k = s ∩ e_{k−1} ∩ e_k` and *edge* `k` is the segment `c_k c_{k+1}`
//!   on the line `s ∩ e_k`;
//! - a *vertex* is one welded point of the [`SurfaceMesh`], named by its
//!   index `u32`; equal exact points are one vertex;
//! - a *T-junction* is a vertex strictly inside an edge of a face that does
//!   not have it as a corner. Faces from different BSP cells (or octree
//!   cells) meet along edges that are cut differently on each side, so the
//!   assembled surface has T-junctions; §3.4 removes them by inserting
//!   valence-2 corners: a rectangle with one T-junction becomes a pentagon.
//!
//! Every decision is exact: welding by [`Point4::same_position`], T-junctions
//! by [`classify_vertex`](crate::exact::classify_vertex) against the face's
//! own planes, their order along an edge by
//! [`compare_offsets`](crate::exact::compare_offsets). Floats only find
//! candidates (a hash of rounded positions, a uniform grid) and make the
//! output ([`TriangleMesh`]).
//!
//! - [`weld`] — equal exact vertices become one index.
//! - `merge` — coplanar fragments with a whole common edge and a convex
//!   union become one polygon ([`SurfaceMesh::merge_coplanar`]).
//! - [`tjunction`] — every vertex strictly inside an edge is inserted there.
//! - [`seal`] — meshes of neighbouring regions (octree cells) split at each
//!   other's wall vertices, so that they meet edge to edge.
//! - [`watertight`] — every directed edge has exactly one opposite.
//! - [`validate`] — the invariants of a [`SurfaceMesh`], checked exactly.
//! - [`wedge`] — the surface around each vertex as exact wedges, for
//!   smooth normals that do not depend on how the surface is split.
//! - [`triangulate`] — polygons to triangles with no zero-area triangle, and
//!   `f32` output with exact face normals and per-face materials.
//!
//! # Example
//!
//! ```
//! use chisel_bsp::convex::ConvexArena;
//! use chisel_bsp::exact::IntPoint;
//! use chisel_bsp::mesh::SurfaceMesh;
//! use chisel_bsp::tree::{BooleanOp, Bsp};
//!
//! let p = |x, y, z| IntPoint::new(x, y, z);
//! let solid = |min: IntPoint, max: IntPoint| -> Result<Bsp, chisel_bsp::Error> {
//!     let mut arena = ConvexArena::new();
//!     let poly = arena.add_box(min, max)?;
//!     Ok(Bsp::from_convex(&arena, poly, 1))
//! };
//! // A box with a half-height box against one side: the union's faces meet
//! // in T-junctions, which the mesh removes.
//! let a = solid(p(0, 0, 0)?, p(10, 10, 10)?)?;
//! let b = solid(p(10, 0, 0)?, p(20, 5, 10)?)?;
//! let mut arena = ConvexArena::new();
//! let bounds = arena.add_box(p(-50, -50, -50)?, p(50, 50, 50)?)?;
//! let union = a.merge(&b, BooleanOp::Union, &mut arena, bounds);
//! let mut arena = ConvexArena::new();
//! let bounds = arena.add_box(p(-50, -50, -50)?, p(50, 50, 50)?)?;
//! let mesh = SurfaceMesh::from_faces(&union.boundary(&mut arena, bounds));
//! assert!(mesh.check_watertight().is_ok());
//! let triangles = mesh.triangles();
//! assert_eq!(triangles.indices.len(), triangles.normals.len());
//! # Ok::<(), chisel_bsp::Error>(())
//! ```

mod merge;
pub mod seal;
mod spare;
pub mod tjunction;
pub mod triangulate;
pub mod validate;
pub mod watertight;
pub mod wedge;
pub mod weld;

pub use seal::{BorderEdge, UnsealedMesh};
pub use triangulate::{FlatShadedMesh, TriangleMesh};
pub use validate::MeshInvariantError;
pub use watertight::{BadEdge, EdgeProblem, WatertightError};
pub use wedge::{Ray, SurfaceAround, Turn, Wedge, merge_wedges, primitive_normal};

use crate::exact::{Plane, Point4};
use crate::tree::{BoundaryFace, Label};

/// One polygon of a [`SurfaceMesh`]: a boundary face with its corners as
/// welded vertex indices, including the corners inserted at T-junctions.
///
/// Invariants (checked by [`SurfaceMesh::validate`]): `corners[originals[k]]`
/// is the face's original corner `k` (`s ∩ e_{k−1} ∩ e_k`), `originals` is
/// strictly increasing with `originals[0] = 0`, and every corner strictly
/// between `originals[k]` and `originals[k + 1]` (or after the last, for
/// `k = n − 1`) lies strictly inside original edge `k`, in order along it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MeshPolygon {
    /// Supporting plane, positive side outside (towards [`Self::outside`]).
    pub plane: Plane,
    /// The face's original edge planes (see [`BoundaryFace::edges`]).
    pub edges: Vec<Plane>,
    /// Vertex indices, counter-clockwise seen from outside.
    pub corners: Vec<u32>,
    /// Positions in [`Self::corners`] of the original corners, one per edge
    /// plane.
    pub originals: Vec<u32>,
    /// The material behind the polygon (never empty).
    pub label: Label,
    /// The material in front of it ([`crate::tree::EMPTY`] for a surface
    /// polygon and for polygons on the bounds).
    pub outside: Label,
    /// Whether the polygon lies on the bounds rather than on a BSP plane.
    pub on_bounds: bool,
}

impl MeshPolygon {
    /// Number of original edges (and original corners).
    #[must_use]
    #[inline]
    pub fn original_len(&self) -> usize {
        self.edges.len()
    }

    /// The range of positions in [`Self::corners`] of the corners inserted
    /// strictly inside original edge `k`.
    #[must_use]
    #[inline]
    pub fn inserted_on_edge(&self, k: usize) -> core::ops::Range<usize> {
        let start = self.originals[k] as usize + 1;
        let end = self
            .originals
            .get(k + 1)
            .map_or(self.corners.len(), |&o| o as usize);
        start..end
    }
}

/// A closed surface of exact polygons over welded vertices, as built from
/// boundary faces by [`SurfaceMesh::from_faces`].
#[derive(Clone, Debug, Default)]
pub struct SurfaceMesh {
    vertices: Vec<Point4>,
    polygons: Vec<MeshPolygon>,
}

impl SurfaceMesh {
    /// The surface of `faces`: equal corners welded exactly, coplanar
    /// fragments merged ([`Self::merge_coplanar`]), then every T-junction
    /// removed ([`Self::split_t_junctions`]).
    ///
    /// # Panics
    /// When a face breaks the shape [`Bsp::boundary`](crate::tree::Bsp::boundary)
    /// guarantees: as many edge planes as corners, at least three.
    #[must_use]
    pub fn from_faces(faces: &[BoundaryFace]) -> Self {
        let mut mesh = Self::welded(faces);
        mesh.merge_coplanar();
        mesh.split_t_junctions();
        mesh
    }

    /// Merges polygons on the same plane with the same materials that
    /// share a whole edge, wherever their union is convex, until no merge
    /// applies (exactly; see the `merge` module docs), and drops the
    /// vertices no polygon uses any more (the others keep their order).
    /// The surface as a point set is unchanged. Corners inserted at
    /// T-junctions are dropped first: call [`Self::split_t_junctions`]
    /// afterwards.
    pub fn merge_coplanar(&mut self) {
        for polygon in &mut self.polygons {
            if polygon.corners.len() != polygon.edges.len() {
                let corners = polygon
                    .originals
                    .iter()
                    .map(|&o| polygon.corners[o as usize])
                    .collect();
                polygon.corners = corners;
                polygon.originals = (0..polygon.edges.len() as u32).collect();
            }
        }
        if merge::merge_coplanar(&self.vertices, &mut self.polygons) {
            self.drop_unused_vertices();
        }
    }

    /// Removes the vertices that no polygon uses, renumbering the others
    /// in order.
    fn drop_unused_vertices(&mut self) {
        const UNUSED: u32 = u32::MAX;
        let mut renumber = vec![UNUSED; self.vertices.len()];
        for polygon in &self.polygons {
            for &c in &polygon.corners {
                renumber[c as usize] = 0;
            }
        }
        let mut kept = 0u32;
        for slot in &mut renumber {
            if *slot != UNUSED {
                *slot = kept;
                kept += 1;
            }
        }
        if kept as usize == self.vertices.len() {
            return;
        }
        let mut v = 0;
        self.vertices.retain(|_| {
            v += 1;
            renumber[v - 1] != UNUSED
        });
        for polygon in &mut self.polygons {
            for c in &mut polygon.corners {
                *c = renumber[*c as usize];
            }
        }
    }

    /// The faces with equal corners welded exactly, but T-junctions left in
    /// place: mostly for diagnosis and tests (such a mesh is in general not
    /// watertight).
    ///
    /// # Panics
    /// As [`Self::from_faces`].
    #[must_use]
    pub fn welded(faces: &[BoundaryFace]) -> Self {
        Self::welded_with(
            faces.iter().map(|face| (face, face.edges.clone())),
            vertex_room(faces),
        )
    }

    /// As [`Self::from_faces`], taking the faces (their edge planes move
    /// into the polygons instead of being copied).
    ///
    /// # Panics
    /// As [`Self::from_faces`].
    #[must_use]
    pub fn from_face_vec(faces: Vec<BoundaryFace>) -> Self {
        let mut mesh = Self::welded_owned(faces);
        mesh.merge_coplanar();
        mesh.split_t_junctions();
        mesh
    }

    /// The welded mesh of `faces`, taking them: their edge planes move into
    /// the polygons and their vertex buffers go back to the pool.
    pub(crate) fn welded_owned(mut faces: Vec<BoundaryFace>) -> Self {
        let room = vertex_room(&faces);
        let mesh = Self::welded_with(
            faces.iter_mut().map(|face| {
                let edges = core::mem::take(&mut face.edges);
                (&*face, edges)
            }),
            room,
        );
        for face in faces {
            crate::tree::polygon::give_back_buffers(Vec::new(), face.vertices);
        }
        mesh
    }

    /// As [`Self::from_face_vec`] of all batches one after the other (the
    /// same mesh), welding each batch before the next is asked for: only
    /// one batch of faces is held at a time besides the welded mesh, whose
    /// shared vertices take far less memory than every face's own corners.
    /// For large surfaces built cell by cell.
    ///
    /// # Panics
    /// As [`Self::from_faces`].
    #[must_use]
    pub fn from_face_batches(batches: impl IntoIterator<Item = Vec<BoundaryFace>>) -> Self {
        let mut welder = weld::Welder::with_capacity(0);
        let mut polygons = Vec::new();
        for mut faces in batches {
            polygons.reserve(faces.len());
            for face in &mut faces {
                let edges = core::mem::take(&mut face.edges);
                polygons.push(weld_face(&mut welder, polygons.len(), face, edges));
            }
            for face in faces {
                crate::tree::polygon::give_back_buffers(Vec::new(), face.vertices);
            }
        }
        let mut mesh = Self {
            vertices: welder.into_vertices(),
            polygons,
        };
        mesh.merge_coplanar();
        mesh.split_t_junctions();
        mesh
    }

    /// The welded mesh of faces given with their edge planes, with room
    /// for `room` vertices.
    fn welded_with<'a>(
        faces: impl ExactSizeIterator<Item = (&'a BoundaryFace, Vec<Plane>)>,
        room: usize,
    ) -> Self {
        let mut welder = weld::Welder::with_capacity(room);
        let polygons = faces
            .enumerate()
            .map(|(f, (face, edges))| weld_face(&mut welder, f, face, edges))
            .collect();
        Self {
            vertices: welder.into_vertices(),
            polygons,
        }
    }

    /// Inserts, into every original edge of every polygon, each vertex lying
    /// strictly inside it, in order along the edge. Idempotent: the inserted
    /// corners are recomputed from the original edges each time.
    pub fn split_t_junctions(&mut self) {
        tjunction::split(&self.vertices, &mut self.polygons);
    }

    /// The welded exact vertices.
    #[must_use]
    #[inline]
    pub fn vertices(&self) -> &[Point4] {
        &self.vertices
    }

    /// The polygons.
    #[must_use]
    #[inline]
    pub fn polygons(&self) -> &[MeshPolygon] {
        &self.polygons
    }

    /// Keeps only the polygons for which `keep` is true (the vertices stay,
    /// so indices are unchanged). For example, `|p| p.outside == EMPTY`
    /// keeps the outer surface of a multi-material solid, which is closed
    /// again once interfaces are dropped.
    pub fn retain(&mut self, keep: impl FnMut(&MeshPolygon) -> bool) {
        self.polygons.retain(keep);
    }

    /// The position of vertex `v` in `f64` (each coordinate within `2^-51`
    /// relative of the exact value).
    ///
    /// # Panics
    /// When `v` is not a vertex index.
    #[must_use]
    #[inline]
    pub fn position(&self, v: u32) -> [f64; 3] {
        self.vertices[v as usize].to_f64()
    }
}

impl Drop for SurfaceMesh {
    /// Hands the polygons' edge planes and index lists to the spare
    /// buffers of this thread, for the next faces cut and welded there.
    fn drop(&mut self) {
        crate::tree::polygon::give_back_edge_buffers(
            self.polygons
                .iter_mut()
                .map(|p| core::mem::take(&mut p.edges)),
        );
        spare::give_back(self.polygons.iter_mut().flat_map(|p| {
            [
                core::mem::take(&mut p.corners),
                core::mem::take(&mut p.originals),
            ]
        }));
    }
}

/// Room for the welded vertices of `faces`: about half their corners, as
/// most corners are shared by two or more faces, and a little more so
/// that the vertices of one cell's surface rarely outgrow it.
fn vertex_room(faces: &[BoundaryFace]) -> usize {
    faces.iter().map(|f| f.vertices.len()).sum::<usize>() / 2 + 8
}

/// Boundary face number `f` with its edge planes as a polygon of welded
/// corners.
fn weld_face(
    welder: &mut weld::Welder,
    f: usize,
    face: &BoundaryFace,
    edges: Vec<Plane>,
) -> MeshPolygon {
    assert!(
        edges.len() == face.vertices.len() && edges.len() >= 3,
        "boundary face {f} has {} edge planes and {} corners",
        edges.len(),
        face.vertices.len()
    );
    let n = face.vertices.len();
    let mut corners = spare::index_buffer(n);
    corners.extend(face.vertices.iter().map(|v| welder.index(v)));
    let mut originals = spare::index_buffer(n);
    originals.extend(0..n as u32);
    MeshPolygon {
        plane: face.plane,
        edges,
        originals,
        corners,
        label: face.label,
        outside: face.outside,
        on_bounds: face.on_bounds,
    }
}
