//! Shared test support: the bigint reference, the backends, the inputs, shapes,
//! random BSPs, exact volumes and octrees checked against one big BSP.
//!
//! The benchmarks (`fig9_cuts` among them) include some of these files
//! by path; `fig9.rs` (the planes of paper 1's Figure 9) is theirs alone.

pub mod backends;
pub mod bigint_reference;
pub mod inputs;
pub mod octree_reference;
pub mod random_bsp;
pub mod shapes;
pub mod surface;
pub mod volume;
