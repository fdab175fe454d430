//! Renders a frame through Bevy's real render pipeline on the machine's
//! Vulkan adapter (the CPU driver lavapipe in CI), headless, and checks the
//! pixels: the clear colour around the edges, an unlit red cube in the
//! middle, nothing else.

use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};

use crate::ONE_APP_AT_A_TIME;

const BACKGROUND: [u8; 3] = [0, 0, 255];
const CUBE: [u8; 3] = [255, 0, 0];

fn spawn_scene(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(1.0, 1.0, 1.0))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb_u8(CUBE[0], CUBE[1], CUBE[2]),
            unlit: true,
            ..default()
        })),
    ));
    // Looking straight at one face from 3 units away: the face spans the
    // middle third of the view height at a 45° vertical field of view.
    commands.spawn((
        Camera3d::default(),
        Tonemapping::None,
        Msaa::Off,
        Transform::from_xyz(0.0, 0.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

fn rgb(image: &Image, x: u32, y: u32) -> [u8; 3] {
    let c = image
        .get_color_at(x, y)
        .expect("pixel inside the image")
        .to_srgba()
        .to_u8_array();
    [c[0], c[1], c[2]]
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter().zip(b).all(|(&x, y)| x.abs_diff(y) <= 2)
}

#[test]
fn renders_a_cube_headless_and_reads_back_its_pixels() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let config = HeadlessConfig {
        width: 128,
        height: 96,
        // Not the first frames: the offscreen target and the mesh reach the
        // GPU a few frames after startup (later under load).
        capture_frames: vec![8, 12],
        output_dir: None,
        stem: "headless_render".into(),
        max_frames: 240,
        // The pixels are checked one by one below.
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "headless test");
    crate::common::hold_captures_until_pipelines_ready(&mut app);
    app.insert_resource(ClearColor(Color::srgb_u8(
        BACKGROUND[0],
        BACKGROUND[1],
        BACKGROUND[2],
    )))
    .add_systems(Startup, spawn_scene);
    assert_eq!(
        app.run(),
        AppExit::Success,
        "headless run did not capture its frame"
    );

    let images = frames.images();
    assert_eq!(images.len(), 2);
    // A still scene: both captures agree pixel for pixel.
    assert_eq!(
        images[0].data, images[1].data,
        "the frame changed between captures"
    );
    let image = &images[1];
    assert_eq!((image.width(), image.height()), (128, 96));

    // Centre: the cube's face.
    assert!(
        close(rgb(image, 64, 48), CUBE),
        "centre is {:?}",
        rgb(image, 64, 48)
    );
    // Corners and edge midpoints: background.
    for (x, y) in [(0, 0), (127, 0), (0, 95), (127, 95), (64, 2), (2, 48)] {
        assert!(
            close(rgb(image, x, y), BACKGROUND),
            "({x}, {y}) is {:?}",
            rgb(image, x, y)
        );
    }
    // The face covers the expected share of the frame: at distance 2.5 the
    // half-height of the view is 2.5·tan(22.5°) = 1.036, so the unit face
    // spans 0.5/1.036 = 48.3% of the height, about 46 px, and as many across.
    let red = (0..96)
        .flat_map(|y| (0..128).map(move |x| (x, y)))
        .filter(|&(x, y)| close(rgb(image, x, y), CUBE))
        .count();
    let expected = (0.483f64 * 96.0).powi(2);
    let ratio = red as f64 / expected;
    assert!(
        (0.9..1.1).contains(&ratio),
        "cube covers {red} px, expected about {expected:.0}"
    );
}
