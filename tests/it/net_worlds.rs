//! What the networked world tests (`net_world`, `net_host`) share: their
//! streamed world, what a peer holds of it, and tools as a request sends
//! them.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::net::{WirePiece, WirePose, WireShape, WireTool};
use bevy_chisel::terrain::{ChunkCoord, StreamSettings, Terrain, TerrainWorld};

use crate::net::world_of;
use crate::terrain_world;

/// The world of `terrain_world` (chunks of 32 grid units of 1 m, heights
/// 8..=20), streamed 24 m around each focus, with material 2 to add.
pub fn streamed_world() -> TerrainWorld {
    TerrainWorld::new(terrain_world::layout(), terrain_world::height)
        .expect("valid layout")
        .with_streaming(StreamSettings {
            load_radius: 24.0,
            unload_radius: 40.0,
            max_building: 4,
        })
        .expect("valid settings")
        .with_labels([2])
}

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
