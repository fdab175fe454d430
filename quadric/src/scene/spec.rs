//! The serde model of a scene file (see the [`scene`](crate::scene) module docs).
//!
//! Values are checked while they are deserialized (`try_from` wrappers), so
//! that the parser reports the line of a bad radius or an empty union.

use glam::{DMat4, DQuat, DVec2, DVec3, EulerRot};
use serde::Deserialize;

use crate::csg::Color;
use crate::error::{Error, Result};
use crate::quadric::{Quadric, affine_inverse};
use crate::sampling::BoundingSphere;

/// A whole scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[serde(rename = "Scene")]
pub(crate) struct SceneSpec {
    #[serde(default)]
    pub primitives: Vec<PrimitiveSpec>,
    #[serde(default)]
    pub nodes: Vec<NamedNodeSpec>,
    pub root: NodeSpec,
    /// The bounding sphere `(x, y, z, r)` to sample in, if given.
    #[serde(default)]
    pub bounds: Option<Bounds>,
}

/// A checked bounding sphere `(x, y, z, r)`: finite, `r > 0`.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "[f64; 4]")]
pub(crate) struct Bounds(pub BoundingSphere);

impl TryFrom<[f64; 4]> for Bounds {
    type Error = String;
    fn try_from([x, y, z, r]: [f64; 4]) -> Result<Self, String> {
        BoundingSphere::new(DVec3::new(x, y, z), r)
            .map(Self)
            .map_err(|_| {
                format!(
                    "bounds ({x}, {y}, {z}, {r}): a sphere (x, y, z, r) needs finite numbers \
                     and a positive radius r"
                )
            })
    }
}

/// A named primitive: a shape, an optional colour, optional metallic and
/// roughness (checked when the scene is built, so that the error names the
/// primitive) and an optional placement.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PrimitiveSpec {
    pub name: String,
    pub shape: Shape,
    #[serde(default)]
    pub color: Option<Rgb>,
    #[serde(default)]
    pub metallic: Option<f32>,
    #[serde(default)]
    pub roughness: Option<f32>,
    #[serde(default)]
    pub transform: Option<Transform>,
}

/// A named sub-graph that several places can refer to.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct NamedNodeSpec {
    pub name: String,
    pub node: NodeSpec,
}

/// The quadric types as written. Angles in degrees.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) enum ShapeSpec {
    HalfSpace {
        normal: [f64; 3],
        offset: f64,
    },
    Sphere {
        center: [f64; 3],
        radius: f64,
    },
    Ellipsoid {
        center: [f64; 3],
        radii: [f64; 3],
    },
    Cylinder {
        point: [f64; 3],
        axis: [f64; 3],
        radius: f64,
    },
    EllipticCylinder {
        radii: [f64; 2],
    },
    Cone {
        apex: [f64; 3],
        axis: [f64; 3],
        half_angle_deg: f64,
    },
    EllipticCone {
        radii: [f64; 2],
    },
    EllipticParaboloid {
        radii: [f64; 2],
    },
    HyperbolicParaboloid {
        radii: [f64; 2],
    },
    HyperboloidOneSheet {
        radii: [f64; 3],
    },
    HyperboloidTwoSheets {
        radii: [f64; 3],
    },
    Box {
        min: [f64; 3],
        max: [f64; 3],
    },
    Matrix(Rows4),
}

/// An affine placement: `translate · rotate · scale`, or a raw `matrix`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TransformSpec {
    #[serde(default)]
    pub translate: Option<[f64; 3]>,
    /// Euler angles in degrees, applied about x, then y, then z.
    #[serde(default)]
    pub rotate: Option<[f64; 3]>,
    #[serde(default)]
    pub scale: Option<[f64; 3]>,
    /// Row-major 4×4; excludes the other fields.
    #[serde(default)]
    pub matrix: Option<Rows4>,
}

/// A CSG expression as written.
#[derive(Debug, Deserialize)]
pub(crate) enum RawNode {
    Ref(String),
    Union(Vec<NodeSpec>),
    Intersection(Vec<NodeSpec>),
    Difference(Vec<NodeSpec>),
    Complement(Box<NodeSpec>),
    Transform(Transform, Box<NodeSpec>),
}

/// A checked CSG expression: operations have enough operands.
#[derive(Debug, Deserialize)]
#[serde(try_from = "RawNode")]
pub(crate) struct NodeSpec(pub RawNode);

impl TryFrom<RawNode> for NodeSpec {
    type Error = String;
    fn try_from(raw: RawNode) -> Result<Self, String> {
        match &raw {
            RawNode::Union(v) if v.is_empty() => {
                Err("Union([]) has no operands; give at least one".to_owned())
            }
            RawNode::Intersection(v) if v.is_empty() => {
                Err("Intersection([]) has no operands; give at least one".to_owned())
            }
            RawNode::Difference(v) if v.len() < 2 => {
                Err("Difference([..]) needs a base and at least one operand to subtract".to_owned())
            }
            _ => Ok(Self(raw)),
        }
    }
}

/// A 4×4 matrix written as four rows of four numbers, `[[..], [..], [..], [..]]`.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "Vec<Vec<f64>>")]
pub(crate) struct Rows4(pub [[f64; 4]; 4]);

impl TryFrom<Vec<Vec<f64>>> for Rows4 {
    type Error = String;
    fn try_from(rows: Vec<Vec<f64>>) -> Result<Self, String> {
        let shape_ok = rows.len() == 4 && rows.iter().all(|r| r.len() == 4);
        if !shape_ok {
            return Err(format!(
                "a matrix needs 4 rows of 4 numbers, got {} rows",
                rows.len()
            ));
        }
        let mut m = [[0.0; 4]; 4];
        for (dst, src) in m.iter_mut().zip(&rows) {
            dst.copy_from_slice(src);
        }
        Ok(Self(m))
    }
}

/// A checked shape: its quadrics (six for a box).
#[derive(Debug, Deserialize)]
#[serde(try_from = "ShapeSpec")]
pub(crate) struct Shape(pub Vec<Quadric>);

impl TryFrom<ShapeSpec> for Shape {
    type Error = Error;
    fn try_from(spec: ShapeSpec) -> Result<Self> {
        shape_quadrics(&spec).map(Shape)
    }
}

/// A checked colour: three channels in `[0, 1]`.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "[f32; 3]")]
pub(crate) struct Rgb(pub Color);

impl TryFrom<[f32; 3]> for Rgb {
    type Error = String;
    fn try_from(c: [f32; 3]) -> Result<Self, String> {
        if c.iter().all(|x| (0.0..=1.0).contains(x)) {
            Ok(Self(c))
        } else {
            Err(format!("colour {c:?}: channels must lie in [0, 1]"))
        }
    }
}

/// A checked, invertible affine transform.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "TransformSpec")]
pub(crate) struct Transform(pub DMat4);

impl TryFrom<TransformSpec> for Transform {
    type Error = Error;
    fn try_from(spec: TransformSpec) -> Result<Self> {
        transform_matrix(&spec).map(Transform)
    }
}

fn v3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

fn v2(a: [f64; 2]) -> DVec2 {
    DVec2::from_array(a)
}

fn rows_to_mat4(rows: [[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(&rows).transpose()
}

/// The quadrics of one shape (six half-spaces for a box).
fn shape_quadrics(shape: &ShapeSpec) -> Result<Vec<Quadric>> {
    let one = |q: Result<Quadric>| q.map(|q| vec![q]);
    match *shape {
        ShapeSpec::HalfSpace { normal, offset } => one(Quadric::half_space(v3(normal), offset)),
        ShapeSpec::Sphere { center, radius } => one(Quadric::sphere(v3(center), radius)),
        ShapeSpec::Ellipsoid { center, radii } => one(Quadric::ellipsoid(v3(center), v3(radii))),
        ShapeSpec::Cylinder {
            point,
            axis,
            radius,
        } => one(Quadric::cylinder(v3(point), v3(axis), radius)),
        ShapeSpec::EllipticCylinder { radii } => one(Quadric::elliptic_cylinder(v2(radii))),
        ShapeSpec::Cone {
            apex,
            axis,
            half_angle_deg,
        } => one(Quadric::cone(
            v3(apex),
            v3(axis),
            half_angle_deg.to_radians(),
        )),
        ShapeSpec::EllipticCone { radii } => one(Quadric::elliptic_cone(v2(radii))),
        ShapeSpec::EllipticParaboloid { radii } => one(Quadric::elliptic_paraboloid(v2(radii))),
        ShapeSpec::HyperbolicParaboloid { radii } => one(Quadric::hyperbolic_paraboloid(v2(radii))),
        ShapeSpec::HyperboloidOneSheet { radii } => one(Quadric::hyperboloid_one_sheet(v3(radii))),
        ShapeSpec::HyperboloidTwoSheets { radii } => {
            one(Quadric::hyperboloid_two_sheets(v3(radii)))
        }
        ShapeSpec::Box { min, max } => Quadric::box_planes(v3(min), v3(max)).map(Vec::from),
        ShapeSpec::Matrix(rows) => one(Quadric::from_matrix(rows_to_mat4(rows.0))),
    }
}

/// The largest `|translate|` component and `matrix` entry a scene transform
/// takes: a quadric placed there has coefficients up to about its square,
/// far inside `f64`.
pub(crate) const MAX_TRANSLATE: f64 = 1e12;

/// The largest scale factor, and the reciprocal of the smallest non-zero
/// one (a zero factor is a singular transform).
pub(crate) const MAX_SCALE: f64 = 1e6;

/// The largest `|rotate|` angle in degrees (beyond it the angle's own
/// rounding exceeds a degree).
pub(crate) const MAX_ROTATE_DEG: f64 = 1e12;

/// Checks one part of a transform spec: finite, each `|value| ≤ max`, and
/// each non-zero `|value| ≥ min`. The error names the part and its value.
fn check_part<const N: usize>(
    what: &str,
    part: Option<[f64; N]>,
    max: f64,
    min: Option<f64>,
) -> Result<()> {
    let Some(values) = part else {
        return Ok(());
    };
    let shown = values.map(|v| format!("{v:e}")).join(", ");
    let range = match min {
        Some(min) => format!("a magnitude in [{min:e}, {max:e}] (or 0)"),
        None => format!("a magnitude of at most {max:e}"),
    };
    let bad = values
        .iter()
        .any(|v| !v.is_finite() || v.abs() > max || min.is_some_and(|m| *v != 0.0 && v.abs() < m));
    if bad {
        return Err(Error::Scene {
            line: 0,
            column: 0,
            message: format!(
                "transform {what} ({shown}) is out of range: each component needs a finite \
                 value with {range}"
            ),
        });
    }
    Ok(())
}

/// The matrix of a transform spec: `translate · rotate · scale`, or `matrix`.
fn transform_matrix(t: &TransformSpec) -> Result<DMat4> {
    let m = if let Some(rows) = t.matrix {
        if t.translate.is_some() || t.rotate.is_some() || t.scale.is_some() {
            return Err(Error::Scene {
                line: 0,
                column: 0,
                message: "a transform takes either `matrix` or translate/rotate/scale, not both"
                    .to_owned(),
            });
        }
        for row in rows.0 {
            check_part("matrix row", Some(row), MAX_TRANSLATE, None)?;
        }
        rows_to_mat4(rows.0)
    } else {
        check_part("translate", t.translate, MAX_TRANSLATE, None)?;
        check_part("rotate", t.rotate, MAX_ROTATE_DEG, None)?;
        check_part("scale", t.scale, MAX_SCALE, Some(1.0 / MAX_SCALE))?;
        let translate = v3(t.translate.unwrap_or([0.0; 3]));
        let [rx, ry, rz] = t.rotate.unwrap_or([0.0; 3]);
        let scale = v3(t.scale.unwrap_or([1.0; 3]));
        // Extrinsic x, then y, then z: R = Rz · Ry · Rx.
        let rot = DQuat::from_euler(
            EulerRot::ZYX,
            rz.to_radians(),
            ry.to_radians(),
            rx.to_radians(),
        );
        DMat4::from_scale_rotation_translation(scale, rot, translate)
    };
    affine_inverse(&m)?;
    Ok(m)
}
