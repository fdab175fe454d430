//! Leaves over the budget split from their boundary faces (§3.8): after
//! every edit of random sequences of several materials — with cuboids on
//! the middle planes of cells, so that faces lie between two children —
//! every leaf has exactly the regions of one big reference BSP edited the
//! same way (element for element: every reference cell inside the leaf,
//! cut by the leaf's BSP, keeps its label), the faces handed back for the
//! new leaves finish into each leaf's fresh surface, and the surface
//! encloses exactly the material volumes.

use crate::common;

use std::collections::BTreeMap;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use chisel_bsp::tree::{BoundaryFace, Bsp, EMPTY, Label};
use common::octree_reference::{add, octree_volumes, reference_edit};
use common::volume::{Fraction, polygons_volume};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 10;
const SIZE: i64 = 1 << K;

fn config() -> OctreeConfig {
    OctreeConfig {
        max_bsp_nodes: 12,
        max_depth: 5,
    }
}

fn block() -> CellBox {
    CellBox {
        min: [64, 64, 64],
        max: [SIZE - 64, SIZE - 64, SIZE / 2],
    }
}

/// A cuboid with corners on the middle planes of cells.
fn snapped_cuboid(rng: &mut ChaCha8Rng) -> Tool {
    common::octree_reference::snapped_cuboid(rng, SIZE, 2..=5, 0)
}

fn dodecahedron(rng: &mut ChaCha8Rng) -> Tool {
    let pose = Pose::at([
        rng.random_range(0.0..SIZE as f64),
        rng.random_range(0.0..SIZE as f64),
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.6),
    ]);
    Tool::placed(&dodecahedron_corners(rng.random_range(30.0..150.0)), &pose).unwrap()
}

fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    match rng.random_range(0..3) {
        0 => dodecahedron(rng),
        _ => snapped_cuboid(rng),
    }
}

fn random_edit(rng: &mut ChaCha8Rng) -> Edit {
    match rng.random_range(0..6) {
        0 | 1 => Edit::Subtract,
        2 | 3 => Edit::Add(rng.random_range(1..=3)),
        _ => Edit::Paint(rng.random_range(1..=3)),
    }
}

/// Whether `a` and `b` have the same label everywhere inside `cell`: each
/// cell of `a` there, cut by `b`, has only pieces of its label.
fn same_regions(a: &Bsp, b: &Bsp, cell: &CellBox) -> bool {
    let mut arena = ConvexArena::new();
    let bounds = cell.add_to(&mut arena).unwrap();
    let cells = a.cells(&mut arena, bounds);
    cells.iter().all(|c| {
        b.cells(&mut arena, c.poly)
            .iter()
            .all(|piece| piece.label == c.label)
    })
}

/// Exact per-label divergence integrals of surface pieces (each face
/// counted for its label, and reversed for the material in front).
fn faces_integrals(faces: &[BoundaryFace]) -> BTreeMap<Label, Fraction> {
    let mut total = BTreeMap::new();
    for face in faces {
        assert!(!face.on_bounds && face.outside < face.label);
        add(
            &mut total,
            face.label,
            polygons_volume(std::slice::from_ref(&face.vertices)),
        );
        if face.outside != EMPTY {
            let mut reversed = face.vertices.clone();
            reversed.reverse();
            add(&mut total, face.outside, polygons_volume(&[reversed]));
        }
    }
    total.retain(|_, v| v.num != 0.into());
    total
}

/// One random sequence of edits, checked after every step.
fn check_edits(seed: u64, steps: usize, tool: fn(&mut ChaCha8Rng) -> Tool) -> usize {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    let mut arena = ConvexArena::new();
    let b = block().add_to(&mut arena).unwrap();
    let mut reference = Bsp::from_convex(&arena, b, 1);
    let mut new_children = 0;
    for step in 0..steps {
        let tool = tool(&mut rng);
        let edit = random_edit(&mut rng);
        let mut plain = octree.clone();
        let (changes, faces) = octree.apply_with_faces(&tool, edit).unwrap();
        assert_eq!(plain.apply(&tool, edit).unwrap(), changes, "step {step}");
        assert_eq!(plain.to_bytes(), octree.to_bytes(), "step {step}");
        reference = reference_edit(&reference, &tool, edit, SIZE);
        for (key, leaf) in octree.leaves() {
            let bsp = leaf.to_bsp();
            bsp.validate().unwrap();
            let cell = octree.cell_box(key);
            assert!(
                same_regions(&reference, &bsp, &cell),
                "step {step}: {edit:?} {key:?}"
            );
        }
        for (key, faces) in faces {
            new_children += usize::from(changes.removed.iter().any(|r| {
                key.depth > r.depth && key.pos.map(|p| p >> (key.depth - r.depth)) == r.pos
            }));
            assert_eq!(
                faces_integrals(&octree.cell_surface_from(key, faces)),
                faces_integrals(&octree.cell_surface(key)),
                "step {step}: {edit:?} {key:?}"
            );
        }
    }
    assert_eq!(
        faces_integrals(&octree.surface()),
        octree_volumes(&octree),
        "the surface encloses the volumes"
    );
    new_children
}

/// Cuboids on the middle planes of cells and dodecahedra, several
/// materials.
#[test]
fn split_leaves_keep_the_regions_and_the_surface() {
    let new_children = check_edits(31, 30, random_tool);
    assert!(new_children > 30, "only {new_children} new children");
}

/// Cuboids only: many faces in middle planes, between two materials too.
#[test]
fn faces_in_middle_planes_split_exactly() {
    let new_children = check_edits(32, 30, snapped_cuboid);
    assert!(new_children > 30, "only {new_children} new children");
}
