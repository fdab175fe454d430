//! Carves that add or paint a material the terrain's material table has no
//! entry for are refused with [`TerrainError::NoMaterial`], as a message
//! and as an entity event, and change nothing; replicated carves
//! ([`GridCarve`]) are not refused for it, because every peer must apply
//! what the server accepted.

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveTool, GridCarve, Terrain, TerrainBase,
    TerrainCarveRejected, TerrainError, TerrainMaterials, TerrainPlugin, TerrainSystems,
};

use crate::terrain_common::settle;

#[derive(Resource, Default)]
struct Seen {
    applied: Vec<CarveApplied>,
    rejected: Vec<CarveRejected>,
    observed: Vec<TerrainError>,
}

fn record(
    mut seen: ResMut<Seen>,
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
) {
    seen.applied.extend(applied.read().cloned());
    seen.rejected.extend(rejected.read().cloned());
}

/// Rock (1) in a 32³ cube; sand (2) and ore (3) may be carved in.
fn block() -> Terrain {
    let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 5,
        solid: CellBox {
            min: [0; 3],
            max: [24; 3],
        },
        label: 1,
    };
    Terrain::from_base(grid, base, OctreeConfig::default())
        .expect("valid block")
        .with_labels([2, 3])
}

fn terrain(app: &App, entity: Entity) -> &Terrain {
    app.world().get::<Terrain>(entity).expect("terrain")
}

fn carve(app: &mut App, entity: Entity, edit: Edit) {
    app.world_mut().write_message(Carve {
        terrain: entity,
        tool: CarveTool::dodecahedron(4.0, Vec3::new(12.0, 24.0, 12.0)),
        edit,
    });
    settle(app, entity);
}

#[test]
fn carving_a_material_without_an_entry_in_the_table_is_refused() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TerrainPlugin))
        .init_asset::<StandardMaterial>()
        .init_resource::<Seen>()
        .add_systems(Update, record.after(TerrainSystems::Mesh));
    // Materials for rock and sand, none for ore.
    let table = TerrainMaterials::<StandardMaterial>::new(
        [(1, Handle::default()), (2, Handle::default())],
        Handle::default(),
    );
    let entity = app.world_mut().spawn((block(), table)).id();
    app.world_mut().entity_mut(entity).observe(
        |refused: On<TerrainCarveRejected>, mut seen: ResMut<Seen>| {
            seen.observed.push(refused.rejection.error.clone());
        },
    );
    settle(&mut app, entity);
    assert_eq!(
        terrain(&app, entity)
            .material_labels()
            .map(|l| l.iter().copied().collect::<Vec<_>>()),
        Some(vec![1, 2])
    );

    // Sand has a material: the carve is applied.
    carve(&mut app, entity, Edit::Add(2));
    assert_eq!(app.world().resource::<Seen>().applied.len(), 1);
    let (hash, journal) = (
        terrain(&app, entity).state_hash(),
        terrain(&app, entity).journal().len(),
    );
    let octree = terrain(&app, entity).octree().to_bytes();

    // Ore has none: refused, as a message and as an entity event.
    carve(&mut app, entity, Edit::Paint(3));
    carve(&mut app, entity, Edit::Add(3));
    let no_ore = TerrainError::NoMaterial {
        label: 3,
        table: vec![1, 2],
    };
    let seen = app.world().resource::<Seen>();
    let refused: Vec<&TerrainError> = seen.rejected.iter().map(|r| &r.error).collect();
    assert_eq!(refused, vec![&no_ore, &no_ore]);
    assert_eq!(seen.observed, vec![no_ore.clone(), no_ore.clone()]);
    assert!(no_ore.to_string().contains("TerrainMaterials"), "{no_ore}");
    assert_eq!(seen.applied.len(), 1);
    // Nothing changed.
    assert_eq!(terrain(&app, entity).state_hash(), hash);
    assert_eq!(terrain(&app, entity).journal().len(), journal);
    assert!(terrain(&app, entity).octree().to_bytes() == octree);

    // Outside the app the same check applies.
    let grid = CarveTool::dodecahedron(4.0, Vec3::new(12.0, 24.0, 12.0))
        .to_grid(terrain(&app, entity).quantization())
        .expect("on the grid");
    let refused = app
        .world_mut()
        .get_mut::<Terrain>(entity)
        .expect("terrain")
        .apply_now(&grid, Edit::Paint(3));
    assert_eq!(refused.err(), Some(no_ore));
    assert_eq!(terrain(&app, entity).state_hash(), hash);

    // A replicated carve must be applied as the server sent it.
    app.world_mut().write_message(GridCarve {
        terrain: entity,
        tool: grid.clone(),
        edit: Edit::Paint(3),
        request: 7,
    });
    settle(&mut app, entity);
    let seen = app.world().resource::<Seen>();
    assert_eq!(seen.applied.last().and_then(|a| a.request), Some(7));
    assert_ne!(terrain(&app, entity).state_hash(), hash);

    // Without a table nothing restricts the terrain's own labels.
    app.world_mut()
        .entity_mut(entity)
        .remove::<TerrainMaterials<StandardMaterial>>();
    app.update();
    assert_eq!(terrain(&app, entity).material_labels(), None);
    let applied = app.world().resource::<Seen>().applied.len();
    carve(&mut app, entity, Edit::Add(3));
    assert_eq!(app.world().resource::<Seen>().applied.len(), applied + 1);
    // An unknown label stays refused.
    carve(&mut app, entity, Edit::Add(9));
    assert!(matches!(
        app.world()
            .resource::<Seen>()
            .rejected
            .last()
            .map(|r| &r.error),
        Some(TerrainError::UnknownLabel { label: 9, .. })
    ));
}
