//! Debris across chunk borders (`debris_across_chunk_borders`): what the
//! detach across chunk borders costs the frames that run it, in the
//! `world` example's layout (1 cm grid, 20.48 m chunks) with the four
//! chunks around the corner x = z = 20.48 m live.
//!
//! Two cases. *Craters*: radius-2 m dodecahedra blasted on the chunk
//! borders around the corner, whose search stops at the first anchored
//! cell. *Blocks*: a block of ground around the corner cut loose (a slot
//! under it, then its four walls), at the default limits (none), whose
//! last cut makes the search explore the whole block across the four
//! chunks. For each it reports the time the frames spent in the pass
//! (span `chisel::world::detach_across_borders`, on whatever thread ran
//! the system) and in searches on the async compute pool (span
//! `chisel::world::debris_search`), summed per carve and largest in one
//! frame, and for the blocks the same search run inline on clones of the
//! chunks (as a frame that searched on its own thread would), median of
//! five. `CHISEL_BENCH_BLOCKS` (metres, comma-separated; default
//! `6,12,20`) sets the blocks' edges.

use super::world::{terrain_app, world_of_the_example};
use super::*;
use bevy_chisel::bsp::octree::{CellKey, ChunkOctree, DebrisLimits, detach_across_chunks};
use bevy_chisel::terrain::world::chunk_debris;
use bevy_chisel::terrain::{
    StreamSettings, TerrainDebris, TerrainFocus, TerrainWorld, WorldCarve, WorldSource, apply_carve,
};

/// The pass's span, run by the frame.
const PASS: &str = "chisel::world::detach_across_borders";
/// The search's span, where it runs off the frame.
const SEARCH: &str = "chisel::world::debris_search";
/// The corner of the four live chunks, in grid units.
const CORNER: i64 = 2048;

/// The world's debris searches started and dropped as stale so far.
fn searches(app: &App, world: Entity) -> (u64, u64) {
    let stats = app
        .world()
        .get::<TerrainWorld>(world)
        .expect("the world")
        .stats();
    (stats.debris_searches, stats.debris_searches_dropped)
}

/// An app with the example's world (no bands) and a focus over the
/// corner that keeps exactly the four chunks around it live, settled.
fn corner_app() -> (App, Entity) {
    let (mut app, world) = corner_world_app();
    settle(&mut app, world);
    assert_eq!(the_world(&app, world).live_chunks().count(), 4);
    (app, world)
}

/// [`corner_app`] before any frame ran (nothing built yet).
pub(super) fn corner_world_app() -> (App, Entity) {
    let world = world_of_the_example(false)
        .with_streaming(StreamSettings {
            load_radius: 15.0,
            unload_radius: 18.0,
            max_building: 4,
        })
        .expect("valid settings");
    let mut app = terrain_app();
    let world = app.world_mut().spawn(world).id();
    app.world_mut().spawn((
        TerrainFocus,
        Transform::from_translation(Vec3::new(20.48, 10.0, 20.48)),
    ));
    (app, world)
}

fn the_world(app: &App, world: Entity) -> &TerrainWorld {
    app.world().get::<TerrainWorld>(world).expect("world")
}

/// Whether nothing builds, no carve or search waits, and every live chunk
/// is idle.
fn idle(app: &App, world: Entity) -> bool {
    let w = the_world(app, world);
    w.is_settled()
        && w.live_chunks()
            .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle))
}

/// A frame's pass (wall and CPU time of the thread that ran it) and
/// search (wall) times.
type Frame = [Duration; 3];
/// Indices into a [`Frame`].
const PASS_WALL: usize = 0;
const PASS_CPU: usize = 1;
const SEARCH_WALL: usize = 2;

/// Runs frames until the world stays idle for five frames; the pass's and
/// the search's times of each frame, frames without either left out.
fn settle(app: &mut App, world: Entity) -> Vec<Frame> {
    let mut frames = Vec::new();
    let mut calm = 0;
    for _ in 0..100_000 {
        app.update();
        let steps = frame_steps::take_frame();
        let pass = steps.get(PASS).copied().unwrap_or_default();
        let search = steps.get(SEARCH).map_or(Duration::ZERO, |t| t.wall);
        if pass.wall + search > Duration::ZERO {
            frames.push([pass.wall, pass.cpu, search]);
        }
        calm = if idle(app, world) { calm + 1 } else { 0 };
        if calm == 5 {
            return frames;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("the world did not settle");
}

/// A box tool with grid corners `min` and `max` (1 cm units).
fn cuboid(min: [i64; 3], max: [i64; 3]) -> CarveTool {
    let m = |v: i64| v as f32 * 0.01;
    let lo = Vec3::new(m(min[0]), m(min[1]), m(min[2]));
    let hi = Vec3::new(m(max[0]), m(max[1]), m(max[2]));
    CarveTool::new(
        CarveShape::Cuboid {
            half_size: (hi - lo) / 2.0,
        },
        Transform::from_translation((lo + hi) / 2.0),
    )
}

/// Carves `tool` out of the world and settles: the frames' pass and
/// search times.
fn carve(app: &mut App, world: Entity, tool: CarveTool) -> Vec<Frame> {
    app.world_mut().write_message(WorldCarve {
        world,
        tool,
        edit: Edit::Subtract,
    });
    settle(app, world)
}

/// The sum and the largest frame of `frames`' time `k` ([`PASS_WALL`],
/// [`PASS_CPU`], [`SEARCH_WALL`]), in milliseconds.
fn sum_and_max(frames: &[Frame], k: usize) -> (f64, f64) {
    let pick = |f: &Frame| f[k];
    let sum: Duration = frames.iter().map(pick).sum();
    let max = frames.iter().map(pick).max().unwrap_or_default();
    (sum.as_secs_f64() * 1e3, max.as_secs_f64() * 1e3)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// The search `tool` starts, run inline on clones of the live chunks as
/// they are before it: its wall time in milliseconds and the pieces and
/// convex cells it finds (the seeds are what the tool changes in each
/// chunk it reaches).
fn inline_search(app: &App, world: Entity, tool: &CarveTool) -> (f64, usize, usize) {
    let w = the_world(app, world);
    let grid = tool.to_grid(&w.layout().quantization).expect("grid tool");
    let mut chunks = Vec::new();
    let mut near: Vec<(usize, CellKey)> = Vec::new();
    for (_, entity) in w.live_chunks() {
        let terrain = app.world().get::<Terrain>(entity).expect("chunk");
        let mut octree = terrain.octree().clone();
        let config = chunk_debris(terrain.base().floor());
        if let Ok(changes) = apply_carve(&mut octree, &grid, Edit::Subtract) {
            let changes = octree
                .detach_after(&changes, &config)
                .expect("no limits")
                .changes;
            near.extend(changes.changed.iter().map(|&k| (chunks.len(), k)));
        }
        chunks.push(ChunkOctree {
            octree,
            anchors: config.anchors,
        });
    }
    let mut times = Vec::new();
    let mut found = (0, 0);
    for _ in 0..5 {
        let mut copy = chunks.clone();
        let start = Instant::now();
        let detached =
            detach_across_chunks(&mut copy, &near, DebrisLimits::default()).expect("no limits");
        times.push(start.elapsed().as_secs_f64() * 1e3);
        let cells = detached
            .pieces
            .iter()
            .flat_map(|p| &p.parts)
            .map(|p| p.piece.cells.len())
            .sum();
        found = (detached.pieces.len(), cells);
    }
    (median(times), found.0, found.1)
}

pub(super) fn debris_across_chunk_borders() {
    if !frame_steps::install() {
        println!("(a tracing subscriber is already set: nothing to time)");
        return;
    }
    let noise = super::world::example_noise();
    // Craters on the borders around the corner: on lattice samples
    // (every 1.28 m), at the surface.
    let spots: [(i64, i64); 7] = [
        (16, 16),
        (16, 12),
        (16, 20),
        (12, 16),
        (20, 16),
        (16, 14),
        (18, 16),
    ];
    let (mut app, world) = corner_app();
    let (mut pass_sum, mut pass_max, mut search_sum) = (Vec::new(), Vec::new(), Vec::new());
    let mut pass_cpu_max = Vec::new();
    for (i, j) in spots {
        let centre = Vec3::new(
            i as f32 * 1.28,
            noise.height(i, j) as f32 * 0.01,
            j as f32 * 1.28,
        );
        let tool = CarveTool::new(
            CarveShape::Dodecahedron { radius: 2.0 },
            Transform::from_translation(centre),
        );
        let frames = carve(&mut app, world, tool);
        let (sum, max) = sum_and_max(&frames, PASS_WALL);
        pass_sum.push(sum);
        pass_max.push(max);
        pass_cpu_max.push(sum_and_max(&frames, PASS_CPU).1);
        search_sum.push(sum_and_max(&frames, SEARCH_WALL).0);
    }
    println!(
        "craters: {} on the borders, pass per crater median {:.3} ms (largest frame median \
         {:.3} ms wall, {:.3} ms CPU), search off the frame median {:.3} ms",
        spots.len(),
        median(pass_sum.clone()),
        median(pass_max.clone()),
        median(pass_cpu_max.clone()),
        median(search_sum.clone()),
    );
    let mut figures = serde_json::Map::new();
    figures.insert("crater_pass_ms".into(), json!(median(pass_sum)));
    figures.insert("crater_pass_max_frame_ms".into(), json!(median(pass_max)));
    figures.insert(
        "crater_pass_max_frame_cpu_ms".into(),
        json!(median(pass_cpu_max)),
    );
    figures.insert("crater_search_ms".into(), json!(median(search_sum)));
    let edges: String = env_or("CHISEL_BENCH_BLOCKS", "6,12,20".to_string());
    for edge in edges
        .split(',')
        .filter_map(|e| e.trim().parse::<f64>().ok())
    {
        let half = (edge * 50.0).round() as i64;
        let (lo, hi) = (CORNER - half, CORNER + half);
        let (bottom, top, wall) = (40, 1000, 20);
        let (mut app, world) = corner_app();
        // The slot under the block, then three walls: still held.
        let mut cuts = vec![
            cuboid(
                [lo - wall, bottom, lo - wall],
                [hi + wall, bottom + wall, hi + wall],
            ),
            cuboid([lo - wall, bottom, lo - wall], [lo, top, hi + wall]),
            cuboid([hi, bottom, lo - wall], [hi + wall, top, hi + wall]),
            cuboid([lo, bottom, lo - wall], [hi, top, lo]),
        ];
        let last = cuboid([lo, bottom, hi], [hi, top, hi + wall]);
        let mut held_max: f64 = 0.0;
        for cut in cuts.drain(..) {
            held_max = held_max.max(sum_and_max(&carve(&mut app, world, cut), PASS_WALL).1);
        }
        let (inline, pieces, cells) = inline_search(&app, world, &last);
        let before = searches(&app, world);
        let frames = carve(&mut app, world, last);
        let after = searches(&app, world);
        let (started, dropped) = (after.0 - before.0, after.1 - before.1);
        let fell = app
            .world_mut()
            .query::<&TerrainDebris>()
            .iter(app.world())
            .count();
        let (pass, pass_frame) = sum_and_max(&frames, PASS_WALL);
        let (_, pass_frame_cpu) = sum_and_max(&frames, PASS_CPU);
        let (search, _) = sum_and_max(&frames, SEARCH_WALL);
        println!(
            "block {edge} m: {pieces} piece(s), {cells} cells, {fell} fell; inline search \
             {inline:.2} ms; pass {pass:.3} ms in {} frame(s), largest frame {pass_frame:.3} ms \
             ({pass_frame_cpu:.3} ms CPU); \
             search off the frame {search:.2} ms ({started} search(es), {dropped} dropped as \
             stale); cuts before it: largest frame {held_max:.3} ms",
            frames.len(),
        );
        let key = |name: &str| format!("block_{edge}m_{name}");
        figures.insert(key("inline_search_ms"), json!(inline));
        figures.insert(key("cells"), json!(cells));
        figures.insert(key("pass_ms"), json!(pass));
        figures.insert(key("pass_max_frame_ms"), json!(pass_frame));
        figures.insert(key("pass_max_frame_cpu_ms"), json!(pass_frame_cpu));
        figures.insert(key("search_ms"), json!(search));
        figures.insert(key("held_cuts_max_frame_ms"), json!(held_max));
        figures.insert(key("searches"), json!(started));
        figures.insert(key("searches_dropped"), json!(dropped));
    }
    json_line(
        "terrain::debris_across_chunk_borders",
        serde_json::Value::Object(figures),
    );
}
