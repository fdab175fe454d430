//! Cell meshes: the visible surface of one leaf cell, per material, as
//! indexed triangles in the terrain's local frame, with smooth normals
//! within a smoothing angle and a welded triangle list for colliders.
//!
//! Notation: `P`, `Q` — surface polygons (faces in front of empty space);
//! `n_P` — the unit normal of `P`'s exact plane; `v` — a welded exact
//! vertex of the cell's [`SurfaceMesh`]; `θ` — the smoothing angle.
//!
//! Positions. Every position is the exact vertex rounded once, from grid
//! units to the terrain's local frame ([`Quantization::to_world`], then
//! `f32`): the same exact vertex gives the same bits in every cell that
//! has it, so neighbouring cells whose meshes share their border vertices
//! meet without cracks.
//!
//! Normals. The corner of `P` at `v` gets the angle-weighted mean of `n_Q`
//! over the surface polygons `Q` around `v` with `n_P · n_Q ≥ cos θ`
//! (polygons of every material count, so normals are smooth across a
//! change of material). Faces meeting at more than `θ`, such as a crater's
//! rim, stay sharp; render vertices are shared by the corners of one `v`
//! that get the same normal.
//!
//! Across cell borders ([`cell_meshes_around`]). At a vertex on the
//! cell's walls the polygons around it are those of every cell that has
//! it, handed over by the seamed mesher as exact wedges
//! ([`SurfaceAround`], merged per plane so that how cells and pieces split
//! the surface does not matter, in a canonical order): each wedge `W`
//! counts `angle(W) · n_W`, its angle from its exact rays. So both sides
//! of a border sum the same numbers in the same order and give the same
//! bits for the same (vertex, plane of `P`), whatever the thread count,
//! and an incremental update gives what a build from scratch gives
//! there. Inside the cell, the angles come from the rounded positions of
//! the cell's own polygons.
//!
//! Pure functions of the octree, run on the worker threads, which also
//! build the [`Mesh`]es; the main thread only adds them as assets.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use chisel_bsp::mesh::{MeshPolygon, SurfaceAround, SurfaceMesh, Turn, Wedge, primitive_normal};
use chisel_bsp::octree::{CellKey, Octree};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::{BoundaryFace, EMPTY, Label};

/// The smoothing angle of [`super::TerrainSettings`] by default, in
/// degrees: gentle slopes (a heightfield's facets) shade smoothly, crater
/// walls and rims stay sharp.
pub const DEFAULT_SMOOTHING_DEGREES: f32 = 35.0;

/// The triangles of one material in one cell.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellMesh {
    /// The material.
    pub label: Label,
    /// Render vertex positions, in the terrain's local frame.
    pub positions: Vec<[f32; 3]>,
    /// Per render vertex, its unit normal (smoothed within the smoothing
    /// angle).
    pub normals: Vec<[f32; 3]>,
    /// Triangles as render vertex indices, counter-clockwise from outside.
    pub indices: Vec<u32>,
    /// The same triangles over the welded exact vertices, for a collider.
    pub collider: ColliderMesh,
}

/// Indexed, welded triangles: one entry per exact vertex, so adjacent
/// triangles share their vertices (what a trimesh collider needs to slide
/// over internal edges).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ColliderMesh {
    /// Vertex positions, in the terrain's local frame.
    pub positions: Vec<Vec3>,
    /// Triangles, counter-clockwise from outside.
    pub triangles: Vec<[u32; 3]>,
}

impl CellMesh {
    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
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
        .with_inserted_indices(Indices::U32(self.indices))
    }
}

/// The visible surface of leaf cell `key` (faces in front of empty space),
/// one [`CellMesh`] per material, sorted by label; empty when the cell has
/// no surface or is not a leaf. Normals are smoothed within
/// [`DEFAULT_SMOOTHING_DEGREES`]; [`cell_meshes_of`] takes the angle.
#[must_use]
pub fn cell_meshes(octree: &Octree, quantization: &Quantization, key: CellKey) -> Vec<CellMesh> {
    let faces = octree.cell_surface(key);
    cell_meshes_of(
        &SurfaceMesh::from_face_vec(faces),
        quantization,
        DEFAULT_SMOOTHING_DEGREES,
    )
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
    let faces = octree.cell_surface_from(key, faces);
    cell_meshes_of(
        &SurfaceMesh::from_face_vec(faces),
        quantization,
        DEFAULT_SMOOTHING_DEGREES,
    )
}

/// One [`CellMesh`] per material of the surface polygons of `surface` (a
/// cell's surface, T-junctions split, or a standalone surface such as a
/// debris piece), sorted by label, with normals smoothed within
/// `smoothing_degrees` (0: flat shading) over its own polygons.
#[must_use]
pub fn cell_meshes_of(
    surface: &SurfaceMesh,
    quantization: &Quantization,
    smoothing_degrees: f32,
) -> Vec<CellMesh> {
    cell_meshes_around(
        surface,
        &SurfaceAround::default(),
        quantization,
        smoothing_degrees,
    )
}

/// [`cell_meshes_of`] of a sealed cell mesh, with `around` the surface
/// around its border vertices in every cell that has them
/// ([`chisel_bsp::octree::SeamedMesher::update_shaded`]): a vertex with
/// wedges there is smoothed over them, so that neighbouring cells agree
/// on its normals (see the module docs); the others over the cell's own
/// polygons.
#[must_use]
pub fn cell_meshes_around(
    surface: &SurfaceMesh,
    around: &SurfaceAround,
    quantization: &Quantization,
    smoothing_degrees: f32,
) -> Vec<CellMesh> {
    let polygons: Vec<&MeshPolygon> = surface
        .polygons()
        .iter()
        .filter(|p| p.outside == EMPTY)
        .collect();
    if polygons.is_empty() {
        return Vec::new();
    }
    let positions: Vec<[f64; 3]> = (0..surface.vertices().len() as u32)
        .map(|v| quantization.to_world(surface.position(v)))
        .collect();
    let normals: Vec<[f64; 3]> = polygons.iter().map(|p| p.unit_normal()).collect();
    let mut border = BorderWedges::new(around);
    let own = CornersAround::of(&polygons, &positions, |v| border.has(v));
    let cos_limit = f64::from(smoothing_degrees.clamp(0.0, 180.0))
        .to_radians()
        .cos();

    let mut labels: Vec<Label> = polygons.iter().map(|p| p.label).collect();
    labels.sort_unstable();
    labels.dedup();
    // Per exact vertex, its first render vertex and its collider vertex
    // in the mesh being built (`NONE`: none yet); per render vertex, the
    // next one of the same exact vertex.
    let mut first_render = vec![NONE; positions.len()];
    let mut welded = vec![NONE; positions.len()];
    let mut next_render: Vec<u32> = Vec::new();
    // Per corner of the polygon at hand: its exact vertex and smoothed
    // normal.
    let mut corner_normals: Vec<(u32, [f32; 3])> = Vec::new();
    labels
        .into_iter()
        .map(|label| {
            let mut mesh = CellMesh {
                label,
                ..CellMesh::default()
            };
            first_render.fill(NONE);
            welded.fill(NONE);
            next_render.clear();
            for (p, polygon) in polygons.iter().enumerate() {
                if polygon.label != label {
                    continue;
                }
                let n_p = normals[p];
                // The plane's normal as the wedges name it, at border
                // vertices.
                let mut n_exact = None;
                let mut smoothed = |v: u32| {
                    if border.has(v) {
                        let n = *n_exact.get_or_insert_with(|| exact_unit_normal(polygon));
                        border.smooth_normal(v, n, cos_limit)
                    } else {
                        smooth_normal(n_p, own.of_vertex(v), &normals, cos_limit)
                    }
                };
                corner_normals.clear();
                corner_normals.extend(polygon.corners.iter().map(|&v| (v, smoothed(v))));
                let mut corner = |v: u32| -> (u32, u32) {
                    let normal = corner_normals
                        .iter()
                        .find(|(w, _)| *w == v)
                        .map_or_else(|| smoothed(v), |(_, n)| *n);
                    let bits = normal.map(f32::to_bits);
                    // The render vertex of (exact vertex, normal bits).
                    let mut r = first_render[v as usize];
                    while r != NONE && mesh.normals[r as usize].map(f32::to_bits) != bits {
                        r = next_render[r as usize];
                    }
                    if r == NONE {
                        r = mesh.positions.len() as u32;
                        mesh.positions.push(positions[v as usize].map(|c| c as f32));
                        mesh.normals.push(normal);
                        next_render.push(first_render[v as usize]);
                        first_render[v as usize] = r;
                    }
                    // The collider vertex of the exact vertex.
                    let w = &mut welded[v as usize];
                    if *w == NONE {
                        *w = mesh.collider.positions.len() as u32;
                        let p = positions[v as usize];
                        mesh.collider.positions.push(Vec3::new(
                            p[0] as f32,
                            p[1] as f32,
                            p[2] as f32,
                        ));
                    }
                    (r, *w)
                };
                for triangle in polygon.triangulate() {
                    let [a, b, c] = triangle.map(&mut corner);
                    mesh.indices.extend([a.0, b.0, c.0]);
                    mesh.collider.triangles.push([a.1, b.1, c.1]);
                }
            }
            mesh
        })
        .filter(|m| !m.indices.is_empty())
        .collect()
}

/// No render or collider vertex yet.
const NONE: u32 = u32::MAX;

/// Per exact vertex, the surface polygons around it with their corner
/// angle there, `(polygon, angle)`, in polygon order: one list of all
/// corners, grouped by vertex.
struct CornersAround {
    /// Vertex `v`'s corners are `corners[start[v]..start[v + 1]]`.
    start: Vec<u32>,
    corners: Vec<(u32, f64)>,
}

impl CornersAround {
    /// The corners of `polygons`, with their angles except at the
    /// vertices `skipped` (smoothed otherwise; angle 0 there).
    fn of(
        polygons: &[&MeshPolygon],
        positions: &[[f64; 3]],
        skipped: impl Fn(u32) -> bool,
    ) -> Self {
        let mut start = vec![0u32; positions.len() + 1];
        for polygon in polygons {
            for &c in &polygon.corners {
                start[c as usize + 1] += 1;
            }
        }
        for v in 0..positions.len() {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut corners = vec![(0u32, 0.0f64); start[positions.len()] as usize];
        for (p, polygon) in polygons.iter().enumerate() {
            let c = &polygon.corners;
            let n = c.len();
            for k in 0..n {
                let weight = if skipped(c[k]) {
                    0.0
                } else {
                    let at = positions[c[k] as usize];
                    let prev = positions[c[(k + n - 1) % n] as usize];
                    let next = positions[c[(k + 1) % n] as usize];
                    angle(sub(prev, at), sub(next, at))
                };
                let slot = &mut fill[c[k] as usize];
                corners[*slot as usize] = (p as u32, weight);
                *slot += 1;
            }
        }
        Self { start, corners }
    }

    /// The corners at vertex `v`.
    fn of_vertex(&self, v: u32) -> &[(u32, f64)] {
        &self.corners[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The surface around the border vertices of a cell in floats: per
/// vertex with wedges, each wedge's unit normal and angle, computed once.
struct BorderWedges<'a> {
    around: &'a SurfaceAround,
    /// Per vertex, where its wedges' floats start in `floats` (`NONE`:
    /// not yet computed).
    start: Vec<u32>,
    floats: Vec<([f64; 3], f64)>,
}

impl<'a> BorderWedges<'a> {
    fn new(around: &'a SurfaceAround) -> Self {
        Self {
            around,
            start: vec![NONE; around.vertices()],
            floats: Vec::new(),
        }
    }

    /// Whether vertex `v` has wedges.
    fn has(&self, v: u32) -> bool {
        !self.around.of_vertex(v).is_empty()
    }

    /// The unit normal of the corner at border vertex `v` of a polygon
    /// with unit normal `n_p` ([`exact_unit_normal`]): the angle-weighted
    /// mean of the wedges' normals within the smoothing angle, in the
    /// wedges' order.
    fn smooth_normal(&mut self, v: u32, n_p: [f64; 3], cos_limit: f64) -> [f32; 3] {
        let wedges = self.around.of_vertex(v);
        let start = &mut self.start[v as usize];
        if *start == NONE {
            *start = self.floats.len() as u32;
            self.floats
                .extend(wedges.iter().map(|w| (unit(w.normal), wedge_angle(w))));
        }
        let floats = &self.floats[*start as usize..*start as usize + wedges.len()];
        let mut sum = [0.0f64; 3];
        for &(n_q, weight) in floats {
            if dot(n_p, n_q) >= cos_limit {
                for a in 0..3 {
                    sum[a] += weight * n_q[a];
                }
            }
        }
        normalized_or(sum, n_p)
    }
}

/// The unit normal of `polygon`'s plane from its primitive normal, as
/// [`BorderWedges`] computes the wedges' normals (the same bits for the
/// same plane).
fn exact_unit_normal(polygon: &MeshPolygon) -> [f64; 3] {
    unit(primitive_normal(&polygon.plane))
}

/// `n` as a unit vector in `f64`.
fn unit(n: [i64; 3]) -> [f64; 3] {
    let n = n.map(|c| c as f64);
    let length = dot(n, n).sqrt();
    n.map(|c| c / length)
}

/// The angle of a wedge, in radians: from its exact turn and rays (the
/// unsigned angle between the rays, or its complement for more than half
/// a turn).
fn wedge_angle(wedge: &Wedge) -> f64 {
    match wedge.turn {
        Turn::Full => std::f64::consts::TAU,
        Turn::Straight => std::f64::consts::PI,
        Turn::Convex | Turn::Reflex => {
            let a = wedge.from.0.map(|c| c as f64);
            let b = wedge.to.0.map(|c| c as f64);
            let between = angle(a, b);
            if wedge.turn == Turn::Reflex {
                std::f64::consts::TAU - between
            } else {
                between
            }
        }
    }
}

/// `sum` normalized, or `fallback` where it is (nearly) zero.
fn normalized_or(sum: [f64; 3], fallback: [f64; 3]) -> [f32; 3] {
    let length = dot(sum, sum).sqrt();
    if length.is_finite() && length > 1e-12 {
        sum.map(|c| (c / length) as f32)
    } else {
        fallback.map(|c| c as f32)
    }
}

/// The unit normal of a corner of a polygon with normal `n_p`: the
/// angle-weighted mean of the normals around the vertex within the
/// smoothing angle (`n_p` itself when nothing else is).
fn smooth_normal(
    n_p: [f64; 3],
    around: &[(u32, f64)],
    normals: &[[f64; 3]],
    cos_limit: f64,
) -> [f32; 3] {
    let mut sum = [0.0f64; 3];
    for &(q, weight) in around {
        let n_q = normals[q as usize];
        if dot(n_p, n_q) >= cos_limit {
            for a in 0..3 {
                sum[a] += weight * n_q[a];
            }
        }
    }
    normalized_or(sum, n_p)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The angle between two vectors, in radians (0 for a zero vector).
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    dot(cross, cross).sqrt().atan2(dot(a, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use chisel_bsp::octree::{CellBox, OctreeConfig};

    fn cube() -> (Octree, Quantization) {
        let solid = CellBox {
            min: [0; 3],
            max: [8; 3],
        };
        let octree =
            Octree::from_box([0; 3], 4, solid, 1, OctreeConfig::default()).expect("a valid cube");
        (
            octree,
            Quantization::new(0.5, [1.0, 2.0, 3.0]).expect("unit"),
        )
    }

    #[test]
    fn a_cube_keeps_sharp_edges_and_shares_collider_vertices() {
        let (octree, grid) = cube();
        let meshes: Vec<CellMesh> = octree
            .leaves()
            .iter()
            .flat_map(|(key, _)| cell_meshes(&octree, &grid, *key))
            .collect();
        let triangles: usize = meshes.iter().map(CellMesh::triangle_count).sum();
        assert!(triangles >= 12);
        for mesh in &meshes {
            // Every normal is one of the six axis directions: 90° edges
            // stay sharp at the default angle.
            for n in &mesh.normals {
                let axis = n.iter().filter(|c| c.abs() == 1.0).count();
                assert_eq!(axis, 1, "normal {n:?} is smoothed across a 90° edge");
            }
            // Welded: fewer collider vertices than render corners.
            assert!(mesh.collider.positions.len() <= mesh.positions.len());
            assert_eq!(mesh.collider.triangles.len(), mesh.triangle_count());
            // Positions are in the terrain's frame: grid 0..8 at unit 0.5
            // from the origin (1, 2, 3).
            for p in &mesh.positions {
                for (a, &c) in p.iter().enumerate() {
                    let lo = [1.0, 2.0, 3.0][a];
                    assert!((lo..=lo + 4.0).contains(&c), "{p:?} outside the box");
                }
            }
        }
    }

    #[test]
    fn a_wide_angle_smooths_the_cube_corners() {
        let (octree, grid) = cube();
        let surface = SurfaceMesh::from_face_vec(octree.surface());
        let meshes = cell_meshes_of(&surface, &grid, 100.0);
        let corner = meshes[0]
            .normals
            .iter()
            .find(|n| n.iter().all(|c| c.abs() > 0.5))
            .expect("a corner normal averaged over three faces");
        for c in corner {
            assert!((c.abs() - 1.0 / 3f32.sqrt()).abs() < 1e-5, "{corner:?}");
        }
    }
}
