//! [`RedoCarve`] re-applies the carves [`UndoCarve`] took back: the octree
//! bytes and state hash after each redo equal those right after the
//! carve, as do the journal, the undo depth and the cells shown; redo
//! reports say they are redos and rebuild the cells the undo rebuilt; a
//! redo with nothing to redo is refused and changes nothing; a new carve
//! forgets what was undone; undo, redo and undo again are exact; a piece
//! the carve cut loose is taken out of the terrain again by the redo
//! (without a second body). [`Terrain::redo_now`] does the same outside
//! the ECS. A world chunk redoes its own undo; a [`WorldUndo`] leaves it
//! nothing to redo.

use std::collections::BTreeSet;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, CellKey, Edit, OctreeConfig, StateHash};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveShape, CarveTool, DebrisDetached, JournalEntry,
    RedoCarve, Terrain, TerrainBase, TerrainCell, TerrainDebris, TerrainError, TerrainPlugin,
    TerrainSettings, TerrainSystems, UndoCarve, WorldCarve, WorldUndo,
};

use crate::terrain_common::settle;
use crate::terrain_world::{
    app_with as world_app, settle as settle_world, the_world, world as new_world,
};

/// World units per grid unit.
const UNIT: f64 = 0.5;

/// Messages seen by the test.
#[derive(Resource, Default)]
struct Seen {
    applied: Vec<CarveApplied>,
    rejected: Vec<CarveRejected>,
    detached: Vec<DebrisDetached>,
}

fn record(
    mut seen: ResMut<Seen>,
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    mut detached: MessageReader<DebrisDetached>,
) {
    seen.applied.extend(applied.read().cloned());
    seen.rejected.extend(rejected.read().cloned());
    seen.detached.extend(detached.read().cloned());
}

/// Rock (1) filling the lower 24 m of a 32 m cube; sand (2) may be added.
fn block() -> Terrain {
    let grid = Quantization::new(UNIT, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 6,
        solid: CellBox {
            min: [0; 3],
            max: [64, 48, 64],
        },
        label: 1,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 24,
        ..OctreeConfig::default()
    };
    Terrain::from_base(grid, base, config)
        .expect("valid block")
        .with_labels([2])
}

fn app() -> (App, Entity) {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TerrainPlugin))
        .insert_resource(TerrainSettings {
            measure_volumes: true,
            ..TerrainSettings::default()
        })
        .init_resource::<Seen>()
        .add_systems(Update, record.after(TerrainSystems::Mesh));
    let entity = app.world_mut().spawn(block()).id();
    settle(&mut app, entity);
    (app, entity)
}

fn terrain(app: &App, entity: Entity) -> &Terrain {
    app.world().get::<Terrain>(entity).expect("terrain entity")
}

fn crater(x: f32, z: f32, radius: f32) -> CarveTool {
    CarveTool::dodecahedron(radius, Vec3::new(x, 24.0, z))
}

fn send<M: Message>(app: &mut App, entity: Entity, message: M) {
    app.world_mut().write_message(message);
    settle(app, entity);
}

fn carve(app: &mut App, entity: Entity, tool: CarveTool, edit: Edit) {
    let terrain = entity;
    send(
        app,
        entity,
        Carve {
            terrain,
            tool,
            edit,
        },
    );
}

fn undo(app: &mut App, entity: Entity) {
    send(app, entity, UndoCarve { terrain: entity });
}

fn redo(app: &mut App, entity: Entity) {
    send(app, entity, RedoCarve { terrain: entity });
}

/// What a game reads of a terrain, to compare states exactly.
#[derive(Debug, PartialEq, Eq)]
struct State {
    octree: Vec<u8>,
    hash: u64,
    journal: Vec<JournalEntry>,
    undo_depth: usize,
    /// The (cell, material) pairs shown.
    shown: BTreeSet<(CellKey, u8)>,
}

fn state(app: &mut App, entity: Entity) -> State {
    let shown = (app.world_mut().query::<&TerrainCell>())
        .iter(app.world())
        .filter(|cell| cell.terrain == entity)
        .map(|cell| (cell.key, cell.label))
        .collect();
    let t = terrain(app, entity);
    // The hash kept per carve is the hash of the whole octree.
    assert_eq!(t.state_hash(), StateHash::of(t.octree()).value());
    State {
        octree: t.octree().to_bytes(),
        hash: t.state_hash(),
        journal: t.journal().to_vec(),
        undo_depth: t.undo_depth(),
        shown,
    }
}

fn last_report(app: &App) -> CarveApplied {
    let seen = app.world().resource::<Seen>();
    seen.applied.last().cloned().expect("a report")
}

#[test]
fn three_carves_undone_twice_and_redone_twice_match_exactly() {
    let (mut app, entity) = app();
    let tools = [
        (crater(8.0, 8.0, 4.0), Edit::Subtract),
        (crater(10.0, 9.0, 3.0), Edit::Add(2)),
        (crater(20.0, 14.0, 5.0), Edit::Subtract),
    ];
    let mut after = vec![state(&mut app, entity)];
    for (tool, edit) in tools.clone() {
        carve(&mut app, entity, tool, edit);
        after.push(state(&mut app, entity));
    }
    let carved: Vec<CarveApplied> = app.world().resource::<Seen>().applied.clone();
    assert_eq!(carved.len(), 3);
    assert!(carved.iter().all(|r| !r.redo && r.edit.is_some()));

    let mut undos = Vec::new();
    for back in [2, 1] {
        undo(&mut app, entity);
        assert_eq!(state(&mut app, entity), after[back], "undo to carve {back}");
        assert_eq!(terrain(&app, entity).redo_depth(), 3 - back);
        undos.push(last_report(&app));
    }
    for forward in [2, 3] {
        redo(&mut app, entity);
        assert_eq!(
            state(&mut app, entity),
            after[forward],
            "redo of carve {forward}"
        );
        assert_eq!(terrain(&app, entity).redo_depth(), 3 - forward);
        let report = last_report(&app);
        // A redo says so, with the edit it redid and the hash after it.
        assert!(report.redo);
        assert_eq!(report.edit, Some(tools[forward - 1].1));
        assert_eq!(report.request, None);
        assert_eq!(report.hash, after[forward].hash);
        // It rebuilt the cells the undo of the same carve rebuilt.
        let undone = &undos[3 - forward];
        assert_eq!(report.cells, undone.cells);
        // And took out what the undo gave back.
        let (taken, given) = (
            report.volume_change.clone().expect("measured"),
            undone.volume_change.clone().expect("measured"),
        );
        assert_eq!(
            taken.keys().collect::<Vec<_>>(),
            given.keys().collect::<Vec<_>>()
        );
        for (label, v) in &taken {
            assert!((v + given[label]).abs() <= 1e-9, "material {label}: {v}");
        }
    }
    let seen = app.world().resource::<Seen>();
    assert!(seen.rejected.is_empty());
    assert_eq!(seen.applied.len(), 3 + 2 + 2);
}

#[test]
fn a_redo_with_nothing_to_redo_is_refused_and_changes_nothing() {
    let (mut app, entity) = app();
    // Nothing undone on a fresh terrain.
    let fresh = state(&mut app, entity);
    redo(&mut app, entity);
    assert_eq!(state(&mut app, entity), fresh);
    carve(&mut app, entity, crater(8.0, 8.0, 4.0), Edit::Subtract);
    let carved = state(&mut app, entity);
    // Nothing undone since the carve; then one redo too many.
    redo(&mut app, entity);
    assert_eq!(state(&mut app, entity), carved);
    undo(&mut app, entity);
    redo(&mut app, entity);
    redo(&mut app, entity);
    assert_eq!(state(&mut app, entity), carved);
    let seen = app.world().resource::<Seen>();
    let errors: Vec<&TerrainError> = seen.rejected.iter().map(|r| &r.error).collect();
    assert_eq!(errors, [&TerrainError::NothingToRedo; 3]);
    assert!(
        seen.rejected
            .iter()
            .all(|r| r.terrain == entity && r.request.is_none())
    );
    // The carve, the undo and the one redo.
    assert_eq!(seen.applied.len(), 3);
}

#[test]
fn a_new_carve_after_an_undo_forgets_what_was_undone() {
    let (mut app, entity) = app();
    carve(&mut app, entity, crater(8.0, 8.0, 4.0), Edit::Subtract);
    carve(&mut app, entity, crater(20.0, 14.0, 5.0), Edit::Subtract);
    undo(&mut app, entity);
    undo(&mut app, entity);
    assert_eq!(terrain(&app, entity).redo_depth(), 2);
    carve(&mut app, entity, crater(14.0, 20.0, 3.0), Edit::Subtract);
    assert_eq!(terrain(&app, entity).redo_depth(), 0);
    let carved = state(&mut app, entity);
    redo(&mut app, entity);
    assert_eq!(state(&mut app, entity), carved);
    let seen = app.world().resource::<Seen>();
    assert_eq!(seen.rejected.len(), 1);
    assert_eq!(seen.rejected[0].error, TerrainError::NothingToRedo);
    assert_eq!(terrain(&app, entity).journal().len(), 1);
}

#[test]
fn undo_redo_undo_round_trips_exactly() {
    let (mut app, entity) = app();
    carve(&mut app, entity, crater(8.0, 8.0, 4.0), Edit::Subtract);
    let first = state(&mut app, entity);
    carve(&mut app, entity, crater(10.0, 9.0, 3.0), Edit::Add(2));
    let second = state(&mut app, entity);
    for _ in 0..2 {
        undo(&mut app, entity);
        assert_eq!(state(&mut app, entity), first);
        redo(&mut app, entity);
        assert_eq!(state(&mut app, entity), second);
    }
    // The redone carve is on the undo history like any other.
    undo(&mut app, entity);
    undo(&mut app, entity);
    assert!(terrain(&app, entity).journal().is_empty());
    assert_eq!(terrain(&app, entity).redo_depth(), 2);
    redo(&mut app, entity);
    redo(&mut app, entity);
    assert_eq!(state(&mut app, entity), second);
    assert!(app.world().resource::<Seen>().rejected.is_empty());
}

#[test]
fn a_redone_carve_cuts_its_piece_loose_again() {
    let (mut app, entity) = app();
    // A sand table on one leg, on the rock's top (24 m).
    let sand = |min: Vec3, max: Vec3| {
        let centre = (min + max) / 2.0;
        let shape = CarveShape::Cuboid {
            half_size: (max - min) / 2.0,
        };
        CarveTool::new(shape, Transform::from_translation(centre))
    };
    let leg = sand(Vec3::new(4.0, 24.0, 4.0), Vec3::new(6.0, 28.0, 6.0));
    let top = sand(Vec3::new(4.0, 28.0, 4.0), Vec3::new(14.0, 29.0, 14.0));
    carve(&mut app, entity, leg, Edit::Add(2));
    carve(&mut app, entity, top, Edit::Add(2));
    let before = state(&mut app, entity);
    let cut = sand(Vec3::new(3.0, 25.0, 3.0), Vec3::new(7.0, 27.0, 7.0));
    carve(&mut app, entity, cut, Edit::Subtract);
    let after = state(&mut app, entity);
    let cut_report = last_report(&app);
    assert_eq!(
        app.world().resource::<Seen>().detached.len(),
        1,
        "the table falls"
    );
    let piece = app.world().resource::<Seen>().detached[0]
        .exact_volume
        .to_f64();
    let bodies = |app: &mut App| {
        (app.world_mut().query::<&TerrainDebris>())
            .iter(app.world())
            .count()
    };
    assert_eq!(bodies(&mut app), 1);

    // The undo puts the table back into the terrain.
    undo(&mut app, entity);
    assert_eq!(state(&mut app, entity), before);
    let undone = last_report(&app);
    // The redo takes it out again: the terrain is the one after the cut.
    redo(&mut app, entity);
    assert_eq!(state(&mut app, entity), after);
    let redone = last_report(&app);
    assert!(redone.redo);
    assert_eq!(redone.hash, cut_report.hash);
    assert_eq!(redone.cells, undone.cells);
    // Its change counts the piece with the cut (2 × 2 × 2 m of sand).
    let taken = redone.volume_change.clone().expect("measured");
    let expected = -8.0 - piece * UNIT * UNIT * UNIT;
    assert!(
        (taken[&2] - expected).abs() <= 1e-9,
        "{taken:?}, {expected}"
    );
    // The body the cut spawned is the only one: a redo spawns none.
    assert_eq!(app.world().resource::<Seen>().detached.len(), 1);
    assert_eq!(bodies(&mut app), 1);
    // And it undoes again like the cut.
    undo(&mut app, entity);
    assert_eq!(state(&mut app, entity), before);
}

#[test]
fn redo_now_matches_the_carves_outside_the_ecs() {
    let mut terrain = block();
    let grid = *terrain.quantization();
    let tools = [
        crater(8.0, 8.0, 4.0),
        crater(20.0, 14.0, 5.0),
        crater(14.0, 20.0, 3.0),
    ];
    let snap = |t: &Terrain| (t.octree().to_bytes(), t.state_hash(), t.journal().to_vec());
    let mut after = vec![snap(&terrain)];
    for tool in &tools {
        let tool = tool.to_grid(&grid).expect("on the grid");
        terrain.apply_now(&tool, Edit::Subtract).expect("carves");
        after.push(snap(&terrain));
    }
    terrain.undo_now().expect("undoes");
    terrain.undo_now().expect("undoes");
    assert_eq!(snap(&terrain), after[1]);
    let cells = terrain.redo_now().expect("redoes");
    assert!(!cells.is_empty());
    assert_eq!(snap(&terrain), after[2]);
    terrain.redo_now().expect("redoes");
    assert_eq!(snap(&terrain), after[3]);
    assert_eq!(terrain.redo_now(), Err(TerrainError::NothingToRedo));
    assert_eq!(snap(&terrain), after[3]);
    assert_eq!(terrain.undo_depth(), 3);
    // Forgetting the undo steps forgets the redo steps too.
    terrain.undo_now().expect("undoes");
    terrain.clear_undo();
    assert_eq!(terrain.redo_now(), Err(TerrainError::NothingToRedo));
    assert_eq!(snap(&terrain), after[2]);
}

#[test]
fn a_chunk_redoes_its_own_undo_and_a_world_undo_leaves_nothing_to_redo() {
    let (mut app, world, _) = world_app(new_world(), Vec3::new(16.0, 30.0, 16.0));
    let chunk = the_world(&app, world)
        .chunk_entity(bevy_chisel::terrain::ChunkCoord { x: 0, z: 0 })
        .expect("chunk (0, 0) is live");
    let snap = |app: &App| {
        let t = terrain(app, chunk);
        let depths = (t.journal().len(), t.undo_depth(), t.redo_depth());
        (t.octree().to_bytes(), t.state_hash(), depths)
    };
    let fresh = snap(&app);
    // A world carve inside chunk (0, 0).
    let tool = CarveTool::dodecahedron(5.0, Vec3::new(12.0, 12.0, 12.0));
    let edit = Edit::Subtract;
    app.world_mut()
        .write_message(WorldCarve { world, tool, edit });
    settle_world(&mut app, world);
    let carved = snap(&app);
    assert_eq!(carved.2, (1, 1, 0));
    // The chunk's own undo and redo.
    app.world_mut().write_message(UndoCarve { terrain: chunk });
    settle_world(&mut app, world);
    assert_eq!(snap(&app).1, fresh.1);
    assert_eq!(snap(&app).2, (0, 0, 1));
    app.world_mut().write_message(RedoCarve { terrain: chunk });
    settle_world(&mut app, world);
    assert_eq!(snap(&app), carved);
    // The world undo finds the chunk as its carve left it, and undoes it;
    // the chunk has nothing to redo after it.
    app.world_mut().write_message(WorldUndo { world });
    settle_world(&mut app, world);
    assert_eq!(snap(&app).1, fresh.1);
    assert_eq!(snap(&app).2, (0, 0, 0));
    app.world_mut().write_message(RedoCarve { terrain: chunk });
    settle_world(&mut app, world);
    assert_eq!(snap(&app).1, fresh.1);
    assert_eq!(snap(&app).2, (0, 0, 0));
}
