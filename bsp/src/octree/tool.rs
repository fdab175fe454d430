//! Tools: the solids an edit applies, as BSPs with integer bounds.
//!
//! A tool is a convex polyhedron (an exact hull of integer points, a box, a
//! placed or swept shape from [`crate::tools`]) or a union of such; its
//! bounds are a closed integer box containing it, used to find the cells
//! it can touch, and its convex pieces decide exactly which of those boxes
//! the closed solid meets ([`Tool::touches`]).

mod contact;
mod facets;
mod restrict;

use contact::ConvexPiece;
pub(crate) use facets::facet_chain;
pub(crate) use restrict::{restricted, solid_at_a_corner};

use super::cell::CellBox;
use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::IntPoint;
use crate::exact::budget::MAX_COORD;
use crate::tools::Pose;
use crate::tools::hull::{HullPolygons, with_hull_polygons};
use crate::tools::shapes::{placed_points, swept_points};
use crate::tree::{BooleanOp, Bsp, Label};

/// A solid to carve with, add or paint.
#[derive(Clone, Debug)]
pub struct Tool {
    bsp: Bsp,
    bounds: CellBox,
    /// The convex pieces whose union is the solid, each with its bounds;
    /// a piece with a vertex off the integer grid is `None`, and only its
    /// bounds decide where it touches.
    pieces: Vec<(CellBox, Option<ConvexPiece>)>,
}

impl Tool {
    /// The convex hull of integer points.
    ///
    /// # Errors
    /// [`Error::DegenerateHull`] when the points span no volume.
    pub fn convex_hull(points: &[IntPoint]) -> Result<Tool, Error> {
        with_hull_polygons(points, Self::from_hull)
    }

    /// The tool [`Tool::from_polyhedron`] makes of the hull's polyhedron,
    /// built from the hull's arrays without an arena: the BSP's planes and
    /// the piece's faces in [`ConvexArena::faces_of`] order, bounds one
    /// unit around the integer vertices.
    fn from_hull(hull: &HullPolygons) -> Tool {
        let piece = ConvexPiece::from_hull(hull);
        let (mut min, mut max) = ([MAX_COORD; 3], [-MAX_COORD; 3]);
        for p in &hull.vertices {
            for a in 0..3 {
                min[a] = min[a].min((p[a] - 1).max(-MAX_COORD));
                max[a] = max[a].max((p[a] + 1).min(MAX_COORD));
            }
        }
        let planes = hull.breadth_first.iter().map(|&f| hull.planes[f as usize]);
        Tool {
            bsp: Bsp::convex(planes, 1),
            bounds: CellBox { min, max },
            pieces: vec![(CellBox { min, max }, piece)],
        }
    }

    /// A shape's corners (in grid units) placed at `pose` and rounded: the
    /// hull of the rounded corners.
    ///
    /// # Errors
    /// Non-finite or out-of-range coordinates, or a flat result.
    pub fn placed(corners: &[[f64; 3]], pose: &Pose) -> Result<Tool, Error> {
        Self::convex_hull(&placed_points(corners, pose)?)
    }

    /// The volume a convex shape sweeps from pose `a` to pose `b` (hull of
    /// its rounded corners at both).
    ///
    /// # Errors
    /// As [`Tool::placed`].
    pub fn swept(corners: &[[f64; 3]], a: &Pose, b: &Pose) -> Result<Tool, Error> {
        Self::convex_hull(&swept_points(corners, a, b)?)
    }

    /// The axis-aligned box `solid`.
    ///
    /// # Errors
    /// An empty or out-of-range box.
    pub fn cuboid(solid: CellBox) -> Result<Tool, Error> {
        let mut arena = ConvexArena::new();
        let poly = solid.add_to(&mut arena)?;
        Ok(Self::from_polyhedron(&arena, poly))
    }

    /// A convex polyhedron of `arena`.
    #[must_use]
    pub fn from_polyhedron(arena: &ConvexArena, poly: PolyId) -> Tool {
        let mut min = [MAX_COORD; 3];
        let mut max = [-MAX_COORD; 3];
        for v in arena.vertices_of(poly) {
            let p = arena.position(v);
            for a in 0..3 {
                // One unit of slack covers the rounding of the position.
                min[a] = min[a].min((p[a].floor() as i64 - 1).max(-MAX_COORD));
                max[a] = max[a].max((p[a].ceil() as i64 + 1).min(MAX_COORD));
            }
        }
        Tool {
            bsp: Bsp::from_convex(arena, poly, 1),
            bounds: CellBox { min, max },
            pieces: vec![(CellBox { min, max }, ConvexPiece::of(arena, poly))],
        }
    }

    /// The union of several tools.
    ///
    /// # Errors
    /// [`Error::NoTools`] for an empty list.
    pub fn union(tools: &[Tool]) -> Result<Tool, Error> {
        let (first, rest) = tools.split_first().ok_or(Error::NoTools)?;
        let mut out = first.clone();
        for tool in rest {
            for a in 0..3 {
                out.bounds.min[a] = out.bounds.min[a].min(tool.bounds.min[a]);
                out.bounds.max[a] = out.bounds.max[a].max(tool.bounds.max[a]);
            }
            let mut arena = ConvexArena::new();
            let bounds = out.bounds.add_to(&mut arena)?;
            out.bsp = out
                .bsp
                .merge(&tool.bsp, BooleanOp::Union, &mut arena, bounds);
            out.pieces.extend(tool.pieces.iter().cloned());
        }
        Ok(out)
    }

    /// A closed integer box containing the tool.
    #[must_use]
    pub fn bounds(&self) -> CellBox {
        self.bounds
    }

    /// Whether the closed solid meets the closed box `cell` (they share at
    /// least a point: touching at a vertex, along an edge or on a face
    /// counts). Exact for tools made of convex hulls of integer points
    /// ([`Tool::convex_hull`], [`Tool::placed`], [`Tool::swept`],
    /// [`Tool::cuboid`] and their unions); a piece made by
    /// [`Tool::from_polyhedron`] with a vertex off the integer grid counts
    /// as meeting every box that touches its bounds.
    #[must_use]
    pub fn touches(&self, cell: &CellBox) -> bool {
        self.bounds.touches(cell)
            && self.pieces.iter().any(|(bounds, piece)| {
                bounds.touches(cell)
                    && piece
                        .as_ref()
                        .is_none_or(|piece| piece.touches(cell.min, cell.max))
            })
    }

    /// Whether the solid shares volume with the box `cell` (with volume
    /// itself), decided exactly from the convex pieces; `None` when a piece
    /// that may share it has a vertex off the integer grid. The same answer
    /// as asking whether the tool's BSP has a solid cell with volume in
    /// `cell` ([`Bsp::cells`]), without cutting.
    #[must_use]
    pub fn shares_volume(&self, cell: &CellBox) -> Option<bool> {
        if !self.bounds.overlaps(cell) || (0..3).any(|a| cell.min[a] >= cell.max[a]) {
            return Some(false);
        }
        let mut unknown = false;
        for (bounds, piece) in &self.pieces {
            if !bounds.overlaps(cell) {
                continue;
            }
            match piece {
                Some(piece) if piece.shares_volume(cell.min, cell.max) => return Some(true),
                Some(_) => {}
                None => unknown = true,
            }
        }
        (!unknown).then_some(false)
    }

    /// The tool's solid (label 1) as a BSP.
    #[must_use]
    pub fn bsp(&self) -> &Bsp {
        &self.bsp
    }

    /// The tool's BSP with its solid labelled `label`.
    pub(crate) fn labelled(&self, label: Label) -> Bsp {
        self.bsp.relabeled(|l| if l == 0 { 0 } else { label })
    }
}

/// The hull of `points` random integer points within `radius` of
/// `centre` on every axis, drawn again until they span a solid (tests).
#[cfg(test)]
pub(crate) fn random_hull(
    rng: &mut rand_chacha::ChaCha8Rng,
    centre: i64,
    radius: i64,
    points: usize,
) -> Tool {
    use rand::Rng;
    loop {
        let points: Vec<IntPoint> = (0..points)
            .map(|_| {
                let c = [0; 3].map(|_: i64| centre + rng.random_range(-radius..=radius));
                IntPoint::from_array(c).expect("small coordinates")
            })
            .collect();
        if let Ok(tool) = Tool::convex_hull(&points) {
            return tool;
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::Tool;
    use crate::convex::ConvexArena;
    use crate::exact::IntPoint;
    use crate::tools::convex_hull;

    /// [`Tool::convex_hull`] builds without an arena what
    /// [`Tool::from_polyhedron`] builds from the hull's polyhedron: the
    /// same BSP (planes in order), bounds and contact piece.
    #[test]
    fn hull_tool_equals_the_tool_of_the_hull_polyhedron() {
        let mut rng = ChaCha8Rng::seed_from_u64(72);
        for round in 0..300 {
            let (n, radius, centre) = match round % 3 {
                0 => (rng.random_range(4..60), 3, 0),
                1 => (rng.random_range(4..90), 1 << 20, 1 << 24),
                _ => (rng.random_range(4..90), 1 << 26, 0),
            };
            let points: Vec<IntPoint> = (0..n)
                .map(|_| {
                    let c = [0; 3].map(|_: i64| {
                        (centre + rng.random_range(-radius..=radius)).clamp(-(1 << 26), 1 << 26)
                    });
                    IntPoint::from_array(c).expect("in budget")
                })
                .collect();
            let mut arena = ConvexArena::new();
            let Ok(poly) = convex_hull(&mut arena, &points) else {
                assert!(Tool::convex_hull(&points).is_err());
                continue;
            };
            let expected = Tool::from_polyhedron(&arena, poly);
            let tool = Tool::convex_hull(&points).expect("the same hull");
            assert_eq!(
                format!("{tool:?}"),
                format!("{expected:?}"),
                "round {round}"
            );
        }
    }
}
