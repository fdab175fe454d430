//! What an edit changed of each material (`Changes::exact_volume_change`,
//! and in `f64` `Changes::volume_change`):
//! measured only in the cells the edit names, it equals, exactly, the
//! whole octree's volumes after the edit less before, for every kind of
//! edit, through splits and combines; with debris taken out, it is the
//! carve's change less the pieces; and `exact_volumes_in` counts nested
//! cells and cells inside a leaf once.

use std::collections::BTreeMap;

use chisel_bsp::octree::{
    CellBox, CellKey, DebrisConfig, Edit, ExactVolume, Octree, OctreeConfig, Tool,
};
use chisel_bsp::tools::{Pose, dodecahedron_corners};
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

/// `after − before` per material, zeros left out.
fn difference(
    after: &BTreeMap<Label, ExactVolume>,
    before: &BTreeMap<Label, ExactVolume>,
) -> BTreeMap<Label, ExactVolume> {
    let mut out = after.clone();
    for (label, v) in before {
        let entry = out.entry(*label).or_default();
        *entry = &*entry - v;
    }
    out.retain(|_, v| !v.is_zero());
    out
}

/// A random dodecahedron or box somewhere in the cube.
fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let centre = [0, 1, 2].map(|_| rng.random_range(100.0..(SIZE as f64 - 100.0)));
    if rng.random_bool(0.5) {
        let mut pose = Pose::at(centre);
        let angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let (s, c) = angle.sin_cos();
        pose.rotation = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]];
        Tool::placed(&dodecahedron_corners(rng.random_range(40.0..160.0)), &pose).unwrap()
    } else {
        let half = [0, 1, 2].map(|_| rng.random_range(20..150));
        let min = [0, 1, 2].map(|a| centre[a] as i64 - half[a]);
        let max = [0, 1, 2].map(|a| centre[a] as i64 + half[a]);
        Tool::cuboid(CellBox { min, max }).unwrap()
    }
}

/// Random subtractions, additions and paints with three materials: after
/// every edit the change measured in its cells is the whole octree's,
/// exactly, and has the sign the edit allows.
#[test]
fn the_change_in_the_named_cells_is_the_whole_octrees() {
    for seed in 0..4 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut octree = Octree::new([0; 3], K, 0, config()).unwrap();
        let ground = CellBox {
            min: [0; 3],
            max: [SIZE, SIZE / 2, SIZE],
        };
        octree
            .apply(&Tool::cuboid(ground).unwrap(), Edit::Add(1))
            .unwrap();
        let start = octree.exact_volumes();
        let mut total: BTreeMap<Label, ExactVolume> = BTreeMap::new();
        for step in 0..40 {
            let tool = random_tool(&mut rng);
            let edit = match rng.random_range(0..6) {
                0 => Edit::Add(rng.random_range(1..=3)),
                1 => Edit::Paint(rng.random_range(1..=3)),
                _ => Edit::Subtract,
            };
            let before = octree.clone();
            let changes = octree.apply(&tool, edit).unwrap();
            let change = changes.exact_volume_change(&before, &octree);
            let whole = difference(&octree.exact_volumes(), &before.exact_volumes());
            assert_eq!(change, whole, "seed {seed}, step {step}, {edit:?}");
            // Summed in `f64`, the same change up to rounding.
            let rounded = changes.volume_change(&before, &octree);
            for label in 1..=3 {
                let exact = change.get(&label).map_or(0.0, ExactVolume::to_f64);
                let sum = rounded.get(&label).copied().unwrap_or(0.0);
                assert!(
                    (sum - exact).abs() <= 1e-5,
                    "{label}: {sum} against {exact}"
                );
            }
            let zero = ExactVolume::zero();
            match edit {
                Edit::Subtract => assert!(change.values().all(|v| *v < zero)),
                Edit::Add(label) => {
                    assert!(change.keys().all(|l| *l == label));
                    assert!(change.values().all(|v| *v > zero));
                }
                Edit::Paint(_) => {
                    let sum: ExactVolume = change.values().cloned().sum();
                    assert!(sum.is_zero(), "painting keeps the solid's volume");
                }
                Edit::Intersect => {}
            }
            for (label, v) in change {
                *total.entry(label).or_default() += &v;
            }
        }
        let run = difference(&octree.exact_volumes(), &start);
        total.retain(|_, v| !v.is_zero());
        assert_eq!(total, run, "seed {seed}: the changes add up to the run's");
    }
}

/// Where a carve cuts a piece loose, the changes of carve and detach
/// together are the carve's change less the pieces' volumes.
#[test]
fn debris_taken_out_is_part_of_the_change() {
    let mut octree = Octree::new([0; 3], K, 0, config()).unwrap();
    let slab = CellBox {
        min: [100, 400, 100],
        max: [700, 500, 220],
    };
    for b in [
        CellBox {
            min: [100, 0, 100],
            max: [200, 400, 220],
        },
        slab,
    ] {
        octree
            .apply(&Tool::cuboid(b).unwrap(), Edit::Add(2))
            .unwrap();
    }
    let before = octree.clone();
    let pillar = CellBox {
        min: [90, 30, 90],
        max: [210, 400, 230],
    };
    let changes = octree
        .apply(&Tool::cuboid(pillar).unwrap(), Edit::Subtract)
        .unwrap();
    let carve = changes.exact_volume_change(&before, &octree);
    let carved = octree
        .detach_after(&changes, &DebrisConfig::default())
        .unwrap();
    assert_eq!(carved.detached.pieces.len(), 1);
    let both = carved.changes.exact_volume_change(&before, &octree);
    let piece = carved.detached.pieces[0].volume();
    assert_eq!(piece, ExactVolume::of_box(&slab));
    assert_eq!(&both[&2], &(&carve[&2] - &piece));
    assert_eq!(
        both,
        difference(&octree.exact_volumes(), &before.exact_volumes())
    );
}

/// Cells that nest count once; a cell inside a leaf counts its part.
#[test]
fn volumes_in_cells_count_each_point_once() {
    let mut octree = Octree::new([0; 3], K, 0, config()).unwrap();
    let half = CellBox {
        min: [0; 3],
        max: [SIZE, SIZE / 2, SIZE],
    };
    octree
        .apply(&Tool::cuboid(half).unwrap(), Edit::Add(1))
        .unwrap();
    let pose = Pose::at([500.0, 512.0, 500.0]);
    let crater = Tool::placed(&dodecahedron_corners(120.0), &pose).unwrap();
    octree.apply(&crater, Edit::Subtract).unwrap();
    let all = octree.exact_volumes();
    let children: Vec<CellKey> = (0..8).map(|i| CellKey::ROOT.child(i)).collect();
    assert_eq!(octree.exact_volumes_in(&children), all);
    let mut nested = children.clone();
    nested.push(CellKey::ROOT);
    nested.push(CellKey::ROOT.child(3).child(5));
    assert_eq!(octree.exact_volumes_in(&nested), all);
    // The lower half's far corner is one uniform leaf: a cell deep inside
    // it holds its box of material 1.
    let deep = CellKey::ROOT.child(0).child(0).child(0).child(0);
    let inside = octree.exact_volumes_in(&[deep]);
    assert_eq!(
        inside,
        BTreeMap::from([(1, ExactVolume::of_box(&octree.cell_box(deep)))])
    );
    // Cells along the crater: their leaves' parts in the cell add up.
    let parts: Vec<CellKey> = (0..8).map(|i| CellKey::ROOT.child(6).child(i)).collect();
    let sum = (0..8).map(|i| octree.exact_volumes_in(&parts[i..=i])).fold(
        BTreeMap::<Label, ExactVolume>::new(),
        |mut acc, part| {
            for (label, v) in part {
                *acc.entry(label).or_default() += &v;
            }
            acc
        },
    );
    assert_eq!(octree.exact_volumes_in(&parts), sum);
    assert_eq!(
        octree.exact_volumes_in(&[CellKey::ROOT.child(6)]),
        sum,
        "a cell and its eight children hold the same"
    );
    // Keys outside the cube measure nothing.
    let outside = [
        CellKey {
            depth: 1,
            pos: [2, 0, 0],
        },
        CellKey {
            depth: K + 1,
            pos: [0; 3],
        },
    ];
    assert!(octree.exact_volumes_in(&outside).is_empty());
}
