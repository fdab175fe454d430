//! Octree files: a round trip is bit-identical (cells, planes, nodes,
//! labels, exact volumes, later edits, bytes written again); snapshots
//! share their BSPs again after loading; every truncation and random damage
//! is a typed error, never a panic; and crafted defects behind a valid
//! checksum give the specific error.

use crate::common;

use std::collections::BTreeMap;
use std::sync::Arc;

use chisel_bsp::Error;
use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::Plane;
use chisel_bsp::exact::budget::MAX_NORMAL;
use chisel_bsp::octree::store::{
    FORMAT_VERSION, MAGIC, MAX_STORED_BSP_DEPTH, checksum, snapshots_from_bytes, snapshots_to_bytes,
};
use chisel_bsp::octree::{CellBox, CellKey, Edit, Leaf, Octree, OctreeConfig, Tool};
use chisel_bsp::tree::{Bsp, EMPTY, Label, Node};
use common::shapes::{placed_dodecahedron, random_rotation};
use common::volume::{Fraction, volume};
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

fn block() -> Octree {
    let solid = CellBox {
        min: [100, 100, 100],
        max: [SIZE - 100, SIZE - 100, SIZE / 2],
    };
    Octree::from_box([-SIZE / 2, 0, 0], K, solid, 1, config()).expect("valid block")
}

fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let scale = rng.random_range(60.0..300.0);
    let rotation = random_rotation(rng);
    let at = [
        rng.random_range(-SIZE as f64 / 2.0..SIZE as f64 / 2.0),
        rng.random_range(0.0..SIZE as f64),
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.6),
    ];
    placed_dodecahedron(scale, rotation, at)
}

fn random_edit(rng: &mut ChaCha8Rng) -> Edit {
    match rng.random_range(0..10) {
        0..=5 => Edit::Subtract,
        6 | 7 => Edit::Add(rng.random_range(1..=3)),
        _ => Edit::Paint(rng.random_range(1..=3)),
    }
}

/// A block after `carves` random edits.
fn carved(seed: u64, carves: usize) -> Octree {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut octree = block();
    for _ in 0..carves {
        let tool = random_tool(&mut rng);
        octree
            .apply(&tool, random_edit(&mut rng))
            .expect("valid edit");
    }
    octree
}

/// Exact volume per non-empty label.
fn exact_volumes(octree: &Octree) -> BTreeMap<Label, Fraction> {
    let mut total: BTreeMap<Label, Fraction> = BTreeMap::new();
    for (key, leaf) in octree.leaves() {
        let mut arena = ConvexArena::new();
        let cell = octree.cell_box(key).add_to(&mut arena).expect("in range");
        for c in leaf.to_bsp().cells(&mut arena, cell) {
            if c.label != EMPTY {
                let e = total.entry(c.label).or_insert_with(Fraction::zero);
                *e = e.add(&volume(&arena, c.poly));
            }
        }
    }
    total
}

/// Same cube, settings, cells, and per cell the same label or the same
/// planes (exact coefficients), nodes and labels.
fn assert_identical(a: &Octree, b: &Octree) {
    assert_eq!(a.origin(), b.origin());
    assert_eq!(a.size_log2(), b.size_log2());
    assert_eq!(a.config(), b.config());
    let (la, lb) = (a.leaves(), b.leaves());
    assert_eq!(la.len(), lb.len());
    for ((ka, a), (kb, b)) in la.iter().zip(&lb) {
        assert_eq!(ka, kb);
        match (a, b) {
            (Leaf::Uniform(x), Leaf::Uniform(y)) => assert_eq!(x, y, "{ka:?}"),
            (Leaf::Bsp(x), Leaf::Bsp(y)) => {
                assert_eq!(x.nodes(), y.nodes(), "{ka:?}");
                assert_eq!(x.planes().len(), y.planes().len());
                for (p, q) in x.planes().iter().zip(y.planes()) {
                    assert_eq!(p.normal(), q.normal());
                    assert_eq!(p.offset(), q.offset());
                }
            }
            _ => panic!("{ka:?}: leaf kinds differ"),
        }
    }
}

/// The file with its checksum recomputed, so that the records behind it
/// are what the loader checks.
fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
    let end = bytes.len() - 8;
    let sum = checksum(&bytes[..end]);
    bytes[end..].copy_from_slice(&sum.to_le_bytes());
    bytes
}

#[test]
fn round_trips_are_bit_identical_after_random_carves() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut octree = block();
    for step in 0..24 {
        let tool = random_tool(&mut rng);
        octree
            .apply(&tool, random_edit(&mut rng))
            .expect("valid edit");
        if step % 6 != 5 {
            continue;
        }
        let bytes = octree.to_bytes();
        let loaded = Octree::from_bytes(&bytes).expect("loads");
        assert_identical(&octree, &loaded);
        assert_eq!(exact_volumes(&octree), exact_volumes(&loaded));
        assert_eq!(octree.volumes(), loaded.volumes());
        assert_eq!(octree.stats(), loaded.stats());
        assert_eq!(loaded.to_bytes(), bytes, "written again, the same bytes");
        // Both go on identically.
        let (mut a, mut b) = (octree.clone(), loaded);
        let tool = random_tool(&mut rng);
        let edit = random_edit(&mut rng);
        assert_eq!(a.apply(&tool, edit), b.apply(&tool, edit));
        assert_eq!(a.to_bytes(), b.to_bytes());
    }
    assert!(octree.stats().bsp_leaves > 10, "{:?}", octree.stats());
}

#[test]
fn uniform_and_single_leaf_octrees_round_trip() {
    let empty = Octree::new([0; 3], 3, EMPTY, OctreeConfig::default()).expect("valid cube");
    let back = Octree::from_bytes(&empty.to_bytes()).expect("loads");
    assert_identical(&empty, &back);
    let full = Octree::new([-8, -8, -8], 4, 7, OctreeConfig::default()).expect("valid cube");
    assert_identical(&full, &Octree::from_bytes(&full.to_bytes()).expect("loads"));
    let one = single_bsp_leaf();
    assert!(matches!(one.leaves()[..], [(_, Leaf::Bsp(_))]));
    assert_identical(&one, &Octree::from_bytes(&one.to_bytes()).expect("loads"));
}

#[test]
fn snapshots_share_their_bsps_again() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut history = vec![carved(11, 10)];
    for _ in 0..5 {
        let mut next = history[history.len() - 1].clone();
        next.apply(&random_tool(&mut rng), Edit::Subtract)
            .expect("valid edit");
        history.push(next);
    }
    let refs: Vec<&Octree> = history.iter().collect();
    let bytes = snapshots_to_bytes(&refs);
    let single: usize = history.iter().map(|o| o.to_bytes().len()).sum();
    assert!(bytes.len() * 2 < single, "{} vs {single}", bytes.len());
    let loaded = snapshots_from_bytes(&bytes).expect("loads");
    assert_eq!(loaded.len(), history.len());
    for (a, b) in history.iter().zip(&loaded) {
        assert_identical(a, b);
    }
    // A BSP shared by two snapshots is shared after loading, and only then.
    let first = &history[0];
    let last = &history[history.len() - 1];
    for (key, leaf) in first.leaves() {
        let (Leaf::Bsp(a), Some(Leaf::Bsp(b))) = (leaf, last.leaf(key)) else {
            continue;
        };
        let (Some(Leaf::Bsp(la)), Some(Leaf::Bsp(lb))) = (loaded[0].leaf(key), loaded[5].leaf(key))
        else {
            panic!("{key:?} is a BSP leaf in both");
        };
        assert_eq!(Arc::ptr_eq(a, b), Arc::ptr_eq(la, lb), "{key:?}");
    }
    let again: Vec<&Octree> = loaded.iter().collect();
    assert_eq!(snapshots_to_bytes(&again), bytes);
    assert!(matches!(
        Octree::from_bytes(&bytes),
        Err(Error::CorruptFile { .. })
    ));
}

#[test]
fn every_truncation_is_an_error() {
    let bytes = carved(5, 12).to_bytes();
    assert_eq!(Octree::from_bytes(&[]).err(), Some(Error::NotAnOctreeFile));
    for n in 1..bytes.len() {
        assert_eq!(
            Octree::from_bytes(&bytes[..n]).err(),
            Some(Error::TruncatedFile { at: n }),
            "truncated to {n} of {} bytes",
            bytes.len()
        );
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(matches!(
        Octree::from_bytes(&longer),
        Err(Error::CorruptFile { at: 12, .. })
    ));
}

#[test]
fn random_damage_is_an_error_and_never_a_panic() {
    let bytes = carved(9, 12).to_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..3000 {
        let mut damaged = bytes.clone();
        for _ in 0..rng.random_range(1..=4) {
            let at = rng.random_range(0..damaged.len());
            damaged[at] ^= rng.random_range(1..=255u8);
        }
        assert!(Octree::from_bytes(&damaged).is_err());
    }
}

#[test]
fn damage_behind_a_valid_checksum_never_panics() {
    // The checksum is recomputed, so every record check is exercised. Some
    // damage gives another valid octree (a changed label); that one must
    // then be a sound octree that writes and reads back.
    let bytes = carved(13, 8).to_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let (mut refused, mut accepted) = (0, 0);
    for _ in 0..4000 {
        let mut damaged = bytes.clone();
        for _ in 0..rng.random_range(1..=3) {
            let at = rng.random_range(20..damaged.len() - 8);
            damaged[at] = match rng.random_range(0..3) {
                0 => damaged[at] ^ (1 << rng.random_range(0..8)),
                1 => 0xff,
                _ => rng.random(),
            };
        }
        match Octree::from_bytes(&resealed(damaged)) {
            Err(_) => refused += 1,
            Ok(octree) => {
                accepted += 1;
                let again = Octree::from_bytes(&octree.to_bytes()).expect("reloads");
                assert_identical(&octree, &again);
            }
        }
    }
    assert!(refused > 1000 && accepted > 10, "{refused} {accepted}");
}

#[test]
fn wrong_magic_and_version_are_named() {
    let bytes = carved(1, 3).to_bytes();
    let mut magic = bytes.clone();
    magic[3] = b'x';
    assert_eq!(
        Octree::from_bytes(&magic).err(),
        Some(Error::NotAnOctreeFile)
    );
    assert_eq!(
        Octree::from_bytes(b"solid cube\nfacet normal").err(),
        Some(Error::NotAnOctreeFile)
    );
    assert_eq!(
        Octree::from_bytes(&MAGIC[..5]).err(),
        Some(Error::TruncatedFile { at: 5 })
    );
    let mut version = bytes.clone();
    version[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    assert_eq!(
        Octree::from_bytes(&version).err(),
        Some(Error::UnsupportedFormatVersion {
            found: FORMAT_VERSION + 1,
            supported: FORMAT_VERSION,
        })
    );
    let mut flipped = bytes.clone();
    let middle = bytes.len() / 2;
    flipped[middle] ^= 4;
    assert!(matches!(
        Octree::from_bytes(&flipped),
        Err(Error::ChecksumMismatch { .. })
    ));
}

/// A cube small enough that the block is one BSP leaf at the root.
fn single_bsp_leaf() -> Octree {
    let solid = CellBox {
        min: [1, 2, 3],
        max: [9, 10, 11],
    };
    Octree::from_box([0; 3], 4, solid, 2, OctreeConfig::default()).expect("valid box")
}

// Offsets in a file of one octree with one BSP leaf (see the layout in
// `chisel_bsp::octree::store`): header 20, node count 4, the leaf's tag 1,
// plane and BSP node counts 4 + 4, then the planes (40 bytes each), then
// the BSP nodes.
const FIRST_PLANE: usize = 20 + 4 + 1 + 8;
/// Bytes of one octree record: cube, settings, root.
const OCTREE: usize = 24 + 1 + 8 + 1 + 4;

/// A file from raw node records and octree records (`root` per octree,
/// each over the cube at the origin with edge `2^size_log2`), with a
/// valid length and checksum.
fn craft(nodes: &[Vec<u8>], octrees: &[(u8, u32)]) -> Vec<u8> {
    let mut bytes = MAGIC.to_vec();
    bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    bytes.extend_from_slice(&0u64.to_le_bytes());
    bytes.extend_from_slice(&(nodes.len() as u32).to_le_bytes());
    nodes.iter().for_each(|n| bytes.extend_from_slice(n));
    bytes.extend_from_slice(&(octrees.len() as u32).to_le_bytes());
    for &(size_log2, root) in octrees {
        bytes.extend_from_slice(&[0; 24]);
        bytes.push(size_log2);
        bytes.extend_from_slice(&150u64.to_le_bytes());
        bytes.push(20);
        bytes.extend_from_slice(&root.to_le_bytes());
    }
    let length = (bytes.len() + 8) as u64;
    bytes[12..20].copy_from_slice(&length.to_le_bytes());
    bytes.extend_from_slice(&[0; 8]);
    resealed(bytes)
}

fn inner(children: [u32; 8]) -> Vec<u8> {
    let mut node = vec![2];
    children
        .iter()
        .for_each(|c| node.extend_from_slice(&c.to_le_bytes()));
    node
}

#[test]
fn planes_outside_the_bit_budget_are_refused() {
    let bytes = single_bsp_leaf().to_bytes();
    let mut wide = bytes.clone();
    wide[FIRST_PLANE..FIRST_PLANE + 8].copy_from_slice(&(MAX_NORMAL + 1).to_le_bytes());
    assert_eq!(
        Octree::from_bytes(&resealed(wide)).err(),
        Some(Error::StoredPlaneOutOfBudget {
            at: FIRST_PLANE,
            cause: Box::new(Error::NormalOutOfRange {
                component: 0,
                value: MAX_NORMAL + 1
            }),
        })
    );
    let mut far = bytes.clone();
    far[FIRST_PLANE + 24..FIRST_PLANE + 40].copy_from_slice(&(1i128 << 100).to_le_bytes());
    assert!(matches!(
        Octree::from_bytes(&resealed(far)),
        Err(Error::StoredPlaneOutOfBudget { cause, .. })
            if matches!(*cause, Error::OffsetOutOfRange { .. })
    ));
    let mut zero = bytes;
    zero[FIRST_PLANE..FIRST_PLANE + 24].fill(0);
    assert!(matches!(
        Octree::from_bytes(&resealed(zero)),
        Err(Error::StoredPlaneOutOfBudget { cause, .. }) if *cause == Error::ZeroNormal
    ));
}

#[test]
fn broken_trees_are_refused() {
    let octree = single_bsp_leaf();
    let Leaf::Bsp(bsp) = octree.leaves()[0].1.clone() else {
        panic!("one BSP leaf");
    };
    let bytes = octree.to_bytes();
    let nodes = FIRST_PLANE + 40 * bsp.planes().len();
    // The root's `below` child pointing back at the root: not a tree.
    let mut cycle = bytes.clone();
    assert_eq!(cycle[nodes], 1, "the root is a split");
    cycle[nodes + 5..nodes + 9].copy_from_slice(&0u32.to_le_bytes());
    assert!(matches!(
        Octree::from_bytes(&resealed(cycle)),
        Err(Error::InvalidStoredBsp { index: 0, .. })
    ));
    let mut plane = bytes.clone();
    plane[nodes + 1..nodes + 5].copy_from_slice(&999u32.to_le_bytes());
    assert!(matches!(
        Octree::from_bytes(&resealed(plane)),
        Err(Error::InvalidStoredBsp { index: 0, .. })
    ));
    let mut tag = bytes.clone();
    tag[nodes] = 7;
    assert_eq!(
        Octree::from_bytes(&resealed(tag)).err(),
        Some(Error::CorruptFile {
            at: nodes,
            reason: "an unknown BSP node tag"
        })
    );
    let mut tag = bytes;
    tag[24] = 9;
    assert_eq!(
        Octree::from_bytes(&resealed(tag)).err(),
        Some(Error::CorruptFile {
            at: 24,
            reason: "an unknown octree node tag"
        })
    );
}

#[test]
fn bsps_deeper_than_any_the_kernel_builds_are_refused() {
    // A chain of splits x < 1, x < 2, …: each level one more split.
    let chain = |depth: u32| {
        let planes = (0..depth)
            .map(|k| Plane::new(-1, 0, 0, i128::from(k % 1000) + 1).expect("in budget"))
            .collect();
        let mut nodes = Vec::new();
        for k in 0..depth {
            let n = 2 * k;
            nodes.push(Node::Split {
                plane: k,
                below: n + 1,
                above: n + 2,
            });
            nodes.push(Node::Leaf(1));
        }
        nodes.push(Node::Leaf(EMPTY));
        let bsp = Bsp::from_stored_parts(planes, nodes).expect("a tree");
        Octree::from_leaves(
            [0; 3],
            10,
            OctreeConfig::default(),
            [(CellKey::ROOT, Leaf::Bsp(Arc::new(bsp)))],
        )
        .expect("one leaf")
    };
    let deep = chain(MAX_STORED_BSP_DEPTH as u32);
    assert_identical(&deep, &Octree::from_bytes(&deep.to_bytes()).expect("loads"));
    let deeper = chain(MAX_STORED_BSP_DEPTH as u32 + 1);
    assert!(matches!(
        Octree::from_bytes(&deeper.to_bytes()),
        Err(Error::InvalidStoredBsp { index: 0, .. })
    ));
}

#[test]
fn broken_octrees_are_refused() {
    let octree = carved(17, 4);
    assert!(octree.stats().depth >= 2);
    let bytes = octree.to_bytes();
    let record = bytes.len() - 8 - OCTREE;
    // A cube too small for the cells' nesting.
    let mut shallow = bytes.clone();
    assert_eq!(shallow[record + 24], K);
    shallow[record + 24] = 1;
    assert!(matches!(
        Octree::from_bytes(&resealed(shallow)),
        Err(Error::InvalidOctree { .. })
    ));
    // A cube beyond the exact range.
    let mut far = bytes.clone();
    far[record..record + 8].copy_from_slice(&(i64::MAX - 3).to_le_bytes());
    assert!(matches!(
        Octree::from_bytes(&resealed(far)),
        Err(Error::OctreeSize { .. })
    ));
    // A root beyond the node table.
    let mut root = bytes.clone();
    root[record + 34..record + 38].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(
        Octree::from_bytes(&resealed(root)),
        Err(Error::CorruptFile { .. })
    ));
    // The root (the last node) naming itself as a child: a cycle.
    let last = record - 4 - 33;
    let mut cycle = bytes.clone();
    assert_eq!(cycle[last], 2, "the root is an inner cell");
    let own = u32::from_le_bytes(bytes[20..24].try_into().unwrap()) - 1;
    cycle[last + 1..last + 5].copy_from_slice(&own.to_le_bytes());
    assert_eq!(
        Octree::from_bytes(&resealed(cycle)).err(),
        Some(Error::CorruptFile {
            at: last + 1,
            reason: "a child that is not stored before its parent"
        })
    );

    // Crafted files: the smallest valid one, a node no octree uses, and a
    // chain of inner cells each repeating the one below eight times (8^20
    // cells from 21 nodes), which would make every later walk explode.
    let empty = craft(&[vec![0, 0]], &[(3, 0)]);
    let back = Octree::from_bytes(&empty).expect("a valid empty octree");
    assert!(matches!(back.leaves()[..], [(_, Leaf::Uniform(EMPTY))]));
    assert!(matches!(
        Octree::from_bytes(&craft(&[vec![0, 0], vec![0, 1]], &[(3, 0)])),
        Err(Error::CorruptFile { .. })
    ));
    let one_level = craft(
        &[vec![0, 0], vec![0, 1], inner([0, 1, 0, 1, 0, 1, 0, 1])],
        &[(3, 2)],
    );
    assert_eq!(
        Octree::from_bytes(&one_level)
            .expect("valid")
            .leaves()
            .len(),
        8
    );
    let mut chain = vec![vec![0, 1]];
    for k in 0..20 {
        chain.push(inner([k; 8]));
    }
    assert_eq!(
        Octree::from_bytes(&craft(&chain, &[(20, 20)])).err(),
        Some(Error::InvalidOctree {
            reason: "more cells than the stored nodes can make"
        })
    );
}

#[test]
fn files_save_and_load() {
    let octree = carved(21, 6);
    let dir = std::env::temp_dir().join(format!("chisel-octree-store-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("carved.chisel");
    octree.save(&path).expect("saves");
    assert_identical(&octree, &Octree::load(&path).expect("loads"));
    let mut buffer = Vec::new();
    octree.write_to(&mut buffer).expect("writes");
    assert_identical(
        &octree,
        &Octree::read_from(buffer.as_slice()).expect("reads"),
    );
    std::fs::remove_dir_all(&dir).expect("cleans up");
    assert!(matches!(
        Octree::load(dir.join("missing.chisel")),
        Err(Error::Io { .. })
    ));
}

/// A file storing a node budget below [`OctreeConfig::MIN_BSP_NODES`]
/// (cells would be split to the depth limit) is refused.
#[test]
fn a_stored_budget_below_the_minimum_is_refused() {
    for budget in [0, 1, 7] {
        let config = OctreeConfig {
            max_bsp_nodes: budget,
            ..OctreeConfig::default()
        };
        let block = CellBox {
            min: [0; 3],
            max: [10; 3],
        };
        let octree = Octree::from_box([0; 3], 5, block, 1, config).unwrap();
        let err = Octree::from_bytes(&octree.to_bytes()).unwrap_err();
        assert!(err.to_string().contains("budget below 8"), "{err}");
    }
}
