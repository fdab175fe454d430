//! The terrain plugin's carve job without the engine: per crater, the
//! carve ([`Octree::apply_with_faces`]), the debris search
//! ([`Octree::detach_after`]) and the sealed meshes of every cell that
//! changed or whose seams did ([`SeamedMesher::update`]), timed one by one.
//! It is the kernel's share of the latency the plugin's terrain bench
//! (`crater_latency`) reports, on the same kind of terrain, and a stable
//! target for a profiler or an instruction count:
//!
//! ```sh
//! cargo bench -p chisel_bsp --bench crater_job -- 1000 [THREADS] [check] [shade]
//! cargo bench -p chisel_bsp --bench crater_job --no-run   # prints the binary's path
//! perf stat -e task-clock target/release/deps/crater_job-HASH --bench 1000
//! valgrind --tool=callgrind target/release/deps/crater_job-HASH --bench 200 1 check
//! ```
//!
//! It measures only with `--bench` among its arguments (`cargo bench`
//! passes it): `cargo test --all-targets` runs it without, and it then
//! prints one line and exits. The other arguments are positional:
//! carves (default 1000), threads (default 1), `check`.
//!
//! With `shade`, the mesher also keeps the surface around border vertices
//! ([`SeamedMesher::with_shading`]) and hands back the cells whose
//! normals that changes, as the plugin's does.
//!
//! With `check`, it also prints hashes of every sealed mesh, every debris
//! piece, the final octree and every carve's change of each material
//! (`Changes::exact_volume_change` and `Changes::volume_change`, which the
//! plugin reports; timed apart from the rest): equal hashes before and
//! after a change to the kernel mean bit-identical results.

use std::collections::hash_map::DefaultHasher;
use std::collections::{BTreeMap, BTreeSet};
use std::hash::{Hash, Hasher};
use std::time::{Duration, Instant};

use chisel_bsp::exact::IntPoint;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{
    Anchors, CellBox, CellKey, CubeSide, DebrisConfig, Detached, Edit, Octree, OctreeConfig,
    SeamedMesher, Tool,
};
use chisel_bsp::tools::dodecahedron_corners;

/// Grid units per metre.
const UNIT: f64 = 1000.0;

/// xorshift64*: a fixed stream of numbers in `[0, 1)`.
fn uniform(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A radius-2 m dodecahedron somewhere under the slab's top.
fn crater(next: &mut impl FnMut() -> f64) -> Tool {
    let centre = [4.0 + 248.0 * next(), -next(), 4.0 + 248.0 * next()];
    let (sin, cos) = (std::f64::consts::TAU * next()).sin_cos();
    let points: Vec<IntPoint> = dodecahedron_corners(2.0 / 3f64.sqrt())
        .into_iter()
        .map(|[x, y, z]| {
            let turned = [cos * x + sin * z, y, cos * z - sin * x];
            let [x, y, z] = [0, 1, 2].map(|a| ((centre[a] + turned[a]) * UNIT).round() as i64);
            IntPoint::new(x, y, z).expect("inside the grid")
        })
        .collect();
    Tool::convex_hull(&points).expect("a solid hull")
}

/// Feeds a sealed mesh's exact vertices and polygons to `state`.
fn hash_mesh(mesh: &SurfaceMesh, state: &mut impl Hasher) {
    for v in mesh.vertices() {
        v.xyz().hash(state);
        v.w().hash(state);
    }
    for p in mesh.polygons() {
        (p.plane, &p.edges, &p.corners, &p.originals).hash(state);
        (p.label, p.outside, p.on_bounds).hash(state);
    }
}

/// Feeds the debris pieces' leaves, cells, volumes and solids to `state`.
/// The meshes of [`SeamedMesher::update_shaded`]'s cells (the `check` hash
/// of a shaded run covers the meshes only, of more cells).
fn shaded(
    cells: Vec<(CellKey, Option<chisel_bsp::octree::ShadedCell>)>,
) -> Vec<(CellKey, Option<SurfaceMesh>)> {
    cells
        .into_iter()
        .map(|(key, cell)| (key, cell.map(|cell| cell.mesh)))
        .collect()
}

fn hash_debris(detached: &Detached, state: &mut impl Hasher) {
    for piece in &detached.pieces {
        (&piece.leaves, &piece.volumes, piece.solid.state_hash()).hash(state);
        for cell in &piece.cells {
            (cell.cell, cell.label, &cell.planes, &cell.volume).hash(state);
        }
    }
}

fn median(times: &mut [Duration]) -> f64 {
    times.sort_unstable();
    times[times.len() / 2].as_secs_f64() * 1e3
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !args.iter().any(|a| a == "--bench") {
        println!("crater_job: not run as a benchmark (no --bench argument); skipped");
        return;
    }
    // The positional arguments, after cargo's flags are set aside.
    let args: Vec<&String> = args.iter().filter(|a| !a.starts_with('-')).collect();
    let arg =
        |i: usize, default: usize| args.get(i).and_then(|n| n.parse().ok()).unwrap_or(default);
    let (carves, threads) = (arg(0, 1000), arg(1, 1));
    let check = args.iter().skip(2).any(|a| *a == "check");
    let shade = args.iter().skip(2).any(|a| *a == "shade");
    // As the plugin's jobs: everything on the worker pool's threads.
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(|| run(carves, check, shade));
}

fn run(carves: usize, check: bool, shade: bool) {
    let solid = CellBox {
        min: [0, -20_000, 0],
        max: [256_000, 0, 256_000],
    };
    // As the plugin's `Terrain::from_box`: a cube with a margin of an eighth.
    let margin = 256_000 / 8 + 1;
    let origin = solid.min.map(|m| m - margin);
    let size_log2 = 19;
    let config = OctreeConfig {
        max_bsp_nodes: 40,
        ..OctreeConfig::default()
    };
    let mut octree = Octree::from_box(origin, size_log2, solid, 1, config).expect("a valid box");
    let edge = 1i64 << size_log2;
    let debris = DebrisConfig {
        anchors: Anchors {
            sides: vec![CubeSide::BOTTOM],
            boxes: vec![CellBox {
                min: [origin[0], solid.min[1], origin[2]],
                max: [origin[0] + edge, solid.min[1] + 1, origin[2] + edge],
            }],
        },
        ..DebrisConfig::default()
    };
    let mut mesher = if shade {
        SeamedMesher::with_shading()
    } else {
        SeamedMesher::new()
    };
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(key, _)| key).collect();
    mesher.update(&octree, all, BTreeMap::new());

    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
    let (mut apply, mut detach, mut meshes, mut total) = (vec![], vec![], vec![], vec![]);
    let (mut volumes, mut rounded_volumes) = (Vec::new(), Vec::new());
    let mut cells = Vec::new();
    let (mut mesh_hash, mut debris_hash) = (DefaultHasher::new(), DefaultHasher::new());
    let mut volume_hash = DefaultHasher::new();
    for _ in 0..carves {
        let tool = crater(&mut next);
        let start = Instant::now();
        let before = octree.clone();
        let (changes, faces) = octree
            .apply_with_faces(&tool, Edit::Subtract)
            .expect("a valid carve");
        let applied = start.elapsed();
        let carved = octree
            .detach_after(&changes, &debris)
            .expect("no debris limit");
        let detached = start.elapsed();
        let fresh: BTreeMap<CellKey, _> = faces
            .into_iter()
            .filter(|(key, _)| {
                !carved
                    .detached
                    .pieces
                    .iter()
                    .any(|p| p.leaves.contains(key))
            })
            .collect();
        let keys: BTreeSet<CellKey> = carved
            .changes
            .changed
            .iter()
            .chain(&carved.changes.removed)
            .copied()
            .collect();
        let sealed = if shade {
            shaded(mesher.update_shaded(&octree, keys, fresh))
        } else {
            mesher.update(&octree, keys, fresh)
        };
        let done = start.elapsed();
        // What the plugin reports of each carve, timed on its own.
        let measured = Instant::now();
        let change = carved.changes.exact_volume_change(&before, &octree);
        let exact_time = measured.elapsed();
        let rounded = carved.changes.volume_change(&before, &octree);
        rounded_volumes.push(measured.elapsed() - exact_time);
        volumes.push(exact_time);
        drop(before);
        if check {
            for (key, mesh) in &sealed {
                key.hash(&mut mesh_hash);
                if let Some(mesh) = mesh {
                    hash_mesh(mesh, &mut mesh_hash);
                }
            }
            hash_debris(&carved.detached, &mut debris_hash);
            change.hash(&mut volume_hash);
            for (label, v) in &rounded {
                (label, v.to_bits()).hash(&mut volume_hash);
            }
        }
        cells.push(sealed.len());
        apply.push(applied);
        detach.push(detached - applied);
        meshes.push(done - detached);
        total.push(done);
    }
    let cells_total: usize = cells.iter().sum();
    cells.sort_unstable();
    println!(
        "{carves} craters{}: apply {:.3} ms, debris {:.3} ms, sealed meshes {:.3} ms, \
         total {:.3} ms (medians); material change exact {:.3} ms, f64 {:.3} ms (medians, \
         outside the total); \
         cells meshed per carve: median {}, mean {:.2}",
        if shade { " (shaded)" } else { "" },
        median(&mut apply),
        median(&mut detach),
        median(&mut meshes),
        median(&mut total),
        median(&mut volumes),
        median(&mut rounded_volumes),
        cells[cells.len() / 2],
        cells_total as f64 / carves as f64
    );
    let stats = octree.stats();
    println!(
        "octree: {} leaves, {} BSP nodes; mesher keeps {} cells",
        stats.leaves,
        stats.bsp_nodes,
        mesher.cells()
    );
    if check {
        println!(
            "hashes: meshes {:016x}, debris {:016x}, octree {:016x}, volume changes {:016x}",
            mesh_hash.finish(),
            debris_hash.finish(),
            octree.state_hash(),
            volume_hash.finish()
        );
    }
}
