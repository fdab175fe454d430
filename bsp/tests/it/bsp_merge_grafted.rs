//! The grafted merge (`Bsp::merge_grafted`, the paper's §3.5 merge that
//! copies `B` whole into the cells of `A`) against the pruned one
//! (`Bsp::merge`): on random pairs of operands — the paper's random BSPs and
//! unions of random convex polyhedra, with several materials — both give
//! exactly the same volume of every material, before and after
//! simplification, and the volume identities hold; the result is a
//! well-formed tree and a pure function of its inputs; where one operand is
//! a single leaf, the result is known node for node.

use crate::common;

use std::collections::BTreeMap;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::exact::Plane;
use chisel_bsp::tree::{BooleanOp, Bsp, EMPTY, Label, Node, NodeId};
use common::random_bsp;
use common::shapes::{self, p};
use common::volume::{Fraction, volume};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const H: i64 = 1 << 16;

fn bounds(arena: &mut ConvexArena) -> PolyId {
    arena.add_box(p(-H, -H, -H), p(H, H, H)).unwrap()
}

/// A random BSP of the paper's Figure 10 in the bounding cube.
fn paper_random_bsp(rng: &mut ChaCha8Rng, splits: usize, labels: Label) -> Bsp {
    random_bsp::paper_random_bsp(rng, splits, labels, H)
}

/// A union of one to three random convex polyhedra of random materials
/// below `labels`.
fn convex_union(rng: &mut ChaCha8Rng, labels: Label) -> Bsp {
    let piece = |rng: &mut ChaCha8Rng| {
        let label = rng.random_range(1..labels);
        shapes::random_convex_bsp(rng, label, H / 2, (H / 8, H / 2), 6)
    };
    let mut acc = piece(rng);
    for _ in 0..rng.random_range(0..3) {
        let more = piece(rng);
        acc = pruned(&acc, &more, BooleanOp::Union);
    }
    acc
}

fn pruned(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = bounds(&mut arena);
    a.merge(b, op, &mut arena, bounds)
}

/// The grafted merge, checked to be a well-formed tree that stored parts
/// rebuild, and to be the same on a second run.
fn grafted(a: &Bsp, b: &Bsp, op: BooleanOp) -> Bsp {
    let run = || {
        let mut arena = ConvexArena::new();
        let bounds = bounds(&mut arena);
        a.merge_grafted(b, op, &mut arena, bounds)
    };
    let out = run();
    out.validate().unwrap();
    let stored = Bsp::from_stored_parts(out.planes().to_vec(), out.nodes().to_vec()).unwrap();
    assert_eq!(stored, out);
    assert_eq!(run(), out, "deterministic");
    out
}

fn simplified(bsp: &Bsp) -> Bsp {
    let mut arena = ConvexArena::new();
    let bounds = bounds(&mut arena);
    let out = bsp.simplified(&mut arena, bounds);
    out.validate().unwrap();
    out
}

/// The exact volume of every material of `bsp` in the bounds.
fn material_volumes(bsp: &Bsp) -> BTreeMap<Label, Fraction> {
    let mut arena = ConvexArena::new();
    let b = bounds(&mut arena);
    let mut volumes = BTreeMap::new();
    for cell in bsp.cells(&mut arena, b) {
        arena.validate(cell.poly).unwrap();
        if cell.label != EMPTY {
            let v = volumes.entry(cell.label).or_insert_with(Fraction::zero);
            *v = v.add(&volume(&arena, cell.poly));
        }
    }
    volumes
}

fn solid(volumes: &BTreeMap<Label, Fraction>) -> Fraction {
    volumes.values().fold(Fraction::zero(), |t, v| t.add(v))
}

fn neg(f: &Fraction) -> Fraction {
    Fraction {
        num: -f.num.clone(),
        den: f.den.clone(),
    }
}

const OPS: [BooleanOp; 4] = [
    BooleanOp::Union,
    BooleanOp::Intersection,
    BooleanOp::Difference,
    BooleanOp::Paint(7),
];

/// Every operation on one pair: per-material volumes equal to the pruned
/// merge's, before and after simplification, and the identities.
fn check_pair(a: &Bsp, b: &Bsp, case: &str) {
    let (va, vb) = (material_volumes(a), material_volumes(b));
    let mut solids = BTreeMap::new();
    for op in OPS {
        let out = grafted(a, b, op);
        let volumes = material_volumes(&out);
        assert_eq!(
            volumes,
            material_volumes(&pruned(a, b, op)),
            "{case} {op:?}: the pruned merge's regions"
        );
        assert_eq!(
            material_volumes(&simplified(&out)),
            volumes,
            "{case} {op:?}: simplification keeps the regions"
        );
        solids.insert(format!("{op:?}"), solid(&volumes));
    }
    let (union, inter, diff, paint) = (
        &solids["Union"],
        &solids["Intersection"],
        &solids["Difference"],
        &solids["Paint(7)"],
    );
    let (sa, sb) = (solid(&va), solid(&vb));
    assert_eq!(union.add(inter), sa.add(&sb), "{case}: ∪ + ∩ = A + B");
    assert_eq!(*diff, sa.add(&neg(inter)), "{case}: A − B = A − A∩B");
    assert_eq!(*paint, sa, "{case}: painting keeps the solid");
}

#[test]
fn paper_random_pairs_match_the_pruned_merge() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for case in 0..150 {
        let labels = [2, 3, 5][case % 3];
        let (na, nb) = (rng.random_range(1..=24), rng.random_range(1..=24));
        let a = paper_random_bsp(&mut rng, na, labels);
        let b = paper_random_bsp(&mut rng, nb, labels);
        check_pair(&a, &b, &format!("random pair {case} ({na}, {nb})"));
    }
}

#[test]
fn convex_union_pairs_match_the_pruned_merge() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for case in 0..150 {
        let labels = [2, 4][case % 2];
        let a = convex_union(&mut rng, labels);
        let b = if case % 5 == 0 {
            paper_random_bsp(&mut rng, 12, labels)
        } else {
            convex_union(&mut rng, labels)
        };
        check_pair(&a, &b, &format!("convex pair {case}"));
    }
}

/// A single leaf `a` as `A`: the result is the image `f(a, B)` itself,
/// node for node, or one leaf where `f(a, ·)` is constant on `B`'s labels.
#[test]
fn a_single_leaf_gives_the_image_of_b() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for case in 0..40 {
        let splits = rng.random_range(1..=30);
        let b = paper_random_bsp(&mut rng, splits, 4);
        for a in 0..4 {
            for op in OPS {
                let out = grafted(&Bsp::uniform(a), &b, op);
                let image = b.relabeled(|l| op.apply(a, l));
                let labels: Vec<Label> = image
                    .nodes()
                    .iter()
                    .filter_map(|n| match *n {
                        Node::Leaf(l) => Some(l),
                        Node::Split { .. } => None,
                    })
                    .collect();
                if labels.iter().all(|&l| l == labels[0]) {
                    assert_eq!(out, Bsp::uniform(labels[0]), "case {case} {a} {op:?}");
                } else {
                    assert_eq!(out, image, "case {case} {a} {op:?}");
                }
            }
        }
    }
}

/// The tree in preorder, planes by value (palette order aside).
fn preorder(bsp: &Bsp) -> Vec<(Option<Plane>, Label)> {
    let mut out = Vec::new();
    let mut stack = vec![0 as NodeId];
    while let Some(n) = stack.pop() {
        match bsp.nodes()[n as usize] {
            Node::Leaf(l) => out.push((None, l)),
            Node::Split {
                plane,
                below,
                above,
            } => {
                out.push((Some(bsp.planes()[plane as usize]), EMPTY));
                stack.extend([above, below]);
            }
        }
    }
    out
}

/// A single leaf `b` as `B`: nothing is copied, and the result is the
/// pruned merge's tree split for split (both cut `A` alone and collapse
/// equal leaves).
#[test]
fn b_single_leaf_gives_the_pruned_tree() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for case in 0..40 {
        let splits = rng.random_range(1..=40);
        let a = paper_random_bsp(&mut rng, splits, 4);
        for b in 0..4 {
            for op in OPS {
                let b = Bsp::uniform(b);
                let out = grafted(&a, &b, op);
                assert_eq!(
                    preorder(&out),
                    preorder(&pruned(&a, &b, op)),
                    "case {case} {op:?}"
                );
            }
        }
    }
}
