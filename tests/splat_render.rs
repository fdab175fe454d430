//! The splat pass against the CPU reference ray tracer, headless on the
//! machine's Vulkan adapter (lavapipe in CI).
//!
//! Each SCENARIOS scene is sampled, drawn by the plugin with quadric ids as
//! colours, and compared pixel by pixel with `chisel_quadric::trace_image`
//! from the same camera: the primitive ids must agree on ≥ 99.5 % of the
//! pixels, and pixels where the reference sees the solid but the pass shows
//! background (holes) must stay ≤ 0.1 %. A cube mesh through a prop checks
//! depth compositing both ways.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU32, Ordering};

use bevy::camera::ClearColorConfig;
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};
use bevy_chisel::quadric::{Camera as RefCamera, NO_HIT, Scene, trace_image};
use bevy_chisel::splat::{
    ChiselSplatPlugin, PropBounds, PropSplats, SplatMode, SplatOutput, SplatSettings,
};

/// Bevy apps are run one at a time.
static ONE_APP_AT_A_TIME: Mutex<()> = Mutex::new(());
static SHOT: AtomicU32 = AtomicU32::new(0);

const SIZE: u32 = 256;
const FOV_DEGREES: f64 = 30.0;
/// World units per scene unit (millimetres to decimetres): exercises the
/// prop's `Transform`.
const SCALE: f32 = 0.01;

/// `(scene, bounding centre, bounding radius)` as in the sampling benchmark.
const SCENES: [(&str, [f64; 3], f64); 4] = [
    ("three_spheres", [0.0, 0.0, 10.0], 75.0),
    ("classic", [0.0, 0.0, 0.0], 90.0),
    ("sharp8", [0.0, 0.0, 0.0], 60.0),
    ("machine80", [0.0, 0.0, 35.0], 100.0),
];

fn load_scene(name: &str) -> Scene {
    let path = format!("{}/assets/scenes/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    Scene::load(&path).expect("shipped scene")
}

/// The eye of the comparison views, in scene units.
fn eye(centre: DVec3, radius: f64) -> DVec3 {
    centre + DVec3::new(1.8, -2.4, 1.5) * radius * 0.85
}

/// An extra mesh in the comparison scene.
#[derive(Clone, Copy)]
struct CubeMesh {
    centre: Vec3,
    half: f32,
}

const CUBE_RGB: [u8; 3] = [255, 0, 0];

/// Renders `splats` (scene units, scaled by `SCALE`) from `eye` towards
/// `centre`, returning the captured image.
fn render(
    splats: PropSplats,
    eye: DVec3,
    centre: DVec3,
    settings: SplatSettings,
    cube: Option<CubeMesh>,
) -> Image {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let config = HeadlessConfig {
        width: SIZE,
        height: SIZE,
        // The first frames may come before the pass is ready: compare a later
        // one, and check that the picture has settled.
        capture_frames: vec![8, 10],
        // CHISEL_TEST_SCREENSHOTS=dir keeps the images for inspection.
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: format!(
            "splat_render-{:?}-{}",
            settings.mode,
            SHOT.fetch_add(1, Ordering::Relaxed)
        ),
        max_frames: 60,
        // The pixels are checked one by one below.
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "splat test");
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(settings)
        .insert_resource(ClearColor(Color::BLACK));
    let eye = eye.as_vec3() * SCALE;
    let centre = centre.as_vec3() * SCALE;
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              mut meshes: ResMut<Assets<Mesh>>,
              mut materials: ResMut<Assets<StandardMaterial>>| {
            commands.spawn((splats.clone(), Transform::from_scale(Vec3::splat(SCALE))));
            commands.spawn((
                Camera3d::default(),
                Camera {
                    clear_color: ClearColorConfig::Custom(Color::BLACK),
                    ..default()
                },
                Projection::Perspective(PerspectiveProjection {
                    fov: (FOV_DEGREES as f32).to_radians(),
                    near: 0.01,
                    ..default()
                }),
                Tonemapping::None,
                DebandDither::Disabled,
                Msaa::Off,
                Transform::from_translation(eye).looking_at(centre, Vec3::Z),
            ));
            if let Some(cube) = cube {
                commands.spawn((
                    Mesh3d(meshes.add(Cuboid::from_length(2.0 * cube.half * SCALE))),
                    MeshMaterial3d(materials.add(StandardMaterial {
                        base_color: Color::srgb_u8(CUBE_RGB[0], CUBE_RGB[1], CUBE_RGB[2]),
                        unlit: true,
                        ..default()
                    })),
                    Transform::from_translation(cube.centre * SCALE),
                ));
            }
        },
    );
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    let mut images = frames.images();
    assert_eq!(images.len(), 2, "two captured frames");
    assert!(
        images[0].data == images[1].data,
        "frames 8 and 10 differ: the picture has not settled"
    );
    images.pop().expect("two captured frames")
}

/// What a pixel shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pixel {
    Background,
    Quadric(u32),
    Cube,
    Other([u8; 3]),
}

fn classify(image: &Image, x: u32, y: u32) -> Pixel {
    let c = image
        .get_color_at(x, y)
        .expect("pixel inside the image")
        .to_srgba()
        .to_u8_array();
    let near = |a: u8, b: u8| a.abs_diff(b) <= 3;
    if c[0] <= 3 && c[1] <= 3 && c[2] <= 3 {
        return Pixel::Background;
    }
    if near(c[0], CUBE_RGB[0]) && near(c[1], CUBE_RGB[1]) && near(c[2], CUBE_RGB[2]) {
        return Pixel::Cube;
    }
    let nibble = |v: u8| {
        let k = (i32::from(v) - 8 + 8).div_euclid(16);
        ((0..16).contains(&k) && (i32::from(v) - (16 * k + 8)).abs() <= 3).then_some(k as u32)
    };
    match (nibble(c[0]), nibble(c[1]), near(c[2], 200)) {
        (Some(lo), Some(hi), true) => Pixel::Quadric(lo + 16 * hi),
        _ => Pixel::Other([c[0], c[1], c[2]]),
    }
}

/// Agreement figures of one comparison.
#[derive(Debug, Default)]
struct Agreement {
    pixels: usize,
    agree: usize,
    holes: usize,
    covered: usize,
}

impl Agreement {
    fn agree_fraction(&self) -> f64 {
        self.agree as f64 / self.pixels as f64
    }
    fn hole_fraction(&self) -> f64 {
        self.holes as f64 / self.pixels as f64
    }
}

/// Slab test: the distance along the unit ray to the axis-aligned cube.
fn cube_distance(origin: DVec3, dir: DVec3, cube: CubeMesh) -> f64 {
    let c = cube.centre.as_dvec3();
    let h = f64::from(cube.half);
    let (mut t0, mut t1) = (0.0_f64, f64::INFINITY);
    for i in 0..3 {
        let (a, b) = (
            (c[i] - h - origin[i]) / dir[i],
            (c[i] + h - origin[i]) / dir[i],
        );
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    if t0 <= t1 { t0 } else { f64::INFINITY }
}

fn compare(
    name: &str,
    centre: DVec3,
    radius: f64,
    settings: SplatSettings,
    cube: Option<CubeMesh>,
) -> Agreement {
    let scene = load_scene(name);
    let dnf = scene.dnf().expect("normal form");
    let bounds = PropBounds {
        centre: centre.as_vec3(),
        radius: radius as f32,
    };
    let splats = PropSplats::build(&scene, bounds, (radius / 30.0) as f32).expect("sampling");
    let eye = eye(centre, radius);
    let camera = RefCamera::new(eye, centre, FOV_DEGREES, SIZE, SIZE).expect("camera");
    let reference = trace_image(&dnf, &camera);
    let image = render(splats, eye, centre, settings, cube);
    let mut a = Agreement::default();
    let mut others = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let i = (y * SIZE + x) as usize;
            let mut expected = match reference.quadric[i] {
                NO_HIT => Pixel::Background,
                q => Pixel::Quadric(q),
            };
            if let Some(cube) = cube {
                let ray = camera.ray(x, y);
                if cube_distance(ray.origin, ray.direction, cube) < reference.depth[i] {
                    expected = Pixel::Cube;
                }
            }
            let got = classify(&image, x, y);
            a.pixels += 1;
            a.covered += usize::from(expected != Pixel::Background);
            a.agree += usize::from(got == expected);
            a.holes += usize::from(expected != Pixel::Background && got == Pixel::Background);
            if let Pixel::Other(c) = got
                && others.len() < 5
            {
                others.push((x, y, c));
            }
        }
    }
    println!(
        "{name} ({:?}): {:.3} % agree, {:.3} % holes, {} covered px, unknown colours {others:?}",
        settings.mode,
        100.0 * a.agree_fraction(),
        100.0 * a.hole_fraction(),
        a.covered
    );
    a
}

fn id_settings(mode: SplatMode) -> SplatSettings {
    SplatSettings {
        mode,
        output: SplatOutput::QuadricIds,
        ..default()
    }
}

#[test]
fn splat_pass_matches_the_reference_tracer_on_every_scene() {
    let mut failures = Vec::new();
    for (name, centre, radius) in SCENES {
        let a = compare(
            name,
            DVec3::from(centre),
            radius,
            id_settings(SplatMode::SurfaceBoxes),
            None,
        );
        assert!(
            a.covered as f64 > 0.1 * a.pixels as f64,
            "{name}: the view misses the prop"
        );
        if a.agree_fraction() < 0.995 || a.hole_fraction() > 0.001 {
            failures.push(format!("{name}: {a:?}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn screen_quads_and_global_ray_tracing_match_the_reference_tracer() {
    let mut failures = Vec::new();
    for (name, centre, radius) in [SCENES[1], SCENES[2]] {
        for mode in [SplatMode::ScreenQuads, SplatMode::GlobalRayTrace] {
            let a = compare(name, DVec3::from(centre), radius, id_settings(mode), None);
            if a.agree_fraction() < 0.995 || a.hole_fraction() > 0.001 {
                failures.push(format!("{name} {mode:?}: {a:?}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_cube_mesh_and_a_prop_occlude_each_other() {
    // A cube through the lens of three_spheres: parts of it in front of the
    // spheres, parts hidden inside and behind them.
    let (name, centre, radius) = SCENES[0];
    let cube = CubeMesh {
        centre: Vec3::new(10.0, -30.0, 20.0),
        half: 22.0,
    };
    let a = compare(
        name,
        DVec3::from(centre),
        radius,
        id_settings(SplatMode::SurfaceBoxes),
        Some(cube),
    );
    assert!(
        a.agree_fraction() >= 0.995 && a.hole_fraction() <= 0.001,
        "{a:?}"
    );
}
