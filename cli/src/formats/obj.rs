//! Wavefront OBJ: `v x y z` vertices and `f` faces (`i`, `i/t`, `i//n`,
//! `i/t/n`; 1-based, or negative for relative to the vertices so far);
//! every other statement is ignored. Written with exact `f32` values, one
//! normal per triangle, and a group per material label.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use chisel_bsp::mesh::TriangleMesh;

use super::{FormatError, Location, Problem, TriangleSoup, push_fan};

/// A face as read: its line and corners as 0-based indices, to be checked
/// once all vertices are known (faces may come before their vertices).
struct Face {
    line: usize,
    corners: Vec<(i64, i64)>,
}

/// Parses OBJ content.
pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<TriangleSoup, FormatError> {
    let mut soup = TriangleSoup::default();
    let mut faces = Vec::new();
    for (number, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = number + 1;
        let err = |problem| FormatError::new(path, Location::Line(line), problem);
        let text = String::from_utf8_lossy(raw);
        let text = text.split('#').next().unwrap_or("");
        let mut tokens = text.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut p = [0.0; 3];
                for (c, what) in p
                    .iter_mut()
                    .zip(["x coordinate", "y coordinate", "z coordinate"])
                {
                    let token = tokens
                        .next()
                        .ok_or_else(|| err(Problem::Missing { what }))?;
                    *c = token.parse::<f64>().map_err(|_| {
                        err(Problem::MalformedNumber {
                            text: token.to_string(),
                        })
                    })?;
                }
                if p.iter().any(|c| !c.is_finite()) {
                    return Err(err(Problem::NonFinite {
                        vertex: soup.positions.len(),
                    }));
                }
                soup.positions.push(p);
            }
            Some("f") => {
                let mut corners = Vec::new();
                for token in tokens {
                    let index_text = token.split('/').next().unwrap_or("");
                    let index: i64 = index_text.parse().map_err(|_| {
                        err(Problem::MalformedNumber {
                            text: token.to_string(),
                        })
                    })?;
                    // 1-based, or relative to the vertices read so far.
                    let absolute = match index {
                        0 => -1,
                        i if i > 0 => i - 1,
                        i => soup.positions.len() as i64 + i,
                    };
                    corners.push((index, absolute));
                }
                if corners.len() < 3 {
                    return Err(err(Problem::FaceTooSmall {
                        corners: corners.len(),
                    }));
                }
                faces.push(Face { line, corners });
            }
            _ => {}
        }
    }
    let count = soup.positions.len();
    if u32::try_from(count).is_err() {
        return Err(FormatError::new(
            path,
            Location::File,
            Problem::Unsupported {
                what: format!("{count} vertices (at most 2^32 − 1)"),
            },
        ));
    }
    for face in &faces {
        let mut corners = Vec::with_capacity(face.corners.len());
        for &(index, absolute) in &face.corners {
            if absolute < 0 || absolute >= count as i64 {
                return Err(FormatError::new(
                    path,
                    Location::Line(face.line),
                    Problem::IndexOutOfRange { index, count },
                ));
            }
            corners.push(absolute as u32);
        }
        push_fan(&mut soup.triangles, &corners);
    }
    Ok(soup)
}

/// Encodes a (checked) mesh as OBJ: positions and normals printed as the
/// exact decimal of their `f32` values, triangles grouped by label.
pub(super) fn encode(mesh: &TriangleMesh) -> Vec<u8> {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# chisel surface mesh: {} vertices, {} triangles",
        mesh.positions.len(),
        mesh.indices.len()
    );
    for p in &mesh.positions {
        let [x, y, z] = p.map(f64::from);
        let _ = writeln!(out, "v {x} {y} {z}");
    }
    for n in &mesh.normals {
        let [x, y, z] = n.map(f64::from);
        let _ = writeln!(out, "vn {x} {y} {z}");
    }
    let mut by_label: BTreeMap<u8, Vec<usize>> = BTreeMap::new();
    for (t, &label) in mesh.labels.iter().enumerate() {
        by_label.entry(label).or_default().push(t);
    }
    for (label, triangles) in by_label {
        let _ = writeln!(out, "g material_{label}");
        for t in triangles {
            let [a, b, c] = mesh.indices[t].map(|v| v + 1);
            let n = t + 1;
            let _ = writeln!(out, "f {a}//{n} {b}//{n} {c}//{n}");
        }
    }
    out.into_bytes()
}
