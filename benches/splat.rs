//! Paper 2, §7: the splat pass against the global ray-tracing pass of the
//! same prop and camera, at 1920×1080 on this machine's Vulkan adapter
//! (lavapipe where there is no GPU), and the splat pass's overdraw.
//! Run (the global pass takes seconds per frame on a CPU driver)
//!
//! `WGPU_BACKEND=vulkan cargo bench -p bevy_chisel --all-features --bench splat`
//!
//! It prints the figures of each scene, two Markdown tables, then one JSON
//! line of the figures. `cargo test` runs this binary without `--bench`:
//! it then measures nothing (see `support`).
//!
//! Per benchmark scene (`assets/scenes/`), one app renders the prop alone (from the view of
//! `tests/it/splat_render.rs`, whose scenes and eye `tests/it/common/scenes.rs`
//! gives both: the bounding sphere fills the image height)
//! through a sequence of steps, in turn, in the same run:
//!
//! - time: surface-aligned boxes, screen quads, global ray tracing and an
//!   empty frame (prop hidden), in `ROUNDS` interleaved rounds, each step
//!   after `WARM_UP` frames. The pass time is the GPU timestamp span of the
//!   `chisel_splat_pass` (Bevy's `RenderDiagnosticsPlugin`); the frame time
//!   minus the empty frame's is reported beside it as a check that needs no
//!   timestamps.
//! - overdraw: the `Overdraw` output (1/64 per fragment, added up, no depth
//!   test) into an `Rgba16Float` target, read back: every count up to 2048
//!   is exact in `f16`. Covered pixels are those where the `QuadricIds`
//!   output shows the solid. Overdraw = fragments ÷ covered pixels. The
//!   pipeline-statistics count of fragment invocations is printed beside
//!   the read-back sum when the adapter has them.
//! - culling: the boxes are also read back with
//!   `SplatSettings::cull_facing_away` off (`UnculledBoxes`), overdraw and
//!   quadric ids; the ids must agree pixel for pixel.
//! - cell boxes: a second prop of the same samples with boxes around each
//!   splat's whole sphere (`SphereBoxes`, the proxies before they bounded
//!   the sample's cell), overdraw and quadric ids, compared pixel for
//!   pixel with the default boxes.
//! - depth-tested overdraw: the `DepthTestedOverdraw` output (a depth
//!   prepass of the splats, then 1/64 per proxy fragment that passes the
//!   depth test against it, read back exactly): the fragment shader
//!   invocations a GPU with early depth tests runs after a depth prepass,
//!   the paper's depth-tested count at its lowest. Lavapipe's pipeline
//!   statistics count invocations before the depth test, in 2×2 quads.
//!
//! - MSAA (`CHISEL_BENCH_MSAA=4`, or 2 or 8): each round also times the
//!   boxes and the empty frame on the camera with that many samples
//!   (`Msaa::Sample4`, Bevy's default, which the game examples keep), where
//!   the splat pass traces the ray of each covered sample (`SAMPLE_RAYS`
//!   at 4 samples, `PER_SAMPLE` at 2 or 8, in `shaders/splat.wgsl`),
//!   beside the same boxes with `Msaa::Off` in the same round. The read-backs stay at one sample per pixel: a
//!   multisampled target is resolved (averaged) into the image read back,
//!   and the counts above are exact only with one sample.
//!
//! A step that takes far more frames than it asked for (a measurement that
//! never arrives: no timestamps on the adapter, a read-back that never
//! completes) ends the run with an error naming the step, rather than
//! rendering on for thousands of frames.
//!
//! Environment: `CHISEL_BENCH_FRAMES` (timed frames per splat step,
//! default 15), `CHISEL_BENCH_GLOBAL_FRAMES` (per global step, default 3;
//! 0 leaves the global pass out, e.g. for a sweep of splat sizes),
//! `CHISEL_BENCH_SCENES` (comma-separated names, default all four),
//! `CHISEL_BENCH_SPLAT_DIVISOR` (bounding radius ÷ splat radius, default
//! 40 as `SplatRadius::default()`), `CHISEL_BENCH_MSAA` (samples of the
//! multisampled timing steps: 2, 4 or 8; default 1, none),
//! `CHISEL_BENCH_MSAA_ONLY=1` (with `CHISEL_BENCH_MSAA`: only the boxes
//! and the empty frame, at one sample and at the multisampled camera's;
//! no other variant, no read-back).

#[path = "../tests/it/common/scenes.rs"]
mod common;
#[path = "splat/driver.rs"]
mod driver;
#[path = "splat/figures.rs"]
mod figures;
mod support;

use driver::{Driver, SphereProp, drive, steps};
use figures::figures;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::RenderAssetUsages;
use bevy::camera::{ClearColorConfig, RenderTarget};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::diagnostic::DiagnosticsStore;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{
    Extent3d, TextureDimension, TextureFormat, TextureUsages, WgpuFeatures,
};
use bevy::render::renderer::{RenderAdapterInfo, RenderDevice};
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use bevy_chisel::quadric::{BoundingSphere, SampleOptions, Scene, sample};
use bevy_chisel::splat::{
    ChiselSplatPlugin, PropBounds, PropSplats, SplatMode, SplatOutput, SplatSettings,
};
use common::{FOV_DEGREES, SCALE, SCENES, load_scene};

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;
/// Frames run after each switch before frame times are recorded (with
/// pipelined rendering, a frame's time is that of the previous frame's
/// render). Pass times need none: they are told apart by what they drew.
const WARM_UP: u32 = 2;
/// Frames after a switch before a read-back, and before pipeline
/// statistics are taken for the new output (the diagnostics lag a few
/// frames and cannot tell outputs of one mode apart).
const READ_SETTLE: u32 = 5;
/// Timing rounds, interleaved so that a change of machine load hits every
/// mode alike.
const ROUNDS: u32 = 2;
/// Frames a step may run beyond those it asked for before the run is
/// given up with an error: measurements lag a few frames, and a first
/// frame of a new pipeline is dropped.
const STEP_SLACK: u32 = 40;

use support::env_or;

/// How the prop is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Variant {
    /// Surface-aligned boxes (the default splat pass).
    Boxes,
    /// Surface-aligned boxes without their `−n` face.
    OpenBoxes,
    /// Surface-aligned boxes, every splat drawn (no culling of the splats
    /// facing away): the default before that culling; read back only.
    UnculledBoxes,
    /// Surface-aligned boxes around each splat's whole sphere (tangent
    /// half-extents `r`, normal half-extent `r (δ₊ − δ₋)` of eq. 23), as
    /// before the boxes bounded the sample's cell: a second prop of the
    /// same samples; read back only.
    SphereBoxes,
    /// Screen-aligned quads.
    Quads,
    /// Global ray tracing of a cube around the prop.
    Global,
}

impl Variant {
    fn mode(self) -> SplatMode {
        match self {
            Variant::Boxes | Variant::OpenBoxes | Variant::UnculledBoxes | Variant::SphereBoxes => {
                SplatMode::SurfaceBoxes
            }
            Variant::Quads => SplatMode::ScreenQuads,
            Variant::Global => SplatMode::GlobalRayTrace,
        }
    }

    /// Vertex shader invocations of one frame with `splats` splats: how a
    /// late diagnostic is told apart.
    fn vertices(self, splats: u32) -> f64 {
        let n = f64::from(splats);
        match self {
            Variant::Boxes | Variant::UnculledBoxes | Variant::SphereBoxes => 36.0 * n,
            Variant::OpenBoxes => 30.0 * n,
            Variant::Quads => 6.0 * n,
            Variant::Global => 36.0,
        }
    }
}

/// What is drawn in one step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Draw {
    /// The prop, shaded.
    Prop(Variant),
    /// Nothing (the prop hidden): the frame's fixed cost.
    Empty,
}

/// One step of the sequence.
#[derive(Clone, Copy, Debug)]
enum Step {
    /// Record `frames` frames on the camera with `samples` MSAA samples.
    Time {
        draw: Draw,
        frames: u32,
        samples: u32,
    },
    /// Read one frame of `output` back.
    Read {
        variant: Variant,
        output: SplatOutput,
    },
}

/// What the steps recorded.
#[derive(Default)]
struct Log {
    /// GPU time of the pass (ms) per drawing and MSAA samples.
    pass_ms: HashMap<(Draw, u32), Vec<f64>>,
    /// Frame time (ms) per drawing and MSAA samples.
    frame_ms: HashMap<(Draw, u32), Vec<f64>>,
    /// Fragment shader invocations of the pass (pipeline statistics).
    invocations: HashMap<(Variant, SplatOutput), Vec<f64>>,
    /// Each read-back frame (linear RGBA per pixel).
    images: HashMap<(Variant, SplatOutput), Vec<[f32; 4]>>,
    /// The adapter and whether it has timestamps inside passes and
    /// pipeline statistics.
    adapter: String,
}

#[derive(Resource, Clone, Default)]
struct SharedLog(Arc<Mutex<Log>>);

impl SharedLog {
    fn with<R>(&self, f: impl FnOnce(&mut Log) -> R) -> R {
        let mut log = self
            .0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        f(&mut log)
    }
}

fn report_adapter(
    device: Option<Res<RenderDevice>>,
    info: Option<Res<RenderAdapterInfo>>,
    log: Res<SharedLog>,
) {
    let features = device.map(|d| d.features()).unwrap_or_default();
    let text = format!(
        "{} ({:?}); timestamps in passes: {}, pipeline statistics: {}",
        info.as_ref().map_or("?".into(), |i| i.name.clone()),
        info.as_ref().map(|i| i.backend),
        features.contains(WgpuFeatures::TIMESTAMP_QUERY_INSIDE_PASSES),
        features.contains(WgpuFeatures::PIPELINE_STATISTICS_QUERY),
    );
    log.with(|log| log.adapter = text);
}

fn run_scene(
    splats: PropSplats,
    sphere_splats: PropSplats,
    centre: Vec3,
    radius: f32,
    steps: Vec<Step>,
) -> Log {
    let splat_count = u32::try_from(splats.0.splat_count()).expect("splats fit in u32");
    let log = SharedLog::default();
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
            .disable::<WinitPlugin>(),
        ScheduleRunnerPlugin::run_loop(Duration::ZERO),
        RenderDiagnosticsPlugin,
        ChiselSplatPlugin,
    ));
    let mut image = Image::new_uninit(
        Extent3d {
            width: WIDTH,
            height: HEIGHT,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        TextureFormat::Rgba16Float,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage |= TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    let target = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    let eye = local_eye(centre, radius) * SCALE;
    let look = centre * SCALE;
    let camera_target = target.clone();
    app.insert_resource(log.clone())
        .insert_resource(Driver {
            steps,
            step: 0,
            frame: 0,
            taken: 0,
            target,
            splat_count,
            last_measurement: None,
            seen: Vec::new(),
            samples_of: HashMap::new(),
            read_done: Arc::default(),
            reader: None,
            total_frames: 0,
        })
        .add_systems(Startup, report_adapter)
        .add_systems(Update, drive)
        .add_systems(Startup, move |mut commands: Commands| {
            commands.spawn((splats.clone(), Transform::from_scale(Vec3::splat(SCALE))));
            commands.spawn((
                sphere_splats.clone(),
                SphereProp,
                Visibility::Hidden,
                Transform::from_scale(Vec3::splat(SCALE)),
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
                Camera {
                    clear_color: ClearColorConfig::Custom(Color::BLACK),
                    ..default()
                },
                RenderTarget::Image(camera_target.clone().into()),
                Projection::Perspective(PerspectiveProjection {
                    fov: (FOV_DEGREES as f32).to_radians(),
                    near: 0.01,
                    ..default()
                }),
                Tonemapping::None,
                DebandDither::Disabled,
                Msaa::Off,
                Transform::from_translation(eye).looking_at(look, Vec3::Z),
            ));
        });
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    drop(app);
    Arc::try_unwrap(log.0)
        .map(|m| {
            m.into_inner()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        })
        .unwrap_or_else(|shared| std::mem::take(&mut *shared.lock().expect("log")))
}

/// The eye of the benchmark view in the prop's local (scene) coordinates:
/// the render tests' comparison eye.
fn local_eye(centre: Vec3, radius: f32) -> Vec3 {
    common::eye(centre.as_dvec3(), f64::from(radius)).as_vec3()
}

/// The splats of `splats` with boxes around their whole spheres, as
/// before the boxes bounded the cells: tangent half-extents `r` in the
/// frame the shader builds from the normal alone, normal half-extent
/// `r (δ₊ − δ₋)` over the plane box `uv ± r` (eq. 23, capped at `r`). The
/// samples are drawn again with the same options, in the same order.
fn sphere_boxes(scene: &Scene, bounds: PropBounds, radius: f32, splats: &PropSplats) -> PropSplats {
    let dnf = scene.dnf().expect("normal form");
    let sphere =
        BoundingSphere::new(bounds.centre.as_dvec3(), f64::from(bounds.radius)).expect("bounds");
    let options = SampleOptions::new(f64::from(radius), sphere).expect("options");
    let samples = sample(&dnf, &options).expect("sampling");
    let mut data = (*splats.0).clone();
    assert_eq!(samples.samples.len(), data.splats.len(), "the same samples");
    for (record, s) in data.splats.iter_mut().zip(&samples.samples) {
        assert_eq!(record.position, s.position, "in the same order");
        let n = record.normal;
        if n.length_squared() < 0.25 {
            continue;
        }
        let r = f64::from(s.radius);
        let hf = &samples.patches[s.patch as usize].heightfield;
        let uv = samples.uv_of(s);
        let (low, high) = hf.distortion_bounds(uv - DVec2::splat(r), uv + DVec2::splat(r));
        let extent = r * (high - low);
        let helper = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
        record.tangent = helper.cross(n).normalize();
        record.tangent_extent = Vec2::splat(record.radius);
        record.normal_extent = if extent.is_finite() {
            extent.min(r) as f32
        } else {
            record.radius
        };
    }
    data.generation = u64::MAX - data.generation;
    PropSplats(Arc::new(data))
}

/// Of the splats drawn: the fraction whose normal faces away from `eye`
/// (their boxes' `−n` faces are drawn), the mean radius over `requested`,
/// and the area of their squares, `Σ (2 r)²` (scene units).
fn splat_stats(splats: &PropSplats, eye: Vec3, requested: f32) -> (f64, f64, f64) {
    let records = &splats.0.splats;
    let n = records.len().max(1) as f64;
    let away = records
        .iter()
        .filter(|s| s.normal.dot(eye - s.position) < 0.0)
        .count();
    let radii = records.iter().map(|s| f64::from(s.radius));
    let squares = radii.clone().map(|r| 4.0 * r * r).sum::<f64>();
    (
        away as f64 / n,
        radii.sum::<f64>() / n / f64::from(requested),
        squares,
    )
}

fn main() {
    let Some(args) = support::Args::parse("splat") else {
        return;
    };
    let name = "splat_pass_against_global_ray_tracing_at_full_hd";
    if args.wants(name) {
        splat_pass_against_global_ray_tracing_at_full_hd();
    }
}

fn splat_pass_against_global_ray_tracing_at_full_hd() {
    let splat_frames = env_or("CHISEL_BENCH_FRAMES", 15);
    let global_frames = env_or("CHISEL_BENCH_GLOBAL_FRAMES", 3);
    let divisor: f32 = env_or("CHISEL_BENCH_SPLAT_DIVISOR", 40.0);
    let msaa: u32 = env_or("CHISEL_BENCH_MSAA", 1);
    assert!(
        [1, 2, 4, 8].contains(&msaa),
        "CHISEL_BENCH_MSAA must be 1 (off), 2, 4 or 8, not {msaa}"
    );
    let msaa_only = msaa > 1 && env_or("CHISEL_BENCH_MSAA_ONLY", 0u32) == 1;
    let global_frames = if msaa_only { 0 } else { global_frames };
    let only: Option<Vec<String>> = std::env::var("CHISEL_BENCH_SCENES")
        .ok()
        .map(|s| s.split(',').map(str::to_owned).collect());
    let mut times = Vec::new();
    let mut msaa_times = Vec::new();
    let mut overdraws = Vec::new();
    let mut json_scenes = Vec::new();
    // The benchmark scenes of `assets/scenes/`; each is sampled and viewed in its file's
    // `bounds`.
    for (name, _, _) in SCENES {
        if only.as_ref().is_some_and(|o| !o.iter().any(|n| n == name)) {
            continue;
        }
        let scene = load_scene(name);
        let bounds = PropBounds::resolve(None, &scene).expect("shipped scenes give their bounds");
        let PropBounds { centre, radius } = bounds;
        let splats = PropSplats::build(&scene, bounds, radius / divisor).expect("sampling");
        let sphere_splats = sphere_boxes(&scene, bounds, radius / divisor, &splats);
        let (quadrics, splat_count) = (splats.0.quadrics.len(), splats.0.splat_count());
        let (away, mean_radius, squares) =
            splat_stats(&splats, local_eye(centre, radius), radius / divisor);
        let log = run_scene(
            splats,
            sphere_splats,
            centre,
            radius,
            steps(splat_frames, global_frames, msaa, msaa_only),
        );
        println!(
            "\n{name}: {quadrics} quadrics, {splat_count} splats (radius {:.3}, mean {:.3} of it; \
             squares Σ(2r)² = {squares:.0}; {:.1} % face away from the eye); {}",
            radius / divisor,
            mean_radius,
            100.0 * away,
            log.adapter
        );
        let f = figures(&log);
        // Where cell and sphere boxes disagree, the reference tracer says
        // which shows the solid.
        let dnf = scene.dnf().expect("normal form");
        let camera = bevy_chisel::quadric::Camera::new(
            local_eye(centre, radius).as_dvec3(),
            centre.as_dvec3(),
            FOV_DEGREES,
            WIDTH,
            HEIGHT,
        )
        .expect("camera");
        for &(x, y, cell, sphere) in f.sphere_differ.iter().take(20) {
            let hit = bevy_chisel::quadric::trace_ray(&dnf, &camera.ray(x, y), 0.0);
            println!(
                "  ({x}, {y}): solid with cell boxes {cell}, with sphere boxes {sphere}; \
                 reference: {:?}",
                hit.map(|h| (h.quadric, h.t))
            );
        }
        let pass = |v| f.pass_ms.get(&v).copied().unwrap_or(f64::NAN);
        let check = |v| f.frame_minus_empty_ms.get(&v).copied().unwrap_or(f64::NAN);
        let od = |v| f.overdraw.get(&v).copied().unwrap_or((f64::NAN, f64::NAN));
        let tested = |v| f.depth_tested.get(&v).copied().unwrap_or(f64::NAN);
        if let Some(m) = f.msaa_boxes {
            msaa_times.push(format!(
                "| {name} | {splat_count} | {:.2} | {:.2} | {:.2}× | {:.2}× |",
                pass(Variant::Boxes),
                m.pass_ms,
                m.pass_ms / pass(Variant::Boxes),
                m.frame_minus_empty_ms / check(Variant::Boxes),
            ));
        }
        times.push(format!(
            "| {name} | {quadrics} | {splat_count} | {:.2} | {:.2} | {:.1}× | {:.1}× | {:.2} | {:.2} |",
            pass(Variant::Boxes),
            pass(Variant::Global),
            pass(Variant::Global) / pass(Variant::Boxes),
            check(Variant::Global) / check(Variant::Boxes),
            pass(Variant::OpenBoxes),
            pass(Variant::Quads),
        ));
        let by_variant = |value: &dyn Fn(Variant) -> f64| {
            serde_json::Map::from_iter(
                [
                    Variant::Boxes,
                    Variant::OpenBoxes,
                    Variant::Quads,
                    Variant::Global,
                ]
                .map(|v| (format!("{v:?}"), serde_json::json!(value(v)))),
            )
        };
        json_scenes.push(serde_json::json!({
            "scene": name,
            "quadrics": quadrics,
            "splats": splat_count,
            "adapter": log.adapter,
            "pass_ms": by_variant(&pass),
            "frame_minus_empty_ms": by_variant(&check),
            "overdraw": by_variant(&|v| od(v).0),
            "invocations_per_covered_px": by_variant(&|v| od(v).1),
            "unculled_overdraw": od(Variant::UnculledBoxes).0,
            "sphere_boxes_overdraw": od(Variant::SphereBoxes).0,
            "sphere_boxes_invocations_per_covered_px": od(Variant::SphereBoxes).1,
            "depth_tested_overdraw": tested(Variant::Boxes),
            "sphere_boxes_depth_tested_overdraw": tested(Variant::SphereBoxes),
            "covered_px": f.covered,
            "msaa_boxes": f.msaa_boxes.map(|m| serde_json::json!({
                "samples": m.samples,
                "pass_ms": m.pass_ms,
                "frame_minus_empty_ms": m.frame_minus_empty_ms,
            })),
        }));
        overdraws.push(format!(
            "| {name} | {} | {:.2} → **{:.2}** | {:.2} → **{:.2}** | {:.2} → {:.2} | {:.2} | \
             {:.2} | {:.2} |",
            f.covered,
            od(Variant::SphereBoxes).0,
            od(Variant::Boxes).0,
            tested(Variant::SphereBoxes),
            tested(Variant::Boxes),
            od(Variant::SphereBoxes).1,
            od(Variant::Boxes).1,
            od(Variant::UnculledBoxes).0,
            od(Variant::OpenBoxes).0,
            od(Variant::Quads).0,
        ));
    }
    println!(
        "\n| scene | quadrics | splats | splat pass ms | global pass ms | global ÷ splat | \
         same, frame − empty | open boxes ms | screen quads ms |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for row in times {
        println!("{row}");
    }
    if !msaa_times.is_empty() {
        println!(
            "\n| scene | splats | boxes, MSAA off, ms | boxes, {msaa}× MSAA, ms | {msaa}× ÷ off | \
             same, frame − empty |"
        );
        println!("|---|---:|---:|---:|---:|---:|");
        for row in msaa_times {
            println!("{row}");
        }
        println!(
            "(read-backs and overdraw at MSAA off: a multisampled target is resolved before it \
             is read)"
        );
    }
    if msaa_only {
        println!("\n(CHISEL_BENCH_MSAA_ONLY: no other variant, no read-back)");
    } else {
        println!(
            "\n| scene | covered px | fragments per covered px, sphere → cell boxes | \
             depth-tested (after a depth prepass), sphere → cell boxes | adapter's invocations \
             per covered px, sphere → cell boxes | cell boxes unculled | open cell boxes | \
             screen quads |"
        );
        println!("|---|---:|---:|---:|---:|---:|---:|---:|");
        for row in overdraws {
            println!("{row}");
        }
    }
    support::json_line(
        "splat::splat_pass_against_global_ray_tracing_at_full_hd",
        serde_json::json!({
            "splat_frames": splat_frames,
            "global_frames": global_frames,
            "splat_divisor": divisor,
            "msaa": msaa,
            "scenes": json_scenes,
        }),
    );
}
