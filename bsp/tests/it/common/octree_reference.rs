//! An octree checked against one big BSP: exact volumes per material and
//! the reference BSP edited the same way as the octree.

use std::collections::BTreeMap;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::octree::{CellBox, Edit, Octree, Tool};
use chisel_bsp::tree::{BooleanOp, Bsp, EMPTY, Label};
use rand::Rng as _;
use rand_chacha::ChaCha8Rng;

use super::shapes::p;
use super::volume::{Fraction, volume};

/// Adds `v` to the total of `label`.
pub fn add(total: &mut BTreeMap<Label, Fraction>, label: Label, v: Fraction) {
    let e = total.entry(label).or_insert_with(Fraction::zero);
    *e = e.add(&v);
}

/// Exact volume per non-empty label, over all leaves (each leaf's BSP
/// validated).
pub fn octree_volumes(octree: &Octree) -> BTreeMap<Label, Fraction> {
    let mut total = BTreeMap::new();
    for (key, leaf) in octree.leaves() {
        let bsp = leaf.to_bsp();
        bsp.validate().unwrap();
        let mut arena = ConvexArena::new();
        let cell = octree.cell_box(key).add_to(&mut arena).unwrap();
        for c in bsp.cells(&mut arena, cell) {
            if c.label != EMPTY {
                add(&mut total, c.label, volume(&arena, c.poly));
            }
        }
    }
    total
}

/// `reference` (a BSP of the cube `[0, size]³`) after `edit` with `tool`,
/// simplified: what the octree should hold.
pub fn reference_edit(reference: &Bsp, tool: &Tool, edit: Edit, size: i64) -> Bsp {
    let (op, label) = match edit {
        Edit::Subtract => (BooleanOp::Difference, 1),
        Edit::Add(m) => (BooleanOp::Union, m),
        Edit::Paint(m) => (BooleanOp::Paint(m), 1),
        Edit::Intersect => (BooleanOp::Intersection, 1),
    };
    let tool = tool
        .bsp()
        .relabeled(|l| if l == EMPTY { EMPTY } else { label });
    let mut arena = ConvexArena::new();
    let root = arena.add_box(p(0, 0, 0), p(size, size, size)).unwrap();
    let merged = reference.merge(&tool, op, &mut arena, root);
    let mut arena = ConvexArena::new();
    let root = arena.add_box(p(0, 0, 0), p(size, size, size)).unwrap();
    merged.simplified(&mut arena, root)
}

/// A cuboid on the planes between cells of edge `g = size >> k` for a
/// random `k` in `levels` (so that it meets cells only on whole faces,
/// edges or corners, or on their middle planes), one or two cells of edge
/// `g` long on each axis, its lowest corner at `z ≥ g·z_from` and below
/// `size / 2`.
pub fn snapped_cuboid(
    rng: &mut ChaCha8Rng,
    size: i64,
    levels: std::ops::RangeInclusive<u32>,
    z_from: i64,
) -> Tool {
    let g = size >> rng.random_range(levels);
    let min = [
        g * rng.random_range(0..size / g - 2),
        g * rng.random_range(0..size / g - 2),
        g * rng.random_range(z_from..size / 2 / g),
    ];
    let extent = [0; 3].map(|_| g * rng.random_range(1..3));
    Tool::cuboid(CellBox {
        min,
        max: [0, 1, 2].map(|a| min[a] + extent[a]),
    })
    .unwrap()
}
