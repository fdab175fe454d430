//! Latency of a crater in a streamed world (`carve_latency_while_streaming`):
//! frames and milliseconds from a [`WorldCarve`] to the frame its chunk's
//! [`CarveApplied`] is read (the chunk's job finished and every mesh it
//! changed in place), in the `world` example's layout (1 cm grid,
//! 20.48 m chunks) with the four chunks around the corner x = z = 20.48 m
//! live, at 60 frames per second (each frame padded to 16.7 ms).
//!
//! Two cases, in a fresh app each, with the same craters: *idle* (nothing
//! else happens) and *streaming* (a second focus 100 m away moves one
//! chunk every four frames, so that chunks keep building). Each crater is
//! a radius-1 m dodecahedron inside one of the four chunks, 4 m or more
//! from its borders; the next is carved once the corner has been quiet for
//! three frames. For each case it reports the median and largest number
//! of frames and milliseconds, over `CHISEL_BENCH_REPS` craters (default
//! 12, at most 48), and the chunks built meanwhile.

use super::corner_latency::{Activity, CornerApp, EDGE, MOST_FRAMES, median, most};
use super::*;

/// The craters' least distance to a chunk border (metres).
const MARGIN: f32 = 4.0;

/// The crater `k`: a radius-1 m dodecahedron in chunk `k % 4` of the
/// corner, `MARGIN` or more from its borders, 2 to 8 m high.
fn crater(k: usize, next: &mut impl FnMut() -> f64) -> CarveTool {
    let (cx, cz) = ((k % 2) as f32 * EDGE, ((k / 2) % 2) as f32 * EDGE);
    let span = EDGE - 2.0 * MARGIN;
    let x = cx + MARGIN + span * next() as f32;
    let z = cz + MARGIN + span * next() as f32;
    let y = 2.0 + 6.0 * next() as f32;
    CarveTool::new(
        CarveShape::Dodecahedron { radius: 1.0 },
        Transform::from_translation(Vec3::new(x, y, z)),
    )
}

/// Carves `tool` once the corner is quiet and runs frames until its carve
/// is applied: the frames and milliseconds it took.
fn carve_one(corner: &mut CornerApp, tool: CarveTool) -> (u64, f64) {
    corner.wait_quiet();
    corner.cut(tool);
    let start = Instant::now();
    for frames in 1..=MOST_FRAMES {
        if corner.frame() > 0 {
            return (frames, start.elapsed().as_secs_f64() * 1e3);
        }
    }
    panic!("a crater was not applied in {MOST_FRAMES} frames");
}

pub(super) fn carve_latency_while_streaming() {
    let reps: usize = env_or("CHISEL_BENCH_REPS", 12).clamp(1, 48);
    let mut figures = serde_json::Map::new();
    for activity in [Activity::Idle, Activity::Streaming] {
        let mut corner = CornerApp::new(activity);
        let mut next = uniform(0xc4a7_e2f0);
        let built = corner.the_world().stats().generated;
        let took: Vec<(u64, f64)> = (0..reps)
            .map(|k| {
                let tool = crater(k, &mut next);
                carve_one(&mut corner, tool)
            })
            .collect();
        let built = corner.the_world().stats().generated - built;
        let frames: Vec<f64> = took.iter().map(|t| t.0 as f64).collect();
        let ms: Vec<f64> = took.iter().map(|t| t.1).collect();
        let name = activity.name();
        println!(
            "{name}: {reps} craters, carve to meshes median {} frames ({:.1} ms), largest {} \
             frames ({:.1} ms); {built} chunks built meanwhile (frames {frames:?})",
            median(frames.clone()),
            median(ms.clone()),
            most(&frames),
            most(&ms),
        );
        let key = |k: &str| format!("{name}_{k}");
        figures.insert(key("frames_median"), json!(median(frames.clone())));
        figures.insert(key("frames_max"), json!(most(&frames)));
        figures.insert(key("ms_median"), json!(median(ms.clone())));
        figures.insert(key("ms_max"), json!(most(&ms)));
        figures.insert(key("chunks_built"), json!(built));
    }
    json_line(
        "terrain::carve_latency_while_streaming",
        serde_json::Value::Object(figures),
    );
}
