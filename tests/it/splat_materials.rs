//! Per-quadric metallic and roughness from the scene file reach the
//! shading: one prop of two spheres, a smooth metal one above and a rough
//! dielectric one below, each matches a `StandardMaterial` sphere mesh of
//! the same base colour, metallic and roughness, side by side under a
//! directional and a point light (the comparison of `splat_exposure.rs`,
//! with its tolerances). The prop's own `PropMaterial` (roughness 0.5,
//! metallic 0) is what a sphere without the fields takes: the same prop
//! with the fields left out fails both comparisons by a clear margin.
//!
//! Headless on the machine's Vulkan adapter (lavapipe in CI).

use bevy::prelude::*;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};
use bevy_chisel::quadric::Scene;
use bevy_chisel::splat::{ChiselSplatPlugin, PropBounds, PropMaterial, PropSplats};

use crate::ONE_APP_AT_A_TIME;
use crate::common::pbr::{
    MAX_MEAN_BYTES, MAX_MEAN_RELATIVE, MAX_P99_BYTES, SphereDifference, compare_mirrored,
    spawn_comparison_lights_and_camera,
};

/// Two spheres of radius 50, 125 apart along z (scene units), each with
/// its own surface; `{top}` and `{bottom}` are replaced by the fields.
const TWO_SPHERES: &str = "Scene(
    primitives: [
        (name: \"smooth\", shape: Sphere(center: (0, 0, 62.5), radius: 50),
         color: (0.8, 0.3, 0.2){top}),
        (name: \"rough\", shape: Sphere(center: (0, 0, -62.5), radius: 50),
         color: (0.8, 0.3, 0.2){bottom}),
    ],
    root: Union([Ref(\"smooth\"), Ref(\"rough\")]),
    bounds: (0, 0, 0, 130),
)";

/// Metallic and perceptual roughness of the two spheres (top, bottom).
const SURFACES: [(f32, f32); 2] = [(0.9, 0.3), (0.0, 0.9)];

const SIZE: (u32, u32) = (320, 256);

/// Renders the prop (at x = −1.5) beside the two meshes (at x = +1.5) and
/// compares each row.
fn render_rows(scene_text: &str, stem: &str) -> [SphereDifference; 2] {
    let scene = Scene::from_ron(scene_text).expect("two spheres");
    let bounds = PropBounds {
        centre: Vec3::ZERO,
        radius: 130.0,
    };
    let splats = PropSplats::build(&scene, bounds, 2.0).expect("sampling");
    let (width, height) = SIZE;
    let config = HeadlessConfig {
        width,
        height,
        capture_frames: vec![8, 10],
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: stem.into(),
        max_frames: 240,
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "materials test");
    crate::common::hold_captures_until_pipelines_ready(&mut app);
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(ClearColor(Color::BLACK));
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              mut meshes: ResMut<Assets<Mesh>>,
              mut standard: ResMut<Assets<StandardMaterial>>| {
            // The prop's own material: StandardMaterial's default.
            commands.spawn((
                splats.clone(),
                PropMaterial::default(),
                Transform::from_xyz(-1.5, 0.0, 0.0).with_scale(Vec3::splat(0.02)),
            ));
            let sphere = meshes.add(Sphere::new(1.0).mesh().ico(5).expect("ico sphere"));
            for (z, (metallic, perceptual_roughness)) in [1.25, -1.25].into_iter().zip(SURFACES) {
                commands.spawn((
                    Mesh3d(sphere.clone()),
                    MeshMaterial3d(standard.add(StandardMaterial {
                        base_color: Color::linear_rgb(0.8, 0.3, 0.2),
                        metallic,
                        perceptual_roughness,
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
    [0..height / 2, height / 2..height].map(|rows| compare_mirrored(&image, width, rows))
}

/// Largest relative difference of the mean linear colours.
fn mean_relative(d: &SphereDifference) -> f64 {
    d.mean_relative().into_iter().fold(0.0, f64::max)
}

#[test]
fn each_quadric_is_shaded_with_its_own_metallic_and_roughness() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let field = |(metallic, roughness): (f32, f32)| {
        format!(", metallic: {metallic}, roughness: {roughness}")
    };
    let with_fields = TWO_SPHERES
        .replace("{top}", &field(SURFACES[0]))
        .replace("{bottom}", &field(SURFACES[1]));
    let rows = render_rows(&with_fields, "splat_materials");
    for (name, d) in ["smooth metal", "rough"].iter().zip(&rows) {
        println!(
            "{name}: {} px; mean linear colour prop {:.4?} mesh {:.4?} (largest relative \
             difference {:.4}); per-pixel difference mean {:.3} B, 99th percentile {} B",
            d.pixels,
            d.means[0],
            d.means[1],
            mean_relative(d),
            d.mean_bytes,
            d.p99_bytes
        );
        assert!(d.pixels > 2000, "{name}: the spheres fill the view: {d:?}");
        assert!(
            mean_relative(d) < MAX_MEAN_RELATIVE,
            "{name}: mean colours differ: {d:?}"
        );
        assert!(d.mean_bytes < MAX_MEAN_BYTES, "{name}: {d:?}");
        assert!(d.p99_bytes <= MAX_P99_BYTES, "{name}: {d:?}");
    }

    // Without the fields both spheres take the prop's material and match
    // neither mesh, by a clear margin: the comparison tells these surfaces
    // apart. (Measured with lavapipe: rough row 4.6 B mean, 15 B at the
    // 99th percentile; smooth metal row 60 B mean.)
    let without = TWO_SPHERES.replace("{top}", "").replace("{bottom}", "");
    let rows = render_rows(&without, "splat_materials_prop");
    for (name, d) in ["smooth metal", "rough"].iter().zip(&rows) {
        println!(
            "{name}, prop's material: largest relative difference {:.4}, per-pixel \
             difference mean {:.3} B, 99th percentile {} B",
            mean_relative(d),
            d.mean_bytes,
            d.p99_bytes
        );
        assert!(
            d.mean_bytes > 2.0 * MAX_MEAN_BYTES && d.p99_bytes > 2 * MAX_P99_BYTES,
            "{name}: the prop's material looks like the mesh's: {d:?}"
        );
    }
}
