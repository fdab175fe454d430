//! Surface extraction for the scenarios: per changed cell after every step
//! (what a game re-meshes), and the whole surface once at the end.

use chisel_bsp::mesh::{SurfaceMesh, TriangleMesh};
use chisel_bsp::octree::{CellFaces, CellKey, Octree};
use chisel_bsp::tree::BoundaryFace;
use rayon::prelude::*;

/// What the per-step latency includes, for reports.
pub const PER_STEP: &str = "tool hull + apply (keeping the rebuilt cells' faces) + for every changed cell: \
     its surface (cell_surface_from, else cell_surface), welding, T-junctions, triangles";

/// Re-extracts the triangles of every cell in `keys` (cells in parallel),
/// as a game rebuilds the meshes of the cells an edit changed; `faces` are
/// the faces [`Octree::apply_with_faces`] handed back (sorted by key): a
/// cell listed there finishes from them, the others (cells whose content
/// did not change but which the tool touches, leaves combined from uniform
/// children) are extracted afresh. Returns the number of triangles.
#[must_use]
pub fn changed_cells(octree: &Octree, keys: &[CellKey], faces: CellFaces) -> usize {
    let mut faces = faces.into_iter().peekable();
    let jobs: Vec<(CellKey, Option<Vec<BoundaryFace>>)> = keys
        .iter()
        .map(|&key| {
            while faces.next_if(|(k, _)| *k < key).is_some() {}
            (key, faces.next_if(|(k, _)| *k == key).map(|(_, f)| f))
        })
        .collect();
    jobs.into_par_iter()
        .map(|(key, faces)| {
            let faces = match faces {
                Some(faces) => octree.cell_surface_from(key, faces),
                None => octree.cell_surface(key),
            };
            if faces.is_empty() {
                return 0;
            }
            SurfaceMesh::from_face_vec(faces).triangles().len()
        })
        .sum()
}

/// Whether a surface is closed, and whether it is also a 2-manifold, each
/// material's region on its own: an interface between two materials is one
/// polygon, which bounds the region behind it as it is and the region in
/// front of it turned round
/// ([`SurfaceMesh::check_regions_closed`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Closure {
    /// Every directed edge bounds each region as often as its opposite:
    /// the boundary of a solid, possibly touching itself along edges.
    pub closed: bool,
    /// Every directed edge of each region's boundary is used exactly once,
    /// and its opposite once (watertight in the strict sense).
    pub manifold: bool,
}

/// Leaf cells whose surfaces are extracted together (in parallel) and
/// welded before the next batch: bounds the faces held at once.
const CELLS_PER_BATCH: usize = 64;

/// The whole surface as one mesh, and how closed it is. The same mesh as
/// welding [`Octree::surface`] at once, built batch by batch of cells so
/// that only one batch of faces is held beside the welded mesh.
#[must_use]
pub fn whole(octree: &Octree) -> (TriangleMesh, Closure) {
    let keys: Vec<CellKey> = octree.leaves().into_iter().map(|(key, _)| key).collect();
    let batches = keys.chunks(CELLS_PER_BATCH).map(|batch| {
        batch
            .par_iter()
            .map(|&key| octree.cell_surface(key))
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect::<Vec<BoundaryFace>>()
    });
    let mesh = SurfaceMesh::from_face_batches(batches);
    let closure = Closure {
        closed: mesh.check_regions_closed().is_ok(),
        manifold: mesh.check_regions_watertight().is_ok(),
    };
    (mesh.triangles(), closure)
}

/// A 64-bit FNV-1a hash of the mesh (positions, triangles, labels): equal
/// for bit-identical results, e.g. across thread counts.
#[must_use]
pub fn mesh_hash(mesh: &TriangleMesh) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for p in &mesh.positions {
        for c in p {
            eat(&c.to_bits().to_le_bytes());
        }
    }
    for (t, label) in mesh.indices.iter().zip(&mesh.labels) {
        for v in t {
            eat(&v.to_le_bytes());
        }
        eat(&[*label]);
    }
    h
}
