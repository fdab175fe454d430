//! Shared test support: the bigint reference, the backends, the inputs, shapes,
//! random BSPs and exact volumes.

pub mod backends;
pub mod bigint_reference;
pub mod inputs;
pub mod random_bsp;
pub mod shapes;
pub mod surface;
pub mod volume;
