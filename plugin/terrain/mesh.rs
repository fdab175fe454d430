//! Cell meshes: the visible surface of one leaf cell, per material, as
//! flat-shaded `f32` triangles relative to the cell's lower corner.
//!
//! Pure functions of the octree, run on the async compute pool, which also
//! builds the [`Mesh`]es; the main thread only adds them as assets.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::PrimitiveTopology;
use bevy::prelude::*;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{CellKey, Octree};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::{BoundaryFace, EMPTY, Label};

/// The triangles of one material in one cell, flat shaded: vertex `3t..3t+3`
/// is triangle `t`, each with its face's exact normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellMesh {
    /// The material.
    pub label: Label,
    /// Positions in world units relative to the cell's lower corner.
    pub positions: Vec<[f32; 3]>,
    /// Per vertex, the unit normal of its triangle's exact plane.
    pub normals: Vec<[f32; 3]>,
}

impl CellMesh {
    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.positions.len() / 3
    }

    /// As a Bevy triangle-list mesh.
    #[must_use]
    pub fn to_mesh(&self) -> Mesh {
        self.clone().into_mesh()
    }

    /// As a Bevy triangle-list mesh, without copying the vertices.
    #[must_use]
    pub fn into_mesh(self) -> Mesh {
        Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, self.positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, self.normals)
    }
}

/// One material's mesh of a cell, built off the main thread and ready to be
/// added as an asset.
pub(crate) struct ReadyMesh {
    /// The material.
    pub label: Label,
    /// Number of triangles.
    pub triangles: usize,
    /// The Bevy mesh.
    pub mesh: Mesh,
}

impl From<CellMesh> for ReadyMesh {
    fn from(mesh: CellMesh) -> Self {
        Self {
            label: mesh.label,
            triangles: mesh.triangle_count(),
            mesh: mesh.into_mesh(),
        }
    }
}

/// The visible surface of leaf cell `key` (faces in front of empty space),
/// one [`CellMesh`] per material, sorted by label; empty when the cell has
/// no surface or is not a leaf.
///
/// Positions are computed in `f64` from the exact vertices, made relative
/// to the cell's lower corner, then scaled by the unit and rounded to
/// `f32`: the error is about `2^-24` of the cell's edge.
#[must_use]
pub fn cell_meshes(octree: &Octree, quantization: &Quantization, key: CellKey) -> Vec<CellMesh> {
    meshes_of_surface(octree, quantization, key, octree.cell_surface(key))
}

/// [`cell_meshes`] from the boundary faces a carve handed back for `key`
/// ([`Octree::apply_with_faces`]): the same surface without cutting the
/// cell's BSP again (possibly split into different triangles).
#[must_use]
pub fn cell_meshes_from(
    octree: &Octree,
    quantization: &Quantization,
    key: CellKey,
    faces: Vec<BoundaryFace>,
) -> Vec<CellMesh> {
    meshes_of_surface(
        octree,
        quantization,
        key,
        octree.cell_surface_from(key, faces),
    )
}

/// One mesh per material of a cell's surface pieces.
fn meshes_of_surface(
    octree: &Octree,
    quantization: &Quantization,
    key: CellKey,
    faces: Vec<BoundaryFace>,
) -> Vec<CellMesh> {
    if faces.is_empty() {
        return Vec::new();
    }
    let surface = SurfaceMesh::from_faces(&faces);
    let corner = octree.cell_box(key).min.map(|c| c as f64);
    let unit = quantization.unit();
    let mut out: Vec<CellMesh> = Vec::new();
    for polygon in surface.polygons() {
        if polygon.outside != EMPTY {
            continue;
        }
        let slot = match out.iter().position(|m| m.label == polygon.label) {
            Some(i) => i,
            None => {
                out.push(CellMesh {
                    label: polygon.label,
                    ..CellMesh::default()
                });
                out.len() - 1
            }
        };
        let mesh = &mut out[slot];
        let normal = polygon.unit_normal().map(|c| c as f32);
        for triangle in polygon.triangulate() {
            for v in triangle {
                let p = surface.position(v);
                mesh.positions
                    .push([0, 1, 2].map(|a| ((p[a] - corner[a]) * unit) as f32));
                mesh.normals.push(normal);
            }
        }
    }
    out.retain(|m| !m.positions.is_empty());
    out.sort_by_key(|m| m.label);
    out
}

/// World (terrain-local) position of a cell's lower corner.
#[must_use]
pub fn cell_translation(octree: &Octree, quantization: &Quantization, key: CellKey) -> Vec3 {
    let min = octree.cell_box(key).min.map(|c| c as f64);
    let p = quantization.to_world(min);
    Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
}
