//! The integration tests of `chisel_quadric`, in one test binary: one
//! module per area, and the seeded random inputs in [`common`]. One binary
//! links once instead of once per file.
//!
//! Run one area with a filter on its module path, for example
//! `cargo test --profile checked -p chisel_quadric --test it scene_files::`.

mod common;

// Quadrics, transforms and rays.
mod principal_frame;
mod ray_intersection;
mod transforms;

// CSG trees: normal form, distance bounds and the reference tracer.
mod conservative_distance;
mod dnf_equivalence;
mod reference_tracer;

// Sampling into splats.
mod carving;
mod curved_regions;
mod partial_resampling;
mod sampling_guarantees;
mod sampling_limits;
mod sampling_quadrics;
mod splat_output;

// Scene files, and property-based fuzzing of their reader.
mod fuzz_scenes;
mod scene_files;
