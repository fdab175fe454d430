//! Invariant checks of a scenario step (`--check`), for tests at small
//! sizes: the volume bookkeeping of the edit and a closed surface.
//!
//! Notation: `A` — the solid before the step, `T` — the tool, `V(·)` —
//! volume. After subtracting, `V(A) = V(A − T) + V(A ∩ T)`; after a union,
//! `V(A ∪ T) = V(A) + V(T) − V(A ∩ T)`; after intersecting, the result is
//! `A ∩ T`. `A ∩ T` is computed on a copy of the octree (cheap: the octree
//! is persistent) and `T` alone in an empty octree of the same cube. The
//! regions are exact; only the volume sums are `f64`, hence the relative
//! tolerance.

use chisel_bsp::octree::{Edit, Octree, Tool};
use chisel_bsp::tree::EMPTY;

use super::extract;
use super::sequence::Op;

/// Relative tolerance of the `f64` volume sums.
const TOLERANCE: f64 = 1e-9;

/// Checks one step that turned `before` into `after`.
///
/// # Errors
/// A message saying which invariant failed, with the volumes.
pub fn step(before: &Octree, after: &Octree, tool: &Tool, op: Op) -> Result<(), String> {
    let kernel = |e: chisel_bsp::Error| e.to_string();
    let v_before = before.solid_volume();
    let v_after = after.solid_volume();
    let mut common = before.clone();
    common.apply(tool, Edit::Intersect).map_err(kernel)?;
    let v_common = common.solid_volume();
    let expected = match op {
        Op::Subtract => v_before - v_common,
        Op::Intersect => v_common,
        Op::Union => {
            let mut alone = Octree::new(after.origin(), after.size_log2(), EMPTY, *after.config())
                .map_err(kernel)?;
            alone.apply(tool, Edit::Add(1)).map_err(kernel)?;
            v_before + alone.solid_volume() - v_common
        }
    };
    let scale = v_before.abs().max(v_after.abs()).max(1.0);
    if (v_after - expected).abs() > TOLERANCE * scale {
        return Err(format!(
            "volume bookkeeping failed for {}: before {v_before}, after {v_after}, expected \
             {expected} (common part {v_common})",
            op.name()
        ));
    }
    if v_after > v_before * (1.0 + TOLERANCE) && op != Op::Union {
        return Err(format!(
            "{} grew the solid: {v_before} -> {v_after}",
            op.name()
        ));
    }
    let (_, closure) = extract::whole(after);
    if !closure.closed {
        return Err("the surface after this step is not closed".into());
    }
    Ok(())
}
