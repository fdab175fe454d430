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
//! `lod_of_a_world`). World: chunks of the `world` example's landscape
//! built one at a time, their size, the banded base built in one pass
//! against painting its bands, and an app streaming them around a focus
//! touring the world (a line, a loop or a lawnmower; `CHISEL_BENCH_TOUR`)
//! at 50 m/s while blasting craters, with time to first frame and peak
//! memory. Level of detail: what coarse chunks cost to build, and what the
//! view to a far radius draws with and without.
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

fn main() {
    let Some(args) = Args::parse("terrain") else {
        return;
    };
    let all: [(&str, fn()); 6] = [
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

/// The `world` example's landscape and layout: a 1 cm grid, 20.48 m
/// chunks, samples 1.28 m apart, with (or without) grass and dirt bands.
fn world_of_the_example(layers: bool) -> bevy_chisel::terrain::TerrainWorld {
    use bevy_chisel::terrain::{TerrainWorld, WorldLayout};
    let layout = WorldLayout {
        quantization: Quantization::new(0.01, [0.0; 3]).expect("valid unit"),
        chunk_log2: 11,
        spacing_log2: 7,
        floor: 0,
        label: 1,
        layers: if layers {
            vec![(120, 2), (25, 3)]
        } else {
            Vec::new()
        },
    };
    TerrainWorld::new(layout, example_noise()).expect("valid layout")
}

/// A banded heightfield base built as before the one-pass import: the
/// closed field imported, then each band painted with one convex column
/// per square (from the band's depth under the corners up past the
/// highest), deepest band first.
fn painted_bands(base: &bevy_chisel::terrain::TerrainBase) -> bevy_chisel::bsp::octree::Octree {
    use bevy_chisel::bsp::exact::IntPoint;
    use bevy_chisel::bsp::octree::{Octree, Tool};
    use bevy_chisel::terrain::TerrainBase;
    let TerrainBase::Heightfield {
        origin,
        size_log2,
        field,
    } = base
    else {
        panic!("a heightfield base");
    };
    let point = |c: [i64; 3]| IntPoint::from_array(c).expect("in range");
    let triangles: Vec<[IntPoint; 3]> = field
        .closed_mesh()
        .expect("valid field")
        .iter()
        .map(|t| t.map(point))
        .collect();
    let mut octree = Octree::from_triangles(
        *origin,
        *size_log2,
        &triangles,
        field.label,
        terrain_octree_config(),
    )
    .expect("closed field");
    let [nx, nz] = field.samples;
    let at = |i: u32, j: u32, y: i64| {
        [
            field.corner[0] + i64::from(i) * field.spacing,
            y,
            field.corner[2] + i64::from(j) * field.spacing,
        ]
    };
    let height = |i: u32, j: u32| field.heights[(i + j * nx) as usize];
    let mut layers = field.layers.clone();
    layers.sort_by_key(|&(depth, _)| std::cmp::Reverse(depth));
    for (depth, label) in layers {
        for j in 0..nz - 1 {
            for i in 0..nx - 1 {
                let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
                let high = corners
                    .iter()
                    .map(|&(a, b)| height(a, b))
                    .max()
                    .unwrap_or(0)
                    + 1;
                let mut points = Vec::with_capacity(8);
                for (a, b) in corners {
                    points.push(point(at(a, b, height(a, b) - depth)));
                    points.push(point(at(a, b, high)));
                }
                let column = Tool::convex_hull(&points).expect("a column");
                octree.apply(&column, Edit::Paint(label)).expect("paint");
            }
        }
    }
    octree
}

/// The `world` example's landscape.
fn example_noise() -> bevy_chisel::terrain::ValueNoise {
    use bevy_chisel::terrain::{NoiseOctave, ValueNoise};
    let octave = |cell, amplitude, seed| NoiseOctave {
        cell,
        amplitude,
        seed,
    };
    ValueNoise {
        base: 100,
        octaves: vec![octave(24, 650, 1), octave(6, 180, 2)],
    }
}

/// A focus's path: a polyline through waypoints (metres, x and z), walked
/// at constant speed and held at its end.
struct Tour {
    points: Vec<(f32, f32)>,
}

impl Tour {
    /// `line`: 100 km along x at z = 10 m; `loop`: around the square
    /// `[0, extent]²`; `lawnmower`: across it in `lanes` lanes, turning at
    /// the ends.
    fn new(name: &str, extent: f32, lanes: usize) -> Self {
        let points = match name {
            "line" => vec![(0.0, 10.0), (100_000.0, 10.0)],
            "loop" => vec![
                (0.0, 0.0),
                (extent, 0.0),
                (extent, extent),
                (0.0, extent),
                (0.0, 0.0),
            ],
            "lawnmower" => (0..lanes)
                .flat_map(|lane| {
                    let z = extent * (lane as f32 + 0.5) / lanes as f32;
                    if lane % 2 == 0 {
                        [(0.0, z), (extent, z)]
                    } else {
                        [(extent, z), (0.0, z)]
                    }
                })
                .collect(),
            other => panic!("CHISEL_BENCH_TOUR: no tour {other:?} (line, loop, lawnmower)"),
        };
        Self { points }
    }

    fn length(&self) -> f32 {
        self.points
            .windows(2)
            .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
            .sum()
    }

    /// The point `distance` metres along the path.
    fn at(&self, distance: f32) -> (f32, f32) {
        let mut left = distance.max(0.0);
        for w in self.points.windows(2) {
            let leg = (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1);
            if left <= leg && leg > 0.0 {
                let t = left / leg;
                return (
                    w[0].0 + t * (w[1].0 - w[0].0),
                    w[0].1 + t * (w[1].1 - w[0].1),
                );
            }
            left -= leg;
        }
        *self.points.last().expect("a tour has points")
    }
}

/// The process's peak resident memory in MiB (`VmHWM`), 0 where unknown.
fn peak_resident_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            status.lines().find_map(|line| {
                let kib = line.strip_prefix("VmHWM:")?.trim().strip_suffix("kB")?;
                kib.trim().parse::<f64>().ok()
            })
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

fn streaming_a_world() {
    use bevy::transform::TransformPlugin;
    use bevy_chisel::terrain::{
        ChunkCoord, StreamSettings, TerrainFocus, TerrainWorld, WorldCarve, WorldSource,
    };

    let chunks: i64 = env_or("CHISEL_BENCH_CHUNKS", 16);
    let side = (chunks as f64).sqrt().ceil() as i64;
    let mut figures = serde_json::Map::new();
    // CHISEL_BENCH_CHUNKS=0 leaves out the chunk builds one by one.
    if chunks > 0 {
        for layers in [false, true] {
            let world = world_of_the_example(layers);
            let mut times = Vec::new();
            let (mut bsp_bytes, mut leaves, mut file_bytes) = (0usize, 0usize, 0usize);
            for k in 0..chunks {
                let coord = ChunkCoord {
                    x: k % side,
                    z: k / side,
                };
                let start = Instant::now();
                let terrain = world.generate_chunk(coord).expect("chunk builds");
                times.push(start.elapsed());
                let stats = terrain.octree().stats();
                bsp_bytes += stats.bsp_bytes;
                leaves += stats.leaves;
                file_bytes += terrain.to_bytes().len();
            }
            times.sort_unstable();
            let n = chunks as usize;
            let tag = if layers { "with_bands" } else { "no_bands" };
            println!(
                "chunk build ({tag}), one thread, {chunks} chunks: median {:.1} ms, p90 {:.1} ms; \
             per chunk {} leaves, {} BSP bytes, {} file bytes",
                percentile(&times, 0.5),
                percentile(&times, 0.9),
                leaves / n,
                bsp_bytes / n,
                file_bytes / n
            );
            figures.insert(
                format!("build_median_ms_{tag}"),
                percentile(&times, 0.5).into(),
            );
            figures.insert(
                format!("build_p90_ms_{tag}"),
                percentile(&times, 0.9).into(),
            );
            figures.insert(format!("bsp_bytes_per_chunk_{tag}"), (bsp_bytes / n).into());
            figures.insert(
                format!("file_bytes_per_chunk_{tag}"),
                (file_bytes / n).into(),
            );
        }

        // The banded base build against the construction it replaced (the
        // closed field imported, then each band painted with one convex column
        // per square, deepest first), alternating chunk by chunk in this run;
        // the two must give the same exact volume per material.
        let banded = world_of_the_example(true);
        let noise = example_noise();
        let (mut layered, mut painted) = (Vec::new(), Vec::new());
        for k in 0..chunks {
            let coord = ChunkCoord {
                x: k % side,
                z: k / side,
            };
            let base = banded
                .layout()
                .chunk_base(&noise, coord)
                .expect("chunk base");
            let time_layered = |times: &mut Vec<Duration>| {
                let start = Instant::now();
                let octree = base.build(terrain_octree_config()).expect("layered build");
                times.push(start.elapsed());
                octree
            };
            let time_painted = |times: &mut Vec<Duration>| {
                let start = Instant::now();
                let octree = painted_bands(&base);
                times.push(start.elapsed());
                octree
            };
            let (a, b) = if k % 2 == 0 {
                let a = time_layered(&mut layered);
                (a, time_painted(&mut painted))
            } else {
                let b = time_painted(&mut painted);
                (time_layered(&mut layered), b)
            };
            let nonzero = |o: &bevy_chisel::bsp::octree::Octree| -> Vec<_> {
                o.exact_volumes()
                    .into_iter()
                    .filter(|(_, v)| !v.is_zero())
                    .collect()
            };
            assert_eq!(nonzero(&a), nonzero(&b), "chunk {coord:?}: same materials");
        }
        layered.sort_unstable();
        painted.sort_unstable();
        println!(
            "banded base build, {chunks} chunks alternating: one-pass layered import median {:.1} ms \
         (p90 {:.1}), painted bands median {:.1} ms (p90 {:.1}), ratio {:.2}",
            percentile(&layered, 0.5),
            percentile(&layered, 0.9),
            percentile(&painted, 0.5),
            percentile(&painted, 0.9),
            percentile(&painted, 0.5) / percentile(&layered, 0.5)
        );
        figures.insert(
            "base_median_ms_layered".into(),
            percentile(&layered, 0.5).into(),
        );
        figures.insert(
            "base_median_ms_painted".into(),
            percentile(&painted, 0.5).into(),
        );
    }

    // An app streaming the banded world around a focus touring it at
    // CHISEL_BENCH_SPEED m/s (default 50), frames paced at 60 per second,
    // blasting a crater every CHISEL_BENCH_CRATER_EVERY metres (default 6;
    // 0 for none) 14 m ahead, with render meshes built (no renderer). The
    // tour (CHISEL_BENCH_TOUR): `line` (default) along x; `loop` around a
    // square of side CHISEL_BENCH_WORLD_M metres (default 4000) from the
    // origin; `lawnmower` across that square in CHISEL_BENCH_LANES lanes
    // (default 4). CHISEL_BENCH_FRAMES (default 600; 0: the whole tour).
    // Time to first frame runs from before the app is made to the first
    // frame with the focus's chunks built and meshed; peak memory is the
    // process's peak resident set (VmHWM) at the end.
    let speed: f32 = env_or("CHISEL_BENCH_SPEED", 50.0);
    let crater_every: f32 = env_or("CHISEL_BENCH_CRATER_EVERY", 6.0);
    let tour_name: String = env_or("CHISEL_BENCH_TOUR", "line".to_string());
    let extent: f32 = env_or("CHISEL_BENCH_WORLD_M", 4000.0);
    let lanes: usize = env_or("CHISEL_BENCH_LANES", 4usize).max(1);
    let tour = Tour::new(&tour_name, extent, lanes);
    let frames: usize = match env_or("CHISEL_BENCH_FRAMES", 600usize) {
        0 => (tour.length() / speed * 60.0).ceil() as usize,
        n => n,
    };
    let app_start = Instant::now();
    let world = world_of_the_example(true)
        .with_streaming(StreamSettings {
            load_radius: 30.0,
            unload_radius: 45.0,
            max_building: 4,
        })
        .expect("valid settings");
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        TerrainPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>();
    // CHISEL_BENCH_LOD_FAR metres (default 0: none): coarse chunks out to
    // that radius beside the streamed full-detail ones.
    let lod_far: f32 = env_or("CHISEL_BENCH_LOD_FAR", 0.0);
    let world = if lod_far > 0.0 {
        let lod = bevy_chisel::terrain::WorldLod::new(bevy_chisel::terrain::LodSettings {
            far_radius: lod_far,
            ..Default::default()
        })
        .expect("valid settings");
        app.world_mut().spawn((world, lod)).id()
    } else {
        app.world_mut().spawn(world).id()
    };
    let (x0, z0) = tour.at(0.0);
    let focus = app
        .world_mut()
        .spawn((TerrainFocus, Transform::from_xyz(x0, 20.0, z0)))
        .id();
    let settled = |app: &App| {
        let w = app.world().get::<TerrainWorld>(world).expect("world");
        w.is_settled()
            && w.live_chunks().count() > 0
            && w.live_chunks()
                .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle))
    };
    while !settled(&app) && app_start.elapsed() < Duration::from_secs(600) {
        app.update();
    }
    let first = app_start.elapsed();
    let live = app
        .world()
        .get::<TerrainWorld>(world)
        .expect("world")
        .stats()
        .live;
    println!(
        "first frame: {live} chunks built and meshed {:.0} ms after app start ({:.1} chunks/s)",
        first.as_secs_f64() * 1e3,
        live as f64 / first.as_secs_f64()
    );
    let noise = example_noise();
    let mut frame_times = Vec::with_capacity(frames);
    let frame = Duration::from_secs_f64(1.0 / 60.0);
    let built_before = {
        let s = app
            .world()
            .get::<TerrainWorld>(world)
            .expect("world")
            .stats();
        s.generated + s.restored
    };
    let mut next_crater = 0.0;
    let mut craters = 0usize;
    let start = Instant::now();
    for k in 0..frames {
        let due = start + frame * k as u32;
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let flown_m = speed * k as f32 / 60.0;
        let (x, z) = tour.at(flown_m);
        {
            let mut transform = app.world_mut().get_mut::<Transform>(focus).expect("focus");
            transform.translation.x = x;
            transform.translation.z = z;
        }
        if crater_every > 0.0 && flown_m >= next_crater {
            next_crater = flown_m + crater_every;
            craters += 1;
            // On the ground 14 m ahead (the nearest sample's height).
            let (cx, cz) = tour.at(flown_m + 14.0);
            let sample = |m: f32| (m / 1.28).round() as i64;
            let ground = noise.height(sample(cx), sample(cz)) as f32 * 0.01;
            app.world_mut().write_message(WorldCarve {
                world,
                tool: CarveTool::dodecahedron(1.6, Vec3::new(cx, ground, cz)),
                edit: Edit::Subtract,
            });
        }
        let t = Instant::now();
        app.update();
        frame_times.push(t.elapsed());
    }
    let flown = start.elapsed();
    let stats = app
        .world()
        .get::<TerrainWorld>(world)
        .expect("world")
        .stats()
        .clone();
    frame_times.sort_unstable();
    let built = stats.generated + stats.restored - built_before;
    let peak_mib = peak_resident_mib();
    println!(
        "flying {:.0} m ({tour_name}) at {speed} m/s, {frames} frames at 60/s, {craters} \
         craters: main-thread update median {:.2} ms, p99 {:.2} ms, max {:.2} ms; {built} \
         chunks built ({:.1} chunks/s, {:.1} ms each on the pool); {} live, {} building, {} \
         edited chunks stored in {} bytes; peak resident memory {peak_mib:.0} MiB",
        speed * frames as f32 / 60.0,
        percentile(&frame_times, 0.5),
        percentile(&frame_times, 0.99),
        percentile(&frame_times, 1.0),
        built as f64 / flown.as_secs_f64(),
        stats.build_time.as_secs_f64() * 1e3 / (stats.generated + stats.restored).max(1) as f64,
        stats.live,
        stats.building,
        stats.stored,
        stats.stored_bytes
    );
    figures.insert("tour".into(), tour_name.clone().into());
    figures.insert("flown_m".into(), (speed * frames as f32 / 60.0).into());
    figures.insert("craters".into(), craters.into());
    figures.insert("peak_rss_mib".into(), peak_mib.into());
    figures.insert("first_frame_ms".into(), (first.as_secs_f64() * 1e3).into());
    figures.insert("first_fill_chunks".into(), live.into());
    figures.insert(
        "frame_median_ms".into(),
        percentile(&frame_times, 0.5).into(),
    );
    figures.insert("frame_p99_ms".into(), percentile(&frame_times, 0.99).into());
    figures.insert("chunks_built".into(), built.into());
    figures.insert(
        "chunks_per_s".into(),
        (built as f64 / flown.as_secs_f64()).into(),
    );
    figures.insert("stored_chunks".into(), stats.stored.into());
    figures.insert("stored_bytes".into(), stats.stored_bytes.into());
    json_line("streaming_a_world", serde_json::Value::Object(figures));
}

/// Bytes of a mesh's vertex and index data.
fn mesh_bytes(mesh: &Mesh) -> usize {
    let indices = mesh.indices().map_or(0, |i| i.len() * 4);
    mesh.count_vertices() * mesh.get_vertex_size() as usize + indices
}

fn lod_of_a_world() {
    use bevy::transform::TransformPlugin;
    use bevy_chisel::terrain::WorldSource;
    use bevy_chisel::terrain::world::lod_mesh::{edited_pyramid, source_pyramid};
    use bevy_chisel::terrain::{
        ChunkCoord, LodMesh, LodSettings, StreamSettings, TerrainFocus, TerrainWorld, WorldCarve,
        WorldLod,
    };

    let far: f32 = env_or("CHISEL_BENCH_FAR", 320.0);
    let chunks: i64 = env_or("CHISEL_BENCH_CHUNKS", 16);
    let mut figures = serde_json::Map::new();

    // Building coarse chunks, one thread: every level of an unedited
    // chunk from the source, and of a chunk with a crater from its octree.
    let world = world_of_the_example(true);
    let layout = world.layout().clone();
    let noise = example_noise();
    let (mut source_times, mut edited_times) = (Vec::new(), Vec::new());
    let levels = usize::from(layout.chunk_log2 - layout.spacing_log2);
    let mut errors = vec![0.0f64; levels];
    let mut level_triangles = vec![0usize; levels];
    let mut edited_triangles = vec![0usize; levels];
    let mut edited_errors = vec![0.0f32; levels];
    let side = (chunks as f64).sqrt().ceil() as i64;
    for k in 0..chunks {
        let coord = ChunkCoord {
            x: k % side,
            z: k / side,
        };
        let start = Instant::now();
        let pyramid = source_pyramid(&layout, &noise, coord).expect("builds");
        source_times.push(start.elapsed());
        for (l, level) in pyramid.levels.iter().enumerate() {
            errors[l] += f64::from(level.error) / chunks as f64;
            level_triangles[l] += level.triangles;
        }
        let mut terrain = world.generate_chunk(coord).expect("builds");
        let (cx, cz) = (coord.x as f32 * 20.48 + 10.0, coord.z as f32 * 20.48 + 10.0);
        let ground = noise.height((cx / 1.28).round() as i64, (cz / 1.28).round() as i64) as f32;
        let tool = CarveTool::dodecahedron(1.6, Vec3::new(cx, ground * 0.01, cz))
            .to_grid(&layout.quantization)
            .expect("on the grid");
        terrain.apply_now(&tool, Edit::Subtract).expect("carves");
        let start = Instant::now();
        let pyramid = edited_pyramid(
            &layout,
            &noise,
            coord,
            terrain.octree(),
            terrain.state_hash(),
        )
        .expect("builds");
        edited_times.push(start.elapsed());
        for (l, level) in pyramid.levels.iter().enumerate() {
            edited_triangles[l] += level.triangles;
            edited_errors[l] = level.error;
        }
    }
    source_times.sort_unstable();
    edited_times.sort_unstable();
    let n = chunks as usize;
    println!(
        "coarse chunk build, one thread, {chunks} chunks, all {levels} levels: from the source \
         median {:.3} ms; with a crater, from its octree, median {:.1} ms",
        percentile(&source_times, 0.5),
        percentile(&edited_times, 0.5),
    );
    for l in 0..levels {
        println!(
            "level {}: unedited {} triangles (skirts included), mean error {:.3} m; edited {} \
             triangles, error bound {:.3} m",
            l + 1,
            level_triangles[l] / n,
            errors[l],
            edited_triangles[l] / n,
            edited_errors[l]
        );
    }
    figures.insert(
        "coarse_build_median_ms_source".into(),
        percentile(&source_times, 0.5).into(),
    );
    figures.insert(
        "coarse_build_median_ms_edited".into(),
        percentile(&edited_times, 0.5).into(),
    );
    figures.insert(
        "level_triangles_unedited".into(),
        level_triangles
            .iter()
            .map(|t| t / n)
            .collect::<Vec<_>>()
            .into(),
    );
    figures.insert("level_mean_error_m".into(), errors.clone().into());

    // The view: an app streaming the banded world (load 30 m, unload 45 m)
    // around a focus flying at 50 m/s for 300 frames with a crater every
    // 6 m, then settled; without and with coarse chunks out to `far`.
    for with_lod in [false, true] {
        let world = world_of_the_example(true)
            .with_streaming(StreamSettings {
                load_radius: 30.0,
                unload_radius: 45.0,
                max_building: 4,
            })
            .expect("valid settings");
        let mut app = App::new();
        app.add_plugins((
            MinimalPlugins,
            TransformPlugin,
            AssetPlugin::default(),
            TerrainPlugin,
        ))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>();
        let world = if with_lod {
            let lod = WorldLod::new(LodSettings {
                far_radius: far,
                ..LodSettings::default()
            })
            .expect("valid settings");
            app.world_mut().spawn((world, lod)).id()
        } else {
            app.world_mut().spawn(world).id()
        };
        let focus = app
            .world_mut()
            .spawn((TerrainFocus, Transform::from_xyz(0.0, 20.0, 10.0)))
            .id();
        let settled = |app: &App| {
            let w = app.world().get::<TerrainWorld>(world).expect("world");
            w.is_settled()
                && w.live_chunks().count() > 0
                && w.live_chunks()
                    .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle))
                && app
                    .world()
                    .get::<WorldLod>(world)
                    .is_none_or(WorldLod::is_settled)
        };
        let start = Instant::now();
        while !settled(&app) && start.elapsed() < Duration::from_secs(600) {
            app.update();
        }
        let first = start.elapsed();
        let frame = Duration::from_secs_f64(1.0 / 60.0);
        let mut frame_times = Vec::new();
        let mut next_crater = 0.0;
        let start = Instant::now();
        for k in 0..300 {
            let due = start + frame * k as u32;
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
            let x = 50.0 * k as f32 / 60.0;
            app.world_mut()
                .get_mut::<Transform>(focus)
                .expect("focus")
                .translation
                .x = x;
            if x >= next_crater {
                next_crater = x + 6.0;
                let ground = noise.height(((x + 14.0) / 1.28).round() as i64, 8) as f32 * 0.01;
                app.world_mut().write_message(WorldCarve {
                    world,
                    tool: CarveTool::dodecahedron(1.6, Vec3::new(x + 14.0, ground, 10.24)),
                    edit: Edit::Subtract,
                });
            }
            let t = Instant::now();
            app.update();
            frame_times.push(t.elapsed());
        }
        let start = Instant::now();
        while !settled(&app) && start.elapsed() < Duration::from_secs(600) {
            app.update();
        }
        frame_times.sort_unstable();
        // What is drawn: the live chunks' cells and the coarse chunks.
        let live: Vec<Entity> = app
            .world()
            .get::<TerrainWorld>(world)
            .expect("world")
            .live_chunks()
            .map(|(_, e)| e)
            .collect();
        let mut full_handles = Vec::new();
        for &e in &live {
            let terrain = app.world().get::<Terrain>(e).expect("terrain");
            for (_, cells) in terrain.cells() {
                for cell in cells {
                    if let Some(mesh) = app.world().get::<Mesh3d>(cell) {
                        full_handles.push(mesh.0.clone());
                    }
                }
            }
        }
        let mut query = app.world_mut().query::<(&LodMesh, &Mesh3d)>();
        let coarse_handles: Vec<Handle<Mesh>> =
            query.iter(app.world()).map(|(_, m)| m.0.clone()).collect();
        let meshes = app.world().resource::<Assets<Mesh>>();
        let count = |handles: &[Handle<Mesh>]| {
            handles.iter().fold((0usize, 0usize), |(t, b), h| {
                let mesh = meshes.get(h).expect("mesh");
                (
                    t + mesh.indices().map_or(0, |i| i.len() / 3),
                    b + mesh_bytes(mesh),
                )
            })
        };
        let (full_tris, full_bytes) = count(&full_handles);
        let (coarse_tris, coarse_bytes) = count(&coarse_handles);
        let lod = app
            .world()
            .get::<WorldLod>(world)
            .map(|l| l.stats().clone());
        let tag = if with_lod { "with_lod" } else { "without_lod" };
        println!(
            "{tag}: first fill {:.0} ms; flying 250 m: main-thread update median {:.2} ms, p99 \
             {:.2} ms; then {} full chunks, {full_tris} triangles, {:.1} MB of mesh data; coarse \
             {} chunks {:?}, {coarse_tris} triangles, {:.2} MB",
            first.as_secs_f64() * 1e3,
            percentile(&frame_times, 0.5),
            percentile(&frame_times, 0.99),
            live.len(),
            full_bytes as f64 / 1e6,
            lod.as_ref()
                .map_or(0, |l| l.drawn_per_level.iter().sum::<usize>()),
            lod.as_ref().map(|l| l.drawn_per_level.clone()),
            coarse_bytes as f64 / 1e6,
        );
        if with_lod {
            // Full detail out to the far radius instead: every chunk
            // within it at the mean of the live chunks measured here.
            let chunk = 20.48f64;
            let mut within = 0usize;
            let span = (f64::from(far) / chunk).ceil() as i64 + 1;
            let fx = 250.0f64;
            let (cx0, cz0) = ((fx / chunk).floor() as i64, (10.0 / chunk).floor() as i64);
            for x in cx0 - span..=cx0 + span {
                for z in cz0 - span..=cz0 + span {
                    let gap = |p: f64, c: i64| {
                        let (lo, hi) = (c as f64 * chunk, (c + 1) as f64 * chunk);
                        (lo - p).max(p - hi).max(0.0)
                    };
                    if gap(fx, x).hypot(gap(10.0, z)) <= f64::from(far) {
                        within += 1;
                    }
                }
            }
            let per = |v: usize| v as f64 / live.len().max(1) as f64;
            println!(
                "full detail out to {far} m instead: {within} chunks, about {:.0} triangles and \
                 {:.0} MB of mesh data (at {:.0} triangles, {:.2} MB per live chunk)",
                per(full_tris) * within as f64,
                per(full_bytes) * within as f64 / 1e6,
                per(full_tris),
                per(full_bytes) / 1e6
            );
            figures.insert("full_to_far_chunks".into(), within.into());
            figures.insert(
                "full_to_far_triangles".into(),
                (per(full_tris) * within as f64).into(),
            );
        }
        figures.insert(format!("{tag}_full_triangles"), full_tris.into());
        figures.insert(format!("{tag}_coarse_triangles"), coarse_tris.into());
        figures.insert(format!("{tag}_full_bytes"), full_bytes.into());
        figures.insert(format!("{tag}_coarse_bytes"), coarse_bytes.into());
        figures.insert(
            format!("{tag}_frame_median_ms"),
            percentile(&frame_times, 0.5).into(),
        );
        figures.insert(
            format!("{tag}_frame_p99_ms"),
            percentile(&frame_times, 0.99).into(),
        );
    }
    json_line(
        "terrain::lod_of_a_world",
        serde_json::Value::Object(figures),
    );
}
