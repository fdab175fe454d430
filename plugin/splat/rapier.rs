//! Prop colliders with bevy_rapier3d (feature `rapier`).
//!
//! [`PropRapierPlugin`] does for Rapier what
//! [`super::avian::PropAvianPlugin`] does for avian3d: each quadric prop
//! gets a fixed body with a voxel collider of its exact solid
//! ([`super::prop_collider`]: on a child fitted to the prop's scale), so
//! arches and bores stay open: a ring prop scaled by 1/10 holds a ball on
//! its band and lets a narrower one through its hole
//! (`tests/it/terrain_physics/props.rs`).
//!
//! ```
//! use bevy::prelude::*;
//! use bevy_chisel::splat::{ChiselSplatPlugin, rapier::PropRapierPlugin};
//! use bevy_rapier3d::prelude::*;
//!
//! fn add_physics(app: &mut App) {
//!     app.add_plugins((ChiselSplatPlugin, RapierPhysicsPlugin::<NoUserData>::default()))
//!         .add_plugins(PropRapierPlugin { resolution: 48 });
//! }
//! # let _ = add_physics;
//! ```

use bevy::ecs::system::EntityCommands;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;

use super::prop_collider::{DEFAULT_RESOLUTION, add_prop_colliders};
pub use super::prop_collider::{PropCollider, PropColliderShape, PropVoxels};

/// Static voxel colliders for quadric props, with bevy_rapier3d.
#[derive(Clone, Copy, Debug)]
pub struct PropRapierPlugin {
    /// Voxels along each edge of a prop's bounding cube (at least 2).
    pub resolution: u32,
}

impl Default for PropRapierPlugin {
    fn default() -> Self {
        Self {
            resolution: DEFAULT_RESOLUTION,
        }
    }
}

impl Plugin for PropRapierPlugin {
    fn build(&self, app: &mut App) {
        add_prop_colliders(app, self.resolution, insert_collider);
    }
}

/// The Rapier collider of a prop's voxels (`None` when there are none).
#[must_use]
pub fn voxel_collider(voxels: &PropVoxels) -> Option<Collider> {
    (!voxels.cells.is_empty()).then(|| Collider::voxels(voxels.size, &voxels.cells))
}

/// The static body and collider on a prop's shape entity.
fn insert_collider(voxels: &PropVoxels, shape: &mut EntityCommands) -> bool {
    let Some(collider) = voxel_collider(voxels) else {
        return false;
    };
    shape.insert((RigidBody::Fixed, collider));
    true
}

#[cfg(test)]
mod tests {
    use super::super::prop_collider::tests::ring_voxels;
    use super::*;

    #[test]
    fn the_collider_of_a_ring_is_solid_in_the_ring_and_open_in_its_hole() {
        let voxels = ring_voxels();
        let collider = voxel_collider(&voxels).expect("a ring has voxels");
        let inside = |p: Vec3| collider.contains_local_point(p);
        assert!(inside(Vec3::new(7.5, 0.0, 0.0)), "the ring's material");
        assert!(inside(Vec3::new(0.0, -7.5, 1.0)), "the ring's material");
        assert!(!inside(Vec3::ZERO), "the hole");
        assert!(!inside(Vec3::new(0.0, 0.0, 3.0)), "above the ring");
    }

    #[test]
    fn no_solid_gives_no_collider() {
        let voxels = PropVoxels {
            size: Vec3::ONE,
            cells: Vec::new(),
        };
        assert!(voxel_collider(&voxels).is_none());
    }
}
