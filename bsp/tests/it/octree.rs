//! The octree of BSPs (§3.8): after every edit of random sequences, the
//! exact volume of every material equals that of one big reference BSP
//! edited the same way; leaves stay within the budget; cells the edit did
//! not report keep their stored leaf; the surface encloses exactly the
//! material volumes; results are bit-identical for 1 and 3 threads.

use crate::common;

use std::collections::BTreeMap;

use chisel_bsp::Error;
use chisel_bsp::convex::ConvexArena;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{CellBox, CellKey, Changes, Edit, Leaf, Octree, OctreeConfig, Tool};
use chisel_bsp::tree::{Bsp, EMPTY, Label};
use common::octree_reference::{add, octree_volumes, reference_edit};
use common::shapes::{p, placed_dodecahedron, random_rotation};
use common::volume::{Fraction, polygons_volume, volume};
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

fn block() -> CellBox {
    CellBox {
        min: [100, 100, 100],
        max: [SIZE - 100, SIZE - 100, SIZE / 2],
    }
}

fn bsp_volumes(bsp: &Bsp) -> BTreeMap<Label, Fraction> {
    let mut total = BTreeMap::new();
    let mut arena = ConvexArena::new();
    let root = arena.add_box(p(0, 0, 0), p(SIZE, SIZE, SIZE)).unwrap();
    for c in bsp.cells(&mut arena, root) {
        if c.label != EMPTY {
            add(&mut total, c.label, volume(&arena, c.poly));
        }
    }
    total
}

/// Exact volume per label enclosed by the octree's surface: faces count
/// outward for the label behind them and inward for the one in front.
fn surface_volumes(octree: &Octree) -> BTreeMap<Label, Fraction> {
    faces_integrals(&octree.surface())
}

fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let scale = rng.random_range(60.0..300.0);
    let rotation = random_rotation(rng);
    let at = [
        rng.random_range(0.0..SIZE as f64),
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

/// Unreported leaves keep their stored value; reported keys are right.
fn check_changes(before: &Octree, after: &Octree, changes: &Changes) {
    for (key, leaf) in after.leaves() {
        if changes.changed.binary_search(&key).is_err() {
            let old = before
                .leaf(key)
                .unwrap_or_else(|| panic!("{key:?} is new but unreported"));
            assert!(old.same_as(leaf), "{key:?} changed but was not reported");
        }
    }
    for key in &changes.changed {
        assert!(after.leaf(*key).is_some(), "reported {key:?} is not a leaf");
    }
    for key in &changes.removed {
        assert!(before.leaf(*key).is_some() && after.leaf(*key).is_none());
    }
}

fn check_budget(octree: &Octree) {
    for (key, leaf) in octree.leaves() {
        assert!(
            leaf.bsp_nodes() <= config().max_bsp_nodes || key.depth == config().max_depth,
            "{key:?} holds {} nodes",
            leaf.bsp_nodes()
        );
    }
}

#[test]
fn random_edits_match_one_big_bsp_exactly() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    let mut arena = ConvexArena::new();
    let b = block().add_to(&mut arena).unwrap();
    let mut reference = Bsp::from_convex(&arena, b, 1);
    assert_eq!(octree_volumes(&octree), bsp_volumes(&reference));
    for step in 0..24 {
        let tool = random_tool(&mut rng);
        let edit = random_edit(&mut rng);
        let before = octree.clone();
        let changes = octree.apply(&tool, edit).unwrap();
        reference = reference_edit(&reference, &tool, edit, SIZE);
        assert_eq!(
            octree_volumes(&octree),
            bsp_volumes(&reference),
            "step {step}: {edit:?}"
        );
        check_changes(&before, &octree, &changes);
        check_budget(&octree);
    }
    assert!(octree.stats().leaves > 8, "the budget never split a cell");
    // The f64 report agrees with the exact volumes.
    for (label, exact) in octree_volumes(&octree) {
        let approx = octree.volumes()[&label];
        let exact = exact.to_f64();
        assert!(
            (approx - exact).abs() <= 1e-9 * exact,
            "{label}: {approx} vs {exact}"
        );
    }
    assert_eq!(surface_volumes(&octree), octree_volumes(&octree));
    // One watertight mesh across all cells once T-junctions are split —
    // and not before: cell borders leave T-junctions.
    // (The outer surface: material interfaces meet it in three-way edges.)
    let faces = octree.surface();
    let mut welded = SurfaceMesh::welded(&faces);
    welded.retain(|p| p.outside == EMPTY);
    assert!(welded.check_closed().is_err());
    let mut mesh = SurfaceMesh::from_faces(&faces);
    mesh.retain(|p| p.outside == EMPTY);
    mesh.check_closed().unwrap();
    assert!(!mesh.triangles().is_empty());
}

#[test]
fn the_previous_octree_survives_an_edit() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    for _ in 0..5 {
        octree
            .apply(&random_tool(&mut rng), Edit::Subtract)
            .unwrap();
    }
    let before = octree.clone();
    let volumes = octree_volumes(&octree);
    octree
        .apply(&random_tool(&mut rng), Edit::Subtract)
        .unwrap();
    assert_eq!(octree_volumes(&before), volumes);
}

#[test]
fn results_are_bit_identical_for_any_thread_count() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
            for _ in 0..25 {
                let (tool, edit) = (random_tool(&mut rng), random_edit(&mut rng));
                octree.apply(&tool, edit).unwrap();
            }
            octree
                .leaves()
                .into_iter()
                .map(|(key, leaf)| {
                    let bsp = leaf.to_bsp();
                    (key, bsp.nodes().to_vec(), bsp.planes().to_vec())
                })
                .collect::<Vec<_>>()
        })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn emptied_cells_combine_back_into_one_leaf() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    for _ in 0..10 {
        octree
            .apply(&random_tool(&mut rng), Edit::Subtract)
            .unwrap();
    }
    assert!(octree.stats().leaves > 1);
    // One material: a manifold, watertight surface across all cells.
    SurfaceMesh::from_faces(&octree.surface())
        .check_watertight()
        .unwrap();
    let everything = Tool::cuboid(CellBox {
        min: [-1; 3],
        max: [SIZE + 1; 3],
    })
    .unwrap();
    let changes = octree.apply(&everything, Edit::Subtract).unwrap();
    assert_eq!(octree.stats().leaves, 1);
    assert_eq!(changes.changed, vec![CellKey::ROOT]);
    assert!(octree_volumes(&octree).is_empty());
}

#[test]
fn intersecting_empties_the_cells_the_tool_misses() {
    let mut octree = Octree::from_box([0; 3], K, block(), 2, config()).unwrap();
    let keep = CellBox {
        min: [1000, 1000, 200],
        max: [1500, 1800, 1000],
    };
    octree
        .apply(&Tool::cuboid(keep).unwrap(), Edit::Intersect)
        .unwrap();
    let mut expected = BTreeMap::new();
    add(
        &mut expected,
        2,
        Fraction::new((500 * 800 * 800).into(), 1.into()),
    );
    assert_eq!(octree_volumes(&octree), expected);
    assert_eq!(surface_volumes(&octree), expected);
}

#[test]
fn bad_edits_are_errors_and_change_nothing() {
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    let tool = Tool::cuboid(CellBox {
        min: [0; 3],
        max: [500; 3],
    })
    .unwrap();
    let before = octree_volumes(&octree);
    assert!(matches!(
        octree.apply(&tool, Edit::Add(EMPTY)),
        Err(Error::InvalidEdit { .. })
    ));
    assert_eq!(octree_volumes(&octree), before);
    assert!(matches!(
        Octree::new([1 << 26, 0, 0], 4, EMPTY, config()),
        Err(Error::OctreeSize { .. })
    ));
    assert!(matches!(
        Octree::new([0; 3], 0, EMPTY, config()),
        Err(Error::OctreeSize { .. })
    ));
    // Far outside the budget: an error, not an overflow.
    assert!(matches!(
        Octree::new([i64::MAX, 0, 0], 27, EMPTY, config()),
        Err(Error::OctreeSize { .. })
    ));
    let flat = [p(0, 0, 0), p(10, 0, 0), p(0, 10, 0), p(10, 10, 0)];
    assert!(matches!(
        Tool::convex_hull(&flat),
        Err(Error::DegenerateHull { .. })
    ));
    // A tool far outside the cube touches nothing.
    let far = Tool::cuboid(CellBox {
        min: [3 * SIZE; 3],
        max: [3 * SIZE + 10; 3],
    })
    .unwrap();
    let changes = octree.apply(&far, Edit::Subtract).unwrap();
    assert!(changes.changed.is_empty() && changes.removed.is_empty());
}

#[test]
fn octrees_rebuild_from_their_stored_leaves() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    for _ in 0..8 {
        let (tool, edit) = (random_tool(&mut rng), random_edit(&mut rng));
        octree.apply(&tool, edit).unwrap();
    }
    // Store every leaf as plain parts, then rebuild from them.
    let stored: Vec<(CellKey, Leaf)> = octree
        .leaves()
        .into_iter()
        .map(|(key, leaf)| {
            let leaf = match leaf {
                Leaf::Uniform(l) => Leaf::Uniform(*l),
                Leaf::Bsp(bsp) => Leaf::Bsp(std::sync::Arc::new(
                    Bsp::from_stored_parts(bsp.planes().to_vec(), bsp.nodes().to_vec()).unwrap(),
                )),
            };
            (key, leaf)
        })
        .collect();
    let rebuilt = Octree::from_leaves([0; 3], K, config(), stored.clone()).unwrap();
    let parts = |o: &Octree| {
        o.leaves()
            .into_iter()
            .map(|(k, l)| (k, l.to_bsp().nodes().to_vec(), l.to_bsp().planes().to_vec()))
            .collect::<Vec<_>>()
    };
    assert_eq!(parts(&rebuilt), parts(&octree));
    assert_eq!(octree_volumes(&rebuilt), octree_volumes(&octree));
    // Defects are errors.
    let invalid = |leaves: Vec<(CellKey, Leaf)>| {
        matches!(
            Octree::from_leaves([0; 3], K, config(), leaves),
            Err(Error::InvalidOctree { .. })
        )
    };
    assert!(invalid(stored[1..].to_vec()), "a missing leaf");
    let mut twice = stored.clone();
    twice.push(stored[0].clone());
    assert!(invalid(twice), "a repeated leaf");
    let mut nested = stored.clone();
    nested.push((stored[0].0.child(0), Leaf::Uniform(EMPTY)));
    assert!(invalid(nested), "a leaf inside a leaf");
    let mut outside = stored.clone();
    outside.push((
        CellKey {
            depth: 1,
            pos: [2, 0, 0],
        },
        Leaf::Uniform(EMPTY),
    ));
    assert!(invalid(outside), "a leaf outside the cube");
    let nodes = vec![
        chisel_bsp::tree::Node::Split {
            plane: 0,
            below: 1,
            above: 1,
        },
        chisel_bsp::tree::Node::Leaf(1),
    ];
    assert!(Bsp::from_stored_parts(Vec::new(), nodes).is_err());
}

/// Exact per-label divergence integrals of cell surface pieces (each
/// face counted for its label, and reversed for the material in front).
fn faces_integrals(faces: &[chisel_bsp::tree::BoundaryFace]) -> BTreeMap<Label, Fraction> {
    let mut total = BTreeMap::new();
    for face in faces {
        assert!(!face.on_bounds);
        // No face between a material and itself; interfaces once.
        assert!(
            face.outside < face.label,
            "{:?} over {:?}",
            face.label,
            face.outside
        );
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

/// Whether cell `a` lies strictly inside cell `b`.
fn strictly_below(a: CellKey, b: CellKey) -> bool {
    a.depth > b.depth && a.pos.map(|p| p >> (a.depth - b.depth)) == b.pos
}

/// The faces `apply_with_faces` hands back finish into the same surface as
/// a fresh `cell_surface` (same exact integrals per material), for changed
/// leaves only — edited leaves, the new children of a split leaf and
/// combined leaves — and the octree is the one `apply` makes.
#[test]
fn faces_handed_back_finish_into_the_cells_surface() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    let mut plain = octree.clone();
    let (mut finished, mut new_children, mut combined) = (0, 0, 0);
    for step in 0..83 {
        // Random edits, then the top of the block cut away in three slabs
        // (off the cell planes): cells split for what was there hold
        // little afterwards, and are combined.
        let (tool, edit) = if step < 80 {
            (random_tool(&mut rng), random_edit(&mut rng))
        } else {
            let z = [1503, 1007, 605][step - 80];
            let slab = CellBox {
                min: [-1, -1, z],
                max: [SIZE + 1, SIZE + 1, SIZE + 1],
            };
            (Tool::cuboid(slab).unwrap(), Edit::Subtract)
        };
        let (changes, faces) = octree.apply_with_faces(&tool, edit).unwrap();
        assert_eq!(plain.apply(&tool, edit).unwrap(), changes, "step {step}");
        assert_eq!(plain.to_bytes(), octree.to_bytes(), "step {step}");
        assert!(faces.windows(2).all(|w| w[0].0 < w[1].0));
        for (key, faces) in faces {
            assert!(changes.changed.binary_search(&key).is_ok(), "{key:?}");
            new_children += usize::from(changes.removed.iter().any(|&r| strictly_below(key, r)));
            combined += usize::from(changes.removed.iter().any(|&r| strictly_below(r, key)));
            let from = octree.cell_surface_from(key, faces);
            let fresh = octree.cell_surface(key);
            assert_eq!(
                faces_integrals(&from),
                faces_integrals(&fresh),
                "step {step}: {key:?}"
            );
            finished += 1;
        }
    }
    assert!(finished > 24, "only {finished} cells finished from faces");
    assert!(
        new_children > 0 && combined > 0,
        "faces of {new_children} new children, {combined} combined leaves"
    );
}

/// A cuboid on the planes between cells (so that neighbours meet it only
/// on a face, an edge or a corner), reaching into the block.
fn snapped_cuboid(rng: &mut ChaCha8Rng) -> Tool {
    common::octree_reference::snapped_cuboid(rng, SIZE, 3..=6, 1)
}

/// Dodecahedra, cuboids on cell planes, and unions of both.
fn random_contact_tool(rng: &mut ChaCha8Rng) -> Tool {
    match rng.random_range(0..3) {
        0 => random_tool(rng),
        1 => snapped_cuboid(rng),
        _ => Tool::union(&[random_tool(rng), snapped_cuboid(rng)]).unwrap(),
    }
}

/// The exact surface integrals of every leaf.
fn leaf_surfaces(octree: &Octree) -> BTreeMap<CellKey, BTreeMap<Label, Fraction>> {
    octree
        .leaves()
        .into_iter()
        .map(|(key, _)| (key, faces_integrals(&octree.cell_surface(key))))
        .collect()
}

/// Leaves an edit does not report keep their surface (same exact
/// integrals per material), including those whose box touches the tool's
/// bounds but not the tool itself.
#[test]
fn leaves_not_reported_keep_their_surface() {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let mut octree = Octree::from_box([0; 3], K, block(), 1, config()).unwrap();
    let mut surfaces = leaf_surfaces(&octree);
    let mut narrowed = 0;
    for step in 0..30 {
        let tool = random_contact_tool(&mut rng);
        let edit = random_edit(&mut rng);
        let before = octree.clone();
        let changes = octree.apply(&tool, edit).unwrap();
        check_changes(&before, &octree, &changes);
        let after = leaf_surfaces(&octree);
        for (key, integrals) in &after {
            if changes.changed.binary_search(key).is_err() {
                assert_eq!(
                    Some(integrals),
                    surfaces.get(key),
                    "step {step}: {edit:?} {key:?}"
                );
                narrowed += usize::from(octree.cell_box(*key).touches(&tool.bounds()));
            }
        }
        surfaces = after;
    }
    assert!(narrowed > 10, "only {narrowed} leaves narrowed");
}

#[test]
fn the_enclosing_box_holds_exactly_the_points() {
    assert_eq!(CellBox::enclosing(std::iter::empty()), None);
    let points = [[3, -1, 7], [-2, 5, 7], [0, 0, -4]];
    assert_eq!(
        CellBox::enclosing(points),
        Some(CellBox {
            min: [-2, -1, -4],
            max: [3, 5, 7],
        })
    );
    assert_eq!(
        CellBox::enclosing([[1, 2, 3]]),
        Some(CellBox {
            min: [1, 2, 3],
            max: [1, 2, 3],
        })
    );
}
