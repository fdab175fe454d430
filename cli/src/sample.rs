//! `chisel sample`: adaptive splat sampling of a quadric CSG scene.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::failure::Failure;
use chisel_quadric::{INDEX_MASK, SampleOptions, Scene, SplatSet, sample};
use glam::DVec3;

/// What `chisel sample` was asked to do: its command-line arguments.
#[derive(clap::Args)]
pub struct SampleArgs {
    /// Scene file (RON, see quadric/SCENES.md).
    pub scene: PathBuf,
    /// Splat radius in scene units: every surface point is within it of
    /// a sample on the same quadric.
    #[arg(long)]
    pub radius: f64,
    /// Bounding sphere `x,y,z,r` that limits sampling (default: the
    /// scene's `bounds`).
    #[arg(long, value_parser = crate::args::sphere)]
    pub bounds: Option<(DVec3, f64)>,
    /// Write the samples as a PLY point cloud.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Refuse to emit more samples than this (checked before each
    /// grid of samples is allocated).
    #[arg(long, default_value_t = chisel_quadric::DEFAULT_MAX_SAMPLES)]
    pub max_samples: u64,
    /// Refuse to sample when the tables built before the first sample
    /// (heightfields, basic regions, distance tables) would need more
    /// than this many MiB; estimated from the scene before allocating.
    #[arg(long, default_value_t = chisel_quadric::DEFAULT_MAX_MEMORY >> 20)]
    pub max_memory_mb: u64,
    /// One line of JSON instead of a report.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command; errors are messages for the user.
pub fn run(args: &SampleArgs) -> Result<(), Failure> {
    if let Some(path) = &args.output {
        crate::failure::check_output(path, false)?;
    }
    let scene = Scene::load(&args.scene).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let dnf = scene.dnf().map_err(|e| e.to_string())?;
    let bounds = crate::args::bounds(args.bounds, &scene, &args.scene).map_err(Failure::usage)?;
    let mut options =
        SampleOptions::new(args.radius, bounds).map_err(|e| Failure::usage(e.to_string()))?;
    options.max_samples = args.max_samples;
    options.max_memory = args.max_memory_mb.saturating_mul(1 << 20);
    let start = Instant::now();
    let samples = sample(&dnf, &options).map_err(|e| e.to_string())?;
    let seconds = start.elapsed().as_secs_f64();
    let splats = SplatSet::new(&dnf, &scene.dag, &samples);
    if let Some(path) = &args.output {
        write_ply(path, &splats).map_err(|e| Failure::write(format!("{}: {e}", path.display())))?;
    }
    let count = samples.samples.len();
    let rate = count as f64 / seconds.max(1e-12);
    if args.json {
        println!(
            "{{\"scene\":\"{}\",\"radius\":{},\"quadrics\":{},\"products\":{},\"samples\":{count},\
             \"distance_queries\":{},\"clip_indices\":{},\"seconds\":{seconds:.6},\"samples_per_second\":{rate:.0}}}",
            args.scene.display(),
            args.radius,
            dnf.quadrics().len(),
            dnf.products().len(),
            samples.stats.distance_queries,
            splats.clip_indices.len(),
        );
    } else {
        println!("scene            {}", args.scene.display());
        println!(
            "quadrics         {} in {} products",
            dnf.quadrics().len(),
            dnf.products().len()
        );
        println!("samples          {count} (splat radius {})", args.radius);
        println!("distance queries {}", samples.stats.distance_queries);
        println!("clip-list size   {}", splats.clip_indices.len());
        println!("time             {seconds:.4} s ({rate:.0} samples/s)");
        if let Some(path) = &args.output {
            println!("wrote            {}", path.display());
        }
    }
    Ok(())
}

/// Samples as an ASCII PLY point cloud with normals, colours and radii.
fn write_ply(path: &Path, splats: &SplatSet) -> std::io::Result<()> {
    crate::atomic::write_with(path, |out| write_ply_to(out, splats))
}

fn write_ply_to(out: &mut impl Write, splats: &SplatSet) -> std::io::Result<()> {
    writeln!(
        out,
        "ply\nformat ascii 1.0\nelement vertex {}",
        splats.splats.len()
    )?;
    for field in ["x", "y", "z", "nx", "ny", "nz"] {
        writeln!(out, "property float {field}")?;
    }
    writeln!(
        out,
        "property uchar red\nproperty uchar green\nproperty uchar blue"
    )?;
    writeln!(out, "property float radius\nend_header")?;
    for s in &splats.splats {
        let c = splats.quadrics[(s.quadric & INDEX_MASK) as usize].color;
        let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        writeln!(
            out,
            "{} {} {} {} {} {} {} {} {} {}",
            s.position.x,
            s.position.y,
            s.position.z,
            s.normal.x,
            s.normal.y,
            s.normal.z,
            byte(c[0]),
            byte(c[1]),
            byte(c[2]),
            s.radius
        )?;
    }
    Ok(())
}
