//! Terrain benchmarks at 1 mm units. Crater carves on a 256 m × 256 m
//! terrain: time to apply a radius-2 m dodecahedron and re-mesh the cells
//! it changed, as the plugin does off the main thread. Terrain files: time
//! to load a carved quarry against replaying its carves. Ignored by default
//! (they take a while); run
//!
//! `cargo test --release -p bevy_chisel --test terrain_bench -- --ignored --nocapture`
//!
//! The release profile keeps the kernel's overflow checks and debug
//! assertions (see the root `Cargo.toml`), so these figures are an upper
//! bound of the bench profile's.

use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::mesh::cell_meshes;
use bevy_chisel::terrain::{CarveTool, Terrain, apply_carve};
use rayon::prelude::*;

fn percentile(sorted: &[Duration], p: f64) -> f64 {
    let k = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[k].as_secs_f64() * 1e3
}

#[test]
#[ignore = "benchmark"]
fn crater_carves_on_a_large_terrain() {
    let carves: usize = std::env::var("CHISEL_BENCH_CARVES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000);
    let grid = Quantization::new(0.001, [0.0; 3]).expect("valid unit");
    let terrain = Terrain::from_box(
        grid,
        Vec3::new(0.0, -20.0, 0.0),
        Vec3::new(256.0, 0.0, 256.0),
        1,
    )
    .expect("valid box");
    let mut octree = terrain.octree().clone();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut apply, mut total) = (Vec::new(), Vec::new());
    let mut by_decile = vec![Vec::new(); 10];
    for k in 0..carves {
        let centre = Vec3::new(
            (4.0 + 248.0 * next()) as f32,
            -next() as f32,
            (4.0 + 248.0 * next()) as f32,
        );
        let tool = CarveTool::new(
            bevy_chisel::terrain::CarveShape::Dodecahedron { radius: 2.0 },
            Transform::from_translation(centre).with_rotation(Quat::from_rotation_y(
                (std::f64::consts::TAU * next()) as f32,
            )),
        )
        .to_grid(&grid)
        .expect("on the grid");
        let start = Instant::now();
        let changes = apply_carve(&mut octree, &tool, Edit::Subtract).expect("valid carve");
        let applied = start.elapsed();
        let keys: Vec<_> = changes
            .changed
            .iter()
            .chain(&changes.removed)
            .copied()
            .collect();
        let triangles: usize = keys
            .par_iter()
            .map(|&key| {
                cell_meshes(&octree, &grid, key)
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
        "{carves} crater carves (r = 2 m, 1 mm grid, 256 m × 256 m), {} threads",
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
    for (d, mut times) in by_decile.into_iter().enumerate() {
        times.sort();
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
}

/// Loading a saved terrain (the octree snapshot and undo history) against
/// rebuilding it from its base and replaying its journal, which is what
/// loading cost before terrain files stored the octree. The quarry
/// example's terrain, blasted `CHISEL_BENCH_CARVES` times (default 1000)
/// with radius-2 m dodecahedra at the surface, every tenth carve a heap of
/// added dirt.
///
/// `cargo test --release -p bevy_chisel --test terrain_bench load -- --ignored --nocapture`
#[test]
#[ignore = "benchmark"]
fn loading_a_saved_terrain_against_replaying_its_carves() {
    use bevy::math::Ray3d;
    use bevy_chisel::bsp::octree::Octree;
    use bevy_chisel::terrain::{CarveShape, HeightLayer, Heightfield};

    let carves: usize = std::env::var("CHISEL_BENCH_CARVES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000);
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
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f32 / (1u64 << 53) as f32
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
}
