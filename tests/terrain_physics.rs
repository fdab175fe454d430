//! Terrain colliders with avian3d (feature `avian`), in an app without
//! rendering: every cell entity carries a trimesh collider built with its
//! mesh, a ball comes to rest on the ground and falls into a crater carved
//! under it, and a box slides over many cell borders without catching.

use std::time::Duration;

use avian3d::prelude::*;
use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::avian::TerrainAvianPlugin;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveTool, Terrain, TerrainCell, TerrainPlugin, TerrainSystems,
};

/// One physics step per update, whatever the wall clock does.
const STEP: f32 = 1.0 / 60.0;

#[derive(Resource, Default)]
struct Applied(Vec<CarveApplied>);

fn record(mut seen: ResMut<Applied>, mut applied: MessageReader<CarveApplied>) {
    seen.0.extend(applied.read().cloned());
}

/// A 16 m × 4 m × 16 m slab, top at y = 0, on a 1 cm grid, with a small
/// node budget so its surface spans many cells.
fn app_with_slab() -> (App, Entity) {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        PhysicsPlugins::default(),
        TerrainPlugin,
        TerrainAvianPlugin::default(),
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
        STEP,
    )))
    .init_resource::<Applied>()
    .add_systems(Update, record.after(TerrainSystems::Mesh));
    let grid = Quantization::new(0.01, [0.0; 3]).expect("valid unit");
    let terrain = Terrain::from_box(
        grid,
        Vec3::new(-8.0, -4.0, -8.0),
        Vec3::new(8.0, 0.0, 8.0),
        1,
    )
    .expect("valid slab");
    let entity = app.world_mut().spawn(terrain).id();
    settle(&mut app, entity);
    (app, entity)
}

fn settle(app: &mut App, entity: Entity) {
    for _ in 0..20_000 {
        app.update();
        let idle = app
            .world()
            .get::<Terrain>(entity)
            .is_some_and(Terrain::is_idle);
        if idle {
            app.update();
            return;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("terrain did not settle");
}

fn step(app: &mut App, frames: usize) {
    for _ in 0..frames {
        app.update();
    }
}

fn position(app: &App, body: Entity) -> Vec3 {
    app.world().get::<Position>(body).expect("a rigid body").0
}

/// Every cell entity of the terrain has a collider, and there are some.
fn assert_every_cell_has_a_collider(app: &mut App) -> usize {
    let mut cells = app
        .world_mut()
        .query_filtered::<(Entity, Has<Collider>), With<TerrainCell>>();
    let all: Vec<(Entity, bool)> = cells.iter(app.world()).collect();
    assert!(!all.is_empty(), "the terrain shows no cells");
    for (entity, has) in &all {
        assert!(has, "cell entity {entity} has no collider");
    }
    all.len()
}

#[test]
fn a_ball_rests_on_the_ground_and_falls_into_a_crater_carved_under_it() {
    let (mut app, terrain) = app_with_slab();
    assert_every_cell_has_a_collider(&mut app);

    let radius = 0.5;
    let ball = app
        .world_mut()
        .spawn((
            RigidBody::Dynamic,
            Collider::sphere(radius),
            Transform::from_xyz(0.3, 2.0, -0.2),
        ))
        .id();
    step(&mut app, 180);
    let rest = position(&app, ball);
    assert!(
        (rest.y - radius).abs() < 0.05,
        "the ball should rest on the ground at y = {radius}, it is at {rest}"
    );

    // A crater 2 m deep right under the ball.
    app.world_mut().write_message(Carve {
        terrain,
        tool: CarveTool::dodecahedron(2.5, Vec3::new(rest.x, 0.5, rest.z)),
        edit: Edit::Subtract,
    });
    settle(&mut app, terrain);
    let applied = &app.world().resource::<Applied>().0;
    let last = applied.last().expect("the carve is applied");
    assert!(last.collider_time > Duration::ZERO, "colliders were built");
    assert_every_cell_has_a_collider(&mut app);

    step(&mut app, 180);
    let fallen = position(&app, ball);
    assert!(
        fallen.y < -1.0,
        "the ball should have fallen into the crater, it is at {fallen}"
    );
}

#[test]
fn a_box_slides_over_cell_borders_without_catching() {
    let (mut app, _) = app_with_slab();
    let cells = assert_every_cell_has_a_collider(&mut app);
    assert!(cells >= 4, "the slab's top spans {cells} cells");

    let half = 0.25;
    let body = app
        .world_mut()
        .spawn((
            RigidBody::Dynamic,
            Collider::cuboid(2.0 * half, 2.0 * half, 2.0 * half),
            Friction::ZERO.with_combine_rule(CoefficientCombine::Min),
            LockedAxes::ROTATION_LOCKED,
            Transform::from_xyz(-6.0, half + 0.01, 0.37),
        ))
        .id();
    step(&mut app, 30);
    app.world_mut()
        .entity_mut(body)
        .insert(LinearVelocity(Vec3::new(4.0, 0.0, 0.0)));
    let mut max_rise = 0.0f32;
    let mut min_speed = f32::INFINITY;
    for _ in 0..150 {
        step(&mut app, 1);
        let p = position(&app, body);
        max_rise = max_rise.max(p.y - half);
        let v = app
            .world()
            .get::<LinearVelocity>(body)
            .expect("a rigid body")
            .0;
        min_speed = min_speed.min(v.x);
        if p.x > 5.0 {
            break;
        }
    }
    let end = position(&app, body);
    assert!(end.x > 4.0, "the box stopped at {end}");
    assert!(
        max_rise < 0.02,
        "the box bounced {max_rise} m off the ground at a cell border"
    );
    assert!(
        min_speed > 3.5,
        "the box caught on an edge: its speed fell to {min_speed} m/s"
    );
}
