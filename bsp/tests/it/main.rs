//! The integration tests of `chisel_bsp`, in one test binary: one module
//! per area of the kernel, and the shared support in [`common`]. One binary
//! links once instead of once per file.
//!
//! Run one area with a filter on its module path, for example
//! `cargo test --profile checked -p chisel_bsp --test it octree_store::`.

mod common;

// Exact predicates and wide integers.
mod predicates_conformance;
mod predicates_properties;
mod wide_int;

// Convex polyhedra and tool shapes.
mod convex_cut;
mod convex_hull;
mod tool_round;
mod tool_shapes;
mod tool_touch;

// BSP trees.
mod bsp_boundary;
mod bsp_cells;
mod bsp_fuzz;
mod bsp_import;
mod bsp_merge;
mod bsp_merge_grafted;
mod bsp_simplify;

// Surface meshes.
mod mesh_merge;
mod mesh_surface;

// The octree of BSPs.
mod octree;
mod octree_chunk_debris;
mod octree_components;
mod octree_debris;
mod octree_hash;
mod octree_import;
mod octree_import_layers;
mod octree_large_tools;
mod octree_nesting;
mod octree_seams;
mod octree_seams_outside;
mod octree_shading;
mod octree_shading_outside;
mod octree_split;
mod octree_store;
mod octree_volume_change;

// Property-based fuzzing of the kernel's inputs.
mod fuzz_inputs;
