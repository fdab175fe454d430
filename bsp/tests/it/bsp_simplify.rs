//! Redundancy removal (§3.7): the rebuilt BSP has exactly the regions of the
//! original inside the bounds — per material, checked by exact volumes —
//! never more nodes than needed for random Boolean results, and no plane of
//! the bounds.

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::tree::{BooleanOp, Bsp, Label, Node};
use common::shapes::{self, p};
use common::volume::{Fraction, volume};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

const H: i64 = 1 << 16;

fn bounds(arena: &mut ConvexArena, lo: i64, hi: i64) -> PolyId {
    arena.add_box(p(lo, lo, lo), p(hi, hi, hi)).unwrap()
}

/// Exact volume of every label of `bsp` inside the cube `[lo, hi]³`.
fn volumes(bsp: &Bsp, lo: i64, hi: i64) -> BTreeMap<Label, Fraction> {
    bsp.validate().unwrap();
    let mut arena = ConvexArena::new();
    let b = bounds(&mut arena, lo, hi);
    let mut out: BTreeMap<Label, Fraction> = BTreeMap::new();
    for cell in bsp.cells(&mut arena, b) {
        let v = volume(&arena, cell.poly);
        let e = out.entry(cell.label).or_insert_with(Fraction::zero);
        *e = e.add(&v);
    }
    out
}

fn simplified(bsp: &Bsp, lo: i64, hi: i64) -> Bsp {
    let mut arena = ConvexArena::new();
    let b = bounds(&mut arena, lo, hi);
    let out = bsp.simplified(&mut arena, b);
    out.validate().unwrap();
    out
}

fn merge(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = bounds(&mut arena, -H, H);
    a.merge(b, op, &mut arena, bounds)
}

fn random_operand(rng: &mut ChaCha8Rng, label: Label) -> Bsp {
    shapes::random_convex_bsp(rng, label, H / 2, (H / 8, H / 2), 6)
}

#[test]
fn rebuilt_regions_equal_the_originals_per_material() {
    let mut rng = ChaCha8Rng::seed_from_u64(71);
    let ops = [
        BooleanOp::Union,
        BooleanOp::Difference,
        BooleanOp::Intersection,
        BooleanOp::Paint(3),
    ];
    let (mut before, mut after) = (0, 0);
    for case in 0..150 {
        let mut acc = random_operand(&mut rng, 1 + (case % 2) as Label);
        for _ in 0..3 {
            let label = rng.random_range(1..=4);
            let b = random_operand(&mut rng, label);
            acc = merge(&acc, &b, ops[rng.random_range(0..ops.len())]);
        }
        let rebuilt = simplified(&acc, -H, H);
        assert_eq!(
            volumes(&rebuilt, -H, H),
            volumes(&acc, -H, H),
            "case {case}"
        );
        before += acc.nodes().len();
        after += rebuilt.nodes().len();
        // Idempotent in geometry, and deterministic.
        let again = simplified(&rebuilt, -H, H);
        assert_eq!(volumes(&again, -H, H), volumes(&acc, -H, H), "case {case}");
        let twice = simplified(&acc, -H, H);
        assert_eq!(twice.nodes(), rebuilt.nodes());
        assert_eq!(twice.planes(), rebuilt.planes());
    }
    // Merging already drops planes that cut nothing; rebuilding random
    // results must not make them bigger overall.
    assert!(
        after <= before,
        "rebuilt trees grew: {before} -> {after} nodes"
    );
}

#[test]
fn swallowed_solids_leave_no_planes_behind() {
    // A ∪ B with A inside B: the merge keeps A's planes (inside A the label
    // comes from A), the rebuilt tree only B's six faces.
    let mut arena = ConvexArena::new();
    let small = arena
        .add_box(p(-100, -100, -100), p(100, 100, 100))
        .unwrap();
    let big = arena
        .add_box(p(-H / 2, -H / 2, -H / 2), p(H / 2, H / 2, H / 2))
        .unwrap();
    let a = Bsp::from_convex(&arena, small, 1);
    let b = Bsp::from_convex(&arena, big, 1);
    let union = merge(&a, &b, BooleanOp::Union);
    assert!(union.planes().len() > 6);
    let rebuilt = simplified(&union, -H, H);
    assert_eq!(rebuilt.planes().len(), 6);
    assert_eq!(rebuilt.nodes().len(), 13);
    assert_eq!(volumes(&rebuilt, -H, H), volumes(&b, -H, H));
}

#[test]
fn restricting_to_smaller_bounds_keeps_the_regions_there() {
    let mut rng = ChaCha8Rng::seed_from_u64(72);
    for case in 0..100 {
        let a = random_operand(&mut rng, 1);
        let b = random_operand(&mut rng, 2);
        let acc = merge(&a, &b, BooleanOp::Union);
        let (lo, hi) = (rng.random_range(-H..0), rng.random_range(1..H));
        let rebuilt = simplified(&acc, lo, hi);
        assert_eq!(
            volumes(&rebuilt, lo, hi),
            volumes(&acc, lo, hi),
            "case {case}"
        );
    }
}

#[test]
fn planes_of_the_bounds_never_enter_the_rebuilt_tree() {
    // A box filling the upper half of the bounds: only its bottom face is
    // surface inside the bounds, so the rebuilt tree is that one plane.
    let mut arena = ConvexArena::new();
    let solid = arena
        .add_box(p(-2 * H, -2 * H, 0), p(2 * H, 2 * H, 2 * H))
        .unwrap();
    let bsp = Bsp::from_convex(&arena, solid, 5);
    assert_eq!(bsp.planes().len(), 6);
    let rebuilt = simplified(&bsp, -H, H);
    assert_eq!(rebuilt.planes().len(), 1);
    assert_eq!(rebuilt.planes()[0].normal(), [0, 0, -1]);
    assert!(matches!(rebuilt.nodes()[0], Node::Split { .. }));
    // Entirely inside the solid: a uniform tree of its label.
    let inside = simplified(&bsp, H / 4, H / 2);
    assert_eq!(inside.nodes(), Bsp::uniform(5).nodes());
    // Entirely outside: empty.
    let outside = simplified(&bsp, -H, -H / 2);
    assert_eq!(outside.nodes(), Bsp::uniform(0).nodes());
}
