//! `chisel trace`: the CPU reference ray tracer, shaded to a PNG.

use std::path::PathBuf;
use std::time::Instant;

use crate::failure::Failure;
use chisel_quadric::{Camera, NO_HIT, Scene, trace_image};
use glam::DVec3;

/// What `chisel trace` was asked to do: its command-line arguments.
#[derive(clap::Args)]
pub struct TraceArgs {
    /// Scene file (RON, see quadric/SCENES.md).
    pub scene: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Bounding sphere `x,y,z,r`; places the default camera (default:
    /// the scene's `bounds`).
    #[arg(long, value_parser = crate::args::sphere)]
    pub bounds: Option<(DVec3, f64)>,
    /// Camera position `x,y,z`.
    #[arg(long, value_parser = crate::args::vec3)]
    pub eye: Option<DVec3>,
    /// Point looked at `x,y,z`.
    #[arg(long, value_parser = crate::args::vec3)]
    pub look_at: Option<DVec3>,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 40.0)]
    pub fov: f64,
    /// Image size `WIDTHxHEIGHT` (at most 8192x8192 pixels in all).
    #[arg(long, value_parser = crate::args::size, default_value = "800x600")]
    pub size: (u32, u32),
}

/// Runs the command; errors are messages for the user.
pub fn run(args: &TraceArgs) -> Result<(), Failure> {
    crate::failure::check_output(&args.output, false)?;
    let scene = Scene::load(&args.scene).map_err(|e| format!("{}: {e}", args.scene.display()))?;
    let dnf = scene.dnf().map_err(|e| e.to_string())?;
    let bounds = crate::args::bounds(args.bounds, &scene, &args.scene).map_err(Failure::usage)?;
    let (centre, radius) = (bounds.centre, bounds.radius);
    let eye = args
        .eye
        .unwrap_or(centre + DVec3::new(1.8, -2.4, 1.5) * radius);
    let look_at = args.look_at.unwrap_or(centre);
    if !(args.fov > 0.0 && args.fov < 180.0) {
        return Err(Failure::usage(format!(
            "--fov {}: the vertical field of view must lie strictly between 0 and 180 degrees",
            args.fov
        )));
    }
    let view = eye - look_at;
    if !(view.length_squared().is_finite() && view.length_squared() > 0.0) {
        return Err(Failure::usage(format!(
            "--eye {eye} and --look-at {look_at}: the camera must be a finite, non-zero \
             distance from the point it looks at (squared distance within f64)"
        )));
    }
    let camera = Camera::new(eye, look_at, args.fov, args.size.0, args.size.1).map_err(|e| {
        Failure::usage(format!(
            "the camera (--eye, --look-at, --fov, --bounds): {e}"
        ))
    })?;
    let start = Instant::now();
    let image = trace_image(&dnf, &camera);
    let seconds = start.elapsed().as_secs_f64();
    // Lambert shading from a light over the camera's shoulder, plus ambient.
    let light = (eye - look_at).normalize() + DVec3::new(0.3, 0.2, 0.8);
    let light = light.normalize();
    let mut png = image::RgbImage::new(image.width, image.height);
    for (i, pixel) in png.pixels_mut().enumerate() {
        let q = image.quadric[i];
        *pixel = if q == NO_HIT {
            image::Rgb([235, 238, 242])
        } else {
            let primitive = dnf.quadrics()[q as usize].primitive;
            let colour = scene.color(primitive).unwrap_or([0.7, 0.7, 0.7]);
            let lambert = image.normal[i].dot(light).max(0.0);
            let shade = (0.25 + 0.75 * lambert) as f32;
            let byte = |c: f32| ((c * shade).clamp(0.0, 1.0) * 255.0).round() as u8;
            image::Rgb([byte(colour[0]), byte(colour[1]), byte(colour[2])])
        };
    }
    let mut bytes = std::io::Cursor::new(Vec::new());
    png.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| format!("{}: {e}", args.output.display()))?;
    crate::atomic::write_bytes(&args.output, bytes.get_ref())
        .map_err(|e| Failure::write(format!("{}: {e}", args.output.display())))?;
    let hits = image.quadric.iter().filter(|&&q| q != NO_HIT).count();
    println!(
        "traced {}x{} ({hits} surface pixels) in {seconds:.3} s; wrote {}",
        image.width,
        image.height,
        args.output.display()
    );
    Ok(())
}
