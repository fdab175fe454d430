//! Round tools: spheres, cylinders and capsules, rounded to the grid at a
//! turned pose, contain the true shape and lie within the tolerance of its
//! surface (Hausdorff distance, sampled densely both ways); a sphere
//! carved from a slab removes exactly its hull's volume, which converges
//! to `4/3·π·r³` within the tolerance's bound; bad numbers are typed
//! errors that leave the octree as it was.

use crate::common;

use chisel_bsp::Error;
use chisel_bsp::convex::ConvexArena;
use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
use chisel_bsp::tools::{
    GRID_ROUNDING, Pose, capsule_corners, cylinder_corners, placed_tool, sphere_corners,
};
use common::octree_reference::octree_volumes;
use common::volume::{Fraction, volume};

/// A true shape in its own frame (centre at the origin, axis `z`).
#[derive(Clone, Copy, Debug)]
enum Shape {
    Sphere { r: f64 },
    Cylinder { r: f64, h: f64 },
    Capsule { r: f64, h: f64 },
}

impl Shape {
    /// Signed Euclidean distance to the shape's surface (negative inside).
    fn signed_distance(self, p: [f64; 3]) -> f64 {
        match self {
            Shape::Sphere { r } => len(p) - r,
            Shape::Cylinder { r, h } => {
                let radial = p[0].hypot(p[1]) - r;
                let axial = p[2].abs() - h;
                if radial > 0.0 && axial > 0.0 {
                    radial.hypot(axial)
                } else {
                    radial.max(axial)
                }
            }
            Shape::Capsule { r, h } => len([p[0], p[1], p[2] - p[2].clamp(-h, h)]) - r,
        }
    }

    /// Points on the surface, about `n²` of them, evenly spread.
    fn surface_samples(self, n: usize) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        let ring = |radius: f64, z: f64, out: &mut Vec<[f64; 3]>| {
            for k in 0..n {
                let a = (k as f64 + 0.37) * std::f64::consts::TAU / n as f64;
                out.push([radius * a.cos(), radius * a.sin(), z]);
            }
        };
        match self {
            Shape::Sphere { r } => {
                for i in 0..=n {
                    let polar = i as f64 * std::f64::consts::PI / n as f64;
                    ring(r * polar.sin(), r * polar.cos(), &mut out);
                }
            }
            Shape::Cylinder { r, h } => {
                for i in 0..=n {
                    let z = -h + 2.0 * h * i as f64 / n as f64;
                    ring(r, z, &mut out);
                }
                for i in 0..=n {
                    let radius = r * i as f64 / n as f64;
                    ring(radius, h, &mut out);
                    ring(radius, -h, &mut out);
                }
            }
            Shape::Capsule { r, h } => {
                for i in 0..=n {
                    let polar = i as f64 * std::f64::consts::PI / n as f64;
                    let z = r * polar.cos();
                    ring(r * polar.sin(), z + if z >= 0.0 { h } else { -h }, &mut out);
                }
                for i in 0..=n {
                    ring(r, -h + 2.0 * h * i as f64 / n as f64, &mut out);
                }
            }
        }
        out
    }

    fn corners(self, tolerance: f64) -> Vec<[f64; 3]> {
        let got = match self {
            Shape::Sphere { r } => sphere_corners(r, tolerance, GRID_ROUNDING, 8192),
            Shape::Cylinder { r, h } => cylinder_corners(r, h, tolerance, GRID_ROUNDING, 8192),
            Shape::Capsule { r, h } => capsule_corners(r, h, tolerance, GRID_ROUNDING, 8192),
        }
        .unwrap();
        assert!(got.deviation <= tolerance);
        got.corners
    }
}

fn len(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

/// A turn about a skew axis and a translation off the grid.
fn turned_pose() -> Pose {
    let (s, c) = (0.6f64, 0.8f64);
    // Rx(θ)·Rz(θ) with cos θ = 0.8.
    let rz = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
    let rx = [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]];
    let mut rotation = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            rotation[i][j] = (0..3).map(|k| rx[i][k] * rz[k][j]).sum();
        }
    }
    Pose {
        rotation,
        translation: [40_000.31, 41_000.62, 39_000.47],
    }
}

/// The point of the shape's frame at world position `p` (rotation
/// transposed).
fn to_shape_frame(pose: &Pose, p: [f64; 3]) -> [f64; 3] {
    let d = [0, 1, 2].map(|i| p[i] - pose.translation[i]);
    [0, 1, 2].map(|j| (0..3).map(|i| pose.rotation[i][j] * d[i]).sum())
}

/// Checks containment and the Hausdorff distance both ways, sampled.
fn check_hausdorff(shape: Shape, tolerance: f64) {
    let pose = turned_pose();
    let mut arena = ConvexArena::new();
    let tool = placed_tool(&mut arena, &shape.corners(tolerance), &pose).unwrap();
    arena.validate(tool).unwrap();
    let faces = arena.face_polygons(tool);
    // Outward unit normals and offsets: inside is `n·x + d ≤ 0`.
    let planes: Vec<([f64; 3], f64)> = faces
        .iter()
        .map(|(plane, _)| {
            let [a, b, c, d] = plane.approx();
            let l = len([a, b, c]);
            ([a / l, b / l, c / l], d / l)
        })
        .collect();
    // True surface → polytope: every sample inside, within the tolerance
    // of the nearest face.
    let mut worst_in = 0.0f64;
    for p in shape.surface_samples(120) {
        let w = pose.apply(p);
        let to_face = planes
            .iter()
            .map(|(n, d)| -(n[0] * w[0] + n[1] * w[1] + n[2] * w[2] + d))
            .fold(f64::INFINITY, f64::min);
        assert!(
            to_face >= -1e-6,
            "{shape:?}: surface point {p:?} outside the tool"
        );
        worst_in = worst_in.max(to_face);
    }
    // Polytope surface → true surface: every sample outside the shape and
    // within the tolerance.
    let mut worst_out = 0.0f64;
    for (_, corners) in &faces {
        let a = corners[0];
        for k in 1..corners.len() - 1 {
            let (b, c) = (corners[k], corners[k + 1]);
            let n = 12;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let w = [0, 1, 2].map(|x| a[x] + u * (b[x] - a[x]) + v * (c[x] - a[x]));
                    let d = shape.signed_distance(to_shape_frame(&pose, w));
                    assert!(
                        d >= -1e-6,
                        "{shape:?}: tool surface inside the shape by {d}"
                    );
                    worst_out = worst_out.max(d);
                }
            }
        }
    }
    assert!(
        worst_in <= tolerance && worst_out <= tolerance,
        "{shape:?}: Hausdorff {worst_in} / {worst_out} over {tolerance}"
    );
    // Far from the grid the fit uses the tolerance: it is not far finer
    // than asked.
    if tolerance > 20.0 {
        assert!(worst_out.max(worst_in) > tolerance / 4.0, "{shape:?}");
    }
}

#[test]
fn a_sphere_is_within_its_tolerance() {
    check_hausdorff(Shape::Sphere { r: 3000.0 }, 60.0);
    check_hausdorff(Shape::Sphere { r: 3000.0 }, 8.0);
    // Close to the grid: the tolerance must be more than 2·δ.
    check_hausdorff(Shape::Sphere { r: 40.0 }, 3.0);
}

#[test]
fn a_cylinder_is_within_its_tolerance() {
    check_hausdorff(
        Shape::Cylinder {
            r: 2000.0,
            h: 3000.0,
        },
        50.0,
    );
    check_hausdorff(Shape::Cylinder { r: 30.0, h: 5.0 }, 3.0);
}

#[test]
fn a_capsule_is_within_its_tolerance() {
    check_hausdorff(
        Shape::Capsule {
            r: 1500.0,
            h: 2500.0,
        },
        40.0,
    );
    check_hausdorff(Shape::Capsule { r: 25.0, h: 0.0 }, 3.0);
}

/// The exact volume a sphere of `r` within `tolerance` removes from a
/// slab, checked against the exact volume of the tool's own hull.
fn carved_sphere_volume(r: f64, tolerance: f64) -> f64 {
    let slab = CellBox {
        min: [0, 0, 20_000],
        max: [100_000, 100_000, 80_000],
    };
    let mut octree = Octree::from_box([0; 3], 17, slab, 1, OctreeConfig::default()).unwrap();
    let before = octree_volumes(&octree).remove(&1).unwrap();
    let pose = Pose::at([50_000.4, 49_999.7, 50_000.2]);
    let corners = Shape::Sphere { r }.corners(tolerance);
    let mut arena = ConvexArena::new();
    let hull = placed_tool(&mut arena, &corners, &pose).unwrap();
    let points: Vec<_> = corners.iter().map(|&c| pose.place(c).unwrap()).collect();
    octree
        .apply(&Tool::convex_hull(&points).unwrap(), Edit::Subtract)
        .unwrap();
    let after = octree_volumes(&octree).remove(&1).unwrap();
    // Exact bookkeeping: what is left plus the tool is the slab.
    assert!(after.add(&volume(&arena, hull)) == before);
    let removed = Fraction::new(
        &before.num * &after.den - &after.num * &before.den,
        &before.den * &after.den,
    );
    removed.to_f64()
}

#[test]
fn a_carved_sphere_converges_to_the_ball_within_the_tolerance() {
    let r = 20_000.0;
    let ball = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let mut last_error = f64::INFINITY;
    for tolerance in [2000.0, 400.0, 80.0] {
        let v = carved_sphere_volume(r, tolerance);
        assert!(
            v >= ball(r) && v <= ball(r + tolerance),
            "tolerance {tolerance}: {v} not in [{}, {}]",
            ball(r),
            ball(r + tolerance)
        );
        let error = v / ball(r) - 1.0;
        assert!(error < last_error, "{error} after {last_error}");
        last_error = error;
    }
}

#[test]
fn bad_numbers_are_typed_errors_and_change_nothing() {
    for r in [0.0, -5.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            sphere_corners(r, 1.0, GRID_ROUNDING, 8192),
            Err(Error::InvalidRoundTool { .. })
        ));
        assert!(matches!(
            capsule_corners(r, 1.0, 1.0, GRID_ROUNDING, 8192),
            Err(Error::InvalidRoundTool { .. })
        ));
        assert!(matches!(
            cylinder_corners(r, 1.0, 1.0, GRID_ROUNDING, 8192),
            Err(Error::InvalidRoundTool { .. })
        ));
    }
    for t in [0.0, -1.0, f64::NAN] {
        assert!(matches!(
            sphere_corners(100.0, t, GRID_ROUNDING, 8192),
            Err(Error::InvalidRoundTool { .. })
        ));
    }
    assert!(matches!(
        cylinder_corners(100.0, 0.0, 5.0, GRID_ROUNDING, 8192),
        Err(Error::InvalidRoundTool { .. })
    ));
    assert!(matches!(
        capsule_corners(100.0, -1.0, 5.0, GRID_ROUNDING, 8192),
        Err(Error::InvalidRoundTool { .. })
    ));
    // Within twice the rounding no polyhedron can be sure to fit.
    assert!(matches!(
        sphere_corners(100.0, 1.7, GRID_ROUNDING, 8192),
        Err(Error::ToleranceUnreachable {
            max_points: 8192,
            ..
        })
    ));
    // Reachable, but not within the cap on corners.
    match sphere_corners(100_000.0, 1.0, 0.0, 500) {
        Err(Error::ToleranceUnreachable { best, .. }) => assert!(best > 1.0 && best.is_finite()),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        cylinder_corners(100_000.0, 10.0, 1.0, 0.0, 64),
        Err(Error::ToleranceUnreachable { .. })
    ));
    // A failed tool is no edit: the octree is as it was.
    let slab = CellBox {
        min: [0; 3],
        max: [1000; 3],
    };
    let mut octree = Octree::from_box([0; 3], 10, slab, 1, OctreeConfig::default()).unwrap();
    let hash = octree.state_hash();
    let result = capsule_corners(300.0, 100.0, 0.5, GRID_ROUNDING, 8192).and_then(|c| {
        let points = c
            .corners
            .iter()
            .map(|&p| Pose::at([500.0; 3]).place(p))
            .collect::<Result<Vec<_>, _>>()?;
        octree.apply(&Tool::convex_hull(&points)?, Edit::Subtract)
    });
    assert!(matches!(result, Err(Error::ToleranceUnreachable { .. })));
    assert_eq!(octree.state_hash(), hash);
}
