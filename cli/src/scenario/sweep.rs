//! `chisel sweep`: the volume swept by a gear moving along a cubic Bézier
//! curve while turning, as a union of convex pieces (paper 1 §5, Fig. 12).
//!
//! The geometry — the gear's mesh and convex wedges, the curve, the poses
//! and the per-triangle sweep prisms with flat ones left out — is
//! [`chisel_bsp::tools::sweep`], shared with the `sweep` example; here it
//! is placed on the 1 µm grid and written down as a [`Sequence`] of unions.

use chisel_bsp::tools::{GearSweep, Pose};

use super::sequence::{Base, Op, Sequence, Step, UNITS_PER_MM};

/// The gear's pose at sample `k` of `samples`, on the 1 µm grid.
fn pose(k: usize, samples: usize) -> Pose {
    let pose = GearSweep::FIG12_MM.pose(k, samples);
    Pose {
        translation: pose.translation.map(|x| x * UNITS_PER_MM),
        ..pose
    }
}

/// The sweep over `samples` positions (at least 2): the unions, and how
/// many flat sweep prisms were left out.
///
/// # Errors
/// Fewer than two samples, or a position beyond the exact range.
pub fn sequence(samples: usize) -> Result<(Sequence, usize), String> {
    if samples < 2 {
        return Err("a sweep needs at least 2 samples".into());
    }
    let mut gear = GearSweep::FIG12_MM.gear.mesh();
    for v in &mut gear.vertices {
        *v = v.map(|c| c * UNITS_PER_MM);
    }
    let placed: Vec<Vec<[i64; 3]>> = (0..samples)
        .map(|k| {
            let pose = pose(k, samples);
            gear.vertices
                .iter()
                .map(|&v| pose.place(v).map(|p| p.coords()).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<_, _>>()?;
    let mut steps: Vec<Step> = gear
        .wedge_points(&placed[0])
        .into_iter()
        .map(|hull| Step {
            op: Op::Union,
            hull,
        })
        .collect();
    let mut flat = 0;
    for pair in placed.windows(2) {
        let (prisms, left_out) = gear.sweep_prisms(&pair[0], &pair[1]);
        flat += left_out;
        steps.extend(prisms.into_iter().map(|hull| Step {
            op: Op::Union,
            hull,
        }));
    }
    Ok((
        Sequence {
            base: Base::Empty,
            steps,
        },
        flat,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use chisel_bsp::tools::spans_volume;

    #[test]
    fn the_sweep_has_wedges_then_prisms() {
        let (seq, flat) = sequence(3).unwrap();
        let g = GearSweep::FIG12_MM.gear.mesh();
        assert_eq!(
            seq.steps.len() + flat,
            g.wedges.len() + 2 * g.triangles.len()
        );
        assert!(
            seq.steps
                .iter()
                .all(|s| s.op == Op::Union && spans_volume(&s.hull))
        );
        assert!(sequence(1).is_err());
    }
}
