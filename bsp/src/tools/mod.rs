//! Convex tools: exact convex hulls of integer points (paper 1 §3.3's
//! carving tools are convex polyhedra).

pub mod hull;

pub use hull::convex_hull;
