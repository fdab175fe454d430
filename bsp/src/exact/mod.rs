//! Exact arithmetic: fixed-width integers, planes, homogeneous vertices and
//! the predicates of paper 1 §3.2 (Table 1).
//!
//! | operation                                  | what it answers                              |
//! |--------------------------------------------|----------------------------------------------|
//! | [`plane_from_points`]                      | the oriented plane through three points      |
//! | [`plane_from_points_normalized`]           | the same, divided by the gcd (canonical)     |
//! | [`are_planes_parallel`]                    | `n_p × n_q = 0`                              |
//! | [`intersect_3_planes`]                     | the exact common vertex `(X, Y, Z, W)`       |
//! | [`classify_vertex`]                        | the side of a plane a vertex is on           |
//! | [`Plane::eval`] / [`Plane::side_of`]       | signed distance / side of an input point     |
//!
//! [`budget`] derives every bit width from the input bound `|v| ≤ 2^26`.

pub mod budget;
mod classify;
mod digits;
mod intersect;
pub mod orient;
mod plane;
mod point;
mod sign;
pub mod wide;

pub(crate) use classify::FilteredDot;
pub use classify::{
    FILTER_EPSILON, classify_vertex, classify_vertex_exact, classify_vertex_filtered,
    compare_offsets, offset_estimate, plane_dot_exact,
};
pub use intersect::intersect_3_planes;
pub(crate) use intersect::intersect_3_planes_with;
pub use plane::{Plane, are_planes_parallel, plane_from_points, plane_from_points_normalized};
pub(crate) use plane::{gcd_u64, gcd_u128};
pub use point::{IntPoint, Point4};
pub use sign::Sign;
pub use wide::{I64, I128, I192, I256, Int};
