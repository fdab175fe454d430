//! `chisel` — the command line of bevy_chisel's kernels.
//!
//! - `chisel budget` prints the exact kernel's bit budget.
//! - `chisel sample SCENE --radius R --bounds X,Y,Z,R` samples a quadric
//!   CSG scene into splats (`--json` for one summary line, `-o FILE.ply`).
//! - `chisel trace SCENE --bounds X,Y,Z,R -o IMAGE.png` renders it with the
//!   CPU reference ray tracer.
//!
//! Bad input (unreadable or malformed files, out-of-range numbers) is
//! reported on standard error with exit code 2.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use glam::DVec3;

mod args;
mod budget;
mod formats;
mod sample;
mod trace;

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
    Sample {
        /// Scene file (RON, see quadric/SCENES.md).
        scene: PathBuf,
        /// Splat radius in scene units: every surface point is within it of
        /// a sample on the same quadric.
        #[arg(long)]
        radius: f64,
        /// Bounding sphere `x,y,z,r` that limits sampling.
        #[arg(long, value_parser = args::sphere)]
        bounds: (DVec3, f64),
        /// Write the samples as a PLY point cloud.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// One line of JSON instead of a report.
        #[arg(long)]
        json: bool,
    },
    /// Render a quadric CSG scene with the CPU reference ray tracer.
    Trace {
        /// Scene file (RON, see quadric/SCENES.md).
        scene: PathBuf,
        /// Output PNG.
        #[arg(short, long)]
        output: PathBuf,
        /// Bounding sphere `x,y,z,r`; places the default camera.
        #[arg(long, value_parser = args::sphere)]
        bounds: (DVec3, f64),
        /// Camera position `x,y,z`.
        #[arg(long, value_parser = args::vec3)]
        eye: Option<DVec3>,
        /// Point looked at `x,y,z`.
        #[arg(long, value_parser = args::vec3)]
        look_at: Option<DVec3>,
        /// Vertical field of view, degrees.
        #[arg(long, default_value_t = 40.0)]
        fov: f64,
        /// Image size `WIDTHxHEIGHT`.
        #[arg(long, value_parser = args::size, default_value = "800x600")]
        size: (u32, u32),
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Budget { json } => {
            budget::print(json);
            Ok(())
        }
        Command::Sample {
            scene,
            radius,
            bounds,
            output,
            json,
        } => sample::run(&sample::SampleArgs {
            scene,
            radius,
            bounds,
            output,
            json,
        }),
        Command::Trace {
            scene,
            output,
            bounds,
            eye,
            look_at,
            fov,
            size,
        } => trace::run(&trace::TraceArgs {
            scene,
            output,
            bounds,
            eye,
            look_at,
            fov,
            size,
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("chisel: {message}");
            ExitCode::from(2)
        }
    }
}
