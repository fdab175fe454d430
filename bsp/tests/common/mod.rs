//! Shared test support: the bigint reference, the backends and the inputs.

pub mod backends;
pub mod bigint_reference;
pub mod inputs;
pub mod shapes;
pub mod volume;
