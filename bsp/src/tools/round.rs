//! Round tools — spheres, cylinders and capsules — as the corners of exact
//! convex polyhedra that *contain* the true shape and lie within a stated
//! tolerance of its surface, after the corners are rounded to the grid.
//!
//! Notation: `K` — the true shape (ball, cylinder or capsule) centred at
//! the origin, axis `z`; `t` — the tolerance; `δ` — how far rounding may
//! move a corner (`√3/2` grid steps, [`GRID_ROUNDING`]); `P₀` — the hull of
//! the corners as computed; `P` — the hull of the rounded corners; `h_X(n)`
//! — the support function of `X` in the unit direction `n`.
//!
//! Guarantee. Moving every corner by at most `δ` changes the support
//! function of the hull by at most `δ`. So if `P₀ ⊇ K ⊕ B(δ)` (the shape
//! grown by `δ`) then `P ⊇ K`, and the Hausdorff distance of `P` and `K`
//! (equal, for nested convex bodies, to that of their surfaces) is at most
//! `max_{v ∈ corners} dist(v, K) + δ`. Each shape below computes that bound
//! ([`RoundCorners::deviation`]) and takes the fewest corners that bring it
//! within `t`.
//!
//! Spheres use a geodesic sphere (an icosahedron whose faces are divided
//! into `f²` triangles, projected onto the sphere). Its flat triangles,
//! seen from the centre, tile the sphere, so its hull contains the ball of
//! radius `c_min` — the least distance from the centre to the plane of a
//! triangle (every ray from the centre crosses a triangle at least that
//! far out). Scaling it to radius `(r + δ) / c_min` makes it contain the
//! ball grown by `δ`.

use std::collections::HashMap;

use crate::Error;

/// How far rounding a point to the integer grid moves it, in grid steps:
/// `√3/2` (half a step on each axis), with room for the `f64` error of
/// placing a corner (about `2^-52` of coordinates up to `2^26`).
pub const GRID_ROUNDING: f64 = 0.866_026_5;

/// The corners of a round tool and the bound they meet.
#[derive(Clone, Debug, PartialEq)]
pub struct RoundCorners {
    /// The corners, in the shape's frame (centre at the origin, axis `z`).
    pub corners: Vec<[f64; 3]>,
    /// A bound on the Hausdorff distance between the true shape and the
    /// hull of the corners after each moved by at most the rounding given;
    /// at most the tolerance asked for.
    pub deviation: f64,
}

/// A geodesic sphere of unit radius: points, and the triangles that tile
/// the sphere seen from its centre.
#[derive(Clone, Debug, PartialEq)]
pub struct GeodesicSphere {
    /// Unit vectors, `10·f² + 2` of them.
    pub points: Vec<[f64; 3]>,
    /// Triangles of `points`, counter-clockwise seen from outside.
    pub triangles: Vec<[usize; 3]>,
    /// The least distance from the centre to the plane of a triangle: the
    /// hull of `points` contains the ball of this radius.
    pub inradius: f64,
}

/// The number of points of the geodesic sphere of `frequency`.
#[must_use]
pub fn geodesic_point_count(frequency: usize) -> usize {
    10 * frequency * frequency + 2
}

/// The geodesic sphere of `frequency ≥ 1`: each face of an icosahedron
/// divided into `frequency²` triangles, the points projected onto the unit
/// sphere. Every coordinate is computed the same way on every machine
/// (only `+ − × ÷ √`).
#[must_use]
pub fn geodesic_sphere(frequency: usize) -> GeodesicSphere {
    let f = frequency.max(1);
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let ico: [[f64; 3]; 12] = [
        [-1.0, phi, 0.0],
        [1.0, phi, 0.0],
        [-1.0, -phi, 0.0],
        [1.0, -phi, 0.0],
        [0.0, -1.0, phi],
        [0.0, 1.0, phi],
        [0.0, -1.0, -phi],
        [0.0, 1.0, -phi],
        [phi, 0.0, -1.0],
        [phi, 0.0, 1.0],
        [-phi, 0.0, -1.0],
        [-phi, 0.0, 1.0],
    ];
    let faces: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    // A point is keyed by its integer weights on the icosahedron's corners
    // (sorted by corner), so points on shared edges are made once, and
    // computed in one order.
    let mut index: HashMap<Vec<(usize, usize)>, usize> = HashMap::new();
    let mut points = Vec::with_capacity(geodesic_point_count(f));
    let mut point = |weights: [(usize, usize); 3]| -> usize {
        let mut key: Vec<(usize, usize)> = weights.into_iter().filter(|w| w.1 > 0).collect();
        key.sort_unstable();
        *index.entry(key.clone()).or_insert_with(|| {
            let mut p = [0.0; 3];
            for &(corner, weight) in &key {
                for (axis, v) in p.iter_mut().enumerate() {
                    *v += weight as f64 * ico[corner][axis];
                }
            }
            let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            points.push(p.map(|v| v / len));
            points.len() - 1
        })
    };
    let mut triangles = Vec::with_capacity(20 * f * f);
    for [a, b, c] in faces {
        // Grid point (i, j): weight f − i − j on a, i on b, j on c.
        let mut grid = vec![vec![0usize; f + 1]; f + 1];
        for (i, row) in grid.iter_mut().enumerate() {
            for (j, slot) in row.iter_mut().enumerate().take(f + 1 - i) {
                *slot = point([(a, f - i - j), (b, i), (c, j)]);
            }
        }
        for i in 0..f {
            for j in 0..f - i {
                triangles.push([grid[i][j], grid[i + 1][j], grid[i][j + 1]]);
                if j + 1 < f - i {
                    triangles.push([grid[i + 1][j], grid[i + 1][j + 1], grid[i][j + 1]]);
                }
            }
        }
    }
    let inradius = triangles
        .iter()
        .map(|t| plane_distance(points[t[0]], points[t[1]], points[t[2]]))
        .fold(f64::INFINITY, f64::min);
    GeodesicSphere {
        points,
        triangles,
        inradius,
    }
}

/// The distance from the origin to the plane through `a`, `b`, `c`.
fn plane_distance(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]).abs() / len
}

/// Relative allowance for the `f64` error of the bounds below (far above
/// it, far below any tolerance that matters).
const FLOAT_SLACK: f64 = 1e-9;

/// Checks the numbers every round shape shares.
fn check_inputs(radius: f64, tolerance: f64, rounding: f64) -> Result<(), Error> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(Error::InvalidRoundTool {
            reason: "the radius must be positive and finite",
        });
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(Error::InvalidRoundTool {
            reason: "the tolerance must be positive and finite",
        });
    }
    if !(rounding.is_finite() && rounding >= 0.0) {
        return Err(Error::InvalidRoundTool {
            reason: "the rounding allowance must be finite and not negative",
        });
    }
    Ok(())
}

/// The radius at which a geodesic sphere of `frequency` contains the ball
/// of radius `radius + rounding`, and that sphere.
fn covering_sphere(frequency: usize, radius: f64, rounding: f64) -> (f64, GeodesicSphere) {
    let sphere = geodesic_sphere(frequency);
    let scaled = (radius + rounding) / sphere.inradius * (1.0 + FLOAT_SLACK);
    (scaled, sphere)
}

/// Picks the least geodesic frequency whose covering sphere, `copies`
/// times, fits in `max_points` and meets `tolerance`.
fn fit_sphere(
    radius: f64,
    tolerance: f64,
    rounding: f64,
    max_points: usize,
    copies: usize,
) -> Result<(f64, GeodesicSphere), Error> {
    let mut best = f64::INFINITY;
    let mut frequency = 1;
    while copies * geodesic_point_count(frequency) <= max_points {
        let (scaled, sphere) = covering_sphere(frequency, radius, rounding);
        let deviation = scaled - radius + rounding;
        if deviation <= tolerance {
            return Ok((scaled, sphere));
        }
        best = deviation;
        frequency += 1;
    }
    Err(Error::ToleranceUnreachable {
        tolerance,
        best,
        max_points,
    })
}

/// The corners of a polyhedron containing the ball of `radius` around the
/// origin, within `tolerance` of it once every corner has moved by at most
/// `rounding` (pass [`GRID_ROUNDING`] for grid units): the fewest points of
/// a geodesic sphere, up to `max_points`.
///
/// # Errors
/// [`Error::InvalidRoundTool`] for a radius or tolerance that is not
/// positive and finite; [`Error::ToleranceUnreachable`] when no geodesic
/// sphere of at most `max_points` points meets the tolerance (it must be
/// more than `2·rounding`).
pub fn sphere_corners(
    radius: f64,
    tolerance: f64,
    rounding: f64,
    max_points: usize,
) -> Result<RoundCorners, Error> {
    check_inputs(radius, tolerance, rounding)?;
    let (scaled, sphere) = fit_sphere(radius, tolerance, rounding, max_points, 1)?;
    Ok(RoundCorners {
        corners: sphere
            .points
            .iter()
            .map(|p| p.map(|v| v * scaled))
            .collect(),
        deviation: scaled - radius + rounding,
    })
}

/// The corners of a polyhedron containing the capsule of `radius` around
/// the segment from `z = −half_height` to `z = half_height`, within
/// `tolerance` of it once every corner has moved by at most `rounding`: a
/// covering geodesic sphere (as [`sphere_corners`]) around each end, so
/// the hull contains the hull of the two balls, which is the capsule.
///
/// # Errors
/// As [`sphere_corners`], and [`Error::InvalidRoundTool`] for a negative
/// or non-finite half height.
pub fn capsule_corners(
    radius: f64,
    half_height: f64,
    tolerance: f64,
    rounding: f64,
    max_points: usize,
) -> Result<RoundCorners, Error> {
    check_inputs(radius, tolerance, rounding)?;
    if !(half_height.is_finite() && half_height >= 0.0) {
        return Err(Error::InvalidRoundTool {
            reason: "a capsule's half height must be finite and not negative",
        });
    }
    let (scaled, sphere) = fit_sphere(radius, tolerance, rounding, max_points, 2)?;
    let mut corners = Vec::with_capacity(2 * sphere.points.len());
    for z in [-half_height, half_height] {
        corners.extend(
            sphere
                .points
                .iter()
                .map(|p| [p[0] * scaled, p[1] * scaled, p[2] * scaled + z]),
        );
    }
    Ok(RoundCorners {
        corners,
        deviation: scaled - radius + rounding,
    })
}

/// The corners of a polyhedron containing the cylinder of `radius` around
/// the `z` axis from `z = −half_height` to `z = half_height`, within
/// `tolerance` of it once every corner has moved by at most `rounding`: a
/// regular prism with the fewest sides whose apothem is `radius + rounding`
/// and whose caps are `rounding` beyond the cylinder's.
///
/// # Errors
/// As [`sphere_corners`], and [`Error::InvalidRoundTool`] for a half height
/// that is not positive and finite.
pub fn cylinder_corners(
    radius: f64,
    half_height: f64,
    tolerance: f64,
    rounding: f64,
    max_points: usize,
) -> Result<RoundCorners, Error> {
    check_inputs(radius, tolerance, rounding)?;
    if !(half_height.is_finite() && half_height > 0.0) {
        return Err(Error::InvalidRoundTool {
            reason: "a cylinder's half height must be positive and finite",
        });
    }
    let apothem = radius + rounding;
    let mut best = f64::INFINITY;
    let mut sides = 3usize;
    while 2 * sides <= max_points {
        let half_angle = std::f64::consts::PI / sides as f64;
        let circumradius = apothem / half_angle.cos() * (1.0 + FLOAT_SLACK);
        // The farthest corner from the cylinder: `circumradius − radius`
        // out and `rounding` above a cap.
        let deviation = (circumradius - radius).hypot(rounding) + rounding;
        if deviation <= tolerance {
            let z = half_height + rounding;
            let mut corners = Vec::with_capacity(2 * sides);
            for cap in [-z, z] {
                for k in 0..sides {
                    let a = k as f64 * std::f64::consts::TAU / sides as f64;
                    corners.push([circumradius * a.cos(), circumradius * a.sin(), cap]);
                }
            }
            return Ok(RoundCorners { corners, deviation });
        }
        best = deviation;
        sides += 1;
    }
    Err(Error::ToleranceUnreachable {
        tolerance,
        best,
        max_points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geodesic_spheres_have_the_expected_counts_and_tile_the_sphere() {
        for f in 1..=6 {
            let s = geodesic_sphere(f);
            assert_eq!(s.points.len(), geodesic_point_count(f));
            assert_eq!(s.triangles.len(), 20 * f * f);
            // Euler: V − E + F = 2 with E = 3F/2.
            assert_eq!(
                s.points.len() + s.triangles.len() - 3 * s.triangles.len() / 2,
                2
            );
            // Counter-clockwise from outside: the normal points away.
            for t in &s.triangles {
                let [a, b, c] = t.map(|i| s.points[i]);
                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                assert!(n[0] * a[0] + n[1] * a[1] + n[2] * a[2] > 0.0);
            }
            assert!(s.inradius > 0.79 && s.inradius < 1.0);
        }
        // The icosahedron's inradius over circumradius.
        assert!((geodesic_sphere(1).inradius - 0.794_654_472_291_766).abs() < 1e-12);
    }

    #[test]
    fn finer_tolerances_take_more_points() {
        let counts: Vec<usize> = [0.1, 0.01, 0.001]
            .iter()
            .map(|&t| sphere_corners(1.0, t, 0.0, 8192).unwrap().corners.len())
            .collect();
        assert!(counts[0] < counts[1] && counts[1] < counts[2], "{counts:?}");
    }
}
