//! Shared by the headless splat tests: the benchmark scenes and their
//! comparison views, a headless render of one prop seen by several cameras
//! side by side, and the comparison of a capture with the CPU reference
//! tracer (`chisel_quadric::trace_image`) on quadric ids and on normals.
//!
//! Thresholds of every comparison (the splat-pass acceptance criteria):
//! ids agree on ≥ 99.5 % of the pixels, holes (reference solid, capture
//! background) ≤ 0.1 %.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use bevy::camera::{ClearColorConfig, Viewport};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy::render::render_resource::PipelineCache;
use bevy::render::{Render, RenderApp, RenderSystems};
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::quadric::{Camera as RefCamera, NO_HIT, Scene, TraceImage, trace_image};
use bevy_chisel::splat::{
    ChiselSplatPlugin, PropBounds, PropSplats, SplatMode, SplatOutput, SplatSettings,
    SplatViewSettings,
};

use crate::ONE_APP_AT_A_TIME;

pub mod pbr;
mod scenes;
pub use scenes::{FOV_DEGREES, SCALE, SCENES, eye, load_scene};

/// Set by the render world while its pipeline cache still waits on a
/// pipeline (a shader, or one of Bevy's shader libraries it imports, still
/// loading).
#[derive(Resource, Clone, Default)]
struct PipelinesWaiting(Arc<AtomicBool>);

/// Holds the headless captures while any render pipeline is still waiting,
/// so that a capture never shows a frame whose passes were skipped for want
/// of a compiled pipeline. Bevy loads its shader libraries through the asset
/// server, off the main thread, so how many frames that takes depends on
/// what else the process is doing (the other tests of this binary).
pub fn hold_captures_until_pipelines_ready(app: &mut App) {
    let waiting = PipelinesWaiting::default();
    app.insert_resource(waiting.clone())
        .insert_resource(HoldCaptures(false))
        .add_systems(
            Update,
            |waiting: Res<PipelinesWaiting>, mut hold: ResMut<HoldCaptures>| {
                hold.0 = waiting.0.load(Ordering::Relaxed);
            },
        );
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app.insert_resource(waiting).add_systems(
            Render,
            (|cache: Res<PipelineCache>, waiting: Res<PipelinesWaiting>| {
                let busy = cache.waiting_pipelines().next().is_some();
                waiting.0.store(busy, Ordering::Relaxed);
            })
            .in_set(RenderSystems::Cleanup),
        );
    }
}

/// Captures taken so far, numbering the screenshot files.
static SHOT: AtomicU32 = AtomicU32::new(0);

/// The file name, without its extension, of the test file that called the
/// `#[track_caller]` functions leading here.
#[track_caller]
fn caller_file_stem() -> String {
    std::path::Path::new(std::panic::Location::caller().file())
        .file_stem()
        .map_or_else(|| "splat".into(), |s| s.to_string_lossy().into_owned())
}

/// Smallest fraction of agreeing pixels.
pub const MIN_AGREE: f64 = 0.995;
/// Largest fraction of holes.
pub const MAX_HOLES: f64 = 0.001;

/// The entry of [`SCENES`] named `name`.
pub fn scene_entry(name: &str) -> (&'static str, DVec3, f64) {
    let (name, centre, radius) = SCENES
        .into_iter()
        .find(|(n, _, _)| *n == name)
        .expect("one of the benchmark scenes");
    (name, DVec3::from(centre), radius)
}

/// The splats of `name` sampled as the tests sample them (splat radius a
/// thirtieth of the bounding radius).
pub fn scene_splats(scene: &Scene, centre: DVec3, radius: f64) -> PropSplats {
    let bounds = PropBounds {
        centre: centre.as_vec3(),
        radius: radius as f32,
    };
    PropSplats::build(scene, bounds, (radius / 30.0) as f32).expect("sampling")
}

/// The reference ids and normals of `scene` from `eye` towards `centre`
/// (scene units), `size`² pixels.
pub fn reference(scene: &Scene, eye: DVec3, centre: DVec3, size: u32) -> TraceImage {
    let dnf = scene.dnf().expect("normal form");
    let camera = RefCamera::new(eye, centre, FOV_DEGREES, size, size).expect("camera");
    trace_image(&dnf, &camera)
}

/// Settings that draw quadric ids in `mode`.
pub fn id_settings(mode: SplatMode) -> SplatSettings {
    SplatSettings {
        mode,
        output: SplatOutput::QuadricIds,
        ..default()
    }
}

/// One camera of a headless render.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Eye in world units.
    pub eye: Vec3,
    /// The point looked at, in world units.
    pub centre: Vec3,
    /// The camera's own settings, if any.
    pub settings: Option<SplatViewSettings>,
    /// The camera's multisampling.
    pub msaa: Msaa,
}

/// An unlit, axis-aligned cube mesh drawn beside the prop (world units),
/// to check depth compositing with ordinary meshes.
#[derive(Clone, Copy, Debug)]
pub struct UnlitCube {
    /// Centre in world units.
    pub centre: Vec3,
    /// Half the edge in world units.
    pub half: f32,
    /// Its colour (sRGB), unlike any quadric id or the background.
    pub rgb: [u8; 3],
}

/// Renders one prop (`splats` placed by `transform`) with the
/// [`SplatSettings`] resource `settings`, seen by each of `views` in a
/// `size`² viewport of its own, left to right in one image
/// (`size · views.len()` wide); returns the captured image.
#[track_caller]
pub fn render_views(
    splats: PropSplats,
    transform: Transform,
    settings: SplatSettings,
    views: &[View],
    size: u32,
) -> Image {
    render_views_with(splats, transform, settings, views, size, None)
}

/// [`render_views`] with an optional [`UnlitCube`] in the scene. The
/// capture's file stem starts with the calling test file's name.
#[track_caller]
pub fn render_views_with(
    splats: PropSplats,
    transform: Transform,
    settings: SplatSettings,
    views: &[View],
    size: u32,
    cube: Option<UnlitCube>,
) -> Image {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let count = u32::try_from(views.len()).expect("a few views");
    let config = HeadlessConfig {
        width: size * count,
        height: size,
        // The first frames may come before the pass is ready: compare a later
        // one, and check that the picture has settled.
        capture_frames: vec![8, 10],
        // CHISEL_TEST_SCREENSHOTS=dir keeps the images for inspection.
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: format!(
            "{}-{:?}-{}",
            caller_file_stem(),
            settings.mode,
            SHOT.fetch_add(1, Ordering::Relaxed)
        ),
        max_frames: 240,
        // The pixels are checked one by one.
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "splat test");
    hold_captures_until_pipelines_ready(&mut app);
    app.add_plugins(ChiselSplatPlugin)
        .insert_resource(settings)
        .insert_resource(ClearColor(Color::BLACK));
    let views = views.to_vec();
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              mut meshes: ResMut<Assets<Mesh>>,
              mut materials: ResMut<Assets<StandardMaterial>>| {
            commands.spawn((splats.clone(), transform));
            for (i, view) in (0_u32..).zip(&views) {
                let mut camera = commands.spawn((
                    Camera3d::default(),
                    Camera {
                        clear_color: ClearColorConfig::Custom(Color::BLACK),
                        order: i as isize,
                        viewport: Some(Viewport {
                            physical_position: UVec2::new(i * size, 0),
                            physical_size: UVec2::splat(size),
                            ..default()
                        }),
                        ..default()
                    },
                    Projection::Perspective(PerspectiveProjection {
                        fov: (FOV_DEGREES as f32).to_radians(),
                        near: 0.01,
                        ..default()
                    }),
                    Tonemapping::None,
                    DebandDither::Disabled,
                    view.msaa,
                    Transform::from_translation(view.eye).looking_at(view.centre, Vec3::Z),
                ));
                if let Some(own) = view.settings {
                    camera.insert(own);
                }
            }
            if let Some(cube) = cube {
                let [r, g, b] = cube.rgb;
                commands.spawn((
                    Mesh3d(meshes.add(Cuboid::from_length(2.0 * cube.half))),
                    MeshMaterial3d(materials.add(StandardMaterial {
                        base_color: Color::srgb_u8(r, g, b),
                        unlit: true,
                        ..default()
                    })),
                    Transform::from_translation(cube.centre),
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

/// What a pixel of a quadric-id capture shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixel {
    /// The clear colour.
    Background,
    /// The quadric of this index.
    Quadric(u32),
    /// No id colour.
    Other([u8; 3]),
}

fn bytes(image: &Image, x: u32, y: u32) -> [u8; 4] {
    image
        .get_color_at(x, y)
        .expect("pixel inside the image")
        .to_srgba()
        .to_u8_array()
}

fn is_background(c: [u8; 4]) -> bool {
    c[0] <= 3 && c[1] <= 3 && c[2] <= 3
}

/// Decodes a pixel of [`SplatOutput::QuadricIds`].
pub fn classify(image: &Image, x: u32, y: u32) -> Pixel {
    let c = bytes(image, x, y);
    if is_background(c) {
        return Pixel::Background;
    }
    let near = |a: u8, b: u8| a.abs_diff(b) <= 3;
    let nibble = |v: u8| {
        let k = (i32::from(v) - 8 + 8).div_euclid(16);
        ((0..16).contains(&k) && (i32::from(v) - (16 * k + 8)).abs() <= 3).then_some(k as u32)
    };
    match (nibble(c[0]), nibble(c[1]), near(c[2], 200)) {
        (Some(lo), Some(hi), true) => Pixel::Quadric(lo + 16 * hi),
        _ => Pixel::Other([c[0], c[1], c[2]]),
    }
}

/// Decodes a pixel of [`SplatOutput::Normals`] (`n · 0.5 + 0.5`, linear,
/// in an sRGB target): `None` for background.
pub fn normal_at(image: &Image, x: u32, y: u32) -> Option<Vec3> {
    if is_background(bytes(image, x, y)) {
        return None;
    }
    let c = image.get_color_at(x, y).ok()?.to_linear();
    Some(Vec3::new(c.red, c.green, c.blue) * 2.0 - 1.0)
}

/// Agreement figures of one comparison.
#[derive(Debug, Default)]
pub struct Agreement {
    /// Pixels compared.
    pub pixels: usize,
    /// Pixels showing what the reference shows.
    pub agree: usize,
    /// Pixels where the reference sees the solid and the capture shows
    /// background.
    pub holes: usize,
    /// Pixels where the reference sees the solid.
    pub covered: usize,
}

impl Agreement {
    /// Agreeing pixels over all pixels.
    pub fn agree_fraction(&self) -> f64 {
        self.agree as f64 / self.pixels as f64
    }

    /// Holes over all pixels.
    pub fn hole_fraction(&self) -> f64 {
        self.holes as f64 / self.pixels as f64
    }

    /// Within the acceptance thresholds, and the view sees the prop.
    pub fn passes(&self) -> bool {
        self.covered as f64 > 0.1 * self.pixels as f64
            && self.agree_fraction() >= MIN_AGREE
            && self.hole_fraction() <= MAX_HOLES
    }
}

/// Where a capture's pixel is found in the reference: the viewport's left
/// edge in the capture, and whether the view is the reference's mirror
/// image (left and right swapped).
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    /// First column of the viewport in the capture.
    pub x_offset: u32,
    /// The capture shows the mirror image of the reference.
    pub mirrored: bool,
}

/// Compares the `reference.width`² viewport of `image` at `at` with the
/// reference: `same(reference index, capture x, capture y)` tells whether a
/// covered pixel shows the same thing; `background(x, y)` whether the
/// capture shows background there.
fn compare(
    reference: &TraceImage,
    at: Placement,
    mut same: impl FnMut(usize, u32, u32) -> bool,
    background: impl Fn(u32, u32) -> bool,
) -> Agreement {
    let size = reference.width;
    let mut a = Agreement::default();
    for y in 0..size {
        for x in 0..size {
            let rx = if at.mirrored { size - 1 - x } else { x };
            let i = (y * size + rx) as usize;
            let (cx, empty) = (at.x_offset + x, background(at.x_offset + x, y));
            let covered = reference.quadric[i] != NO_HIT;
            a.pixels += 1;
            a.covered += usize::from(covered);
            a.holes += usize::from(covered && empty);
            a.agree += usize::from(if covered {
                !empty && same(i, cx, y)
            } else {
                empty
            });
        }
    }
    a
}

/// Compares the quadric ids of a viewport with the reference.
pub fn compare_ids(reference: &TraceImage, image: &Image, at: Placement) -> Agreement {
    compare(
        reference,
        at,
        |i, x, y| classify(image, x, y) == Pixel::Quadric(reference.quadric[i]),
        |x, y| classify(image, x, y) == Pixel::Background,
    )
}

/// Compares the normals of a viewport with the reference (within about
/// 8°; mirrored: the reference normal mirrored by `x → −x`).
pub fn compare_normals(reference: &TraceImage, image: &Image, at: Placement) -> Agreement {
    compare(
        reference,
        at,
        |i, x, y| {
            let mut expected = reference.normal[i].as_vec3();
            if at.mirrored {
                expected.x = -expected.x;
            }
            normal_at(image, x, y).is_some_and(|n| n.normalize_or_zero().dot(expected) >= 0.99)
        },
        |x, y| normal_at(image, x, y).is_none(),
    )
}
