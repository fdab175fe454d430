//! Scene files: CSG trees of quadrics in [RON](https://github.com/ron-rs/ron).
//!
//! A scene has a list of named `primitives`, an optional list of named
//! sub-graphs `nodes`, a `root` expression and an optional bounding sphere
//! `bounds: (x, y, z, r)`, the part of space to sample (never computed from
//! the primitives: half-spaces, cylinders and other infinite quadrics leave
//! most trees without a finite bound, so the file states it). Lengths are in scene units
//! (millimetres by convention), angles in degrees, colours linear RGB in
//! `[0, 1]`; a primitive may also set its `metallic` and (perceptual)
//! `roughness`, in `[0, 1]`. Comments (`//`, `/* */`) are allowed. The full reference is
//! `quadric/SCENES.md`; in short:
//!
//! ```ron
//! // (A ∩ B) ∪ C
//! Scene(
//!     primitives: [
//!         (name: "A", shape: Sphere(center: (0, 0, 0), radius: 30), color: (0.9, 0.3, 0.2)),
//!         (name: "B", shape: Sphere(center: (25, 0, 0), radius: 30), metallic: 1, roughness: 0.3),
//!         (name: "C", shape: Box(min: (-5, -5, -5), max: (5, 5, 5)),
//!          transform: (translate: (0, 40, 0), rotate: (0, 0, 45))),
//!     ],
//!     nodes: [
//!         (name: "lens", node: Intersection([Ref("A"), Ref("B")])),
//!     ],
//!     root: Union([Ref("lens"), Ref("C")]),
//!     bounds: (10, 10, 0, 60),
//! )
//! ```
//!
//! Shapes: `HalfSpace(normal, offset)` (inside `n·x ≤ offset`),
//! `Sphere(center, radius)`, `Ellipsoid(center, radii)`,
//! `Cylinder(point, axis, radius)`, `EllipticCylinder(radii)` (along z),
//! `Cone(apex, axis, half_angle_deg)` (double cone),
//! `EllipticCone(radii)`, `EllipticParaboloid(radii)`,
//! `HyperbolicParaboloid(radii)`, `HyperboloidOneSheet(radii)`,
//! `HyperboloidTwoSheets(radii)` (all along z, centred at the origin),
//! `Box(min, max)` (six half-spaces, intersected) and `Matrix(rows)` (a raw
//! symmetric 4×4, row by row, inside where `xᵀQx < 0`).
//!
//! Expressions: `Ref(name)` (a primitive or a named node; a name used twice
//! is one shared DAG node), `Union([..])`, `Intersection([..])`,
//! `Difference([base, cut, ..])`, `Complement(expr)`,
//! `Transform((translate: .., rotate: .., scale: ..), expr)` or
//! `Transform((matrix: rows), expr)`. A transform is `translate · rotate ·
//! scale`, the rotation Euler angles about x, then y, then z.
//!
//! Errors name the line and column: syntax and value errors (a negative
//! radius, an empty union) where the parser met them, name errors (an
//! unknown or duplicate name) at the name's first mention.

mod build;
pub mod carve;
mod spec;

use std::path::Path;

pub use build::DEFAULT_COLOR;

use crate::csg::{Color, CsgDag, Dnf, NodeId};
use crate::error::{Error, Result};
use crate::sampling::BoundingSphere;

/// A parsed scene: a CSG DAG, its root and the primitives' names.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The CSG DAG; its primitives carry the colours.
    pub dag: CsgDag,
    /// The root node of the scene's solid.
    pub root: NodeId,
    /// One name per DAG primitive (a box `b` gives `b[0]` … `b[5]`).
    pub names: Vec<String>,
    /// The scene's bounding sphere (`bounds` in the file), if it gives one:
    /// the default for sampling and for placing a camera.
    pub bounds: Option<BoundingSphere>,
}

impl Scene {
    /// Parses a scene from RON text.
    ///
    /// Errors: [`Error::Scene`] with the line, column and problem.
    pub fn from_ron(text: &str) -> Result<Self> {
        let options = ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let spec: spec::SceneSpec = options.from_str(text).map_err(|e| Error::Scene {
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        build::build(text, &spec)
    }

    /// Reads and parses a scene file.
    ///
    /// Errors: [`Error::Scene`] (line 0) when the file cannot be read, else
    /// as [`from_ron`](Self::from_ron).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::Scene {
            line: 0,
            column: 0,
            message: format!("cannot read {}: {e}", path.display()),
        })?;
        Self::from_ron(&text)
    }

    /// The scene's solid in disjunctive normal form.
    pub fn dnf(&self) -> Result<Dnf> {
        Dnf::from_dag(&self.dag, self.root)
    }

    /// The colour of DAG primitive `primitive`, if it exists.
    #[must_use]
    pub fn color(&self, primitive: usize) -> Option<Color> {
        self.dag.primitives().get(primitive).map(|p| p.color)
    }
}
