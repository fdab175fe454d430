//! Chunks built only for work out of sight (`ChunkOffstage`): a carve far
//! from every focus builds its chunk, carves and stores it without a
//! render mesh (with colliders only where physics is on); a focus that
//! reaches such a chunk while it is live gets its meshes, and the octree
//! is the same either way.

use bevy::asset::AssetPlugin;
use bevy::mesh::MeshPlugin;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::terrain::{
    ChunkCoord, ChunkOffstage, Terrain, TerrainCell, TerrainFocus, TerrainPlugin,
};

use super::terrain_world::{app_with, carve, dodecahedron, reference, settle, the_world, world};

/// A chunk's cells: how many, how many with a render mesh, how many with
/// a collider (`has_collider` says whether an entity has one).
fn cells_of(
    app: &mut App,
    chunk: Entity,
    has_collider: fn(&World, Entity) -> bool,
) -> (usize, usize, usize) {
    let mut query = app
        .world_mut()
        .query::<(Entity, &TerrainCell, Has<Mesh3d>)>();
    let of_chunk: Vec<(Entity, bool)> = query
        .iter(app.world())
        .filter(|(_, cell, _)| cell.terrain == chunk)
        .map(|(entity, _, meshed)| (entity, meshed))
        .collect();
    let meshed = of_chunk.iter().filter(|(_, m)| *m).count();
    let colliders = (of_chunk.iter())
        .filter(|(e, _)| has_collider(app.world(), *e))
        .count();
    (of_chunk.len(), meshed, colliders)
}

/// Runs frames until chunk `coord` is live; returns its entity.
fn wait_live(app: &mut App, world: Entity, coord: ChunkCoord) -> Entity {
    for _ in 0..20_000 {
        app.update();
        if let Some(chunk) = the_world(app, world).chunk_entity(coord) {
            return chunk;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    panic!("chunk {coord:?} never came live");
}

/// The scenario: a carve 176 away (beyond the unload radius, 72) builds
/// chunk (6, 0) out of sight, which then streams out stored; a second
/// carve there restores it, and the focus comes to it while it is live.
/// `colliders` says whether the app builds cell colliders.
fn out_of_sight_then_in_sight(
    mut app: App,
    world: Entity,
    focus: Entity,
    has_collider: fn(&World, Entity) -> bool,
    colliders: bool,
) {
    let far = ChunkCoord { x: 6, z: 0 };
    let first = dodecahedron(5.0, Vec3::new(6.0 * 32.0 + 12.0, 14.0, 16.0));
    carve(&mut app, world, first.clone());
    let chunk = wait_live(&mut app, world, far);
    let (mut frames_live, mut most_cells) = (0, 0);
    while the_world(&app, world).chunk_entity(far) == Some(chunk) {
        assert!(
            app.world().get::<ChunkOffstage>(chunk).is_some(),
            "out of sight while live"
        );
        let (cells, meshed, with_collider) = cells_of(&mut app, chunk, has_collider);
        assert_eq!(meshed, 0, "no render mesh out of sight");
        if !colliders {
            assert_eq!(cells, 0, "no cell out of sight without physics");
        }
        assert_eq!(with_collider, if colliders { cells } else { 0 });
        most_cells = most_cells.max(cells);
        frames_live += 1;
        app.update();
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    assert!(frames_live > 0);
    // With physics the chunk's cells were there, each with its collider.
    assert_eq!(most_cells > 0, colliders, "{most_cells} cells at most");
    settle(&mut app, world);
    assert_eq!(
        the_world(&app, world).stored_chunks().collect::<Vec<_>>(),
        vec![far],
        "carved and stored"
    );

    let second = dodecahedron(4.0, Vec3::new(6.0 * 32.0 + 20.0, 12.0, 20.0));
    carve(&mut app, world, second.clone());
    let chunk = wait_live(&mut app, world, far);
    assert!(app.world().get::<ChunkOffstage>(chunk).is_some());
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(6.0 * 32.0 + 16.0, 30.0, 16.0);
    settle(&mut app, world);
    assert_eq!(
        the_world(&app, world).chunk_entity(far),
        Some(chunk),
        "the same chunk stayed live"
    );
    assert!(app.world().get::<ChunkOffstage>(chunk).is_none());
    let (cells, meshed, with_collider) = cells_of(&mut app, chunk, has_collider);
    assert!(
        cells > 0 && meshed == cells,
        "{meshed} of {cells} cells meshed"
    );
    assert_eq!(with_collider, if colliders { cells } else { 0 });
    let want = reference(the_world(&app, world), far, &[first, second]);
    let got = app.world().get::<Terrain>(chunk).expect("terrain");
    assert_eq!(got.state_hash(), want.state_hash());
    assert_eq!(got.journal(), want.journal());
}

#[test]
fn a_chunk_built_out_of_sight_builds_no_meshes_until_a_focus_comes() {
    let (app, world, focus) = app_with(world(), Vec3::new(16.0, 30.0, 16.0));
    out_of_sight_then_in_sight(app, world, focus, |_, _| false, false);
}

/// With avian3d, a chunk out of sight still gets its colliders (a piece
/// may fall there), and no render mesh until a focus comes.
#[cfg(feature = "avian")]
#[test]
fn with_physics_a_chunk_out_of_sight_has_colliders_but_no_meshes() {
    use bevy_chisel::terrain::avian::TerrainAvianPlugin;
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        MeshPlugin,
        TerrainPlugin,
        avian3d::prelude::PhysicsPlugins::default(),
        TerrainAvianPlugin::default(),
    ))
    .init_asset::<StandardMaterial>();
    app.finish();
    app.cleanup();
    let world = app.world_mut().spawn(world()).id();
    let focus = app
        .world_mut()
        .spawn((TerrainFocus, Transform::from_xyz(16.0, 30.0, 16.0)))
        .id();
    settle(&mut app, world);
    let has_collider =
        |world: &World, entity: Entity| world.get::<avian3d::prelude::Collider>(entity).is_some();
    out_of_sight_then_in_sight(app, world, focus, has_collider, true);
}
