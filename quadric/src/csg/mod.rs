//! Constructive solid geometry over quadrics (paper 2, §5).
//!
//! - [`CsgDag`] — the input: a DAG of primitives and union, intersection,
//!   difference, complement and transform nodes, with point classification.
//! - [`Dnf`] — its disjunctive normal form `S = ⋃ᵢ ⋂ⱼ Qᵢⱼ` (eq. 18):
//!   transforms pushed into the quadrics, complements into the literals.
//! - [`CsgDistance`] — conservative distances to the CSG surface (eqs. 19, 22).

mod dag;
mod distance;
mod dnf;

pub use dag::{Affine, Color, CsgDag, Node, NodeId, Primitive, SurfaceMaterial};
pub use distance::{CsgDistance, OtherTerms};
pub use dnf::{Dnf, DnfQuadric, Literal, MAX_PRODUCTS, Side};
