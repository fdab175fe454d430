//! Shared test support: the bigint reference, the backends, the inputs, shapes,
//! random BSPs, exact volumes and octrees checked against one big BSP.

pub mod backends;
pub mod bigint_reference;
pub mod inputs;
pub mod octree_reference;
pub mod random_bsp;
pub mod shapes;
pub mod surface;
pub mod volume;
