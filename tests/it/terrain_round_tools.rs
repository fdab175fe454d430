//! Round carve tools on a terrain: a sphere, cylinder or capsule removes at
//! least its true shape and at most the shape grown by its tolerance
//! (exact volumes of the octree), finer tolerances come closer to the true
//! volume, and bad numbers are typed errors that leave the terrain as it
//! was.

use std::f64::consts::PI;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{CarveShape, CarveTool, Heightfield, Terrain, TerrainError};

/// A 4 m × 4 m × 6 m block of rock on a millimetre grid, its top at `y = 3`.
pub fn block() -> Terrain {
    let field = Heightfield {
        size: UVec2::new(2, 2),
        heights: vec![3.0; 4],
        spacing: 4.0,
        corner: Vec3::ZERO,
        bottom: -3.0,
        label: 1,
        layers: Vec::new(),
    };
    let mm = Quantization::new(0.001, [0.0; 3]).expect("valid unit");
    Terrain::from_heightfield(mm, &field).expect("valid heightfield")
}

/// Rock in the terrain, cubic metres.
fn rock(terrain: &Terrain) -> f64 {
    terrain.octree().volumes().get(&1).copied().unwrap_or(0.0) * 1e-9
}

/// Rounds `tool` to the terrain's grid and subtracts it.
pub fn carve(terrain: &mut Terrain, tool: &CarveTool) -> Result<(), TerrainError> {
    let grid = tool.to_grid(terrain.quantization())?;
    terrain.apply_now(&grid, Edit::Subtract)?;
    Ok(())
}

/// Cubic metres `tool` removes from a fresh block.
pub fn removed(tool: &CarveTool) -> f64 {
    let mut terrain = block();
    let before = rock(&terrain);
    carve(&mut terrain, tool).expect("the carve succeeds");
    before - rock(&terrain)
}

pub fn ball(r: f64) -> f64 {
    4.0 / 3.0 * PI * r.powi(3)
}

fn assert_between(what: &str, v: f64, lo: f64, hi: f64) {
    assert!(v >= lo && v <= hi, "{what}: {v} m³ not in [{lo}, {hi}]");
}

fn turned(at: Vec3) -> Transform {
    Transform::from_translation(at).with_rotation(Quat::from_euler(EulerRot::XYZ, 0.4, 0.3, 1.1))
}

#[test]
fn round_tools_remove_their_shape_and_at_most_their_tolerance_more() {
    let centre = Vec3::new(2.0003, 0.1007, 1.9991);
    // The default tolerance: 2 % of the radius.
    let v = removed(&CarveTool::sphere(1.0, centre));
    assert_between("sphere", v, ball(1.0), ball(1.02));
    let t = 0.008;
    let v = removed(&CarveTool::new(
        CarveShape::Sphere {
            radius: 1.0,
            tolerance: Some(t as f32),
        },
        Transform::from_translation(centre),
    ));
    assert_between("fine sphere", v, ball(1.0), ball(1.0 + t));
    // A turned cylinder: inside the cylinder grown by `t` on every side.
    let (r, h) = (0.5f64, 0.8f64);
    let v = removed(&CarveTool::new(
        CarveShape::Cylinder {
            radius: r as f32,
            half_height: h as f32,
            tolerance: Some(t as f32),
        },
        turned(centre),
    ));
    let cylinder = |r: f64, h: f64| PI * r * r * 2.0 * h;
    assert_between("cylinder", v, cylinder(r, h), cylinder(r + t, h + t));
    // A turned capsule; grown by `t` it is the capsule of radius `r + t`.
    let (r, h) = (0.4f64, 0.6f64);
    let v = removed(&CarveTool::new(
        CarveShape::Capsule {
            radius: r as f32,
            half_height: h as f32,
            tolerance: Some(t as f32),
        },
        turned(centre),
    ));
    let capsule = |r: f64| ball(r) + cylinder(r, h);
    assert_between("capsule", v, capsule(r), capsule(r + t));
    // Scaled by 2: a sphere of radius 0.8 placed by a scale of 2 is one of
    // radius 1.6, and the tolerance stays in world units.
    let v = removed(&CarveTool::new(
        CarveShape::Sphere {
            radius: 0.8,
            tolerance: Some(t as f32),
        },
        Transform::from_translation(centre).with_scale(Vec3::splat(2.0)),
    ));
    assert_between("scaled sphere", v, ball(1.6), ball(1.6 + t));
}

#[test]
fn finer_tolerances_come_closer_to_the_ball() {
    let centre = Vec3::new(2.0, 0.0, 2.0);
    let mut last = f64::INFINITY;
    for t in [0.1f32, 0.02, 0.008] {
        let v = removed(&CarveTool::new(
            CarveShape::Sphere {
                radius: 1.0,
                tolerance: Some(t),
            },
            Transform::from_translation(centre),
        ));
        let excess = v - ball(1.0);
        assert!(
            excess >= 0.0 && excess < last,
            "{t}: excess {excess} after {last}"
        );
        last = excess;
    }
}

#[test]
fn bad_round_tools_are_typed_errors_and_change_nothing() {
    let mut terrain = block();
    let hash = terrain.state_hash();
    let at = Transform::from_xyz(2.0, 0.0, 2.0);
    let sphere = |radius: f32, tolerance: Option<f32>| {
        CarveTool::new(CarveShape::Sphere { radius, tolerance }, at)
    };
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        for tool in [
            sphere(bad, None),
            CarveTool::cylinder(bad, 1.0, at),
            CarveTool::cylinder(1.0, bad, at),
            CarveTool::capsule(bad, 1.0, at),
        ] {
            assert!(
                matches!(
                    carve(&mut terrain, &tool),
                    Err(TerrainError::InvalidTool { .. })
                ),
                "{tool:?}"
            );
        }
        if bad <= 0.0 || bad.is_nan() {
            assert!(matches!(
                carve(&mut terrain, &sphere(1.0, Some(bad))),
                Err(TerrainError::InvalidTool { .. })
            ));
        }
    }
    // A capsule may have no length (a ball), not a negative one.
    assert!(matches!(
        carve(&mut terrain, &CarveTool::capsule(1.0, -0.5, at)),
        Err(TerrainError::InvalidTool { .. })
    ));
    // A zero scale squashes the shape flat.
    assert!(matches!(
        carve(
            &mut terrain,
            &CarveTool::new(
                CarveShape::Sphere {
                    radius: 1.0,
                    tolerance: None
                },
                at.with_scale(Vec3::new(1.0, 0.0, 1.0))
            )
        ),
        Err(TerrainError::InvalidTool { .. })
    ));
    // Within twice the grid's rounding (√3/2 mm per corner), or finer
    // than the cap on corners allows.
    for t in [0.000_02, 0.001, 0.0025] {
        assert!(matches!(
            carve(&mut terrain, &sphere(1.0, Some(t))),
            Err(TerrainError::Kernel(
                bevy_chisel::bsp::Error::ToleranceUnreachable { .. }
            ))
        ));
    }
    assert_eq!(terrain.state_hash(), hash);
    assert!(terrain.journal().is_empty());
    // The same terrain still carves a good one.
    carve(&mut terrain, &CarveTool::sphere(1.0, at.translation)).expect("a good sphere");
    assert_ne!(terrain.state_hash(), hash);
}

/// Signed distance to a cylinder (`capsule: false`) or capsule of radius
/// `r` along `y` from `−h` to `h`.
fn round_distance(p: Vec3, r: f64, h: f64, capsule: bool) -> f64 {
    let p = p.as_dvec3();
    if capsule {
        return (p - bevy::math::DVec3::Y * p.y.clamp(-h, h)).length() - r;
    }
    let radial = p.x.hypot(p.z) - r;
    let axial = p.y.abs() - h;
    if radial > 0.0 && axial > 0.0 {
        radial.hypot(axial)
    } else {
        radial.max(axial)
    }
}

#[test]
fn scaled_and_turned_round_tools_follow_the_true_surface() {
    use bevy_chisel::bsp::convex::ConvexArena;
    use bevy_chisel::bsp::exact::IntPoint;
    use bevy_chisel::bsp::tools::convex_hull;

    let terrain = block();
    let q = *terrain.quantization();
    let (r, h, t, scale) = (0.3f64, 0.5f64, 0.006f64, 1.5f32);
    let pose = turned(Vec3::new(2.0, 0.0, 2.0)).with_scale(Vec3::splat(scale));
    let to_shape = pose.to_matrix().inverse();
    for capsule in [false, true] {
        let shape = if capsule {
            CarveShape::Capsule {
                radius: r as f32,
                half_height: h as f32,
                tolerance: Some(t as f32),
            }
        } else {
            CarveShape::Cylinder {
                radius: r as f32,
                half_height: h as f32,
                tolerance: Some(t as f32),
            }
        };
        let grid = CarveTool::new(shape, pose).to_grid(&q).unwrap();
        let points: Vec<IntPoint> = grid.pieces[0]
            .iter()
            .map(|&p| IntPoint::from_array(p).unwrap())
            .collect();
        let mut arena = ConvexArena::new();
        let hull = convex_hull(&mut arena, &points).unwrap();
        let world = |g: [f64; 3]| Vec3::from_array(q.to_world(g).map(|v| v as f32));
        // Every corner of the hull is outside the true shape and within
        // the tolerance (world units: the pose scales distances by 1.5).
        for v in arena.vertices_of(hull) {
            let d = f64::from(scale)
                * round_distance(
                    to_shape.transform_point3(world(arena.position(v))),
                    r,
                    h,
                    capsule,
                );
            assert!(d >= -1e-4 && d <= t, "capsule {capsule}: corner at {d} m");
        }
        // Every point of the true surface is inside the hull, within the
        // tolerance of its surface.
        let planes: Vec<[f64; 4]> = arena
            .face_polygons(hull)
            .iter()
            .map(|(plane, _)| {
                let [a, b, c, d] = plane.approx();
                let l = (a * a + b * b + c * c).sqrt();
                [a / l, b / l, c / l, d / l]
            })
            .collect();
        let n = 64;
        for i in 0..=n {
            for k in 0..n {
                let angle = (k as f64 + 0.5) * std::f64::consts::TAU / n as f64;
                let s = i as f64 / n as f64;
                let mut surface = vec![bevy::math::DVec3::new(
                    r * angle.cos(),
                    -h + 2.0 * h * s,
                    r * angle.sin(),
                )];
                if capsule {
                    let polar = s * std::f64::consts::FRAC_PI_2;
                    let (ring, up) = (r * polar.cos(), r * polar.sin());
                    for end in [-1.0, 1.0] {
                        surface.push(bevy::math::DVec3::new(
                            ring * angle.cos(),
                            end * (h + up),
                            ring * angle.sin(),
                        ));
                    }
                } else {
                    for end in [-1.0, 1.0] {
                        surface.push(bevy::math::DVec3::new(
                            r * s * angle.cos(),
                            end * h,
                            r * s * angle.sin(),
                        ));
                    }
                }
                for p in surface {
                    let w = pose.to_matrix().as_dmat4().transform_point3(p);
                    let g = (w - bevy::math::DVec3::from_array(q.origin())) / q.unit();
                    let inside = planes
                        .iter()
                        .map(|[a, b, c, d]| -(a * g.x + b * g.y + c * g.z + d))
                        .fold(f64::INFINITY, f64::min)
                        * q.unit();
                    assert!(
                        inside >= -1e-6 && inside <= t,
                        "capsule {capsule}: surface point {p} at {inside} m inside"
                    );
                }
            }
        }
    }
}
