//! `chisel sweep`: the volume swept by a gear moving along a cubic Bézier
//! curve while turning, as a union of convex pieces (paper 1 §5, Fig. 12).
//!
//! The gear is an extruded outline of `TEETH` trapezoidal teeth, closed by
//! fans from the axis, so its triangle mesh is closed and star-shaped.
//! With poses `P_0 … P_{n−1}` sampled along the curve, the swept volume is
//! the gear at `P_0` (as the convex wedges of its fans) and, for every
//! `k` and every triangle `T` of the mesh, the *sweep prism*
//! `hull(P_k T ∪ P_{k+1} T)`: every point the moving solid covers was
//! either inside it at the start or crossed by its boundary. A triangle
//! that moves within its own plane sweeps no volume; such flat prisms are
//! left out.

use chisel_bsp::tools::Pose;

use super::sequence::{Base, Op, Sequence, Step, UNITS_PER_MM, spans_volume};

/// Teeth of the gear.
const TEETH: usize = 12;
/// Root and tip radius, and thickness, mm.
const ROOT_MM: f64 = 8.0;
const TIP_MM: f64 = 10.0;
const THICKNESS_MM: f64 = 6.0;
/// Control points of the path of the gear's centre, mm.
const CURVE_MM: [[f64; 3]; 4] = [
    [15.0, 15.0, 15.0],
    [95.0, 10.0, 45.0],
    [5.0, 90.0, 70.0],
    [85.0, 85.0, 35.0],
];
/// Turns of the gear about its axis over the whole path.
const TURNS: f64 = 1.0;

/// A closed triangle mesh (grid units), with the convex wedges that make
/// up its solid.
pub struct Gear {
    /// Corner positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, counter-clockwise from outside.
    pub triangles: Vec<[usize; 3]>,
    /// Convex pieces whose union is the solid, as corner lists.
    pub wedges: Vec<Vec<usize>>,
}

/// The gear centred at the origin, axis `+z`, from `z = −t/2` to `t/2`.
#[must_use]
pub fn gear() -> Gear {
    let pitch = std::f64::consts::TAU / TEETH as f64;
    // Per tooth: root, tip, tip, root, at a quarter pitch apart.
    let outline: Vec<[f64; 2]> = (0..TEETH)
        .flat_map(|k| {
            [
                (0.0, ROOT_MM),
                (0.25, TIP_MM),
                (0.5, TIP_MM),
                (0.75, ROOT_MM),
            ]
            .map(|(f, r)| {
                let a = (k as f64 + f) * pitch;
                [r * a.cos(), r * a.sin()]
            })
        })
        .collect();
    let n = outline.len();
    let h = 0.5 * THICKNESS_MM;
    let mut vertices: Vec<[f64; 3]> = Vec::with_capacity(2 * n + 2);
    for z in [-h, h] {
        vertices.extend(outline.iter().map(|p| [p[0], p[1], z]));
    }
    vertices.push([0.0, 0.0, -h]);
    vertices.push([0.0, 0.0, h]);
    let vertices = vertices
        .into_iter()
        .map(|p| p.map(|c| c * UNITS_PER_MM))
        .collect();
    let (bottom, top) = (2 * n, 2 * n + 1);
    let mut triangles = Vec::with_capacity(4 * n);
    let mut wedges = Vec::with_capacity(n);
    for i in 0..n {
        let j = (i + 1) % n;
        triangles.push([bottom, j, i]);
        triangles.push([top, n + i, n + j]);
        triangles.push([i, j, n + j]);
        triangles.push([i, n + j, n + i]);
        wedges.push(vec![bottom, i, j, top, n + i, n + j]);
    }
    Gear {
        vertices,
        triangles,
        wedges,
    }
}

/// The cubic Bézier point at `t ∈ [0, 1]`, mm.
fn curve(t: f64) -> [f64; 3] {
    let s = 1.0 - t;
    let w = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
    [0, 1, 2].map(|a| (0..4).map(|k| w[k] * CURVE_MM[k][a]).sum())
}

/// The gear's pose at sample `k` of `samples`.
fn pose(k: usize, samples: usize) -> Pose {
    let t = k as f64 / (samples - 1).max(1) as f64;
    let (s, c) = (TURNS * std::f64::consts::TAU * t).sin_cos();
    Pose {
        rotation: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        translation: curve(t).map(|x| x * UNITS_PER_MM),
    }
}

/// The sweep over `samples` positions (at least 2): the unions, and how
/// many flat sweep prisms were left out.
///
/// # Errors
/// Fewer than two samples, or a position beyond the exact range.
pub fn sequence(samples: usize) -> Result<(Sequence, usize), String> {
    if samples < 2 {
        return Err("a sweep needs at least 2 samples".into());
    }
    let gear = gear();
    let placed: Vec<Vec<[i64; 3]>> = (0..samples)
        .map(|k| {
            let pose = pose(k, samples);
            gear.vertices
                .iter()
                .map(|&v| pose.place(v).map(|p| p.coords()).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    let mut steps: Vec<Step> = gear
        .wedges
        .iter()
        .map(|w| Step {
            op: Op::Union,
            hull: w.iter().map(|&v| placed[0][v]).collect(),
        })
        .collect();
    let mut flat = 0;
    for pair in placed.windows(2) {
        for t in &gear.triangles {
            let hull: Vec<[i64; 3]> = t.iter().flat_map(|&v| [pair[0][v], pair[1][v]]).collect();
            if spans_volume(&hull) {
                steps.push(Step {
                    op: Op::Union,
                    hull,
                });
            } else {
                flat += 1;
            }
        }
    }
    Ok((
        Sequence {
            base: Base::Empty,
            steps,
        },
        flat,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn the_gear_is_closed_and_consistently_oriented() {
        let g = gear();
        let mut edges: HashMap<(usize, usize), i32> = HashMap::new();
        for t in &g.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1));
        }
        // Outward: the signed volume is positive and near the prism's.
        let six: f64 = g
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| g.vertices[v]);
                a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            })
            .sum();
        let volume_mm3 = six / 6.0 / 1e9;
        let disc = std::f64::consts::PI * ROOT_MM * ROOT_MM * THICKNESS_MM;
        assert!(volume_mm3 > disc && volume_mm3 < disc * 1.6, "{volume_mm3}");
    }

    #[test]
    fn the_sweep_has_wedges_then_prisms() {
        let (seq, flat) = sequence(3).unwrap();
        let g = gear();
        assert_eq!(
            seq.steps.len() + flat,
            g.wedges.len() + 2 * g.triangles.len()
        );
        assert!(
            seq.steps
                .iter()
                .all(|s| s.op == Op::Union && spans_volume(&s.hull))
        );
        assert!(sequence(1).is_err());
    }
}
