//! BSP trees with material labels (paper 1 §3.1, §3.4–3.5).
//!
//! A [`Bsp`] is a flat array of nodes over a palette of exact planes. An
//! inner node splits space by its plane into the part below it
//! (`n·x + d < 0`) and the part above; a leaf carries a material label
//! ([`Label`], `0` = empty). Node `0` is the root.
//!
//! - [`bsp`] — the structure, constructors and `validate()`.
//! - [`cells`] — the convex cells of the leaves inside a bounding
//!   polyhedron, by recursive exact cutting (first step of §3.4).
//! - [`merge`] — Booleans (and painting) by merging two BSPs (§3.5).
//! - [`graft`] — the same Booleans by copying one operand whole into the
//!   other's cells, as the paper states the merge (§3.5).
//! - [`import`] — a BSP from a closed triangle soup (§3.6).
//! - [`boundary`] — the solid's boundary without interior faces (§3.4).
//! - [`simplify`] — redundancy removal by extraction and rebuilding (§3.7).
//! - `locate` — the label just beside a point (symbolic perturbation).
//! - `polygon` — convex polygons in plane-based form and their exact
//!   splits, for import, boundary extraction and the octree's leaves.

pub mod boundary;
pub mod bsp;
pub mod cells;
pub mod graft;
pub mod import;
mod locate;
pub mod merge;
pub(crate) mod polygon;
pub mod simplify;

pub use boundary::BoundaryFace;
pub use bsp::{Bsp, EMPTY, Label, Node, NodeId};
pub use cells::Cell;
pub use merge::BooleanOp;
