//! Watertightness: every directed edge `(u, v)` of a polygon is used once,
//! and its opposite `(v, u)` exactly once, by another polygon.
//!
//! This is what a closed, consistently oriented manifold surface looks like
//! after welding and T-junction removal. A solid touching itself along an
//! edge has a closed surface that is not manifold there (four polygons meet
//! at the edge): [`SurfaceMesh::check_closed`] checks the weaker property
//! that holds for every closed surface, each directed edge used as often as
//! its opposite. A boundary with material interfaces is
//! not such a surface (three polygons meet where two materials and empty
//! space do, and an interface polygon is reported once, by the material
//! with the larger label): check each material's region instead
//! ([`SurfaceMesh::check_regions_closed`]: a polygon bounds the region of
//! its [`label`](super::MeshPolygon::label) as it is, and the region of its
//! [`outside`](super::MeshPolygon::outside) turned round), or its outer
//! surface ([`SurfaceMesh::retain`] with `outside == EMPTY`).

use std::collections::{HashMap, HashSet};
use std::hash::BuildHasherDefault;

use super::SurfaceMesh;
use crate::tree::{EMPTY, Label};
use crate::word_hash::WordHasher;

/// Directed edge `(from, to)` packed into one word.
#[inline]
fn edge_key(from: u32, to: u32) -> u64 {
    (u64::from(from) << 32) | u64::from(to)
}

/// How often each directed edge is used, by [`edge_key`].
type EdgeUses = HashMap<u64, u32, BuildHasherDefault<WordHasher>>;

/// A set of directed edges, by [`edge_key`].
type EdgeSet = HashSet<u64, BuildHasherDefault<WordHasher>>;

/// How often each directed edge bounds each material's region, by label
/// and [`edge_key`].
type RegionEdgeUses = HashMap<(Label, u64), u32, BuildHasherDefault<WordHasher>>;

/// What is wrong with one directed edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeProblem {
    /// No polygon uses the opposite edge `(to, from)`: a crack, a hole, or a
    /// T-junction left in place.
    Open,
    /// More than one polygon uses the edge in this direction: overlapping or
    /// inconsistently oriented polygons, or a non-manifold edge.
    Repeated,
    /// The edge is used once, but its opposite more than once.
    OppositeRepeated,
}

/// One offending directed edge, with its vertices' positions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BadEdge {
    /// Start vertex index.
    pub from: u32,
    /// End vertex index.
    pub to: u32,
    /// Start position (`f64`, for display).
    pub from_position: [f64; 3],
    /// End position (`f64`, for display).
    pub to_position: [f64; 3],
    /// What is wrong with it.
    pub problem: EdgeProblem,
}

/// The surface is not watertight: counts of offending directed edges and
/// the first one found (in polygon order, so the report is deterministic).
///
/// Always a kernel bug when the polygons come from
/// [`Bsp::boundary`](crate::tree::Bsp::boundary) of a single material; for
/// polygons from elsewhere, the input is not a closed surface.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "surface is not watertight: {open} open, {repeated} repeated and {opposite_repeated} with a \
     repeated opposite directed edge(s); e.g. edge {} -> {} from {:?} to {:?} is {}",
    .example.from,
    .example.to,
    .example.from_position,
    .example.to_position,
    problem_text(.example.problem)
)]
pub struct WatertightError {
    /// Directed edges whose opposite no polygon uses.
    pub open: usize,
    /// Directed edges used more than once in the same direction (each such
    /// edge counted once).
    pub repeated: usize,
    /// Directed edges used once whose opposite is used more than once.
    pub opposite_repeated: usize,
    /// The first offending edge.
    pub example: BadEdge,
}

/// What [`WatertightError`]'s message says of its example edge.
fn problem_text(problem: EdgeProblem) -> &'static str {
    match problem {
        EdgeProblem::Open => "open (no opposite edge)",
        EdgeProblem::Repeated => "used more than once in this direction",
        EdgeProblem::OppositeRepeated => "matched by more than one opposite edge",
    }
}

impl SurfaceMesh {
    /// The directed edges `(corner k, corner k + 1)` of every polygon, in
    /// polygon order.
    pub fn directed_edges(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.polygons().iter().flat_map(|p| {
            let n = p.corners.len();
            (0..n).map(move |k| (p.corners[k], p.corners[(k + 1) % n]))
        })
    }

    /// How often each directed edge is used.
    fn edge_uses(&self) -> EdgeUses {
        let edges: usize = self.polygons().iter().map(|p| p.corners.len()).sum();
        let mut uses = EdgeUses::with_capacity_and_hasher(edges, BuildHasherDefault::default());
        for (u, v) in self.directed_edges() {
            *uses.entry(edge_key(u, v)).or_insert(0) += 1;
        }
        uses
    }

    /// Checks that every directed edge is used exactly once and its
    /// opposite exactly once: the surface is a closed, oriented 2-manifold.
    /// Solids that touch themselves along an edge (two cubes sharing only
    /// an edge) fail with [`EdgeProblem::Repeated`] although they are
    /// closed; see [`SurfaceMesh::check_closed`].
    ///
    /// # Errors
    /// [`WatertightError`] with the counts of offending edges and the first
    /// one found.
    pub fn check_watertight(&self) -> Result<(), WatertightError> {
        let uses = self.edge_uses();
        let (mut open, mut repeated, mut opposite_repeated) = (0, 0, 0);
        let mut example = None;
        let mut seen_repeated = EdgeSet::default();
        for (u, v) in self.directed_edges() {
            let here = uses.get(&edge_key(u, v)).copied().unwrap_or(0);
            let opposite = uses.get(&edge_key(v, u)).copied().unwrap_or(0);
            let problem = if here > 1 {
                if !seen_repeated.insert(edge_key(u, v)) {
                    continue;
                }
                repeated += 1;
                EdgeProblem::Repeated
            } else if opposite == 0 {
                open += 1;
                EdgeProblem::Open
            } else if opposite > 1 {
                opposite_repeated += 1;
                EdgeProblem::OppositeRepeated
            } else {
                continue;
            };
            example.get_or_insert(BadEdge {
                from: u,
                to: v,
                from_position: self.position(u),
                to_position: self.position(v),
                problem,
            });
        }
        match example {
            None => Ok(()),
            Some(example) => Err(WatertightError {
                open,
                repeated,
                opposite_repeated,
                example,
            }),
        }
    }

    /// Checks the weaker property of any closed, consistently oriented
    /// surface, manifold or not: every directed edge `(u, v)` is used as
    /// often as its opposite `(v, u)`. True for the boundary of every
    /// single-material solid, including solids touching themselves along an
    /// edge.
    ///
    /// # Errors
    /// [`WatertightError`] whose [`open`](WatertightError::open) counts the
    /// distinct directed edges used more often than their opposite (each
    /// reported as [`EdgeProblem::Open`]), and the first of them.
    pub fn check_closed(&self) -> Result<(), WatertightError> {
        let uses = self.edge_uses();
        let mut seen = EdgeSet::default();
        let mut open = 0;
        let mut example = None;
        for (u, v) in self.directed_edges() {
            let here = uses.get(&edge_key(u, v)).copied().unwrap_or(0);
            let opposite = uses.get(&edge_key(v, u)).copied().unwrap_or(0);
            if here > opposite && seen.insert(edge_key(u, v)) {
                open += 1;
                example.get_or_insert(BadEdge {
                    from: u,
                    to: v,
                    from_position: self.position(u),
                    to_position: self.position(v),
                    problem: EdgeProblem::Open,
                });
            }
        }
        match example {
            None => Ok(()),
            Some(example) => Err(WatertightError {
                open,
                repeated: 0,
                opposite_repeated: 0,
                example,
            }),
        }
    }

    /// The directed edges of every material region's boundary, with the
    /// region's label: a polygon's edges for its `label`, and, for an
    /// interface polygon (`outside` not empty), the same edges reversed
    /// for its `outside`.
    pub fn region_edges(&self) -> impl Iterator<Item = (Label, u32, u32)> + '_ {
        self.polygons().iter().flat_map(|p| {
            let n = p.corners.len();
            (0..n).flat_map(move |k| {
                let (u, v) = (p.corners[k], p.corners[(k + 1) % n]);
                let back = (p.outside != EMPTY).then_some((p.outside, v, u));
                std::iter::once((p.label, u, v)).chain(back)
            })
        })
    }

    /// How often each directed edge bounds each region.
    fn region_edge_uses(&self) -> RegionEdgeUses {
        let mut uses = RegionEdgeUses::default();
        for (label, u, v) in self.region_edges() {
            *uses.entry((label, edge_key(u, v))).or_insert(0) += 1;
        }
        uses
    }

    /// [`SurfaceMesh::check_closed`] for every material region: each
    /// directed edge bounds a region as often as its opposite does. This is
    /// what holds for the boundary of a multi-material solid, where an
    /// interface between two materials is one polygon (see the module
    /// doc); for a single material it is [`SurfaceMesh::check_closed`].
    ///
    /// # Errors
    /// As [`SurfaceMesh::check_closed`], counting per region.
    pub fn check_regions_closed(&self) -> Result<(), WatertightError> {
        let uses = self.region_edge_uses();
        let count =
            |label: Label, u: u32, v: u32| uses.get(&(label, edge_key(u, v))).copied().unwrap_or(0);
        let mut seen = HashSet::<(Label, u64), BuildHasherDefault<WordHasher>>::default();
        let mut open = 0;
        let mut example = None;
        for (label, u, v) in self.region_edges() {
            if count(label, u, v) > count(label, v, u) && seen.insert((label, edge_key(u, v))) {
                open += 1;
                example.get_or_insert_with(|| self.bad_edge(u, v, EdgeProblem::Open));
            }
        }
        match example {
            None => Ok(()),
            Some(example) => Err(WatertightError {
                open,
                repeated: 0,
                opposite_repeated: 0,
                example,
            }),
        }
    }

    /// [`SurfaceMesh::check_watertight`] for every material region: each
    /// directed edge of a region's boundary is used once, and its opposite
    /// once.
    ///
    /// # Errors
    /// As [`SurfaceMesh::check_watertight`], counting per region.
    pub fn check_regions_watertight(&self) -> Result<(), WatertightError> {
        let uses = self.region_edge_uses();
        let count =
            |label: Label, u: u32, v: u32| uses.get(&(label, edge_key(u, v))).copied().unwrap_or(0);
        let (mut open, mut repeated, mut opposite_repeated) = (0, 0, 0);
        let mut example = None;
        let mut seen_repeated = HashSet::<(Label, u64), BuildHasherDefault<WordHasher>>::default();
        for (label, u, v) in self.region_edges() {
            let (here, opposite) = (count(label, u, v), count(label, v, u));
            let problem = if here > 1 {
                if !seen_repeated.insert((label, edge_key(u, v))) {
                    continue;
                }
                repeated += 1;
                EdgeProblem::Repeated
            } else if opposite == 0 {
                open += 1;
                EdgeProblem::Open
            } else if opposite > 1 {
                opposite_repeated += 1;
                EdgeProblem::OppositeRepeated
            } else {
                continue;
            };
            example.get_or_insert_with(|| self.bad_edge(u, v, problem));
        }
        match example {
            None => Ok(()),
            Some(example) => Err(WatertightError {
                open,
                repeated,
                opposite_repeated,
                example,
            }),
        }
    }

    fn bad_edge(&self, from: u32, to: u32, problem: EdgeProblem) -> BadEdge {
        BadEdge {
            from,
            to,
            from_position: self.position(from),
            to_position: self.position(to),
            problem,
        }
    }
}
