//! `chisel` — the command line of bevy_chisel's kernels.
//!
//! - `chisel budget` prints the exact kernel's bit budget.
//! - `chisel sample SCENE --radius R [--bounds X,Y,Z,R]` samples a quadric
//!   CSG scene into splats (`--json` for one summary line, `-o FILE.ply`).
//! - `chisel trace SCENE [--bounds X,Y,Z,R] -o IMAGE.png` renders it with the
//!   CPU reference ray tracer. `--bounds` defaults to the scene's `bounds`.
//! - `chisel mill --steps N`, `chisel cheese --count N`, `chisel sweep
//!   --samples N` run the iterated CSG scenarios (paper 1 §5; measured
//!   in BENCHMARKS.md, "Iterated CSG scenarios") on the octree of BSPs; `chisel replay OPS.jsonl` applies a recorded operation
//!   sequence. All report per-step latency, result size, volume and memory
//!   (`--json`, `--csv`, `--export`, `--record`).
//! - `chisel cutter --path helix|spiral|tilt --sides S --steps N` sweeps a
//!   tapered, tilted cutter in general orientation along a curved path.
//! - `chisel fluted --steps N [--flutes F] [--substeps S]` mills with the
//!   paper's skewed fluted bit, its rotation swept as a union of convex
//!   pieces (paper 1 §5, Fig. 13–14).
//! - `chisel boolean A B --op union|intersection|difference -o OUT` — the
//!   exact Boolean of two closed meshes (OBJ, PLY or GLB) or exact octree
//!   files (`.chisel`).
//!
//! Every result can be written as a mesh (`.obj`, `.ply`, `.glb`: floats,
//! for viewers) or as an exact octree file (`.chisel`: integers, read back
//! bit-identically by `chisel boolean` and by a replay's
//! `{"base": {"mesh": "FILE.chisel"}}`).
//!
//! A failure is a message on standard error and an exit code by kind
//! ([`failure::Exit`]): 2 a wrong command line, 3 bad input data, 4 a
//! failed `--check`, 5 a failed write.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod args;
mod atomic;
mod boolean;
mod budget;
mod failure;
mod formats;
#[cfg(test)]
mod fuzz;
mod meshfile;
mod octree_file;
mod sample;
mod scenario;
mod trace;

use scenario::runner::{RunFlags, Scenario};

/// The kernels allocate and free many small polygons and faces, often on
/// different worker threads: mimalloc makes the scenarios 15–20% faster
/// than the system allocator, for a larger peak resident size
/// (BENCHMARKS.md). The plugin leaves this choice to the game.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Exact solid modelling kernels of bevy_chisel, from the command line.
#[derive(Parser)]
#[command(name = "chisel", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print the exact kernel's bit budget (input range and derived widths).
    Budget {
        /// One line of JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Sample a quadric CSG scene into splats with the coverage guarantee.
    Sample(sample::SampleArgs),
    /// Render a quadric CSG scene with the CPU reference ray tracer.
    Trace(trace::TraceArgs),
    /// Mill a 100 × 100 × 40 mm block: a flat end mill (16-sided prism,
    /// radius 3 mm) swept along a zig-zag path, one subtraction per step.
    Mill {
        /// Number of tool moves (1 to 1,000,000).
        #[arg(long, default_value_t = 270, value_parser = args::steps)]
        steps: usize,
        #[command(flatten)]
        run: RunFlags,
    },
    /// Carve a 100 mm cube with many random dodecahedra, seeded sizes,
    /// rotations and centres (in its top 40 mm).
    Cheese {
        /// Number of carves (1 to 1,000,000).
        #[arg(long, default_value_t = 1000, value_parser = args::steps)]
        count: usize,
        /// Seed of the random sizes, rotations and places.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[command(flatten)]
        run: RunFlags,
    },
    /// Sweep a tapered, tilted many-sided cutter along a helical, spiral
    /// or 5-axis path through a 100 × 100 × 40 mm block, one subtraction
    /// per step.
    Cutter {
        /// The path.
        #[arg(long, value_enum, default_value_t = scenario::cutter::PathKind::Helix)]
        path: scenario::cutter::PathKind,
        /// Sides of the cutter's polygon (3 to 256).
        #[arg(long, default_value_t = 20)]
        sides: usize,
        /// Number of tool moves (1 to 1,000,000).
        #[arg(long, default_value_t = 270, value_parser = args::steps)]
        steps: usize,
        #[command(flatten)]
        run: RunFlags,
    },
    /// Mill with a skewed fluted bit turning 4° a step, each step's swept
    /// volume subtracted as a union of convex hulls, one per piece of the
    /// bit and sub-step (paper 1 §5, Fig. 13–14).
    Fluted {
        /// Rotation steps of 4° (1 to 1,000,000); each is (flutes + 1) ×
        /// substeps subtractions.
        #[arg(long, default_value_t = 270, value_parser = args::steps)]
        steps: usize,
        /// Flutes of the bit (1 to 8).
        #[arg(long, default_value_t = 3)]
        flutes: usize,
        /// Sub-steps each rotation step is swept in (1 to 16).
        #[arg(long, default_value_t = 1)]
        substeps: usize,
        #[command(flatten)]
        run: RunFlags,
    },
    /// Sweep a gear along a Bézier curve by unions of per-triangle sweep
    /// prisms (paper 1 §5).
    Sweep {
        /// Positions sampled along the curve (1 to 1,000,000).
        #[arg(long, default_value_t = 100, value_parser = args::steps)]
        samples: usize,
        #[command(flatten)]
        run: RunFlags,
    },
    /// The exact Boolean of two solids: closed meshes (OBJ, PLY or GLB, in
    /// mm) or exact octree files (.chisel, read with no re-import).
    Boolean(boolean::BooleanArgs),
    /// Apply a recorded operation sequence (JSON lines: a base box, mesh or
    /// .chisel octree, then one convex hull per step, millimetres).
    Replay {
        /// The sequence file.
        ops: PathBuf,
        #[command(flatten)]
        run: RunFlags,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result =
        match cli.command {
            Command::Budget { json } => {
                budget::print(json);
                Ok(())
            }
            Command::Sample(args) => sample::run(&args),
            Command::Trace(args) => trace::run(&args),
            Command::Mill { steps, run } => scenario::mill::sequence(steps)
                .map_err(failure::Failure::usage)
                .and_then(|sequence| {
                    let parameters = serde_json::json!({ "steps": steps });
                    scenario::runner::run(
                        &Scenario {
                            name: "mill",
                            parameters,
                            sequence,
                        },
                        &run,
                    )
                }),
            Command::Cheese { count, seed, run } => scenario::cheese::sequence(count, seed)
                .map_err(failure::Failure::usage)
                .and_then(|sequence| {
                    let parameters = serde_json::json!({ "count": count, "seed": seed });
                    scenario::runner::run(
                        &Scenario {
                            name: "cheese",
                            parameters,
                            sequence,
                        },
                        &run,
                    )
                }),
            Command::Cutter {
                path,
                sides,
                steps,
                run,
            } => scenario::cutter::sequence(path, sides, steps)
                .map_err(failure::Failure::usage)
                .and_then(|sequence| {
                    let parameters = serde_json::json!({
                        "path": path.name(), "sides": sides, "steps": steps
                    });
                    scenario::runner::run(
                        &Scenario {
                            name: "cutter",
                            parameters,
                            sequence,
                        },
                        &run,
                    )
                }),
            Command::Fluted {
                steps,
                flutes,
                substeps,
                run,
            } => scenario::fluted::sequence(steps, flutes, substeps)
                .map_err(failure::Failure::usage)
                .and_then(|sequence| {
                    let parameters = serde_json::json!({
                        "steps": steps, "flutes": flutes, "substeps": substeps,
                        "subtractions_per_step": (flutes + 1) * substeps
                    });
                    scenario::runner::run(
                        &Scenario {
                            name: "fluted",
                            parameters,
                            sequence,
                        },
                        &run,
                    )
                }),
            Command::Sweep { samples, run } => scenario::sweep::sequence(samples)
                .map_err(failure::Failure::usage)
                .and_then(|(sequence, flat)| {
                    let parameters =
                        serde_json::json!({ "samples": samples, "flat_prisms_left_out": flat });
                    scenario::runner::run(
                        &Scenario {
                            name: "sweep",
                            parameters,
                            sequence,
                        },
                        &run,
                    )
                }),
            Command::Boolean(args) => boolean::run(&args),
            Command::Replay { ops, run } => scenario::jsonl::read(&ops)
                .map_err(Into::into)
                .and_then(|sequence| {
                    let parameters = serde_json::json!({ "file": ops });
                    scenario::runner::run(
                        &Scenario {
                            name: "replay",
                            parameters,
                            sequence,
                        },
                        &run,
                    )
                }),
        };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            eprintln!("chisel: {}", failure.message);
            ExitCode::from(failure.exit as u8)
        }
    }
}
