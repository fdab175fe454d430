//! Terrain physics with bevy_rapier3d (feature `rapier`).
//!
//! [`TerrainRapierPlugin`] does for Rapier what
//! [`super::avian::TerrainAvianPlugin`] does for avian3d: every [`Terrain`]
//! is a fixed rigid body whose cell entities (its children) carry trimesh
//! colliders, built with their meshes on the worker threads, and debris
//! becomes dynamic bodies with a compound of the exact convex cells. Add
//! Rapier's own `RapierPhysicsPlugin` too. [`crate::ChiselPlugins`] adds
//! this plugin when `avian` is off (with both features it adds the avian
//! one); one terrain physics backend per app. Rapier
//! wakes the bodies touching a collider that is replaced or removed, so a
//! body asleep on ground that a carve takes away falls. The `game` example
//! runs on Rapier with `--physics rapier` (`examples/game/rapier.rs`).
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_chisel::terrain::{TerrainPlugin, rapier::TerrainRapierPlugin};
//! use bevy_rapier3d::prelude::*;
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, RapierPhysicsPlugin::<NoUserData>::default()))
//!     .add_plugins((TerrainPlugin, TerrainRapierPlugin::default()))
//!     .run();
//! ```

use bevy::ecs::system::EntityCommands;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

use super::component::Terrain;
use super::mesh::ColliderMesh;
use super::physics::{ConvexPiece, PhysicsInsert, TerrainPhysics, TerrainPhysicsBackend};

/// Colliders for terrain cells and bodies for debris, with bevy_rapier3d.
#[derive(Clone, Copy, Debug)]
pub struct TerrainRapierPlugin {
    /// Preprocessing of the cell trimeshes. The default fixes internal
    /// edges (contacts on a triangle take its neighbours into account), so
    /// a body sliding over the ground does not catch on triangle edges.
    pub trimesh_flags: TriMeshFlags,
}

impl Default for TerrainRapierPlugin {
    fn default() -> Self {
        Self {
            trimesh_flags: TriMeshFlags::FIX_INTERNAL_EDGES
                | TriMeshFlags::DELETE_DEGENERATE_TRIANGLES,
        }
    }
}

impl Plugin for TerrainRapierPlugin {
    fn build(&self, app: &mut App) {
        let replaced = app
            .world()
            .get_resource::<TerrainPhysicsBackend>()
            .is_some_and(|backend| backend.0.is_some());
        if replaced {
            warn!(
                "TerrainRapierPlugin replaces the terrain physics backend already installed: \
                 add one backend per app"
            );
        }
        app.insert_resource(TerrainPhysicsBackend::new(RapierTerrainPhysics {
            trimesh_flags: self.trimesh_flags,
        }))
        .add_observer(make_terrain_fixed);
    }
}

/// Every terrain is one fixed body; its cells' colliders attach to it.
fn make_terrain_fixed(add: On<Add, Terrain>, mut commands: Commands) {
    commands.entity(add.entity).insert(RigidBody::Fixed);
}

/// [`TerrainPhysics`] for bevy_rapier3d.
#[derive(Clone, Copy, Debug)]
pub struct RapierTerrainPhysics {
    /// As [`TerrainRapierPlugin::trimesh_flags`].
    pub trimesh_flags: TriMeshFlags,
}

impl TerrainPhysics for RapierTerrainPhysics {
    fn cell_collider(&self, mesh: &ColliderMesh) -> Option<PhysicsInsert> {
        if mesh.triangles.is_empty() {
            return None;
        }
        // Preprocessing can refuse a mesh whose edges are not manifold (two
        // solids meeting along an edge); such a cell keeps a plain trimesh.
        let collider = Collider::trimesh_with_flags(
            mesh.positions.clone(),
            mesh.triangles.clone(),
            self.trimesh_flags,
        )
        .or_else(|_| {
            Collider::trimesh_with_flags(
                mesh.positions.clone(),
                mesh.triangles.clone(),
                TriMeshFlags::MERGE_DUPLICATE_VERTICES,
            )
        })
        .ok()?;
        Some(PhysicsInsert::new(move |entity| {
            entity.insert(collider);
        }))
    }

    fn remove_cell_collider(&self, entity: &mut EntityCommands) {
        entity.remove::<Collider>();
    }

    fn debris_body(&self, pieces: &[ConvexPiece], mass: f32) -> Option<PhysicsInsert> {
        let shapes: Vec<(Vec3, Quat, Collider)> = pieces
            .iter()
            .filter_map(|piece| Collider::convex_hull(&piece.corners))
            .map(|hull| (Vec3::ZERO, Quat::IDENTITY, hull))
            .collect();
        if shapes.is_empty() {
            return None;
        }
        let collider = Collider::compound(shapes);
        Some(PhysicsInsert::new(move |entity| {
            entity.insert((
                RigidBody::Dynamic,
                collider,
                ColliderMassProperties::Mass(mass.max(1e-6)),
            ));
        }))
    }
}
