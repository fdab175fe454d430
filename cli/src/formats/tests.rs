//! Round trips (write → read → the same triangles), hand-written files of
//! every supported flavour, malformed input with the error it must give,
//! and random damage that must never panic.

use std::path::{Path, PathBuf};

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::mesh::{SurfaceMesh, TriangleMesh};
use chisel_bsp::tree::{BooleanOp, Bsp};

use super::*;

fn path(name: &str) -> PathBuf {
    PathBuf::from(name)
}

/// A surface with two materials and an interface: box `[0,10]³` of label 1
/// and box `[10,20]×[0,5]×[0,10]` of label 2 beside it.
fn two_material_mesh() -> TriangleMesh {
    let p = |x, y, z| IntPoint::new(x, y, z).unwrap();
    let solid = |min: IntPoint, max: IntPoint, label| {
        let mut arena = ConvexArena::new();
        let poly = arena.add_box(min, max).unwrap();
        Bsp::from_convex(&arena, poly, label)
    };
    let a = solid(p(0, 0, 0), p(10, 10, 10), 1);
    let b = solid(p(10, 0, 0), p(20, 5, 10), 2);
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(-64, -64, -64), p(64, 64, 64)).unwrap();
    let union = a.merge(&b, BooleanOp::Union, &mut arena, bounds);
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(-64, -64, -64), p(64, 64, 64)).unwrap();
    SurfaceMesh::from_faces(&union.boundary(&mut arena, bounds)).triangles()
}

/// A mesh with non-integer coordinates, so that printing must be exact.
fn fractional_mesh() -> TriangleMesh {
    TriangleMesh {
        positions: vec![
            [0.1, -0.0, 1e-7],
            [1.0 / 3.0, 2.5e6, -7.25],
            [-123.456, 0.2, 3.0e-3],
        ],
        indices: vec![[0, 1, 2]],
        normals: vec![[0.0, 0.0, 1.0]],
        labels: vec![7],
        outside: vec![0],
        on_bounds: vec![false],
        polygons: vec![0],
    }
}

type Triangle = [[f64; 3]; 3];

/// Triangles as coordinates, each rotated to start at its smallest corner
/// (orientation kept), sorted: equal for meshes with the same triangles in
/// any order and any vertex sharing.
fn canonical(triangles: impl Iterator<Item = Triangle>) -> Vec<Triangle> {
    let mut out: Vec<Triangle> = triangles
        .map(|t| {
            let first = (0..3)
                .min_by(|&i, &j| t[i].partial_cmp(&t[j]).unwrap())
                .unwrap();
            [t[first], t[(first + 1) % 3], t[(first + 2) % 3]]
        })
        .collect();
    out.sort_by(|a, b| a.partial_cmp(b).unwrap());
    out
}

fn mesh_triangles(mesh: &TriangleMesh) -> Vec<Triangle> {
    canonical(
        mesh.indices
            .iter()
            .map(|t| t.map(|v| mesh.positions[v as usize].map(f64::from))),
    )
}

fn soup_triangles(soup: &TriangleSoup) -> Vec<Triangle> {
    canonical(
        (0..soup.triangles.len()).map(|t| soup.triangles[t].map(|v| soup.positions[v as usize])),
    )
}

fn roundtrip(mesh: &TriangleMesh, format: MeshFormat) -> TriangleSoup {
    let bytes = encode_triangle_mesh(mesh, format).unwrap();
    parse_triangle_soup(&bytes, format, &path("roundtrip")).unwrap()
}

#[test]
fn every_format_round_trips_the_same_triangles() {
    for mesh in [two_material_mesh(), fractional_mesh()] {
        assert!(!mesh.is_empty());
        for format in [MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Glb] {
            let soup = roundtrip(&mesh, format);
            assert_eq!(soup.triangles.len(), mesh.len(), "{format:?}");
            assert_eq!(soup_triangles(&soup), mesh_triangles(&mesh), "{format:?}");
        }
        // OBJ and PLY keep the shared vertices too.
        for format in [MeshFormat::Obj, MeshFormat::Ply] {
            let soup = roundtrip(&mesh, format);
            let positions: Vec<[f64; 3]> =
                mesh.positions.iter().map(|p| p.map(f64::from)).collect();
            assert_eq!(soup.positions, positions, "{format:?}");
        }
    }
}

#[test]
fn files_are_written_and_read_by_extension() {
    let dir = std::env::temp_dir().join(format!("chisel-formats-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = two_material_mesh();
    for name in ["surface.obj", "surface.PLY", "surface.glb"] {
        let file = dir.join(name);
        write_triangle_mesh(&file, &mesh).unwrap();
        let soup = read_triangle_soup(&file).unwrap();
        assert_eq!(soup_triangles(&soup), mesh_triangles(&mesh), "{name}");
    }
    let err = write_triangle_mesh(&dir.join("surface.stl"), &mesh).unwrap_err();
    assert!(
        matches!(err.problem, Problem::UnknownFormat { .. }),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn glb_has_one_primitive_and_material_per_label() {
    let mesh = two_material_mesh();
    let bytes = encode_triangle_mesh(&mesh, MeshFormat::Glb).unwrap();
    let gltf = gltf::Gltf::from_slice(&bytes).unwrap();
    let primitives: Vec<_> = gltf
        .document
        .meshes()
        .flat_map(|m| m.primitives())
        .collect();
    assert_eq!(primitives.len(), 2);
    assert_eq!(gltf.document.materials().count(), 2);
    for p in &primitives {
        assert!(p.get(&gltf::Semantic::Normals).is_some());
        assert!(p.indices().is_some());
    }
    let json = String::from_utf8_lossy(&bytes);
    assert!(json.contains(r#""name":"material 1""#) && json.contains(r#""name":"material 2""#));
}

#[test]
fn empty_meshes_write_valid_files_that_read_as_no_triangles() {
    let empty = TriangleMesh::default();
    for format in [MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Glb] {
        let bytes = encode_triangle_mesh(&empty, format).unwrap();
        let err = parse_triangle_soup(&bytes, format, &path("empty")).unwrap_err();
        assert!(
            matches!(err.problem, Problem::NoTriangles),
            "{format:?}: {err}"
        );
    }
}

#[test]
fn inconsistent_meshes_are_not_written() {
    let mut mesh = fractional_mesh();
    mesh.indices[0][2] = 3;
    assert!(matches!(
        encode_triangle_mesh(&mesh, MeshFormat::Ply),
        Err(Problem::InvalidMesh { .. })
    ));
    let mut mesh = fractional_mesh();
    mesh.labels.clear();
    assert!(encode_triangle_mesh(&mesh, MeshFormat::Glb).is_err());
    let mut mesh = fractional_mesh();
    mesh.positions[1][0] = f32::NAN;
    assert!(encode_triangle_mesh(&mesh, MeshFormat::Obj).is_err());
}

#[test]
fn formats_follow_the_extension() {
    assert_eq!(
        MeshFormat::from_path(Path::new("a/b.OBJ")).unwrap(),
        MeshFormat::Obj
    );
    assert_eq!(
        MeshFormat::from_path(Path::new("x.ply")).unwrap(),
        MeshFormat::Ply
    );
    assert_eq!(
        MeshFormat::from_path(Path::new("x.glb")).unwrap(),
        MeshFormat::Glb
    );
    let err = MeshFormat::from_path(Path::new("x.gltf")).unwrap_err();
    assert!(err.to_string().contains("'.gltf'"), "{err}");
    let err = MeshFormat::from_path(Path::new("noext")).unwrap_err();
    assert!(err.to_string().contains("no file extension"), "{err}");
}

#[test]
fn a_missing_file_names_the_file() {
    let err = read_triangle_soup(Path::new("/nonexistent/dir/mesh.obj")).unwrap_err();
    assert!(matches!(&err.problem, Problem::Io(e) if e.kind() == std::io::ErrorKind::NotFound));
    assert!(
        err.to_string().starts_with("/nonexistent/dir/mesh.obj: "),
        "{err}"
    );
}

// ---- OBJ ------------------------------------------------------------------

fn obj(text: &str) -> Result<TriangleSoup, FormatError> {
    parse_triangle_soup(text.as_bytes(), MeshFormat::Obj, &path("test.obj"))
}

#[test]
fn obj_polygons_are_fan_triangulated_and_all_index_forms_read() {
    let soup = obj("# a quad and a pentagon\r\n\
         v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\n\
         vt 0 0\nvn 0 0 1\ng quad\ns off\nusemtl x\n\
         f 1/1/1 2/1/1 3/1/1 4/1/1\n\
         f -5//1 -1//1 -2//1 -3 -4 # relative\n")
    .unwrap();
    assert_eq!(soup.positions.len(), 5);
    assert_eq!(
        soup.triangles,
        [[0, 1, 2], [0, 2, 3], [0, 4, 3], [0, 3, 2], [0, 2, 1]]
    );
}

#[test]
fn obj_faces_may_precede_their_vertices() {
    let soup = obj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    assert_eq!(soup.triangles, [[0, 1, 2]]);
}

fn obj_error(text: &str) -> FormatError {
    obj(text).unwrap_err()
}

#[test]
fn malformed_obj_files_give_the_line_and_the_problem() {
    let e = obj_error("v 0 0 0\nv 1 0 zero\n");
    assert_eq!(e.location, Location::Line(2));
    assert!(
        matches!(&e.problem, Problem::MalformedNumber { text } if text == "zero"),
        "{e}"
    );
    assert_eq!(e.to_string(), "test.obj: line 2: malformed number 'zero'");

    let e = obj_error("v 0 0\n");
    assert!(
        matches!(
            e.problem,
            Problem::Missing {
                what: "z coordinate"
            }
        ),
        "{e}"
    );

    let e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\n");
    assert_eq!(e.location, Location::Line(4));
    assert!(matches!(e.problem, Problem::NonFinite { vertex: 3 }), "{e}");
    let e = obj_error("v 0 0 inf\n");
    assert!(matches!(e.problem, Problem::NonFinite { vertex: 0 }), "{e}");

    let e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n");
    assert_eq!(e.location, Location::Line(5));
    assert!(
        matches!(e.problem, Problem::IndexOutOfRange { index: 4, count: 3 }),
        "{e}"
    );
    let e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    assert!(
        matches!(e.problem, Problem::IndexOutOfRange { index: 0, .. }),
        "{e}"
    );
    let e = obj_error("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n");
    assert!(
        matches!(e.problem, Problem::IndexOutOfRange { index: -3, .. }),
        "{e}"
    );
    let e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x/1\n");
    assert!(
        matches!(&e.problem, Problem::MalformedNumber { text } if text == "x/1"),
        "{e}"
    );
    let e = obj_error("v 0 0 0\nv 1 0 0\nf 1 2\n");
    assert!(
        matches!(e.problem, Problem::FaceTooSmall { corners: 2 }),
        "{e}"
    );
    let e = obj_error("v 0 0 0\n# no faces\n");
    assert!(matches!(e.problem, Problem::NoTriangles), "{e}");
}

// ---- PLY ------------------------------------------------------------------

fn ply(bytes: &[u8]) -> Result<TriangleSoup, FormatError> {
    parse_triangle_soup(bytes, MeshFormat::Ply, &path("test.ply"))
}

const ASCII_CUBE: &str = "ply\r\nformat ascii 1.0\r\ncomment a unit cube\r\n\
element vertex 8\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n\
property uchar red\r\n\
element face 6\r\nproperty list uchar int vertex_indices\r\n\
element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\n\
end_header\r\n\
0 0 0 255\r\n1 0 0 255\r\n1 1 0 255\r\n0 1 0 255\r\n\
0 0 1 255\r\n1 0 1 255\r\n1 1 1 255\r\n0 1 1 255\r\n\
4 0 3 2 1\r\n4 4 5 6 7\r\n4 0 1 5 4\r\n4 2 3 7 6\r\n4 1 2 6 5\r\n4 3 0 4 7\r\n\
0 1\r\n";

#[test]
fn ascii_ply_quads_are_fan_triangulated() {
    let soup = ply(ASCII_CUBE.as_bytes()).unwrap();
    assert_eq!(soup.positions.len(), 8);
    assert_eq!(soup.positions[6], [1.0, 1.0, 1.0]);
    assert_eq!(soup.triangles.len(), 12);
    assert_eq!(soup.triangles[0], [0, 3, 2]);
    assert_eq!(soup.triangles[1], [0, 2, 1]);
}

/// A binary little-endian PLY with double coordinates, an extra property
/// before them, a `ushort`-counted list of `uint` indices and a second list
/// after it.
fn binary_ply(faces: &[&[u32]]) -> Vec<u8> {
    let mut out = b"ply\nformat binary_little_endian 1.0\n\
element vertex 4\nproperty short flags\nproperty double x\nproperty double y\nproperty double z\n\
element face "
        .to_vec();
    out.extend_from_slice(
        format!(
            "{}\nproperty list ushort uint vertex_index\nproperty list uchar float texcoord\nend_header\n",
            faces.len()
        )
        .as_bytes(),
    );
    for (i, p) in [
        [0.0, 0.0, 0.0],
        [1.5, 0.0, 0.0],
        [0.0, 2.5, 0.0],
        [0.0, 0.0, -3.25],
    ]
    .iter()
    .enumerate()
    {
        out.extend_from_slice(&(i as i16).to_le_bytes());
        for c in p {
            out.extend_from_slice(&f64::to_le_bytes(*c));
        }
    }
    for face in faces {
        out.extend_from_slice(&(face.len() as u16).to_le_bytes());
        for v in *face {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.push(2);
        out.extend_from_slice(&0.5f32.to_le_bytes());
        out.extend_from_slice(&0.25f32.to_le_bytes());
    }
    out
}

#[test]
fn binary_ply_with_other_types_and_properties_reads() {
    let soup = ply(&binary_ply(&[&[0, 2, 1], &[0, 1, 3], &[0, 3, 2, 1]])).unwrap();
    assert_eq!(soup.positions[3], [0.0, 0.0, -3.25]);
    assert_eq!(soup.triangles, [[0, 2, 1], [0, 1, 3], [0, 3, 2], [0, 2, 1]]);
}

#[test]
fn malformed_ply_files_give_the_location_and_the_problem() {
    let e = ply(b"plx\nformat ascii 1.0\nend_header\n").unwrap_err();
    assert_eq!(e.location, Location::Line(1));
    assert!(matches!(e.problem, Problem::Malformed { .. }), "{e}");

    let e = ply(b"ply\nformat binary_big_endian 1.0\nend_header\n").unwrap_err();
    assert!(matches!(e.problem, Problem::Unsupported { .. }), "{e}");

    let e = ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n").unwrap_err();
    assert!(matches!(e.problem, Problem::UnexpectedEnd), "{e}");

    let e = ply(b"ply\nformat ascii 1.0\nelement vertex many\nend_header\n").unwrap_err();
    assert_eq!(e.location, Location::Line(3));
    assert!(
        matches!(&e.problem, Problem::MalformedNumber { text } if text == "many"),
        "{e}"
    );

    let e = ply(b"ply\nformat ascii 1.0\nproperty float x\nend_header\n").unwrap_err();
    assert!(e.to_string().contains("property before any element"), "{e}");

    let e = ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n")
        .unwrap_err();
    assert!(e.to_string().contains("no property 'z'"), "{e}");

    // A malformed number on body line 10.
    let text = ASCII_CUBE.replace("1 1 0 255", "1 1,0 255");
    let e = ply(text.as_bytes()).unwrap_err();
    assert_eq!(e.location, Location::Line(17));
    assert!(
        matches!(&e.problem, Problem::MalformedNumber { text } if text == "1,0"),
        "{e}"
    );

    let text = ASCII_CUBE.replace("0 1 1 255", "0 1 NaN 255");
    let e = ply(text.as_bytes()).unwrap_err();
    assert!(matches!(e.problem, Problem::NonFinite { vertex: 7 }), "{e}");

    let text = ASCII_CUBE.replace("4 1 2 6 5", "4 1 2 6 8");
    let e = ply(text.as_bytes()).unwrap_err();
    assert_eq!(e.location, Location::Face(4));
    assert!(
        matches!(e.problem, Problem::IndexOutOfRange { index: 8, count: 8 }),
        "{e}"
    );

    let text = ASCII_CUBE.replace("4 1 2 6 5", "2 1 2");
    let e = ply(text.as_bytes()).unwrap_err();
    assert!(
        matches!(e.problem, Problem::FaceTooSmall { corners: 2 }),
        "{e}"
    );

    let text = ASCII_CUBE.replace("4 3 0 4 7\r\n0 1\r\n", "4 3 0 4 7\r\n");
    let e = ply(text.as_bytes()).unwrap_err();
    assert!(matches!(e.problem, Problem::UnexpectedEnd), "{e}");

    // Binary: truncated in the middle of the faces.
    let good = binary_ply(&[&[0, 2, 1], &[0, 1, 3]]);
    let e = ply(&good[..good.len() - 5]).unwrap_err();
    assert!(matches!(e.problem, Problem::UnexpectedEnd), "{e}");
    assert!(
        matches!(e.location, Location::Offset(o) if o as usize >= good.len() - 13),
        "{e}"
    );
    let e = ply(&binary_ply(&[&[0, 2, 7]])).unwrap_err();
    assert!(
        matches!(e.problem, Problem::IndexOutOfRange { index: 7, count: 4 }),
        "{e}"
    );
}

// ---- GLB ------------------------------------------------------------------

fn glb(bytes: &[u8]) -> Result<TriangleSoup, FormatError> {
    parse_triangle_soup(bytes, MeshFormat::Glb, &path("test.glb"))
}

/// A GLB of one quad as a triangle strip with `u16` indices, placed by a
/// translated parent node and a scaled child node.
fn strip_glb(index_count: usize) -> Vec<u8> {
    let mut bin = Vec::new();
    for p in [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"translation":[10,0,0],"children":[1]}},{{"scale":[2,2,2],"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":5}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5123,"count":{index_count},"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":8}}],
        "buffers":[{{"byteLength":56}}]}}"#
    );
    glb_write::container(json.into_bytes(), bin)
}

#[test]
fn glb_strips_and_node_transforms_are_read() {
    let soup = glb(&strip_glb(4)).unwrap();
    assert_eq!(
        soup.positions,
        [
            [10.0, 0.0, 0.0],
            [12.0, 0.0, 0.0],
            [10.0, 2.0, 0.0],
            [12.0, 2.0, 0.0]
        ]
    );
    // Both strip triangles keep the first one's orientation.
    assert_eq!(soup.triangles, [[0, 1, 2], [2, 1, 3]]);
}

#[test]
fn malformed_glb_files_are_errors() {
    let e = glb(b"{\"asset\":{\"version\":\"2.0\"}}").unwrap_err();
    assert!(e.to_string().contains("no 'glTF' magic"), "{e}");

    // An accessor reading past its buffer view.
    let e = glb(&strip_glb(6)).unwrap_err();
    assert_eq!(
        e.location,
        Location::Primitive {
            mesh: 0,
            primitive: 0
        }
    );
    assert!(e.to_string().contains("runs past its buffer view"), "{e}");

    // Truncated: the container's length says more than there is.
    let good = encode_triangle_mesh(&two_material_mesh(), MeshFormat::Glb).unwrap();
    let e = glb(&good[..good.len() / 2]).unwrap_err();
    assert!(matches!(e.problem, Problem::UnexpectedEnd), "{e}");
    assert!(matches!(e.location, Location::Offset(_)), "{e}");

    // JSON that is not glTF.
    let e = glb(&glb_write::container(b"{\"asset\":5}".to_vec(), Vec::new())).unwrap_err();
    assert!(matches!(e.problem, Problem::Gltf { .. }), "{e}");

    // A primitive naming an accessor that does not exist.
    let json =
        br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":3}}]}]}"#;
    let e = glb(&glb_write::container(json.to_vec(), Vec::new())).unwrap_err();
    assert!(e.to_string().contains("no accessor 3"), "{e}");

    // A node that is its own child.
    let json =
        br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"children":[0]}]}"#;
    let e = glb(&glb_write::container(json.to_vec(), Vec::new())).unwrap_err();
    assert!(e.to_string().contains("reached twice"), "{e}");
}

// ---- Damage ---------------------------------------------------------------

/// Truncations and byte flips of valid files: each is read or rejected,
/// never a panic.
#[test]
fn damaged_files_never_panic() {
    let mesh = two_material_mesh();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut files: Vec<(MeshFormat, Vec<u8>)> = [MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Glb]
        .iter()
        .map(|&f| (f, encode_triangle_mesh(&mesh, f).unwrap()))
        .collect();
    files.push((MeshFormat::Ply, ASCII_CUBE.as_bytes().to_vec()));
    files.push((MeshFormat::Ply, binary_ply(&[&[0, 2, 1], &[0, 1, 3]])));
    files.push((MeshFormat::Glb, strip_glb(4)));
    let mut rejected = 0;
    for (format, good) in &files {
        for round in 0..1000 {
            let mut bytes = good.clone();
            if round % 3 == 0 {
                bytes.truncate(next() as usize % good.len());
            } else {
                for _ in 0..1 + next() % 4 {
                    let i = next() as usize % bytes.len();
                    bytes[i] = next() as u8;
                }
            }
            if parse_triangle_soup(&bytes, *format, &path("damaged")).is_err() {
                rejected += 1;
            }
        }
    }
    assert!(rejected > 0);
}

/// [`strip_glb`]'s quad with its buffer in an external file `uri`.
fn external_glb(uri: &str) -> (Vec<u8>, Vec<u8>) {
    let with_bin = strip_glb(4);
    let soup_json = {
        let json_len = u32::from_le_bytes(with_bin[12..16].try_into().unwrap()) as usize;
        String::from_utf8(with_bin[20..20 + json_len].to_vec()).unwrap()
    };
    let json = soup_json.replace(
        r#""buffers":[{"byteLength":56}]"#,
        &format!(r#""buffers":[{{"byteLength":56,"uri":"{uri}"}}]"#),
    );
    assert_ne!(json, soup_json);
    let bin_at = 20 + soup_json.len().next_multiple_of(4) + 8;
    let bin = with_bin[bin_at..bin_at + 56].to_vec();
    (
        glb_write::container(json.trim_end().as_bytes().to_vec(), Vec::new()),
        bin,
    )
}

/// External buffers are read only from regular files inside the GLB's
/// folder: no `..`, absolute paths, devices, pipes, folders or links out.
#[test]
fn external_buffers_stay_inside_the_files_folder() {
    let dir = std::env::temp_dir().join(format!("chisel-glb-uri-{}", std::process::id()));
    let sub = dir.join("sub");
    std::fs::create_dir_all(sub.join("folder.bin")).unwrap();
    let (_, bin) = external_glb("quad.bin");
    std::fs::write(sub.join("quad.bin"), &bin).unwrap();
    std::fs::write(dir.join("outside.bin"), &bin).unwrap();
    let _ = std::fs::remove_file(sub.join("link.bin"));
    std::os::unix::fs::symlink(dir.join("outside.bin"), sub.join("link.bin")).unwrap();
    let _ = std::fs::remove_file(sub.join("pipe.bin"));
    let made = std::process::Command::new("mkfifo")
        .arg(sub.join("pipe.bin"))
        .status()
        .is_ok_and(|s| s.success());
    let at = sub.join("test.glb");
    let read = |uri: &str| parse_triangle_soup(&external_glb(uri).0, MeshFormat::Glb, &at);
    assert_eq!(read("quad.bin").unwrap().triangles.len(), 2);
    for uri in [
        "../outside.bin",
        "/dev/zero",
        "/etc/hostname",
        "file:///etc/hostname",
        "./quad.bin",
        "link.bin",
        "folder.bin",
        "missing.bin",
    ] {
        let e = read(uri).unwrap_err().to_string();
        assert!(
            e.contains("URI") || e.contains("No such file"),
            "{uri}: {e}"
        );
    }
    if made {
        // Before: blocked forever opening the pipe.
        let e = read("pipe.bin").unwrap_err().to_string();
        assert!(e.contains("regular file"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mirroring node transform (negative determinant) reverses the
/// winding, so the faces still point outwards: the quad of [`strip_glb`]
/// faces +z with scale `[2, 2, 2]` and with `[-2, 2, 2]`.
#[test]
fn mirrored_glb_nodes_keep_faces_outward() {
    let normal_z = |soup: &TriangleSoup| -> Vec<f64> {
        soup.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| soup.positions[v as usize]);
                (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
            })
            .collect()
    };
    let plain = glb(&strip_glb(4)).unwrap();
    assert!(normal_z(&plain).iter().all(|&z| z > 0.0));
    let bytes = strip_glb(4);
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json = String::from_utf8(bytes[20..20 + json_len].to_vec()).unwrap();
    let mirrored_json = json.replace(r#""scale":[2,2,2]"#, r#""scale":[-2,2,2]"#);
    assert_ne!(json, mirrored_json);
    let bin = bytes[20 + json_len + 8..].to_vec();
    let mirrored = glb(&glb_write::container(mirrored_json.into_bytes(), bin)).unwrap();
    assert_eq!(mirrored.positions[1], [8.0, 0.0, 0.0]);
    assert!(normal_z(&mirrored).iter().all(|&z| z > 0.0), "{mirrored:?}");
}
