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

use super::world_debris::corner_world_app;
use super::*;
use bevy::tasks::AsyncComputeTaskPool;
use bevy_chisel::terrain::{TerrainDebris, TerrainFocus, TerrainWorld, WorldCarve};

/// One frame at 60 frames per second.
const FRAME: Duration = Duration::from_micros(16_667);
/// The corner of the four live chunks, in grid units.
const CORNER: i64 = 2048;
/// Half the blocks' edge, the walls' thickness and the slot's height and
/// the blocks' bottom and top, in grid units.
const HALF: i64 = 100;
const WALL: i64 = 20;
const BOTTOM: i64 = 40;
const TOP: i64 = 1000;
/// Where the second focus stands (metres, z), out of reach of the corner.
const FAR_Z: f32 = 112.64;
/// Frames between the streaming focus's steps of one chunk.
const STEP_FRAMES: u64 = 4;
/// The most frames a block may take to fall before the bench gives up.
const MOST_FRAMES: u64 = 3_000;

/// What else happens while the blocks are cut.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Case {
    Idle,
    Streaming,
    Carving,
}

impl Case {
    fn name(self) -> &'static str {
        match self {
            Case::Idle => "idle",
            Case::Streaming => "streaming",
            Case::Carving => "carving",
        }
    }
}

/// A headless app with the four chunks around the corner live, the second
/// focus and the frame count.
struct Bench {
    app: App,
    world: Entity,
    far_focus: Entity,
    case: Case,
    frame: u64,
    next: Box<dyn FnMut() -> f64>,
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
        let mut bench = Self {
            app,
            world,
            far_focus,
            case,
            frame: 0,
            next: Box::new(uniform(0x5eed_cafe)),
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

    /// Whether the four chunks around the corner are idle and no search
    /// for debris runs.
    fn corner_quiet(&self) -> bool {
        let w = self.the_world();
        !w.debris_searching()
            && (0..4).all(|k| {
                let coord = bevy_chisel::terrain::ChunkCoord { x: k % 2, z: k / 2 };
                w.chunk_entity(coord).is_some_and(|e| self.chunk_idle(e))
            })
    }

    fn debris(&mut self) -> usize {
        let app = &mut self.app;
        app.world_mut()
            .query::<&TerrainDebris>()
            .iter(app.world())
            .count()
    }

    /// One frame of the case at 60 frames per second: the second focus
    /// steps or a crater is carved by it, then the app updates and the
    /// frame is padded to 16.7 ms.
    fn frame(&mut self) {
        let start = Instant::now();
        match self.case {
            Case::Idle => {}
            Case::Streaming => {
                let x = 10.24 + 20.48 * (self.frame / STEP_FRAMES) as f32;
                let mut transform = (self.app.world_mut())
                    .get_mut::<Transform>(self.far_focus)
                    .expect("focus");
                transform.translation.x = x;
            }
            Case::Carving => {
                let next = &mut self.next;
                let (x, z) = (40.96 * next() as f32, 81.92 + 40.96 * next() as f32);
                let centre = Vec3::new(x, 2.0 + 6.0 * next() as f32, z);
                let tool = CarveTool::new(
                    CarveShape::Dodecahedron { radius: 1.0 },
                    Transform::from_translation(centre),
                );
                self.app.world_mut().write_message(WorldCarve {
                    world: self.world,
                    tool,
                    edit: Edit::Subtract,
                });
            }
        }
        self.app.update();
        self.frame += 1;
        if let Some(rest) = FRAME.checked_sub(start.elapsed()) {
            std::thread::sleep(rest);
        }
    }

    /// Carves `tool` and runs frames until the corner is quiet for three.
    fn cut_and_wait(&mut self, tool: CarveTool) {
        self.cut(tool);
        self.wait_quiet();
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

    fn cut(&mut self, tool: CarveTool) {
        self.app.world_mut().write_message(WorldCarve {
            world: self.world,
            tool,
            edit: Edit::Subtract,
        });
    }
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

fn fall_one(bench: &mut Bench, (x, z): (i64, i64)) -> Fell {
    let (held, last) = block_cuts(x, z);
    for cut in held {
        bench.cut_and_wait(cut);
    }
    let before = bench.debris();
    let searches = bench.the_world().stats().debris_searches;
    bench.cut(last);
    let start = Instant::now();
    let mut to_search = None;
    for frames in 1..=MOST_FRAMES {
        bench.frame();
        if to_search.is_none() && bench.the_world().stats().debris_searches > searches {
            to_search = Some(frames);
        }
        if bench.debris() > before {
            let fell = Fell {
                frames,
                ms: start.elapsed().as_secs_f64() * 1e3,
                to_search: to_search.unwrap_or(frames),
            };
            // Let the rest of the cut settle before the next block.
            bench.wait_quiet();
            return fell;
        }
    }
    panic!("the block at ({x}, {z}) did not fall");
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

pub(super) fn debris_latency_across_borders() {
    let reps: usize = env_or("CHISEL_BENCH_REPS", 6).clamp(1, 12);
    let mut figures = serde_json::Map::new();
    for case in [Case::Idle, Case::Streaming, Case::Carving] {
        let mut bench = Bench::new(case);
        if case == Case::Idle {
            let threads = AsyncComputeTaskPool::get().thread_num();
            println!("async compute pool: {threads} thread(s)");
            figures.insert("async_compute_threads".into(), json!(threads));
        }
        let built = bench.the_world().stats().generated;
        let fell: Vec<Fell> = (spots().into_iter().take(reps))
            .map(|spot| fall_one(&mut bench, spot))
            .collect();
        let built = bench.the_world().stats().generated - built;
        let frames: Vec<f64> = fell.iter().map(|f| f.frames as f64).collect();
        let ms: Vec<f64> = fell.iter().map(|f| f.ms).collect();
        let to_search: Vec<f64> = fell.iter().map(|f| f.to_search as f64).collect();
        let name = case.name();
        let most = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
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
