//! `chisel fluted`: the paper's milling setup (paper 1 §5, Fig. 13–14) — a
//! rotating fluted bit, its axis skewed 30° from the vertical, fed through
//! a block; every step sweeps the bit's rotation by 4° (90 steps a turn)
//! and subtracts the swept volume as a union of convex pieces.
//!
//! The bit is a union of convex pieces in its own frame: a core (a prism
//! of a regular polygon along the axis) and `F` flutes, each a thin blade
//! from near the axis to the bit's radius whose upper end is turned by a
//! helix twist against its lower end (the hull of the two quadrilaterals,
//! so the flutes are skewed yet convex). A rotation step from pose `a` to
//! pose `b` is cut into `S` sub-steps; for every piece and sub-step the
//! tool is the convex hull of that piece's quantized corners at the
//! sub-step's two poses. The step's swept volume is the union of those
//! `(F + 1)·S` hulls, and subtracting a union is subtracting its members
//! one after another, `A − (B ∪ C) = (A − B) − C`, so each hull is one
//! subtraction of the sequence (and one line of the replay file, which
//! Manifold replays with the identical points). Each pose is quantized
//! once and shared by the two hulls on either side of it, so the hulls of
//! one piece meet exactly at their common pose and cover its path without
//! gaps. A hull replaces the arc a corner travels between two poses by its
//! chord: for 4° at the bit's 3 mm radius the chord lies 1.8 µm inside the
//! arc, less with sub-steps.
//!
//! The feed follows the paper's translation per turn: `FEED_MM` along +x
//! per turn, continuously, back and forth over the block in passes, each
//! pass `PASS_DEPTH_MM` deeper than the one before.
//!
//! Notation: `t` is the rotation step (fractional at sub-steps), `θ = t·4°`
//! the bit's angle about its axis, `F` the flutes, `S` the sub-steps,
//! `τ` a flute's helix twist from its lower to its upper end.

use chisel_bsp::octree::CellBox;
use chisel_bsp::tools::Pose;

use super::cutter::{mul, rot_x, rot_z};
use super::sequence::{Base, Op, Sequence, Step, UNITS_PER_MM};

/// Block `[0,60]×[0,40]×[0,20]` mm.
const BLOCK_MM: [f64; 3] = [60.0, 40.0, 20.0];
/// Rotation steps per turn (4° each, as in the paper).
pub const STEPS_PER_TURN: usize = 90;
/// The axis' skew from +z, towards +y (perpendicular to the feed).
const SKEW_DEG: f64 = 30.0;
/// The bit: radius and length of the flutes, the core's radius, sides and
/// length (the core reaches above the flutes, as a shank).
const RADIUS_MM: f64 = 3.0;
const FLUTE_LENGTH_MM: f64 = 16.0;
const CORE_RADIUS_MM: f64 = 1.0;
const CORE_SIDES: usize = 10;
const CORE_LENGTH_MM: f64 = 20.0;
/// A flute's blade: from this radius out to `RADIUS_MM`, this thick.
const FLUTE_INNER_MM: f64 = 0.6;
const FLUTE_THICKNESS_MM: f64 = 0.9;
/// A flute's helix twist `τ` between its lower and upper end, degrees.
const TWIST_DEG: f64 = 30.0;
/// The tip's start, mm: 10 mm deep, clear of the block's sides.
const START_MM: [f64; 3] = [6.0, 14.0, 10.0];
/// Feed along +x per turn, the length of a pass, and the extra depth of
/// each pass after the first.
const FEED_MM: f64 = 2.4;
const PASS_MM: f64 = 48.0;
const PASS_DEPTH_MM: f64 = 1.0;
/// No pass goes deeper than this (tip height, mm).
const FLOOR_MM: f64 = 2.0;

/// The bit's convex pieces in its own frame (grid units): the core first,
/// then the `flutes` blades, each as the corners whose hull it is.
fn pieces(flutes: usize) -> Vec<Vec<[f64; 3]>> {
    let deg = std::f64::consts::PI / 180.0;
    let mm = |p: [f64; 3]| p.map(|c| c * UNITS_PER_MM);
    let mut out = Vec::with_capacity(flutes + 1);
    let mut core = Vec::with_capacity(2 * CORE_SIDES);
    for z in [0.0, CORE_LENGTH_MM] {
        for k in 0..CORE_SIDES {
            let a = k as f64 * std::f64::consts::TAU / CORE_SIDES as f64;
            core.push(mm([CORE_RADIUS_MM * a.cos(), CORE_RADIUS_MM * a.sin(), z]));
        }
    }
    out.push(core);
    for f in 0..flutes {
        let base = f as f64 * std::f64::consts::TAU / flutes as f64;
        let mut blade = Vec::with_capacity(8);
        for (z, turn) in [(0.0, 0.0), (FLUTE_LENGTH_MM, TWIST_DEG * deg)] {
            let (s, c) = (base + turn).sin_cos();
            for r in [FLUTE_INNER_MM, RADIUS_MM] {
                for w in [-0.5 * FLUTE_THICKNESS_MM, 0.5 * FLUTE_THICKNESS_MM] {
                    // Radial `r`, tangential `w`, turned by the blade's angle.
                    blade.push(mm([r * c - w * s, r * s + w * c, z]));
                }
            }
        }
        out.push(blade);
    }
    out
}

/// The tip's position (mm) at rotation step `t`: the feed's distance
/// `FEED_MM·t/90` walked back and forth in passes of `PASS_MM`, each pass
/// `PASS_DEPTH_MM` deeper (down to `FLOOR_MM`).
fn tip(t: f64) -> [f64; 3] {
    let s = FEED_MM * t / STEPS_PER_TURN as f64;
    let pass = (s / PASS_MM).floor();
    let u = s - pass * PASS_MM;
    let along = if (pass as u64).is_multiple_of(2) {
        u
    } else {
        PASS_MM - u
    };
    let z = (START_MM[2] - pass * PASS_DEPTH_MM).max(FLOOR_MM);
    [START_MM[0] + along, START_MM[1], z]
}

/// The bit's pose at rotation step `t` (grid units).
fn pose(t: f64) -> Pose {
    let deg = std::f64::consts::PI / 180.0;
    let theta = t * 360.0 / STEPS_PER_TURN as f64 * deg;
    Pose {
        rotation: mul(rot_x(-SKEW_DEG * deg), rot_z(theta)),
        translation: tip(t).map(|c| c * UNITS_PER_MM),
    }
}

/// The scenario: `steps` rotation steps of the bit with `flutes` flutes,
/// each swept in `substeps` sub-steps, so `steps·(flutes + 1)·substeps`
/// subtractions.
///
/// # Errors
/// Flutes outside 1–8, sub-steps outside 1–16, or a pose beyond the exact
/// range.
pub fn sequence(steps: usize, flutes: usize, substeps: usize) -> Result<Sequence, String> {
    if !(1..=8).contains(&flutes) {
        return Err(format!("a bit has 1 to 8 flutes, not {flutes}"));
    }
    if !(1..=16).contains(&substeps) {
        return Err(format!("a step has 1 to 16 sub-steps, not {substeps}"));
    }
    let pieces = pieces(flutes);
    // placed[j][p]: piece `p` at pose `j / substeps`, each pose quantized
    // once.
    let placed: Vec<Vec<Vec<[i64; 3]>>> = (0..=steps * substeps)
        .map(|j| {
            let pose = pose(j as f64 / substeps as f64);
            pieces
                .iter()
                .map(|piece| {
                    piece
                        .iter()
                        .map(|&c| pose.place(c).map(|p| p.coords()))
                        .collect::<Result<Vec<_>, _>>()
                        .map_err(|e| e.to_string())
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    let mut out = Vec::with_capacity(steps * substeps * pieces.len());
    for pair in placed.windows(2) {
        for (a, b) in pair[0].iter().zip(&pair[1]) {
            out.push(Step {
                op: Op::Subtract,
                hull: a.iter().chain(b).copied().collect(),
            });
        }
    }
    Ok(Sequence {
        base: Base::Box(CellBox {
            min: [0; 3],
            max: BLOCK_MM.map(|c| (c * UNITS_PER_MM) as i64),
        }),
        steps: out,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use chisel_bsp::tools::spans_volume;

    #[test]
    fn every_piece_and_sub_step_is_one_hull_of_two_shared_poses() {
        let (steps, flutes, substeps) = (5, 3, 2);
        let seq = sequence(steps, flutes, substeps).unwrap();
        let per_pose = flutes + 1;
        assert_eq!(seq.steps.len(), steps * substeps * per_pose);
        for (i, s) in seq.steps.iter().enumerate() {
            assert_eq!(s.op, Op::Subtract);
            assert!(spans_volume(&s.hull), "hull {i}");
            let n = if i % per_pose == 0 { 2 * CORE_SIDES } else { 8 };
            assert_eq!(s.hull.len(), 2 * n, "hull {i}");
            // The piece's end pose is exactly the start pose of its next
            // hull: the hulls meet with no gap.
            if let Some(next) = seq.steps.get(i + per_pose) {
                assert_eq!(s.hull[n..], next.hull[..n], "hull {i}");
            }
        }
        assert!(sequence(3, 0, 1).is_err());
        assert!(sequence(3, 2, 17).is_err());
    }

    #[test]
    fn the_bit_is_skewed_its_flutes_twisted_and_it_turns_4_degrees_a_step() {
        // The axis (0,0,1) leans 30° towards +y.
        let p = pose(0.0);
        let axis = [0, 1, 2].map(|i| p.rotation[i][2]);
        assert!((axis[1] - 0.5).abs() < 1e-12 && (axis[2] - 0.75f64.sqrt()).abs() < 1e-12);
        // A flute's outer corner turns by τ from its lower to its upper end.
        let blade = &pieces(3)[1];
        let angle = |q: [f64; 3]| q[1].atan2(q[0]);
        let turn = angle(blade[7]) - angle(blade[3]);
        assert!((turn.to_degrees() - TWIST_DEG).abs() < 1e-9, "{turn}");
        // After a full turn the rotation is the start's again.
        let (a, b) = (pose(0.0), pose(STEPS_PER_TURN as f64));
        for i in 0..3 {
            for j in 0..3 {
                assert!((a.rotation[i][j] - b.rotation[i][j]).abs() < 1e-12);
            }
        }
        // The feed: 2.4 mm a turn along +x, and back one pass later.
        assert!((tip(90.0)[0] - tip(0.0)[0] - FEED_MM).abs() < 1e-9);
        let turns_per_pass = PASS_MM / FEED_MM;
        let back = tip(2.0 * turns_per_pass * 90.0);
        assert!((back[0] - START_MM[0]).abs() < 1e-9);
        assert!((back[2] - (START_MM[2] - 2.0 * PASS_DEPTH_MM)).abs() < 1e-9);
    }
}
