//! Samples one scene repeatedly on one thread, for profilers (callgrind,
//! `perf stat`): `cargo bench -p chisel_quadric --bench sample_profile --
//! SCENE DIVISOR [REPEATS]`, where `SCENE` is a shipped scene name or
//! `sphere` (radius 50 in a bounding sphere of 60; the divisor is then the
//! splat radius itself), and the splat radius is the bounding radius ÷
//! `DIVISOR`. Prints the counts of paper 2, Table 2. Under a profiler, run
//! the binary that `cargo bench -p chisel_quadric --bench sample_profile
//! --no-run` builds, with `--bench SCENE DIVISOR [REPEATS]`.
//!
//! `SAMPLE_THREADS=N` runs it on `N` threads (CPU time then sums them).
//! With the environment variable `SAMPLE_HASH` set it also prints a hash
//! of the sample set (every field of every sample), to check that a change
//! keeps the samples bit-identical, and a hash of their geometry (position
//! and patch, as stored in `f32`). With `SAMPLE_NORMALS` set it also times
//! what a reader pays for the normals, which samples do not store
//! (`SampleSet::normal_of` of every sample, CPU time).
//!
//! It measures only with `--bench` among its arguments (`cargo bench`
//! passes it): `cargo test --all-targets` runs it without, and it then
//! prints one line and exits.

#![allow(clippy::cast_precision_loss)]

use chisel_quadric::{BoundingSphere, SampleOptions, Scene, sample};
use glam::DVec3;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !args.iter().any(|a| a == "--bench") {
        println!("sample_profile: not run as a benchmark (no --bench argument); skipped");
        return;
    }
    // The positional arguments, after cargo's flags are set aside.
    let args: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let name = args.first().copied().unwrap_or("machine80");
    let divisor: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(100.0);
    let repeats: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let (scene, sphere, radius) = if name == "sphere" {
        let scene = Scene::from_ron(
            r#"Scene(primitives: [(name: "ball", shape: Sphere(center: (0, 0, 0), radius: 50))], root: Ref("ball"))"#,
        )
        .expect("a one-sphere scene");
        let sphere = BoundingSphere::new(DVec3::ZERO, 60.0).expect("sphere");
        (scene, sphere, divisor)
    } else {
        let path = format!(
            "{}/../assets/scenes/{name}.quadric.ron",
            env!("CARGO_MANIFEST_DIR")
        );
        let scene = Scene::load(&path).expect("shipped scene");
        let sphere = scene.bounds.expect("shipped scenes give bounds");
        let radius = sphere.radius / divisor;
        (scene, sphere, radius)
    };
    let dnf = scene.dnf().expect("normal form");
    let options = SampleOptions::new(radius, sphere).expect("options");
    let threads: usize = std::env::var("SAMPLE_THREADS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let mut times = Vec::with_capacity(repeats);
    let mut cpu = Vec::with_capacity(repeats);
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        let before = cpu_seconds();
        let set = pool.install(|| sample(&dnf, &options)).expect("sampling");
        cpu.push(cpu_seconds() - before);
        times.push(start.elapsed().as_secs_f64());
        last = Some(set);
    }
    cpu.sort_by(f64::total_cmp);
    times.sort_by(f64::total_cmp);
    let set = last.expect("one run");
    let median = times[times.len() / 2];
    let rate = set.samples.len() as f64 / median;
    println!(
        "{name} r = {radius:.4}: {} quadrics, {} products, {} samples, {} distance queries, \
         {} regions, median {:.3} ms of {} (CPU {:.3} ms), {:.3} M samples/s (CPU {:.3} M/s)",
        dnf.quadrics().len(),
        dnf.products().len(),
        set.samples.len(),
        set.stats.distance_queries,
        set.stats.regions,
        median * 1e3,
        times.len(),
        cpu[cpu.len() / 2] * 1e3,
        rate * 1e-6,
        set.samples.len() as f64 / cpu[cpu.len() / 2] * 1e-6
    );
    println!("{:?}", set.stats);
    // The splats' squares, the fragment count's CPU-side proxy.
    let squares: f64 = set
        .samples
        .iter()
        .map(|s| 4.0 * f64::from(s.radius) * f64::from(s.radius))
        .sum();
    println!("splat squares sum (2r)^2 = {squares:.1}");
    if std::env::var_os("SAMPLE_NORMALS").is_some() {
        // Twenty passes: one is below the resolution of the CPU clock.
        const PASSES: u32 = 20;
        let before = cpu_seconds();
        let mut sum = DVec3::ZERO;
        for _ in 0..PASSES {
            sum += set
                .samples
                .iter()
                .map(|s| set.normal_of(&dnf, s))
                .sum::<DVec3>();
        }
        let seconds = (cpu_seconds() - before) / f64::from(PASSES);
        println!(
            "normals derived in CPU {:.3} ms per pass ({:.1} ns each; sum {sum:.3})",
            seconds * 1e3,
            seconds * 1e9 / set.samples.len().max(1) as f64
        );
    }
    // Off by default: the hash would add to a profiler's instruction count.
    if std::env::var_os("SAMPLE_HASH").is_some() {
        println!("sample set hash {:016x}", sample_hash(&set.samples));
        println!("geometry hash {:016x}", geometry_hash(&set.samples));
    }
}

/// A hash of every field of every sample, in order (the literal,
/// product and quadric are those of the patch) (FNV-1a over 64-bit
/// words): equal hashes mean bit-identical sample sets, in practice.
/// Printed when the environment variable `SAMPLE_HASH` is set.
fn sample_hash(samples: &[chisel_quadric::Sample]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325_u64;
    let mut eat = |bits: u64| {
        h = (h ^ bits).wrapping_mul(0x0100_0000_01b3);
    };
    for s in samples {
        eat_geometry(&mut eat, s);
        for bound in [s.radius, s.cell.x, s.cell.y] {
            eat(u64::from(bound.to_bits()));
        }
    }
    h
}

/// A hash of the position and patch of every sample,
/// in order (FNV-1a, as [`sample_hash`]): the fields that the bounds'
/// widening for the `f32` rounding leaves alone.
fn geometry_hash(samples: &[chisel_quadric::Sample]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325_u64;
    let mut eat = |bits: u64| {
        h = (h ^ bits).wrapping_mul(0x0100_0000_01b3);
    };
    for s in samples {
        eat_geometry(&mut eat, s);
    }
    h
}

fn eat_geometry(eat: &mut impl FnMut(u64), s: &chisel_quadric::Sample) {
    for c in s.position.to_array() {
        eat(u64::from(c.to_bits()));
    }
    eat(u64::from(s.patch));
}

/// CPU time of all threads of this process, seconds (Linux schedstat;
/// `0` elsewhere): unlike wall time, it does not count time spent waiting
/// for a core on a loaded machine.
fn cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    let mut ns = 0u64;
    for task in tasks.flatten() {
        let stat = std::fs::read_to_string(task.path().join("schedstat")).unwrap_or_default();
        ns += stat
            .split_whitespace()
            .next()
            .and_then(|s| s.parse::<u64>().ok())
            .unwrap_or(0);
    }
    ns as f64 * 1e-9
}
