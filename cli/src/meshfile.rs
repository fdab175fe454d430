//! Mesh files for the commands: reading a closed triangle mesh onto the
//! 1 µm grid, and writing a result mesh (format by extension), both in
//! millimetres.

use std::path::Path;

use chisel_bsp::exact::IntPoint;
use chisel_bsp::exact::budget::MAX_COORD;
use chisel_bsp::mesh::TriangleMesh;
use chisel_bsp::octree::CellBox;
use chisel_bsp::tools::Quantization;

use crate::formats::{read_triangle_soup, write_triangle_mesh};
use crate::scenario::sequence::UNITS_PER_MM;

/// A triangle mesh on the integer grid.
pub struct GridMesh {
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[IntPoint; 3]>,
    /// A box around every corner.
    pub bounds: CellBox,
}

/// Reads a mesh file (OBJ, PLY or GLB; millimetres) onto the 1 µm grid.
///
/// # Errors
/// A message naming the file: unreadable or malformed content, or
/// coordinates beyond the exact range.
pub fn read_grid(path: &Path) -> Result<GridMesh, String> {
    let soup = read_triangle_soup(path).map_err(|e| e.to_string())?;
    let grid = Quantization::new(1.0 / UNITS_PER_MM, [0.0; 3]).map_err(|e| e.to_string())?;
    let positions = soup
        .positions
        .iter()
        .enumerate()
        .map(|(v, &p)| {
            grid.to_grid(p).map_err(|e| {
                let e = match e {
                    // The input value and its unit, not the saturated
                    // grid value.
                    chisel_bsp::Error::CoordinateOutOfRange { axis, .. } => format!(
                        "coordinate {}={} mm is outside the exact range of ±{} mm \
                         (2^26 grid units of 1 µm); scale the mesh down",
                        ['x', 'y', 'z'][axis.min(2)],
                        short(p[axis.min(2)]),
                        short(MAX_COORD as f64 / UNITS_PER_MM)
                    ),
                    e => e.to_string(),
                };
                format!("{}: vertex {}: {e}", path.display(), v + 1)
            })
        })
        .collect::<Result<Vec<IntPoint>, String>>()?;
    let bounds = CellBox::enclosing(positions.iter().map(IntPoint::coords))
        .ok_or_else(|| format!("{}: the mesh has no vertices", path.display()))?;
    let triangles = soup
        .triangles
        .iter()
        .map(|t| t.map(|v| positions[v as usize]))
        .collect();
    Ok(GridMesh { triangles, bounds })
}

/// Writes `mesh` (grid units) to `path` in millimetres, in the format of
/// the extension (OBJ, PLY or GLB).
///
/// # Errors
/// A message naming the file.
pub fn write(path: &Path, mesh: &TriangleMesh) -> Result<(), String> {
    let scale = (1.0 / UNITS_PER_MM) as f32;
    let mut mm = mesh.clone();
    for p in &mut mm.positions {
        *p = p.map(|c| c * scale);
    }
    write_triangle_mesh(path, &mm).map_err(|e| e.to_string())
}

/// `x` in plain decimals, or in exponent form when very large or small.
fn short(x: f64) -> String {
    if x != 0.0 && !(1e-4..1e15).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}
