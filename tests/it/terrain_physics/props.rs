//! Quadric props in the simulation: a ring prop (the prop collider unit
//! tests' ring: radii 5 to 10 around its axis, 4 thick), stood up over
//! flat ground at a given scale, is solid where its material is and open
//! in its hole, with either engine.
//!
//! The ring's voxels (48 along each edge of its 24-unit bounding cube,
//! 0.5 units each) end exactly on its top and bottom faces, and lie within
//! half a voxel diagonal, 0.35 units, of its round edges; the expected
//! positions below allow that, and the engines' contact tolerance.

use std::f32::consts::{FRAC_PI_2, SQRT_2};
use std::time::Duration;

use bevy::prelude::*;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::quadric::Scene;
use bevy_chisel::splat::prop_collider::{PropCollider, PropColliderShape};
use bevy_chisel::splat::{
    CarveProp, ChiselSplatPlugin, PropBounds, QuadricProp, QuadricScene, SplatRadius,
};
use bevy_chisel::terrain::Terrain;

use super::{Engine, physics_app, settle, step};
use crate::ONE_APP_AT_A_TIME;

/// The ring of `plugin/splat/prop_collider.rs`'s tests, in scene units.
const RING: &str = r#"Scene(
    primitives: [
        (name: "outer", shape: Cylinder(point: (0, 0, 0), axis: (0, 0, 1), radius: 10)),
        (name: "inner", shape: Cylinder(point: (0, 0, 0), axis: (0, 0, 1), radius: 5)),
        (name: "slab", shape: Box(min: (-20, -20, -2), max: (20, 20, 2))),
    ],
    root: Difference([Intersection([Ref("outer"), Ref("slab")]), Ref("inner")]),
)"#;

/// How far a resting ball's centre may be from where it touches the exact
/// collider: the engines' contact slop (a few millimetres) with margin.
const CONTACT: f32 = 0.02;
/// Frames (of 1/60 s) from the drop to rest: 3 s.
const FALL: usize = 180;

/// The ring prop placed at `scale` metres per scene unit, its axis the
/// world's y axis, its middle `10 · scale` over the ground (top at y = 0).
#[derive(Clone, Copy)]
struct Ring {
    scale: f32,
}

impl Ring {
    fn centre_height(self) -> f32 {
        10.0 * self.scale
    }
    /// The hole's radius.
    fn hole(self) -> f32 {
        5.0 * self.scale
    }
    fn outer(self) -> f32 {
        10.0 * self.scale
    }
    /// The height of the top face.
    fn top(self) -> f32 {
        self.centre_height() + 2.0 * self.scale
    }
    /// Half a voxel diagonal across the axis: how far the collider's round
    /// edges may lie from the exact ones.
    fn voxel_slack(self) -> f32 {
        0.5 * SQRT_2 / 2.0 * self.scale
    }
}

/// The app with flat ground and the ring prop, once the prop's collider
/// is in, and the prop.
fn app_with_ring<E: Engine>(ring: Ring) -> (App, Entity) {
    let mut app = physics_app::<E>(|app| {
        app.add_plugins(ChiselSplatPlugin);
        E::add_prop_plugin(app);
    });
    let grid = Quantization::new(0.01, [0.0; 3]).expect("valid unit");
    let half = ring.outer() + 2.0;
    let ground = Terrain::from_box(
        grid,
        Vec3::new(-half, -2.0, -half),
        Vec3::new(half, 0.0, half),
        1,
    )
    .expect("valid ground");
    let terrain = app.world_mut().spawn(ground).id();
    settle(&mut app, terrain);

    let scene = Scene::from_ron(RING).expect("valid scene");
    let scene = app
        .world_mut()
        .resource_mut::<Assets<QuadricScene>>()
        .add(QuadricScene(scene));
    let prop = app
        .world_mut()
        .spawn((
            QuadricProp {
                scene,
                bounds: Some(PropBounds {
                    centre: Vec3::ZERO,
                    radius: 12.0,
                }),
                radius: SplatRadius::Auto(40.0),
            },
            // The scene's z axis up.
            Transform::from_xyz(0.0, ring.centre_height(), 0.0)
                .with_rotation(Quat::from_rotation_x(-FRAC_PI_2))
                .with_scale(Vec3::splat(ring.scale)),
        ))
        .id();
    for _ in 0..20_000 {
        app.update();
        if app.world().get::<PropCollider>(prop).is_some() {
            step(&mut app, 1);
            let shape = collider_shape(&mut app, prop);
            assert!(
                E::has_collider(app.world(), shape),
                "the prop's shape has a collider"
            );
            return (app, prop);
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    panic!("the prop's collider did not come in");
}

/// The prop's collider shape entity: its only child with a
/// [`PropColliderShape`].
fn collider_shape(app: &mut App, prop: Entity) -> Entity {
    let mut shapes = app
        .world_mut()
        .query_filtered::<(Entity, &ChildOf), With<PropColliderShape>>();
    let shapes: Vec<Entity> = shapes
        .iter(app.world())
        .filter(|(_, child_of)| child_of.parent() == prop)
        .map(|(shape, _)| shape)
        .collect();
    assert_eq!(shapes.len(), 1, "one collider shape under the prop");
    shapes[0]
}

/// Drops a ball of `radius` from 1.5 m over the ring's top at `(x, z)` and
/// returns where it is after [`FALL`] frames.
fn drop_ball<E: Engine>(ring: Ring, radius: f32, x: f32, z: f32) -> Vec3 {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut app, _) = app_with_ring::<E>(ring);
    drop_ball_in::<E>(&mut app, ring, radius, x, z)
}

fn drop_ball_in<E: Engine>(app: &mut App, ring: Ring, radius: f32, x: f32, z: f32) -> Vec3 {
    let ball = E::spawn_ball(app.world_mut(), radius, Vec3::new(x, ring.top() + 1.5, z));
    step(app, FALL);
    E::position(app.world(), ball)
}

pub(super) fn a_ball_dropped_onto_a_ring_prop_rests_on_its_band<E: Engine>(scale: f32) {
    // On the middle of the band, which is flat on top.
    let ring = Ring { scale };
    let radius = 2.0 * scale;
    let middle = (ring.hole() + ring.outer()) / 2.0;
    let rest = drop_ball::<E>(ring, radius, middle, 0.0);
    assert!(
        (rest.y - (ring.top() + radius)).abs() < CONTACT,
        "the ball should rest on the ring's top at y = {}, it is at {rest}",
        ring.top() + radius
    );
    assert!(
        (rest.x - middle).abs() < 0.05 && rest.z.abs() < 0.05,
        "the ball should stay where it landed, on the band at x = {middle}: it is at {rest}"
    );
}

pub(super) fn a_ball_dropped_into_a_ring_prop_falls_through_its_hole<E: Engine>(scale: f32) {
    // 3 against a hole of 5, less the voxels' slack.
    let ring = Ring { scale };
    let radius = 3.0 * scale;
    assert!(radius < ring.hole() - ring.voxel_slack());
    let rest = drop_ball::<E>(ring, radius, 0.0, 0.0);
    assert!(
        (rest.y - radius).abs() < CONTACT,
        "the ball should fall through the hole onto the ground at y = {radius}, it is at {rest}"
    );
    // Straight down the axis: it touched nothing on the way.
    assert!(
        rest.x.abs() < 0.01 && rest.z.abs() < 0.01,
        "the ball should fall straight through the hole, it is at {rest}"
    );
}

pub(super) fn a_ball_wider_than_a_ring_props_hole_rests_on_its_rim<E: Engine>(scale: f32) {
    // A ball of radius R on a circular rim of radius ρ at the top face
    // rests with its centre √(R² − ρ²) above the face; the voxels put the
    // rim within the voxels' slack of the hole's radius.
    let ring = Ring { scale };
    let radius = 6.0 * scale;
    let rest = drop_ball::<E>(ring, radius, 0.0, 0.0);
    let height = |rim: f32| ring.top() + (radius * radius - rim * rim).sqrt();
    let (low, high) = (
        height(ring.hole() + ring.voxel_slack()),
        height(ring.hole() - ring.voxel_slack()),
    );
    assert!(
        rest.y > low - CONTACT && rest.y < high + CONTACT,
        "the ball should rest on the rim, its centre between y = {low} and {high}: it is at {rest}"
    );
    assert!(
        rest.x.abs() < 0.05 && rest.z.abs() < 0.05,
        "the ball should rest centred in the hole, it is at {rest}"
    );
}

pub(super) fn a_ring_prop_scaled_again_and_mirrored_holds_a_ball_at_its_new_size<E: Engine>(
    scale: f32,
) {
    // The collider comes in at twice the size; then the prop is scaled to
    // `scale` and mirrored across the scene's x axis (the ring is
    // symmetric, so its solid is the same): the shape is fitted again, and
    // a ball lands on the band where the smaller ring's top is.
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let ring = Ring { scale };
    let (mut app, prop) = app_with_ring::<E>(Ring { scale: 2.0 * scale });
    let first = collider_shape(&mut app, prop);
    let mirrored = Vec3::new(-scale, scale, scale);
    let mut transform = app
        .world_mut()
        .get_mut::<Transform>(prop)
        .expect("the prop's transform");
    transform.translation.y = ring.centre_height();
    transform.scale = mirrored;
    step(&mut app, 2);
    let shape = collider_shape(&mut app, prop);
    assert_eq!(shape, first, "the same shape entity, fitted again");
    let fitted = app
        .world()
        .get::<PropColliderShape>(shape)
        .expect("a shape")
        .scale;
    assert!(
        (fitted.abs() - Vec3::splat(scale)).abs().max_element() < 1e-5,
        "fitted to the new scale: {fitted}"
    );
    let radius = 2.0 * scale;
    let middle = (ring.hole() + ring.outer()) / 2.0;
    let rest = drop_ball_in::<E>(&mut app, ring, radius, middle, 0.0);
    assert!(
        (rest.y - (ring.top() + radius)).abs() < CONTACT,
        "the ball should rest on the rescaled ring's top at y = {}, it is at {rest}",
        ring.top() + radius
    );
}

pub(super) fn a_ball_falls_through_a_bite_carved_out_of_a_ring_prop<E: Engine>(scale: f32) {
    // A sphere of radius 4 around the middle of the band cuts through its
    // whole thickness (4) and width (5): the collider is voxelized again
    // from the carved solid, and a ball that rested on the band (see
    // above) falls through the gap onto the ground.
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let ring = Ring { scale };
    let (mut app, prop) = app_with_ring::<E>(ring);
    let voxels = app
        .world()
        .get::<PropCollider>(prop)
        .expect("a collider")
        .voxels;
    let middle = (ring.hole() + ring.outer()) / 2.0;
    let centre = Vec3::new(middle, ring.centre_height(), 0.0);
    app.world_mut()
        .write_message(CarveProp::sphere(prop, centre, 4.0 * scale));
    let mut carved = false;
    for _ in 0..20_000 {
        app.update();
        if app
            .world()
            .get::<PropCollider>(prop)
            .is_some_and(|c| c.voxels < voxels)
        {
            carved = true;
            break;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    assert!(carved, "the carved prop's collider did not come in");
    step(&mut app, 1);
    let radius = 1.0 * scale;
    let rest = drop_ball_in::<E>(&mut app, ring, radius, middle, 0.0);
    assert!(
        (rest.y - radius).abs() < CONTACT,
        "the ball should fall through the bite onto the ground at y = {radius}, it is at {rest}"
    );
}
