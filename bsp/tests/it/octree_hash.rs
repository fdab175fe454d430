//! The octree state hash: updated per edit it equals the hash computed
//! from scratch, equal octrees hash equal for any thread count, and edits
//! that change the content change the hash.

use chisel_bsp::octree::store::checksum;
use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, StateHash, Tool};
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 12;
const SIZE: i64 = 1 << K;

fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 40,
        max_depth: 6,
    }
}

fn start() -> Octree {
    let block = CellBox {
        min: [100, 100, 100],
        max: [SIZE - 100, SIZE - 100, SIZE / 2],
    };
    Octree::from_box([0; 3], K, block, 1, config()).unwrap()
}

fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let scale = rng.random_range(60.0..300.0);
    let at = Pose::at([
        rng.random_range(0.0..SIZE as f64),
        rng.random_range(0.0..SIZE as f64),
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.6),
    ]);
    Tool::placed(&dodecahedron_corners(scale), &at).unwrap()
}

fn random_edit(rng: &mut ChaCha8Rng) -> Edit {
    match rng.random_range(0..10) {
        0..=5 => Edit::Subtract,
        6 | 7 => Edit::Add(rng.random_range(1..=3)),
        _ => Edit::Paint(rng.random_range(1..=3)),
    }
}

#[test]
fn the_updated_hash_equals_the_hash_from_scratch_after_every_edit_and_undo() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut octree = start();
    let mut hash = StateHash::of(&octree);
    let mut history = Vec::new();
    let mut seen = std::collections::HashSet::new();
    seen.insert(hash.value());
    for _ in 0..40 {
        let before = octree.clone();
        let changes = octree
            .apply(&random_tool(&mut rng), random_edit(&mut rng))
            .unwrap();
        hash.update(&octree, changes.changed.iter().chain(&changes.removed));
        assert_eq!(hash, StateHash::of(&octree));
        assert_eq!(hash.value(), octree.state_hash());
        assert_eq!(hash.cells(), octree.leaves().len());
        if !changes.changed.is_empty() {
            // Every carve here changes the solid, so every state is new.
            assert!(seen.insert(hash.value()), "a new state repeated a hash");
        }
        history.push((before, changes));
    }
    // Undo everything: the same keys bring the hash back.
    while let Some((before, changes)) = history.pop() {
        octree = before;
        hash.update(&octree, changes.changed.iter().chain(&changes.removed));
        assert_eq!(hash.value(), octree.state_hash());
    }
    assert_eq!(hash.value(), start().state_hash());
}

#[test]
fn equal_octrees_hash_equal_for_any_thread_count_and_after_a_file_round_trip() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut rng = ChaCha8Rng::seed_from_u64(22);
            let mut octree = start();
            let mut hash = StateHash::of(&octree);
            for _ in 0..25 {
                let changes = octree
                    .apply(&random_tool(&mut rng), random_edit(&mut rng))
                    .unwrap();
                hash.update(&octree, changes.changed.iter().chain(&changes.removed));
            }
            (hash.value(), octree.to_bytes())
        })
    };
    let (one, bytes_one) = run(1);
    let (four, bytes_four) = run(4);
    assert_eq!(bytes_one, bytes_four);
    assert_eq!(one, four);
    let back = Octree::from_bytes(&bytes_one).unwrap();
    assert_eq!(back.state_hash(), one);
}

#[test]
fn the_hash_is_the_specified_one() {
    // Pinned: the definition in `chisel_bsp::octree::hash` fixes the value
    // on every machine and in every build.
    let octree = Octree::new([0; 3], 4, 1, config()).unwrap();
    let hash = octree.state_hash();
    // By the definition: the root leaf's record is tag 0, label 1.
    let record = checksum(&[0, 1]);
    let mut cell = vec![0u8; 13];
    cell.extend_from_slice(&record.to_le_bytes());
    let sum = checksum(&cell);
    let mut top = vec![0u8; 24];
    top.push(4);
    top.extend_from_slice(&sum.to_le_bytes());
    assert_eq!(hash, checksum(&top));
    assert_eq!(hash, PINNED, "state hash of a uniform cube: {hash:#018x}");
    // A different label or a different cube gives another hash.
    assert_ne!(
        Octree::new([0; 3], 4, 2, config()).unwrap().state_hash(),
        hash
    );
    assert_ne!(
        Octree::new([2; 3], 4, 1, config()).unwrap().state_hash(),
        hash
    );
}

const PINNED: u64 = 0x3e3f_6af9_5904_c30e;
