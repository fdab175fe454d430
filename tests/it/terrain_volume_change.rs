//! Each [`CarveApplied`] says what its carve changed of each material
//! (`volume_change`, cubic world units): checked against the exact volumes
//! of the whole octree before and after every carve, for subtractions,
//! additions, paints and an undo, on a grid whose unit is not 1; the
//! changes add up to the terrain's volumes after less before, and a piece
//! cut loose is left out of its carve's change and counted by its
//! [`TerrainDebris`] instead; a world carve's chunk reports add up to
//! what its chunks lost. Nothing is measured unless
//! `TerrainSettings::measure_volumes` asks for it.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, Octree, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::bsp::tree::Label;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveShape, CarveTool, Terrain, TerrainBase, TerrainDebris, TerrainPlugin,
    TerrainSettings, TerrainSystems, UndoCarve,
};

use crate::terrain_common::settle;

/// Grid units per world unit: a grid unit is half a metre.
const UNIT: f64 = 0.5;

#[derive(Resource, Default)]
struct Seen(Vec<CarveApplied>);

fn record(mut seen: ResMut<Seen>, mut applied: MessageReader<CarveApplied>) {
    seen.0.extend(applied.read().cloned());
}

/// Rock (1) filling the lower 24 m of a 32 m cube; sand (2) and ore (3)
/// may be carved in.
fn app_with_block(measure_volumes: bool) -> (App, Entity) {
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
    let terrain = Terrain::from_base(grid, base, config)
        .expect("valid block")
        .with_labels([2, 3]);
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TerrainPlugin))
        .insert_resource(TerrainSettings {
            measure_volumes,
            ..TerrainSettings::default()
        })
        .init_resource::<Seen>()
        .add_systems(Update, record.after(TerrainSystems::Mesh));
    let entity = app.world_mut().spawn(terrain).id();
    settle(&mut app, entity);
    (app, entity)
}

fn octree(app: &App, entity: Entity) -> Octree {
    app.world()
        .get::<Terrain>(entity)
        .expect("terrain")
        .octree()
        .clone()
}

/// The exact change of each material from `before` to `after`, in cubic
/// world units (rounded once, at the end).
fn exact_change(before: &Octree, after: &Octree) -> BTreeMap<Label, f64> {
    let (before, after) = (before.exact_volumes(), after.exact_volumes());
    let mut out = BTreeMap::new();
    for label in before.keys().chain(after.keys()) {
        let b = before.get(label).cloned().unwrap_or_default();
        let a = after.get(label).cloned().unwrap_or_default();
        let change = &a - &b;
        if !change.is_zero() {
            out.insert(*label, change.to_f64() * UNIT * UNIT * UNIT);
        }
    }
    out
}

/// `a` and `b` agree per material to `1e-12` of the block's volume.
fn assert_close(a: &BTreeMap<Label, f64>, b: &BTreeMap<Label, f64>, what: &str) {
    let scale = 32.0 * 24.0 * 32.0;
    for label in a.keys().chain(b.keys()) {
        let (x, y) = (a.get(label).copied(), b.get(label).copied());
        let (x0, y0) = (x.unwrap_or(0.0), y.unwrap_or(0.0));
        assert!(
            (x0 - y0).abs() <= 1e-12 * scale,
            "{what}: material {label}: {x:?} against {y:?}"
        );
    }
}

/// Carves and returns the carve's report and its change of each material.
fn carve(
    app: &mut App,
    entity: Entity,
    tool: CarveTool,
    edit: Edit,
) -> (CarveApplied, BTreeMap<Label, f64>) {
    app.world_mut().write_message(Carve {
        terrain: entity,
        tool,
        edit,
    });
    settle(app, entity);
    let report = (app.world_mut().resource_mut::<Seen>().0)
        .pop()
        .expect("the carve is applied");
    let change = report.volume_change.clone().expect("measured");
    (report, change)
}

#[test]
fn each_carve_reports_its_exact_change_of_each_material() {
    let (mut app, entity) = app_with_block(true);
    let start = octree(&app, entity);
    let crater = |x: f32, z: f32, r: f32| CarveTool::dodecahedron(r, Vec3::new(x, 24.0, z));
    let steps = [
        (crater(10.0, 10.0, 4.0), Edit::Subtract),
        (crater(13.0, 12.0, 3.0), Edit::Add(2)),
        (crater(11.0, 9.0, 3.5), Edit::Paint(3)),
        (crater(20.0, 18.0, 5.0), Edit::Subtract),
        (crater(12.0, 11.0, 2.5), Edit::Subtract),
    ];
    let mut total: BTreeMap<Label, f64> = BTreeMap::new();
    let mut last = None;
    for (i, (tool, edit)) in steps.into_iter().enumerate() {
        let before = octree(&app, entity);
        let (report, change) = carve(&mut app, entity, tool, edit);
        let after = octree(&app, entity);
        assert_close(
            &change,
            &exact_change(&before, &after),
            &format!("carve {i}, {edit:?}"),
        );
        match edit {
            Edit::Subtract => {
                assert!(report.removed_volume() > Some(1.0));
                assert_eq!(report.added_volume(), Some(0.0));
            }
            Edit::Add(label) => {
                assert_eq!(change.keys().collect::<Vec<_>>(), [&label]);
                assert!(report.added_volume() > Some(1.0));
            }
            Edit::Paint(_) => {
                let sum: f64 = change.values().sum();
                assert!(sum.abs() < 1e-9 && report.removed_volume() > Some(1.0));
            }
            Edit::Intersect => {}
        }
        for (label, v) in &change {
            *total.entry(*label).or_default() += v;
        }
        last = Some((before, change));
    }
    // What the carves reported adds up to what the terrain lost and gained.
    let terrain = app.world().get::<Terrain>(entity).expect("terrain");
    let now = terrain.volumes();
    let mut lost = BTreeMap::new();
    for label in 1..=3 {
        let start_volume = start.volumes().get(&label).copied().unwrap_or(0.0);
        let start_volume = start_volume * UNIT * UNIT * UNIT;
        lost.insert(
            label,
            now.get(&label).copied().unwrap_or(0.0) - start_volume,
        );
    }
    assert_close(&total, &lost, "the run");

    // An undo reports the change it makes: back to the last carve's before.
    let (before, last_change) = last.expect("carved");
    let after = octree(&app, entity);
    app.world_mut().write_message(UndoCarve { terrain: entity });
    settle(&mut app, entity);
    let undo = app
        .world_mut()
        .resource_mut::<Seen>()
        .0
        .pop()
        .expect("an undo report");
    assert!(undo.edit.is_none());
    let undone = undo.volume_change.expect("measured");
    assert_close(&undone, &exact_change(&after, &before), "the undo");
    let negated = last_change.iter().map(|(l, v)| (*l, -v)).collect();
    assert_close(&undone, &negated, "the undo against the carve");
}

#[test]
fn a_piece_cut_loose_is_counted_by_its_debris_not_by_the_carve() {
    let (mut app, entity) = app_with_block(true);
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
    let before = octree(&app, entity);
    // Cutting the leg below the top frees the table.
    let cut = sand(Vec3::new(3.0, 25.0, 3.0), Vec3::new(7.0, 27.0, 7.0));
    let (_, change) = carve(&mut app, entity, cut, Edit::Subtract);
    let after = octree(&app, entity);
    let debris: Vec<&TerrainDebris> = app
        .world_mut()
        .query::<&TerrainDebris>()
        .iter(app.world())
        .collect();
    assert_eq!(debris.len(), 1, "the table falls");
    let piece: f64 = debris[0].exact_volume.to_f64() * UNIT * UNIT * UNIT;
    // The table: 10 × 1 × 10 m and the leg's metre above the cut.
    assert!((piece - (100.0 + 4.0)).abs() < 1e-9, "piece {piece}");
    // The carve took out the leg's 2 × 2 × 2 m, only.
    assert_close(&change, &BTreeMap::from([(2, -8.0)]), "the cut");
    // The terrain lost both.
    assert_close(
        &exact_change(&before, &after),
        &BTreeMap::from([(2, -8.0 - piece)]),
        "the terrain",
    );
}

/// Off by default: reports say nothing was measured.
#[test]
fn reports_measure_nothing_unless_asked() {
    let (mut app, entity) = app_with_block(false);
    let crater = CarveTool::dodecahedron(4.0, Vec3::new(10.0, 24.0, 10.0));
    app.world_mut().write_message(Carve {
        terrain: entity,
        tool: crater,
        edit: Edit::Subtract,
    });
    settle(&mut app, entity);
    let report = (app.world_mut().resource_mut::<Seen>().0)
        .pop()
        .expect("the carve is applied");
    assert_eq!(report.volume_change, None);
    assert_eq!(report.removed_volume(), None);
}

/// A world carve across a chunk border: the chunks' reports add up to
/// what both chunks lost, exactly as measured on their octrees.
#[test]
fn a_world_carve_across_a_border_reports_each_chunks_part() {
    use crate::terrain_world::{app_with, carve as carve_world, dodecahedron, settle, terrain};
    use bevy_chisel::terrain::ChunkCoord;

    let (mut app, world, _) = app_with(crate::terrain_world::world(), Vec3::new(32.0, 30.0, 16.0));
    app.insert_resource(TerrainSettings {
        measure_volumes: true,
        ..TerrainSettings::default()
    })
    .init_resource::<Seen>()
    .add_systems(Update, record.after(TerrainSystems::Mesh));
    let chunks = [ChunkCoord { x: 0, z: 0 }, ChunkCoord { x: 1, z: 0 }];
    let before = chunks.map(|c| terrain(&app, world, c).octree().clone());
    carve_world(
        &mut app,
        world,
        dodecahedron(6.0, Vec3::new(32.0, 13.0, 16.0)),
    );
    settle(&mut app, world);
    let reports = &app.world().resource::<Seen>().0;
    assert_eq!(reports.len(), 2, "one report per chunk");
    let mut reported = 0.0;
    for (c, before) in chunks.into_iter().zip(&before) {
        let chunk = terrain(&app, world, c);
        let entity = crate::terrain_world::the_world(&app, world)
            .chunk_entity(c)
            .expect("live chunk");
        let report = reports
            .iter()
            .find(|r| r.terrain == entity)
            .expect("reported");
        let change = report.volume_change.clone().expect("measured");
        // The world's grid unit is 1: world and grid volumes agree.
        let exact = &before.exact_volumes()[&1] - &chunk.octree().exact_volumes()[&1];
        let lost = -change[&1];
        assert!(
            (lost - exact.to_f64()).abs() <= 1e-9 * exact.to_f64(),
            "{c:?}: {lost} against {exact}"
        );
        assert!(lost > 1.0, "{c:?} loses");
        reported += lost;
    }
    let removed: f64 = reports
        .iter()
        .filter_map(CarveApplied::removed_volume)
        .sum();
    assert_eq!(removed, reported);
}
