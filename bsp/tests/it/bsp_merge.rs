//! Booleans by BSP merging, checked by exact volume identities on random
//! convex operands and on random Boolean sequences:
//! `vol(A ∪ B) + vol(A ∩ B) = vol(A) + vol(B)`,
//! `vol(A − B) = vol(A) − vol(A ∩ B)`, painting keeps the solid volume,
//! and every tree and cell stays valid.

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::tree::{BooleanOp, Bsp, EMPTY, Label};
use common::shapes::{self, p};
use common::volume::{Fraction, volume};
use num_bigint::BigInt;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const H: i64 = 1 << 16;

fn bounds(arena: &mut ConvexArena) -> PolyId {
    arena.add_box(p(-H, -H, -H), p(H, H, H)).unwrap()
}

fn random_convex_bsp(rng: &mut ChaCha8Rng, label: Label, spread: i64) -> Bsp {
    shapes::random_convex_bsp(rng, label, spread, (H / 8, H / 2), 6)
}

/// Exact volume of the material (any non-empty label) of `bsp` in the bounds.
fn solid_volume(bsp: &Bsp) -> Fraction {
    bsp.validate().unwrap();
    let mut arena = ConvexArena::new();
    let b = bounds(&mut arena);
    let mut total = Fraction::zero();
    for cell in bsp.cells(&mut arena, b) {
        arena.validate(cell.poly).unwrap();
        if cell.label != EMPTY {
            total = total.add(&volume(&arena, cell.poly));
        }
    }
    total
}

fn merge(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = bounds(&mut arena);
    let out = a.merge(b, op, &mut arena, bounds);
    out.validate().unwrap();
    out
}

fn neg(f: &Fraction) -> Fraction {
    Fraction {
        num: -f.num.clone(),
        den: f.den.clone(),
    }
}

#[test]
fn label_functions() {
    use BooleanOp::*;
    assert_eq!(Union.apply(0, 2), 2);
    assert_eq!(Union.apply(1, 2), 1);
    assert_eq!(Intersection.apply(1, 0), 0);
    assert_eq!(Intersection.apply(1, 2), 1);
    assert_eq!(Difference.apply(1, 2), 0);
    assert_eq!(Difference.apply(1, 0), 1);
    assert_eq!(Paint(5).apply(1, 2), 5);
    assert_eq!(Paint(5).apply(0, 2), 0);
}

#[test]
fn volume_identities_hold_exactly_on_random_operands() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    // A thousand pairs of operands, each the union of one to three random
    // convex solids (so most are not convex).
    let operand = |rng: &mut ChaCha8Rng, label: Label| {
        let mut acc = random_convex_bsp(rng, label, H / 2);
        for _ in 0..rng.random_range(0..3) {
            let more = random_convex_bsp(rng, label, H / 2);
            acc = merge(&acc, &more, BooleanOp::Union);
        }
        acc
    };
    for _ in 0..1000 {
        let a = operand(&mut rng, 1);
        let b = operand(&mut rng, 2);
        let (va, vb) = (solid_volume(&a), solid_volume(&b));
        let union = solid_volume(&merge(&a, &b, BooleanOp::Union));
        let inter = solid_volume(&merge(&a, &b, BooleanOp::Intersection));
        let diff = solid_volume(&merge(&a, &b, BooleanOp::Difference));
        let paint = merge(&a, &b, BooleanOp::Paint(9));
        assert_eq!(
            union.add(&inter),
            va.add(&vb),
            "vol(A∪B) + vol(A∩B) = vol(A) + vol(B)"
        );
        assert_eq!(diff, va.add(&neg(&inter)), "vol(A−B) = vol(A) − vol(A∩B)");
        assert_eq!(solid_volume(&paint), va, "painting keeps the solid");
    }
}

/// Random Boolean sequences: the running result keeps satisfying the
/// identities and stays a valid tree.
#[test]
fn random_boolean_sequences_keep_the_identities() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut overlapping = 0;
    for _ in 0..3 {
        let mut acc = random_convex_bsp(&mut rng, 1, H / 8);
        let mut v_acc = solid_volume(&acc);
        for step in 0..12 {
            let tool = random_convex_bsp(&mut rng, 1 + (step % 3) as Label, H / 8);
            let v_tool = solid_volume(&tool);
            let inter = solid_volume(&merge(&acc, &tool, BooleanOp::Intersection));
            let op = if rng.random_bool(0.5) {
                BooleanOp::Union
            } else {
                BooleanOp::Difference
            };
            acc = merge(&acc, &tool, op);
            let v_new = solid_volume(&acc);
            let expected = match op {
                BooleanOp::Union => v_acc.add(&v_tool).add(&neg(&inter)),
                _ => v_acc.add(&neg(&inter)),
            };
            assert_eq!(v_new, expected, "step {step}: {op:?}");
            assert!(v_new.num >= BigInt::from(0));
            overlapping += usize::from(inter.is_positive());
            v_acc = v_new;
        }
    }
    assert!(
        overlapping >= 10,
        "tools overlap the solid: {overlapping} of 36"
    );
}

/// Every face of a cell as its plane, tag and corners, in traversal order.
fn cell_faces(arena: &ConvexArena, poly: PolyId) -> Vec<String> {
    arena
        .faces_of(poly)
        .into_iter()
        .map(|f| {
            let face = arena.faces()[f as usize];
            let corners: Vec<String> = arena
                .face_loop(f)
                .map(|h| {
                    let v = arena.half_edges()[h as usize].origin;
                    format!("{:?}", arena.point(v))
                })
                .collect();
            format!("{:?} {} {corners:?}", arena.face_plane(f), face.tag)
        })
        .collect()
}

/// The cells the merge keeps are those `cells()` cuts from its result,
/// polyhedron for polyhedron (planes, tags, corners, traversal order), and
/// merging with simplification gives the same tree as the two steps.
#[test]
fn merge_keeps_the_cells_of_its_result() {
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    let ops = [
        BooleanOp::Union,
        BooleanOp::Intersection,
        BooleanOp::Difference,
        BooleanOp::Paint(3),
    ];
    for round in 0..6 {
        let mut acc = random_convex_bsp(&mut rng, 1, H / 4);
        for step in 0..10 {
            let tool = random_convex_bsp(&mut rng, 1 + (step % 3) as Label, H / 4);
            let op = ops[(round + step) % ops.len()];
            let mut arena = ConvexArena::new();
            let b = bounds(&mut arena);
            let (merged, cells) = acc.merge_cells(&tool, op, &mut arena, b);
            assert_eq!(merged, merge(&acc, &tool, op), "the same tree");
            let mut again = ConvexArena::new();
            let b = bounds(&mut again);
            let expected = merged.cells(&mut again, b);
            assert_eq!(cells.len(), expected.len(), "round {round} step {step}");
            for (c, e) in cells.iter().zip(&expected) {
                assert_eq!((c.leaf, c.label), (e.leaf, e.label));
                arena.validate(c.poly).unwrap();
                assert_eq!(cell_faces(&arena, c.poly), cell_faces(&again, e.poly));
            }
            let mut arena = ConvexArena::new();
            let b = bounds(&mut arena);
            let simplified = acc.merge_simplified(&tool, op, &mut arena, b);
            let mut arena = ConvexArena::new();
            let b = bounds(&mut arena);
            assert_eq!(simplified, merged.simplified(&mut arena, b));
            // Keep the operand small and non-convex, as octree leaves are.
            acc = if merged.nodes().len() > 1 {
                simplified
            } else {
                random_convex_bsp(&mut rng, 1, H / 4)
            };
        }
    }
}
