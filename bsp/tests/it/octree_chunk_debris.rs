//! Debris across chunks: a world split into octrees side by side, each
//! first detaching on its own with its sides as anchors (as a world's
//! chunks do), then [`detach_across_chunks`] over all of them, gives
//! exactly the pieces that one octree over the whole world gives: the same
//! piece volumes per material, the same solid left, as rationals. A piece
//! held through a neighbour stays; a neighbour not in the set anchors;
//! edges across a chunk corner do not connect; limits count all chunks
//! and refuse with every chunk unchanged; results are bit-identical for 1
//! and 2 threads.

use std::collections::BTreeMap;

use chisel_bsp::Error;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{
    Anchors, CellBox, CellKey, ChunkOctree, ChunkedDetached, CubeSide, DebrisConfig, DebrisLimits,
    Edit, ExactVolume, Octree, OctreeConfig, Tool, detach_across_chunks,
    detach_across_chunks_with_open_sides,
};
use chisel_bsp::tree::Label;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The chunks' edge, `2^K`.
const K: u8 = 10;
const EDGE: i64 = 1 << K;
/// The ground every scene stands on.
const GROUND: i64 = 30;

fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 24,
        max_depth: 6,
    }
}

fn cube(min: [i64; 3], max: [i64; 3]) -> CellBox {
    CellBox { min, max }
}

/// A chunk's anchors: the bottom and its four vertical sides, as a
/// world's chunks list them.
fn chunk_anchors() -> Anchors {
    let side = |axis, upper| CubeSide { axis, upper };
    Anchors {
        sides: vec![
            CubeSide::BOTTOM,
            side(0, false),
            side(0, true),
            side(2, false),
            side(2, true),
        ],
        boxes: Vec::new(),
    }
}

/// The chunks at `coords` (x, z), each holding its share of the boxes
/// (added in turn with their materials) over a ground layer.
fn world(coords: &[(i64, i64)], boxes: &[(CellBox, Label)]) -> Vec<ChunkOctree> {
    coords
        .iter()
        .map(|&(x, z)| {
            let mut octree = Octree::new([x * EDGE, 0, z * EDGE], K, 0, config()).unwrap();
            let root = octree.root_box();
            let ground = cube(
                [root.min[0], 0, root.min[2]],
                [root.max[0], GROUND, root.max[2]],
            );
            for (b, label) in std::iter::once((ground, 2)).chain(boxes.iter().copied()) {
                if b.overlaps(&root) {
                    octree
                        .apply(&Tool::cuboid(b).unwrap(), Edit::Add(label))
                        .unwrap();
                }
            }
            ChunkOctree {
                octree,
                anchors: chunk_anchors(),
            }
        })
        .collect()
}

/// One octree over the chunks at `coords` (within `[0, 2)²`) with the
/// same solid, anchored by its bottom only.
fn reference(coords: &[(i64, i64)], boxes: &[(CellBox, Label)]) -> Octree {
    let mut octree = Octree::new([0; 3], K + 1, 0, config()).unwrap();
    let grounds = coords.iter().map(|&(x, z)| {
        let min = [x * EDGE, 0, z * EDGE];
        (cube(min, [min[0] + EDGE, GROUND, min[2] + EDGE]), 2)
    });
    for (b, label) in grounds.chain(boxes.iter().copied()) {
        octree
            .apply(&Tool::cuboid(b).unwrap(), Edit::Add(label))
            .unwrap();
    }
    octree
}

/// What a carve over the chunks cut loose, as a world does it: the tool in
/// every chunk it overlaps, each chunk's own detach (sides anchoring),
/// then the detach across chunks from the leaves both changed. Returns
/// the volumes per material of every piece (sorted) and the pass across.
fn carve_world(
    chunks: &mut [ChunkOctree],
    tool: &Tool,
    limits: DebrisLimits,
) -> Result<(Vec<BTreeMap<Label, ExactVolume>>, ChunkedDetached), Error> {
    let mut pieces = Vec::new();
    let mut near = Vec::new();
    for (i, chunk) in chunks.iter_mut().enumerate() {
        if !tool.bounds().overlaps(&chunk.octree.root_box()) {
            continue;
        }
        let own = DebrisConfig {
            anchors: chunk.anchors.clone(),
            ..DebrisConfig::default()
        };
        let carved = chunk.octree.apply_detaching(tool, Edit::Subtract, &own)?;
        pieces.extend(carved.detached.pieces.iter().map(|p| p.volumes.clone()));
        near.extend(carved.changes.changed.iter().map(|&k| (i, k)));
    }
    // Past the open sides too: the same pieces and chunks, and the open
    // sides that held what stays.
    let mut plain_chunks = chunks.to_vec();
    let plain = detach_across_chunks(&mut plain_chunks, &near, limits);
    let across =
        detach_across_chunks_with_open_sides(chunks, &near, limits, &CubeSide::HORIZONTAL)?;
    let plain = plain.expect("the same outcome without open sides");
    assert!(plain.held_at_open_sides.is_empty());
    assert_eq!(bytes(&plain_chunks), bytes(chunks), "the same chunks");
    let volumes = |d: &ChunkedDetached| d.pieces.iter().map(|p| p.volumes()).collect::<Vec<_>>();
    assert_eq!(volumes(&plain), volumes(&across), "the same pieces");
    pieces.extend(across.pieces.iter().map(|p| p.volumes()));
    pieces.sort();
    Ok((pieces, across))
}

/// The same carve on the reference: its pieces' volumes, sorted.
fn carve_reference(octree: &mut Octree, tool: &Tool) -> Vec<BTreeMap<Label, ExactVolume>> {
    let carved = octree
        .apply_detaching(tool, Edit::Subtract, &DebrisConfig::default())
        .unwrap();
    let mut pieces: Vec<_> = carved
        .detached
        .pieces
        .iter()
        .map(|p| p.volumes.clone())
        .collect();
    pieces.sort();
    pieces
}

/// The exact volumes of all chunks together.
fn world_volumes(chunks: &[ChunkOctree]) -> BTreeMap<Label, ExactVolume> {
    let mut total: BTreeMap<Label, ExactVolume> = BTreeMap::new();
    for chunk in chunks {
        for (label, v) in chunk.octree.exact_volumes() {
            *total.entry(label).or_default() += &v;
        }
    }
    total
}

/// Each part is one piece of its chunk, the volume its chunk lost; no
/// unanchored component is left anywhere in the chunks.
fn check(before: &[Vec<u8>], chunks: &[ChunkOctree], detached: &ChunkedDetached) {
    let mut lost: BTreeMap<usize, ExactVolume> = BTreeMap::new();
    for piece in &detached.pieces {
        for pair in piece.parts.windows(2) {
            assert!(pair[0].chunk < pair[1].chunk, "parts by chunk, one each");
        }
        for part in &piece.parts {
            assert_eq!(part.piece.solid.exact_volumes(), part.piece.volumes);
            *lost.entry(part.chunk).or_default() += &part.piece.volume();
        }
    }
    for (i, chunk) in chunks.iter().enumerate() {
        let was = Octree::from_bytes(&before[i]).unwrap().exact_solid_volume();
        let lost = lost.remove(&i).unwrap_or_default();
        assert_eq!(
            was,
            chunk.octree.exact_solid_volume() + lost,
            "chunk {i} lost its parts"
        );
        if detached.changes[i].changed.is_empty() && detached.changes[i].removed.is_empty() {
            assert_eq!(chunk.octree.to_bytes(), before[i], "chunk {i} untouched");
        }
    }
    let mut all = chunks.to_vec();
    let everywhere: Vec<(usize, CellKey)> = (0..all.len()).map(|i| (i, CellKey::ROOT)).collect();
    let left = detach_across_chunks(&mut all, &everywhere, DebrisLimits::default()).unwrap();
    assert!(left.pieces.is_empty(), "an unanchored piece was left");
}

fn bytes(chunks: &[ChunkOctree]) -> Vec<Vec<u8>> {
    chunks.iter().map(|c| c.octree.to_bytes()).collect()
}

const FOUR: [(i64, i64); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];

/// A slab across the border x = EDGE resting on a pillar in chunk 0.
fn slab_on_pillar() -> Vec<(CellBox, Label)> {
    vec![
        (cube([900, GROUND, 100], [980, 400, 220]), 1),
        (cube([900, 400, 100], [1150, 480, 220]), 3),
    ]
}

fn pillar_cut() -> Tool {
    Tool::cuboid(cube([890, 100, 90], [990, 150, 230])).unwrap()
}

/// The pillar cut through: what is above the cut falls as one piece with
/// a part in each chunk, exactly what one octree over both gives.
#[test]
fn a_slab_across_a_border_falls_as_one_piece() {
    let boxes = slab_on_pillar();
    let mut chunks = world(&FOUR[..2], &boxes);
    let mut one = reference(&FOUR[..2], &boxes);
    let (pieces, across) =
        carve_world(&mut chunks, &pillar_cut(), DebrisLimits::default()).unwrap();
    assert_eq!(across.pieces.len(), 1);
    let piece = &across.pieces[0];
    assert_eq!(
        piece.parts.iter().map(|p| p.chunk).collect::<Vec<_>>(),
        [0, 1]
    );
    let upper = ExactVolume::of_box(&cube([900, 150, 100], [980, 400, 220]));
    let slab = ExactVolume::of_box(&cube([900, 400, 100], [1150, 480, 220]));
    assert_eq!(piece.volumes(), BTreeMap::from([(1, upper), (3, slab)]));
    assert_eq!(
        piece.parts[1].piece.volume(),
        ExactVolume::of_box(&cube([1024, 400, 100], [1150, 480, 220]))
    );
    assert_eq!(pieces, carve_reference(&mut one, &pillar_cut()));
    assert_eq!(world_volumes(&chunks), one.exact_volumes());
    // The carve and the detach changed chunk 0; the detach chunk 1.
    check(&before_cut(&boxes, 2), &chunks, &across);
    assert!(!across.changes[1].changed.is_empty());
    assert_eq!(
        chunks[1].octree.label_at([1100, 450, 150]).unwrap(),
        Some(0)
    );
}

/// The chunks of `boxes` with the pillar cut but nothing detached: the
/// state [`check`] compares a detach against.
fn before_cut(boxes: &[(CellBox, Label)], n: usize) -> Vec<Vec<u8>> {
    let mut chunks = world(&FOUR[..n], boxes);
    for chunk in &mut chunks {
        if pillar_cut().bounds().overlaps(&chunk.octree.root_box()) {
            chunk.octree.apply(&pillar_cut(), Edit::Subtract).unwrap();
        }
    }
    bytes(&chunks)
}

/// A second pillar in the neighbouring chunk holds the slab: nothing
/// falls and no chunk changes; cut that one too and the slab falls.
#[test]
fn a_piece_held_through_the_neighbour_stays() {
    let mut boxes = slab_on_pillar();
    boxes.push((cube([1060, GROUND, 100], [1140, 400, 220]), 1));
    let mut chunks = world(&FOUR[..2], &boxes);
    let mut one = reference(&FOUR[..2], &boxes);
    let (pieces, across) =
        carve_world(&mut chunks, &pillar_cut(), DebrisLimits::default()).unwrap();
    assert!(pieces.is_empty(), "held by the pillar across the border");
    assert!(across.changes.iter().all(|c| c.changed.is_empty()));
    assert!(carve_reference(&mut one, &pillar_cut()).is_empty());
    let second = Tool::cuboid(cube([1050, 200, 90], [1150, 260, 230])).unwrap();
    let (pieces, across) = carve_world(&mut chunks, &second, DebrisLimits::default()).unwrap();
    assert_eq!(across.pieces.len(), 1);
    assert_eq!(pieces, carve_reference(&mut one, &second));
    assert_eq!(world_volumes(&chunks), one.exact_volumes());
}

/// Without the neighbouring chunk in the set (not loaded), the side the
/// slab crosses anchors it: nothing falls, and the result names that side.
#[test]
fn a_chunk_not_loaded_anchors() {
    let boxes = slab_on_pillar();
    let mut chunks = world(&FOUR[..1], &boxes);
    let before = before_cut(&boxes, 1);
    let (pieces, across) =
        carve_world(&mut chunks, &pillar_cut(), DebrisLimits::default()).unwrap();
    assert!(pieces.is_empty());
    assert_eq!(bytes(&chunks), before);
    check(&before, &chunks, &across);
    // The search from the slab stopped on that side: loading the chunk
    // across is what would let it fall.
    let across_x = CubeSide {
        axis: 0,
        upper: true,
    };
    assert!(
        across.held_at_open_sides.contains(&(0, across_x)),
        "{:?}",
        across.held_at_open_sides
    );
    let mut both = world(&FOUR[..2], &boxes);
    let (_, across) = carve_world(&mut both, &pillar_cut(), DebrisLimits::default()).unwrap();
    assert!(
        !across.held_at_open_sides.contains(&(0, across_x)),
        "a side with a chunk across holds nothing: {:?}",
        across.held_at_open_sides
    );
}

/// A slab over the corner where four chunks meet, on a pillar in one of
/// them: one piece of four parts, as one octree over all four gives.
#[test]
fn a_piece_around_a_corner_spans_four_chunks() {
    let boxes = vec![
        (cube([900, GROUND, 900], [980, 400, 980]), 1),
        (cube([900, 400, 900], [1150, 480, 1150]), 3),
    ];
    let mut chunks = world(&FOUR, &boxes);
    let mut one = reference(&FOUR, &boxes);
    let cut = Tool::cuboid(cube([890, 100, 890], [990, 150, 990])).unwrap();
    let before = {
        let mut c = world(&FOUR, &boxes);
        c[0].octree.apply(&cut, Edit::Subtract).unwrap();
        bytes(&c)
    };
    let (pieces, across) = carve_world(&mut chunks, &cut, DebrisLimits::default()).unwrap();
    assert_eq!(across.pieces.len(), 1);
    assert_eq!(
        across.pieces[0]
            .parts
            .iter()
            .map(|p| p.chunk)
            .collect::<Vec<_>>(),
        [0, 1, 2, 3]
    );
    assert_eq!(pieces, carve_reference(&mut one, &cut));
    assert_eq!(world_volumes(&chunks), one.exact_volumes());
    check(&before, &chunks, &across);
}

/// Blocks in diagonal chunks meet only along the corner line: the one on
/// a pillar stays, the other falls alone, as in one octree.
#[test]
fn an_edge_across_a_chunk_corner_does_not_hold() {
    let boxes = vec![
        (cube([924, GROUND, 924], [1024, 500, 1024]), 1),
        (cube([1024, 400, 1024], [1124, 500, 1124]), 3),
    ];
    let mut chunks = world(&FOUR, &boxes);
    let mut one = reference(&FOUR, &boxes);
    let before = bytes(&chunks);
    let everywhere: Vec<(usize, CellKey)> = (0..4).map(|i| (i, CellKey::ROOT)).collect();
    let across = detach_across_chunks(&mut chunks, &everywhere, DebrisLimits::default()).unwrap();
    let alone = one
        .detach_unanchored(&[CellKey::ROOT], &DebrisConfig::default())
        .unwrap();
    assert_eq!(across.pieces.len(), 1);
    assert_eq!(alone.pieces.len(), 1);
    assert_eq!(across.pieces[0].parts.len(), 1);
    assert_eq!(across.pieces[0].parts[0].chunk, 3);
    assert_eq!(across.pieces[0].volumes(), alone.pieces[0].volumes);
    assert_eq!(world_volumes(&chunks), one.exact_volumes());
    check(&before, &chunks, &across);
}

/// The limits count the parts in every chunk together; over them the
/// call fails and no chunk changes; at them exactly it goes through.
#[test]
fn limits_count_all_chunks_and_refuse_with_nothing_changed() {
    let boxes = slab_on_pillar();
    let total = 80 * 250 * 120 + 250 * 80 * 120;
    let fresh = || {
        let mut chunks = world(&FOUR[..2], &boxes);
        let near: Vec<(usize, CellKey)> = (chunks[0].octree.apply(&pillar_cut(), Edit::Subtract))
            .unwrap()
            .changed
            .into_iter()
            .map(|k| (0, k))
            .collect();
        (chunks, near)
    };
    let (mut chunks, near) = fresh();
    let before = bytes(&chunks);
    for limits in [
        DebrisLimits {
            max_volume: Some(total - 1),
            max_cells: None,
        },
        DebrisLimits {
            max_volume: None,
            max_cells: Some(1),
        },
    ] {
        let err = detach_across_chunks(&mut chunks, &near, limits).unwrap_err();
        assert!(matches!(err, Error::TooMuchDebris { .. }), "{err}");
        assert_eq!(bytes(&chunks), before);
    }
    let at = DebrisLimits {
        max_volume: Some(total),
        max_cells: None,
    };
    let detached = detach_across_chunks(&mut chunks, &near, at).unwrap();
    assert_eq!(detached.volume(), ExactVolume::from_integer(total as i128));
    // The part in chunk 1 alone is under the limit: the whole counts.
    assert!(detached.pieces[0].parts[1].piece.volume() < ExactVolume::from_integer(total as i128));
    let (mut chunks, near) = fresh();
    let config = DebrisConfig {
        max_volume: Some(total - 1),
        ..DebrisConfig::default()
    };
    assert!(detach_across_chunks(&mut chunks, &near, DebrisLimits::from(&config)).is_err());
}

/// Overlapping cubes and seeds naming no chunk are typed errors.
#[test]
fn bad_chunks_are_refused() {
    let mut chunks = world(&FOUR[..1], &[]);
    let mut twice = chunks.clone();
    twice.extend(chunks.clone());
    let err = detach_across_chunks(&mut twice, &[], DebrisLimits::default()).unwrap_err();
    assert!(matches!(err, Error::InvalidChunks { .. }), "{err}");
    let err = detach_across_chunks(&mut chunks, &[(1, CellKey::ROOT)], DebrisLimits::default())
        .unwrap_err();
    assert!(err.to_string().contains("chunk 1"), "{err}");
}

fn random_box(rng: &mut ChaCha8Rng, lo: i64, hi: i64, size: std::ops::Range<i64>) -> CellBox {
    let mut min = [0; 3];
    let mut max = [0; 3];
    for a in 0..3 {
        let e = rng.random_range(size.clone());
        min[a] = rng.random_range(lo..hi - e);
        max[a] = min[a] + e;
    }
    CellBox { min, max }
}

/// A small convex hull of random integer points near the middle lines of
/// the four chunks (tilted planes across borders).
fn random_hull(rng: &mut ChaCha8Rng) -> Tool {
    let c = [
        EDGE + rng.random_range(-250..250),
        rng.random_range(100..600),
        EDGE + rng.random_range(-250..250),
    ];
    let points: Vec<IntPoint> = (0..8)
        .map(|_| {
            let q = c.map(|x| x + rng.random_range(-90..=90));
            IntPoint::new(q[0], q[1], q[2]).unwrap()
        })
        .collect();
    Tool::convex_hull(&points).unwrap()
}

/// Towers and bridges near the middle of four chunks, carved at random:
/// after every carve the chunks give the pieces one octree gives, and
/// hold what it holds. Returns every chunk's bytes after each carve and
/// the number of pieces that spanned chunks.
fn random_scene(seed: u64, carves: usize) -> (Vec<Vec<u8>>, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut boxes = Vec::new();
    for _ in 0..4 {
        let mut pillar = random_box(&mut rng, EDGE - 300, EDGE + 300, 40..120);
        pillar.min[1] = GROUND;
        pillar.max[1] = rng.random_range(150..500);
        let mut top = random_box(&mut rng, EDGE - 350, EDGE + 350, 100..350);
        top.min[1] = pillar.max[1] - 20;
        top.max[1] = pillar.max[1] + rng.random_range(30..90);
        boxes.push((pillar, 1));
        boxes.push((top, rng.random_range(1..=3)));
    }
    let mut chunks = world(&FOUR, &boxes);
    let mut one = reference(&FOUR, &boxes);
    // Whatever stands in the air falls first.
    let everywhere: Vec<(usize, CellKey)> = (0..4).map(|i| (i, CellKey::ROOT)).collect();
    detach_across_chunks(&mut chunks, &everywhere, DebrisLimits::default()).unwrap();
    one.detach_unanchored(&[CellKey::ROOT], &DebrisConfig::default())
        .unwrap();
    assert_eq!(world_volumes(&chunks), one.exact_volumes());
    let mut snapshots = bytes(&chunks);
    let mut spanning = 0;
    for i in 0..carves {
        let tool = if i % 2 == 1 {
            random_hull(&mut rng)
        } else {
            let (pillar, _) = boxes[2 * rng.random_range(0..boxes.len() / 2)];
            let mut cut = pillar;
            for a in [0, 2] {
                cut.min[a] -= 10;
                cut.max[a] += 10;
            }
            cut.min[1] = rng.random_range(pillar.min[1] + 10..pillar.max[1] - 30);
            cut.max[1] = cut.min[1] + 20;
            Tool::cuboid(cut).unwrap()
        };
        let (pieces, across) = carve_world(&mut chunks, &tool, DebrisLimits::default()).unwrap();
        assert_eq!(pieces, carve_reference(&mut one, &tool), "carve {i}");
        assert_eq!(world_volumes(&chunks), one.exact_volumes(), "carve {i}");
        spanning += across.pieces.iter().filter(|p| p.parts.len() > 1).count();
        snapshots.extend(bytes(&chunks));
        for part in across.pieces.iter().flat_map(|p| &p.parts) {
            snapshots.push(part.piece.solid.to_bytes());
        }
    }
    (snapshots, spanning)
}

#[test]
fn random_carves_across_chunks_match_one_octree() {
    let spanning: usize = (0..6).map(|seed| random_scene(seed, 8).1).sum();
    assert!(
        spanning >= 4,
        "the carves cut {spanning} pieces across chunks"
    );
}

#[test]
fn chunked_results_are_bit_identical_for_one_and_two_threads() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| random_scene(11, 6).0)
    };
    assert_eq!(run(1), run(2));
}
