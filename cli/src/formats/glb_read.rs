//! Binary glTF in. The container (12-byte header, JSON chunk, optional
//! binary chunk) is split here; the JSON is deserialized into the `gltf`
//! crate's schema types (`gltf::json`), and everything after that is read
//! here with every index and byte range checked first, so a corrupt file is
//! an error, never a panic. (The crate's own validation and its wrapper
//! types index without checking, so they are not used on untrusted input.)
//!
//! The meshes of the default scene (or the first scene; or every mesh when
//! there is none) are placed by their nodes' global transforms. Primitives
//! in triangle, strip and fan modes are read; points and lines have no
//! faces and are skipped. Positions must be `float` vectors; indices
//! unsigned bytes, shorts or ints (or absent: consecutive triangles).

use std::borrow::Cow;
use std::path::Path;

use glam::{DMat4, DQuat, DVec3};
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;

use super::{FormatError, Location, Problem, TriangleSoup};

fn malformed(reason: String) -> Problem {
    Problem::Malformed { reason }
}

fn to_usize(value: u64, what: &str) -> Result<usize, Problem> {
    usize::try_from(value).map_err(|_| malformed(format!("{what} {value} is too large")))
}

/// Splits a GLB into its JSON chunk and optional binary chunk (glTF 2.0
/// §4.4), checking every length against the data.
/// The JSON chunk and the binary chunk, if any.
type Chunks<'a> = (&'a [u8], Option<&'a [u8]>);

/// A problem at a byte offset.
type AtOffset = (u64, Problem);

fn split_container(bytes: &[u8]) -> Result<Chunks<'_>, AtOffset> {
    let u32_at = |offset: usize| -> Result<u32, AtOffset> {
        bytes
            .get(offset..offset + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or((offset as u64, Problem::UnexpectedEnd))
    };
    if !bytes.starts_with(b"glTF") {
        return Err((
            0,
            malformed("not a binary glTF file (no 'glTF' magic)".into()),
        ));
    }
    let version = u32_at(4)?;
    if version != 2 {
        return Err((
            4,
            Problem::Unsupported {
                what: format!("glTF container version {version} (only 2)"),
            },
        ));
    }
    let length = u32_at(8)? as usize;
    if length > bytes.len() {
        return Err((bytes.len() as u64, Problem::UnexpectedEnd));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut offset = 12;
    while offset < bytes.len() && chunks.len() < 2 {
        let chunk_length = u32_at(offset)? as usize;
        let kind = bytes
            .get(offset + 4..offset + 8)
            .ok_or((offset as u64 + 4, Problem::UnexpectedEnd))?;
        let start = offset + 8;
        let data = bytes
            .get(start..start + chunk_length)
            .ok_or((bytes.len() as u64, Problem::UnexpectedEnd))?;
        chunks.push((offset, kind, data));
        offset = start + chunk_length.next_multiple_of(4);
    }
    match chunks.as_slice() {
        [(_, b"JSON", json)] => Ok((json, None)),
        [(_, b"JSON", json), (_, b"BIN\0", bin), ..] => Ok((json, Some(bin))),
        [(_, b"JSON", json), (_, _, _), ..] => Ok((json, None)),
        [(at, _, _), ..] => Err((*at as u64, malformed("the first chunk is not JSON".into()))),
        [] => Err((12, Problem::UnexpectedEnd)),
    }
}

/// Parses GLB content; external buffers are read relative to `path`.
pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<TriangleSoup, FormatError> {
    let file_err = |problem| FormatError::new(path, Location::File, problem);
    let (json_chunk, bin) = split_container(bytes)
        .map_err(|(offset, problem)| FormatError::new(path, Location::Offset(offset), problem))?;
    let root: json::Root = json::deserialize::from_slice(json_chunk).map_err(|e| {
        file_err(Problem::Gltf {
            reason: e.to_string(),
        })
    })?;
    let buffers = load_buffers(&root, bin, path)?;
    let placed = placed_meshes(&root).map_err(file_err)?;

    let mut soup = TriangleSoup::default();
    for (mesh_index, transform) in placed {
        let Some(mesh) = root.meshes.get(mesh_index) else {
            return Err(file_err(malformed(format!("no mesh {mesh_index}"))));
        };
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = Location::Primitive {
                mesh: mesh_index,
                primitive: p,
            };
            read_primitive(&root, primitive, &buffers, transform, &mut soup)
                .map_err(|problem| FormatError::new(path, at, problem))?;
        }
    }
    Ok(soup)
}

/// The bytes of every buffer: the GLB's binary chunk or a file next to
/// `path`.
fn load_buffers<'a>(
    root: &json::Root,
    bin: Option<&'a [u8]>,
    path: &Path,
) -> Result<Vec<Cow<'a, [u8]>>, FormatError> {
    let file_err = |problem| FormatError::new(path, Location::File, problem);
    let mut buffers = Vec::new();
    for (i, buffer) in root.buffers.iter().enumerate() {
        let data: Cow<[u8]> = match (buffer.uri.as_deref(), bin) {
            (None, Some(bin)) if i == 0 => Cow::Borrowed(bin),
            (None, _) => {
                return Err(file_err(malformed(format!(
                    "buffer {i} has no URI and there is no binary chunk for it"
                ))));
            }
            (Some(uri), _) if uri.starts_with("data:") => {
                return Err(file_err(Problem::Unsupported {
                    what: format!(
                        "buffer {i} embedded as a data URI (store it in the GLB's binary chunk)"
                    ),
                }));
            }
            (Some(uri), _) => Cow::Owned(read_external(path, i, uri)?),
        };
        let declared = buffer.byte_length.0;
        if (data.len() as u64) < declared {
            return Err(file_err(malformed(format!(
                "buffer {i} declares {declared} bytes but has {}",
                data.len()
            ))));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The most bytes of one external buffer file.
pub const MAX_EXTERNAL_BUFFER: u64 = 1 << 30;

/// The bytes of buffer `i`'s external file `uri`, relative to the GLB at
/// `path`: a relative path with no `..` that stays, links resolved, inside
/// the GLB's folder, names a regular file (no device, pipe or folder), and
/// holds at most [`MAX_EXTERNAL_BUFFER`] bytes.
fn read_external(path: &Path, i: usize, uri: &str) -> Result<Vec<u8>, FormatError> {
    use std::io::Read;
    let refuse = |why: String| {
        FormatError::new(
            path,
            Location::File,
            malformed(format!("buffer {i}'s URI `{uri}` {why}")),
        )
    };
    let relative = Path::new(uri);
    if uri.contains(':')
        || uri.contains('\\')
        || relative.is_absolute()
        || relative
            .components()
            .any(|c| !matches!(c, std::path::Component::Normal(_)))
    {
        return Err(refuse(
            "is not a plain relative path inside the file's folder (no scheme, no leading \
             `/`, no `.` or `..`)"
                .into(),
        ));
    }
    let io =
        |file: &Path, e: std::io::Error| FormatError::new(file, Location::File, Problem::Io(e));
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let folder = std::fs::canonicalize(parent).map_err(|e| io(parent, e))?;
    let joined = folder.join(relative);
    let file = std::fs::canonicalize(&joined).map_err(|e| io(&joined, e))?;
    if !file.starts_with(&folder) {
        return Err(refuse(
            "leads out of the file's folder (through a link)".into(),
        ));
    }
    let meta = std::fs::metadata(&file).map_err(|e| io(&file, e))?;
    if !meta.is_file() {
        return Err(refuse("does not name a regular file".into()));
    }
    if meta.len() > MAX_EXTERNAL_BUFFER {
        return Err(refuse(format!(
            "names a file of {} bytes, over the limit of {MAX_EXTERNAL_BUFFER}",
            meta.len()
        )));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(&file)
        .and_then(|f| f.take(MAX_EXTERNAL_BUFFER + 1).read_to_end(&mut bytes))
        .map_err(|e| io(&file, e))?;
    if bytes.len() as u64 > MAX_EXTERNAL_BUFFER {
        return Err(refuse(format!(
            "grew past the limit of {MAX_EXTERNAL_BUFFER} bytes"
        )));
    }
    Ok(bytes)
}

/// The local transform of a node: its matrix, or translation · rotation ·
/// scale.
fn local_transform(node: &json::Node) -> Result<DMat4, Problem> {
    if let Some(m) = node.matrix {
        return Ok(DMat4::from_cols_array(&m.map(f64::from)));
    }
    let t = node.translation.unwrap_or([0.0; 3]).map(f64::from);
    let s = node.scale.unwrap_or([1.0; 3]).map(f64::from);
    let [x, y, z, w] = node
        .rotation
        .map_or([0.0, 0.0, 0.0, 1.0], |r| r.0.map(f64::from));
    let q = DQuat::from_xyzw(x, y, z, w);
    if !q.is_finite() || q.length_squared() == 0.0 {
        return Err(malformed(format!(
            "node rotation {:?} is not a rotation",
            [x, y, z, w]
        )));
    }
    Ok(DMat4::from_scale_rotation_translation(
        DVec3::from(s),
        q.normalize(),
        DVec3::from(t),
    ))
}

/// Every placed mesh with its global transform, in scene order.
fn placed_meshes(root: &json::Root) -> Result<Vec<(usize, DMat4)>, Problem> {
    let scene = match root.scene {
        Some(i) => Some(
            root.scenes
                .get(i.value())
                .ok_or_else(|| malformed(format!("no scene {}", i.value())))?,
        ),
        None => root.scenes.first(),
    };
    let Some(scene) = scene else {
        return Ok((0..root.meshes.len())
            .map(|m| (m, DMat4::IDENTITY))
            .collect());
    };
    // glTF nodes form disjoint trees: a node reached twice means a cycle or
    // a shared child, which the format forbids.
    let mut visited = vec![false; root.nodes.len()];
    let mut placed = Vec::new();
    let mut stack: Vec<(usize, DMat4)> = scene
        .nodes
        .iter()
        .rev()
        .map(|n| (n.value(), DMat4::IDENTITY))
        .collect();
    while let Some((n, parent)) = stack.pop() {
        match visited.get_mut(n) {
            None => return Err(malformed(format!("no node {n}"))),
            Some(true) => {
                return Err(malformed(format!(
                    "node {n} is reached twice (a cycle or a shared child)"
                )));
            }
            Some(seen) => *seen = true,
        }
        let node = &root.nodes[n];
        let global = parent * local_transform(node)?;
        if let Some(mesh) = node.mesh {
            placed.push((mesh.value(), global));
        }
        if let Some(children) = &node.children {
            stack.extend(children.iter().rev().map(|c| (c.value(), global)));
        }
    }
    Ok(placed)
}

/// The bytes of element `i` of an accessor are
/// `data[start + i·stride ..][..size]`.
struct Elements<'b> {
    data: &'b [u8],
    start: usize,
    stride: usize,
    count: usize,
}

impl Elements<'_> {
    fn element(&self, i: usize) -> &[u8] {
        &self.data[self.start + i * self.stride..]
    }
}

/// Accessor `index`, checked to be of one of `types` with `dimensions`
/// and to lie within its view and buffer; returns its component type and
/// where its elements lie.
fn elements<'b>(
    root: &json::Root,
    index: usize,
    types: &[ComponentType],
    dimensions: Type,
    buffers: &'b [Cow<[u8]>],
) -> Result<(ComponentType, Elements<'b>), Problem> {
    let what = format!("accessor {index}");
    let accessor = root
        .accessors
        .get(index)
        .ok_or_else(|| malformed(format!("no {what}")))?;
    let component = match (&accessor.component_type, &accessor.type_) {
        (Checked::Valid(c), Checked::Valid(t)) if types.contains(&c.0) && *t == dimensions => c.0,
        _ => {
            return Err(Problem::Unsupported {
                what: format!(
                    "{what}: component type or shape (expected {types:?} {dimensions:?})"
                ),
            });
        }
    };
    if accessor.sparse.is_some() {
        return Err(Problem::Unsupported {
            what: format!("{what} is sparse"),
        });
    }
    let view_index = accessor.buffer_view.ok_or_else(|| Problem::Unsupported {
        what: format!("{what} has no buffer view"),
    })?;
    let view = root
        .buffer_views
        .get(view_index.value())
        .ok_or_else(|| malformed(format!("{what}: no buffer view {}", view_index.value())))?;
    let data = buffers
        .get(view.buffer.value())
        .ok_or_else(|| malformed(format!("{what}: no buffer {}", view.buffer.value())))?;
    let size = component.size() * dimensions.multiplicity();
    let stride = view.byte_stride.map_or(size, |s| s.0);
    if stride < size {
        return Err(malformed(format!(
            "{what}: stride {stride} below element size {size}"
        )));
    }
    let view_offset = to_usize(view.byte_offset.map_or(0, |o| o.0), "buffer view offset")?;
    let view_length = to_usize(view.byte_length.0, "buffer view length")?;
    if view_offset
        .checked_add(view_length)
        .is_none_or(|end| end > data.len())
    {
        return Err(malformed(format!(
            "buffer view {} runs past its buffer",
            view_index.value()
        )));
    }
    let offset = to_usize(accessor.byte_offset.map_or(0, |o| o.0), "accessor offset")?;
    let count = to_usize(accessor.count.0, "accessor count")?;
    if count > 0 {
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(offset))
            .and_then(|x| x.checked_add(size));
        if end.is_none_or(|end| end > view_length) {
            return Err(malformed(format!("{what} runs past its buffer view")));
        }
    }
    Ok((
        component,
        Elements {
            data,
            start: view_offset + offset,
            stride,
            count,
        },
    ))
}

fn read_primitive(
    root: &json::Root,
    primitive: &json::mesh::Primitive,
    buffers: &[Cow<[u8]>],
    transform: DMat4,
    soup: &mut TriangleSoup,
) -> Result<(), Problem> {
    let mode = match primitive.mode {
        Checked::Valid(mode) => mode,
        Checked::Invalid => return Err(malformed("unknown primitive mode".into())),
    };
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(());
    }
    let position_accessor = primitive
        .attributes
        .get(&Checked::Valid(Semantic::Positions))
        .ok_or_else(|| malformed("primitive has no POSITION attribute".into()))?;
    let (_, positions) = elements(
        root,
        position_accessor.value(),
        &[ComponentType::F32],
        Type::Vec3,
        buffers,
    )?;
    let base = soup.positions.len();
    let count = positions.count;
    if u32::try_from(base + count).is_err() {
        return Err(Problem::Unsupported {
            what: "more than 2^32 − 1 vertices".into(),
        });
    }
    for i in 0..count {
        let b = positions.element(i);
        let c = |k: usize| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
        let p = transform.transform_point3(DVec3::new(c(0).into(), c(1).into(), c(2).into()));
        if !p.is_finite() {
            return Err(Problem::NonFinite { vertex: i });
        }
        soup.positions.push(p.to_array());
    }

    let indices: Vec<u32> = match primitive.indices {
        None => (0..count as u32).collect(),
        Some(accessor) => {
            let (component, e) = elements(
                root,
                accessor.value(),
                &[ComponentType::U8, ComponentType::U16, ComponentType::U32],
                Type::Scalar,
                buffers,
            )?;
            (0..e.count)
                .map(|i| {
                    let b = e.element(i);
                    match component {
                        ComponentType::U8 => b[0] as u32,
                        ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    }
                })
                .collect()
        }
    };
    if let Some(&index) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(Problem::IndexOutOfRange {
            index: index.into(),
            count,
        });
    }
    let v = |i: usize| base as u32 + indices[i];
    let first = soup.triangles.len();
    match mode {
        Mode::TriangleStrip => {
            for i in 0..indices.len().saturating_sub(2) {
                // Every other triangle of a strip is flipped back to keep
                // the orientation.
                soup.triangles.push(if i % 2 == 0 {
                    [v(i), v(i + 1), v(i + 2)]
                } else {
                    [v(i + 1), v(i), v(i + 2)]
                });
            }
        }
        Mode::TriangleFan => {
            for i in 1..indices.len().saturating_sub(1) {
                soup.triangles.push([v(0), v(i), v(i + 1)]);
            }
        }
        _ => {
            for i in 0..indices.len() / 3 {
                soup.triangles.push([v(3 * i), v(3 * i + 1), v(3 * i + 2)]);
            }
        }
    }
    // A mirroring transform (negative determinant) turns counter-clockwise
    // corners clockwise: glTF says to reverse the winding then.
    if transform.determinant() < 0.0 {
        for t in &mut soup.triangles[first..] {
            t.swap(1, 2);
        }
    }
    Ok(())
}
