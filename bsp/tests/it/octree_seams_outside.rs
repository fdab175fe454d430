//! Sealed meshes across the cubes of neighbouring octrees (the chunks of a
//! large world): four octrees over the cubes around one vertical corner
//! line, carved by random tools across their shared sides, each mesher
//! taking the others' wall points on its cube as outside points
//! ([`SeamedMesher::set_outside_points`]). After every exchange the
//! meshes of all four, without the side walls on the shared planes, are
//! one watertight surface (a T-junction across a side would leave an edge
//! unmatched), which they are not before it; and the kept meshes equal a
//! first build with the same outside points.

use std::collections::BTreeMap;

use crate::common::shapes::{placed_dodecahedron, random_rotation};
use chisel_bsp::exact::{Sign, classify_vertex};
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{CellBox, CellKey, Edit, Octree, OctreeConfig, SeamedMesher, Tool};
use chisel_bsp::tree::EMPTY;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 10;
const SIZE: i64 = 1 << K;
/// Height of the ground's flat top (y is up, as in a world).
const GROUND: i64 = SIZE / 2 - 37;

/// A small budget, so that cells split often and differently per cube.
fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 24,
        max_depth: 6,
    }
}

/// One cube of the 2 × 2 grid in x and z, its ground up to [`GROUND`].
struct Chunk {
    octree: Octree,
    mesher: SeamedMesher,
    meshes: BTreeMap<CellKey, SurfaceMesh>,
}

impl Chunk {
    fn new(cx: i64, cz: i64) -> Self {
        let origin = [cx * SIZE, 0, cz * SIZE];
        let ground = CellBox {
            min: origin,
            max: [origin[0] + SIZE, GROUND, origin[2] + SIZE],
        };
        let octree = Octree::from_box(origin, K, ground, 1, config()).unwrap();
        Self {
            octree,
            mesher: SeamedMesher::new(),
            meshes: BTreeMap::new(),
        }
    }

    fn keep(&mut self, out: Vec<(CellKey, Option<SurfaceMesh>)>) {
        for (key, mesh) in out {
            match mesh {
                Some(mesh) => self.meshes.insert(key, mesh),
                None => self.meshes.remove(&key),
            };
        }
    }
}

/// A dodecahedron near the corner line (x = z = SIZE) at the ground's top.
fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let mut near = |c: f64, r: f64| rng.random_range(c - r..c + r);
    let at = [
        near(SIZE as f64, 150.0),
        near(GROUND as f64 - 40.0, 60.0),
        near(SIZE as f64, 150.0),
    ];
    let scale = rng.random_range(30.0..110.0);
    let rotation = random_rotation(rng);
    placed_dodecahedron(scale, rotation, at)
}

/// Every chunk's outside points: the others' wall points on its cube.
fn exchange(chunks: &mut [Chunk]) {
    let outside: Vec<Vec<_>> = (0..chunks.len())
        .map(|i| {
            let cube = chunks[i].octree.root_box();
            (0..chunks.len())
                .filter(|&j| j != i)
                .flat_map(|j| chunks[j].mesher.wall_points_in(&chunks[j].octree, &cube))
                .collect()
        })
        .collect();
    for (chunk, points) in chunks.iter_mut().zip(outside) {
        chunk.mesher.set_outside_points(points);
        let out = chunk.mesher.update(&chunk.octree, [], BTreeMap::new());
        chunk.keep(out);
    }
}

/// Whether the polygon lies in one of the shared planes x = SIZE, z = SIZE.
fn on_shared_plane(mesh: &SurfaceMesh, corners: &[u32]) -> bool {
    [0usize, 2].into_iter().any(|axis| {
        let mut n = [0i64; 3];
        n[axis] = 1;
        let plane = chisel_bsp::exact::Plane::new(n[0], n[1], n[2], -i128::from(SIZE)).unwrap();
        corners
            .iter()
            .all(|&c| classify_vertex(&mesh.vertices()[c as usize], &plane) == Sign::Zero)
    })
}

/// The outer surface of all chunks' meshes as one, without the side walls
/// on the shared planes.
fn joined(chunks: &[Chunk]) -> SurfaceMesh {
    let mut union = SurfaceMesh::welded_union(chunks.iter().flat_map(|c| c.meshes.values()));
    let walls: Vec<bool> = union
        .polygons()
        .iter()
        .map(|p| on_shared_plane(&union, &p.corners))
        .collect();
    let mut i = 0;
    union.retain(|p| {
        let keep = p.outside == EMPTY && !walls[i];
        i += 1;
        keep
    });
    union
}

#[test]
fn four_octrees_around_a_corner_meet_without_t_junctions() {
    let mut rng = ChaCha8Rng::seed_from_u64(26);
    let mut chunks: Vec<Chunk> = [(0, 0), (1, 0), (0, 1), (1, 1)]
        .into_iter()
        .map(|(x, z)| Chunk::new(x, z))
        .collect();
    for chunk in &mut chunks {
        let all: Vec<CellKey> = chunk.octree.leaves().into_iter().map(|(k, _)| k).collect();
        let out = chunk.mesher.update(&chunk.octree, all, BTreeMap::new());
        chunk.keep(out);
    }
    exchange(&mut chunks);
    joined(&chunks).check_watertight().unwrap();

    let (mut open_before, mut edited) = (0, 0);
    for step in 0..40 {
        let tool = random_tool(&mut rng);
        for chunk in &mut chunks {
            if !tool.bounds().overlaps(&chunk.octree.root_box()) {
                continue;
            }
            edited += 1;
            let changes = chunk.octree.apply(&tool, Edit::Subtract).unwrap();
            let keys: Vec<CellKey> = changes
                .changed
                .iter()
                .chain(&changes.removed)
                .copied()
                .collect();
            let out = chunk.mesher.update(&chunk.octree, keys, BTreeMap::new());
            chunk.keep(out);
        }
        if joined(&chunks).check_watertight().is_err() {
            open_before += 1;
        }
        exchange(&mut chunks);
        if let Err(error) = joined(&chunks).check_watertight() {
            panic!("step {step}: the chunks do not meet: {error}");
        }
    }
    println!("{edited} chunk edits; {open_before} of 40 steps open before the exchange");
    assert!(
        open_before > 0,
        "no step needed the exchange: the test does not test it"
    );

    // The kept meshes equal a first build with the same outside points.
    for chunk in &chunks {
        let mut fresh = SeamedMesher::new();
        fresh.set_outside_points(chunk.mesher.outside_points().to_vec());
        let all: Vec<CellKey> = chunk.octree.leaves().into_iter().map(|(k, _)| k).collect();
        let scratch = fresh.update(&chunk.octree, all, BTreeMap::new());
        assert_eq!(scratch.len(), chunk.meshes.len());
        for (key, mesh) in scratch {
            let (mesh, kept) = (mesh.expect("a leaf"), &chunk.meshes[&key]);
            assert_eq!(mesh.vertices().len(), kept.vertices().len(), "{key:?}");
            assert!(
                mesh.vertices()
                    .iter()
                    .all(|p| kept.vertices().iter().any(|q| p.same_position(q))),
                "{key:?}: other vertices than a first build"
            );
        }
    }
}

#[test]
fn outside_points_are_the_wall_points_on_the_cube_and_changes_reseal() {
    let (mut a, mut b) = (Chunk::new(0, 0), Chunk::new(1, 0));
    for chunk in [&mut a, &mut b] {
        let all: Vec<CellKey> = chunk.octree.leaves().into_iter().map(|(k, _)| k).collect();
        let out = chunk.mesher.update(&chunk.octree, all, BTreeMap::new());
        chunk.keep(out);
    }
    let cube = a.octree.root_box();
    let points = b.mesher.wall_points_in(&b.octree, &cube);
    assert!(!points.is_empty());
    // All on the shared side x = SIZE, each once.
    for (i, p) in points.iter().enumerate() {
        assert_eq!(p.to_f64()[0], SIZE as f64);
        assert!(points[..i].iter().all(|q| !q.same_position(p)));
    }
    a.mesher.set_outside_points(points.clone());
    // The same points again change nothing: no leaf is sealed again.
    let out = a.mesher.update(&a.octree, [], BTreeMap::new());
    a.keep(out);
    a.mesher.set_outside_points(points.clone());
    assert!(a.mesher.update(&a.octree, [], BTreeMap::new()).is_empty());
    // A crater across the side gives `b` new wall points there, which
    // seal leaves of `a` again; the old points seal them back.
    let rotation = [[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]];
    let at = [
        SIZE as f64 + 13.0,
        GROUND as f64 - 5.0,
        SIZE as f64 / 2.0 + 7.0,
    ];
    let tool = placed_dodecahedron(70.0, rotation, at);
    let changes = b.octree.apply(&tool, Edit::Subtract).unwrap();
    let keys: Vec<CellKey> = changes
        .changed
        .iter()
        .chain(&changes.removed)
        .copied()
        .collect();
    let out = b.mesher.update(&b.octree, keys, BTreeMap::new());
    b.keep(out);
    let after = b.mesher.wall_points_in(&b.octree, &cube);
    a.mesher.set_outside_points(after);
    let resealed = a.mesher.update(&a.octree, [], BTreeMap::new());
    assert!(!resealed.is_empty(), "new points on the side seal again");
    a.keep(resealed);
    a.mesher.set_outside_points(points);
    let back = a.mesher.update(&a.octree, [], BTreeMap::new());
    assert!(!back.is_empty());
    a.keep(back);
    let mut fresh = SeamedMesher::new();
    fresh.set_outside_points(a.mesher.outside_points().to_vec());
    let all: Vec<CellKey> = a.octree.leaves().into_iter().map(|(k, _)| k).collect();
    for (key, mesh) in fresh.update(&a.octree, all, BTreeMap::new()) {
        assert_eq!(
            mesh.expect("a leaf").vertices().len(),
            a.meshes[&key].vertices().len(),
            "{key:?} sealed back"
        );
    }
}
