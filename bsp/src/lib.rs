//! # chisel_bsp — exact solid modelling on integers
//!
//! The exact kernel of `bevy_chisel`: plane-based geometry with integer
//! coefficients, in which every predicate is decided exactly, so Boolean
//! operations never fail, never crack and give bit-identical results on
//! every machine (paper 1: *Fast Exact Booleans for Iterated CSG using
//! Octree-Embedded BSPs*).
//!
//! Integers only inside: floats appear at the edges (import, export) and as
//! a certified filter in front of the exact predicates.
//!
//! ## Map
//!
//! - [`exact`] — fixed-width integers, the bit budget, planes, homogeneous
//!   vertices and the predicates of §3.2.
//! - [`convex`] — convex polyhedra as half-edge meshes with exact vertices,
//!   and cutting them by planes (§3.3).
//! - [`tools`] — convex tools: exact convex hulls of integer points, the
//!   corners of dodecahedra, prisms and round shapes within a tolerance,
//!   swept volumes, and [`tools::Quantization`], the one rounding of float
//!   input to the grid.
//! - [`tree`] — BSP trees with material labels, and their convex cells.
//! - [`mesh`] — boundary surfaces without T-junctions, and their triangles.
//! - [`octree`] — the persistent octree of BSPs that edits touch locally.
//! - `pool` — the per-thread pool that recycles their working memory.
//! - [`Error`] — the one error type: what was wrong with the input and how
//!   to fix it.
//!
//! ## Example
//!
//! ```
//! use chisel_bsp::exact::{IntPoint, Plane, Sign, classify_vertex, intersect_3_planes};
//!
//! // Three axis planes x = 1, y = 2, z = 3 meet at (1, 2, 3).
//! let px = Plane::new(1, 0, 0, -1)?;
//! let py = Plane::new(0, 1, 0, -2)?;
//! let pz = Plane::new(0, 0, 1, -3)?;
//! let v = intersect_3_planes(&px, &py, &pz).expect("independent normals");
//! assert_eq!(v.to_f64(), [1.0, 2.0, 3.0]);
//!
//! // x + y + z = 6 passes exactly through it; x + y + z = 5 does not.
//! assert_eq!(classify_vertex(&v, &Plane::new(1, 1, 1, -6)?), Sign::Zero);
//! assert_eq!(classify_vertex(&v, &Plane::new(1, 1, 1, -5)?), Sign::Positive);
//!
//! // Out-of-budget input is a typed error, never a silent wrap.
//! assert!(IntPoint::new(1 << 27, 0, 0).is_err());
//! # Ok::<(), chisel_bsp::Error>(())
//! ```

#![warn(missing_docs)]

pub mod convex;
mod error;
pub mod exact;
pub mod mesh;
pub mod octree;
mod pool;
pub mod tools;
pub mod tree;
mod word_hash;

pub use error::Error;
