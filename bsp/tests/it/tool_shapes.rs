//! Tool shapes: prisms, dodecahedra and swept volumes are valid strictly
//! convex polyhedra with the expected structure; bad numbers are errors.

use crate::common;

use chisel_bsp::Error;
use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::Sign;
use chisel_bsp::tools::{Pose, dodecahedron_corners, placed_tool, prism_corners, swept_tool};
use common::volume::volume;

#[test]
fn a_sixteen_sided_prism() {
    let mut arena = ConvexArena::new();
    let corners = prism_corners(16, 3000.0, 30000.0);
    let tool = placed_tool(&mut arena, &corners, &Pose::at([10000.0, 10000.0, 30000.0])).unwrap();
    arena.validate(tool).unwrap();
    assert_eq!(arena.faces_of(tool).len(), 18);
    assert_eq!(arena.vertices_of(tool).len(), 32);
    // Volume: area of the rounded 16-gon times the length, within rounding.
    let v = volume(&arena, tool);
    let v = (v.num / v.den).to_string().parse::<f64>().unwrap();
    let ideal = 0.5 * 16.0 * 3000.0f64.powi(2) * (std::f64::consts::TAU / 16.0).sin() * 30000.0;
    assert!((v / ideal - 1.0).abs() < 1e-3, "{v} vs {ideal}");
}

#[test]
fn a_rotated_dodecahedron() {
    let mut arena = ConvexArena::new();
    let (s, c) = (0.6f64, 0.8f64);
    let pose = Pose {
        rotation: [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        translation: [50000.0, 50000.0, 80000.0],
    };
    let tool = placed_tool(&mut arena, &dodecahedron_corners(3000.0), &pose).unwrap();
    arena.validate(tool).unwrap();
    assert_eq!(arena.vertices_of(tool).len(), 20);
    // Rounding may split a pentagon into triangles, never merge faces.
    let faces = arena.faces_of(tool).len();
    assert!((12..=36).contains(&faces), "{faces} faces");
}

#[test]
fn a_swept_prism_contains_both_end_poses() {
    let mut arena = ConvexArena::new();
    let corners = prism_corners(16, 3000.0, 30000.0);
    let (a, b) = (
        Pose::at([10000.0, 10000.0, 30000.0]),
        Pose::at([11500.0, 10000.0, 30000.0]),
    );
    let swept = swept_tool(&mut arena, &corners, &a, &b).unwrap();
    arena.validate(swept).unwrap();
    for pose in [a, b] {
        for &c in &corners {
            let q = pose.place(c).unwrap();
            for &f in &arena.faces_of(swept) {
                assert_ne!(arena.face_plane(f).side_of(q), Sign::Positive);
            }
        }
    }
}

#[test]
fn bad_numbers_are_errors() {
    let mut arena = ConvexArena::new();
    let corners = prism_corners(8, 10.0, 10.0);
    assert_eq!(
        placed_tool(&mut arena, &corners, &Pose::at([f64::NAN, 0.0, 0.0])).unwrap_err(),
        Error::NonFinite {
            what: "tool coordinate"
        }
    );
    assert!(matches!(
        placed_tool(&mut arena, &corners, &Pose::at([1e12, 0.0, 0.0])),
        Err(Error::CoordinateOutOfRange { axis: 0, .. })
    ));
    // Too small to survive rounding: all corners collapse.
    assert!(matches!(
        placed_tool(&mut arena, &prism_corners(8, 0.1, 0.1), &Pose::at([0.0; 3])),
        Err(Error::DegenerateHull { .. })
    ));
}
