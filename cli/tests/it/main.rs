//! The integration tests of the `chisel` command line, in one test binary:
//! one module per area, each running the built `chisel` binary, and the
//! shared helpers in [`common`]. One binary links once instead of once
//! per file.
//!
//! Run one area with a filter on its module path, for example
//! `cargo test --profile checked -p chisel --test it hostile::`.

mod common;

// The binary end to end: scenes in, summaries and files out, exit codes.
mod cli;
// Hostile input: huge requests, full disks, broken meshes and scenes.
mod hostile;
// Exact octree files: export, combine, replay, damaged files.
mod octree_files;
// The iterated CSG scenarios and their recorded sequences.
mod scenarios;
