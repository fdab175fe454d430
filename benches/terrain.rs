//! Terrain benchmarks at 1 mm units. Crater carves on a 256 m × 256 m
//! terrain: time to apply a radius-2 m dodecahedron and re-mesh the cells
//! it changed, as the plugin does off the main thread. Terrain files: time
//! to load a carved quarry against replaying its carves. Frames: what
//! carving costs a game running at 60 frames per second. Latency: from a
//! `Carve` message to meshes and colliders in place. Run all four, or those
//! whose names contain a filter, with
//!
//! `cargo bench -p bevy_chisel --all-features --bench terrain [-- FILTER]`
//!
//! (measurements: `crater_carves_on_a_large_terrain`,
//! `loading_a_saved_terrain_against_replaying_its_carves`,
//! `carving_at_sixty_frames_per_second`,
//! `crater_latency_to_meshes_and_colliders`, `streaming_a_world`,
//! `lod_of_a_world`, `debris_across_chunk_borders`,
//! `debris_latency_across_borders`, `saving_a_world`,
//! `carve_latency_while_streaming`). World: chunks of the `world` example's landscape
//! built one at a time, their size, the banded base built in one pass
//! against painting its bands, and an app streaming them around a focus
//! touring the world (a line, a loop or a lawnmower; `CHISEL_BENCH_TOUR`)
//! at 50 m/s while blasting craters, with time to first frame and peak
//! memory. Level of detail: what coarse chunks cost to build, and what the
//! view to a far radius draws with and without. Saving: what a save
//! costs the frame that asks for it, synchronous or in the background.
//! Each prints its figures, then
//! one JSON line of them. `cargo test` runs this binary without `--bench`:
//! it then measures nothing (see `support`).
//!

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::mesh::{cell_meshes, cell_meshes_from};
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveShape, CarveTool, Terrain, TerrainCellChanged, TerrainPlugin,
    TerrainSettings, TerrainSystems, apply_carve_with_faces, terrain_octree_config,
};
use rayon::prelude::*;
use serde_json::json;

mod support;
use support::{Args, env_or, json_line, percentile};
#[path = "terrain/corner_latency.rs"]
mod corner_latency;
#[path = "support/frame_steps.rs"]
mod frame_steps;
#[path = "terrain/world.rs"]
mod world;
#[path = "terrain/world_carve_latency.rs"]
mod world_carve_latency;
#[path = "terrain/world_debris.rs"]
mod world_debris;
#[path = "terrain/world_debris_latency.rs"]
mod world_debris_latency;
#[path = "terrain/world_lod.rs"]
mod world_lod;
#[path = "terrain/world_save.rs"]
mod world_save;
use world::streaming_a_world;
use world_carve_latency::carve_latency_while_streaming;
use world_debris::debris_across_chunk_borders;
use world_debris_latency::debris_latency_across_borders;
use world_lod::lod_of_a_world;
use world_save::saving_a_world;

fn main() {
    let Some(args) = Args::parse("terrain") else {
        return;
    };
    let all: [(&str, fn()); 10] = [
        (
            "crater_carves_on_a_large_terrain",
            crater_carves_on_a_large_terrain,
        ),
        (
            "loading_a_saved_terrain_against_replaying_its_carves",
            loading_a_saved_terrain_against_replaying_its_carves,
        ),
        (
            "carving_at_sixty_frames_per_second",
            carving_at_sixty_frames_per_second,
        ),
        (
            "crater_latency_to_meshes_and_colliders",
            crater_latency_to_meshes_and_colliders,
        ),
        ("streaming_a_world", streaming_a_world),
        ("lod_of_a_world", lod_of_a_world),
        ("debris_across_chunk_borders", debris_across_chunk_borders),
        (
            "debris_latency_across_borders",
            debris_latency_across_borders,
        ),
        ("saving_a_world", saving_a_world),
        (
            "carve_latency_while_streaming",
            carve_latency_while_streaming,
        ),
    ];
    for (name, measure) in all {
        if args.wants(name) {
            println!("\n== terrain::{name}");
            measure();
        }
    }
}

/// A deterministic stream of numbers in `[0, 1)` (xorshift64).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A 256 m × 256 m × 20 m block of rock on a 1 mm grid, top face at y = 0.
fn large_terrain() -> Terrain {
    let grid = Quantization::new(0.001, [0.0; 3]).expect("valid unit");
    Terrain::from_box(
        grid,
        Vec3::new(0.0, -20.0, 0.0),
        Vec3::new(256.0, 0.0, 256.0),
        1,
    )
    .expect("valid box")
}

/// A radius-2 m dodecahedron at a random place just under the top face of
/// [`large_terrain`], turned at random about y.
fn crater(next: &mut impl FnMut() -> f64) -> CarveTool {
    let centre = Vec3::new(
        (4.0 + 248.0 * next()) as f32,
        -next() as f32,
        (4.0 + 248.0 * next()) as f32,
    );
    let turn = Quat::from_rotation_y((std::f64::consts::TAU * next()) as f32);
    CarveTool::new(
        CarveShape::Dodecahedron { radius: 2.0 },
        Transform::from_translation(centre).with_rotation(turn),
    )
}

fn crater_carves_on_a_large_terrain() {
    let carves: usize = env_or("CHISEL_BENCH_CARVES", 1000);
    // CHISEL_BENCH_BUDGET: the octree's BSP node budget per cell (default:
    // the terrains' own).
    let config = OctreeConfig {
        max_bsp_nodes: env_or("CHISEL_BENCH_BUDGET", terrain_octree_config().max_bsp_nodes),
        ..terrain_octree_config()
    };
    let budget = config.max_bsp_nodes;
    let terrain = large_terrain();
    let grid = *terrain.quantization();
    let terrain = Terrain::from_base(grid, terrain.base().clone(), config).expect("same base");
    let mut octree = terrain.octree().clone();
    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
    let (mut apply, mut total) = (Vec::new(), Vec::new());
    let mut by_decile = vec![Vec::new(); 10];
    for k in 0..carves {
        let tool = crater(&mut next).to_grid(&grid).expect("on the grid");
        let start = Instant::now();
        // As the plugin's background job does: cells the carve rebuilt are
        // meshed from the faces it handed back, the others afresh.
        let (changes, faces) =
            apply_carve_with_faces(&mut octree, &tool, Edit::Subtract).expect("valid carve");
        let applied = start.elapsed();
        let mut faces: BTreeMap<_, _> = faces.into_iter().collect();
        let jobs: Vec<_> = changes
            .changed
            .iter()
            .chain(&changes.removed)
            .map(|&key| (key, faces.remove(&key)))
            .collect();
        let triangles: usize = jobs
            .into_par_iter()
            .map(|(key, faces)| {
                match faces {
                    Some(faces) => cell_meshes_from(&octree, &grid, key, faces),
                    None => cell_meshes(&octree, &grid, key),
                }
                .iter()
                .map(|m| m.triangle_count())
                .sum::<usize>()
            })
            .sum();
        assert!(triangles > 0);
        let done = start.elapsed();
        apply.push(applied);
        total.push(done);
        by_decile[k * 10 / carves].push(done);
    }
    apply.sort();
    total.sort();
    let stats = octree.stats();
    println!(
        "{carves} crater carves (r = 2 m, 1 mm grid, 256 m × 256 m), {} threads, budget {budget}",
        rayon::current_num_threads()
    );
    println!(
        "apply:          median {:.2} ms, p99 {:.2} ms",
        percentile(&apply, 0.5),
        percentile(&apply, 0.99)
    );
    println!(
        "apply + meshes: median {:.2} ms, p99 {:.2} ms",
        percentile(&total, 0.5),
        percentile(&total, 0.99)
    );
    let mut decile_medians = Vec::new();
    for (d, mut times) in by_decile.into_iter().enumerate() {
        times.sort();
        decile_medians.push(percentile(&times, 0.5));
        println!(
            "  carves {:>5}..: median {:.2} ms",
            d * carves / 10,
            percentile(&times, 0.5)
        );
    }
    println!(
        "octree: {} leaves, {} BSP nodes, {} KiB",
        stats.leaves,
        stats.bsp_nodes,
        stats.bsp_bytes / 1024
    );
    json_line(
        "terrain::crater_carves_on_a_large_terrain",
        json!({
            "carves": carves,
            "threads": rayon::current_num_threads(),
            "budget": budget,
            "apply_median_ms": percentile(&apply, 0.5),
            "apply_p99_ms": percentile(&apply, 0.99),
            "apply_meshes_median_ms": percentile(&total, 0.5),
            "apply_meshes_p99_ms": percentile(&total, 0.99),
            "decile_median_ms": decile_medians,
            "leaves": stats.leaves,
            "bsp_nodes": stats.bsp_nodes,
            "bsp_kib": stats.bsp_bytes / 1024,
        }),
    );
}

/// Loading a saved terrain (the octree snapshot and undo history) against
/// rebuilding it from its base and replaying its journal, which is what
/// loading cost before terrain files stored the octree. The quarry
/// example's terrain, blasted `CHISEL_BENCH_CARVES` times (default 1000)
/// with radius-2 m dodecahedra at the surface, every tenth carve a heap of
/// added dirt.
///
/// `cargo bench -p bevy_chisel --all-features --bench terrain -- loading`
fn loading_a_saved_terrain_against_replaying_its_carves() {
    use bevy::math::Ray3d;
    use bevy_chisel::bsp::octree::Octree;
    use bevy_chisel::terrain::{HeightLayer, Heightfield};

    let carves: usize = env_or("CHISEL_BENCH_CARVES", 1000);
    let grid = Quantization::new(0.001, [0.0; 3]).expect("valid unit");
    let field = Heightfield::load_image("assets/terrain/quarry_height.png", 1.0, 0.0, 5.0, 8.0, 1)
        .expect("the quarry heightfield")
        .with_layers([
            HeightLayer {
                depth: 1.2,
                label: 2,
            },
            HeightLayer {
                depth: 0.25,
                label: 3,
            },
        ]);
    let mut terrain = Terrain::from_heightfield(grid, &field).expect("valid heightfield");
    let mut next = {
        let mut next = uniform(0x2545_F491_4F6C_DD1D);
        move || next() as f32
    };
    let start = Instant::now();
    // Blasts where a ray from above meets the ground (a few rays fall
    // through holes blasted down to the bottom).
    for attempt in 0..10 * carves {
        let k = terrain.journal().len();
        if k == carves {
            break;
        }
        let (x, z) = (-14.0 + 28.0 * next(), -14.0 + 28.0 * next());
        let down = Ray3d::new(Vec3::new(x, 30.0, z), Dir3::NEG_Y);
        let Some(hit) = terrain.ray_cast(down, 100.0) else {
            assert!(attempt < 10 * carves - 1, "no ground left to blast");
            continue;
        };
        let (shape, edit) = if k % 10 == 9 {
            (CarveShape::Dodecahedron { radius: 1.0 }, Edit::Add(2))
        } else {
            (CarveShape::Dodecahedron { radius: 2.0 }, Edit::Subtract)
        };
        let turn = Quat::from_euler(EulerRot::YXZ, 0.9 * k as f32, 0.4, 0.3 * k as f32);
        let tool = CarveTool::new(
            shape,
            Transform::from_translation(hit.point).with_rotation(turn),
        )
        .to_grid(&grid)
        .expect("on the grid");
        terrain.apply_now(&tool, edit).expect("valid carve");
    }
    let carving = start.elapsed();

    let start = Instant::now();
    let bytes = terrain.to_bytes();
    let saving = start.elapsed();
    let start = Instant::now();
    let loaded = Terrain::from_bytes(&bytes).expect("loads");
    let loading = start.elapsed();
    assert_eq!(loaded.to_bytes(), bytes);

    // The previous format's load: the base rebuilt, every carve replayed.
    let start = Instant::now();
    let mut replayed = Terrain::from_base(grid, terrain.base().clone(), *terrain.octree().config())
        .expect("the base builds");
    let rebuilding = start.elapsed();
    for entry in terrain.journal() {
        replayed
            .apply_now(&entry.tool, entry.edit)
            .expect("the carve replays");
    }
    let replaying = start.elapsed();
    assert_eq!(replayed.octree().to_bytes(), terrain.octree().to_bytes());

    let stats = terrain.octree().stats();
    let current = terrain.octree().to_bytes();
    let start = Instant::now();
    let alone = Octree::from_bytes(&current).expect("loads");
    let loading_alone = start.elapsed();
    assert_eq!(alone.stats(), stats);
    println!(
        "quarry, {} carves ({:.1} s), {} threads: {} leaves, {} BSP nodes",
        terrain.journal().len(),
        carving.as_secs_f64(),
        rayon::current_num_threads(),
        stats.leaves,
        stats.bsp_nodes
    );
    println!(
        "file: {:.2} MiB with {} undo steps and the journal; the current octree alone {:.2} MiB, \
         loaded in {:.1} ms",
        bytes.len() as f64 / (1 << 20) as f64,
        terrain.undo_depth(),
        current.len() as f64 / (1 << 20) as f64,
        loading_alone.as_secs_f64() * 1e3
    );
    println!(
        "save {:.1} ms, load {:.1} ms; the previous load {:.1} ms ({:.0}× the load): \
         base rebuilt {:.1} ms, carves replayed {:.1} ms",
        saving.as_secs_f64() * 1e3,
        loading.as_secs_f64() * 1e3,
        replaying.as_secs_f64() * 1e3,
        replaying.as_secs_f64() / loading.as_secs_f64(),
        rebuilding.as_secs_f64() * 1e3,
        (replaying - rebuilding).as_secs_f64() * 1e3,
    );
    json_line(
        "terrain::loading_a_saved_terrain_against_replaying_its_carves",
        json!({
            "carves": terrain.journal().len(),
            "carving_s": carving.as_secs_f64(),
            "threads": rayon::current_num_threads(),
            "leaves": stats.leaves,
            "bsp_nodes": stats.bsp_nodes,
            "file_bytes": bytes.len(),
            "undo_steps": terrain.undo_depth(),
            "octree_bytes": current.len(),
            "octree_load_ms": loading_alone.as_secs_f64() * 1e3,
            "save_ms": saving.as_secs_f64() * 1e3,
            "load_ms": loading.as_secs_f64() * 1e3,
            "replay_load_ms": replaying.as_secs_f64() * 1e3,
            "rebuild_ms": rebuilding.as_secs_f64() * 1e3,
        }),
    );
}

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

/// What carving costs a game's frame: an app paced at 60 frames per second
/// (no rendering, `MinimalPlugins`) sends a crater carve every few frames to
/// a 256 m × 256 m terrain at 1 mm units and records, per frame, the
/// main-thread span of the terrain systems (from before
/// [`TerrainSystems::Carve`] to after [`TerrainSystems::Mesh`]), and per
/// carve, the frames from the `Carve` message to its `CarveApplied` (every
/// changed cell's mesh in place). The same span over frames with nothing
/// to carve is the baseline. Run
///
/// `cargo bench -p bevy_chisel --all-features --bench terrain -- carving_at_sixty_frames`
///
/// Environment: `CHISEL_BENCH_CARVES` (default 300), `CHISEL_BENCH_EVERY`
/// (frames between carves, default 6: ten carves a second).
///
/// The span covers the plugin's systems only: a renderer adds the upload of
/// the new meshes to the GPU, on the render thread.
fn carving_at_sixty_frames_per_second() {
    let carves: usize = env_or("CHISEL_BENCH_CARVES", 300);
    let every = env_or::<u64>("CHISEL_BENCH_EVERY", 6).max(1);
    let terrain = large_terrain();

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

    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
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
            app.world_mut().write_message(Carve {
                terrain: entity,
                tool: crater(&mut next),
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
        percentile(&spans, 0.5),
        percentile(&spans, 0.99),
        percentile(&spans, 1.0)
    );
    println!(
        "the same with nothing to carve ({} frames): median {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        baseline.len(),
        percentile(&baseline, 0.5),
        percentile(&baseline, 0.99),
        percentile(&baseline, 1.0)
    );
    println!(
        "the same in the {} carving frames that uploaded no mesh: median {:.3} ms, p99 {:.3} ms, max {:.3} ms",
        idle.len(),
        percentile(&idle, 0.5),
        percentile(&idle, 0.99),
        percentile(&idle, 1.0)
    );
    println!(
        "background work per carve (kernel + meshes): median {:.2} ms, p99 {:.2} ms",
        percentile(&work, 0.5),
        percentile(&work, 0.99)
    );
    println!(
        "frames from Carve to CarveApplied: median {}, p99 {}, max {}; within 1 frame {:.1}%, within 2 frames {:.1}%",
        lag[lag.len() / 2],
        lag[((lag.len() - 1) as f64 * 0.99).round() as usize],
        lag[lag.len() - 1],
        100.0 * within(1),
        100.0 * within(2)
    );
    let ms = |sorted: &[Duration]| {
        json!({
            "median": percentile(sorted, 0.5),
            "p99": percentile(sorted, 0.99),
            "max": percentile(sorted, 1.0),
        })
    };
    json_line(
        "terrain::carving_at_sixty_frames_per_second",
        json!({
            "carves": carves,
            "every_frames": every,
            "frames": spans.len(),
            "span_ms": ms(&spans),
            "baseline_span_ms": ms(&baseline),
            "idle_span_ms": ms(&idle),
            "work_median_ms": percentile(&work, 0.5),
            "work_p99_ms": percentile(&work, 0.99),
            "lag_frames_median": lag[lag.len() / 2],
            "lag_frames_p99": lag[((lag.len() - 1) as f64 * 0.99).round() as usize],
            "lag_frames_max": lag[lag.len() - 1],
            "within_1_frame": within(1),
            "within_2_frames": within(2),
        }),
    );
}

/// The latency a game sees: from a crater carve sent as a [`Carve`]
/// message to its meshes (and, with the `avian` feature, its colliders) in
/// place, [`CarveApplied::latency`], one carve at a time on
/// [`large_terrain`], the app updated as fast as it goes (no frame pacing).
/// Also how many app updates each carve took to show.
///
/// `cargo bench -p bevy_chisel --all-features --bench terrain -- crater_latency`
fn crater_latency_to_meshes_and_colliders() {
    let carves: usize = env_or("CHISEL_BENCH_CARVES", 1000);
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>();
    #[cfg(feature = "avian")]
    app.add_plugins(bevy_chisel::terrain::avian::TerrainAvianPlugin::default());
    let colliders = cfg!(feature = "avian");
    // CHISEL_BENCH_THREADS: the terrain's worker threads (default: the
    // plugin's own choice).
    let threads = env_or(
        "CHISEL_BENCH_THREADS",
        TerrainSettings::default().worker_threads,
    );
    app.insert_resource(TerrainSettings {
        worker_threads: threads,
        ..TerrainSettings::default()
    });
    // CHISEL_BENCH_BUDGET: the octree's BSP node budget per cell (default:
    // the terrains' own).
    let config = OctreeConfig {
        max_bsp_nodes: env_or("CHISEL_BENCH_BUDGET", terrain_octree_config().max_bsp_nodes),
        ..terrain_octree_config()
    };
    let base = large_terrain();
    let grid = *base.quantization();
    let base = Terrain::from_base(grid, base.base().clone(), config).expect("same base");
    let terrain = app.world_mut().spawn(base).id();
    let idle = |app: &App| {
        app.world()
            .get::<Terrain>(terrain)
            .is_some_and(Terrain::is_idle)
    };
    while !idle(&app) {
        app.update();
    }
    let mut cursor = app
        .world()
        .resource::<Messages<CarveApplied>>()
        .get_cursor_current();
    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
    let (mut latency, mut apply, mut mesh, mut collider, mut updates) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..carves {
        let tool = crater(&mut next);
        app.world_mut().write_message(Carve {
            terrain,
            tool,
            edit: Edit::Subtract,
        });
        let mut n = 0usize;
        let report = loop {
            app.update();
            n += 1;
            let messages = app.world().resource::<Messages<CarveApplied>>();
            if let Some(report) = cursor.read(messages).last() {
                break report.clone();
            }
            assert!(n < 1_000_000, "the carve never landed");
        };
        latency.push(report.latency);
        apply.push(report.apply_time);
        mesh.push(report.mesh_time);
        collider.push(report.collider_time);
        updates.push(n);
    }
    for times in [&mut latency, &mut apply, &mut mesh, &mut collider] {
        times.sort();
    }
    updates.sort();
    println!(
        "{carves} crater carves (r = 2 m, 1 mm grid, 256 m × 256 m) through the ECS, \
         colliders {}, {} worker threads, budget {}",
        if colliders { "on (avian)" } else { "off" },
        threads,
        config.max_bsp_nodes
    );
    let mut figures = json!({
        "carves": carves,
        "colliders": colliders,
        "worker_threads": threads,
        "budget": config.max_bsp_nodes,
        "updates_median": updates[updates.len() / 2],
        "updates_max": updates.last().copied().unwrap_or(0),
    });
    for (name, times) in [
        ("latency", &latency),
        ("apply", &apply),
        ("meshes", &mesh),
        ("colliders", &collider),
    ] {
        let max = times.last().map_or(0.0, |t| t.as_secs_f64() * 1e3);
        println!(
            "{name:>10}: median {:.2} ms, p99 {:.2} ms, max {:.2} ms",
            percentile(times, 0.5),
            percentile(times, 0.99),
            max
        );
        figures[format!("{name}_ms")] = json!({
            "median": percentile(times, 0.5),
            "p99": percentile(times, 0.99),
            "max": max,
        });
    }
    println!(
        "app updates until shown: median {}, max {}",
        updates[updates.len() / 2],
        updates.last().copied().unwrap_or(0)
    );
    json_line("terrain::crater_latency_to_meshes_and_colliders", figures);
}
