//! Quadric CSG props drawn by the splat pass: the four scenes of
//! `assets/scenes/` on a ground plane, a standard box mesh passing through
//! one of them, a slowly orbiting camera.
//!
//! Keys: `1` splats (surface-aligned boxes), `2` splats (screen quads), `3`
//! global ray tracing; `S` shaded, `B` splat bounds (the proxies
//! themselves), `O` overdraw, `N` normals; `C` bites a sphere out of every
//! prop where it is nearest the camera (`CarveProp`: props are
//! destructible); left/right arrows orbit, up/down zoom. Without a
//! display (or with `CHISEL_HEADLESS=1`) it renders offscreen and writes
//! screenshots to `screenshots/props-*.png`: frame 40 shaded, frame 60 the
//! splat bounds, frame 100 shaded with a bite out of each prop (carved at
//! frame 70).
//!
//! ```sh
//! cargo run --release --all-features --example props
//! CHISEL_HEADLESS=1 WGPU_BACKEND=vulkan cargo run --release --all-features --example props
//! ```

use bevy::prelude::*;
use bevy_chisel::presentation::Presentation;
use bevy_chisel::splat::{
    CarveProp, ChiselSplatPlugin, PropCarveRefused, PropCarved, PropSplats, QuadricProp, SplatMode,
    SplatOutput, SplatRadius, SplatSettings,
};

/// The radius of a bite (`C`), in world units: 20 mm of the scenes.
const BITE: f32 = 0.2;

/// Headless: the props are carved at this frame.
#[derive(Resource)]
struct CarveAt(u32);

/// World units per scene unit: the scenes are in millimetres, the world in
/// metres at a tenth of the size (a 10 cm part is 1 unit).
const SCALE: f32 = 0.01;

/// `(scene file, bounding centre, bounding radius, position on the ground)`;
/// the bounds are those of the scene files (the props take theirs from
/// there), repeated here to stand each prop on the ground.
const PROPS: [(&str, [f32; 3], f32, [f32; 2]); 4] = [
    (
        "scenes/three_spheres.quadric.ron",
        [0.0, 0.0, 10.0],
        75.0,
        [-1.2, -1.2],
    ),
    (
        "scenes/classic.quadric.ron",
        [0.0, 0.0, 0.0],
        90.0,
        [1.2, -1.2],
    ),
    (
        "scenes/sharp8.quadric.ron",
        [0.0, 0.0, 0.0],
        60.0,
        [-1.2, 1.2],
    ),
    (
        "scenes/machine80.quadric.ron",
        [0.0, 0.0, 35.0],
        100.0,
        [1.2, 1.2],
    ),
];

#[derive(Component)]
struct Orbit {
    angle: f32,
    distance: f32,
}

fn main() -> AppExit {
    let mut presentation = Presentation::detect("props");
    if let Presentation::Headless(config) = &mut presentation {
        // Sampling runs on the async pool: give it some frames first.
        config.capture_frames = vec![40, 60, 100];
        config.max_frames = 300;
    }
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — quadric props");
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(ClearColor(Color::srgb(0.55, 0.65, 0.8)))
        .add_systems(Startup, setup)
        .add_systems(Update, (keys, orbit, carve, report_carves));
    if headless {
        app.insert_resource(CarveAt(70))
            .add_systems(Update, headless_tour);
    }
    app.run()
}

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    for (path, centre, radius, [x, y]) in PROPS {
        let centre = Vec3::from_array(centre);
        // Standing on the ground: the lowest point of the bounds at z = 0
        // would float most props, so lift by half the bounding radius.
        let lift = 0.5 * radius * SCALE - centre.z * SCALE;
        commands.spawn((
            QuadricProp {
                scene: assets.load(path),
                // The scene file's `bounds`.
                bounds: None,
                radius: SplatRadius::Auto(40.0),
            },
            Transform::from_xyz(x, y, lift).with_scale(Vec3::splat(SCALE)),
        ));
    }
    // A standard mesh passing through the `classic` prop.
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(0.3, 2.2, 0.3))),
        MeshMaterial3d(materials.add(Color::srgb(0.8, 0.2, 0.2))),
        Transform::from_xyz(1.2, -1.2, 0.45),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::new(Vec3::Z, Vec2::splat(4.0)))),
        MeshMaterial3d(materials.add(Color::srgb(0.35, 0.4, 0.3))),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 8000.0,
            ..default()
        },
        Transform::from_xyz(2.0, -3.0, 5.0).looking_at(Vec3::ZERO, Vec3::Z),
    ));
    commands.spawn((
        Camera3d::default(),
        Orbit {
            angle: -0.6,
            distance: 6.0,
        },
        Transform::default(),
    ));
}

fn keys(input: Res<ButtonInput<KeyCode>>, mut settings: ResMut<SplatSettings>) {
    let pressed = |k| input.just_pressed(k);
    if pressed(KeyCode::Digit1) {
        settings.mode = SplatMode::SurfaceBoxes;
    } else if pressed(KeyCode::Digit2) {
        settings.mode = SplatMode::ScreenQuads;
    } else if pressed(KeyCode::Digit3) {
        settings.mode = SplatMode::GlobalRayTrace;
    } else if pressed(KeyCode::KeyB) {
        settings.output = SplatOutput::Bounds;
    } else if pressed(KeyCode::KeyO) {
        settings.output = SplatOutput::Overdraw;
    } else if pressed(KeyCode::KeyN) {
        settings.output = SplatOutput::Normals;
    } else if pressed(KeyCode::KeyS) {
        settings.output = SplatOutput::Shaded;
    }
}

/// Headless: the splat bounds from frame 50 on, shaded again from frame 80
/// (screenshots at 40, 60 and 100).
fn headless_tour(mut frame: Local<u32>, mut settings: ResMut<SplatSettings>) {
    *frame += 1;
    if *frame == 50 {
        settings.output = SplatOutput::Bounds;
    } else if *frame == 80 {
        settings.output = SplatOutput::Shaded;
    }
}

/// `C`: a bite out of every prop, centred on its splat nearest the camera
/// (a point of its surface). Headless: at frame [`CarveAt`].
fn carve(
    input: Res<ButtonInput<KeyCode>>,
    carve_at: Option<Res<CarveAt>>,
    mut frame: Local<u32>,
    cameras: Query<&GlobalTransform, With<Camera3d>>,
    props: Query<(Entity, &GlobalTransform, &PropSplats)>,
    mut carves: MessageWriter<CarveProp>,
) {
    *frame += 1;
    let now = input.just_pressed(KeyCode::KeyC) || carve_at.is_some_and(|at| at.0 == *frame);
    let Ok(eye) = cameras.single().map(GlobalTransform::translation) else {
        return;
    };
    if !now {
        return;
    }
    for (prop, transform, splats) in &props {
        let nearest = splats
            .0
            .splats
            .iter()
            .map(|s| transform.transform_point(s.position))
            .min_by(|a, b| a.distance_squared(eye).total_cmp(&b.distance_squared(eye)));
        if let Some(centre) = nearest {
            carves.write(CarveProp::sphere(prop, centre, BITE));
        }
    }
}

fn report_carves(
    mut carved: MessageReader<PropCarved>,
    mut refused: MessageReader<PropCarveRefused>,
) {
    for c in carved.read() {
        info!("prop {}: drawn with {} carve(s)", c.prop, c.carves);
    }
    for r in refused.read() {
        warn!("prop {}: carve refused: {}", r.prop, r.reason);
    }
}

fn orbit(
    time: Res<Time>,
    input: Res<ButtonInput<KeyCode>>,
    mut cameras: Query<(&mut Orbit, &mut Transform)>,
) {
    let dt = time.delta_secs();
    for (mut orbit, mut transform) in &mut cameras {
        let mut spin = 0.15;
        if input.pressed(KeyCode::ArrowLeft) {
            spin -= 1.0;
        }
        if input.pressed(KeyCode::ArrowRight) {
            spin += 1.0;
        }
        if input.pressed(KeyCode::ArrowUp) {
            orbit.distance = (orbit.distance - 3.0 * dt).max(1.0);
        }
        if input.pressed(KeyCode::ArrowDown) {
            orbit.distance = (orbit.distance + 3.0 * dt).min(20.0);
        }
        orbit.angle += spin * dt;
        let eye = Vec3::new(
            orbit.angle.cos() * orbit.distance,
            orbit.angle.sin() * orbit.distance,
            0.55 * orbit.distance,
        );
        *transform = Transform::from_translation(eye).looking_at(Vec3::new(0.0, 0.0, 0.3), Vec3::Z);
    }
}
