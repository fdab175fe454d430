//! Swept volumes of non-convex solids as unions of convex pieces (paper 1
//! §5, Fig. 12): a gear moving along a cubic Bézier curve while turning.
//!
//! Notation: `M` — a closed triangle mesh whose solid is also given as a
//! union of convex *wedges*; `P_0 … P_{n−1}` — poses sampled along the path;
//! `P T` — triangle `T` placed at pose `P`.
//!
//! The swept volume is the solid at `P_0` (the union of its wedges there)
//! and, for every `k` and every triangle `T` of `M`, the *sweep prism*
//! `hull(P_k T ∪ P_{k+1} T)`: every point the moving solid covers was
//! either inside it at the start or crossed by its boundary. Between two
//! samples the motion is taken as each corner moving straight from one
//! pose to the next; the prism holds every placement of the triangle on
//! that motion. For a translation this is the true sweep; for a turning
//! solid it differs from the true sweep by each step's sagitta (the gap
//! between the arc of a corner and its chord), which shrinks with the
//! square of the step, so dense samples approach the true volume. The
//! unions themselves are exact. A triangle
//! that moves within its own plane sweeps no volume: its prism is flat
//! once rounded to the grid and is left out ([`spans_volume`]).
//!
//! Everything here is generic over where the corners were placed (grid
//! points, or world points that a caller rounds itself), so the command
//! line's `sweep` scenario and the `sweep` example build the same pieces.

use super::shapes::Pose;

/// A closed triangle mesh together with convex pieces (wedges) whose union
/// is its solid.
#[derive(Clone, Debug, PartialEq)]
pub struct WedgeMesh {
    /// Corner positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as corner indices, counter-clockwise seen from outside.
    pub triangles: Vec<[usize; 3]>,
    /// Convex pieces whose union is the solid, as corner-index lists.
    pub wedges: Vec<Vec<usize>>,
}

impl WedgeMesh {
    /// The corners of every wedge, taken from `placed` (one entry per
    /// vertex, e.g. the vertices placed at a pose and rounded): the solid
    /// at that pose as convex point sets.
    ///
    /// Precondition: `placed.len() == self.vertices.len()`.
    #[must_use]
    pub fn wedge_points<T: Copy>(&self, placed: &[T]) -> Vec<Vec<T>> {
        self.wedges
            .iter()
            .map(|w| w.iter().map(|&v| placed[v]).collect())
            .collect()
    }

    /// The six corners of the sweep prism of triangle `triangle` from
    /// `from` to `to` (the vertices placed at two consecutive poses): its
    /// corners at both, in the order `a₀ a₁ b₀ b₁ c₀ c₁`.
    ///
    /// Precondition: `triangle < self.triangles.len()`, and `from` and `to`
    /// have one entry per vertex.
    #[must_use]
    pub fn prism_points<T: Copy>(&self, triangle: usize, from: &[T], to: &[T]) -> Vec<T> {
        self.triangles[triangle]
            .iter()
            .flat_map(|&v| [from[v], to[v]])
            .collect()
    }

    /// The sweep prisms from `from` to `to` (grid points) that span a
    /// volume, and how many flat ones were left out.
    #[must_use]
    pub fn sweep_prisms(&self, from: &[[i64; 3]], to: &[[i64; 3]]) -> (Vec<Vec<[i64; 3]>>, usize) {
        let mut prisms = Vec::with_capacity(self.triangles.len());
        let mut flat = 0;
        for t in 0..self.triangles.len() {
            let hull = self.prism_points(t, from, to);
            if spans_volume(&hull) {
                prisms.push(hull);
            } else {
                flat += 1;
            }
        }
        (prisms, flat)
    }
}

/// A spur gear: an extruded outline of trapezoidal teeth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gear {
    /// Number of teeth (at least 3).
    pub teeth: usize,
    /// Radius at the foot of the teeth.
    pub root_radius: f64,
    /// Radius at the tips of the teeth.
    pub tip_radius: f64,
    /// Extent along the axis.
    pub thickness: f64,
}

impl Gear {
    /// The mesh of the gear centred at the origin, axis `+z`, from
    /// `z = −thickness/2` to `thickness/2`.
    ///
    /// The outline has four corners per tooth (root, tip, tip, root, a
    /// quarter pitch apart); the caps are fans from the axis, so the mesh
    /// is closed and star-shaped, and each fan sector extruded is a convex
    /// wedge (a triangular prism).
    #[must_use]
    pub fn mesh(&self) -> WedgeMesh {
        let pitch = std::f64::consts::TAU / self.teeth as f64;
        let outline: Vec<[f64; 2]> = (0..self.teeth)
            .flat_map(|k| {
                [
                    (0.0, self.root_radius),
                    (0.25, self.tip_radius),
                    (0.5, self.tip_radius),
                    (0.75, self.root_radius),
                ]
                .map(|(f, r)| {
                    let a = (k as f64 + f) * pitch;
                    [r * a.cos(), r * a.sin()]
                })
            })
            .collect();
        let n = outline.len();
        let h = 0.5 * self.thickness;
        let mut vertices: Vec<[f64; 3]> = Vec::with_capacity(2 * n + 2);
        for z in [-h, h] {
            vertices.extend(outline.iter().map(|p| [p[0], p[1], z]));
        }
        vertices.push([0.0, 0.0, -h]);
        vertices.push([0.0, 0.0, h]);
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
        WedgeMesh {
            vertices,
            triangles,
            wedges,
        }
    }
}

/// A cubic Bézier curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicBezier {
    /// The four control points.
    pub control: [[f64; 3]; 4],
}

impl CubicBezier {
    /// The point at parameter `t ∈ [0, 1]`.
    #[must_use]
    pub fn point(&self, t: f64) -> [f64; 3] {
        let s = 1.0 - t;
        let w = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
        [0, 1, 2].map(|a| (0..4).map(|k| w[k] * self.control[k][a]).sum())
    }
}

/// A gear moving along a curve while turning about its own axis (which
/// stays parallel to `+z`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GearSweep {
    /// The gear.
    pub gear: Gear,
    /// The path of its centre.
    pub curve: CubicBezier,
    /// Turns about its axis over the whole path.
    pub turns: f64,
}

impl GearSweep {
    /// The sweep of the `chisel sweep` scenario and the `sweep` example, in
    /// millimetres: a 12-tooth gear (root radius 8, tip 10, 6 thick) over
    /// one turn along a curve inside `[5, 95]³`.
    pub const FIG12_MM: GearSweep = GearSweep {
        gear: Gear {
            teeth: 12,
            root_radius: 8.0,
            tip_radius: 10.0,
            thickness: 6.0,
        },
        curve: CubicBezier {
            control: [
                [15.0, 15.0, 15.0],
                [95.0, 10.0, 45.0],
                [5.0, 90.0, 70.0],
                [85.0, 85.0, 35.0],
            ],
        },
        turns: 1.0,
    };

    /// The gear's pose at sample `k` of `samples` (evenly spaced in the
    /// curve parameter, the first at its start, the last at its end), in
    /// the sweep's own units.
    #[must_use]
    pub fn pose(&self, k: usize, samples: usize) -> Pose {
        let t = k as f64 / (samples.max(2) - 1) as f64;
        let (s, c) = (self.turns * std::f64::consts::TAU * t).sin_cos();
        Pose {
            rotation: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
            translation: self.curve.point(t),
        }
    }
}

/// Whether `points` (grid units) span a volume (four of them not
/// coplanar): exactly when their convex hull is a tool rather than a
/// degenerate-hull error. Exact: coordinates within the kernel's range give cross
/// products below 2^56 and dot products below 2^84, inside `i128`.
#[must_use]
pub fn spans_volume(points: &[[i64; 3]]) -> bool {
    let sub = |a: [i64; 3], b: [i64; 3]| [0, 1, 2].map(|i| i128::from(a[i]) - i128::from(b[i]));
    let cross = |u: [i128; 3], v: [i128; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let Some(&a) = points.first() else {
        return false;
    };
    let Some(&b) = points.iter().find(|&&p| p != a) else {
        return false;
    };
    let ab = sub(b, a);
    let Some(normal) = points
        .iter()
        .map(|&p| cross(ab, sub(p, a)))
        .find(|n| *n != [0; 3])
    else {
        return false;
    };
    points.iter().any(|&p| {
        let d = sub(p, a);
        normal[0] * d[0] + normal[1] * d[1] + normal[2] * d[2] != 0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn the_gear_is_closed_and_consistently_oriented() {
        let gear = GearSweep::FIG12_MM.gear;
        let g = gear.mesh();
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
        let volume = six / 6.0;
        let disc = std::f64::consts::PI * gear.root_radius * gear.root_radius * gear.thickness;
        assert!(volume > disc && volume < disc * 1.6, "{volume}");
        assert_eq!(g.wedges.len(), 4 * gear.teeth);
        assert!(g.wedges.iter().all(|w| w.len() == 6));
    }

    #[test]
    fn poses_run_from_the_curve_start_to_its_end() {
        let sweep = GearSweep::FIG12_MM;
        let first = sweep.pose(0, 10);
        let last = sweep.pose(9, 10);
        assert_eq!(first.translation, sweep.curve.control[0]);
        assert_eq!(last.translation, sweep.curve.control[3]);
        // One whole turn: the last rotation is the identity again.
        assert!((last.rotation[0][0] - 1.0).abs() < 1e-12);
        assert!(last.rotation[0][1].abs() < 1e-12);
    }

    #[test]
    fn a_triangle_moving_in_its_plane_sweeps_no_volume() {
        let g = Gear {
            teeth: 4,
            root_radius: 8.0,
            tip_radius: 10.0,
            thickness: 6.0,
        }
        .mesh();
        let place = |shift: [i64; 3]| -> Vec<[i64; 3]> {
            g.vertices
                .iter()
                .map(|v| [0, 1, 2].map(|a| (v[a] * 1000.0).round() as i64 + shift[a]))
                .collect()
        };
        // Sliding along x keeps the caps in their planes: their prisms are
        // flat, the rim's are not.
        let (prisms, flat) = g.sweep_prisms(&place([0; 3]), &place([5000, 0, 0]));
        assert_eq!(flat, 2 * 4 * 4, "every cap triangle");
        assert_eq!(prisms.len() + flat, g.triangles.len());
        assert!(prisms.iter().all(|p| p.len() == 6 && spans_volume(p)));
        // Lifting along the axis moves every rim triangle within its plane.
        let (prisms, flat) = g.sweep_prisms(&place([0; 3]), &place([0, 0, 5000]));
        assert_eq!(flat, 2 * 4 * 4, "every rim triangle");
        assert_eq!(prisms.len(), 2 * 4 * 4);
    }

    #[test]
    fn spans_volume_knows_flat_sets() {
        let tet = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]];
        assert!(spans_volume(&tet));
        assert!(!spans_volume(&tet[..3]));
        assert!(!spans_volume(&[[0, 0, 0]; 5]));
        assert!(!spans_volume(&[[0, 0, 0], [1, 1, 1], [2, 2, 2], [5, 5, 5]]));
        assert!(!spans_volume(&[[0, 0, 7], [1, 0, 7], [0, 1, 7], [3, 9, 7]]));
    }
}
