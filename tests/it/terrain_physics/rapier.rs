//! The physics scenarios with bevy_rapier3d (`TerrainRapierPlugin`).

use bevy::prelude::*;
use bevy_chisel::terrain::rapier::TerrainRapierPlugin;
use bevy_rapier3d::prelude::*;

#[cfg(feature = "props")]
use super::prop_physics_tests;
use super::{Engine, physics_tests};

struct Rapier;

impl Engine for Rapier {
    fn add_plugins(app: &mut App) {
        app.add_plugins((
            RapierPhysicsPlugin::<NoUserData>::default(),
            TerrainRapierPlugin::default(),
        ));
    }

    #[cfg(feature = "props")]
    fn add_prop_plugin(app: &mut App) {
        app.add_plugins(bevy_chisel::splat::rapier::PropRapierPlugin::default());
    }

    fn spawn_ball(world: &mut World, radius: f32, at: Vec3) -> Entity {
        world
            .spawn((
                RigidBody::Dynamic,
                Collider::ball(radius),
                Transform::from_translation(at),
            ))
            .id()
    }

    fn spawn_sliding_cube(world: &mut World, half: f32, at: Vec3) -> Entity {
        world
            .spawn((
                RigidBody::Dynamic,
                Collider::cuboid(half, half, half),
                Friction {
                    coefficient: 0.0,
                    combine_rule: CoefficientCombineRule::Min,
                },
                LockedAxes::ROTATION_LOCKED,
                Velocity::zero(),
                Transform::from_translation(at),
            ))
            .id()
    }

    fn set_velocity(world: &mut World, body: Entity, velocity: Vec3) {
        world.entity_mut(body).insert(Velocity::linear(velocity));
    }

    fn velocity(world: &World, body: Entity) -> Vec3 {
        world.get::<Velocity>(body).expect("a rigid body").linear
    }

    fn position(world: &World, body: Entity) -> Vec3 {
        world
            .get::<Transform>(body)
            .expect("a rigid body")
            .translation
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
            .as_compound()
            .map_or(1, |compound| compound.raw.shapes().len())
    }

    fn trimesh(world: &World, entity: Entity) -> (usize, Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let collider = world.get::<Collider>(entity).expect("a collider");
        let trimesh = collider.as_trimesh().expect("a trimesh collider");
        let vertices = trimesh
            .raw
            .vertices()
            .iter()
            .map(|p| [f64::from(p.x), f64::from(p.y), f64::from(p.z)])
            .collect();
        let shape = std::sync::Arc::as_ptr(&collider.raw.0).cast::<()>() as usize;
        (shape, vertices, trimesh.raw.indices().to_vec())
    }
}

physics_tests!(Rapier);
#[cfg(feature = "props")]
prop_physics_tests!(Rapier, props_at_scale_1, 1.0);
#[cfg(feature = "props")]
prop_physics_tests!(Rapier, props_at_scale_1_10, 0.1);
