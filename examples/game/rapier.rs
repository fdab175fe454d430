//! The game on bevy_rapier3d: its plugins, the player's body, and the
//! systems that copy [`Body`] to and from the simulation.

use bevy::prelude::*;
use bevy_chisel::splat::rapier::PropRapierPlugin;
use bevy_chisel::terrain::rapier::TerrainRapierPlugin;
use bevy_rapier3d::prelude::*;

use super::physics::{AfterPhysics, Body, GROUND_REACH, PROBE_RADIUS, PROBE_REACH};
use super::{PLAYER_LENGTH, PLAYER_RADIUS, Player, ThirdPerson, camera_target};

/// Adds Rapier with the terrain's and the props' colliders. In a window the
/// physics steps 1/60 s at a time, as many steps as real time has passed
/// (so the game keeps its speed below 60 frames a second), and the player
/// is drawn between its last two steps; headless, each frame advances it
/// by 1/20 s, in three steps of 1/60 s.
pub fn add_physics(app: &mut App, headless: bool) {
    app.add_plugins((
        RapierPhysicsPlugin::<NoUserData>::default(),
        TerrainRapierPlugin::default(),
        PropRapierPlugin::default(),
    ))
    .add_observer(give_player_a_body)
    .configure_sets(PostUpdate, AfterPhysics.after(PhysicsSet::Writeback))
    .add_systems(PreUpdate, read_body)
    .add_systems(PostUpdate, write_body.before(PhysicsSet::SyncBackend))
    .add_systems(
        PostUpdate,
        find_camera_blocks
            .in_set(AfterPhysics)
            .before(super::follow_player),
    );
    app.insert_resource(if headless {
        TimestepMode::Fixed {
            dt: 1.0 / 20.0,
            substeps: 3,
        }
    } else {
        TimestepMode::Interpolated {
            dt: 1.0 / 60.0,
            time_scale: 1.0,
            substeps: 1,
        }
    });
}

/// A capsule that does not turn, slides without friction (the game steers
/// its velocity) and reports what it touches.
fn give_player_a_body(add: On<Add, Player>, mut commands: Commands) {
    commands.entity(add.entity).insert((
        RigidBody::Dynamic,
        Collider::capsule_y(PLAYER_LENGTH / 2.0, PLAYER_RADIUS),
        LockedAxes::ROTATION_LOCKED,
        Friction {
            coefficient: 0.0,
            combine_rule: CoefficientCombineRule::Min,
        },
        Restitution {
            coefficient: 0.0,
            combine_rule: CoefficientCombineRule::Min,
        },
        Velocity::zero(),
        TransformInterpolation::default(),
        ActiveEvents::COLLISION_EVENTS,
        CollidingEntities::default(),
    ));
}

/// The simulation's velocity and contacts, and a ground probe (a sphere
/// cast down from the capsule's centre), into [`Body`].
fn read_body(
    mut players: Query<
        (Entity, &Transform, &mut Body, &Velocity, &CollidingEntities),
        With<Player>,
    >,
    rapier: ReadRapierContext,
) {
    let Ok(context) = rapier.single() else {
        return;
    };
    let probe = Collider::ball(PROBE_RADIUS);
    for (entity, transform, mut body, velocity, touching) in &mut players {
        let hit = context.cast_shape(
            transform.translation,
            Quat::IDENTITY,
            Vec3::NEG_Y,
            &*probe.raw,
            ShapeCastOptions::with_max_time_of_impact(PROBE_REACH),
            QueryFilter::default().exclude_rigid_body(entity),
        );
        body.velocity = velocity.linear;
        body.grounded = hit.is_some_and(|(_, hit)| hit.time_of_impact <= GROUND_REACH);
        body.touching = touching.iter().collect();
    }
}

/// The game's velocity, into the simulation.
fn write_body(mut players: Query<(&Body, &mut Velocity), With<Player>>) {
    for (body, mut velocity) in &mut players {
        if velocity.linear != body.velocity {
            velocity.linear = body.velocity;
        }
    }
}

/// Where something other than the player blocks each camera's view.
fn find_camera_blocks(
    players: Query<(Entity, &Transform), With<Player>>,
    mut cameras: Query<&mut ThirdPerson>,
    rapier: ReadRapierContext,
) {
    let (Ok((player, body)), Ok(context)) = (players.single(), rapier.single()) else {
        return;
    };
    let target = camera_target(body.translation);
    let filter = QueryFilter::default().exclude_rigid_body(player);
    for mut view in &mut cameras {
        let back = view.back();
        view.blocked_at = context
            .cast_ray(target, back, view.distance, true, filter)
            .map(|(_, distance)| distance);
    }
}
