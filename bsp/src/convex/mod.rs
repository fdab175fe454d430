//! Convex polyhedra with exact homogeneous vertices (paper 1 §3.3).
//!
//! A [`ConvexArena`] stores half-edge meshes of convex polyhedra in flat
//! arrays: vertices, half-edges and faces, with the exact points and planes
//! they name by index in two more. One arena holds many polyhedra: cutting a polyhedron by a
//! plane splits it in place into two, which stay in the same arena and are
//! named by a [`PolyId`] (any half-edge on them). Faces carry their exact
//! supporting [`Plane`](crate::exact::Plane), oriented outwards, and a tag
//! (the BSP node on the other side of the face, for boundary extraction).
//!
//! - [`mesh`] — the arena, its elements, constructors and traversal.
//! - [`validate`] — every invariant, checked exactly (tests call it after
//!   every step).
//! - [`cut`] — cutting a polyhedron by a plane: finding the section.
//! - `landmarks` — where the descent of the next cut starts.
//! - `extremes` — vertices farthest in fixed directions, as starts too.
//! - `survey` — what one walk around a face tells the split.
//! - `scratch` — the working memory of the cuts and the records it holds
//!   (`stamp_map`, `starts`).
//! - `split` — splitting along the section once it is found.
//! - `ring` — the one-sided cut of a section with no vertex on the plane,
//!   in one walk and one pass; `ring_both` — the two-sided one.

pub mod cut;
mod extremes;
mod landmarks;
pub mod mesh;
pub mod pool;
mod ring;
mod ring_both;
mod scratch;
mod split;
#[cfg(test)]
mod split_reference;
mod stamp_map;
mod starts;
mod survey;
#[cfg(test)]
mod test_support;
pub mod validate;

pub use cut::{CutOutcome, CutStats, KeptOutcome, Part};
pub use mesh::{ConvexArena, Face, HalfEdge, NO_TAG, PolyId};
pub use pool::with_arena;
pub use validate::InvariantError;
