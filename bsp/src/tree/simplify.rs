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

use super::boundary::{BoundaryFace, Bounds};
use super::bsp::{Bsp, EMPTY};
use super::cells::Cell;
use super::merge::BooleanOp;
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
        self.rebuilt(arena, &cells)
    }

    /// `(self op other).simplified(…)` inside `bounds` (a polyhedron of
    /// `arena`, used up), equal to [`Bsp::merge`] followed by
    /// [`Bsp::simplified`] but without cutting the merged tree's cells a
    /// second time: the merge keeps them ([`Bsp::merge_cells`]).
    #[must_use]
    pub fn merge_simplified(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> Bsp {
        let (merged, cells) = self.merge_cells(other, op, arena, bounds);
        merged.rebuilt(arena, &cells)
    }

    /// [`Bsp::merge_simplified`], also returning the merged tree's boundary
    /// inside `bounds` that the rebuild starts from, with the faces on the
    /// bounds ([`Bsp::boundary`] of the result, in other pieces).
    pub(crate) fn merge_simplified_faces(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> (Bsp, Vec<BoundaryFace>) {
        let (merged, cells) = self.merge_cells(other, op, arena, bounds);
        merged.rebuilt_with_faces(arena, &cells)
    }

    /// [`Bsp::simplified`], also returning the boundary inside `bounds`
    /// that the rebuild starts from, with the faces on the bounds
    /// ([`Bsp::boundary`] of the result, in other pieces).
    pub(crate) fn simplified_faces(
        &self,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> (Bsp, Vec<BoundaryFace>) {
        let cells = self.cells(arena, bounds);
        self.rebuilt_with_faces(arena, &cells)
    }

    /// [`Bsp::rebuilt`], also returning the boundary it starts from with the
    /// faces on the bounds.
    fn rebuilt_with_faces(&self, arena: &ConvexArena, cells: &[Cell]) -> (Bsp, Vec<BoundaryFace>) {
        let faces = self.boundary_of_cells(arena, cells, Bounds::Keep);
        let rebuilt = Bsp::rebuilt_from_boundary(&faces)
            .unwrap_or_else(|| Bsp::uniform(cells.first().map_or(EMPTY, |c| c.label)));
        (rebuilt, faces)
    }

    /// The rebuild from `faces`, the exact boundary of some regions inside
    /// some bounds with the faces on the bounds marked (those are left
    /// out): the tree [`Bsp::simplified`] builds from that boundary, or
    /// `None` when no face lies inside the bounds (the regions are then one
    /// label there).
    pub(crate) fn rebuilt_from_boundary(faces: &[BoundaryFace]) -> Option<Bsp> {
        // The same faces in the same order as with `Bounds::Skip`.
        let mut inner = faces.iter().filter(|f| !f.on_bounds).peekable();
        inner.peek()?;
        Some(Bsp::from_faces(inner, REBUILD_SEED))
    }

    /// The rebuild from `self`'s cells inside some bounds (from
    /// [`Bsp::cells`] or [`Bsp::merge_cells`] on `arena`).
    fn rebuilt(&self, arena: &ConvexArena, cells: &[Cell]) -> Bsp {
        let uniform = cells.first().map_or(EMPTY, |c| c.label);
        let faces = self.boundary_of_cells(arena, cells, Bounds::Skip);
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
