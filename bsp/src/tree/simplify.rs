//! Redundancy removal by extraction and rebuilding (paper 1 §3.7).
//!
//! Notation: `T` — the BSP, `K` — the convex bounds it is restricted to.
//!
//! Booleans leave planes that no longer bound anything and split the same
//! surface many times. Extracting the exact boundary of `T` inside `K`
//! ([`Bsp::boundary`]) and importing it again ([`super::import`]) gives a
//! BSP of the same regions inside `K` whose planes all carry surface. The
//! faces on `K` itself are not inserted — outside `K` nothing is promised —
//! so the planes of an octree cell never enter its BSP. Interfaces between
//! two materials are inserted with both labels.
//!
//! Why the rebuilt labels are right: every final leaf was created by
//! splitting with a face piece lying on its boundary, and takes the label
//! on its side of that face; no face crosses a final leaf's cell inside
//! `K`, so the whole cell has that label. With no face inside `K`, all of
//! `K` has one label, read off any cell.

use super::boundary::Bounds;
use super::bsp::{Bsp, EMPTY};
use crate::convex::{ConvexArena, PolyId};

/// Seed of the face order in rebuilt BSPs: fixed, so that rebuilding is a
/// pure function of the input.
const REBUILD_SEED: u64 = 0x5EED_C415_E100_0001;

impl Bsp {
    /// The same regions as `self` inside `bounds` (a polyhedron of `arena`,
    /// cut up in place), rebuilt from the exact boundary: no plane that
    /// bounds nothing, no surface split more than the rebuild needs.
    /// Deterministic.
    #[must_use]
    pub fn simplified(&self, arena: &mut ConvexArena, bounds: PolyId) -> Bsp {
        let cells = self.cells(arena, bounds);
        let uniform = cells.first().map_or(EMPTY, |c| c.label);
        let faces = self.boundary_of_cells(arena, &cells, Bounds::Skip);
        if faces.is_empty() {
            return Bsp::uniform(uniform);
        }
        let polygons: Vec<_> = faces
            .into_iter()
            .map(|f| {
                let (label, outside) = (f.label, f.outside);
                (f.into_polygon(), label, outside)
            })
            .collect();
        Bsp::from_polygons(polygons, REBUILD_SEED)
    }
}
