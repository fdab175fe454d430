//! The integration tests of `bevy_chisel`, in one test binary: one module
//! per area, each built under the features it needs, with the shared
//! support in [`common`] (headless splat renders and their comparison with
//! the reference tracer) and [`net`] (servers and clients in one process).
//! One binary links Bevy once instead of once per file.
//!
//! Run one area with a filter on its module path, for example
//! `cargo test --release -p bevy_chisel --all-features --test it terrain_ecs::`.
//! `tests/terrain_soak.rs` is a binary of its own: it counts the process's
//! allocations with its own global allocator. The timed runs are benches
//! (`benches/`), not tests.

#[cfg(any(feature = "props", feature = "net"))]
use std::sync::Mutex;

/// The Bevy apps that render, and the networked ones, run one at a time:
/// each takes this lock for as long as it lives. Bevy's task pools are
/// global to the process, so in one test binary a render test waiting a
/// bounded number of frames for its props to be sampled on the async pool
/// would otherwise wait behind a thousand carves of a networked test, and
/// the networked test's late client could join before its server applied
/// a carve (both were seen failing). The short, light ECS tests run beside
/// them as before.
#[cfg(any(feature = "props", feature = "net"))]
static ONE_APP_AT_A_TIME: Mutex<()> = Mutex::new(());

#[cfg(feature = "viewer")]
mod common;
#[cfg(feature = "net")]
mod net;

// Shaders: every WGSL file and its Rust mirrors, validated by naga.
#[cfg(all(feature = "terrain", feature = "props"))]
mod shaders_validate;

// Headless rendering through Bevy's pipeline.
#[cfg(feature = "viewer")]
mod headless_render;

// Quadric props drawn as splats.
#[cfg(feature = "props")]
mod prop_carving;
#[cfg(feature = "props")]
mod prop_editing;
#[cfg(feature = "props")]
mod splat_culling;
#[cfg(feature = "viewer")]
mod splat_exposure;
#[cfg(feature = "viewer")]
mod splat_materials;
#[cfg(feature = "viewer")]
mod splat_overdraw;
#[cfg(feature = "viewer")]
mod splat_render;
#[cfg(feature = "viewer")]
mod splat_shadows;
#[cfg(feature = "viewer")]
mod splat_views;

// Destructible terrain.
#[cfg(feature = "terrain")]
mod change_detection;
#[cfg(feature = "terrain")]
mod terrain_assets;
#[cfg(feature = "terrain")]
mod terrain_common;
#[cfg(feature = "terrain")]
mod terrain_data;
#[cfg(feature = "terrain")]
mod terrain_ecs;
#[cfg(all(feature = "terrain", feature = "render"))]
mod terrain_labels;
#[cfg(feature = "viewer")]
mod terrain_material;
#[cfg(feature = "terrain")]
mod terrain_normals;
#[cfg(feature = "avian")]
mod terrain_output;
#[cfg(any(feature = "avian", feature = "rapier"))]
mod terrain_physics;
#[cfg(all(feature = "terrain", feature = "props"))]
mod terrain_prop_tools;
#[cfg(feature = "terrain")]
mod terrain_redo;
#[cfg(feature = "terrain")]
mod terrain_round_tools;
#[cfg(feature = "viewer")]
mod terrain_seams_render;
#[cfg(feature = "terrain")]
mod terrain_volume_change;
#[cfg(feature = "terrain")]
mod terrain_world;
#[cfg(feature = "terrain")]
mod terrain_world_carve_busy;
#[cfg(feature = "terrain")]
mod terrain_world_debris;
#[cfg(feature = "terrain")]
mod terrain_world_debris_busy;
#[cfg(feature = "terrain")]
mod terrain_world_debris_stream;
#[cfg(feature = "terrain")]
mod terrain_world_lod;
#[cfg(feature = "terrain")]
mod terrain_world_normals;
#[cfg(feature = "terrain")]
mod terrain_world_offstage;
#[cfg(feature = "terrain")]
mod terrain_world_seams;
#[cfg(feature = "terrain")]
mod world_probe;
#[cfg(feature = "terrain")]
mod world_redo;
#[cfg(feature = "terrain")]
mod world_save;
#[cfg(feature = "terrain")]
mod world_save_cut;
#[cfg(feature = "terrain")]
mod world_save_seeds;
#[cfg(feature = "terrain")]
mod world_save_wait;
mod world_undo;
#[cfg(feature = "terrain")]
mod world_undo_seeds;

// Multiplayer over renet's netcode UDP transport on 127.0.0.1.
#[cfg(feature = "net")]
mod net_host;
#[cfg(feature = "net")]
mod net_hostile;
#[cfg(feature = "net")]
mod net_predict;
#[cfg(feature = "net")]
mod net_replication;
#[cfg(feature = "net")]
mod net_undo;
#[cfg(feature = "net")]
mod net_world;
#[cfg(feature = "net")]
mod net_world_debris;
#[cfg(feature = "net")]
mod net_world_interest;
#[cfg(feature = "net")]
mod net_world_restart;
#[cfg(feature = "net")]
mod net_world_resync;
#[cfg(feature = "net")]
mod net_worlds;
