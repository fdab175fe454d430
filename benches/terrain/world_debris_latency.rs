//! Latency of debris across chunk borders (`debris_latency_across_borders`):
//! frames and milliseconds from the carve that cuts a block loose over a
//! chunk border to the frame its [`TerrainDebris`] is spawned, in the
//! `world` example's layout (1 cm grid, 20.48 m chunks) with the four
//! chunks around the corner x = z = 20.48 m live, at 60 frames per second
//! (each frame padded to 16.7 ms).
//!
//! Three cases, in a fresh app each, with the same blocks: *idle* (nothing
//! else happens), *streaming* (a second focus 100 m away moves one chunk
//! every four frames, so that chunks keep building) and *carving* (the
//! second focus stands still and a radius-1 m crater is carved in its
//! chunks every frame). Each block is 2 m wide, over the border x =
//! 20.48 m or z = 20.48 m: a slot under it and three walls are cut first
//! (it stays held), then the last wall frees it. For each case it reports
//! the median and largest number of frames and milliseconds to the spawn,
//! and the median frames from the cut to the first search of the world
//! that starts after it (the chunks' carve jobs, and whatever holds the
//! search back), over `CHISEL_BENCH_REPS` blocks (default 6, at most 12). It also prints the number of threads of the async compute
//! pool, which runs the chunk builds, the carve jobs and the search.

use super::corner_latency::{Activity, CornerApp, MOST_FRAMES, median, most};
use super::*;
use bevy::tasks::AsyncComputeTaskPool;
use bevy_chisel::terrain::TerrainDebris;

/// The corner of the four live chunks, in grid units.
const CORNER: i64 = 2048;
/// Half the blocks' edge, the walls' thickness and the slot's height and
/// the blocks' bottom and top, in grid units.
const HALF: i64 = 100;
const WALL: i64 = 20;
const BOTTOM: i64 = 40;
const TOP: i64 = 1000;

/// The debris pieces spawned so far.
fn debris(corner: &mut CornerApp) -> usize {
    let app = &mut corner.app;
    (app.world_mut().query::<&TerrainDebris>())
        .iter(app.world())
        .count()
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

/// The cuts that free the block centred at grid `(x, z)`: the slot under
/// it and three walls (it stays held), then the last wall.
fn block_cuts(x: i64, z: i64) -> (Vec<CarveTool>, CarveTool) {
    let (x0, x1, z0, z1) = (x - HALF, x + HALF, z - HALF, z + HALF);
    let held = vec![
        cuboid(
            [x0 - WALL, BOTTOM, z0 - WALL],
            [x1 + WALL, BOTTOM + WALL, z1 + WALL],
        ),
        cuboid([x0 - WALL, BOTTOM, z0 - WALL], [x0, TOP, z1 + WALL]),
        cuboid([x1, BOTTOM, z0 - WALL], [x1 + WALL, TOP, z1 + WALL]),
        cuboid([x0, BOTTOM, z0 - WALL], [x1, TOP, z0]),
    ];
    (held, cuboid([x0, BOTTOM, z1], [x1, TOP, z1 + WALL]))
}

/// The blocks' centres: over the border x = 20.48 m, then over z = 20.48 m,
/// away from the corner and from each other.
fn spots() -> Vec<(i64, i64)> {
    let along = [400, 1000, 1600, 2600, 3200, 3700];
    let mut spots = Vec::new();
    for (a, b) in along.iter().zip(along.iter().rev()) {
        spots.push((CORNER, *a));
        spots.push((*b, CORNER));
    }
    spots
}

/// One block's latency: frames and milliseconds from its last cut to its
/// debris, and frames to the start of the search.
struct Fell {
    frames: u64,
    ms: f64,
    to_search: u64,
}

fn fall_one(corner: &mut CornerApp, (x, z): (i64, i64)) -> Fell {
    let (held, last) = block_cuts(x, z);
    for cut in held {
        corner.cut(cut);
        corner.wait_quiet();
    }
    let before = debris(corner);
    let searches = corner.the_world().stats().debris_searches;
    corner.cut(last);
    let start = Instant::now();
    let mut to_search = None;
    for frames in 1..=MOST_FRAMES {
        corner.frame();
        if to_search.is_none() && corner.the_world().stats().debris_searches > searches {
            to_search = Some(frames);
        }
        if debris(corner) > before {
            let fell = Fell {
                frames,
                ms: start.elapsed().as_secs_f64() * 1e3,
                to_search: to_search.unwrap_or(frames),
            };
            // Let the rest of the cut settle before the next block.
            corner.wait_quiet();
            return fell;
        }
    }
    panic!("the block at ({x}, {z}) did not fall");
}

pub(super) fn debris_latency_across_borders() {
    let reps: usize = env_or("CHISEL_BENCH_REPS", 6).clamp(1, 12);
    let mut figures = serde_json::Map::new();
    for activity in [Activity::Idle, Activity::Streaming, Activity::Carving] {
        let mut corner = CornerApp::new(activity);
        if activity == Activity::Idle {
            let threads = AsyncComputeTaskPool::get().thread_num();
            println!("async compute pool: {threads} thread(s)");
            figures.insert("async_compute_threads".into(), json!(threads));
        }
        let built = corner.the_world().stats().generated;
        let fell: Vec<Fell> = (spots().into_iter().take(reps))
            .map(|spot| fall_one(&mut corner, spot))
            .collect();
        let built = corner.the_world().stats().generated - built;
        let frames: Vec<f64> = fell.iter().map(|f| f.frames as f64).collect();
        let ms: Vec<f64> = fell.iter().map(|f| f.ms).collect();
        let to_search: Vec<f64> = fell.iter().map(|f| f.to_search as f64).collect();
        let name = activity.name();
        println!(
            "{name}: {reps} blocks, cut to debris median {} frames ({:.1} ms), largest {} \
             frames ({:.1} ms); cut to search median {} frames; {built} chunks built meanwhile \
             (frames {frames:?})",
            median(frames.clone()),
            median(ms.clone()),
            most(&frames),
            most(&ms),
            median(to_search.clone()),
        );
        let key = |k: &str| format!("{name}_{k}");
        figures.insert(key("frames_median"), json!(median(frames.clone())));
        figures.insert(key("frames_max"), json!(most(&frames)));
        figures.insert(key("ms_median"), json!(median(ms.clone())));
        figures.insert(key("ms_max"), json!(most(&ms)));
        figures.insert(key("to_search_frames_median"), json!(median(to_search)));
        figures.insert(key("chunks_built"), json!(built));
    }
    json_line(
        "terrain::debris_latency_across_borders",
        serde_json::Value::Object(figures),
    );
}
