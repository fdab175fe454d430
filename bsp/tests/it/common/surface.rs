//! Solids and surface measures shared by the surface-mesh tests: BSPs in
//! the cube `[-H, H]³`, their Booleans and boundaries there, and the exact
//! volume a surface mesh's polygons enclose.

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::exact::Point4;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::tree::{BooleanOp, BoundaryFace, Bsp, Label};

use super::shapes::p;
use super::volume::{Fraction, polygons_volume};

/// Half the edge of the cube the solids live in.
pub const H: i64 = 1 << 16;

/// The cube `[-H, H]³` in `arena`.
pub fn bounds(arena: &mut ConvexArena) -> PolyId {
    arena.add_box(p(-H, -H, -H), p(H, H, H)).unwrap()
}

/// The box `[min, max]` as a BSP of solid `label`.
pub fn box_bsp(min: [i64; 3], max: [i64; 3], label: Label) -> Bsp {
    let mut arena = ConvexArena::new();
    let b = arena
        .add_box(p(min[0], min[1], min[2]), p(max[0], max[1], max[2]))
        .unwrap();
    Bsp::from_convex(&arena, b, label)
}

/// `a op b` inside the cube.
pub fn merge(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bd = bounds(&mut arena);
    a.merge(b, op, &mut arena, bd)
}

/// The boundary of `bsp` inside the cube.
pub fn boundary(bsp: &Bsp) -> Vec<BoundaryFace> {
    let mut arena = ConvexArena::new();
    let bd = bounds(&mut arena);
    bsp.boundary(&mut arena, bd)
}

/// The exact points of `vertices` of `mesh`.
pub fn corners(mesh: &SurfaceMesh, vertices: &[u32]) -> Vec<Point4> {
    vertices
        .iter()
        .map(|&v| mesh.vertices()[v as usize])
        .collect()
}

/// The exact volume enclosed by the mesh's polygons (with their inserted
/// corners).
pub fn polygons_volume_of(mesh: &SurfaceMesh) -> Fraction {
    let polygons: Vec<Vec<Point4>> = mesh
        .polygons()
        .iter()
        .map(|p| corners(mesh, &p.corners))
        .collect();
    polygons_volume(&polygons)
}
