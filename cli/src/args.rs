//! Parsers for comma-separated vector arguments.

use std::path::Path;

use chisel_quadric::{BoundingSphere, Scene};
use glam::DVec3;

/// Parses `x,y,z`.
pub fn vec3(text: &str) -> Result<DVec3, String> {
    let v = numbers(text, 3)?;
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// Parses `x,y,z,r` (a sphere).
pub fn sphere(text: &str) -> Result<(DVec3, f64), String> {
    let v = numbers(text, 4)?;
    Ok((DVec3::new(v[0], v[1], v[2]), v[3]))
}

/// The bounding sphere of a command: `--bounds` if given, else the scene
/// file's `bounds`; an error naming both ways when there is neither.
pub fn bounds(
    given: Option<(DVec3, f64)>,
    scene: &Scene,
    path: &Path,
) -> Result<BoundingSphere, String> {
    match (given, scene.bounds) {
        (Some((centre, radius)), _) => {
            BoundingSphere::new(centre, radius).map_err(|e| format!("--bounds: {e}"))
        }
        (None, Some(b)) => Ok(b),
        (None, None) => Err(format!(
            "{} has no bounding sphere: add `bounds: (x, y, z, r)` to the scene \
             (quadric/SCENES.md) or pass --bounds x,y,z,r",
            path.display()
        )),
    }
}

/// The most pixels `chisel trace` renders (8192 × 8192).
pub const MAX_PIXELS: u64 = 1 << 26;

/// The most steps of a scenario (`mill --steps`, `cheese --count`, `sweep
/// --samples`): the sequence is built before the run, a few hundred bytes
/// a step.
pub const MAX_STEPS: usize = 1_000_000;

/// Parses `WIDTHxHEIGHT`, each at least 1, at most [`MAX_PIXELS`] in all.
pub fn size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once('x')
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got `{text}`"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("`{s}` is not a pixel count (a whole number from 1)"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(format!(
            "{w}x{h} is {} pixels, more than the limit of {MAX_PIXELS} (8192x8192)",
            u64::from(w) * u64::from(h)
        ));
    }
    Ok((w, h))
}

/// Parses a step count: a whole number from 1 to [`MAX_STEPS`].
pub fn steps(text: &str) -> Result<usize, String> {
    let n: u128 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number of steps"))?;
    if n == 0 || n > MAX_STEPS as u128 {
        return Err(format!(
            "{n} steps: give 1 to {MAX_STEPS} (longer runs: several replays, each from \
             the `.chisel` export of the one before)"
        ));
    }
    Ok(n as usize)
}

fn numbers(text: &str, count: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| format!("`{}` is not a number", s.trim()))
        })
        .collect::<Result<_, _>>()?;
    if v.len() != count {
        return Err(format!(
            "expected {count} comma-separated numbers, got {}",
            v.len()
        ));
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err("numbers must be finite".into());
    }
    Ok(v)
}
