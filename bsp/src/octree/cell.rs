//! Octree cells: keys and integer boxes.
//!
//! Notation: the root cell is the cube `[o, o + 2^k]³` (`o` the origin,
//! `k` the size exponent); a cell at depth `d` has edge `2^(k−d)` and key
//! `(d, x, y, z)`, its position in units of that edge. Child `i` takes the
//! upper half along x when bit 0 of `i` is set, y for bit 1, z for bit 2.

use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::IntPoint;

/// One octree cell: its depth and its integer position at that depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CellKey {
    /// Depth below the root (the root is 0).
    pub depth: u8,
    /// Position in units of the cell's edge, per axis.
    pub pos: [u32; 3],
}

impl CellKey {
    /// The root cell.
    pub const ROOT: CellKey = CellKey {
        depth: 0,
        pos: [0; 3],
    };

    /// Child `i` (bit 0: upper x half, bit 1: upper y, bit 2: upper z).
    #[must_use]
    pub fn child(self, i: usize) -> CellKey {
        let mut pos = self.pos;
        for (axis, p) in pos.iter_mut().enumerate() {
            *p = 2 * *p + ((i >> axis) & 1) as u32;
        }
        CellKey {
            depth: self.depth + 1,
            pos,
        }
    }

    /// The parent cell, or `None` for the root.
    #[must_use]
    pub fn parent(self) -> Option<CellKey> {
        (self.depth > 0).then(|| CellKey {
            depth: self.depth - 1,
            pos: self.pos.map(|p| p / 2),
        })
    }
}

/// A closed axis-aligned box `[min, max]` on the integer grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CellBox {
    /// Lower corner.
    pub min: [i64; 3],
    /// Upper corner.
    pub max: [i64; 3],
}

impl CellBox {
    /// The smallest closed box holding every point of `points`, or `None`
    /// when there are none (the box may be flat).
    #[must_use]
    pub fn enclosing(points: impl IntoIterator<Item = [i64; 3]>) -> Option<CellBox> {
        let mut points = points.into_iter();
        let first = points.next()?;
        let mut out = CellBox {
            min: first,
            max: first,
        };
        for p in points {
            for (a, c) in p.into_iter().enumerate() {
                out.min[a] = out.min[a].min(c);
                out.max[a] = out.max[a].max(c);
            }
        }
        Some(out)
    }

    /// Whether the closed boxes share at least a point.
    #[must_use]
    pub fn touches(&self, other: &CellBox) -> bool {
        (0..3).all(|a| self.min[a] <= other.max[a] && other.min[a] <= self.max[a])
    }

    /// Whether the boxes share volume (their interiors meet).
    #[must_use]
    pub fn overlaps(&self, other: &CellBox) -> bool {
        (0..3).all(|a| self.min[a] < other.max[a] && other.min[a] < self.max[a])
    }

    /// The centre, rounded down (exact for cells of edge ≥ 2).
    #[must_use]
    pub fn mid(&self) -> [i64; 3] {
        [0, 1, 2].map(|a| self.min[a] + (self.max[a] - self.min[a]) / 2)
    }

    /// The box of child `i` (see [`CellKey::child`]).
    #[must_use]
    pub fn child(&self, i: usize) -> CellBox {
        let mid = self.mid();
        let mut out = *self;
        for (axis, &m) in mid.iter().enumerate() {
            if (i >> axis) & 1 == 1 {
                out.min[axis] = m;
            } else {
                out.max[axis] = m;
            }
        }
        out
    }

    /// The smallest edge length.
    #[must_use]
    pub fn min_edge(&self) -> i64 {
        (0..3).map(|a| self.max[a] - self.min[a]).min().unwrap_or(0)
    }

    /// The box as a convex polyhedron in `arena`.
    ///
    /// # Errors
    /// Out-of-range corners or an empty box.
    pub fn add_to(&self, arena: &mut ConvexArena) -> Result<PolyId, Error> {
        arena.add_box(
            IntPoint::from_array(self.min)?,
            IntPoint::from_array(self.max)?,
        )
    }
}
