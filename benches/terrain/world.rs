//! Streamed worlds: chunk builds of the `world` example's landscape, the
//! banded base built in one pass against painting its bands, and an app
//! streaming chunks around a touring focus (`streaming_a_world`); the
//! apps and checks `world_lod.rs` shares. See the crate docs for the
//! knobs.

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

/// A headless app with the terrain plugin: no renderer, but the mesh and
/// material assets its chunks make.
pub(super) fn terrain_app() -> App {
    use bevy::transform::TransformPlugin;
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        TerrainPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>();
    app
}

/// An app streaming the banded world of the `world` example (load 30 m,
/// unload 45 m, 4 builds at a time) with render meshes but no renderer,
/// coarse chunks out to `lod_far` metres when that is positive, and a
/// focus at `focus_at`: the app, the world and the focus.
pub(super) fn streaming_app(lod_far: f32, focus_at: Vec3) -> (App, Entity, Entity) {
    let world = world_of_the_example(true)
        .with_streaming(StreamSettings {
            load_radius: 30.0,
            unload_radius: 45.0,
            max_building: 4,
        })
        .expect("valid settings");
    let mut app = terrain_app();
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
pub(super) fn executor_of_the_bench(app: &mut App) -> String {
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
pub(super) fn full_detail_settled(app: &App, world: Entity) -> bool {
    let w = app.world().get::<TerrainWorld>(world).expect("world");
    w.is_settled()
        && w.live_chunks().count() > 0
        && w.live_chunks()
            .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle))
}
