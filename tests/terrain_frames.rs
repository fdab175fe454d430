//! What carving costs a game's frame: an app paced at 60 frames per second
//! (no rendering, `MinimalPlugins`) sends a crater carve every few frames to
//! a 256 m × 256 m terrain at 1 mm units and records, per frame, the
//! main-thread span of the terrain systems (from before
//! [`TerrainSystems::Carve`] to after [`TerrainSystems::Mesh`]), and per
//! carve, the frames from the `Carve` message to its `CarveApplied` (every
//! changed cell's mesh in place). The same span over frames with nothing
//! to carve is the baseline. Ignored by default; run
//!
//! `cargo test --release -p bevy_chisel --test terrain_frames -- --ignored --nocapture`
//!
//! Environment: `CHISEL_BENCH_CARVES` (default 300), `CHISEL_BENCH_EVERY`
//! (frames between carves, default 6: ten carves a second).
//!
//! The span covers the plugin's systems only: a renderer adds the upload of
//! the new meshes to the GPU, on the render thread.

use std::time::{Duration, Instant};

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveShape, CarveTool, Terrain, TerrainCellChanged, TerrainPlugin,
    TerrainSystems,
};

const FRAME: Duration = Duration::from_nanos(16_666_667);

/// Frames run with nothing to carve before the carves start.
const BASELINE_FRAMES: usize = 600;

/// Per-frame records.
#[derive(Resource, Default)]
struct Frames {
    /// The frame being run.
    frame: u64,
    /// When the terrain systems of this frame began.
    start: Option<Instant>,
    /// Main-thread span of the terrain systems, per frame.
    spans: Vec<Duration>,
    /// The same, in the frames that uploaded no mesh: what is left there is
    /// bookkeeping, and the scheduler's preemption of the main thread by the
    /// background work on a machine with few cores.
    idle_spans: Vec<Duration>,
    /// Frame of each `CarveApplied` with an edit, in order.
    applied: Vec<u64>,
    /// Kernel and mesh times reported by the plugin, per carve.
    work: Vec<Duration>,
}

fn mark_start(mut frames: ResMut<Frames>) {
    frames.start = Some(Instant::now());
}

fn mark_end(
    mut frames: ResMut<Frames>,
    mut applied: MessageReader<CarveApplied>,
    mut changed: MessageReader<TerrainCellChanged>,
) {
    let uploaded = changed.read().count() > 0;
    if let Some(start) = frames.start.take() {
        let span = start.elapsed();
        frames.spans.push(span);
        if !uploaded {
            frames.idle_spans.push(span);
        }
    }
    let frame = frames.frame;
    for report in applied.read() {
        if report.edit.is_some() {
            frames.applied.push(frame);
            frames.work.push(report.apply_time + report.mesh_time);
        }
    }
}

fn percentile_ms(sorted: &[Duration], p: f64) -> f64 {
    let k = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[k].as_secs_f64() * 1e3
}

fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
#[ignore = "benchmark"]
fn carving_at_sixty_frames_per_second() {
    let carves = env_or("CHISEL_BENCH_CARVES", 300);
    let every = env_or("CHISEL_BENCH_EVERY", 6).max(1) as u64;
    let grid = Quantization::new(0.001, [0.0; 3]).expect("valid unit");
    let terrain = Terrain::from_box(
        grid,
        Vec3::new(0.0, -20.0, 0.0),
        Vec3::new(256.0, 0.0, 256.0),
        1,
    )
    .expect("valid box");

    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>()
        .init_resource::<Frames>()
        .add_systems(
            Update,
            (
                mark_start.before(TerrainSystems::Carve),
                mark_end.after(TerrainSystems::Mesh),
            ),
        );
    let entity = app.world_mut().spawn(terrain).id();
    for _ in 0..10_000 {
        app.update();
        if app
            .world()
            .get::<Terrain>(entity)
            .is_some_and(Terrain::is_idle)
        {
            break;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    {
        let mut frames = app.world_mut().resource_mut::<Frames>();
        frames.spans.clear();
        frames.idle_spans.clear();
        frames.applied.clear();
        frames.work.clear();
    }

    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    // A baseline: the same frames with nothing to carve, so that what
    // carving adds can be told from the machine's own noise.
    for _ in 0..BASELINE_FRAMES {
        let begin = Instant::now();
        app.update();
        if let Some(rest) = FRAME.checked_sub(begin.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    let mut baseline = std::mem::take(&mut app.world_mut().resource_mut::<Frames>().spans);
    baseline.sort();
    app.world_mut().resource_mut::<Frames>().idle_spans.clear();

    let mut sent = Vec::with_capacity(carves);
    let mut frame = 0u64;
    loop {
        let begin = Instant::now();
        app.world_mut().resource_mut::<Frames>().frame = frame;
        if frame.is_multiple_of(every) && sent.len() < carves {
            let centre = Vec3::new(
                (4.0 + 248.0 * next()) as f32,
                -next() as f32,
                (4.0 + 248.0 * next()) as f32,
            );
            let turn = Quat::from_rotation_y((std::f64::consts::TAU * next()) as f32);
            app.world_mut().write_message(Carve {
                terrain: entity,
                tool: CarveTool::new(
                    CarveShape::Dodecahedron { radius: 2.0 },
                    Transform::from_translation(centre).with_rotation(turn),
                ),
                edit: Edit::Subtract,
            });
            sent.push(frame);
        }
        app.update();
        let done = app.world().resource::<Frames>().applied.len();
        if done >= carves || frame > (carves as u64 * every + 60) * 20 {
            break;
        }
        frame += 1;
        if let Some(rest) = FRAME.checked_sub(begin.elapsed()) {
            std::thread::sleep(rest);
        }
    }

    let frames = app.world().resource::<Frames>();
    assert_eq!(frames.applied.len(), carves, "every carve was applied");
    let mut spans = frames.spans.clone();
    spans.sort();
    let mut idle = frames.idle_spans.clone();
    idle.sort();
    let mut work = frames.work.clone();
    work.sort();
    let mut lag: Vec<u64> = frames
        .applied
        .iter()
        .zip(&sent)
        .map(|(applied, sent)| applied - sent)
        .collect();
    lag.sort_unstable();
    let within = |n: u64| lag.iter().filter(|&&l| l <= n).count() as f64 / lag.len() as f64;
    println!(
        "{carves} crater carves (r = 2 m, 1 mm grid, 256 m × 256 m), one every {every} frames at 60 fps, {} frames",
        spans.len()
    );
    println!(
        "main-thread span of the terrain systems per frame: median {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        percentile_ms(&spans, 0.5),
        percentile_ms(&spans, 0.99),
        percentile_ms(&spans, 1.0)
    );
    println!(
        "the same with nothing to carve ({} frames): median {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        baseline.len(),
        percentile_ms(&baseline, 0.5),
        percentile_ms(&baseline, 0.99),
        percentile_ms(&baseline, 1.0)
    );
    println!(
        "the same in the {} carving frames that uploaded no mesh: median {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        idle.len(),
        percentile_ms(&idle, 0.5),
        percentile_ms(&idle, 0.99),
        percentile_ms(&idle, 1.0)
    );
    println!(
        "background work per carve (kernel + meshes): median {:.2} ms, p99 {:.2} ms",
        percentile_ms(&work, 0.5),
        percentile_ms(&work, 0.99)
    );
    println!(
        "frames from Carve to CarveApplied: median {}, p99 {}, max {}; within 1 frame {:.1}%, within 2 frames {:.1}%",
        lag[lag.len() / 2],
        lag[((lag.len() - 1) as f64 * 0.99).round() as usize],
        lag[lag.len() - 1],
        100.0 * within(1),
        100.0 * within(2)
    );
}
