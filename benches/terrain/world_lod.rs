//! Level of detail of a streamed world (`lod_of_a_world`): coarse chunks
//! of the `world` example's landscape out to a far radius around a
//! touring focus, their builds, meshes and the main thread's share. See
//! the crate docs for the knobs.

use super::world::{
    example_noise, executor_of_the_bench, full_detail_settled, streaming_app, world_of_the_example,
};
use super::*;
use bevy_chisel::terrain::{TerrainWorld, WorldLod};

/// Bytes of a mesh's vertex and index data.
fn mesh_bytes(mesh: &Mesh) -> usize {
    let indices = mesh.indices().map_or(0, |i| i.len() * 4);
    mesh.count_vertices() * mesh.get_vertex_size() as usize + indices
}

pub(super) fn lod_of_a_world() {
    use bevy_chisel::terrain::WorldSource;
    use bevy_chisel::terrain::world::lod_mesh::{edited_pyramid, source_pyramid};
    use bevy_chisel::terrain::{ChunkCoord, LodMesh, WorldCarve};

    let far: f32 = env_or("CHISEL_BENCH_FAR", 320.0);
    let chunks: i64 = env_or("CHISEL_BENCH_CHUNKS", 16);
    // CHISEL_BENCH_STEPS (default 1; 0: off): time the plugin's steps
    // (its spans) and the main schedules. Off, no span is recorded: the
    // frames as an app without a tracing subscriber runs them.
    let timed = env_or("CHISEL_BENCH_STEPS", 1u32) != 0 && frame_steps::install();
    // The CPU time `update_lod` (its span) took in the frame just run.
    let lod_step_time = |steps: &BTreeMap<&'static str, frame_steps::Times>| {
        steps
            .get("chisel::lod::update")
            .map_or(Duration::ZERO, |t| t.cpu)
    };
    // CHISEL_BENCH_SCHEDULES (default 1; 0: off): time each of the main
    // schedules (`First` .. `Last`) on the main thread.
    let time_schedules = timed && env_or("CHISEL_BENCH_SCHEDULES", 1u32) != 0;
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
        let (mut app, world, focus) =
            streaming_app(if with_lod { far } else { 0.0 }, Vec3::new(0.0, 20.0, 10.0));
        if time_schedules {
            frame_steps::time_schedules(&mut app);
        }
        let executor = executor_of_the_bench(&mut app);
        let settled = |app: &App| {
            full_detail_settled(app, world)
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
        println!(
            "{} schedules:",
            if with_lod { "with_lod" } else { "without_lod" }
        );
        frame_steps::print_main_thread_systems(&app);
        let frame = Duration::from_secs_f64(1.0 / 60.0);
        let mut frame_times = Vec::new();
        let mut lod_steps = Vec::new();
        // Per frame, the steps on the main thread (`update`: the whole of
        // `App::update`) and on every thread (`threads::GROUP`: each
        // group's CPU time).
        let (mut main_frames, mut all_frames) = (Vec::new(), Vec::new());
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
            frame_steps::take_frame();
            frame_steps::take_main_frame();
            let threads_before = frame_steps::threads();
            let mark = frame_steps::Mark::now();
            app.update();
            let update = mark.since();
            let mut main_steps = frame_steps::take_main_frame();
            let mut steps = frame_steps::take_frame();
            steps.extend(frame_steps::thread_steps(
                &threads_before,
                &frame_steps::threads(),
            ));
            main_steps.insert("update", update);
            frame_times.push(update.wall);
            lod_steps.push(lod_step_time(&steps));
            main_frames.push(main_steps);
            all_frames.push(steps);
        }
        let start = Instant::now();
        while !settled(&app) && start.elapsed() < Duration::from_secs(600) {
            app.update();
        }
        frame_times.sort_unstable();
        lod_steps.sort_unstable();
        let tag = if with_lod { "with_lod" } else { "without_lod" };
        let floor = Duration::from_micros(5);
        frame_steps::print_medians(
            &format!("{tag} ({executor} executor), flying: on the main thread"),
            &main_frames,
            floor,
        );
        frame_steps::print_medians(
            &format!("{tag} ({executor} executor), flying: every thread"),
            &all_frames,
            floor,
        );
        let median_of =
            |frames: &[BTreeMap<&'static str, frame_steps::Times>], name: &str, cpu: bool| {
                let mut v: Vec<Duration> = frames
                    .iter()
                    .map(|f| {
                        f.get(name)
                            .map_or(Duration::ZERO, |t| if cpu { t.cpu } else { t.wall })
                    })
                    .collect();
                v.sort_unstable();
                percentile(&v, 0.5)
            };
        let mut updates: Vec<frame_steps::Times> = main_frames
            .iter()
            .filter_map(|f| f.get("update").copied())
            .collect();
        updates.sort_by_key(|t| t.wall);
        let middle = updates.len() / 2;
        let near_median = &updates[middle.saturating_sub(15)..(middle + 15).min(updates.len())];
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let mean_of = |f: &dyn Fn(&frame_steps::Times) -> f64| {
            near_median.iter().map(f).sum::<f64>() / near_median.len().max(1) as f64
        };
        println!(
            "{tag} ({executor} executor), flying: the 30 frames around the median update, mean: \
             wall {:.3} ms = main-thread CPU {:.3} + runqueue wait {:.3} + asleep {:.3}; put on a \
             core {:.1} times",
            mean_of(&|t| ms(t.wall)),
            mean_of(&|t| ms(t.cpu)),
            mean_of(&|t| ms(t.wait)),
            mean_of(&|t| ms(t.wall) - ms(t.cpu) - ms(t.wait)),
            mean_of(&|t| t.slices as f64),
        );
        figures.insert(
            format!("{tag}_main_slices_near_median"),
            mean_of(&|t| t.slices as f64).into(),
        );
        figures.insert(
            format!("{tag}_main_cpu_median_ms"),
            median_of(&main_frames, "update", true).into(),
        );
        figures.insert(
            format!("{tag}_compute_cpu_median_ms"),
            median_of(&all_frames, "threads::compute", true).into(),
        );
        // Then 120 frames with the focus standing still.
        let mut still_lod_steps = Vec::new();
        let start = Instant::now();
        for k in 0..120 {
            let due = start + frame * k as u32;
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
            frame_steps::take_frame();
            app.update();
            still_lod_steps.push(lod_step_time(&frame_steps::take_frame()));
        }
        still_lod_steps.sort_unstable();
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
        println!(
            "{tag}: first fill {:.0} ms; flying 250 m: main-thread update median {:.2} ms, p99 \
             {:.2} ms (level of detail's step: CPU median {:.3} ms, p99 {:.3} ms; standing still \
             {:.3} / {:.3} ms); then {} full chunks, {full_tris} triangles, {:.1} MB of mesh data; \
             coarse {} chunks {:?}, {coarse_tris} triangles, {:.2} MB",
            first.as_secs_f64() * 1e3,
            percentile(&frame_times, 0.5),
            percentile(&frame_times, 0.99),
            percentile(&lod_steps, 0.5),
            percentile(&lod_steps, 0.99),
            percentile(&still_lod_steps, 0.5),
            percentile(&still_lod_steps, 0.99),
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
        for (name, times) in [
            ("lod_step", &lod_steps),
            ("still_lod_step", &still_lod_steps),
        ] {
            figures.insert(
                format!("{tag}_{name}_median_ms"),
                percentile(times, 0.5).into(),
            );
            figures.insert(
                format!("{tag}_{name}_p99_ms"),
                percentile(times, 0.99).into(),
            );
        }
    }
    json_line(
        "terrain::lod_of_a_world",
        serde_json::Value::Object(figures),
    );
}
