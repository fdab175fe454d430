//! # chisel_quadric — quadric CSG props
//!
//! CSG trees of quadrics (spheres, cylinders, cones, planes and the other
//! quadric surfaces), sampled into splats with a coverage guarantee, and a
//! CPU reference ray tracer of the same trees (paper 2: point/splat sampling
//! of quadric CSG). No Bevy: the plugin's render pass builds on it.
//!
//! This crate is being built; its modules land with the quadric sampling
//! work.
