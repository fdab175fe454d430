//! The physics side of terrain, behind one small trait.
//!
//! A physics engine plugs in by implementing [`TerrainPhysics`] and putting
//! it in the [`TerrainPhysicsBackend`] resource. The carve jobs then build
//! each cell's collider on the worker thread that built its mesh, and the
//! upload inserts both in the same frame, so the ground a body stands on
//! and the ground it sees never disagree. A neighbour that a carve only
//! re-seals (new vertices on its border edges, the same surface) keeps its
//! collider. With the `avian` feature,
//! [`super::avian::TerrainAvianPlugin`] is such a backend for avian3d;
//! another engine (bevy_rapier3d, say) needs only another implementation.

use std::sync::Arc;

use bevy::ecs::system::EntityCommands;
use bevy::prelude::*;

use super::mesh::ColliderMesh;

/// Components a physics backend built off the main thread, to be inserted
/// on an entity by the upload.
pub struct PhysicsInsert(Box<dyn FnOnce(&mut EntityCommands) + Send + Sync>);

impl PhysicsInsert {
    /// Inserting is calling `insert` on the entity's commands.
    pub fn new(insert: impl FnOnce(&mut EntityCommands) + Send + Sync + 'static) -> Self {
        Self(Box::new(insert))
    }

    /// Inserts the components on `entity`.
    pub fn apply(self, entity: &mut EntityCommands) {
        (self.0)(entity);
    }
}

impl std::fmt::Debug for PhysicsInsert {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PhysicsInsert")
    }
}

/// A convex piece of a debris body, in the body's local frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConvexPiece {
    /// Its corners (the piece is their convex hull).
    pub corners: Vec<Vec3>,
}

/// What a physics engine does for terrain. Every method but
/// [`TerrainPhysics::remove_cell_collider`] may run on a worker thread.
pub trait TerrainPhysics: Send + Sync + 'static {
    /// A static collider for one cell entity's mesh (welded triangles in the
    /// terrain's local frame); `None` when the mesh gives none (too small
    /// or degenerate), and the upload then removes the old one.
    fn cell_collider(&self, mesh: &ColliderMesh) -> Option<PhysicsInsert>;

    /// Removes what [`TerrainPhysics::cell_collider`] inserted.
    fn remove_cell_collider(&self, entity: &mut EntityCommands);

    /// A dynamic body for a piece cut loose from the terrain: its convex
    /// pieces (an exact convex decomposition, in the body's frame) and its
    /// mass. `None` when the engine cannot make one.
    fn debris_body(&self, pieces: &[ConvexPiece], mass: f32) -> Option<PhysicsInsert>;
}

/// The physics engine of the terrains: `None` (the default) builds no
/// colliders.
#[derive(Resource, Reflect, Clone, Default)]
#[reflect(Resource)]
pub struct TerrainPhysicsBackend(#[reflect(ignore)] pub Option<Arc<dyn TerrainPhysics>>);

impl TerrainPhysicsBackend {
    /// A backend from an engine's implementation.
    pub fn new(physics: impl TerrainPhysics) -> Self {
        Self(Some(Arc::new(physics)))
    }
}
