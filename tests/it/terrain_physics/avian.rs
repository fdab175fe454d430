//! The physics scenarios with avian3d (`TerrainAvianPlugin`).

use avian3d::prelude::*;
use bevy::prelude::*;
use bevy_chisel::terrain::avian::TerrainAvianPlugin;

#[cfg(feature = "props")]
use super::prop_physics_tests;
use super::{Engine, physics_tests};

struct Avian;

impl Engine for Avian {
    fn add_plugins(app: &mut App) {
        app.add_plugins((PhysicsPlugins::default(), TerrainAvianPlugin::default()));
    }

    #[cfg(feature = "props")]
    fn add_prop_plugin(app: &mut App) {
        app.add_plugins(bevy_chisel::splat::avian::PropAvianPlugin::default());
    }

    fn spawn_ball(world: &mut World, radius: f32, at: Vec3) -> Entity {
        world
            .spawn((
                RigidBody::Dynamic,
                Collider::sphere(radius),
                Transform::from_translation(at),
            ))
            .id()
    }

    fn spawn_sliding_cube(world: &mut World, half: f32, at: Vec3) -> Entity {
        world
            .spawn((
                RigidBody::Dynamic,
                Collider::cuboid(2.0 * half, 2.0 * half, 2.0 * half),
                Friction::ZERO.with_combine_rule(CoefficientCombine::Min),
                LockedAxes::ROTATION_LOCKED,
                Transform::from_translation(at),
            ))
            .id()
    }

    fn set_velocity(world: &mut World, body: Entity, velocity: Vec3) {
        world.entity_mut(body).insert(LinearVelocity(velocity));
    }

    fn velocity(world: &World, body: Entity) -> Vec3 {
        world.get::<LinearVelocity>(body).expect("a rigid body").0
    }

    fn position(world: &World, body: Entity) -> Vec3 {
        world.get::<Position>(body).expect("a rigid body").0
    }

    fn has_collider(world: &World, entity: Entity) -> bool {
        world.get::<Collider>(entity).is_some()
    }

    fn is_dynamic(world: &World, entity: Entity) -> bool {
        world.get::<RigidBody>(entity) == Some(&RigidBody::Dynamic)
    }

    fn convex_shapes(world: &World, entity: Entity) -> usize {
        let collider = world.get::<Collider>(entity).expect("a collider");
        collider
            .shape()
            .as_compound()
            .map_or(1, |compound| compound.shapes().len())
    }

    fn trimesh(world: &World, entity: Entity) -> (usize, Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let collider = world.get::<Collider>(entity).expect("a collider");
        let trimesh = collider.shape().as_trimesh().expect("a trimesh collider");
        let vertices = trimesh
            .vertices()
            .iter()
            .map(|p| [f64::from(p.x), f64::from(p.y), f64::from(p.z)])
            .collect();
        let shape = std::sync::Arc::as_ptr(&collider.shape().0).cast::<()>() as usize;
        (shape, vertices, trimesh.indices().to_vec())
    }
}

physics_tests!(Avian);
#[cfg(feature = "props")]
prop_physics_tests!(Avian, props_at_scale_1, 1.0);
#[cfg(feature = "props")]
prop_physics_tests!(Avian, props_at_scale_1_10, 0.1);
