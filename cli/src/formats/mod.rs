//! Mesh files: OBJ, PLY (ASCII and binary little-endian) and GLB in, as an
//! indexed triangle soup; OBJ, binary PLY and GLB out, from a
//! [`TriangleMesh`] of the exact kernel. The format follows the file
//! extension ([`MeshFormat::from_path`]).
//!
//! Reading never panics on bad input: every problem is a [`FormatError`]
//! naming the file, the line / byte offset / face / primitive, and what is
//! wrong (malformed numbers, indices out of range, NaN or infinite
//! coordinates, truncated data, missing files). Faces with more than three
//! corners are fan-triangulated; GLB node transforms are applied.
//!
//! - [`obj`] — Wavefront OBJ, read and write.
//! - [`ply`] — PLY header and bodies (ASCII, binary little-endian), read
//!   and write.
//! - [`glb_read`] — binary glTF through the `gltf` crate, with every
//!   accessor bounds-checked before it is read.
//! - [`glb_write`] — binary glTF, one primitive and material per label.
//! - [`error`] — [`FormatError`], [`Location`], [`Problem`].

mod error;
mod glb_read;
mod glb_write;
mod obj;
mod ply;
#[cfg(test)]
mod tests;

use std::path::Path;

use chisel_bsp::mesh::TriangleMesh;

pub use error::{FormatError, Location, Problem};

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`), text.
    Obj,
    /// Stanford PLY (`.ply`): ASCII or binary little-endian in, binary
    /// little-endian out.
    Ply,
    /// Binary glTF 2.0 (`.glb`).
    Glb,
}

impl MeshFormat {
    /// The format named by the extension of `path` (case-insensitive).
    ///
    /// # Errors
    /// [`Problem::UnknownFormat`] for any other extension or none.
    pub fn from_path(path: &Path) -> Result<Self, FormatError> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            Some("glb") => Ok(MeshFormat::Glb),
            _ => Err(FormatError::new(
                path,
                Location::File,
                Problem::UnknownFormat { extension },
            )),
        }
    }
}

/// An indexed triangle soup as read from a file: positions in `f64` (every
/// one finite) and triangles as indices into them (every one in range).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleSoup {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Triangles, in the orientation of the file.
    pub triangles: Vec<[u32; 3]>,
}

/// Reads the mesh file at `path`, in the format of its extension.
///
/// # Errors
/// A [`FormatError`] for an unknown extension, an unreadable file or
/// malformed content (see [`Problem`]).
pub fn read_triangle_soup(path: &Path) -> Result<TriangleSoup, FormatError> {
    let format = MeshFormat::from_path(path)?;
    let bytes =
        std::fs::read(path).map_err(|e| FormatError::new(path, Location::File, Problem::Io(e)))?;
    parse_triangle_soup(&bytes, format, path)
}

/// Parses mesh file content; `path` names the file in errors and, for GLB,
/// locates external buffers.
///
/// # Errors
/// A [`FormatError`] for malformed content (see [`Problem`]).
pub fn parse_triangle_soup(
    bytes: &[u8],
    format: MeshFormat,
    path: &Path,
) -> Result<TriangleSoup, FormatError> {
    let soup = match format {
        MeshFormat::Obj => obj::parse(bytes, path)?,
        MeshFormat::Ply => ply::parse(bytes, path)?,
        MeshFormat::Glb => glb_read::parse(bytes, path)?,
    };
    if soup.triangles.is_empty() {
        return Err(FormatError::new(path, Location::File, Problem::NoTriangles));
    }
    Ok(soup)
}

/// Writes `mesh` to `path` in the format of its extension.
///
/// # Errors
/// A [`FormatError`] for an unknown extension, an inconsistent mesh or a
/// failed write.
pub fn write_triangle_mesh(path: &Path, mesh: &TriangleMesh) -> Result<(), FormatError> {
    let format = MeshFormat::from_path(path)?;
    let bytes = encode_triangle_mesh(mesh, format)
        .map_err(|problem| FormatError::new(path, Location::File, problem))?;
    crate::atomic::write_bytes(path, &bytes)
        .map_err(|e| FormatError::new(path, Location::File, Problem::Io(e)))
}

/// The file content of `mesh` in `format`.
///
/// # Errors
/// [`Problem::InvalidMesh`] when the mesh is inconsistent.
pub fn encode_triangle_mesh(mesh: &TriangleMesh, format: MeshFormat) -> Result<Vec<u8>, Problem> {
    check_mesh(mesh).map_err(|reason| Problem::InvalidMesh { reason })?;
    // GLB lengths are 32-bit; flat shading takes 84 bytes per triangle.
    if format == MeshFormat::Glb && mesh.indices.len() > (u32::MAX / 96) as usize {
        return Err(Problem::InvalidMesh {
            reason: format!("{} triangles do not fit a 4 GiB GLB", mesh.indices.len()),
        });
    }
    Ok(match format {
        MeshFormat::Obj => obj::encode(mesh),
        MeshFormat::Ply => ply::encode(mesh),
        MeshFormat::Glb => glb_write::encode(mesh),
    })
}

/// Checks what the writers rely on: per-triangle lists as long as the
/// triangles, indices in range, finite positions and normals.
fn check_mesh(mesh: &TriangleMesh) -> Result<(), String> {
    let n = mesh.indices.len();
    if mesh.normals.len() != n || mesh.labels.len() != n {
        return Err(format!(
            "{n} triangles but {} normals and {} labels",
            mesh.normals.len(),
            mesh.labels.len()
        ));
    }
    if u32::try_from(mesh.positions.len()).is_err() || n > (u32::MAX / 3) as usize {
        return Err("too many vertices or triangles for 32-bit indices".into());
    }
    if let Some((t, _)) = mesh
        .indices
        .iter()
        .enumerate()
        .find(|(_, tri)| tri.iter().any(|&v| v as usize >= mesh.positions.len()))
    {
        return Err(format!(
            "triangle {t} names a vertex beyond the {} positions",
            mesh.positions.len()
        ));
    }
    if let Some(v) = mesh
        .positions
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(format!("position {v} is not finite"));
    }
    if let Some(t) = mesh
        .normals
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(format!("normal {t} is not finite"));
    }
    Ok(())
}

/// Appends the fan triangulation `(c_0, c_k, c_{k+1})` of a face.
fn push_fan(triangles: &mut Vec<[u32; 3]>, corners: &[u32]) {
    for k in 1..corners.len().saturating_sub(1) {
        triangles.push([corners[0], corners[k], corners[k + 1]]);
    }
}
