//! Saving a streamed world (`saving_a_world`): what a save costs the frame
//! that asks for it. The `world` example's layout (1 cm grid, 20.48 m
//! chunks) with a block of 4 × 4, then 8 × 8, live chunks around the
//! focus, each carved once (a radius-2.5 m dodecahedron at its centre);
//! then, alternately, the synchronous `TerrainWorld::save` into a new
//! folder and a `SaveWorld` into another new folder (so that both write
//! every edited chunk). Reported, medians of `CHISEL_BENCH_RUNS` (9) runs:
//! the synchronous save's wall time; the wall time of the frame that reads
//! the request and of an idle frame before it; the wall and CPU time of
//! the request system (span `chisel::world::save_worlds`) in that frame;
//! and the time until `WorldSaved` (the task on the I/O pool, files
//! synced). Every file is synced to disk in both, so the figures depend on
//! the disk.

use std::path::PathBuf;

use super::world::{terrain_app, world_of_the_example};
use super::*;
use bevy_chisel::terrain::{
    SaveWorld, StreamSettings, TerrainFocus, TerrainWorld, WorldCarve, WorldSaveFailed, WorldSaved,
};

/// The request system's span.
const SAVE_SYSTEM: &str = "chisel::world::save_worlds";
/// A chunk's edge (m).
const CHUNK: f32 = 20.48;

/// The answers to the saves so far.
#[derive(Resource, Default)]
struct Answers {
    saved: Vec<WorldSaved>,
    failed: Vec<WorldSaveFailed>,
}

fn collect_answers(
    mut saved: MessageReader<WorldSaved>,
    mut failed: MessageReader<WorldSaveFailed>,
    mut answers: ResMut<Answers>,
) {
    answers.saved.extend(saved.read().cloned());
    answers.failed.extend(failed.read().cloned());
}

fn the_world(app: &App, world: Entity) -> &TerrainWorld {
    app.world().get::<TerrainWorld>(world).expect("world")
}

/// Runs frames until the world stays settled, with every live chunk idle,
/// for five frames.
fn settle(app: &mut App, world: Entity) {
    let mut calm = 0;
    for _ in 0..100_000 {
        app.update();
        let w = the_world(app, world);
        let idle = w.is_settled()
            && (w.live_chunks())
                .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle));
        calm = if idle { calm + 1 } else { 0 };
        if calm == 5 {
            return;
        }
    }
    panic!("the world did not settle");
}

/// An app whose focus keeps the `side` × `side` chunks around the origin
/// live, each carved once, settled.
fn carved_block(side: i64) -> (App, Entity) {
    let half = CHUNK * side as f32 / 2.0;
    let world = world_of_the_example(false)
        .with_streaming(StreamSettings {
            load_radius: half + 1.0,
            unload_radius: half * 1.5 + 2.0,
            max_building: 4,
        })
        .expect("valid settings");
    let mut app = terrain_app();
    app.init_resource::<Answers>()
        .add_systems(Last, collect_answers);
    let world = app.world_mut().spawn(world).id();
    app.world_mut()
        .spawn((TerrainFocus, Transform::from_xyz(0.0, 10.0, 0.0)));
    settle(&mut app, world);
    for x in -side / 2..side / 2 {
        for z in -side / 2..side / 2 {
            let centre = Vec3::new((x as f32 + 0.5) * CHUNK, 2.0, (z as f32 + 0.5) * CHUNK);
            app.world_mut().write_message(WorldCarve {
                world,
                tool: CarveTool::dodecahedron(2.5, centre),
                edit: Edit::Subtract,
            });
        }
    }
    settle(&mut app, world);
    (app, world)
}

fn folder(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "bevy_chisel-bench-save-{tag}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn median_ms(mut v: Vec<Duration>) -> f64 {
    v.sort_unstable();
    v.get(v.len() / 2).map_or(0.0, |d| d.as_secs_f64() * 1e3)
}

pub(super) fn saving_a_world() {
    // The layer may be installed already by another measurement.
    frame_steps::install();
    let runs = env_or("CHISEL_BENCH_RUNS", 9usize).max(1);
    for side in [4i64, 8] {
        let (mut app, world) = carved_block(side);
        let edited = {
            let w = the_world(&app, world);
            (w.live_chunks())
                .filter(|&(c, e)| {
                    app.world()
                        .get::<Terrain>(e)
                        .is_some_and(|t| w.chunk_edited(c, t))
                })
                .count()
        };
        assert_eq!(
            edited,
            (side * side) as usize,
            "every chunk of the block carved"
        );
        let (mut sync, mut idle, mut request, mut whole) = (vec![], vec![], vec![], vec![]);
        let (mut system_wall, mut system_cpu) = (vec![], vec![]);
        let mut bytes = 0;
        for run in 0..runs {
            let dir = folder(&format!("sync-{side}-{run}"));
            let t = Instant::now();
            let written = the_world(&app, world)
                .save(&dir, |e| app.world().get::<Terrain>(e))
                .expect("saves");
            sync.push(t.elapsed());
            assert_eq!(written.len(), edited);
            let _ = std::fs::remove_dir_all(&dir);

            frame_steps::take_frame();
            let t = Instant::now();
            app.update();
            idle.push(t.elapsed());

            let dir = folder(&format!("background-{side}-{run}"));
            let answered = app.world().resource::<Answers>().saved.len();
            app.world_mut().write_message(SaveWorld {
                world,
                folder: dir.clone(),
            });
            frame_steps::take_frame();
            let t = Instant::now();
            app.update();
            request.push(t.elapsed());
            let step = frame_steps::take_frame()
                .get(SAVE_SYSTEM)
                .copied()
                .unwrap_or_default();
            system_wall.push(step.wall);
            system_cpu.push(step.cpu);
            loop {
                let answers = app.world().resource::<Answers>();
                assert!(answers.failed.is_empty(), "{:?}", answers.failed);
                if let Some(done) = answers.saved.get(answered) {
                    assert_eq!(done.written.len(), edited);
                    bytes = done.bytes;
                    break;
                }
                std::thread::sleep(Duration::from_micros(200));
                app.update();
            }
            whole.push(t.elapsed());
            let _ = std::fs::remove_dir_all(&dir);
        }
        let figures = serde_json::json!({
            "edited_chunks": edited,
            "bytes": bytes,
            "runs": runs,
            "sync_save_ms": median_ms(sync),
            "idle_frame_ms": median_ms(idle),
            "request_frame_ms": median_ms(request),
            "request_system_wall_ms": median_ms(system_wall),
            "request_system_cpu_ms": median_ms(system_cpu),
            "background_save_ms": median_ms(whole),
        });
        println!(
            "{edited} edited chunks ({bytes} bytes): synchronous save {:.2} ms; the request frame \
             {:.2} ms (idle frame {:.2} ms), its system {:.3} ms wall / {:.3} ms CPU; saved in \
             the background after {:.1} ms",
            figures["sync_save_ms"].as_f64().unwrap_or_default(),
            figures["request_frame_ms"].as_f64().unwrap_or_default(),
            figures["idle_frame_ms"].as_f64().unwrap_or_default(),
            figures["request_system_wall_ms"]
                .as_f64()
                .unwrap_or_default(),
            figures["request_system_cpu_ms"]
                .as_f64()
                .unwrap_or_default(),
            figures["background_save_ms"].as_f64().unwrap_or_default(),
        );
        json_line("terrain::saving_a_world", figures);
    }
}
