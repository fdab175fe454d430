//! The game on avian3d: its plugins, the player's body, and the systems
//! that copy [`Body`] to and from the simulation.

use avian3d::prelude::*;
use bevy::prelude::*;
use bevy_chisel::splat::avian::PropAvianPlugin;
use bevy_chisel::terrain::avian::TerrainAvianPlugin;

use super::physics::{AfterPhysics, Body, GROUND_REACH, PROBE_RADIUS, PROBE_REACH};
use super::{PLAYER_LENGTH, PLAYER_RADIUS, Player, ThirdPerson, camera_target};

/// Adds avian3d with the terrain's and the props' colliders. Headless, the
/// physics steps at 20 Hz, one step per frame.
pub fn add_physics(app: &mut App, headless: bool) {
    app.add_plugins((
        PhysicsPlugins::default(),
        TerrainAvianPlugin::default(),
        PropAvianPlugin::default(),
    ))
    .add_observer(give_player_a_body)
    .configure_sets(PostUpdate, AfterPhysics.after(PhysicsSystems::Writeback))
    // The physics steps in the fixed loop, after `PreUpdate` and before
    // `Update`.
    .add_systems(
        RunFixedMainLoop,
        read_body.in_set(RunFixedMainLoopSystems::AfterFixedMainLoop),
    )
    .add_systems(
        PostUpdate,
        (
            write_body,
            find_camera_blocks
                .in_set(AfterPhysics)
                .before(super::follow_player),
        ),
    );
    if headless {
        app.insert_resource(Time::<Fixed>::from_hz(20.0));
    }
}

/// A capsule that does not turn, slides without friction (the game steers
/// its velocity) and probes the ground under it.
fn give_player_a_body(add: On<Add, Player>, mut commands: Commands) {
    commands.entity(add.entity).insert((
        RigidBody::Dynamic,
        Collider::capsule(PLAYER_RADIUS, PLAYER_LENGTH),
        LockedAxes::ROTATION_LOCKED,
        Friction::ZERO.with_combine_rule(CoefficientCombine::Min),
        Restitution::ZERO.with_combine_rule(CoefficientCombine::Min),
        ShapeCaster::new(
            Collider::sphere(PROBE_RADIUS),
            Vec3::ZERO,
            Quat::IDENTITY,
            Dir3::NEG_Y,
        )
        .with_max_distance(PROBE_REACH),
        CollidingEntities::default(),
    ));
}

/// The simulation's velocity, ground probe and contacts, into [`Body`].
fn read_body(
    mut players: Query<(&mut Body, &LinearVelocity, &ShapeHits, &CollidingEntities), With<Player>>,
) {
    for (mut body, velocity, hits, touching) in &mut players {
        body.velocity = velocity.0;
        body.grounded = hits.iter().any(|hit| hit.distance <= GROUND_REACH);
        body.touching = touching.iter().copied().collect();
    }
}

/// The game's velocity, into the simulation.
fn write_body(mut players: Query<(&Body, &mut LinearVelocity), With<Player>>) {
    for (body, mut velocity) in &mut players {
        if velocity.0 != body.velocity {
            velocity.0 = body.velocity;
        }
    }
}

/// Where something other than the player blocks each camera's view.
fn find_camera_blocks(
    players: Query<(Entity, &Transform), With<Player>>,
    mut cameras: Query<&mut ThirdPerson>,
    spatial: SpatialQuery,
) {
    let Ok((player, body)) = players.single() else {
        return;
    };
    let target = camera_target(body.translation);
    let filter = SpatialQueryFilter::default().with_excluded_entities([player]);
    for mut view in &mut cameras {
        let Ok(direction) = Dir3::new(view.back()) else {
            continue;
        };
        view.blocked_at = spatial
            .cast_ray(target, direction, view.distance, true, &filter)
            .map(|hit| hit.distance);
    }
}
