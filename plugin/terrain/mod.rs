//! Destructible terrain: exact octree-BSP solids in the ECS, carved by
//! messages, re-meshed only where they changed.
//!
//! A [`Terrain`] component owns a persistent [`chisel_bsp::octree::Octree`]
//! on an integer grid ([`chisel_bsp::tools::Quantization`]: unit and
//! origin). Each leaf cell with a visible surface is shown by one child
//! entity per material ([`TerrainCell`], `Mesh3d` + the material from the
//! terrain's [`TerrainMaterials`], of any Bevy material type).
//!
//! ## Map
//!
//! - [`component`] — [`Terrain`], [`TerrainCell`]; undo and the record of
//!   carves.
//! - [`material`] — [`TerrainMaterials`] (label → material, generic over
//!   the material type) and [`TerrainMaterialPlugin`];
//!   [`material::triplanar`]: [`TriplanarMaterial`], textured PBR terrain.
//! - [`spawn`] — terrains from a box, a [`Heightfield`] (image, layers by
//!   depth) or a Bevy mesh.
//! - [`base`] — what a terrain starts from, on the grid.
//! - [`tool`] — [`CarveTool`] in world units, [`GridTool`] on the grid.
//! - `prop_tool` — [`CarveTool::from_prop`]: a tool of a convex quadric
//!   prop's shape (feature `props`).
//! - [`mesh`] — the surface of one cell as indexed triangles with smooth
//!   normals, and welded triangles for its collider.
//! - [`physics`] — [`TerrainPhysics`], the trait a physics engine
//!   implements; `avian` (feature `avian`) and `rapier` (feature `rapier`)
//!   implement it.
//! - [`debris`] — pieces a carve cut loose, spawned as bodies of their own;
//!   [`debris_hulls`] merges a piece's convex cells into a few hulls for
//!   its collider.
//! - [`raycast`] — [`Terrain::ray_cast`] for aiming.
//! - [`probe`] — [`Terrain::material_at`] and [`TerrainWorld::material_at`]:
//!   the material at a point, exactly.
//! - [`file`](mod@file) — versioned terrain files ([`Terrain::save`], [`Terrain::load`]).
//! - [`snapshot`] — the terrain as it is now, without journal or undo
//!   history ([`Terrain::to_snapshot_bytes`]), for a peer that joins.
//! - [`asset`] — terrain files (`*.chiselterrain`) and heightfields through
//!   the asset server, with hot reload ([`TerrainSource`]).
//! - [`events`] — the reports as entity events on the terrain
//!   ([`TerrainCarved`], [`TerrainCarveRejected`], [`TerrainCellRebuilt`],
//!   [`TerrainDebrisDetached`]), for observers.
//! - [`error`](mod@error) — [`TerrainError`].
//! - [`world`] — [`TerrainWorld`]: large worlds as a grid of terrain
//!   chunks from a procedural [`WorldSource`], streamed around
//!   [`TerrainFocus`] entities, with only edited chunks stored.
//!
//! A carve runs through four modules in order, each once:
//!
//! 1. [`carve`] — the messages and settings: [`Carve`] / [`UndoCarve`] /
//!    [`RedoCarve`] in ([`GridCarve`]: a carve already on the grid, with a request id),
//!    [`TerrainCellChanged`] and [`CarveApplied`] out, [`TerrainSettings`].
//! 2. [`queue`] — the messages onto each terrain's queue, and the next job
//!    started on the async compute pool.
//! 3. `jobs` — the carve job runtime: a terrain's work in progress, and
//!    the job that applies the exact carves and builds the meshes and
//!    colliders of the changed cells on the worker threads
//!    ([`apply_carve`] is its exact step, for code outside the ECS).
//! 4. [`upload`] — the finished job's octree swapped in and its cells
//!    shown, within a per-frame budget for a first full build.
//!
//! ## Example
//!
//! A server without a renderer: `MinimalPlugins` and [`TerrainPlugin`],
//! which adds Bevy's `AssetPlugin` and `MeshPlugin` where they are missing.
//!
//! ```
//! use bevy::prelude::*;
//! use bevy_chisel::bsp::octree::Edit;
//! use bevy_chisel::bsp::tools::Quantization;
//! use bevy_chisel::terrain::{Carve, CarveApplied, CarveTool, Terrain, TerrainPlugin};
//!
//! fn setup(mut commands: Commands) -> Result {
//!     // A 20 m × 4 m × 20 m slab of rock (label 1) on a 1 mm grid.
//!     let grid = Quantization::new(0.001, [0.0; 3])?;
//!     let terrain = Terrain::from_box(grid, Vec3::new(-10.0, -4.0, -10.0), Vec3::new(10.0, 0.0, 10.0), 1)?;
//!     let terrain = commands.spawn(terrain).id();
//!     commands.write_message(Carve {
//!         terrain,
//!         tool: CarveTool::dodecahedron(2.0, Vec3::ZERO),
//!         edit: Edit::Subtract,
//!     });
//!     Ok(())
//! }
//!
//! #[derive(Resource, Default)]
//! struct Applied(usize);
//!
//! fn count(mut applied: MessageReader<CarveApplied>, mut n: ResMut<Applied>) {
//!     n.0 += applied.read().count();
//! }
//!
//! let mut app = App::new();
//! app.add_plugins((MinimalPlugins, TerrainPlugin))
//!     .init_resource::<Applied>()
//!     .add_systems(Startup, setup)
//!     .add_systems(Update, count);
//! // The carve runs on the async compute pool; a game just keeps running.
//! for _ in 0..2000 {
//!     app.update();
//!     if app.world().resource::<Applied>().0 == 1 {
//!         break;
//!     }
//!     std::thread::sleep(std::time::Duration::from_millis(5));
//! }
//! assert_eq!(app.world().resource::<Applied>().0, 1);
//! ```

pub mod asset;
mod atomic_write;
#[cfg(feature = "avian")]
pub mod avian;
pub mod base;
pub mod carve;
pub mod component;
pub mod debris;
pub mod debris_hulls;
pub mod error;
pub mod events;
pub mod file;
mod file_values;
pub(crate) mod jobs;
#[cfg(feature = "render")]
pub mod material;
pub mod mesh;
pub mod physics;
mod pool_order;
pub mod probe;
#[cfg(feature = "props")]
pub mod prop_tool;
pub mod queue;
#[cfg(feature = "rapier")]
pub mod rapier;
pub mod raycast;
pub mod snapshot;
pub mod spawn;
pub mod tool;
pub mod upload;
pub mod world;

use bevy::asset::AssetPlugin;
use bevy::ecs::schedule::{InternedScheduleLabel, ScheduleLabel};
use bevy::mesh::MeshPlugin;
use bevy::prelude::*;

pub use asset::{
    HeightfieldLoader, HeightfieldSettings, TERRAIN_EXTENSION, TerrainAsset, TerrainFileLoader,
    TerrainSource,
};
pub use base::{GridHeightfield, TerrainBase};
pub use carve::{
    Carve, CarveApplied, CarveRejected, CellOutput, GridCarve, RedoCarve, TerrainCellChanged,
    TerrainSettings, UndoCarve,
};
pub use component::{JournalEntry, Terrain, TerrainCell};
pub use debris::{DebrisConfig, DebrisDetached, DebrisLimits, DebrisPart, TerrainDebris};
pub use debris_hulls::DEFAULT_MAX_DEBRIS_HULLS;
pub use error::TerrainError;
pub use events::{TerrainCarveRejected, TerrainCarved, TerrainCellRebuilt, TerrainDebrisDetached};
pub use jobs::{apply_carve, apply_carve_with_faces};
#[cfg(feature = "render")]
pub use material::triplanar::{
    TerrainSurface, TriplanarExtension, TriplanarMaterial, TriplanarMaterialPlugin, surface_table,
};
#[cfg(feature = "render")]
pub use material::{HasTerrainMaterials, TerrainMaterialPlugin, TerrainMaterials};
pub use mesh::{CellMesh, ColliderMesh};
pub use physics::{ConvexPiece, PhysicsInsert, TerrainPhysics, TerrainPhysicsBackend};
pub use raycast::TerrainHit;
pub use spawn::{HeightLayer, Heightfield, terrain_octree_config};
pub use tool::{
    CarveShape, CarveTool, DEFAULT_ROUND_TOLERANCE, GridTool, MAX_ROUND_CORNERS,
    MIN_DEFAULT_TOLERANCE_STEPS, ToolPiece,
};
pub use world::{
    ChunkCoord, ChunkOffstage, DEFAULT_MAX_DEFERRED_CARVES, DEFAULT_MAX_SAVE_WAIT,
    DEFAULT_SAVE_HOLD_FRAMES, DEFAULT_SAVE_SETTLE_FRAMES, HeightArray, LodMesh, LodSettings,
    LodStats, NoiseOctave, SaveWorld, StreamSettings, TerrainFocus, TerrainWorld, ValueNoise,
    WorldCarve, WorldChunk, WorldLayout, WorldLod, WorldRedo, WorldRedoRefusal, WorldRedoRejected,
    WorldRedone, WorldSaveFailed, WorldSaved, WorldSource, WorldStats, WorldUndo, WorldUndoRefusal,
    WorldUndoRejected, WorldUndone,
};

/// The terrain systems, in this order, in the schedule [`TerrainPlugin`]
/// runs them in (`Update` unless [`TerrainPlugin::in_schedule`] picks
/// another).
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TerrainSystems {
    /// Reads [`Carve`] / [`UndoCarve`] / [`RedoCarve`], collects finished
    /// background jobs and starts new ones. Send carves before this set to have them start
    /// in the same frame.
    Carve,
    /// Turns finished cell meshes into assets and entities within the
    /// frame's budget; writes [`TerrainCellChanged`] and [`CarveApplied`].
    /// Read those after this set.
    Mesh,
    /// Gives the cells spawned in [`TerrainSystems::Mesh`] their materials
    /// (`TerrainMaterialPlugin`, feature `render`). Always in `Update`,
    /// which runs after the frame's fixed steps, so cells meshed in
    /// `FixedUpdate` get their materials in the same frame.
    Material,
}

/// Destructible terrain: messages, settings and systems, in `Update`.
///
/// Needs Bevy's asset plugin and the `Mesh` asset: `DefaultPlugins` has
/// both, and where they are missing when this plugin is added (say, under
/// `MinimalPlugins` on a server) it adds `AssetPlugin` and `MeshPlugin`
/// itself; add it after `DefaultPlugins` or `MinimalPlugins`. Rendering is
/// optional; with the feature `render` it adds [`TerrainMaterialPlugin`] for
/// `StandardMaterial`, and cells of terrains without a material table get
/// Bevy's default material.
///
/// [`TerrainPlugin::in_schedule`] runs the carve and mesh systems in
/// another schedule, `FixedUpdate` for a game that simulates at a fixed
/// rate.
pub struct TerrainPlugin;

impl TerrainPlugin {
    /// The terrain plugin with [`TerrainSystems::Carve`] and
    /// [`TerrainSystems::Mesh`] in `schedule` (for example `FixedUpdate`).
    pub fn in_schedule(schedule: impl ScheduleLabel) -> ScheduledTerrainPlugin {
        ScheduledTerrainPlugin {
            schedule: schedule.intern(),
        }
    }
}

impl Plugin for TerrainPlugin {
    fn build(&self, app: &mut App) {
        build_terrain(app, Update.intern());
    }
}

/// [`TerrainPlugin`] in a schedule of the user's choice
/// ([`TerrainPlugin::in_schedule`]). Add one of the two, not both.
pub struct ScheduledTerrainPlugin {
    schedule: InternedScheduleLabel,
}

impl Plugin for ScheduledTerrainPlugin {
    fn build(&self, app: &mut App) {
        build_terrain(app, self.schedule);
    }
}

fn build_terrain(app: &mut App, schedule: InternedScheduleLabel) {
    if !app.is_plugin_added::<AssetPlugin>() {
        app.add_plugins(AssetPlugin::default());
    }
    if !app.is_plugin_added::<MeshPlugin>() {
        app.add_plugins(MeshPlugin);
    }
    app.init_resource::<TerrainSettings>()
        .init_resource::<TerrainPhysicsBackend>()
        .add_message::<Carve>()
        .add_message::<GridCarve>()
        .add_message::<UndoCarve>()
        .add_message::<RedoCarve>()
        .add_message::<CarveApplied>()
        .add_message::<CarveRejected>()
        .add_message::<DebrisDetached>()
        .add_message::<TerrainCellChanged>()
        .add_message::<WorldCarve>()
        .add_message::<WorldUndo>()
        .add_message::<WorldUndone>()
        .add_message::<WorldUndoRejected>()
        .add_message::<WorldRedo>()
        .add_message::<WorldRedone>()
        .add_message::<WorldRedoRejected>()
        .add_message::<SaveWorld>()
        .add_message::<WorldSaved>()
        .add_message::<WorldSaveFailed>()
        .register_type::<Terrain>()
        .register_type::<TerrainCell>()
        .register_type::<TerrainDebris>()
        .register_type::<DebrisPart>()
        .register_type::<TerrainSettings>()
        .register_type::<CellOutput>()
        .register_type::<TerrainPhysicsBackend>()
        .register_type::<Carve>()
        .register_type::<GridCarve>()
        .register_type::<UndoCarve>()
        .register_type::<RedoCarve>()
        .register_type::<CarveApplied>()
        .register_type::<CarveRejected>()
        .register_type::<TerrainCellChanged>()
        .register_type::<DebrisDetached>()
        .register_type::<TerrainFocus>()
        .register_type::<WorldChunk>()
        .register_type::<ChunkOffstage>()
        .register_type::<LodMesh>()
        .register_type::<WorldCarve>()
        .register_type::<WorldUndo>()
        .register_type::<WorldUndone>()
        .register_type::<WorldUndoRejected>()
        .register_type::<WorldRedo>()
        .register_type::<WorldRedone>()
        .register_type::<WorldRedoRejected>()
        .register_type::<SaveWorld>()
        .register_type::<WorldSaved>()
        .register_type::<WorldSaveFailed>()
        .register_type::<CarveTool>()
        .register_type::<Heightfield>()
        .register_type::<TerrainSource>()
        .init_asset::<TerrainAsset>()
        .init_asset::<Heightfield>()
        .init_asset_loader::<TerrainFileLoader>()
        .init_asset_loader::<HeightfieldLoader>()
        .configure_sets(
            schedule,
            (TerrainSystems::Carve, TerrainSystems::Mesh).chain(),
        )
        .add_systems(
            schedule,
            (
                (
                    queue::read_requests,
                    upload::finish_jobs,
                    world::debris::detach_across_borders,
                    world::undo::undo_world_carves,
                    queue::start_jobs,
                )
                    .chain()
                    .in_set(TerrainSystems::Carve),
                upload::upload_meshes.in_set(TerrainSystems::Mesh),
                // After the carves of the frame, before its meshes.
                world::store::save_worlds
                    .after(TerrainSystems::Carve)
                    .before(TerrainSystems::Mesh),
                events::trigger_events.after(TerrainSystems::Mesh),
                asset::spawn_from_assets.before(TerrainSystems::Carve),
                (
                    world::stream::route_world_carves,
                    world::stream::stream_chunks,
                    world::seams::stitch_chunk_borders,
                )
                    .chain()
                    .before(TerrainSystems::Carve),
            ),
        );
    if schedule == Update.intern() {
        app.configure_sets(Update, TerrainSystems::Material.after(TerrainSystems::Mesh));
    }
    // Coarse chunks are drawing, not simulation: every frame, after the
    // frame's cells are shown and before materials are given.
    app.add_systems(
        Update,
        world::lod::update_lod
            .after(TerrainSystems::Mesh)
            .before(TerrainSystems::Material),
    );
    #[cfg(feature = "render")]
    app.add_systems(
        Update,
        material::default_materials.in_set(TerrainSystems::Material),
    )
    .add_plugins(TerrainMaterialPlugin::<StandardMaterial>::default());
}
