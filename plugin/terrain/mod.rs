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
//! - [`carve`] — the messages and the systems: [`Carve`] / [`UndoCarve`]
//!   in ([`GridCarve`]: a carve already on the grid, with a request id), exact edits on the async compute pool, meshes of the changed cells
//!   within a per-frame budget, [`TerrainCellChanged`] and [`CarveApplied`]
//!   out.
//! - `jobs` — what a carve job does on the worker threads.
//! - [`mesh`] — the surface of one cell as indexed triangles with smooth
//!   normals, and welded triangles for its collider.
//! - [`physics`] — [`TerrainPhysics`], the trait a physics engine
//!   implements; `avian` implements it (feature `avian`).
//! - [`raycast`] — [`Terrain::ray_cast`] for aiming.
//! - [`file`] — versioned terrain files ([`Terrain::save`], [`Terrain::load`]).
//! - [`error`] — [`TerrainError`].
//!
//! ## Example
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_chisel::bsp::octree::Edit;
//! use bevy_chisel::bsp::tools::Quantization;
//! use bevy_chisel::terrain::{Carve, CarveTool, Terrain, TerrainPlugin};
//!
//! fn setup(mut commands: Commands) -> Result {
//!     // A 20 m × 4 m × 20 m slab of rock (label 1) on a 1 mm grid.
//!     let grid = Quantization::new(0.001, [0.0; 3])?;
//!     let terrain = Terrain::from_box(grid, Vec3::new(-10.0, -4.0, -10.0), Vec3::new(10.0, 0.0, 10.0), 1)?;
//!     commands.spawn(terrain);
//!     Ok(())
//! }
//!
//! fn blast(mut carves: MessageWriter<Carve>, terrains: Query<Entity, With<Terrain>>) {
//!     for terrain in &terrains {
//!         carves.write(Carve {
//!             terrain,
//!             tool: CarveTool::dodecahedron(2.0, Vec3::ZERO),
//!             edit: Edit::Subtract,
//!         });
//!     }
//! }
//!
//! App::new()
//!     .add_plugins((MinimalPlugins, TerrainPlugin))
//!     .add_systems(Startup, setup)
//!     .add_systems(PostStartup, blast)
//!     .run();
//! ```

#[cfg(feature = "avian")]
pub mod avian;
pub mod base;
pub mod carve;
pub mod component;
pub mod debris;
pub mod error;
pub mod file;
mod jobs;
pub mod material;
pub mod mesh;
pub mod physics;
pub mod raycast;
pub mod spawn;
pub mod tool;

use bevy::prelude::*;

pub use base::{GridHeightfield, TerrainBase};
pub use carve::{
    Carve, CarveApplied, CarveRejected, GridCarve, TerrainCellChanged, TerrainSettings, UndoCarve,
};
pub use component::{JournalEntry, Terrain, TerrainCell, apply_carve, apply_carve_with_faces};
pub use debris::{DebrisConfig, DebrisDetached, DebrisPart, TerrainDebris};
pub use error::TerrainError;
pub use material::triplanar::{
    TerrainSurface, TriplanarExtension, TriplanarMaterial, TriplanarMaterialPlugin, surface_table,
};
pub use material::{HasTerrainMaterials, TerrainMaterialPlugin, TerrainMaterials};
pub use mesh::{CellMesh, ColliderMesh};
pub use physics::{ConvexPiece, PhysicsInsert, TerrainPhysics, TerrainPhysicsBackend};
pub use raycast::TerrainHit;
pub use spawn::{HeightLayer, Heightfield, terrain_octree_config};
pub use tool::{CarveShape, CarveTool, GridTool, ToolPiece};

/// The terrain systems, in this order within `Update`.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TerrainSystems {
    /// Reads [`Carve`] / [`UndoCarve`], collects finished background jobs
    /// and starts new ones. Send carves before this set to have them start
    /// in the same frame.
    Carve,
    /// Turns finished cell meshes into assets and entities within the
    /// frame's budget; writes [`TerrainCellChanged`] and [`CarveApplied`].
    /// Read those after this set.
    Mesh,
    /// Gives the cells spawned in [`TerrainSystems::Mesh`] their materials
    /// ([`TerrainMaterialPlugin`]), in the same frame.
    Material,
}

/// Destructible terrain: messages, settings and systems. Needs Bevy's asset
/// plugin and the `Mesh` asset (both in `DefaultPlugins`); rendering is
/// optional, so it also runs under `MinimalPlugins` for tests and servers.
pub struct TerrainPlugin;

impl Plugin for TerrainPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<TerrainSettings>()
            .init_resource::<TerrainPhysicsBackend>()
            .add_message::<Carve>()
            .add_message::<GridCarve>()
            .add_message::<UndoCarve>()
            .add_message::<CarveApplied>()
            .add_message::<CarveRejected>()
            .add_message::<DebrisDetached>()
            .add_message::<TerrainCellChanged>()
            .configure_sets(
                Update,
                (
                    TerrainSystems::Carve,
                    TerrainSystems::Mesh,
                    TerrainSystems::Material,
                )
                    .chain(),
            )
            .add_systems(
                Update,
                (
                    (carve::read_requests, carve::finish_jobs, carve::start_jobs)
                        .chain()
                        .in_set(TerrainSystems::Carve),
                    carve::upload_meshes.in_set(TerrainSystems::Mesh),
                    material::default_materials.in_set(TerrainSystems::Material),
                ),
            )
            .add_plugins(TerrainMaterialPlugin::<StandardMaterial>::default());
    }
}
