//! What a peer holds of a networked world, and tools as a request sends
//! them: shared by the networked world tests and the net benches.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::net::{WirePiece, WirePose, WireShape, WireTool, world_state_hash};
use bevy_chisel::terrain::{ChunkCoord, Terrain, TerrainFocus, TerrainWorld};

use super::world_of;

/// Whether the app's world builds nothing, no carve waits and every live
/// chunk is idle.
pub fn world_settled(app: &mut App) -> bool {
    let (entity, _) = world_of(app);
    let ecs = app.world();
    let Some(world) = ecs.get::<TerrainWorld>(entity) else {
        return false;
    };
    world.is_settled()
        && world
            .live_chunks()
            .all(|(_, e)| ecs.get::<Terrain>(e).is_some_and(Terrain::is_idle))
}

/// Asks the app's world to build the chunks whose carves wait deferred
/// (far chunks of a client), so that it holds every edited chunk.
pub fn build_deferred(app: &mut App) {
    let (entity, _) = world_of(app);
    if let Some(mut world) = app.world_mut().get_mut::<TerrainWorld>(entity) {
        world.build_deferred();
    }
}

/// Moves the app's focus (there is one) to `to`.
pub fn move_focus(app: &mut App, to: Vec3) {
    let ecs = app.world_mut();
    let mut foci = ecs.query_filtered::<&mut Transform, With<TerrainFocus>>();
    for mut transform in foci.iter_mut(ecs) {
        transform.translation = to;
    }
}

/// Chunks the app's world built so far, from the source or restored.
pub fn chunk_builds(app: &mut App) -> u64 {
    let stats = world_of(app).1.stats();
    stats.generated + stats.restored
}

/// Every edited chunk the app's world holds, live or stored, as a terrain.
pub fn edited_terrains(app: &mut App) -> BTreeMap<ChunkCoord, Terrain> {
    let (entity, _) = world_of(app);
    let ecs = app.world();
    let world = ecs.get::<TerrainWorld>(entity).expect("world");
    let mut out = BTreeMap::new();
    for (coord, chunk) in world.live_chunks() {
        if let Some(terrain) = ecs.get::<Terrain>(chunk)
            && world.chunk_edited(coord, terrain)
        {
            let bytes = terrain.to_bytes();
            out.insert(coord, Terrain::from_bytes(&bytes).expect("chunk reads"));
        }
    }
    for coord in world.stored_chunks() {
        let bytes = world.stored_chunk(coord).expect("stored chunk");
        out.insert(
            coord,
            Terrain::from_bytes(bytes).expect("stored chunk reads"),
        );
    }
    out
}

/// Every edited chunk's octree bytes and state hash.
pub fn edited_chunks(app: &mut App) -> BTreeMap<ChunkCoord, (Vec<u8>, u64)> {
    edited_terrains(app)
        .into_iter()
        .map(|(c, t)| (c, (t.octree().to_bytes(), t.state_hash())))
        .collect()
}

/// A world-unit tool of one piece: `shape` at `at`, unrotated.
pub fn world_tool(shape: WireShape, at: [f32; 3]) -> WireTool {
    WireTool::World(vec![WirePiece {
        shape,
        pose: WirePose {
            translation: at,
            rotation: [0.0, 0.0, 0.0, 1.0],
            scale: [1.0; 3],
        },
        sweep_to: None,
    }])
}

/// The world hash of every edited chunk the app's world holds, live or
/// stored ([`world_state_hash`] of their state hashes): the server's and
/// a client's are equal once the client holds every edited chunk as the
/// server does.
pub fn world_hash(app: &mut App) -> u64 {
    world_state_hash(
        edited_terrains(app)
            .into_iter()
            .map(|(coord, terrain)| (coord, terrain.state_hash())),
    )
}
