//! An operation sequence on the integer grid: a base solid, then convex
//! tools (hulls of integer points) applied one after another.
//!
//! Units: scenarios speak millimetres; the kernel's grid is 1 µm, so a
//! coordinate in millimetres becomes `round(mm × 1000)` ([`quantize_mm`]).
//! Hull points are stored already quantized, so the tools that run, the
//! tools that are recorded and the tools a peer replays are the same.

use std::path::PathBuf;

use chisel_bsp::exact::budget::MAX_COORD;
use chisel_bsp::octree::{CellBox, Edit};

/// Grid units per millimetre.
pub const UNITS_PER_MM: f64 = 1000.0;

/// What one step does with its tool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// Remove the material inside the tool.
    Subtract,
    /// Add material inside the tool.
    Union,
    /// Keep only the material inside the tool.
    Intersect,
}

impl Op {
    /// The name used in the replay format.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Op::Subtract => "subtract",
            Op::Union => "union",
            Op::Intersect => "intersect",
        }
    }

    /// The octree edit; added material is label 1, like the base.
    #[must_use]
    pub fn edit(self) -> Edit {
        match self {
            Op::Subtract => Edit::Subtract,
            Op::Union => Edit::Add(1),
            Op::Intersect => Edit::Intersect,
        }
    }
}

/// One step: an operation with the convex hull of integer points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Step {
    /// The operation.
    pub op: Op,
    /// The tool is the convex hull of these points (grid units).
    pub hull: Vec<[i64; 3]>,
}

/// The solid the steps start from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Base {
    /// Nothing: the steps build the solid (unions).
    Empty,
    /// An axis-aligned box (grid units).
    Box(CellBox),
    /// A closed triangle mesh read from a file.
    Mesh(PathBuf),
}

/// A base and the steps applied to it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sequence {
    /// The starting solid.
    pub base: Base,
    /// The steps, in order.
    pub steps: Vec<Step>,
}

/// A millimetre coordinate on the 1 µm grid.
///
/// # Errors
/// A message for non-finite values and values beyond the kernel's range
/// (±2^26 µm, about ±67 m).
pub fn quantize_mm(mm: f64) -> Result<i64, String> {
    if !mm.is_finite() {
        return Err(format!("coordinate {mm} is not a finite number"));
    }
    let units = (mm * UNITS_PER_MM).round();
    if units.abs() > MAX_COORD as f64 {
        return Err(format!(
            "coordinate {mm} mm is outside the exact range of ±{} mm",
            MAX_COORD as f64 / UNITS_PER_MM
        ));
    }
    Ok(units as i64)
}

/// A grid coordinate in millimetres (exact inverse of [`quantize_mm`]:
/// the shortest decimal of the result parses and rounds back to `units`).
#[must_use]
pub fn to_mm(units: i64) -> f64 {
    units as f64 / UNITS_PER_MM
}

/// The smallest power-of-two cube `(origin, size_log2)` holding `bounds`,
/// kept inside the exact coordinate range.
///
/// # Errors
/// A message when no such cube fits the range.
pub fn root_cube(bounds: CellBox) -> Result<([i64; 3], u8), String> {
    let extent = (0..3)
        .map(|a| bounds.max[a] - bounds.min[a])
        .max()
        .unwrap_or(0)
        .max(2);
    let size_log2 = (64 - (extent - 1).leading_zeros()) as u8;
    let edge = 1i64 << size_log2;
    let origin = bounds.min.map(|m| m.max(-MAX_COORD).min(MAX_COORD - edge));
    if size_log2 > 27 || (0..3).any(|a| origin[a] < -MAX_COORD || origin[a] > bounds.min[a]) {
        return Err("the geometry spans more than the exact coordinate range".into());
    }
    Ok((origin, size_log2))
}

/// Whether the points span a volume: exactly when their convex hull is a
/// tool rather than a degenerate-hull error.
pub use chisel_bsp::tools::spans_volume;

impl Sequence {
    /// The box around the base box and every tool point, or `None` when
    /// there is neither (a mesh base adds its own bounds later).
    #[must_use]
    pub fn bounds(&self) -> Option<CellBox> {
        let mut out: Option<CellBox> = match &self.base {
            Base::Box(b) => Some(*b),
            Base::Empty | Base::Mesh(_) => None,
        };
        for p in self.steps.iter().flat_map(|s| &s.hull) {
            out = Some(match out {
                None => CellBox { min: *p, max: *p },
                Some(b) => CellBox {
                    min: [0, 1, 2].map(|a| b.min[a].min(p[a])),
                    max: [0, 1, 2].map(|a| b.max[a].max(p[a])),
                },
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn millimetres_round_trip_through_their_shortest_decimal() {
        for units in [0, 1, -1, 999, 12_345, -67_108_864, 67_108_864, 30_001] {
            let text = serde_json::to_string(&to_mm(units)).unwrap();
            let back: f64 = serde_json::from_str(&text).unwrap();
            assert_eq!(quantize_mm(back), Ok(units), "{text}");
        }
        assert!(quantize_mm(f64::NAN).is_err());
        assert!(quantize_mm(1e6).is_err());
    }

    #[test]
    fn the_root_cube_holds_the_bounds() {
        let b = CellBox {
            min: [0, 0, 0],
            max: [100_000, 100_000, 60_000],
        };
        assert_eq!(root_cube(b), Ok(([0, 0, 0], 17)));
        let b = CellBox {
            min: [-8_000, -8_000, 0],
            max: [108_000, 10, 10],
        };
        let (origin, k) = root_cube(b).unwrap();
        assert_eq!(origin, [-8_000, -8_000, 0]);
        assert!(1i64 << k >= 116_000 && 1i64 << (k - 1) < 116_000);
    }
}
