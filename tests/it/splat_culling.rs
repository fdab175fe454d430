//! Frustum culling of props: the `Aabb` that comes with a prop's splats
//! holds every splat's proxy, Bevy's visibility check culls a prop outside
//! a camera's frustum with it, and the render world draws a view's props
//! from that view's list only.
//!
//! The app runs headless on the machine's Vulkan adapter (lavapipe in CI),
//! with pipelined rendering off so that the test can read the render world
//! after each update.

use std::any::TypeId;

use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::camera::primitives::Aabb;
use bevy::camera::visibility::VisibleEntities;
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::sync_world::RenderEntity;
use bevy::render::{RenderApp, RenderPlugin};
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use bevy_chisel::quadric::Scene;
use bevy_chisel::splat::render::{ExtractedProps, VisibleProps};
use bevy_chisel::splat::{ChiselSplatPlugin, PropBounds, PropSplats};

use crate::ONE_APP_AT_A_TIME;

fn splats(name: &str, centre: [f64; 3], radius: f64) -> PropSplats {
    let path = format!(
        "{}/assets/scenes/{name}.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = Scene::load(&path).expect("shipped scene");
    let bounds = PropBounds {
        centre: DVec3::from(centre).as_vec3(),
        radius: radius as f32,
    };
    PropSplats::build(&scene, bounds, (radius / 30.0) as f32).expect("sampling")
}

/// The corners of a splat's surface-aligned box, as `shaders/splat.wgsl`
/// builds them (with the pass's default radius tolerance).
fn box_corners(s: &bevy_chisel::splat::gpu::SplatRecord) -> Vec<Vec3> {
    let tolerance = 1.001;
    let r = s.radius * tolerance;
    let (n, e, t1, h) = if s.normal.length_squared() < 0.25 {
        let helper = Vec3::X;
        (
            Vec3::Z,
            r,
            helper.cross(Vec3::Z).normalize(),
            Vec2::splat(r),
        )
    } else {
        (
            s.normal,
            s.normal_extent * tolerance,
            s.tangent,
            s.tangent_extent * tolerance,
        )
    };
    let t2 = n.cross(t1);
    let mut corners = Vec::new();
    for a in [-1.0, 1.0] {
        for b in [-1.0, 1.0] {
            for c in [-1.0, 1.0] {
                corners.push(s.position + t1 * (a * h.x) + t2 * (b * h.y) + n * (c * e));
            }
        }
    }
    corners
}

#[test]
fn the_aabb_holds_every_splat_proxy() {
    for (name, centre, radius) in [
        ("three_spheres", [0.0, 0.0, 10.0], 75.0),
        ("classic", [0.0, 0.0, 0.0], 90.0),
        ("sharp8", [0.0, 0.0, 0.0], 60.0),
    ] {
        let prop = splats(name, centre, radius);
        let aabb = prop.0.aabb();
        let (lo, hi) = (Vec3::from(aabb.min()), Vec3::from(aabb.max()));
        let mut corners = 0;
        for s in &prop.0.splats {
            for p in box_corners(s) {
                assert!(
                    p.cmpge(lo).all() && p.cmple(hi).all(),
                    "{name}: a proxy corner {p} lies outside the Aabb {lo}..{hi}"
                );
                corners += 1;
            }
        }
        // Not a box around everything: within the bounding sphere's box
        // (plus a splat's reach).
        let reach = 3.0 * prop.0.radius;
        let sphere_lo = DVec3::from(centre).as_vec3() - Vec3::splat(radius as f32 + reach);
        let sphere_hi = DVec3::from(centre).as_vec3() + Vec3::splat(radius as f32 + reach);
        assert!(
            lo.cmpge(sphere_lo).all() && hi.cmple(sphere_hi).all(),
            "{name}: the Aabb {lo}..{hi} is looser than the bounding sphere"
        );
        println!(
            "{name}: {} splats, {corners} proxy corners inside {lo}..{hi}",
            prop.0.splat_count()
        );
    }
}

/// The camera whose frustum culls.
#[derive(Resource, Clone, Copy)]
struct Props {
    camera: Entity,
}

fn headless_app() -> App {
    let mut app = App::new();
    app.add_plugins((
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<WinitPlugin>()
            .disable::<PipelinedRenderingPlugin>(),
        ChiselSplatPlugin,
    ));
    app
}

/// The main-world and render-world answers for one prop.
fn seen(app: &mut App, prop: Entity) -> (bool, bool, bool, bool) {
    let props = *app.world().resource::<Props>();
    let world = app.world_mut();
    let view_visible = world
        .get::<ViewVisibility>(prop)
        .expect("props have a ViewVisibility")
        .get();
    let in_list = world
        .get::<VisibleEntities>(props.camera)
        .expect("the camera has VisibleEntities")
        .get(TypeId::of::<PropSplats>())
        .contains(&prop);
    let render_camera = world
        .get::<RenderEntity>(props.camera)
        .expect("the camera is synced to the render world")
        .id();
    let render = app.sub_app(RenderApp).world();
    let drawn = render
        .get::<VisibleProps>(render_camera)
        .expect("the view has its VisibleProps")
        .0
        .contains(&prop);
    let extracted = render
        .resource::<ExtractedProps>()
        .0
        .iter()
        .any(|p| p.entity == prop);
    (view_visible, in_list, drawn, extracted)
}

#[test]
fn a_prop_outside_the_frustum_is_culled_and_drawn_once_back_in_view() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let prop = splats("classic", [0.0; 3], 90.0);
    let mut app = headless_app();
    let size = Extent3d {
        width: 64,
        height: 64,
        depth_or_array_layers: 1,
    };
    let mut image = Image::new_uninit(
        size,
        TextureDimension::D2,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage |= TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    let target = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    // Scene units are millimetres: the prop is 1.8 m across at 0.01.
    let scale = Transform::from_scale(Vec3::splat(0.01));
    let world = app.world_mut();
    let front = world.spawn((prop.clone(), scale)).id();
    // 6 m to the side of a camera looking down −z with a 45° field of view:
    // its Aabb lies wholly outside the frustum.
    let side = world
        .spawn((
            prop.clone(),
            scale.with_translation(Vec3::new(6.0, 0.0, 0.0)),
        ))
        .id();
    let camera = world
        .spawn((
            Camera3d::default(),
            RenderTarget::Image(target.into()),
            Transform::from_xyz(0.0, 0.0, 5.0).looking_at(Vec3::ZERO, Vec3::Y),
        ))
        .id();
    world.insert_resource(Props { camera });
    app.finish();
    app.cleanup();
    for _ in 0..3 {
        app.update();
    }
    for entity in [front, side] {
        let aabb = app
            .world()
            .get::<Aabb>(entity)
            .expect("splats bring an Aabb");
        assert_eq!(*aabb, prop.0.aabb());
    }
    assert_eq!(
        seen(&mut app, front),
        (true, true, true, true),
        "the prop in front of the camera is visible, listed, extracted and drawn"
    );
    assert_eq!(
        seen(&mut app, side),
        (false, false, false, false),
        "the prop beside the camera is culled"
    );

    // Moved into view, it is drawn; the first one, moved behind the
    // camera, is culled.
    let world = app.world_mut();
    world
        .entity_mut(side)
        .insert(scale.with_translation(Vec3::new(0.5, 0.0, 0.0)));
    world
        .entity_mut(front)
        .insert(scale.with_translation(Vec3::new(0.0, 0.0, 9.0)));
    for _ in 0..2 {
        app.update();
    }
    assert_eq!(seen(&mut app, side), (true, true, true, true));
    assert_eq!(seen(&mut app, front), (false, false, false, false));
}
