//! Property-based fuzzing of what enters the kernel from outside: octree
//! files (`Octree::from_bytes`) damaged at random never panic and, when
//! they are accepted, store back to the same bytes; random exact Booleans
//! of convex hulls on an octree keep the volume identities exactly
//! (`V(A ∪ B) + V(A ∩ B) = V(A) + V(B)`, `V(A − B) = V(A) − V(A ∩ B)`, as
//! rationals). The case count is small in the normal run; `scripts/fuzz`
//! raises it (`PROPTEST_CASES`).

use crate::common;

use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use common::octree_reference::octree_volumes;
use common::volume::Fraction;
use proptest::prelude::*;

/// `PROPTEST_CASES` when set (long runs), else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

const K: u8 = 10;

fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 24,
        max_depth: 5,
    }
}

/// A small carved octree's file: some BSP leaves, two materials.
fn sample_file() -> Vec<u8> {
    let block = CellBox {
        min: [100; 3],
        max: [900; 3],
    };
    let mut octree = Octree::from_box([0; 3], K, block, 1, config()).unwrap();
    for (i, at) in [[300.0, 400.0, 900.0], [700.0, 600.0, 500.0]]
        .iter()
        .enumerate()
    {
        let tool = Tool::placed(&dodecahedron_corners(150.0), &Pose::at(*at)).unwrap();
        let edit = if i == 0 {
            Edit::Subtract
        } else {
            Edit::Paint(2)
        };
        octree.apply(&tool, edit).unwrap();
    }
    octree.to_bytes()
}

/// A random edit of a byte string: flip bytes, truncate, insert or
/// overwrite a run.
#[derive(Clone, Debug)]
enum Damage {
    Flip(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Overwrite(usize, Vec<u8>),
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        (any::<usize>(), 1..=255u8).prop_map(|(at, x)| Damage::Flip(at, x)),
        any::<usize>().prop_map(Damage::Truncate),
        (
            any::<usize>(),
            proptest::collection::vec(any::<u8>(), 1..16)
        )
            .prop_map(|(at, b)| Damage::Insert(at, b)),
        (
            any::<usize>(),
            proptest::collection::vec(any::<u8>(), 1..16)
        )
            .prop_map(|(at, b)| Damage::Overwrite(at, b)),
    ]
}

fn apply(bytes: &mut Vec<u8>, d: &Damage) {
    let n = bytes.len().max(1);
    match d {
        Damage::Flip(at, x) => {
            if let Some(b) = bytes.get_mut(at % n) {
                *b ^= x;
            }
        }
        Damage::Truncate(at) => bytes.truncate(at % n),
        Damage::Insert(at, run) => {
            let at = at % n;
            bytes.splice(at..at, run.iter().copied());
        }
        Damage::Overwrite(at, run) => {
            for (k, x) in run.iter().enumerate() {
                if let Some(b) = bytes.get_mut((at + k) % n) {
                    *b = *x;
                }
            }
        }
    }
}

/// A random convex hull of a few points in the octree's cube.
fn hull() -> impl Strategy<Value = Vec<[i64; 3]>> {
    let size = 1i64 << K;
    (
        proptest::array::uniform3(0..size),
        proptest::collection::vec(proptest::array::uniform3(-250i64..250), 4..10),
    )
        .prop_map(move |(c, offsets)| {
            offsets
                .iter()
                .map(|o| [0, 1, 2].map(|a| (c[a] + o[a]).clamp(0, size)))
                .collect()
        })
}

fn tool(points: &[[i64; 3]]) -> Option<Tool> {
    let points: Vec<IntPoint> = points
        .iter()
        .map(|&p| IntPoint::from_array(p).unwrap())
        .collect();
    Tool::convex_hull(&points).ok()
}

/// The solid of `tools` added one after another to an empty octree.
fn solid(tools: &[&Tool]) -> Octree {
    let mut octree = Octree::new([0; 3], K, 0, config()).unwrap();
    for t in tools {
        octree.apply(t, Edit::Add(1)).unwrap();
    }
    octree
}

fn total(octree: &Octree) -> Fraction {
    octree_volumes(octree)
        .values()
        .fold(Fraction::zero(), |a, v| a.add(v))
}

/// `bytes` with its body (after the header, before the checksum) damaged
/// by `edits`, then the length and checksum fields made right again, so
/// that the damage reaches the record checks behind them.
fn damaged_and_resealed(mut bytes: Vec<u8>, edits: &[Damage]) -> Vec<u8> {
    let checksum = bytes.split_off(bytes.len() - 8);
    let mut body = bytes.split_off(20);
    for d in edits {
        apply(&mut body, d);
    }
    bytes.extend(body);
    let length = bytes.len() as u64 + checksum.len() as u64;
    bytes[12..20].copy_from_slice(&length.to_le_bytes());
    let sum = chisel_bsp::octree::store::checksum(&bytes);
    bytes.extend(sum.to_le_bytes());
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(256)))]

    #[test]
    fn fuzz_damaged_octree_files_never_panic(
        edits in proptest::collection::vec(damage(), 1..4),
        reseal in any::<bool>(),
    ) {
        let bytes = if reseal {
            damaged_and_resealed(sample_file(), &edits)
        } else {
            let mut bytes = sample_file();
            for d in &edits {
                apply(&mut bytes, d);
            }
            bytes
        };
        if let Ok(octree) = Octree::from_bytes(&bytes) {
            // Accepted: a valid octree, which stores back to a file that
            // reads as the same octree.
            let again = octree.to_bytes();
            let back = Octree::from_bytes(&again).unwrap();
            prop_assert_eq!(back.to_bytes(), again);
        }
        // Terrain snapshots are the same records.
        let _ = chisel_bsp::octree::store::snapshots_from_bytes(&bytes);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(12)))]

    #[test]
    fn fuzz_booleans_keep_exact_volume_identities(a in hull(), b in hull()) {
        let (Some(a), Some(b)) = (tool(&a), tool(&b)) else {
            return Ok(());
        };
        let va = total(&solid(&[&a]));
        prop_assert!(va.is_positive());
        let vb = total(&solid(&[&b]));
        let union = total(&solid(&[&a, &b]));
        let mut meet = solid(&[&a]);
        meet.apply(&b, Edit::Intersect).unwrap();
        let meet = total(&meet);
        let mut minus = solid(&[&a]);
        minus.apply(&b, Edit::Subtract).unwrap();
        let minus = total(&minus);
        prop_assert_eq!(union.add(&meet), va.add(&vb));
        prop_assert_eq!(minus.add(&meet), va);
    }
}
