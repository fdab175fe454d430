//! Binary glTF out, written directly: a 12-byte header, a JSON chunk and a
//! binary chunk (glTF 2.0 §4.4). One node, one mesh, and per material label
//! one primitive with its own material; vertices are duplicated per
//! triangle (flat shading) so each carries its face's exact normal.
//!
//! Per primitive the binary chunk holds `POSITION` (float VEC3, with the
//! `min`/`max` the format requires), `NORMAL` (float VEC3) and the indices
//! (unsigned int), each in its own 4-byte aligned buffer view.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use chisel_bsp::mesh::TriangleMesh;

/// `componentType` of `float` and `unsigned int`.
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
/// Buffer view targets: vertex attributes and indices.
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// Base colours by label (label 1 first), cycling.
const PALETTE: [[f32; 3]; 8] = [
    [0.62, 0.60, 0.56],
    [0.55, 0.38, 0.24],
    [0.80, 0.66, 0.22],
    [0.30, 0.45, 0.62],
    [0.42, 0.58, 0.34],
    [0.68, 0.32, 0.30],
    [0.50, 0.40, 0.62],
    [0.85, 0.85, 0.82],
];

/// Encodes a (checked) mesh as GLB.
pub(super) fn encode(mesh: &TriangleMesh) -> Vec<u8> {
    let mut by_label: BTreeMap<u8, Vec<usize>> = BTreeMap::new();
    for (t, &label) in mesh.labels.iter().enumerate() {
        by_label.entry(label).or_default().push(t);
    }
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut primitives, mut materials) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (label, triangles) in &by_label {
        let n = 3 * triangles.len();
        let (mut min, mut max) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let mut view = |bin: &mut Vec<u8>, bytes: &[u8], target: u32| -> usize {
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{},"byteLength":{},"target":{target}}}"#,
                bin.len(),
                bytes.len()
            ));
            bin.extend_from_slice(bytes);
            views.len() - 1
        };
        let mut positions = Vec::with_capacity(12 * n);
        let mut normals = Vec::with_capacity(12 * n);
        for &t in triangles {
            for &v in &mesh.indices[t] {
                let p = mesh.positions[v as usize];
                for k in 0..3 {
                    min[k] = min[k].min(p[k]);
                    max[k] = max[k].max(p[k]);
                    positions.extend_from_slice(&p[k].to_le_bytes());
                    normals.extend_from_slice(&mesh.normals[t][k].to_le_bytes());
                }
            }
        }
        let indices: Vec<u8> = (0..n as u32).flat_map(u32::to_le_bytes).collect();
        let position_view = view(&mut bin, &positions, ARRAY_BUFFER);
        let normal_view = view(&mut bin, &normals, ARRAY_BUFFER);
        let index_view = view(&mut bin, &indices, ELEMENT_ARRAY_BUFFER);
        let a = accessors.len();
        accessors.push(format!(
            r#"{{"bufferView":{position_view},"componentType":{FLOAT},"count":{n},"type":"VEC3","min":{},"max":{}}}"#,
            json_vec3(min),
            json_vec3(max)
        ));
        accessors.push(format!(
            r#"{{"bufferView":{normal_view},"componentType":{FLOAT},"count":{n},"type":"VEC3"}}"#
        ));
        accessors.push(format!(
            r#"{{"bufferView":{index_view},"componentType":{UNSIGNED_INT},"count":{n},"type":"SCALAR"}}"#
        ));
        let m = materials.len();
        let [r, g, b] = PALETTE[(*label as usize + PALETTE.len() - 1) % PALETTE.len()];
        materials.push(format!(
            r#"{{"name":"material {label}","pbrMetallicRoughness":{{"baseColorFactor":[{r},{g},{b},1.0],"metallicFactor":0.0,"roughnessFactor":0.9}}}}"#
        ));
        primitives.push(format!(
            r#"{{"attributes":{{"POSITION":{a},"NORMAL":{}}},"indices":{},"material":{m},"mode":4}}"#,
            a + 1,
            a + 2
        ));
    }

    let mut json = String::from(r#"{"asset":{"version":"2.0","generator":"chisel"},"scene":0,"#);
    if primitives.is_empty() {
        json.push_str(r#""scenes":[{"nodes":[]}]}"#);
    } else {
        let _ = write!(
            json,
            r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"name":"surface"}}],"meshes":[{{"name":"surface","primitives":[{}]}}],"materials":[{}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{"byteLength":{}}}]}}"#,
            primitives.join(","),
            materials.join(","),
            accessors.join(","),
            views.join(","),
            bin.len()
        );
    }
    container(json.into_bytes(), bin)
}

/// A JSON array of three `f32`s, printed as their exact decimal values.
fn json_vec3(v: [f32; 3]) -> String {
    let [x, y, z] = v.map(f64::from);
    format!("[{x},{y},{z}]")
}

/// The GLB container: header, JSON chunk (space-padded), and the binary
/// chunk (zero-padded) when there is one.
pub(super) fn container(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}
