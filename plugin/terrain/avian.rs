//! Terrain physics with avian3d (feature `avian`).
//!
//! [`TerrainAvianPlugin`] makes every [`Terrain`] a static rigid body whose
//! cell entities carry trimesh colliders, rebuilt with their meshes on the
//! worker threads, and turns debris into dynamic bodies with a compound of
//! the exact convex cells. Add avian's own `PhysicsPlugins` too:
//!
//! ```no_run
//! use avian3d::prelude::*;
//! use bevy::prelude::*;
//! use bevy_chisel::terrain::{TerrainPlugin, avian::TerrainAvianPlugin};
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, PhysicsPlugins::default()))
//!     .add_plugins((TerrainPlugin, TerrainAvianPlugin::default()))
//!     .run();
//! ```

use avian3d::prelude::*;
use bevy::ecs::system::EntityCommands;
use bevy::prelude::*;

use super::TerrainSystems;
use super::carve::CarveApplied;
use super::component::Terrain;
use super::mesh::ColliderMesh;
use super::physics::{ConvexPiece, PhysicsInsert, TerrainPhysics, TerrainPhysicsBackend};

/// Colliders for terrain cells and bodies for debris, with avian3d.
#[derive(Clone, Copy, Debug)]
pub struct TerrainAvianPlugin {
    /// Preprocessing of the cell trimeshes. The default fixes internal
    /// edges (contacts on a triangle take its neighbours into account), so
    /// a body sliding over the ground does not catch on triangle edges.
    pub trimesh_flags: TrimeshFlags,
}

impl Default for TerrainAvianPlugin {
    fn default() -> Self {
        Self {
            trimesh_flags: TrimeshFlags::FIX_INTERNAL_EDGES
                | TrimeshFlags::DELETE_DEGENERATE_TRIANGLES,
        }
    }
}

impl Plugin for TerrainAvianPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(TerrainPhysicsBackend::new(AvianTerrainPhysics {
            trimesh_flags: self.trimesh_flags,
        }))
        .add_observer(make_terrain_static)
        .add_systems(Update, wake_after_carves.after(TerrainSystems::Mesh));
    }
}

/// Wakes the sleeping bodies when a carve lands: a body resting on ground
/// that was carved away must fall, but sleeping bodies do not notice a
/// static collider being replaced.
fn wake_after_carves(
    mut applied: MessageReader<CarveApplied>,
    sleeping: Query<Entity, With<Sleeping>>,
    mut commands: Commands,
) {
    if applied.read().count() == 0 {
        return;
    }
    for body in &sleeping {
        commands.queue(WakeBody(body));
    }
}

/// Every terrain is one static body; its cells' colliders attach to it.
fn make_terrain_static(add: On<Add, Terrain>, mut commands: Commands) {
    commands.entity(add.entity).insert(RigidBody::Static);
}

/// [`TerrainPhysics`] for avian3d.
#[derive(Clone, Copy, Debug)]
pub struct AvianTerrainPhysics {
    /// As [`TerrainAvianPlugin::trimesh_flags`].
    pub trimesh_flags: TrimeshFlags,
}

impl TerrainPhysics for AvianTerrainPhysics {
    fn cell_collider(&self, mesh: &ColliderMesh) -> Option<PhysicsInsert> {
        if mesh.triangles.is_empty() {
            return None;
        }
        // Preprocessing can refuse a mesh whose edges are not manifold (two
        // solids meeting along an edge); such a cell keeps a plain trimesh.
        let collider = Collider::try_trimesh_with_config(
            mesh.positions.clone(),
            mesh.triangles.clone(),
            self.trimesh_flags,
        )
        .or_else(|_| {
            Collider::try_trimesh_with_config(
                mesh.positions.clone(),
                mesh.triangles.clone(),
                TrimeshFlags::MERGE_DUPLICATE_VERTICES,
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
            .filter_map(|piece| Collider::convex_hull(piece.corners.clone()))
            .map(|hull| (Vec3::ZERO, Quat::IDENTITY, hull))
            .collect();
        if shapes.is_empty() {
            return None;
        }
        let collider = Collider::compound(shapes);
        Some(PhysicsInsert::new(move |entity| {
            entity.insert((RigidBody::Dynamic, collider, Mass(mass.max(1e-6))));
        }))
    }
}
