//! The terrain plugin in an app without rendering (`MinimalPlugins`):
//! carves rebuild exactly the meshes of the changed cells, volumes drop by
//! exactly the carved amount, undo restores the previous octree, and bad
//! carves are rejected without changing anything.

use std::collections::{BTreeMap, BTreeSet};

use bevy::asset::AssetPlugin;
use bevy::mesh::{Indices, VertexAttributeValues};
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, CellKey, Edit, Octree, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveShape, CarveTool, Terrain, TerrainBase, TerrainCell,
    TerrainCellChanged, TerrainError, TerrainPlugin, UndoCarve, apply_carve,
};

use crate::terrain_common::settle;

/// Messages seen by the test.
#[derive(Resource, Default)]
struct Seen {
    changed: Vec<TerrainCellChanged>,
    applied: Vec<CarveApplied>,
    rejected: Vec<CarveRejected>,
}

fn record(
    mut seen: ResMut<Seen>,
    mut changed: MessageReader<TerrainCellChanged>,
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
) {
    seen.changed.extend(changed.read().cloned());
    seen.applied.extend(applied.read().cloned());
    seen.rejected.extend(rejected.read().cloned());
}

/// A 64³ block (grid unit = 1 world unit) in a 128³ cube, with a small node
/// budget so that carves split it into many cells.
fn block() -> Terrain {
    let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 7,
        solid: CellBox {
            min: [0; 3],
            max: [64; 3],
        },
        label: 1,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 12,
        max_depth: 20,
    };
    // Rock (1), with sand (2) and ore (3) for carves to add and paint.
    Terrain::from_base(grid, base, config)
        .expect("valid block")
        .with_labels([2, 3])
}

fn app_with(terrain: Terrain) -> (App, Entity) {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>()
        .init_resource::<Seen>()
        .add_systems(
            Update,
            record.after(bevy_chisel::terrain::TerrainSystems::Mesh),
        );
    let entity = app.world_mut().spawn(terrain).id();
    settle(&mut app, entity);
    (app, entity)
}

fn terrain(app: &App, entity: Entity) -> &Terrain {
    app.world().get::<Terrain>(entity).expect("terrain entity")
}

fn carve(app: &mut App, entity: Entity, tool: CarveTool, edit: Edit) {
    app.world_mut().write_message(Carve {
        terrain: entity,
        tool,
        edit,
    });
    settle(app, entity);
}

/// Mesh handle per (cell, label) as shown now.
fn shown(app: &mut App) -> BTreeMap<(CellKey, u8), (Entity, AssetId<Mesh>)> {
    let mut query = app.world_mut().query::<(Entity, &TerrainCell, &Mesh3d)>();
    query
        .iter(app.world())
        .map(|(e, cell, mesh)| ((cell.key, cell.label), (e, mesh.id())))
        .collect()
}

/// Total area of the shown cell meshes (indexed triangle lists): the
/// same exact surface has the same area whichever pieces its cells were
/// triangulated into (a cell rebuilt by a carve is meshed from the faces
/// the carve handed back, one restored by undo afresh).
fn shown_area(app: &mut App) -> f64 {
    let shown = shown(app);
    let meshes = app.world().resource::<Assets<Mesh>>();
    let mut area = 0.0;
    for (_, id) in shown.values() {
        let mesh = meshes.get(*id).expect("a shown mesh");
        let Ok(Some(VertexAttributeValues::Float32x3(p))) =
            mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
        else {
            panic!("cell meshes have Float32x3 positions");
        };
        let Some(Indices::U32(indices)) = mesh.indices() else {
            panic!("cell meshes have u32 indices");
        };
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| Vec3::from(p[v as usize]).as_dvec3());
            area += 0.5 * (b - a).cross(c - a).length();
        }
    }
    area
}

/// Whether two octrees have the same leaves with equal content.
fn same_structure(a: &Octree, b: &Octree) -> bool {
    let (la, lb) = (a.leaves(), b.leaves());
    la.len() == lb.len()
        && la
            .iter()
            .zip(&lb)
            .all(|((ka, a), (kb, b))| ka == kb && a.to_bsp() == b.to_bsp())
}

fn crater(at: Vec3, radius: f32) -> CarveTool {
    CarveTool::dodecahedron(radius, at)
}

#[test]
fn a_carve_rebuilds_exactly_the_changed_cells() {
    let (mut app, entity) = app_with(block());
    // Pre-carve so that the block is split into many cells.
    for x in [12.0, 52.0] {
        carve(
            &mut app,
            entity,
            crater(Vec3::new(x, 64.0, 12.0), 9.0),
            Edit::Subtract,
        );
    }
    let before = shown(&mut app);
    let octree_before = terrain(&app, entity).octree().clone();
    assert!(
        octree_before.leaves().len() > 8,
        "the block should be split"
    );
    app.world_mut().resource_mut::<Seen>().changed.clear();

    let tool = crater(Vec3::new(50.0, 64.0, 52.0), 8.0);
    let grid = tool
        .to_grid(terrain(&app, entity).quantization())
        .expect("tool on the grid");
    let mut reference = octree_before.clone();
    let changes = apply_carve(&mut reference, &grid, Edit::Subtract).expect("valid carve");
    carve(&mut app, entity, tool, Edit::Subtract);

    // The ECS result is exactly the kernel's.
    assert!(same_structure(terrain(&app, entity).octree(), &reference));

    // Exactly the changed and removed cells were announced.
    let expected: BTreeSet<CellKey> = changes
        .changed
        .iter()
        .chain(&changes.removed)
        .copied()
        .collect();
    let announced: BTreeSet<CellKey> = app
        .world()
        .resource::<Seen>()
        .changed
        .iter()
        .map(|c| c.key)
        .collect();
    // The changed and removed cells were announced, and besides them only
    // neighbours whose borders the carve split differently (their meshes
    // take the new vertices on the shared wall, so the cells meet without
    // cracks).
    assert!(announced.is_superset(&expected));
    let octree_after = terrain(&app, entity).octree();
    for key in announced.difference(&expected) {
        let cell = octree_after.cell_box(*key);
        assert!(
            expected
                .iter()
                .any(|k| octree_after.cell_box(*k).touches(&cell)),
            "{key:?} was re-meshed but touches no changed cell"
        );
    }

    // Every other cell keeps its entity and its mesh asset.
    let after = shown(&mut app);
    let mut untouched = 0;
    for (key, handle) in &before {
        if !announced.contains(&key.0) {
            assert_eq!(after.get(key), Some(handle), "cell {key:?} was rebuilt");
            untouched += 1;
        }
    }
    assert!(untouched > 0, "some cells must be out of the tool's reach");
    // Changed cells with a surface got new meshes.
    let rebuilt = after
        .iter()
        .filter(|(key, handle)| announced.contains(&key.0) && before.get(*key) != Some(*handle))
        .count();
    assert!(rebuilt > 0);
    // Cells shown are exactly the cells of the octree with a visible surface.
    for (key, _) in after.keys() {
        assert!(
            terrain(&app, entity).octree().leaf(*key).is_some(),
            "{key:?} is not a leaf"
        );
    }
    let applied = &app.world().resource::<Seen>().applied;
    assert_eq!(applied.last().map(|a| a.edit), Some(Some(Edit::Subtract)));
}

#[test]
fn volume_drops_by_exactly_the_carved_volume() {
    let (mut app, entity) = app_with(block());
    let before = terrain(&app, entity).octree().clone();
    let tool = crater(Vec3::new(30.0, 60.0, 33.0), 10.0);
    let grid = tool
        .to_grid(terrain(&app, entity).quantization())
        .expect("tool on the grid");
    // The material inside the tool, by the kernel directly.
    let mut inside = before.clone();
    apply_carve(&mut inside, &grid, Edit::Intersect).expect("valid intersection");
    let carved = inside.solid_volume();
    assert!(
        carved > 1000.0,
        "the tool must reach into the block: {carved}"
    );

    carve(&mut app, entity, tool, Edit::Subtract);
    let after = terrain(&app, entity).octree().solid_volume();
    let drop = before.solid_volume() - after;
    assert!(
        (drop - carved).abs() <= 1e-9 * before.solid_volume(),
        "volume dropped by {drop}, carved {carved}"
    );
    // Adding material with the same tool fills all of it (the crater and
    // the part above the block) and leaves the rock as it was.
    let mut empty = Octree::new([0; 3], 7, 0, *before.config()).expect("valid cube");
    apply_carve(&mut empty, &grid, Edit::Add(1)).expect("valid add");
    let whole = empty.solid_volume();
    assert!(whole > carved);
    carve(
        &mut app,
        entity,
        crater(Vec3::new(30.0, 60.0, 33.0), 10.0),
        Edit::Add(2),
    );
    let volumes = terrain(&app, entity).octree().volumes();
    let added = volumes.get(&2).copied().unwrap_or(0.0);
    assert!(
        (added - whole).abs() <= 1e-9 * before.solid_volume(),
        "added {added}, tool {whole}"
    );
    let rock = volumes.get(&1).copied().unwrap_or(0.0);
    assert!((rock - after).abs() <= 1e-9 * before.solid_volume());
}

#[test]
fn undo_restores_the_previous_octree() {
    let (mut app, entity) = app_with(block());
    carve(
        &mut app,
        entity,
        crater(Vec3::new(20.0, 64.0, 20.0), 9.0),
        Edit::Subtract,
    );
    let snapshot = terrain(&app, entity).octree().clone();
    let area = shown_area(&mut app);
    let shown_before = shown(&mut app).len();
    carve(
        &mut app,
        entity,
        crater(Vec3::new(24.0, 60.0, 24.0), 9.0),
        Edit::Subtract,
    );
    carve(
        &mut app,
        entity,
        crater(Vec3::new(40.0, 30.0, 64.0), 6.0),
        Edit::Paint(3),
    );
    assert_eq!(terrain(&app, entity).journal().len(), 3);

    for _ in 0..2 {
        app.world_mut().write_message(UndoCarve { terrain: entity });
    }
    settle(&mut app, entity);
    let restored = terrain(&app, entity).octree();
    let (a, b) = (restored.leaves(), snapshot.leaves());
    assert_eq!(a.len(), b.len());
    for ((ka, la), (kb, lb)) in a.iter().zip(&b) {
        assert_eq!(ka, kb);
        assert!(la.same_as(lb), "leaf {ka:?} is not the stored one");
    }
    assert_eq!(terrain(&app, entity).journal().len(), 1);
    let restored_area = shown_area(&mut app);
    assert!(
        (restored_area - area).abs() <= 1e-5 * area,
        "shown area {restored_area} after undo, {area} before"
    );
    assert_eq!(shown(&mut app).len(), shown_before);

    // Undo past the last carve is refused.
    for _ in 0..2 {
        app.world_mut().write_message(UndoCarve { terrain: entity });
    }
    settle(&mut app, entity);
    let rejected = &app.world().resource::<Seen>().rejected;
    assert_eq!(rejected.len(), 1);
    assert_eq!(rejected[0].error, TerrainError::NothingToUndo);
    assert!(terrain(&app, entity).journal().is_empty());
}

#[test]
fn bad_carves_are_rejected_and_change_nothing() {
    let (mut app, entity) = app_with(block());
    carve(
        &mut app,
        entity,
        crater(Vec3::new(20.0, 64.0, 20.0), 9.0),
        Edit::Subtract,
    );
    let octree = terrain(&app, entity).octree().clone();
    let meshes = shown(&mut app);
    let flat = CarveShape::Hull(vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(10.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 10.0),
        Vec3::new(10.0, 0.0, 10.0),
    ]);
    let bad = [
        CarveTool::new(flat, Transform::from_xyz(5.0, 60.0, 5.0)),
        crater(Vec3::new(500.0, 500.0, 500.0), 5.0),
        crater(Vec3::new(10.0, 60.0, 10.0), f32::NAN),
        crater(Vec3::new(1.0e9, 0.0, 0.0), 5.0),
        CarveTool { pieces: Vec::new() },
    ];
    for tool in bad {
        carve(&mut app, entity, tool, Edit::Subtract);
    }
    carve(
        &mut app,
        entity,
        crater(Vec3::new(20.0, 64.0, 20.0), 9.0),
        Edit::Add(0),
    );
    carve(
        &mut app,
        entity,
        crater(Vec3::new(20.0, 64.0, 20.0), 9.0),
        Edit::Paint(9),
    );
    let rejected: Vec<TerrainError> = app
        .world()
        .resource::<Seen>()
        .rejected
        .iter()
        .map(|r| r.error.clone())
        .collect();
    assert_eq!(rejected.len(), 7, "{rejected:?}");
    assert!(matches!(
        rejected[0],
        TerrainError::Kernel(bevy_chisel::bsp::Error::DegenerateHull { .. })
    ));
    assert!(matches!(rejected[1], TerrainError::OutsideTerrain { .. }));
    assert!(matches!(rejected[2], TerrainError::InvalidTool { .. }));
    assert!(matches!(
        rejected[3],
        TerrainError::Kernel(bevy_chisel::bsp::Error::CoordinateOutOfRange { .. })
    ));
    assert!(matches!(rejected[4], TerrainError::InvalidTool { .. }));
    assert!(matches!(
        rejected[5],
        TerrainError::Kernel(bevy_chisel::bsp::Error::InvalidEdit { .. })
    ));
    assert_eq!(
        rejected[6],
        TerrainError::UnknownLabel {
            label: 9,
            known: vec![1, 2, 3]
        }
    );
    let now = terrain(&app, entity).octree();
    let (a, b) = (now.leaves(), octree.leaves());
    assert_eq!(a.len(), b.len());
    assert!(
        a.iter()
            .zip(&b)
            .all(|((ka, la), (kb, lb))| ka == kb && la.same_as(lb))
    );
    assert_eq!(terrain(&app, entity).journal().len(), 1);
    assert_eq!(shown(&mut app), meshes);
}
