//! Streamed worlds: chunk builds of the `world` example's landscape, the
//! banded base built in one pass against painting its bands, an app
//! streaming chunks around a touring focus (`streaming_a_world`), and
//! level of detail (`lod_of_a_world`). See the crate docs for the knobs.

use super::*;
use bevy_chisel::terrain::{LodSettings, StreamSettings, TerrainFocus, TerrainWorld, WorldLod};

/// The `world` example's landscape and layout: a 1 cm grid, 20.48 m
/// chunks, samples 1.28 m apart, with (or without) grass and dirt bands.
pub(super) fn world_of_the_example(layers: bool) -> bevy_chisel::terrain::TerrainWorld {
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
pub(super) fn example_noise() -> bevy_chisel::terrain::ValueNoise {
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

pub(super) fn streaming_a_world() {
    use bevy_chisel::terrain::{ChunkCoord, WorldCarve, WorldSource};

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
    // The plugin's steps timed per frame (spans); see `frame_steps`.
    let timed = frame_steps::install();
    let app_start = Instant::now();
    // CHISEL_BENCH_LOD_FAR metres (default 0: none): coarse chunks out to
    // that radius beside the streamed full-detail ones.
    let lod_far: f32 = env_or("CHISEL_BENCH_LOD_FAR", 0.0);
    let (x0, z0) = tour.at(0.0);
    let (mut app, world, focus) = streaming_app(lod_far, Vec3::new(x0, 20.0, z0));
    let executor = executor_of_the_bench(&mut app);
    while !full_detail_settled(&app, world) && app_start.elapsed() < Duration::from_secs(600) {
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
    let mut records = Vec::with_capacity(frames);
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
        frame_steps::take_frame();
        let threads_before = frame_steps::threads();
        let mark = frame_steps::Mark::now();
        app.update();
        let update = mark.since();
        let mut steps = frame_steps::take_frame();
        steps.extend(frame_steps::thread_steps(
            &threads_before,
            &frame_steps::threads(),
        ));
        frame_times.push(update.wall);
        records.push(frame_steps::FrameRecord { update, steps });
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
    if timed {
        // CHISEL_BENCH_SLOW_SHARE: the share of slowest frames broken down
        // (default 0.01).
        frame_steps::report(&records, env_or("CHISEL_BENCH_SLOW_SHARE", 0.01), 12);
    }
    figures.insert("executor".into(), executor.into());
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

/// An app streaming the banded world of the `world` example (load 30 m,
/// unload 45 m, 4 builds at a time) with render meshes but no renderer,
/// coarse chunks out to `lod_far` metres when that is positive, and a
/// focus at `focus_at`: the app, the world and the focus.
fn streaming_app(lod_far: f32, focus_at: Vec3) -> (App, Entity, Entity) {
    use bevy::transform::TransformPlugin;
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
    let world = if lod_far > 0.0 {
        let lod = WorldLod::new(LodSettings {
            far_radius: lod_far,
            ..LodSettings::default()
        })
        .expect("valid settings");
        app.world_mut().spawn((world, lod)).id()
    } else {
        app.world_mut().spawn(world).id()
    };
    let focus = app
        .world_mut()
        .spawn((TerrainFocus, Transform::from_translation(focus_at)))
        .id();
    (app, world, focus)
}

/// CHISEL_BENCH_EXECUTOR=single: every schedule of `app` on the main
/// thread (Bevy's single-threaded executor) rather than handing systems to
/// the compute pool's threads; `multi` (the default) leaves them. Returns
/// the executor's name.
fn executor_of_the_bench(app: &mut App) -> String {
    let executor: String = env_or("CHISEL_BENCH_EXECUTOR", "multi".to_string());
    if executor == "single" {
        use bevy::ecs::schedule::{Schedules, SingleThreadedExecutor};
        for (_, schedule) in app.world_mut().resource_mut::<Schedules>().iter_mut() {
            schedule.set_executor(SingleThreadedExecutor::new());
        }
    }
    executor
}

/// Whether the world's full-detail chunks around the focus are all built
/// and meshed.
fn full_detail_settled(app: &App, world: Entity) -> bool {
    let w = app.world().get::<TerrainWorld>(world).expect("world");
    w.is_settled()
        && w.live_chunks().count() > 0
        && w.live_chunks()
            .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle))
}

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
