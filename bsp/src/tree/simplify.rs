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
use super::bsp::{Bsp, EMPTY, Label};
use super::cells::Cell;
use super::merge::BooleanOp;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::Plane;

/// Seed of the face order in rebuilt BSPs: fixed, so that rebuilding is a
/// pure function of the input.
const REBUILD_SEED: u64 = 0x5EED_C415_E100_0001;

/// A merged tree inside some bounds and its exact boundary there, with the
/// faces on the bounds marked, before the rebuild.
pub(crate) struct MergedBoundary {
    /// The merged tree (the same regions inside the bounds as the rebuild).
    pub(crate) merged: Bsp,
    /// Its boundary inside the bounds, faces on the bounds marked (when
    /// kept).
    pub(crate) faces: Vec<BoundaryFace>,
    /// The label of its first cell: that of all the bounds when no face
    /// lies inside them.
    uniform: Label,
}

impl MergedBoundary {
    /// The rebuild ([`Bsp::merge_simplified_faces`]) and the faces.
    #[cfg(test)]
    pub(crate) fn rebuilt(self) -> (Bsp, Vec<BoundaryFace>) {
        let rebuilt =
            Bsp::rebuilt_from_boundary(&self.faces).unwrap_or_else(|| Bsp::uniform(self.uniform));
        (rebuilt, self.faces)
    }

    /// The rebuild and the faces, when the rebuild has at most
    /// `max_splits` splits, else `self` back (the rebuild is left
    /// unfinished as soon as it has more).
    pub(crate) fn rebuilt_within(
        self,
        max_splits: usize,
    ) -> Result<(Bsp, Vec<BoundaryFace>), Self> {
        match Bsp::rebuilt_from_boundary_within(&self.faces, max_splits) {
            Some(rebuilt) => {
                let rebuilt = rebuilt.unwrap_or_else(|| Bsp::uniform(self.uniform));
                Ok((rebuilt, self.faces))
            }
            None => Err(self),
        }
    }
}

/// A plane's coefficients `(a, b, c, d)`.
type PlaneKey = (i64, i64, i64, i128);

/// The coefficients of `plane` or of `plane` flipped, whichever has its
/// first non-zero normal component positive: the same for both
/// orientations.
fn unoriented(plane: &Plane) -> PlaneKey {
    let (a, b, c, d) = (plane.a, plane.b, plane.c, plane.offset());
    let positive = [a, b, c]
        .into_iter()
        .find(|&x| x != 0)
        .is_some_and(|x| x > 0);
    if positive {
        (a, b, c, d)
    } else {
        (-a, -b, -c, -d)
    }
}

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
    #[cfg(test)]
    pub(crate) fn merge_simplified_faces(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> (Bsp, Vec<BoundaryFace>) {
        self.merge_boundary(other, op, arena, bounds, Bounds::Keep)
            .rebuilt()
    }

    /// `self op other` inside `bounds` (a polyhedron of `arena`, used up)
    /// with its boundary there, faces on the bounds marked (or left out,
    /// as `on_bounds` says): what [`Bsp::merge_simplified_faces`] rebuilds
    /// from, for callers that may not need the rebuild.
    pub(crate) fn merge_boundary(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
        on_bounds: Bounds,
    ) -> MergedBoundary {
        let (merged, cells) = self.merge_cells(other, op, arena, bounds);
        let faces = merged.boundary_of_cells(arena, &cells, on_bounds);
        let uniform = cells.first().map_or(EMPTY, |c| c.label);
        MergedBoundary {
            merged,
            faces,
            uniform,
        }
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

    /// Whether the rebuild from `faces` (as [`Bsp::rebuilt_from_boundary`]
    /// takes them) certainly has more than `budget` splits: its faces lie
    /// in more than `budget` distinct planes. Each face is inserted until
    /// every piece of it becomes a split by its plane or lies in the plane
    /// of a split already there, so each of those planes, up to
    /// orientation and scale, is the plane of at least one split.
    pub(crate) fn rebuild_exceeds(faces: &[BoundaryFace], budget: usize) -> bool {
        let inner = || faces.iter().filter(|f| !f.on_bounds);
        if inner().count() <= budget {
            return false;
        }
        // Faces cut from one split share its coefficients exactly: those
        // are told apart first, and only the distinct ones compared up to
        // scale.
        let mut planes: Vec<PlaneKey> = inner().map(|f| unoriented(&f.plane)).collect();
        planes.sort_unstable();
        planes.dedup();
        if planes.len() <= budget {
            return false;
        }
        for key in &mut planes {
            let (a, b, c, d) = *key;
            *key = unoriented(&Plane::new_unchecked(a, b, c, d).normalized());
        }
        planes.sort_unstable();
        planes.dedup();
        planes.len() > budget
    }

    /// The rebuild from `faces`, the exact boundary of some regions inside
    /// some bounds with the faces on the bounds marked (those are left
    /// out): the tree [`Bsp::simplified`] builds from that boundary, or
    /// `None` when no face lies inside the bounds (the regions are then one
    /// label there).
    pub(crate) fn rebuilt_from_boundary(faces: &[BoundaryFace]) -> Option<Bsp> {
        Bsp::rebuilt_from_boundary_within(faces, usize::MAX)
            .unwrap_or_else(|| unreachable!("no tree has more than usize::MAX splits"))
    }

    /// [`Bsp::rebuilt_from_boundary`] when that tree has at most
    /// `max_splits` splits, else `None` (the rebuild is left unfinished as
    /// soon as it has more).
    pub(crate) fn rebuilt_from_boundary_within(
        faces: &[BoundaryFace],
        max_splits: usize,
    ) -> Option<Option<Bsp>> {
        // The same faces in the same order as with `Bounds::Skip`.
        let mut inner = faces.iter().filter(|f| !f.on_bounds).peekable();
        if inner.peek().is_none() {
            return Some(None);
        }
        Bsp::from_faces_within(inner, REBUILD_SEED, max_splits).map(Some)
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

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::exact::IntPoint;

    fn point(x: i64, y: i64, z: i64) -> IntPoint {
        IntPoint::new(x, y, z).expect("in budget")
    }

    /// A box of random size and place inside `[-40, 40]³` filled with
    /// `label`.
    fn random_box(rng: &mut ChaCha8Rng, label: Label) -> Bsp {
        let lo = [0; 3].map(|_| rng.random_range(-40..20));
        let hi = lo.map(|l| l + rng.random_range(4..20));
        let mut arena = ConvexArena::new();
        let poly = arena
            .add_box(point(lo[0], lo[1], lo[2]), point(hi[0], hi[1], hi[2]))
            .expect("in budget");
        Bsp::from_convex(&arena, poly, label)
    }

    /// For merges of random boxes of two materials: the rebuild within a
    /// budget is the full rebuild, node for node, exactly when that has no
    /// more splits, and the count of distinct planes never claims more
    /// splits than the rebuild has; both answers occur.
    #[test]
    fn rebuild_limits_agree_with_the_full_rebuild() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut exceeded, mut within) = (0, 0);
        for _ in 0..30 {
            let mut bsp = random_box(&mut rng, 1);
            for i in 0..3 {
                let op = if i == 1 {
                    BooleanOp::Union
                } else {
                    BooleanOp::Difference
                };
                let other = random_box(&mut rng, 1 + i % 2);
                let mut arena = ConvexArena::new();
                let bounds = arena
                    .add_box(point(-30, -30, -30), point(30, 30, 30))
                    .expect("in budget");
                let merged = bsp.merge_boundary(&other, op, &mut arena, bounds, Bounds::Keep);
                let full = Bsp::rebuilt_from_boundary(&merged.faces);
                let splits = full.as_ref().map_or(0, |t| t.nodes().len() / 2);
                for budget in 0..splits + 3 {
                    let limited = Bsp::rebuilt_from_boundary_within(&merged.faces, budget);
                    match &limited {
                        Some(tree) => {
                            assert!(splits <= budget);
                            let same = |a: &Option<Bsp>, b: &Option<Bsp>| match (a, b) {
                                (Some(a), Some(b)) => {
                                    a.nodes() == b.nodes() && a.planes() == b.planes()
                                }
                                (None, None) => true,
                                _ => false,
                            };
                            assert!(same(tree, &full));
                            within += 1;
                        }
                        None => assert!(splits > budget),
                    }
                    if Bsp::rebuild_exceeds(&merged.faces, budget) {
                        assert!(splits > budget, "{splits} splits, budget {budget}");
                        exceeded += 1;
                    }
                }
                let (rebuilt, _) = merged.rebuilt();
                bsp = rebuilt;
            }
        }
        assert!(exceeded > 20 && within > 20, "{exceeded} {within}");
    }
}
