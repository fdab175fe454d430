//! Carving with a convex quadric prop's shape: a sphere prop removes what
//! `CarveShape::Sphere` of the same radius removes, within the tolerance's
//! bound; a capped cylinder prop, turned and scaled, removes at least its
//! solid and at most the solid grown by the tolerance; props that are not
//! one intersection of convex solids are refused with the reason.

use bevy::math::DVec3;
use bevy::prelude::*;
use bevy_chisel::quadric::{CsgDag, NodeId, Quadric, Scene};
use bevy_chisel::terrain::{CarveShape, CarveTool, TerrainError};

use crate::terrain_round_tools::{ball, block, removed};

const GREY: [f32; 3] = [0.5, 0.5, 0.5];

fn scene(dag: CsgDag, root: NodeId) -> Scene {
    let names = (0..dag.primitives().len())
        .map(|i| format!("p{i}"))
        .collect();
    Scene {
        dag,
        root,
        names,
        bounds: None,
    }
}

fn sphere_scene(radius: f64) -> Scene {
    let mut dag = CsgDag::new();
    let root = dag.primitive(Quadric::sphere(DVec3::ZERO, radius).unwrap(), GREY);
    scene(dag, root)
}

/// A cylinder of `r` along `z` from `−h` to `h`: an infinite cylinder
/// between two half-spaces.
fn capped_cylinder(r: f64, h: f64) -> Scene {
    let mut dag = CsgDag::new();
    let side = dag.primitive(Quadric::cylinder(DVec3::ZERO, DVec3::Z, r).unwrap(), GREY);
    let top = dag.primitive(Quadric::half_space(DVec3::Z, h).unwrap(), GREY);
    let bottom = dag.primitive(Quadric::half_space(DVec3::NEG_Z, h).unwrap(), GREY);
    let root = dag.intersection(&[side, top, bottom]).unwrap();
    scene(dag, root)
}

fn prop_tool(scene: &Scene, pose: Transform, tolerance: f32) -> Result<CarveTool, TerrainError> {
    CarveTool::from_prop(scene, &pose, tolerance, block().quantization())
}

#[test]
fn a_sphere_prop_carves_as_a_sphere_tool() {
    let centre = Vec3::new(2.0003, 0.1007, 1.9991);
    let t = 0.02;
    let from_prop =
        removed(&prop_tool(&sphere_scene(1.0), Transform::from_translation(centre), t).unwrap());
    let from_shape = removed(&CarveTool::new(
        CarveShape::Sphere {
            radius: 1.0,
            tolerance: Some(t),
        },
        Transform::from_translation(centre),
    ));
    let bound = ball(1.0 + f64::from(t)) - ball(1.0);
    for v in [from_prop, from_shape] {
        assert!(v >= ball(1.0) && v <= ball(1.0) + bound, "{v} m³");
    }
    assert!((from_prop - from_shape).abs() <= bound);
    // A prop of radius 2 scaled by a half is the same sphere.
    let scaled = removed(
        &prop_tool(
            &sphere_scene(2.0),
            Transform::from_translation(centre).with_scale(Vec3::splat(0.5)),
            t,
        )
        .unwrap(),
    );
    assert!(
        scaled >= ball(1.0) && scaled <= ball(1.0) + bound,
        "{scaled} m³"
    );
}

#[test]
fn a_turned_capped_cylinder_prop_is_within_its_tolerance() {
    let (r, h, t) = (0.5f64, 0.8f64, 0.01f32);
    let pose = Transform::from_xyz(2.0, 0.0, 2.0).with_rotation(Quat::from_euler(
        EulerRot::XYZ,
        0.4,
        0.3,
        1.1,
    ));
    let v = removed(&prop_tool(&capped_cylinder(r, h), pose, t).unwrap());
    let cylinder = |r: f64, h: f64| std::f64::consts::PI * r * r * 2.0 * h;
    let t = f64::from(t);
    assert!(
        v >= cylinder(r, h) && v <= cylinder(r + t, h + t),
        "{v} m³ not in [{}, {}]",
        cylinder(r, h),
        cylinder(r + t, h + t)
    );
}

#[test]
fn props_that_are_not_convex_are_refused() {
    let at = Transform::from_xyz(2.0, 0.0, 2.0);
    // Two balls: a union of two intersections.
    let mut dag = CsgDag::new();
    let a = dag.primitive(Quadric::sphere(DVec3::ZERO, 0.5).unwrap(), GREY);
    let b = dag.primitive(Quadric::sphere(DVec3::X, 0.5).unwrap(), GREY);
    let root = dag.union(&[a, b]).unwrap();
    assert!(matches!(
        prop_tool(&scene(dag, root), at, 0.02),
        Err(TerrainError::PropNotConvex { .. })
    ));
    // A ball with a bite: it keeps the outside of a sphere.
    let mut dag = CsgDag::new();
    let a = dag.primitive(Quadric::sphere(DVec3::ZERO, 0.5).unwrap(), GREY);
    let b = dag.primitive(Quadric::sphere(DVec3::X * 0.5, 0.3).unwrap(), GREY);
    let root = dag.difference(a, &[b]).unwrap();
    match prop_tool(&scene(dag, root), at, 0.02) {
        Err(TerrainError::PropNotConvex { reason }) => {
            assert!(reason.contains("outside of primitive `p1`"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // A double cone is not convex either.
    let mut dag = CsgDag::new();
    let cone = dag.primitive(Quadric::cone(DVec3::ZERO, DVec3::Z, 0.4).unwrap(), GREY);
    let cap = dag.primitive(Quadric::sphere(DVec3::ZERO, 0.5).unwrap(), GREY);
    let root = dag.intersection(&[cone, cap]).unwrap();
    assert!(matches!(
        prop_tool(&scene(dag, root), at, 0.02),
        Err(TerrainError::PropNotConvex { .. })
    ));
    // Convex but unbounded: a paraboloid.
    let mut dag = CsgDag::new();
    let root = dag.primitive(
        Quadric::elliptic_paraboloid(bevy::math::DVec2::ONE).unwrap(),
        GREY,
    );
    assert!(matches!(
        prop_tool(
            &scene(dag, root),
            at.with_translation(Vec3::new(2.0, -0.5, 2.0)),
            0.02
        ),
        Err(TerrainError::InvalidProp { .. })
    ));
    // Bad tolerances.
    assert!(matches!(
        prop_tool(&sphere_scene(1.0), at, 0.0),
        Err(TerrainError::InvalidTool { .. })
    ));
    assert!(matches!(
        prop_tool(&sphere_scene(1.0), at, 0.001),
        Err(TerrainError::Kernel(
            bevy_chisel::bsp::Error::ToleranceUnreachable { .. }
        ))
    ));
}
