//! Sealed cell meshes (paper 1 §3.4 across cells): after every edit of a
//! random sequence, [`SeamedMesher::update`] keeps one mesh per leaf such
//! that no vertex of a cell's mesh lies strictly inside an edge of a
//! neighbour's mesh (exactly), the meshes equal a from-scratch build, all
//! of them together form one watertight surface (which the unsealed meshes
//! do not), and the results are bit-identical for 1 and 2 threads.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use crate::common::shapes::{placed_dodecahedron, random_rotation};
use chisel_bsp::exact::{Point4, Sign, classify_vertex, compare_offsets};
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{
    CellBox, CellKey, Changes, Edit, Octree, OctreeConfig, SeamedMesher, Tool,
};
use chisel_bsp::tree::EMPTY;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 12;
const SIZE: i64 = 1 << K;
/// Height of the terrain's flat top (on no cell plane).
const GROUND: i64 = SIZE / 2 - 37;

/// A small budget, so that cells split and combine often.
fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 24,
        max_depth: 6,
    }
}

/// A slab of ground filling the cube up to [`GROUND`].
fn terrain() -> Octree {
    let ground = CellBox {
        min: [0; 3],
        max: [SIZE, SIZE, GROUND],
    };
    Octree::from_box([0; 3], K, ground, 1, config()).unwrap()
}

/// A small dodecahedron near the ground's top, or a small box, in the
/// middle of the cube (so that craters overlap and cells change often).
fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let at = [
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.7),
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.7),
        rng.random_range(GROUND as f64 - 200.0..GROUND as f64 + 40.0),
    ];
    if rng.random_range(0..4) == 0 {
        let half = [0; 3].map(|_| rng.random_range(10..90));
        return Tool::cuboid(CellBox {
            min: [0, 1, 2].map(|a| at[a] as i64 - half[a]),
            max: [0, 1, 2].map(|a| at[a] as i64 + half[a]),
        })
        .unwrap();
    }
    let scale = rng.random_range(30.0..120.0);
    let rotation = random_rotation(rng);
    placed_dodecahedron(scale, rotation, at)
}

fn random_edit(rng: &mut ChaCha8Rng) -> Edit {
    match rng.random_range(0..10) {
        0..=6 => Edit::Subtract,
        7 | 8 => Edit::Add(1),
        _ => Edit::Add(2),
    }
}

/// The keys an edit (or its undo) may have changed.
fn keys_of(changes: &Changes) -> Vec<CellKey> {
    changes
        .changed
        .iter()
        .chain(&changes.removed)
        .copied()
        .collect()
}

/// The kept meshes, one per leaf, with the latest update applied; the
/// keys meshed outside `keys` (neighbours whose seams changed) are
/// checked to have really changed.
fn keep(
    meshes: &mut BTreeMap<CellKey, SurfaceMesh>,
    keys: &[CellKey],
    out: Vec<(CellKey, Option<SurfaceMesh>)>,
) -> usize {
    let mut neighbours = 0;
    for (key, mesh) in out {
        match mesh {
            None => {
                assert!(keys.contains(&key), "{key:?} forgotten but not listed");
                meshes.remove(&key);
            }
            Some(mesh) => {
                if !keys.contains(&key) {
                    neighbours += 1;
                    let old = meshes.get(&key).expect("a neighbour was meshed before");
                    assert!(!same_polygons(old, &mesh), "{key:?} meshed again unchanged");
                }
                meshes.insert(key, mesh);
            }
        }
    }
    neighbours
}

/// Whether the meshes have the same vertices and polygons (planes and
/// corner positions), whatever the vertex order.
fn same_polygons(a: &SurfaceMesh, b: &SurfaceMesh) -> bool {
    let polygons = |m: &SurfaceMesh| {
        let mut out: Vec<_> = m
            .polygons()
            .iter()
            .map(|p| {
                let mut corners: Vec<[u64; 3]> = p
                    .corners
                    .iter()
                    .map(|&c| m.position(c).map(f64::to_bits))
                    .collect();
                corners.sort_unstable();
                (p.plane.normal(), p.plane.offset(), p.label, corners)
            })
            .collect();
        out.sort_unstable();
        out
    };
    same_vertex_set(a.vertices(), b.vertices()) && polygons(a) == polygons(b)
}

/// Whether the two lists hold the same exact points (each list has
/// distinct points).
fn same_vertex_set(a: &[Point4], b: &[Point4]) -> bool {
    a.len() == b.len() && a.iter().all(|p| b.iter().any(|q| p.same_position(q)))
}

/// A box's `f64` bounds widened by far more than the rounding of an
/// exact point's position.
fn widened(lo: [f64; 3], hi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let slack = SIZE as f64 * 1e-9;
    (lo.map(|c| c - slack), hi.map(|c| c + slack))
}

fn inside(p: [f64; 3], (lo, hi): ([f64; 3], [f64; 3])) -> bool {
    (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a])
}

/// Every vertex of a mesh of a cell or its neighbours strictly inside an
/// edge of the cell's mesh, found exactly: `(cell, vertex position)`.
fn t_junctions(
    octree: &Octree,
    meshes: &BTreeMap<CellKey, SurfaceMesh>,
) -> Vec<(CellKey, [f64; 3])> {
    let mut found = Vec::new();
    for (&key, mesh) in meshes {
        if mesh.polygons().is_empty() {
            continue;
        }
        let cell = octree.cell_box(key);
        let region = widened(cell.min.map(|c| c as f64), cell.max.map(|c| c as f64));
        let near: Vec<&Point4> = octree
            .leaves_touching(&cell)
            .into_iter()
            .filter_map(|other| meshes.get(&other))
            .flat_map(|m| m.vertices())
            .filter(|v| inside(v.to_f64(), region))
            .collect();
        for polygon in mesh.polygons() {
            let n = polygon.original_len();
            for k in 0..n {
                let previous = polygon.edges[(k + n - 1) % n];
                let next_original = polygon.originals.get(k + 1).map_or(0, |&o| o as usize);
                let mut run: Vec<u32> = vec![polygon.corners[polygon.originals[k] as usize]];
                run.extend(polygon.inserted_on_edge(k).map(|i| polygon.corners[i]));
                run.push(polygon.corners[next_original]);
                for pair in run.windows(2) {
                    let (c, d) = (
                        &mesh.vertices()[pair[0] as usize],
                        &mesh.vertices()[pair[1] as usize],
                    );
                    let (pc, pd) = (c.to_f64(), d.to_f64());
                    let span = widened(
                        [0, 1, 2].map(|a| pc[a].min(pd[a])),
                        [0, 1, 2].map(|a| pc[a].max(pd[a])),
                    );
                    for v in &near {
                        if inside(v.to_f64(), span)
                            && classify_vertex(v, &polygon.plane) == Sign::Zero
                            && classify_vertex(v, &polygon.edges[k]) == Sign::Zero
                            && compare_offsets(v, c, &previous).is_lt()
                            && compare_offsets(v, d, &previous).is_gt()
                        {
                            found.push((key, v.to_f64()));
                        }
                    }
                }
            }
        }
    }
    found
}

/// Every leaf's sealed mesh, from a new mesher.
fn full_build(octree: &Octree) -> BTreeMap<CellKey, SurfaceMesh> {
    let keys: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    SeamedMesher::new()
        .update(octree, keys, BTreeMap::new())
        .into_iter()
        .map(|(key, mesh)| (key, mesh.expect("every key is a leaf")))
        .collect()
}

/// The outer surface (no material interfaces) of all meshes as one.
fn outer_union<'a>(meshes: impl IntoIterator<Item = &'a SurfaceMesh>) -> SurfaceMesh {
    let mut union = SurfaceMesh::welded_union(meshes);
    union.retain(|p| p.outside == EMPTY);
    union
}

/// The kept meshes are one per leaf and equal a from-scratch build.
fn check_against_full_build(octree: &Octree, meshes: &BTreeMap<CellKey, SurfaceMesh>) {
    let scratch = full_build(octree);
    assert!(
        meshes.keys().eq(scratch.keys()),
        "kept meshes are not one per leaf"
    );
    for (key, mesh) in meshes {
        assert!(
            same_vertex_set(mesh.vertices(), scratch[key].vertices()),
            "{key:?}: {} vertices kept, {} from scratch",
            mesh.vertices().len(),
            scratch[key].vertices().len()
        );
    }
}

/// What a sequence of edits did, for the report and the checks.
#[derive(Default)]
struct Counts {
    splits: usize,
    combines: usize,
    undos: usize,
    neighbours: usize,
}

/// `edits` random edits (and now and then an undo of the last one) with
/// the mesher updated after each, meshing from the faces the edits hand
/// back when `from_faces`: the final octree and the kept meshes. Without
/// the faces, the kept meshes are compared with a full build every 250
/// edits (with them, cells are cut into other pieces than a full build
/// cuts them into: the same surface with other vertices).
fn edit_sequence(
    seed: u64,
    edits: usize,
    from_faces: bool,
) -> (Octree, BTreeMap<CellKey, SurfaceMesh>, Counts) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut octree = terrain();
    let mut mesher = SeamedMesher::new();
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    let mut meshes = BTreeMap::new();
    keep(
        &mut meshes,
        &all,
        mesher.update(&octree, all.clone(), BTreeMap::new()),
    );
    let mut counts = Counts::default();
    let mut last: Option<(Octree, Changes)> = None;
    for step in 0..edits {
        if rng.random_range(0..20) == 0
            && let Some((before, changes)) = last.take()
        {
            // Undo: the cells the edit changed change back.
            octree = before;
            let keys = keys_of(&changes);
            let out = mesher.update(&octree, keys.clone(), BTreeMap::new());
            counts.neighbours += keep(&mut meshes, &keys, out);
            counts.undos += 1;
            continue;
        }
        let (tool, edit) = (random_tool(&mut rng), random_edit(&mut rng));
        let before = octree.clone();
        let (changes, fresh) = if from_faces {
            let (changes, faces) = octree.apply_with_faces(&tool, edit).unwrap();
            (changes, faces.into_iter().collect())
        } else {
            (octree.apply(&tool, edit).unwrap(), BTreeMap::new())
        };
        let split = |k: &&CellKey| octree.leaf(k.child(0)).is_some();
        counts.splits += changes.removed.iter().filter(split).count();
        let combined = |k: &&CellKey| before.leaf(k.child(0)).is_some();
        counts.combines += changes.changed.iter().filter(combined).count();
        let keys = keys_of(&changes);
        let out = mesher.update(&octree, keys.clone(), fresh);
        counts.neighbours += keep(&mut meshes, &keys, out);
        last = Some((before, changes));
        if !from_faces && step % 250 == 249 {
            check_against_full_build(&octree, &meshes);
        }
    }
    println!(
        "{} leaves, {} splits, {} combines, {} undos, {} neighbours meshed again",
        octree.stats().leaves,
        counts.splits,
        counts.combines,
        counts.undos,
        counts.neighbours
    );
    assert!(counts.splits > 20 && counts.combines > 5 && counts.neighbours > 20);
    (octree, meshes, counts)
}

/// No T-junction between the kept meshes, and together they are one
/// watertight surface.
fn check_sealed(octree: &Octree, meshes: &BTreeMap<CellKey, SurfaceMesh>) {
    let found = t_junctions(octree, meshes);
    assert!(
        found.is_empty(),
        "{} T-junctions, first {:?}",
        found.len(),
        found[0]
    );
    outer_union(meshes.values()).check_watertight().unwrap();
}

#[test]
fn a_thousand_edits_leave_no_t_junction_and_match_a_full_build() {
    let (octree, meshes, _) = edit_sequence(17, 1000, false);
    check_sealed(&octree, &meshes);
    check_against_full_build(&octree, &meshes);
    // The checks can fail: the cells meshed alone leave cracks.
    let alone: BTreeMap<CellKey, SurfaceMesh> = meshes
        .keys()
        .map(|&key| (key, SurfaceMesh::from_faces(&octree.cell_surface(key))))
        .collect();
    assert!(outer_union(alone.values()).check_watertight().is_err());
    assert!(!t_junctions(&octree, &alone).is_empty());
}

#[test]
fn a_thousand_edits_meshed_from_their_faces_leave_no_t_junction() {
    let (octree, meshes, _) = edit_sequence(23, 1000, true);
    check_sealed(&octree, &meshes);
}

/// Bit-identical meshes: the same vertex digits and polygons.
fn same_mesh(a: &SurfaceMesh, b: &SurfaceMesh) -> bool {
    a.polygons() == b.polygons()
        && a.vertices().len() == b.vertices().len()
        && a.vertices()
            .iter()
            .zip(b.vertices())
            .all(|(p, q)| p.xyz() == q.xyz() && p.w() == q.w())
}

/// Every update's result over a sequence of edits, on `threads` threads.
fn run(threads: usize, edits: usize) -> Vec<Vec<(CellKey, Option<SurfaceMesh>)>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        let mut octree = terrain();
        let mut mesher = SeamedMesher::new();
        let all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
        let mut results = vec![mesher.update(&octree, all, BTreeMap::new())];
        for _ in 0..edits {
            let (tool, edit) = (random_tool(&mut rng), random_edit(&mut rng));
            let (changes, faces) = octree.apply_with_faces(&tool, edit).unwrap();
            results.push(mesher.update(&octree, keys_of(&changes), faces.into_iter().collect()));
        }
        results
    })
}

#[test]
fn results_are_bit_identical_for_one_and_two_threads() {
    let (one, two) = (run(1, 150), run(2, 150));
    assert_eq!(one.len(), two.len());
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a.len(), b.len());
        for ((ka, ma), (kb, mb)) in a.iter().zip(b) {
            assert_eq!(ka, kb);
            match (ma, mb) {
                (None, None) => {}
                (Some(ma), Some(mb)) => assert!(same_mesh(ma, mb), "{ka:?}"),
                _ => panic!("{ka:?} meshed on one side only"),
            }
        }
    }
}

/// The mesher's first build equals meshing each cell from scratch with
/// its neighbours' surfaces ([`Octree::sealed_cell_mesh`]).
#[test]
fn a_first_build_equals_sealing_each_cell_from_scratch() {
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let mut octree = terrain();
    for _ in 0..60 {
        octree
            .apply(&random_tool(&mut rng), random_edit(&mut rng))
            .unwrap();
    }
    let built = full_build(&octree);
    let mut seams = 0;
    for (key, mesh) in &built {
        let reference = octree.sealed_cell_mesh(*key);
        assert!(same_mesh(mesh, &reference), "{key:?}");
        seams += mesh.vertices().len()
            - SurfaceMesh::from_faces(&octree.cell_surface(*key))
                .vertices()
                .len();
    }
    assert!(seams > 50, "only {seams} seam points");
}

/// Median time per edit of meshing the changed cells alone (as without
/// seams) and of [`SeamedMesher::update`], printed (`--nocapture`).
#[test]
fn the_cost_of_seams_per_edit() {
    let mut rng = ChaCha8Rng::seed_from_u64(53);
    let mut octree = terrain();
    for _ in 0..300 {
        octree
            .apply(&random_tool(&mut rng), random_edit(&mut rng))
            .unwrap();
    }
    let mut mesher = SeamedMesher::new();
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    let start = Instant::now();
    mesher.update(&octree, all, BTreeMap::new());
    let first = start.elapsed();
    let (mut carve, mut alone, mut sealed, mut cells) = (vec![], vec![], vec![], vec![]);
    for _ in 0..200 {
        let (tool, edit) = (random_tool(&mut rng), Edit::Subtract);
        let start = Instant::now();
        let (changes, faces) = octree.apply_with_faces(&tool, edit).unwrap();
        carve.push(start.elapsed());
        let fresh: BTreeMap<CellKey, _> = faces.into_iter().collect();
        let jobs: Vec<(CellKey, Option<_>)> = changes
            .changed
            .iter()
            .map(|key| (*key, fresh.get(key).cloned()))
            .collect();
        let start = Instant::now();
        {
            use rayon::prelude::*;
            let meshes: Vec<SurfaceMesh> = jobs
                .into_par_iter()
                .map(|(key, faces)| {
                    SurfaceMesh::from_face_vec(match faces {
                        Some(faces) => octree.cell_surface_from(key, faces),
                        None => octree.cell_surface(key),
                    })
                })
                .collect();
            std::hint::black_box(meshes);
        }
        alone.push(start.elapsed());
        let start = Instant::now();
        let out = mesher.update(&octree, keys_of(&changes), fresh);
        sealed.push(start.elapsed());
        cells.push((out.len(), changes.changed.len()));
    }
    let median = |v: &mut Vec<Duration>| {
        v.sort_unstable();
        v[v.len() / 2]
    };
    cells.sort_unstable();
    println!(
        "first build of {} leaves {first:?}; per carve (median): carve {:?}, cells meshed alone {:?}, \
         seamed update {:?} (median cells {:?} meshed, {:?} changed)",
        octree.stats().leaves,
        median(&mut carve),
        median(&mut alone),
        median(&mut sealed),
        cells[cells.len() / 2].0,
        {
            let mut c: Vec<usize> = cells.iter().map(|c| c.1).collect();
            c.sort_unstable();
            c[c.len() / 2]
        }
    );
}
