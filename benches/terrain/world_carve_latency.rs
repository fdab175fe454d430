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

use super::world_debris::corner_world_app;
use super::*;
use bevy::ecs::message::MessageCursor;
use bevy_chisel::terrain::{ChunkCoord, TerrainFocus, TerrainWorld, WorldCarve};

/// One frame at 60 frames per second.
const FRAME: Duration = Duration::from_micros(16_667);
/// Where the second focus stands (metres, z), out of reach of the corner.
const FAR_Z: f32 = 112.64;
/// Frames between the streaming focus's steps of one chunk.
const STEP_FRAMES: u64 = 4;
/// The most frames a crater may take before the bench gives up.
const MOST_FRAMES: u64 = 3_000;
/// Chunk edge and the craters' least distance to a chunk border (metres).
const EDGE: f32 = 20.48;
const MARGIN: f32 = 4.0;

/// What else happens while the craters land.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Case {
    Idle,
    Streaming,
}

impl Case {
    fn name(self) -> &'static str {
        match self {
            Case::Idle => "idle",
            Case::Streaming => "streaming",
        }
    }
}

/// A headless app with the four chunks around the corner live, the second
/// focus, the frame count and a cursor over [`CarveApplied`].
struct Bench {
    app: App,
    world: Entity,
    far_focus: Entity,
    case: Case,
    frame: u64,
    applied: MessageCursor<CarveApplied>,
}

impl Bench {
    fn new(case: Case) -> Self {
        let (mut app, world) = corner_world_app();
        let far_focus = app
            .world_mut()
            .spawn((
                TerrainFocus,
                Transform::from_translation(Vec3::new(10.24, 10.0, FAR_Z)),
            ))
            .id();
        let applied = app
            .world()
            .resource::<Messages<CarveApplied>>()
            .get_cursor_current();
        let mut bench = Self {
            app,
            world,
            far_focus,
            case,
            frame: 0,
            applied,
        };
        // Everything built, before the case's activity starts.
        for _ in 0..100_000 {
            bench.app.update();
            let w = bench.the_world();
            if w.is_settled()
                && w.live_chunks().count() > 4
                && w.live_chunks().all(|(_, e)| bench.chunk_idle(e))
            {
                return bench;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        panic!("the world did not settle");
    }

    fn the_world(&self) -> &TerrainWorld {
        self.app
            .world()
            .get::<TerrainWorld>(self.world)
            .expect("world")
    }

    fn chunk_idle(&self, entity: Entity) -> bool {
        (self.app.world().get::<Terrain>(entity)).is_some_and(Terrain::is_idle)
    }

    /// Whether the four chunks around the corner are live and idle.
    fn corner_quiet(&self) -> bool {
        let w = self.the_world();
        (0..4).all(|k| {
            let coord = ChunkCoord { x: k % 2, z: k / 2 };
            w.chunk_entity(coord).is_some_and(|e| self.chunk_idle(e))
        })
    }

    /// One frame of the case at 60 frames per second: the second focus
    /// steps, then the app updates and the frame is padded to 16.7 ms.
    /// Returns how many carves (with an edit) were applied in the frame.
    fn frame(&mut self) -> usize {
        let start = Instant::now();
        if self.case == Case::Streaming {
            let x = 10.24 + EDGE * (self.frame / STEP_FRAMES) as f32;
            let mut transform = (self.app.world_mut())
                .get_mut::<Transform>(self.far_focus)
                .expect("focus");
            transform.translation.x = x;
        }
        self.app.update();
        self.frame += 1;
        let messages = self.app.world().resource::<Messages<CarveApplied>>();
        let applied = (self.applied.read(messages))
            .filter(|a| a.edit.is_some())
            .count();
        if let Some(rest) = FRAME.checked_sub(start.elapsed()) {
            std::thread::sleep(rest);
        }
        applied
    }

    /// Runs frames until the corner is quiet for three.
    fn wait_quiet(&mut self) {
        let mut quiet = 0;
        for _ in 0..MOST_FRAMES {
            self.frame();
            quiet = if self.corner_quiet() { quiet + 1 } else { 0 };
            if quiet == 3 {
                return;
            }
        }
        panic!("the corner did not settle");
    }
}

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

/// Carves `tool` and runs frames until its carve is applied: the frames
/// and milliseconds it took.
fn carve_one(bench: &mut Bench, tool: CarveTool) -> (u64, f64) {
    bench.wait_quiet();
    let world = bench.world;
    bench.app.world_mut().write_message(WorldCarve {
        world,
        tool,
        edit: Edit::Subtract,
    });
    let start = Instant::now();
    for frames in 1..=MOST_FRAMES {
        if bench.frame() > 0 {
            return (frames, start.elapsed().as_secs_f64() * 1e3);
        }
    }
    panic!("a crater was not applied in {MOST_FRAMES} frames");
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

pub(super) fn carve_latency_while_streaming() {
    let reps: usize = env_or("CHISEL_BENCH_REPS", 12).clamp(1, 48);
    let mut figures = serde_json::Map::new();
    for case in [Case::Idle, Case::Streaming] {
        let mut bench = Bench::new(case);
        let mut next = uniform(0xc4a7_e2f0);
        let built = bench.the_world().stats().generated;
        let took: Vec<(u64, f64)> = (0..reps)
            .map(|k| {
                let tool = crater(k, &mut next);
                carve_one(&mut bench, tool)
            })
            .collect();
        let built = bench.the_world().stats().generated - built;
        let frames: Vec<f64> = took.iter().map(|t| t.0 as f64).collect();
        let ms: Vec<f64> = took.iter().map(|t| t.1).collect();
        let most = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        let name = case.name();
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
