//! The splat pass's lighting is Bevy's:
//!
//! - it takes each camera's `Exposure`: two cameras with the same view of
//!   one prop, one stop apart (EV100 9.7 and 10.7), see the same pixels,
//!   the darker at half the linear colour of the brighter (no tonemapping,
//!   so the ratio is the exposure's);
//! - a prop sphere matches a `StandardMaterial` sphere mesh of the same
//!   base colour, metallic, roughness and reflectance, side by side under
//!   a directional and a point light with the default tonemapping.
//!
//! Headless on the machine's Vulkan adapter (lavapipe in CI).

use bevy::camera::{ClearColorConfig, Exposure, Viewport};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};
use bevy_chisel::quadric::Scene;
use bevy_chisel::splat::{ChiselSplatPlugin, PropBounds, PropMaterial, PropSplats};

use crate::ONE_APP_AT_A_TIME;
use crate::common::pbr::{
    MAX_MEAN_BYTES, MAX_MEAN_RELATIVE, MAX_P99_BYTES, compare_mirrored, linear,
    spawn_comparison_lights_and_camera, sphere_splats,
};

const SIZE: u32 = 128;

/// The two cameras' EV100: one stop apart.
const EV100: [f32; 2] = [9.7, 10.7];

#[test]
fn one_stop_more_exposure_value_halves_the_shaded_colour() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let path = format!(
        "{}/assets/scenes/three_spheres.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = Scene::load(&path).expect("shipped scene");
    let centre = DVec3::new(0.0, 0.0, 10.0);
    let bounds = PropBounds {
        centre: centre.as_vec3(),
        radius: 75.0,
    };
    let splats = PropSplats::build(&scene, bounds, 2.5).expect("sampling");

    let config = HeadlessConfig {
        width: 2 * SIZE,
        height: SIZE,
        capture_frames: vec![8, 10],
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: "splat_exposure".into(),
        max_frames: 240,
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "exposure test");
    crate::common::hold_captures_until_pipelines_ready(&mut app);
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(ClearColor(Color::BLACK))
        .insert_resource(GlobalAmbientLight {
            brightness: 80.0,
            ..default()
        });
    let target = (centre.as_vec3() * 0.01).to_array();
    app.add_systems(Startup, move |mut commands: Commands| {
        let target = Vec3::from_array(target);
        let eye = target + Vec3::new(1.8, -2.4, 1.5) * 0.6;
        commands.spawn((splats.clone(), Transform::from_scale(Vec3::splat(0.01))));
        commands.spawn((
            DirectionalLight {
                illuminance: 1500.0,
                ..default()
            },
            Transform::from_translation(eye + Vec3::new(0.5, 0.0, 2.0)).looking_at(target, Vec3::Z),
        ));
        for (i, ev100) in (0_u32..).zip(EV100) {
            commands.spawn((
                Camera3d::default(),
                Camera {
                    clear_color: ClearColorConfig::Custom(Color::BLACK),
                    order: i as isize,
                    viewport: Some(Viewport {
                        physical_position: UVec2::new(i * SIZE, 0),
                        physical_size: UVec2::splat(SIZE),
                        ..default()
                    }),
                    ..default()
                },
                Exposure { ev100 },
                Tonemapping::None,
                DebandDither::Disabled,
                Msaa::Off,
                Transform::from_translation(eye).looking_at(target, Vec3::Z),
            ));
        }
    });
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    let image = frames.images().pop().expect("captured frames");
    let pixel = |x: u32, y: u32| {
        image
            .get_color_at(x, y)
            .expect("pixel inside the image")
            .to_srgba()
            .to_u8_array()
    };
    let (mut covered, mut compared, mut worst) = (0, 0, 0.0_f64);
    let mut ratios = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let (bright, dark) = (pixel(x, y), pixel(x + SIZE, y));
            let lit = |c: [u8; 4]| c[..3].iter().any(|&v| v > 3);
            assert_eq!(
                lit(bright),
                lit(dark),
                "({x}, {y}): both views cover the same pixels"
            );
            if !lit(bright) {
                continue;
            }
            covered += 1;
            // Channels away from quantization (dark) and clamping (bright).
            for ch in 0..3 {
                let (b, d) = (linear(bright[ch]), linear(dark[ch]));
                if (0.1..0.95).contains(&b) {
                    let ratio = d / b;
                    worst = worst.max((ratio - 0.5).abs());
                    ratios.push(ratio);
                    compared += 1;
                }
            }
        }
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "{covered} px covered, {compared} channels compared: median ratio {median:.4}, \
         worst deviation from 0.5 {worst:.4}"
    );
    assert!(covered > 1000, "the prop fills the views: {covered} px");
    assert!(compared > 1000, "enough channels in range: {compared}");
    // 8-bit sRGB steps are ≤ 1.2 % of a linear value above 0.05.
    assert!((median - 0.5).abs() < 0.005, "median ratio {median}");
    assert!(worst < 0.03, "worst ratio deviation {worst}");
}

/// The comparison's base colour (linear RGB), the scene file's.
const SPHERE_RGB: [f32; 3] = [0.8, 0.3, 0.2];

/// Size of the PBR comparison image.
const PBR_SIZE: (u32, u32) = (320, 256);

#[test]
fn a_prop_sphere_matches_a_standard_material_sphere() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let splats = sphere_splats();
    let (width, height) = PBR_SIZE;
    let config = HeadlessConfig {
        width,
        height,
        capture_frames: vec![8, 10],
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: "splat_pbr".into(),
        max_frames: 240,
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "pbr test");
    crate::common::hold_captures_until_pipelines_ready(&mut app);
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(ClearColor(Color::BLACK));
    // Top row: the default material; bottom row: a rough metal.
    let materials = [
        (1.25, PropMaterial::default()),
        (
            -1.25,
            PropMaterial {
                metallic: 0.8,
                perceptual_roughness: 0.3,
                ..default()
            },
        ),
    ];
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              mut meshes: ResMut<Assets<Mesh>>,
              mut standard: ResMut<Assets<StandardMaterial>>| {
            // Mirror symmetric about x = 0: the prop at −x, the mesh at +x,
            // the lights and the camera in the plane x = 0.
            let sphere = meshes.add(Sphere::new(1.0).mesh().ico(5).expect("ico sphere"));
            let [r, g, b] = SPHERE_RGB;
            for (z, material) in materials {
                commands.spawn((
                    splats.clone(),
                    material,
                    Transform::from_xyz(-1.5, 0.0, z).with_scale(Vec3::splat(0.02)),
                ));
                commands.spawn((
                    Mesh3d(sphere.clone()),
                    MeshMaterial3d(standard.add(StandardMaterial {
                        base_color: Color::linear_rgb(r, g, b),
                        metallic: material.metallic,
                        perceptual_roughness: material.perceptual_roughness,
                        reflectance: material.reflectance,
                        ..default()
                    })),
                    Transform::from_xyz(1.5, 0.0, z),
                ));
            }
            spawn_comparison_lights_and_camera(&mut commands);
        },
    );
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    let image = frames.images().pop().expect("captured frames");
    for (name, rows) in [("default", 0..height / 2), ("metal", height / 2..height)] {
        let d = compare_mirrored(&image, width, rows);
        let relative = d.mean_relative();
        println!(
            "{name}: {} px; mean linear colour prop {:.4?} mesh {:.4?} (relative {:.4?}); \
             per-pixel difference mean {:.3} B, 99th percentile {} B",
            d.pixels, d.means[0], d.means[1], relative, d.mean_bytes, d.p99_bytes
        );
        assert!(d.pixels > 2000, "{name}: the spheres fill the view: {d:?}");
        assert!(
            relative.iter().all(|&r| r < MAX_MEAN_RELATIVE),
            "{name}: mean colours differ: {d:?}"
        );
        assert!(d.mean_bytes < MAX_MEAN_BYTES, "{name}: {d:?}");
        assert!(d.p99_bytes <= MAX_P99_BYTES, "{name}: {d:?}");
    }
}
