//! `chisel cutter`: a tapered, tilted many-sided cutter swept along a
//! curved 3D path through a block, each step subtracting the hull of the
//! tool at two consecutive poses.
//!
//! Unlike `mill`, the tool is in general orientation: its axis leans away
//! from +z and its polygon is turned by an irrational angle, so the hull's
//! planes have large, unrelated coefficients (up to the 56-bit normals of
//! points 28 bits apart) instead of the axis-aligned ones of a prism on
//! the grid.
//!
//! Notation: `t` is the step's path parameter (one unit per step), `θ` the
//! angle around the block's centre, `α` the tool axis' tilt from +z, `φ`
//! the azimuth it leans towards, `σ` the spin of the polygon about the axis.

use chisel_bsp::octree::CellBox;
use chisel_bsp::tools::Pose;

use super::sequence::{Base, Op, Sequence, Step, UNITS_PER_MM};

/// Block `[0,100]×[0,100]×[0,40]` mm.
const BLOCK_MM: [f64; 3] = [100.0, 100.0, 40.0];
/// The tool: a frustum of a regular polygon, tip radius 1.5 mm, radius
/// 3.5 mm at 25 mm up its axis (a tapered end mill).
const TIP_RADIUS_MM: f64 = 1.5;
const TOP_RADIUS_MM: f64 = 3.5;
const LENGTH_MM: f64 = 25.0;
/// The polygon's fixed spin about the tool axis (radians; irrational with
/// respect to the side angle, so no face lines up with the grid).
const SPIN: f64 = 0.377;
/// Arc length per step, mm (as `mill`'s 1.5 mm steps).
const STEP_MM: f64 = 1.5;

/// The curved paths.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// Descending helix about the block's centre, radius 25 mm, tool
    /// leaning 15° along the direction of travel.
    Helix,
    /// Archimedean spiral outwards from radius 5 to 45 mm at a fixed
    /// depth, tool tilted 20° towards a fixed skew direction.
    Spiral,
    /// 5-axis: a Lissajous curve over the block, depth and tilt (up to
    /// 30°) and its azimuth all varying along the path.
    Tilt,
}

impl PathKind {
    /// The name used in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            PathKind::Helix => "helix",
            PathKind::Spiral => "spiral",
            PathKind::Tilt => "tilt",
        }
    }

    /// Tip position (mm) and axis `(α, φ)` at step `t` of `steps`.
    fn at(self, t: f64, steps: f64) -> ([f64; 3], f64, f64) {
        let deg = std::f64::consts::PI / 180.0;
        match self {
            PathKind::Helix => {
                let r = 25.0;
                let theta = t * STEP_MM / r;
                let z = 38.0 - 16.0 * t / steps.max(1.0);
                let p = [50.0 + r * theta.cos(), 50.0 + r * theta.sin(), z];
                // Lean along the tangent (θ + 90°).
                (p, 15.0 * deg, theta + 90.0 * deg)
            }
            PathKind::Spiral => {
                // r(θ) = r0 + kθ with k = 0.6 mm per radian (≈ 3.8 mm per
                // turn); θ advances by about STEP_MM / r per step.
                let (r0, k, r_max) = (5.0_f64, 0.6_f64, 45.0_f64);
                // Arc length s(θ) ≈ (r² − r0²) / 2k, so r = √(r0² + 2ks).
                let s = (t * STEP_MM) % ((r_max * r_max - r0 * r0) / (2.0 * k));
                let r = (r0 * r0 + 2.0 * k * s).sqrt();
                let theta = (r - r0) / k;
                let p = [50.0 + r * theta.cos(), 50.0 + r * theta.sin(), 31.0];
                (p, 20.0 * deg, 0.7)
            }
            PathKind::Tilt => {
                // Speeds chosen for ≈ 1.5 mm per step over the block.
                let u = t * 0.0105;
                let p = [
                    50.0 + 38.0 * (3.0 * u).sin(),
                    50.0 + 38.0 * (2.0 * u + 0.5).sin(),
                    32.0 + 4.0 * (5.0 * u).sin(),
                ];
                let alpha = 30.0 * deg * (0.5 + 0.5 * (t / 37.0).sin());
                (p, alpha, t / 53.0)
            }
        }
    }
}

/// `a · b` of row-major 3×3 matrices.
pub(super) fn mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The rotation by `a` radians about +z.
pub(super) fn rot_z(a: f64) -> [[f64; 3]; 3] {
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

fn rot_y(a: f64) -> [[f64; 3]; 3] {
    let (s, c) = a.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// The rotation by `a` radians about +x.
pub(super) fn rot_x(a: f64) -> [[f64; 3]; 3] {
    let (s, c) = a.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// The tool's pose: spin `σ`, then tilt by `α` towards azimuth `φ`, then
/// the tip moved to `tip` (mm), on the grid.
fn pose(tip: [f64; 3], alpha: f64, phi: f64) -> Pose {
    let tilt = mul(mul(rot_z(phi), rot_y(alpha)), rot_z(-phi));
    Pose {
        rotation: mul(tilt, rot_z(SPIN)),
        translation: tip.map(|c| c * UNITS_PER_MM),
    }
}

/// The tool's corners in its own frame (grid units): the tip polygon at
/// `z = 0` and the wider one at `z = LENGTH_MM`.
fn corners(sides: usize) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity(2 * sides);
    for (r, z) in [(TIP_RADIUS_MM, 0.0), (TOP_RADIUS_MM, LENGTH_MM)] {
        for k in 0..sides {
            let a = k as f64 * std::f64::consts::TAU / sides as f64;
            out.push([r * a.cos(), r * a.sin(), z].map(|c| c * UNITS_PER_MM));
        }
    }
    out
}

/// The scenario: `steps` subtractions of the `sides`-gon cutter along
/// `path`.
///
/// # Errors
/// Fewer than 3 sides, or a tool beyond the exact range.
pub fn sequence(path: PathKind, sides: usize, steps: usize) -> Result<Sequence, String> {
    if !(3..=256).contains(&sides) {
        return Err(format!("a cutter has 3 to 256 sides, not {sides}"));
    }
    let corners = corners(sides);
    let poses: Vec<Pose> = (0..=steps)
        .map(|i| {
            let (tip, alpha, phi) = path.at(i as f64, steps as f64);
            pose(tip, alpha, phi)
        })
        .collect();
    let steps = poses
        .windows(2)
        .map(|w| {
            let hull = corners
                .iter()
                .flat_map(|&c| [w[0].place(c), w[1].place(c)])
                .map(|p| p.map(|p| p.coords()).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Step {
                op: Op::Subtract,
                hull,
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Sequence {
        base: Base::Box(CellBox {
            min: [0; 3],
            max: BLOCK_MM.map(|c| (c * UNITS_PER_MM) as i64),
        }),
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_about_a_step_length_apart_and_inside_the_block() {
        for path in [PathKind::Helix, PathKind::Spiral, PathKind::Tilt] {
            let n = 2000;
            let tips: Vec<[f64; 3]> = (0..=n).map(|i| path.at(i as f64, n as f64).0).collect();
            let mut lengths: Vec<f64> = tips
                .windows(2)
                .map(|w| {
                    (0..3)
                        .map(|k| (w[1][k] - w[0][k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            lengths.sort_by(f64::total_cmp);
            let median = lengths[lengths.len() / 2];
            assert!((0.8..2.5).contains(&median), "{path:?}: {median}");
            for p in &tips {
                assert!(
                    p.iter().all(|&c| (0.0..=100.0).contains(&c)),
                    "{path:?} {p:?}"
                );
                assert!(p[2] < 40.0, "the tip cuts: {p:?}");
            }
        }
    }

    #[test]
    fn the_tool_is_tilted_and_turned_off_the_grid() {
        let seq = sequence(PathKind::Helix, 20, 3).unwrap();
        assert_eq!(seq.steps.len(), 3);
        for s in &seq.steps {
            assert_eq!(s.hull.len(), 4 * 20);
            // No two tip corners share a height: the axis leans.
            let mut z: Vec<i64> = s.hull.iter().map(|p| p[2]).collect();
            z.sort_unstable();
            z.dedup();
            assert!(z.len() > 20, "{}", z.len());
        }
        assert!(sequence(PathKind::Tilt, 2, 3).is_err());
    }
}
