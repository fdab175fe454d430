//! The surface around border points across the cubes of neighbouring
//! octrees ([`SeamedMesher::set_outside_wedges`]): four shading meshers
//! over the cubes around one vertical corner line, carved by random tools
//! across their shared sides, each taking the others' wall points and
//! border wedges on its cube. After every exchange, every point that the
//! sealed meshes of two or more octrees share has the same merged wedges
//! in all of them, and those equal the corner wedges of all four
//! octrees' polygons there, merged (computed on the welded union of all
//! meshes); with the points exchanged but not the wedges they differ. The
//! kept wedges equal a first build with the same outside points and
//! wedges, and the same wedges again hand back nothing.

use std::collections::BTreeMap;

use chisel_bsp::exact::Point4;
use chisel_bsp::mesh::weld::Welder;
use chisel_bsp::mesh::{SurfaceMesh, Wedge};
use chisel_bsp::octree::{CellBox, CellKey, Edit, Octree, OctreeConfig, SeamedMesher, ShadedCell};
use chisel_bsp::octree::{PointWedges, Tool};
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 10;
const SIZE: i64 = 1 << K;
/// Height of the ground's flat top (y is up, as in a world).
const GROUND: i64 = SIZE / 2 - 37;

/// One cube of the 2 × 2 grid in x and z, its ground up to [`GROUND`].
struct Chunk {
    octree: Octree,
    mesher: SeamedMesher,
    cells: BTreeMap<CellKey, ShadedCell>,
}

impl Chunk {
    fn new(cx: i64, cz: i64) -> Self {
        let origin = [cx * SIZE, 0, cz * SIZE];
        let ground = CellBox {
            min: origin,
            max: [origin[0] + SIZE, GROUND, origin[2] + SIZE],
        };
        let config = OctreeConfig {
            max_bsp_nodes: 24,
            max_depth: 6,
        };
        let octree = Octree::from_box(origin, K, ground, 1, config).unwrap();
        let mut chunk = Self {
            octree,
            mesher: SeamedMesher::with_shading(),
            cells: BTreeMap::new(),
        };
        let all: Vec<CellKey> = chunk.octree.leaves().into_iter().map(|(k, _)| k).collect();
        let out = chunk
            .mesher
            .update_shaded(&chunk.octree, all, BTreeMap::new());
        chunk.keep(out);
        chunk
    }

    /// Takes an update's cells; how many it handed back.
    fn keep(&mut self, out: Vec<(CellKey, Option<ShadedCell>)>) -> usize {
        let n = out.len();
        for (key, cell) in out {
            match cell {
                Some(cell) => self.cells.insert(key, cell),
                None => self.cells.remove(&key),
            };
        }
        n
    }
}

/// A turned dodecahedron near the corner line (x = z = SIZE) at the
/// ground's top.
fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let mut near = |c: f64, r: f64| rng.random_range(c - r..c + r);
    let at = [
        near(SIZE as f64, 150.0),
        near(GROUND as f64 - 40.0, 60.0),
        near(SIZE as f64, 150.0),
    ];
    let scale = rng.random_range(30.0..110.0);
    let (a, b) = (rng.random_range(0.0..6.3f64), rng.random_range(0.0..6.3f64));
    let (ca, sa, cb, sb) = (a.cos(), a.sin(), b.cos(), b.sin());
    let pose = Pose {
        rotation: [
            [ca, -sa * cb, sa * sb],
            [sa, ca * cb, -ca * sb],
            [0.0, sb, cb],
        ],
        translation: at,
    };
    Tool::placed(&dodecahedron_corners(scale), &pose).unwrap()
}

/// Every chunk takes the others' wall points on its cube and, with
/// `wedges`, their border wedges there, and is updated; how many cells
/// the updates handed back.
fn exchange(chunks: &mut [Chunk], wedges: bool) -> usize {
    let given: Vec<(Vec<Point4>, PointWedges)> = (0..chunks.len())
        .map(|i| {
            let cube = chunks[i].octree.root_box();
            let others = (0..chunks.len()).filter(move |&j| j != i);
            let points = others
                .clone()
                .flat_map(|j| chunks[j].mesher.wall_points_in(&chunks[j].octree, &cube))
                .collect();
            let wedges = others
                .flat_map(|j| chunks[j].mesher.border_wedges_in(&chunks[j].octree, &cube))
                .collect();
            (points, wedges)
        })
        .collect();
    let mut handed_back = 0;
    for (chunk, (points, outside)) in chunks.iter_mut().zip(given) {
        chunk.mesher.set_outside_points(points);
        if wedges {
            chunk.mesher.set_outside_wedges(outside);
        }
        let out = chunk
            .mesher
            .update_shaded(&chunk.octree, [], BTreeMap::new());
        handed_back += chunk.keep(out);
    }
    handed_back
}

/// Exchanges points and wedges until no update hands back a cell; how
/// many exchanges handed some back (at most two: the second one carries
/// the wedges at the points the first one added).
fn settle(chunks: &mut [Chunk]) -> usize {
    for round in 0..4 {
        if exchange(chunks, true) == 0 {
            return round;
        }
    }
    panic!("the exchange does not settle");
}

/// At the points the meshes of two or more chunks share: how many there
/// are, and how many have different wedges in some chunk (or in two cells
/// of one chunk) or differ from `reference` (the merged corner wedges of
/// all chunks' polygons there).
fn compare(chunks: &[Chunk], reference: bool) -> (usize, usize) {
    let union = SurfaceMesh::welded_union(
        chunks
            .iter()
            .flat_map(|c| c.cells.values().map(|s| &s.mesh)),
    );
    let around = union.surface_around();
    let mut welder = Welder::from_distinct(union.vertices().to_vec(), 0);
    // Per point of the union, per chunk, the wedge lists of its cells.
    let mut seen: BTreeMap<u32, BTreeMap<usize, Vec<Vec<Wedge>>>> = BTreeMap::new();
    for (c, chunk) in chunks.iter().enumerate() {
        for cell in chunk.cells.values() {
            for (v, p) in cell.mesh.vertices().iter().enumerate() {
                let wedges = cell.around.of_vertex(v as u32);
                if wedges.is_empty() {
                    continue;
                }
                let i = welder.index(p);
                assert!(
                    (i as usize) < union.vertices().len(),
                    "a vertex of the union"
                );
                seen.entry(i)
                    .or_default()
                    .entry(c)
                    .or_default()
                    .push(wedges.to_vec());
            }
        }
    }
    let (mut shared, mut differ) = (0, 0);
    for (i, by_chunk) in seen {
        if by_chunk.len() < 2 {
            continue;
        }
        shared += 1;
        let first = &by_chunk.values().next().expect("two chunks")[0];
        let same = by_chunk.values().flatten().all(|w| w == first);
        let as_reference = !reference || first.as_slice() == around.of_vertex(i);
        if !(same && as_reference) {
            differ += 1;
        }
    }
    (shared, differ)
}

#[test]
fn four_octrees_around_a_corner_share_the_surface_at_their_border_points() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let mut chunks: Vec<Chunk> = [(0, 0), (1, 0), (0, 1), (1, 1)]
        .into_iter()
        .map(|(x, z)| Chunk::new(x, z))
        .collect();
    settle(&mut chunks);
    let (shared, differ) = compare(&chunks, true);
    assert!(shared > 0, "no shared point");
    assert_eq!(differ, 0, "{differ} of {shared} shared points differ");

    let mut points_only_differ = 0;
    for step in 0..24 {
        let tool = random_tool(&mut rng);
        for chunk in &mut chunks {
            if !tool.bounds().overlaps(&chunk.octree.root_box()) {
                continue;
            }
            let changes = chunk.octree.apply(&tool, Edit::Subtract).unwrap();
            let keys: Vec<CellKey> = changes
                .changed
                .iter()
                .chain(&changes.removed)
                .copied()
                .collect();
            let out = chunk
                .mesher
                .update_shaded(&chunk.octree, keys, BTreeMap::new());
            chunk.keep(out);
        }
        // Points exchanged, the wedges kept from before the carve.
        exchange(&mut chunks, false);
        if compare(&chunks, false).1 > 0 {
            points_only_differ += 1;
        }
        assert!(
            settle(&mut chunks) <= 2,
            "step {step}: more than two exchanges"
        );
        let (shared, differ) = compare(&chunks, true);
        assert!(shared > 0, "step {step}: no shared point");
        assert_eq!(
            differ, 0,
            "step {step}: {differ} of {shared} shared points differ"
        );
    }
    println!("{points_only_differ} of 24 steps differ without the wedges");
    assert!(
        points_only_differ > 0,
        "no step needed the wedges: the test does not test them"
    );

    for chunk in &mut chunks {
        // The same wedges again hand nothing back.
        chunk
            .mesher
            .set_outside_wedges(chunk.mesher.outside_wedges());
        let out = chunk
            .mesher
            .update_shaded(&chunk.octree, [], BTreeMap::new());
        assert!(out.is_empty(), "{} cells handed back", out.len());
        // The kept wedges equal a first build with the same outside
        // points and wedges.
        let mut fresh = SeamedMesher::with_shading();
        fresh.set_outside_points(chunk.mesher.outside_points().to_vec());
        fresh.set_outside_wedges(chunk.mesher.outside_wedges());
        let all: Vec<CellKey> = chunk.octree.leaves().into_iter().map(|(k, _)| k).collect();
        let scratch = fresh.update_shaded(&chunk.octree, all, BTreeMap::new());
        assert_eq!(scratch.len(), chunk.cells.len());
        for (key, cell) in scratch {
            let (cell, kept) = (cell.expect("a leaf"), &chunk.cells[&key]);
            assert_eq!(cell.mesh.vertices().len(), kept.mesh.vertices().len());
            for (v, p) in cell.mesh.vertices().iter().enumerate() {
                let w = kept
                    .mesh
                    .vertices()
                    .iter()
                    .position(|q| q.same_position(p))
                    .expect("the same vertices");
                assert_eq!(
                    cell.around.of_vertex(v as u32),
                    kept.around.of_vertex(w as u32),
                    "{key:?}: other wedges than a first build"
                );
            }
        }
    }
}

#[test]
fn a_mesher_without_shading_hands_back_no_wedges_and_ignores_given_ones() {
    let shaded = Chunk::new(1, 0);
    let mut plain = SeamedMesher::new();
    let octree = Chunk::new(0, 0).octree;
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    plain.update(&octree, all, BTreeMap::new());
    let cube = octree.root_box();
    let given = shaded.mesher.border_wedges_in(&shaded.octree, &cube);
    assert!(!given.is_empty(), "the shading mesher has border wedges");
    assert!(
        given
            .iter()
            .all(|(p, w)| p.to_f64()[0] == SIZE as f64 && !w.is_empty()),
        "all on the shared side x = SIZE, each with wedges"
    );
    assert!(plain.border_wedges_in(&octree, &cube).is_empty());
    plain.set_outside_wedges(given);
    assert!(plain.update(&octree, [], BTreeMap::new()).is_empty());
}
