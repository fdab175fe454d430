//! Iterated CSG scenarios: a base solid edited by a sequence of convex
//! tools, timed step by step (paper 1 §5).
//!
//! Every scenario is first written down as a [`Sequence`] of integer tool
//! points (1 µm grid), then run by one [`runner`], so `mill`, `cheese`,
//! `sweep` and `replay` report the same figures and record the same
//! operation log that the peer comparison replays.
//!
//! - [`sequence`] — the operation sequence, units and the root cube.
//! - [`jsonl`] — the replay format (one JSON object per line, millimetres).
//! - [`mill`], [`cheese`], [`cutter`], [`fluted`], [`sweep`] — the generated
//!   scenarios.
//! - [`runner`] — applies the steps, timing each with its re-extraction.
//! - [`cpu_clock`] — the calling thread's CPU time, for per-step figures.
//! - [`extract`] — per-cell re-extraction and the whole surface.
//! - [`report`] — the figures: text, one JSON line, per-step CSV.
//! - [`check`] — per-step invariants (`--check`) for tests.

pub mod check;
pub mod cheese;
pub mod cpu_clock;
pub mod cutter;
pub mod extract;
pub mod fluted;
pub mod jsonl;
pub mod mill;
pub mod report;
pub mod runner;
pub mod sequence;
pub mod sweep;
