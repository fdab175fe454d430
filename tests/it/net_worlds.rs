//! What the networked world tests (`net_world`, `net_host`) share: their
//! streamed world, and (from [`crate::net::world`], which the net benches
//! include too) what a peer holds of it and tools as a request sends them.

use bevy_chisel::terrain::{StreamSettings, TerrainWorld};

pub use crate::net::world::{edited_chunks, edited_terrains, world_settled, world_tool};
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
