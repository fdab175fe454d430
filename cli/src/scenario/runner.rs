//! Runs an operation sequence on an octree, timing every step: the tool's
//! hull, its application, and the re-extraction of the cells it changed —
//! the latency a game sees between a carve and the updated meshes.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{CellBox, Octree, OctreeConfig, Tool};
use chisel_bsp::tree::EMPTY;
use indicatif::{ProgressBar, ProgressStyle};

use super::check;
use super::cpu_clock::CpuStopwatch;
use super::extract;
use super::jsonl;
use super::report::{Latency, OctreeFigures, Report, StepRecord, peak_memory_mib, write_csv};
use super::sequence::{Base, Sequence, root_cube};
use crate::failure::Failure;
use crate::octree_file;

/// Options shared by every scenario command.
#[derive(clap::Args, Clone, Debug)]
pub struct RunFlags {
    /// Print one line of JSON instead of a report (and no progress bar).
    #[arg(long)]
    pub json: bool,
    /// Write per-step latencies to this CSV file.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the result: its surface as a mesh (.obj, .ply or .glb), or
    /// the exact octree (.chisel), which `chisel boolean` and a replay base
    /// read back bit-identically.
    #[arg(long, value_name = "FILE")]
    pub export: Option<PathBuf>,
    /// Write the operation sequence to this file in the replay format
    /// (JSON lines, millimetres, exactly the quantized tool points).
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Inner BSP nodes an octree cell may hold before it is split (a
    /// `.chisel` replay base keeps the settings it was saved with).
    /// At least 8: smaller budgets split cells down to the depth limit.
    #[arg(long, default_value_t = 150, value_parser = clap::value_parser!(u32).range(8..))]
    pub max_bsp_nodes: u32,
    /// Check every step (untimed): exact volume bookkeeping of the edit and
    /// a closed surface. Slow; for small sizes.
    #[arg(long)]
    pub check: bool,
    /// Worker threads (default: one per core). Results do not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
}

/// A named sequence ready to run.
pub struct Scenario {
    /// `mill`, `cheese`, `cutter`, `fluted`, `sweep` or `replay`.
    pub name: &'static str,
    /// Sizes, seed or file, as reported.
    pub parameters: serde_json::Value,
    /// What to do.
    pub sequence: Sequence,
}

/// Runs `scenario` and prints its report; writes the files `flags` ask
/// for.
///
/// # Errors
/// A message for unwritable files, an unreadable base mesh, or geometry
/// beyond the exact range.
pub fn run(scenario: &Scenario, flags: &RunFlags) -> Result<(), Failure> {
    for (path, mesh_or_octree) in [
        (&flags.export, true),
        (&flags.csv, false),
        (&flags.record, false),
    ] {
        if let Some(path) = path {
            crate::failure::check_output(path, mesh_or_octree)?;
        }
    }
    if let Some(path) = &flags.record {
        jsonl::write(path, &scenario.sequence).map_err(Failure::write)?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(flags.threads.map_or(0, |t| t as usize))
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    let (report, steps, mesh, octree) = pool.install(|| execute(scenario, flags))?;
    if let Some(path) = &flags.csv {
        write_csv(path, &steps).map_err(Failure::write)?;
    }
    if let Some(path) = &flags.export {
        if octree_file::is_octree_file(path) {
            octree_file::write(path, &octree).map_err(Failure::write)?;
        } else {
            crate::meshfile::write(path, &mesh).map_err(Failure::write)?;
        }
    }
    if flags.json {
        println!("{}", report.json());
    } else {
        print!("{}", report.text());
        for (what, path) in [
            ("csv", &flags.csv),
            ("export", &flags.export),
            ("record", &flags.record),
        ] {
            if let Some(path) = path {
                println!("{:<16}{}", format!("wrote {what}"), path.display());
            }
        }
    }
    Ok(())
}

/// The octree of the base solid, in a cube holding it and every tool.
///
/// A `.chisel` base is used exactly as stored (its cube and settings) when
/// its cube holds every tool, and otherwise moved exactly into a cube that
/// does.
fn base_octree(sequence: &Sequence, config: OctreeConfig) -> Result<Octree, String> {
    if let Base::Mesh(path) = &sequence.base
        && octree_file::is_octree_file(path)
    {
        return stored_base(octree_file::read(path)?, sequence)
            .map_err(|e| format!("{}: {e}", path.display()));
    }
    let mesh = match &sequence.base {
        Base::Mesh(path) => Some(crate::meshfile::read_grid(path)?),
        Base::Empty | Base::Box(_) => None,
    };
    let mut bounds = sequence.bounds();
    if let Some(mesh) = &mesh {
        let b = mesh.bounds;
        bounds = Some(match bounds {
            None => b,
            Some(a) => CellBox {
                min: [0, 1, 2].map(|i| a.min[i].min(b.min[i])),
                max: [0, 1, 2].map(|i| a.max[i].max(b.max[i])),
            },
        });
    }
    let bounds = bounds.unwrap_or(CellBox {
        min: [0; 3],
        max: [2; 3],
    });
    let (origin, size_log2) = root_cube(bounds)?;
    let octree = match (&sequence.base, mesh) {
        (Base::Box(b), _) => Octree::from_box(origin, size_log2, *b, 1, config),
        (Base::Mesh(_), Some(mesh)) => {
            Octree::from_triangles(origin, size_log2, &mesh.triangles, 1, config)
        }
        _ => Octree::new(origin, size_log2, EMPTY, config),
    };
    octree.map_err(|e| match &sequence.base {
        Base::Mesh(path) => format!("{}: {e}", path.display()),
        _ => e.to_string(),
    })
}

/// A stored base octree in a cube holding it and every tool of `sequence`.
fn stored_base(octree: Octree, sequence: &Sequence) -> Result<Octree, String> {
    let Some(tools) = sequence.bounds() else {
        return Ok(octree);
    };
    if octree_file::holds(&octree.root_box(), &tools) {
        return Ok(octree);
    }
    let bounds = match octree_file::solid_bounds(&octree) {
        None => tools,
        Some(b) => CellBox {
            min: [0, 1, 2].map(|i| tools.min[i].min(b.min[i])),
            max: [0, 1, 2].map(|i| tools.max[i].max(b.max[i])),
        },
    };
    let (origin, size_log2) = root_cube(bounds)?;
    octree_file::embed(octree, origin, size_log2)
}

fn progress(len: usize, hidden: bool, name: &str) -> ProgressBar {
    if hidden || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "{prefix} [{bar:40}] {pos}/{len} steps, {elapsed} elapsed, eta {eta}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(name.to_string());
    bar
}

type Outcome = (
    Report,
    Vec<StepRecord>,
    chisel_bsp::mesh::TriangleMesh,
    Octree,
);

fn execute(scenario: &Scenario, flags: &RunFlags) -> Result<Outcome, Failure> {
    let config = OctreeConfig {
        max_bsp_nodes: flags.max_bsp_nodes as usize,
        ..OctreeConfig::default()
    };
    let setup = Instant::now();
    let mut octree = base_octree(&scenario.sequence, config)?;
    let setup_seconds = setup.elapsed().as_secs_f64();
    let steps = &scenario.sequence.steps;
    let bar = progress(steps.len(), flags.json, scenario.name);
    let mut records = Vec::with_capacity(steps.len());
    let start = Instant::now();
    let start_cpu = CpuStopwatch::start();
    for (i, step) in steps.iter().enumerate() {
        let fail = |e: chisel_bsp::Error| format!("step {}: {e}", i + 1);
        let before = flags.check.then(|| octree.clone());
        let t0 = Instant::now();
        let cpu = CpuStopwatch::start();
        let points = step
            .hull
            .iter()
            .map(|&p| IntPoint::from_array(p).map_err(fail))
            .collect::<Result<Vec<_>, _>>()?;
        let tool = Tool::convex_hull(&points).map_err(fail)?;
        let built = t0.elapsed().as_secs_f64();
        let (changes, faces) = octree
            .apply_with_faces(&tool, step.op.edit())
            .map_err(fail)?;
        let applied = t0.elapsed().as_secs_f64();
        let triangles = extract::changed_cells(&octree, &changes.changed, faces);
        let cpu_seconds = cpu.elapsed();
        records.push(StepRecord {
            seconds: t0.elapsed().as_secs_f64(),
            cpu_seconds,
            hull_seconds: built,
            apply_seconds: applied - built,
            changed_cells: changes.changed.len(),
            triangles,
        });
        if let Some(before) = &before {
            check::step(before, &octree, &tool, step.op)
                .map_err(|e| Failure::check(format!("step {}: {e}", i + 1)))?;
        }
        bar.inc(1);
    }
    let total_seconds = start.elapsed().as_secs_f64();
    let total_cpu_seconds = start_cpu.elapsed();
    bar.finish_and_clear();
    let (mesh, closure) = extract::whole(&octree);
    let stats = octree.stats();
    let seconds: Vec<f64> = records.iter().map(|r| r.seconds).collect();
    let cpu_seconds: Vec<f64> = records.iter().map(|r| r.cpu_seconds).collect();
    let hull: Vec<f64> = records.iter().map(|r| r.hull_seconds).collect();
    let apply: Vec<f64> = records.iter().map(|r| r.apply_seconds).collect();
    let report = Report {
        scenario: scenario.name.to_string(),
        parameters: scenario.parameters.clone(),
        steps: steps.len(),
        threads: rayon::current_num_threads(),
        setup_seconds,
        total_seconds,
        total_cpu_seconds,
        per_step: extract::PER_STEP,
        latency: Latency::of(&seconds),
        cpu: Latency::of(&cpu_seconds),
        hull_median_ms: Latency::of(&hull).median_ms,
        apply_median_ms: Latency::of(&apply).median_ms,
        changed_cells_mean: records.iter().map(|r| r.changed_cells as f64).sum::<f64>()
            / records.len().max(1) as f64,
        triangles: mesh.len(),
        closed: closure.closed,
        watertight: closure.manifold,
        volume_mm3: octree.solid_volume() / 1e9,
        octree: OctreeFigures {
            leaves: stats.leaves,
            bsp_leaves: stats.bsp_leaves,
            depth: stats.depth,
            bsp_nodes: stats.bsp_nodes,
            planes: stats.planes,
            bsp_bytes: stats.bsp_bytes,
            bytes_per_bsp_node: stats.bsp_bytes as f64 / stats.bsp_nodes.max(1) as f64,
        },
        peak_memory_mib: peak_memory_mib(),
        mesh_hash: format!("{:016x}", extract::mesh_hash(&mesh)),
        checked: flags.check,
    };
    Ok((report, records, mesh, octree))
}
