//! A long random Boolean sequence (§3.5 + §3.7, as every octree cell runs
//! it): hundreds of steps of union, difference, intersection and painting
//! with random convex tools, each result rebuilt without redundancy, with
//! the exact volume identity, tree validity and cell validity checked at
//! every step, and the whole sequence replayed bit-identically.

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::tree::{BooleanOp, Bsp, EMPTY, Label};
use common::shapes::{self, p};
use common::volume::{Fraction, volume};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const H: i64 = 1 << 16;
const STEPS: usize = 200;

fn bounds(arena: &mut ConvexArena) -> PolyId {
    arena.add_box(p(-H, -H, -H), p(H, H, H)).unwrap()
}

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

fn merged(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = bounds(&mut arena);
    let out = a.merge(b, op, &mut arena, bounds);
    let mut arena = ConvexArena::new();
    let bounds = self::bounds(&mut arena);
    out.simplified(&mut arena, bounds)
}

fn neg(f: &Fraction) -> Fraction {
    Fraction {
        num: -f.num.clone(),
        den: f.den.clone(),
    }
}

/// Runs the sequence; returns every intermediate tree.
fn run(seed: u64, check: bool) -> Vec<Bsp> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut acc = shapes::random_convex_bsp(&mut rng, 1, H / 4, (H / 4, H / 2), 6);
    let mut v_acc = if check {
        solid_volume(&acc)
    } else {
        Fraction::zero()
    };
    let mut trees = Vec::with_capacity(STEPS);
    for step in 0..STEPS {
        let label: Label = rng.random_range(1..=3);
        let tool = shapes::random_convex_bsp(&mut rng, label, H / 2, (H / 16, H / 4), 5);
        let op = match rng.random_range(0..8) {
            0..=2 => BooleanOp::Union,
            3..=5 => BooleanOp::Difference,
            6 => BooleanOp::Paint(label),
            _ => BooleanOp::Intersection,
        };
        // Keep the workpiece from vanishing: intersect with big tools only.
        let op = if op == BooleanOp::Intersection && step % 6 != 0 {
            BooleanOp::Union
        } else {
            op
        };
        let next = merged(&acc, &tool, op);
        if check {
            let v_next = solid_volume(&next);
            let v_tool = solid_volume(&tool);
            let inter = solid_volume(&merged(&acc, &tool, BooleanOp::Intersection));
            let expected = match op {
                BooleanOp::Union => v_acc.add(&v_tool).add(&neg(&inter)),
                BooleanOp::Difference => v_acc.add(&neg(&inter)),
                BooleanOp::Intersection => inter,
                BooleanOp::Paint(_) => v_acc.clone(),
            };
            assert_eq!(v_next, expected, "step {step}: {op:?}");
            v_acc = v_next;
        }
        acc = next;
        trees.push(acc.clone());
    }
    trees
}

#[test]
fn hundreds_of_random_booleans_keep_exact_volumes_and_replay_identically() {
    let first = run(99, true);
    let second = run(99, false);
    for (step, (a, b)) in first.iter().zip(&second).enumerate() {
        assert_eq!(a.nodes(), b.nodes(), "step {step}");
        assert_eq!(a.planes(), b.planes(), "step {step}");
    }
    let largest = first.iter().map(|t| t.nodes().len()).max().unwrap_or(0);
    assert!(
        largest > 150,
        "the trees stayed trivial: at most {largest} nodes"
    );
    assert!(
        first.last().unwrap().nodes().len() > 10,
        "the workpiece vanished"
    );
}
