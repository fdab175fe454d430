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

/// Parses `WIDTHxHEIGHT`.
pub fn size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once('x')
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got `{text}`"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|_| format!("`{s}` is not a pixel count"))
    };
    Ok((parse(w)?, parse(h)?))
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
