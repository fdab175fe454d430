//! Stanford PLY: a text header declaring elements and their properties,
//! then an ASCII or binary little-endian body. The `vertex` element gives
//! `x, y, z`; the `face` element's list property `vertex_indices` (or
//! `vertex_index`) gives polygons, fan-triangulated. Other elements and
//! properties are read past and ignored. Written as binary little-endian
//! with a normal and a material label per face.
//!
//! - [`header`] — the header.
//! - [`body`] — the ASCII and binary bodies.

mod body;
mod header;

use std::fmt::Write as _;
use std::path::Path;

use chisel_bsp::mesh::TriangleMesh;

use super::{FormatError, Location, Problem, TriangleSoup, push_fan};
use body::{AsciiBody, BinaryBody, read_body};
use header::{Encoding, parse_header};

/// Parses PLY content.
pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<TriangleSoup, FormatError> {
    let header = parse_header(bytes, path)?;
    let body = &bytes[header.body_offset..];
    let result = match header.encoding {
        Encoding::Ascii => {
            let split: fn(&u8) -> bool = |&b| b == b'\n';
            let mut reader = AsciiBody {
                lines: body.split(split).enumerate(),
                first_line: header.body_line,
                line: header.body_line,
                tokens: Vec::new(),
                next: 0,
            };
            read_body(&header.elements, &mut reader, body.len())
        }
        Encoding::BinaryLittleEndian => {
            let mut reader = BinaryBody {
                data: body,
                pos: 0,
                base: header.body_offset,
            };
            read_body(&header.elements, &mut reader, body.len())
        }
    };
    let (positions, faces) =
        result.map_err(|(at, problem)| FormatError::new(path, at.into(), problem))?;
    let count = positions.len();
    let mut soup = TriangleSoup {
        positions,
        triangles: Vec::new(),
    };
    for (f, corners) in faces.iter().enumerate() {
        let err = |problem| FormatError::new(path, Location::Face(f), problem);
        if corners.len() < 3 {
            return Err(err(Problem::FaceTooSmall {
                corners: corners.len(),
            }));
        }
        if let Some(&index) = corners.iter().find(|&&i| i < 0 || i >= count as i64) {
            return Err(err(Problem::IndexOutOfRange { index, count }));
        }
        let corners: Vec<u32> = corners.iter().map(|&i| i as u32).collect();
        push_fan(&mut soup.triangles, &corners);
    }
    Ok(soup)
}

/// Encodes a (checked) mesh as binary little-endian PLY with `x, y, z`
/// vertices and faces carrying `vertex_indices`, a normal and a material
/// label.
pub(super) fn encode(mesh: &TriangleMesh) -> Vec<u8> {
    let mut header = String::new();
    let _ = write!(
        header,
        "ply\nformat binary_little_endian 1.0\ncomment chisel surface mesh\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar uint vertex_indices\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty uchar material\n\
         end_header\n",
        mesh.positions.len(),
        mesh.indices.len()
    );
    let mut out = header.into_bytes();
    out.reserve(12 * mesh.positions.len() + 26 * mesh.indices.len());
    for p in &mesh.positions {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for ((triangle, normal), label) in mesh.indices.iter().zip(&mesh.normals).zip(&mesh.labels) {
        out.push(3);
        for v in triangle {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for c in normal {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out.push(*label);
    }
    out
}
