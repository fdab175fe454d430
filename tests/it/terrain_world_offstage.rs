//! Chunks built only for work out of sight (`ChunkOffstage`): a carve far
//! from every focus builds its chunk, carves and stores it without a cell
//! mesh; a focus that reaches such a chunk while it is live gets its
//! meshes, and the octree is the same either way.

use bevy::prelude::*;
use bevy_chisel::terrain::{ChunkCoord, ChunkOffstage, TerrainCell};

use super::terrain_world::{app_with, carve, dodecahedron, reference, settle, the_world, world};

/// The cells of `chunk` and how many of them have a render mesh.
fn cells_of(app: &mut App, chunk: Entity) -> (usize, usize) {
    let mut query = app.world_mut().query::<(&TerrainCell, Has<Mesh3d>)>();
    let of_chunk: Vec<bool> = query
        .iter(app.world())
        .filter(|(cell, _)| cell.terrain == chunk)
        .map(|(_, meshed)| meshed)
        .collect();
    (of_chunk.len(), of_chunk.iter().filter(|&&m| m).count())
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

#[test]
fn a_chunk_built_out_of_sight_builds_no_meshes_until_a_focus_comes() {
    let home = Vec3::new(16.0, 30.0, 16.0);
    let (mut app, world, focus) = app_with(world(), home);
    // Chunk (6, 0) is 176 away, beyond the unload radius (72).
    let far = ChunkCoord { x: 6, z: 0 };
    let first = dodecahedron(5.0, Vec3::new(6.0 * 32.0 + 12.0, 14.0, 16.0));
    carve(&mut app, world, first.clone());
    let chunk = wait_live(&mut app, world, far);
    let mut frames_live = 0;
    while the_world(&app, world).chunk_entity(far) == Some(chunk) {
        assert!(
            app.world().get::<ChunkOffstage>(chunk).is_some(),
            "out of sight while live"
        );
        assert_eq!(cells_of(&mut app, chunk), (0, 0), "no cell out of sight");
        frames_live += 1;
        app.update();
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    assert!(frames_live > 0);
    settle(&mut app, world);
    assert_eq!(
        the_world(&app, world).stored_chunks().collect::<Vec<_>>(),
        vec![far],
        "carved and stored"
    );

    // Carve it again; while its restore is live, the focus comes to it:
    // the chunk builds its meshes and keeps the carves, exactly.
    let second = dodecahedron(4.0, Vec3::new(6.0 * 32.0 + 20.0, 12.0, 20.0));
    carve(&mut app, world, second.clone());
    let chunk = wait_live(&mut app, world, far);
    assert!(app.world().get::<ChunkOffstage>(chunk).is_some());
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(6.0 * 32.0 + 16.0, 30.0, 16.0);
    settle(&mut app, world);
    let w = the_world(&app, world);
    assert_eq!(
        w.chunk_entity(far),
        Some(chunk),
        "the same chunk stayed live"
    );
    assert!(app.world().get::<ChunkOffstage>(chunk).is_none());
    let (cells, meshed) = cells_of(&mut app, chunk);
    assert!(
        cells > 0 && meshed == cells,
        "{meshed} of {cells} cells meshed"
    );
    let want = reference(the_world(&app, world), far, &[first, second]);
    let got = app
        .world()
        .get::<bevy_chisel::terrain::Terrain>(chunk)
        .expect("terrain");
    assert_eq!(got.state_hash(), want.state_hash());
    assert_eq!(got.journal(), want.journal());
}
