//! Property-based fuzzing of the command line's readers: mesh files (OBJ,
//! ASCII and binary PLY, GLB) and replay sequences (JSON lines), from
//! valid files damaged at random and from random bytes. A reader never
//! panics; what it accepts is consistent (every index names a vertex,
//! every position is finite; every step a hull of at least four points).
//! The case count is small in the normal run; `scripts/fuzz` raises it
//! (`PROPTEST_CASES`).

use std::path::Path;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::mesh::{SurfaceMesh, TriangleMesh};
use chisel_bsp::tree::{BooleanOp, Bsp};
use proptest::prelude::*;

use crate::formats::{MeshFormat, encode_triangle_mesh, parse_triangle_soup};
use crate::scenario::jsonl;

/// `PROPTEST_CASES` when set (long runs), else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// Two boxes of different materials side by side, as a surface mesh.
fn mesh() -> TriangleMesh {
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

/// A binary little-endian PLY of `mesh` (the writer's PLY is ASCII).
fn binary_ply(mesh: &TriangleMesh) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.indices.len()
    )
    .into_bytes();
    for p in &mesh.positions {
        for c in p {
            out.extend(c.to_le_bytes());
        }
    }
    for t in &mesh.indices {
        out.push(3);
        for v in t {
            out.extend((*v as i32).to_le_bytes());
        }
    }
    out
}

/// A random edit of a byte string.
#[derive(Clone, Debug)]
enum Damage {
    Flip(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Overwrite(usize, Vec<u8>),
    /// Repeats a run, as a duplicated line or record does.
    Repeat(usize, usize),
}

fn damage() -> impl Strategy<Value = Damage> {
    let run = || {
        proptest::collection::vec(
            prop_oneof![
                any::<u8>(),
                // Bytes that matter to the text formats.
                prop::sample::select(b" \n-.0123456789eEfvn/#,[]{}:\"".to_vec()),
            ],
            1..12,
        )
    };
    prop_oneof![
        (any::<usize>(), 1..=255u8).prop_map(|(at, x)| Damage::Flip(at, x)),
        any::<usize>().prop_map(Damage::Truncate),
        (any::<usize>(), run()).prop_map(|(at, b)| Damage::Insert(at, b)),
        (any::<usize>(), run()).prop_map(|(at, b)| Damage::Overwrite(at, b)),
        (any::<usize>(), 1..64usize).prop_map(|(at, n)| Damage::Repeat(at, n)),
    ]
}

fn damaged(mut bytes: Vec<u8>, edits: &[Damage]) -> Vec<u8> {
    for d in edits {
        let n = bytes.len().max(1);
        match d {
            Damage::Flip(at, x) => {
                if let Some(b) = bytes.get_mut(at % n) {
                    *b ^= x;
                }
            }
            Damage::Truncate(at) => bytes.truncate(at % n),
            Damage::Insert(at, run) => {
                let at = (at % n).min(bytes.len());
                bytes.splice(at..at, run.iter().copied());
            }
            Damage::Overwrite(at, run) => {
                for (k, x) in run.iter().enumerate() {
                    if let Some(b) = bytes.get_mut((at + k) % n) {
                        *b = *x;
                    }
                }
            }
            Damage::Repeat(at, len) => {
                let at = (at % n).min(bytes.len());
                let end = (at + len).min(bytes.len());
                let run: Vec<u8> = bytes[at..end].to_vec();
                bytes.splice(at..at, run);
            }
        }
    }
    bytes
}

/// Parses `bytes` as `format`; an accepted soup must be consistent.
fn check_mesh_reader(bytes: &[u8], format: MeshFormat) -> Result<(), TestCaseError> {
    if let Ok(soup) = parse_triangle_soup(bytes, format, Path::new("fuzz.mesh")) {
        let n = soup.positions.len();
        prop_assert!(soup.positions.iter().flatten().all(|c| c.is_finite()));
        prop_assert!(soup.triangles.iter().flatten().all(|&v| (v as usize) < n));
    }
    Ok(())
}

/// A valid replay sequence: a base box and a few hull steps.
const SEQUENCE: &str = "{\"base\": {\"box\": [[0, 0, 0], [100, 100, 40]]}}\n\
    {\"op\": \"subtract\", \"hull\": [[10,10,10],[30,10,10],[10,30,10],[10,10,50]]}\n\
    {\"op\": \"union\", \"hull\": [[50,50,30],[70,50,30],[50,70,30],[50,50,60],[70,70,60]]}\n\
    {\"op\": \"intersect\", \"hull\": [[-1,-1,-1],[101,-1,-1],[-1,101,-1],[-1,-1,101],[101,101,101]]}\n";

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(128)))]

    #[test]
    fn fuzz_damaged_mesh_files_never_panic(
        format in prop::sample::select(vec![MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Glb]),
        binary in any::<bool>(),
        edits in proptest::collection::vec(damage(), 1..4),
    ) {
        let mesh = mesh();
        let valid = if format == MeshFormat::Ply && binary {
            binary_ply(&mesh)
        } else {
            encode_triangle_mesh(&mesh, format).unwrap()
        };
        check_mesh_reader(&damaged(valid, &edits), format)?;
    }

    #[test]
    fn fuzz_random_bytes_are_no_mesh_and_no_panic(
        format in prop::sample::select(vec![MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Glb]),
        bytes in proptest::collection::vec(any::<u8>(), 0..512),
    ) {
        check_mesh_reader(&bytes, format)?;
    }

    #[test]
    fn fuzz_damaged_replay_sequences_never_panic(
        edits in proptest::collection::vec(damage(), 1..4),
    ) {
        let text = damaged(SEQUENCE.as_bytes().to_vec(), &edits);
        if let Ok(sequence) = jsonl::parse(&text[..], Path::new("/fuzz")) {
            prop_assert!(sequence.steps.iter().all(|s| s.hull.len() >= 4));
        }
    }
}
