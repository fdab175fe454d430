//! `chisel mill`: a flat end mill swept along a zig-zag path through a
//! block, each step subtracting the hull of the tool at two consecutive
//! path points.

use chisel_bsp::octree::CellBox;
use chisel_bsp::tools::{Pose, prism_corners};

use super::sequence::{Base, Op, Sequence, Step, UNITS_PER_MM};

/// Block `[0,100]×[0,100]×[0,40]` mm.
const BLOCK_MM: [f64; 3] = [100.0, 100.0, 40.0];
/// Tool: 16-sided prism, circumradius 3 mm, length 30 mm, bottom at z = 30.
const SIDES: usize = 16;
const RADIUS_MM: f64 = 3.0;
const LENGTH_MM: f64 = 30.0;
const BOTTOM_MM: f64 = 30.0;
/// Path: start (10, 10), 1.5 mm steps in x within [10, 90], rows 4 mm
/// apart, back to y = 10 after y passes 90.
const START_MM: [f64; 2] = [10.0, 10.0];
const STEP_MM: f64 = 1.5;
const ROW_MM: f64 = 4.0;
const X_RANGE_MM: [f64; 2] = [10.0, 90.0];
const Y_MAX_MM: f64 = 90.0;

/// The first `count` points of the tool path (x, y in mm).
#[must_use]
pub fn path(count: usize) -> Vec<[f64; 2]> {
    let [mut x, mut y] = START_MM;
    let mut dir = 1.0;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        out.push([x, y]);
        x += STEP_MM * dir;
        if !(X_RANGE_MM[0]..=X_RANGE_MM[1]).contains(&x) {
            x = x.clamp(X_RANGE_MM[0], X_RANGE_MM[1]);
            y += ROW_MM;
            dir = -dir;
            if y > Y_MAX_MM {
                y = START_MM[1];
            }
        }
    }
    out
}

/// The scenario with `steps` subtractions.
///
/// # Errors
/// Never for in-range sizes; a message if a tool leaves the exact range.
pub fn sequence(steps: usize) -> Result<Sequence, String> {
    let corners = prism_corners(SIDES, RADIUS_MM * UNITS_PER_MM, LENGTH_MM * UNITS_PER_MM);
    let poses: Vec<Pose> = path(steps + 1)
        .into_iter()
        .map(|[x, y]| Pose::at([x, y, BOTTOM_MM].map(|c| c * UNITS_PER_MM)))
        .collect();
    let steps = poses
        .windows(2)
        .map(|w| {
            let hull = corners
                .iter()
                .flat_map(|&c| [w[0].place(c), w[1].place(c)])
                .map(|p| p.map(|p| p.coords()).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Step {
                op: Op::Subtract,
                hull,
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Sequence {
        base: Base::Box(CellBox {
            min: [0; 3],
            max: BLOCK_MM.map(|c| (c * UNITS_PER_MM) as i64),
        }),
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_zig_zags_and_wraps() {
        let p = path(400);
        assert_eq!(p[0], [10.0, 10.0]);
        assert_eq!(p[1], [11.5, 10.0]);
        // 10 + 53 · 1.5 = 89.5, then x leaves [10, 90]: clamp, next row.
        assert_eq!(p[53], [89.5, 10.0]);
        assert_eq!(p[54], [90.0, 14.0]);
        assert_eq!(p[55], [88.5, 14.0]);
        assert!(p.iter().all(|q| (10.0..=90.0).contains(&q[0])));
        assert!(p.iter().all(|q| (10.0..=90.0).contains(&q[1])));
        let rows: std::collections::BTreeSet<i64> =
            path(3000).iter().map(|q| q[1] as i64).collect();
        assert_eq!(rows.len(), 21, "rows at y = 10, 14, …, 90");
    }

    #[test]
    fn every_step_is_the_tool_at_two_points() {
        let seq = sequence(3).unwrap();
        assert_eq!(seq.steps.len(), 3);
        for s in &seq.steps {
            assert_eq!(s.hull.len(), 2 * SIDES * 2);
            assert!(s.hull.iter().all(|p| p[2] == 30_000 || p[2] == 60_000));
        }
    }
}
