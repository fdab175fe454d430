//! # chisel_quadric — quadric CSG props
//!
//! CSG trees of quadrics (spheres, cylinders, cones, planes and the other
//! quadric surfaces), sampled into splats with a coverage guarantee, and a
//! CPU reference ray tracer of the same trees (paper 2: *Sampling from
//! Quadric-Based CSG Surfaces*). No Bevy: the plugin's render pass builds on it.
//!
//! All geometry is `f64` with `glam`'s `DVec3` / `DMat4` at the API.
//! Sign convention everywhere: `Q(x) < 0` is inside, `Q(x) > 0` outside.
//!
//! ## Map
//!
//! - [`Quadric`] — the symmetric 4×4 matrix as ten coefficients: value,
//!   gradient, normal, affine transform (`quadric`), and constructors for
//!   the named types (`shapes`).
//! - [`eigen`] — robust symmetric 3×3 eigen solver (Jacobi);
//!   [`PrincipalFrame`] — centre and principal axes (§3.2).
//! - [`Ray`], [`LineHits`] — stable line–quadric intersection (§3.1).
//! - [`csg`] — the CSG DAG ([`CsgDag`]), its normal form ([`Dnf`], §5) and
//!   the CSG distances of eqs. 19 and 22 ([`CsgDistance`]).
//! - [`QuadricDistance`] — conservative signed distance (§3.3, eq. 12).
//! - [`sampling`] — adaptive sampling with the coverage guarantee (§3.2,
//!   §3.4, §4): heightfields, basic regions, subdivision; [`sample`];
//!   partial re-sampling after an edit (`sampling::partial`).
//! - [`splats`] — splats, quadric buffer, deduplicated clip lists and the
//!   encoded normal form: the plain records the renderer reads (§6);
//!   [`SplatSet`], [`encode_normal_form`].
//! - [`trace`] — the CPU reference ray tracer ([`Camera`], [`trace_image`]),
//!   ground truth for the renderer.
//! - [`Scene`] — the RON scene file format (primitives, operations,
//!   transforms, colours) and its loader.
//! - [`Error`] — the one error type: what was wrong with the input and how
//!   to fix it.
//!
//! ## Example
//!
//! ```
//! use chisel_quadric::{CsgDag, CsgDistance, Dnf, Quadric, Ray};
//! use glam::DVec3;
//!
//! // A unit cube with a spherical bite taken out of one corner.
//! let mut dag = CsgDag::new();
//! let cube = dag.cuboid(DVec3::ZERO, DVec3::ONE, [0.8, 0.6, 0.3])?;
//! let ball = dag.primitive(Quadric::sphere(DVec3::ONE, 0.5)?, [0.3, 0.5, 0.9]);
//! let root = dag.difference(cube, &[ball])?;
//!
//! // Normal form: one product, six planes inside and the sphere outside.
//! let dnf = Dnf::from_dag(&dag, root)?;
//! assert_eq!(dnf.products().len(), 1);
//! assert_eq!(dnf.products()[0].len(), 7);
//! assert!(dnf.contains(DVec3::splat(0.25)) && !dnf.contains(DVec3::splat(0.9)));
//!
//! // A ray along the diagonal enters the ball's surface at |x − (1,1,1)| = 0.5.
//! let ray = Ray::new(DVec3::ZERO, DVec3::ONE.normalize())?;
//! let hit = dnf.quadrics()[6].quadric.intersect_line(&ray).first_hit_after(0.0).unwrap();
//! assert!((hit.t - (3f64.sqrt() - 0.5)).abs() < 1e-12);
//!
//! // Conservative distance to the CSG surface: never more than the truth.
//! let d = CsgDistance::new(&dnf).distance(DVec3::splat(0.25));
//! assert!(d < 0.0 && -d <= 0.25);
//! # Ok::<(), chisel_quadric::Error>(())
//! ```

#![warn(missing_docs)]

pub mod csg;
pub mod distance;
pub mod eigen;
mod error;
pub mod frame;
mod quadric;
pub mod ray;
pub mod sampling;
pub mod scene;
mod shapes;
pub mod splats;
pub mod trace;

pub use csg::{CsgDag, CsgDistance, Dnf, Literal, NodeId, Side, SurfaceMaterial};
pub use distance::{QuadricDistance, conservative_distance};
pub use eigen::SymmetricEigen;
pub use error::{Error, Result};
pub use frame::PrincipalFrame;
pub use quadric::{AFFINE_TOLERANCE, Quadric, affine_inverse, snap_affine};
pub use ray::{Hit, LineHits, Ray, Span};
pub use sampling::{
    BoundingSphere, DEFAULT_MAX_MEMORY, DEFAULT_MAX_SAMPLES, MAX_BOUNDS_RATIO, MAX_COORDINATE,
    Sample, SampleOptions, SampleSet, SamplingCost, f32_at_least, sample, sampling_cost,
};
pub use scene::Scene;
pub use splats::{
    ColoredQuadric, INDEX_MASK, OUTSIDE_FLAG, Splat, SplatSet, encode_normal_form,
    literal_reference,
};
pub use trace::{Camera, NO_HIT, TraceHit, TraceImage, trace_image, trace_ray};
