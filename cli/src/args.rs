//! Parsers for comma-separated vector arguments.

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
