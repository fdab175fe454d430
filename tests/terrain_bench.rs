//! Crater carves on a 256 m × 256 m terrain at 1 mm units: time to apply a
//! radius-2 m dodecahedron and re-mesh the cells it changed, as the plugin
//! does off the main thread. Ignored by default (it takes a while); run
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
