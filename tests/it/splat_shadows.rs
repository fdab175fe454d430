//! Props cast shadows into Bevy's shadow maps, with their true silhouette:
//!
//! - a prop sphere above a plane lit by a directional light with shadows
//!   darkens the plane under it by a clear margin, and with
//!   `NotShadowCaster` it does not;
//! - its shadow has the footprint of a `StandardMaterial` sphere's of the
//!   same size, beside it in the same light;
//! - the same holds for a point light's shadow (the six cube-face shadow
//!   maps, drawn by the shared shadow pass).
//!
//! The scene is mirror symmetric about x = 0: the prop sphere at −x, the
//! mesh sphere at +x, the light and the camera in the plane x = 0, the
//! camera straight above the plane (so plane pixels map to plane points by
//! one scale). Both spheres are on render layer 1, which the light shares
//! and the camera does not: the image shows only the plane and the two
//! shadows, so every pixel darker than half the lit plane is shadow.
//!
//! Headless on the machine's Vulkan adapter (lavapipe in CI).

use bevy::camera::visibility::RenderLayers;
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::light::{CascadeShadowConfigBuilder, NotShadowCaster};
use bevy::prelude::*;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};
use bevy_chisel::splat::ChiselSplatPlugin;

use crate::ONE_APP_AT_A_TIME;
use crate::common::pbr::{linear, sphere_splats};

/// Image size: the plane from x = −5 to 5, y = −2.5 to 2.5 or so.
const SIZE: (u32, u32) = (512, 256);
/// Sphere radius (world units) and the scale from scene units.
const RADIUS: f32 = 0.6;
/// Sphere centres: (±X, 0, HEIGHT).
const X: f32 = 2.0;
const HEIGHT: f32 = 1.2;
/// Where the light comes from (the light looks from here at the origin).
const LIGHT_FROM: Vec3 = Vec3::new(0.0, 1.0, 2.0);
/// Camera height, straight above the origin.
const CAMERA_HEIGHT: f32 = 6.0;

/// Where the point light of the point-light test is.
const POINT_LIGHT_AT: Vec3 = Vec3::new(0.0, 1.0, 3.5);

/// The light of a render.
#[derive(Clone, Copy, Debug)]
enum Light {
    /// Directional, from [`LIGHT_FROM`], one cascade.
    Directional,
    /// A point light at [`POINT_LIGHT_AT`] (a cube of six shadow maps).
    Point,
}

/// Renders the plane, the two spheres and their shadows in `light`; the
/// prop sphere (`casters[0]`) and the mesh sphere (`casters[1]`) with
/// `NotShadowCaster` where false.
fn render(light: Light, casters: [bool; 2]) -> Image {
    let splats = sphere_splats();
    let (width, height) = SIZE;
    let config = HeadlessConfig {
        width,
        height,
        capture_frames: vec![8, 10],
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: format!(
            "splat_shadows_{light:?}_{}_{}",
            u8::from(casters[0]),
            u8::from(casters[1])
        ),
        max_frames: 240,
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "shadow test");
    crate::common::hold_captures_until_pipelines_ready(&mut app);
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(ClearColor(Color::BLACK))
        .insert_resource(GlobalAmbientLight {
            brightness: 150.0,
            ..default()
        });
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              mut meshes: ResMut<Assets<Mesh>>,
              mut standard: ResMut<Assets<StandardMaterial>>| {
            let layer = RenderLayers::layer(1);
            let prop = commands
                .spawn((
                    splats.clone(),
                    Transform::from_xyz(-X, 0.0, HEIGHT).with_scale(Vec3::splat(RADIUS / 50.0)),
                    layer.clone(),
                ))
                .id();
            let mesh = commands
                .spawn((
                    Mesh3d(meshes.add(Sphere::new(RADIUS).mesh().ico(30).expect("ico sphere"))),
                    MeshMaterial3d(
                        standard.add(StandardMaterial::from(Color::linear_rgb(0.8, 0.3, 0.2))),
                    ),
                    Transform::from_xyz(X, 0.0, HEIGHT),
                    layer,
                ))
                .id();
            for (entity, casts) in [prop, mesh].into_iter().zip(casters) {
                if !casts {
                    commands.entity(entity).insert(NotShadowCaster);
                }
            }
            commands.spawn((
                Mesh3d(meshes.add(Plane3d::new(Vec3::Z, Vec2::new(6.0, 3.0)))),
                MeshMaterial3d(standard.add(StandardMaterial {
                    base_color: Color::linear_rgb(0.6, 0.6, 0.6),
                    perceptual_roughness: 1.0,
                    ..default()
                })),
            ));
            let light_layers = RenderLayers::from_layers(&[0, 1]);
            match light {
                Light::Directional => {
                    commands.spawn((
                        DirectionalLight {
                            illuminance: 3000.0,
                            shadow_maps_enabled: true,
                            ..default()
                        },
                        // One cascade over everything the camera sees: one
                        // shadow map resolution for both spheres.
                        CascadeShadowConfigBuilder {
                            num_cascades: 1,
                            minimum_distance: 0.1,
                            maximum_distance: 12.0,
                            ..default()
                        }
                        .build(),
                        Transform::from_translation(LIGHT_FROM).looking_at(Vec3::ZERO, Vec3::Z),
                        light_layers,
                    ));
                }
                Light::Point => {
                    commands.spawn((
                        PointLight {
                            intensity: 300_000.0,
                            range: 30.0,
                            shadow_maps_enabled: true,
                            ..default()
                        },
                        Transform::from_translation(POINT_LIGHT_AT),
                        light_layers,
                    ));
                }
            }
            commands.spawn((
                Camera3d::default(),
                Tonemapping::None,
                DebandDither::Disabled,
                Msaa::Off,
                Transform::from_xyz(0.0, 0.0, CAMERA_HEIGHT).looking_at(Vec3::ZERO, Vec3::Y),
            ));
        },
    );
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    frames.images().pop().expect("captured frames")
}

/// Linear luminance of every pixel, row by row.
fn luminance(image: &Image) -> Vec<f64> {
    let (width, height) = SIZE;
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let c = image
                .get_color_at(x, y)
                .expect("pixel inside the image")
                .to_srgba()
                .to_u8_array();
            out.push(0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2]));
        }
    }
    out
}

/// The pixel of the plane point (x, y, 0): the camera looks straight down
/// with +y up in the image, so the map is one scale about the centre.
fn pixel_of(x: f32, y: f32) -> (u32, u32) {
    let (width, height) = SIZE;
    let per_unit = pixels_per_unit();
    (
        (width as f32 / 2.0 + x * per_unit).round() as u32,
        (height as f32 / 2.0 - y * per_unit).round() as u32,
    )
}

/// Pixels per world unit on the plane (the camera's vertical field of
/// view is Bevy's default, π/4).
fn pixels_per_unit() -> f32 {
    let half_height = CAMERA_HEIGHT * (std::f32::consts::FRAC_PI_4 / 2.0).tan();
    SIZE.1 as f32 / 2.0 / half_height
}

/// The shadow of the sphere at (x, 0, HEIGHT)'s centre on the plane.
fn shadow_centre(x: f32) -> (u32, u32) {
    let to_light = LIGHT_FROM.normalize();
    let t = HEIGHT / to_light.z;
    pixel_of(x - t * to_light.x, -t * to_light.y)
}

/// Mean of `lum` over the disc of radius `r` pixels around `at`.
fn disc_mean(lum: &[f64], at: (u32, u32), r: i64) -> f64 {
    let (width, _) = SIZE;
    let (mut sum, mut n) = (0.0, 0.0);
    for dy in -r..=r {
        for dx in -r..=r {
            if dx * dx + dy * dy <= r * r {
                let (x, y) = (i64::from(at.0) + dx, i64::from(at.1) + dy);
                sum += lum[(y * i64::from(width) + x) as usize];
                n += 1.0;
            }
        }
    }
    sum / n
}

/// What one render shows of the two shadows.
#[derive(Debug)]
struct Shadows {
    /// Mean luminance of the lit plane, in a disc far from both shadows.
    lit: f64,
    /// Mean luminance in a disc around each shadow's expected centre
    /// (prop, mesh).
    core: [f64; 2],
    /// Pixels darker than half the lit plane in each half (prop, mesh).
    shadowed: [usize; 2],
    /// Pixels of the left half shadowed where their mirror image in the
    /// right half is not, or the other way round.
    mismatched: usize,
}

fn measure(image: &Image) -> Shadows {
    let (width, height) = SIZE;
    let lum = luminance(image);
    let lit = disc_mean(&lum, pixel_of(0.0, 1.5), 10);
    let core = [-X, X].map(|x| disc_mean(&lum, shadow_centre(x), 8));
    let dark = |x: u32, y: u32| lum[(y * width + x) as usize] < 0.5 * lit;
    let (mut shadowed, mut mismatched) = ([0, 0], 0);
    for y in 0..height {
        for x in 0..width {
            if dark(x, y) {
                shadowed[usize::from(x >= width / 2)] += 1;
            }
            if x < width / 2 && dark(x, y) != dark(width - 1 - x, y) {
                mismatched += 1;
            }
        }
    }
    Shadows {
        lit,
        core,
        shadowed,
        mismatched,
    }
}

#[test]
fn a_prop_casts_the_shadow_of_a_mesh_of_its_shape_unless_told_not_to() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let casting = measure(&render(Light::Directional, [true, true]));
    let silent = measure(&render(Light::Directional, [false, true]));
    println!("prop casting: {casting:?}\nprop with NotShadowCaster: {silent:?}");

    // The mesh's shadow is there in both renders, and the image is lit.
    assert!(casting.lit > 0.2, "the plane is lit: {casting:?}");
    for s in [&casting, &silent] {
        assert!(s.core[1] < 0.3 * s.lit, "the mesh casts: {s:?}");
        assert!(s.shadowed[1] > 3000, "the mesh's shadow is large: {s:?}");
    }
    // The prop casts: its shadow's core is as dark as the mesh's...
    assert!(
        casting.core[0] < 0.3 * casting.lit,
        "the plane under the prop is darker by a clear margin: {casting:?}"
    );
    assert!((casting.core[0] - casting.core[1]).abs() < 0.02 * casting.lit);
    // ...and its footprint is the mesh's, pixel for pixel, and the
    // ellipse a sphere's shadow is.
    let [prop, mesh] = casting.shadowed.map(|n| n as f64);
    let relative = (prop - mesh).abs() / mesh;
    let ellipse = std::f64::consts::PI * f64::from(RADIUS) * f64::from(RADIUS)
        / f64::from(LIGHT_FROM.normalize().z)
        * f64::from(pixels_per_unit()).powi(2);
    let to_ellipse = (prop - ellipse).abs() / ellipse;
    let mismatched = casting.mismatched as f64 / mesh;
    println!(
        "shadow footprints: prop {prop} px, mesh {mesh} px (relative difference {relative:.4}), \
         ellipse {ellipse:.0} px (prop off by {to_ellipse:.4}); {} px mismatched ({mismatched:.4})",
        casting.mismatched
    );
    assert!(
        relative < MAX_FOOTPRINT_RELATIVE,
        "footprints differ by {relative}: {casting:?}"
    );
    assert!(
        to_ellipse < MAX_FOOTPRINT_RELATIVE,
        "the prop's shadow is {to_ellipse} off the ellipse"
    );
    assert!(
        mismatched < MAX_FOOTPRINT_RELATIVE,
        "the footprints differ in shape: {casting:?}"
    );
    // With NotShadowCaster the plane under the prop is lit, the rest as
    // before.
    assert!(
        silent.core[0] > 0.95 * silent.lit,
        "no shadow without a caster: {silent:?}"
    );
    assert_eq!(silent.shadowed[0], 0, "no shadow pixels: {silent:?}");
    assert_eq!(silent.shadowed[1], casting.shadowed[1]);
}

/// Largest relative difference of the prop's shadow footprint (pixels
/// darker than half the lit plane) from the mesh's and from the ellipse,
/// and largest share of mirror pixels in one shadow and not the other.
/// The shadow's boundary is about 210 px long; one pixel of disagreement
/// all round it would be 6 % of its 3350 px. Half the lit plane is where
/// the filtered shadow edge crosses the silhouette, so the two shadows
/// agree to a fraction of a shadow-map texel (under half a pixel here),
/// and the ico sphere (30 subdivisions) lies within 0.02 % of the sphere.
/// Measured with lavapipe: prop 3343 px, mesh 3341 px, ellipse 3354 px,
/// 2 px mismatched.
const MAX_FOOTPRINT_RELATIVE: f64 = 0.02;

/// From a point light (its six shadow maps drawn by the shared shadow
/// pass), the prop's shadow is the mesh's mirror image too. The light
/// falls off across the plane, so a pixel counts as shadowed where it is
/// darker than half its own brightness in a render without casters.
#[test]
fn a_prop_casts_the_shadow_of_a_mesh_of_its_shape_from_a_point_light() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let casting = luminance(&render(Light::Point, [true, true]));
    let reference = luminance(&render(Light::Point, [false, false]));
    let (width, height) = SIZE;
    let dark = |x: u32, y: u32| {
        let i = (y * width + x) as usize;
        casting[i] < 0.5 * reference[i]
    };
    let (mut shadowed, mut mismatched) = ([0_usize; 2], 0_usize);
    for y in 0..height {
        for x in 0..width {
            if dark(x, y) {
                shadowed[usize::from(x >= width / 2)] += 1;
            }
            if x < width / 2 && dark(x, y) != dark(width - 1 - x, y) {
                mismatched += 1;
            }
        }
    }
    // The shadow of each sphere's centre: the point light projects it.
    let centre = |x: f32| {
        let c = Vec3::new(x, 0.0, HEIGHT);
        let s = POINT_LIGHT_AT.z / (POINT_LIGHT_AT.z - c.z);
        let on_plane = POINT_LIGHT_AT + s * (c - POINT_LIGHT_AT);
        pixel_of(on_plane.x, on_plane.y)
    };
    let core =
        [-X, X].map(|x| disc_mean(&casting, centre(x), 8) / disc_mean(&reference, centre(x), 8));
    let [prop, mesh] = shadowed.map(|n| n as f64);
    let relative = (prop - mesh).abs() / mesh;
    println!(
        "point light: shadow footprints prop {prop} px, mesh {mesh} px (relative difference \
         {relative:.4}), {mismatched} px mismatched; core brightness over unshadowed {core:.3?}"
    );
    assert!(mesh > 2000.0, "the mesh casts a large shadow: {mesh} px");
    assert!(
        core.iter().all(|&c| c < 0.3),
        "both cores are dark: {core:?}"
    );
    assert!(
        relative < MAX_FOOTPRINT_RELATIVE,
        "footprints differ by {relative}"
    );
    assert!(
        (mismatched as f64) < MAX_FOOTPRINT_RELATIVE * mesh,
        "the footprints differ in shape: {mismatched} px"
    );
}
