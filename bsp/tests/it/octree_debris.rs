//! Debris detection: after an edit, every solid component that no anchor
//! holds is found, taken out exactly and handed back as a piece; the
//! volumes add up exactly (terrain before = terrain after + pieces, as
//! rationals); faces of positive area connect, edges and points do not;
//! anchor boxes hold; results are bit-identical for 1 and 2 threads; a
//! detach over the limit is refused with the octree unchanged; and random
//! carves never leave an unanchored component behind.

use std::collections::BTreeMap;

use chisel_bsp::Error;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{
    Anchors, CellBox, CellKey, Changes, CubeSide, DebrisConfig, Detached, Edit, ExactVolume,
    Octree, OctreeConfig, Tool,
};
use chisel_bsp::tree::Label;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 10;
const SIZE: i64 = 1 << K;

fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 24,
        max_depth: 6,
    }
}

fn cube(min: [i64; 3], max: [i64; 3]) -> CellBox {
    CellBox { min, max }
}

/// An octree holding the boxes, each added with its material in turn.
fn terrain(boxes: &[(CellBox, Label)]) -> Octree {
    let mut octree = Octree::new([0; 3], K, 0, config()).unwrap();
    for &(b, label) in boxes {
        octree
            .apply(&Tool::cuboid(b).unwrap(), Edit::Add(label))
            .unwrap();
    }
    octree
}

fn subtract(octree: &mut Octree, b: CellBox) -> Changes {
    octree
        .apply(&Tool::cuboid(b).unwrap(), Edit::Subtract)
        .unwrap()
}

fn box_volume(b: CellBox) -> ExactVolume {
    ExactVolume::of_box(&b)
}

fn everywhere() -> Vec<CellKey> {
    vec![CellKey::ROOT]
}

/// The exact volumes of the octree plus those of the pieces.
fn with_pieces(octree: &Octree, detached: &Detached) -> BTreeMap<Label, ExactVolume> {
    let mut total = octree.exact_volumes();
    for piece in &detached.pieces {
        for (label, v) in &piece.volumes {
            *total.entry(*label).or_default() += v;
        }
    }
    total
}

/// Each piece's own octree holds exactly its volumes, its cells add up to
/// them, and no component of the terrain is left unanchored.
fn check(octree: &Octree, detached: &Detached, anchors: &Anchors) {
    for piece in &detached.pieces {
        assert_eq!(piece.solid.exact_volumes(), piece.volumes);
        let cells: ExactVolume = piece.cells.iter().map(|c| c.volume.clone()).sum();
        assert_eq!(cells, piece.volume());
        assert!(!piece.solid.surface().is_empty());
        let components = piece.solid.solid_components(anchors);
        assert_eq!(components.len(), 1, "a piece is one component");
    }
    for component in octree.solid_components(anchors) {
        assert!(
            component.anchored,
            "{:?} is left unanchored",
            component.cells[0]
        );
    }
}

/// A slab on two pillars standing on the bottom, both pillars carved away
/// with boxes: the slab comes off whole as the one piece, exactly.
#[test]
fn a_bridge_without_pillars_falls_as_one_piece() {
    let slab = cube([100, 400, 100], [700, 500, 220]);
    let mut octree = terrain(&[
        (cube([100, 0, 100], [200, 400, 220]), 1),
        (cube([600, 0, 100], [700, 400, 220]), 1),
        (slab, 1),
        (cube([0, 0, 0], [SIZE, 30, SIZE]), 2),
    ]);
    let anchors = Anchors::default();
    let config = DebrisConfig::default();
    let changes = subtract(&mut octree, cube([90, 30, 90], [210, 400, 230]));
    let carved = octree.detach_after(&changes, &config).unwrap();
    assert!(
        carved.detached.pieces.is_empty(),
        "one pillar holds the slab"
    );
    let before = octree.exact_volumes();
    let changes = subtract(&mut octree, cube([590, 30, 90], [710, 400, 230]));
    let after_carve = octree.exact_volumes();
    assert!(after_carve < before || after_carve != before);
    let carved = octree.detach_after(&changes, &config).unwrap();
    let pieces = &carved.detached.pieces;
    assert_eq!(pieces.len(), 1);
    assert_eq!(pieces[0].volume(), box_volume(slab));
    assert_eq!(
        pieces[0].volumes.keys().copied().collect::<Vec<_>>(),
        vec![1]
    );
    assert_eq!(with_pieces(&octree, &carved.detached), after_carve);
    assert!(octree.label_at([400, 450, 150]).unwrap() == Some(0));
    assert!(pieces[0].solid.label_at([400, 450, 150]).unwrap() == Some(1));
    assert!(pieces[0].bounds.min[1] <= 400 && pieces[0].bounds.max[1] >= 500);
    check(&octree, &carved.detached, &anchors);
    // The terrain meshes where the piece was are listed.
    assert!(
        carved
            .changes
            .changed
            .iter()
            .any(|k| octree.cell_box(*k).touches(&slab))
    );
}

/// An arm out of a pillar: cut through at its root it falls; cut only
/// part of the way (by a tilted wedge) it stays.
#[test]
fn an_overhang_falls_only_when_cut_through() {
    let arm = cube([200, 500, 100], [600, 600, 200]);
    let build = || terrain(&[(cube([100, 0, 100], [200, 600, 200]), 1), (arm, 1)]);
    let config = DebrisConfig::default();
    // Part of the way: a wedge from below leaves the top of the arm.
    let mut octree = build();
    let p = |x, y, z| IntPoint::new(x, y, z).unwrap();
    let wedge = Tool::convex_hull(&[
        p(280, 480, 90),
        p(340, 480, 90),
        p(310, 570, 90),
        p(280, 480, 210),
        p(340, 480, 210),
        p(310, 570, 210),
    ])
    .unwrap();
    let before = octree.exact_volumes();
    let changes = octree.apply(&wedge, Edit::Subtract).unwrap();
    assert!(octree.exact_volumes() < before);
    let carved = octree.detach_after(&changes, &config).unwrap();
    assert!(carved.detached.pieces.is_empty());
    // Through: the part beyond the cut falls, exactly.
    let mut octree = build();
    let changes = subtract(&mut octree, cube([300, 490, 90], [320, 610, 210]));
    let after_carve = octree.exact_volumes();
    let carved = octree.detach_after(&changes, &config).unwrap();
    assert_eq!(carved.detached.pieces.len(), 1);
    assert_eq!(
        carved.detached.pieces[0].volume(),
        box_volume(cube([320, 500, 100], [600, 600, 200]))
    );
    assert_eq!(with_pieces(&octree, &carved.detached), after_carve);
    check(&octree, &carved.detached, &Anchors::default());
    // Through with the wedge from above and below: off-grid vertices.
    let mut octree = build();
    let through = Tool::convex_hull(&[
        p(280, 480, 90),
        p(350, 480, 90),
        p(330, 620, 90),
        p(300, 620, 90),
        p(280, 480, 210),
        p(350, 480, 210),
        p(330, 620, 210),
        p(300, 620, 210),
    ])
    .unwrap();
    let changes = octree.apply(&through, Edit::Subtract).unwrap();
    let after_carve = octree.exact_volumes();
    let carved = octree.detach_after(&changes, &config).unwrap();
    assert_eq!(carved.detached.pieces.len(), 1);
    let piece = carved.detached.pieces[0].volume();
    assert!(!piece.denominator().to_string().eq("1") || piece.to_f64() > 0.0);
    assert_eq!(with_pieces(&octree, &carved.detached), after_carve);
    check(&octree, &carved.detached, &Anchors::default());
}

/// Boxes touching a grounded block along an edge or at a point are pieces
/// of their own; one sharing part of a face is held.
#[test]
fn edges_and_points_do_not_connect_faces_do() {
    let base = cube([100, 0, 100], [200, 200, 200]);
    let on_edge = cube([200, 200, 100], [300, 300, 200]);
    let on_point = cube([0, 200, 200], [100, 300, 300]);
    let on_face = cube([150, 200, 150], [260, 260, 260]);
    let config = DebrisConfig::default();
    let mut octree = terrain(&[(base, 1), (on_edge, 1), (on_point, 2)]);
    let total = octree.exact_volumes();
    let detached = octree.detach_unanchored(&everywhere(), &config).unwrap();
    let volumes: Vec<ExactVolume> = detached.pieces.iter().map(|p| p.volume()).collect();
    assert_eq!(volumes.len(), 2, "{volumes:?}");
    assert!(volumes.contains(&box_volume(on_edge)));
    assert!(volumes.contains(&box_volume(on_point)));
    assert_eq!(with_pieces(&octree, &detached), total);
    assert_eq!(octree.exact_solid_volume(), box_volume(base));
    check(&octree, &detached, &Anchors::default());
    let mut octree = terrain(&[(base, 1), (on_face, 3)]);
    let detached = octree.detach_unanchored(&everywhere(), &config).unwrap();
    assert!(detached.pieces.is_empty());
    assert!(detached.changes.changed.is_empty() && detached.changes.removed.is_empty());
}

/// A floating block is held by an anchor box it has volume in, not by one
/// it only touches; another side of the cube can be the ground.
#[test]
fn anchor_boxes_and_sides_hold() {
    let block = cube([500, 300, 500], [600, 400, 600]);
    let mut octree = terrain(&[(block, 1)]);
    let held = DebrisConfig {
        anchors: Anchors {
            sides: vec![CubeSide::BOTTOM],
            boxes: vec![cube([590, 390, 590], [700, 700, 700])],
        },
        ..DebrisConfig::default()
    };
    let detached = octree.detach_unanchored(&everywhere(), &held).unwrap();
    assert!(detached.pieces.is_empty());
    // A box under the block, touching only its bottom face.
    let touching = DebrisConfig {
        anchors: Anchors {
            sides: Vec::new(),
            boxes: vec![cube([400, 0, 400], [700, 300, 700])],
        },
        ..DebrisConfig::default()
    };
    let mut copy = octree.clone();
    let detached = copy.detach_unanchored(&everywhere(), &touching).unwrap();
    assert_eq!(detached.pieces.len(), 1);
    assert_eq!(copy.exact_solid_volume(), ExactVolume::zero());
    // A block against the cube's upper x side, held by that side.
    let wall = cube([SIZE - 100, 300, 500], [SIZE, 400, 600]);
    let mut octree = terrain(&[(wall, 1), (block, 1)]);
    let sides = DebrisConfig {
        anchors: Anchors {
            sides: vec![CubeSide {
                axis: 0,
                upper: true,
            }],
            boxes: Vec::new(),
        },
        ..DebrisConfig::default()
    };
    let detached = octree.detach_unanchored(&everywhere(), &sides).unwrap();
    assert_eq!(detached.pieces.len(), 1);
    assert_eq!(detached.pieces[0].volume(), box_volume(block));
}

/// A piece of three materials keeps each one's exact volume.
#[test]
fn one_piece_of_several_materials() {
    let top = cube([100, 300, 100], [300, 400, 200]);
    let side = cube([300, 300, 100], [400, 400, 200]);
    let cap = cube([150, 400, 120], [250, 450, 180]);
    let mut octree = terrain(&[
        (cube([100, 0, 100], [200, 300, 200]), 1),
        (top, 2),
        (side, 3),
        (cap, 1),
    ]);
    let changes = subtract(&mut octree, cube([90, 100, 90], [210, 150, 210]));
    let after_carve = octree.exact_volumes();
    let carved = octree
        .detach_after(&changes, &DebrisConfig::default())
        .unwrap();
    let pieces = &carved.detached.pieces;
    assert_eq!(pieces.len(), 1);
    let stub = box_volume(cube([100, 150, 100], [200, 300, 200]));
    let expected: BTreeMap<Label, ExactVolume> = [
        (1, &stub + &box_volume(cap)),
        (2, box_volume(top)),
        (3, box_volume(side)),
    ]
    .into_iter()
    .collect();
    assert_eq!(pieces[0].volumes, expected);
    let labels: std::collections::BTreeSet<Label> =
        pieces[0].cells.iter().map(|c| c.label).collect();
    assert_eq!(labels.into_iter().collect::<Vec<_>>(), vec![1, 2, 3]);
    assert_eq!(with_pieces(&octree, &carved.detached), after_carve);
    check(&octree, &carved.detached, &Anchors::default());
}

/// Over the volume or the cell limit the detach is refused with a typed
/// error, and the octree is exactly as it was (also the carve, when both
/// run as one step).
#[test]
fn too_much_debris_is_refused_and_changes_nothing() {
    let slab = cube([100, 400, 100], [700, 500, 220]);
    let build = || terrain(&[(cube([100, 0, 100], [200, 400, 220]), 1), (slab, 1)]);
    let pillar = Tool::cuboid(cube([90, 100, 90], [210, 200, 230])).unwrap();
    let slab_volume = 600 * 100 * 120 + 100 * 200 * 120;
    let mut octree = build();
    let before = octree.to_bytes();
    let limited = DebrisConfig {
        max_volume: Some(slab_volume - 1),
        ..DebrisConfig::default()
    };
    let err = octree
        .apply_detaching(&pillar, Edit::Subtract, &limited)
        .unwrap_err();
    assert!(
        matches!(
            err,
            Error::TooMuchDebris {
                max_volume: Some(_),
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("debris"));
    assert_eq!(octree.to_bytes(), before);
    let changes = octree.apply(&pillar, Edit::Subtract).unwrap();
    let carved_bytes = octree.to_bytes();
    let cells = DebrisConfig {
        max_cells: Some(0),
        ..DebrisConfig::default()
    };
    let err = octree.detach_after(&changes, &cells).unwrap_err();
    assert!(matches!(
        err,
        Error::TooMuchDebris {
            max_cells: Some(0),
            ..
        }
    ));
    assert_eq!(octree.to_bytes(), carved_bytes);
    // At the limit exactly, it goes through.
    let exact = DebrisConfig {
        max_volume: Some(slab_volume),
        ..DebrisConfig::default()
    };
    let carved = octree.detach_after(&changes, &exact).unwrap();
    assert_eq!(
        carved.detached.volume(),
        ExactVolume::from_integer(slab_volume as i128)
    );
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

/// A small convex hull of random integer points (tilted planes, vertices
/// off the grid).
fn random_hull(rng: &mut ChaCha8Rng) -> Tool {
    let c = [0; 3].map(|_| rng.random_range(100..SIZE - 100));
    let points: Vec<IntPoint> = (0..8)
        .map(|_| {
            let q = c.map(|x| x + rng.random_range(-70..=70));
            IntPoint::new(q[0], q[1], q[2]).unwrap()
        })
        .collect();
    Tool::convex_hull(&points).unwrap()
}

/// A thin random cut across `pillar` at a random height: through it
/// when `through`, else through its lower x half.
fn random_cut(rng: &mut ChaCha8Rng, pillar: &CellBox, through: bool) -> CellBox {
    let mut b = *pillar;
    for a in [0, 2] {
        b.min[a] = (b.min[a] - 10).max(0);
        b.max[a] = (b.max[a] + 10).min(SIZE);
    }
    if !through {
        b.max[0] = (pillar.min[0] + pillar.max[0]) / 2;
    }
    b.min[1] = rng.random_range(pillar.min[1]..pillar.max[1] - 10);
    b.max[1] = b.min[1] + rng.random_range(10..60);
    b
}

/// Towers of random blocks on a ground slab, carved at random; after
/// each carve and detach no component is left unanchored, the volumes add
/// up exactly, and the combined changes name every leaf that is not the
/// stored leaf it was before the carve. Returns the octree's bytes after
/// each step, those of every piece, and the number of pieces the carves
/// made.
fn random_scene(seed: u64, carves: usize) -> (Vec<Vec<u8>>, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut boxes = vec![(cube([0, 0, 0], [SIZE, 40, SIZE]), 1)];
    let mut pillars = Vec::new();
    for _ in 0..5 {
        // A pillar with a block on top.
        let mut pillar = random_box(&mut rng, 0, SIZE, 60..160);
        pillar.min[1] = 40;
        pillar.max[1] = rng.random_range(200..700);
        let mut top = random_box(&mut rng, 0, SIZE, 80..300);
        let c = [0, 2].map(|a| (pillar.min[a] + pillar.max[a]) / 2);
        for (i, a) in [0, 2].into_iter().enumerate() {
            let e = top.max[a] - top.min[a];
            top.min[a] = (c[i] - e / 2).clamp(0, SIZE - e);
            top.max[a] = top.min[a] + e;
        }
        top.min[1] = pillar.max[1];
        top.max[1] = pillar.max[1] + rng.random_range(30..120);
        boxes.push((pillar, 1));
        boxes.push((top, rng.random_range(1..=3)));
        pillars.push(pillar);
    }
    let mut octree = terrain(&boxes);
    let anchors = Anchors::default();
    let config = DebrisConfig::default();
    // Whatever stands in the air falls first, wherever it is.
    let total = octree.exact_volumes();
    let detached = octree.detach_unanchored(&everywhere(), &config).unwrap();
    assert_eq!(with_pieces(&octree, &detached), total);
    check(&octree, &detached, &anchors);
    let mut snapshots = vec![octree.to_bytes()];
    let mut made = 0;
    for i in 0..carves {
        let before = octree.clone();
        let tool = if i % 3 == 2 {
            random_hull(&mut rng)
        } else {
            let pillar = pillars[rng.random_range(0..pillars.len())];
            Tool::cuboid(random_cut(&mut rng, &pillar, i % 3 == 0)).unwrap()
        };
        let changes = octree.apply(&tool, Edit::Subtract).unwrap();
        let after_carve = octree.exact_volumes();
        let carved = octree.detach_after(&changes, &config).unwrap();
        assert_eq!(
            with_pieces(&octree, &carved.detached),
            after_carve,
            "carve {i}"
        );
        check(&octree, &carved.detached, &anchors);
        check_changes(&before, &octree, &carved.changes);
        snapshots.push(octree.to_bytes());
        for piece in &carved.detached.pieces {
            snapshots.push(piece.solid.to_bytes());
        }
        made += carved.detached.pieces.len();
    }
    (snapshots, made)
}

/// Every leaf of `after` not in `changes.changed` is the leaf `before`
/// stored at that key; every leaf of `before` that is not a leaf of
/// `after` is in `changes.removed`, and nothing there is a leaf of `after`.
fn check_changes(before: &Octree, after: &Octree, changes: &Changes) {
    for (key, leaf) in after.leaves() {
        if changes.changed.binary_search(&key).is_err() {
            let old = before
                .leaf(key)
                .expect("an unchanged leaf was a leaf before");
            assert!(old.same_as(leaf), "{key:?} changed without being listed");
        }
    }
    for (key, _) in before.leaves() {
        if after.leaf(key).is_none() {
            assert!(
                changes.removed.binary_search(&key).is_ok(),
                "{key:?} not removed"
            );
        }
    }
    for key in &changes.removed {
        assert!(after.leaf(*key).is_none(), "{key:?} removed but a leaf");
    }
}

#[test]
fn random_carves_leave_no_debris_and_volumes_add_up() {
    let made: usize = (0..4).map(|seed| random_scene(seed, 10).1).sum();
    assert!(made >= 4, "the carves made {made} pieces");
}

#[test]
fn results_are_bit_identical_for_one_and_two_threads() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| random_scene(7, 8).0)
    };
    assert_eq!(run(1), run(2));
}
