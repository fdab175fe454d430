//! The bevy_chisel demo scene.
//!
//! For now a preview of the quarry: a layered block of rock, dirt and ore
//! under a sun, seen from a slowly orbiting camera. Carving arrives with the
//! terrain plugin. Runs in a window when a display exists; otherwise renders
//! headless and writes PNG screenshots to `screenshots/`.
//!
//! `cargo run --release --example quarry`

use bevy::prelude::*;
use bevy_chisel::presentation::Presentation;

fn main() -> AppExit {
    let presentation = Presentation::detect("quarry");
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — quarry");
    app.insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
        .add_systems(Startup, spawn_scene)
        .add_systems(Update, orbit_camera)
        .run()
}

/// Layer thickness (m) and colour, top to bottom.
const LAYERS: [(f32, Color); 4] = [
    (1.0, Color::srgb(0.33, 0.52, 0.22)), // grass-topped dirt
    (3.0, Color::srgb(0.45, 0.33, 0.22)), // dirt
    (2.0, Color::srgb(0.55, 0.55, 0.58)), // rock
    (2.0, Color::srgb(0.42, 0.42, 0.46)), // deep rock
];

fn spawn_scene(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let size = 16.0;
    let mut top = 0.0;
    for (thickness, color) in LAYERS {
        commands.spawn((
            Mesh3d(meshes.add(Cuboid::new(size, thickness, size))),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: color,
                perceptual_roughness: 0.9,
                ..default()
            })),
            Transform::from_xyz(0.0, top - thickness / 2.0, 0.0),
        ));
        top -= thickness;
    }
    // Veins of ore in the rock layer.
    let ore = materials.add(StandardMaterial {
        base_color: Color::srgb(0.85, 0.65, 0.15),
        metallic: 0.6,
        perceptual_roughness: 0.4,
        ..default()
    });
    for (x, z) in [(-5.0, 8.0), (2.5, 8.0), (8.0, -3.0), (8.0, 4.5)] {
        commands.spawn((
            Mesh3d(meshes.add(Cuboid::new(1.2, 0.8, 1.2))),
            MeshMaterial3d(ore.clone()),
            Transform::from_xyz(x, -5.0, z),
        ));
    }
    commands.spawn((
        DirectionalLight {
            illuminance: 12_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(10.0, 20.0, 6.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn((Camera3d::default(), Transform::default()));
    commands.spawn((
        Text::new("bevy_chisel quarry (preview): carving arrives with the terrain plugin"),
        Node {
            position_type: PositionType::Absolute,
            top: px(12),
            left: px(12),
            ..default()
        },
    ));
}

fn orbit_camera(time: Res<Time>, mut cameras: Query<&mut Transform, With<Camera3d>>) {
    let angle = 0.6 + 0.15 * time.elapsed_secs();
    for mut transform in &mut cameras {
        *transform = Transform::from_xyz(26.0 * angle.cos(), 14.0, 26.0 * angle.sin())
            .looking_at(Vec3::new(0.0, -3.0, 0.0), Vec3::Y);
    }
}
