//! The exact convex hull of integer points.
//!
//! The points, sorted and without duplicates, are added one by one to a
//! triangulated hull (`incremental`); then coplanar neighbouring
//! triangles are merged into convex polygons, vertices in the middle of a
//! straight side are dropped (`polygons`), and the result becomes a
//! strictly convex polyhedron of a [`ConvexArena`] ([`convex_hull`]) or a
//! tool ([`crate::octree::Tool::convex_hull`], from `with_hull_polygons`
//! without an arena). The working memory is kept per thread between hulls.

mod incremental;
mod polygons;
#[cfg(test)]
mod reference;

use incremental::Incremental;
pub(crate) use polygons::HullPolygons;
use polygons::Merge;

use crate::Error;
use crate::convex::{ConvexArena, PolyId};
use crate::exact::orient::{cross, orient, sub};
use crate::exact::{IntPoint, Point4};
use crate::pool::{PerThread, Pool};

/// The most distinct points of one convex hull. The incremental hull takes
/// time of about points × faces, and an edit with a tool of `F` faces about
/// `F²` (each cell it crosses is tested against every face): a hull of
/// 4,500 points on a sphere (9,000 faces) carves a block in about 20 s on
/// one core, with memory linear in the faces (the octree splits a cell
/// crossed by many faces before merging the tool into it).
pub const MAX_HULL_POINTS: usize = 8192;

/// Adds the convex hull of `points` to `arena` as a strictly convex
/// polyhedron and returns it. Duplicate and interior points are ignored.
///
/// Faces are the groups of coplanar hull triangles in the order of their
/// first triangle; each face's corners run from its smallest point (in the
/// sorted order), and vertices are numbered in order of first appearance.
///
/// # Errors
/// [`Error::DegenerateHull`] when the points span no volume,
/// [`Error::TooManyHullPoints`] for more than [`MAX_HULL_POINTS`]
/// distinct points.
pub fn convex_hull(arena: &mut ConvexArena, points: &[IntPoint]) -> Result<PolyId, Error> {
    with_hull_polygons(points, |hull| add_polygons(arena, hull))
}

/// The convex hull of `points` as polygons, given to `use_hull` (the same
/// faces, order and planes as [`convex_hull`] adds to an arena).
///
/// # Errors
/// As [`convex_hull`].
pub(crate) fn with_hull_polygons<R>(
    points: &[IntPoint],
    use_hull: impl FnOnce(&HullPolygons) -> R,
) -> Result<R, Error> {
    thread_local! {
        static SCRATCH: Pool<Box<Scratch>> = const { Pool::new(1) };
    }
    let mut scratch = SCRATCH.take().unwrap_or_default();
    let result = scratch.hull(points).map(|()| use_hull(&scratch.polygons));
    if scratch.pts.capacity() <= KEEP_SCRATCH_POINTS {
        SCRATCH.keep(scratch);
    }
    result
}

/// The largest hull (in distinct points) whose working memory a thread
/// keeps for the next one: about 90 bytes a triangle made, some 8 made a
/// point, so up to about 0.7 MiB; a larger hull frees its own.
const KEEP_SCRATCH_POINTS: usize = 1024;

/// The working memory of one hull.
#[derive(Default)]
struct Scratch {
    /// The points, sorted, without duplicates.
    pts: Vec<[i64; 3]>,
    incremental: Incremental,
    merge: Merge,
    polygons: HullPolygons,
}

impl Scratch {
    /// The hull of `points` into `self.polygons`.
    fn hull(&mut self, points: &[IntPoint]) -> Result<(), Error> {
        let pts = &mut self.pts;
        pts.clear();
        pts.extend(points.iter().map(|p| p.coords()));
        pts.sort_unstable();
        pts.dedup();
        if pts.len() > MAX_HULL_POINTS {
            return Err(Error::TooManyHullPoints {
                points: pts.len(),
                limit: MAX_HULL_POINTS,
            });
        }
        let (first, corners) = first_tetrahedron(pts)?;
        self.incremental.build(pts, first, corners);
        self.merge
            .polygons(pts, &self.incremental, &mut self.polygons);
        Ok(())
    }
}

/// An initial tetrahedron of the sorted, distinct points `pts`: `a, b` the
/// first two, `c` the first off line `ab`, `d` the first off plane `abc`;
/// its faces counter-clockwise from outside, and its corners.
fn first_tetrahedron(pts: &[[i64; 3]]) -> Result<([[usize; 3]; 4], [usize; 4]), Error> {
    if pts.len() < 4 {
        return Err(Error::DegenerateHull {
            reason: "fewer than four distinct points",
        });
    }
    let (a, b) = (0, 1);
    let c = (2..pts.len())
        .find(|&i| cross(sub(pts[b], pts[a]), sub(pts[i], pts[a])) != [0; 3])
        .ok_or(Error::DegenerateHull {
            reason: "collinear",
        })?;
    let d = (2..pts.len())
        .find(|&i| orient(pts[a], pts[b], pts[c], pts[i]) != 0)
        .ok_or(Error::DegenerateHull { reason: "coplanar" })?;
    let faces = if orient(pts[a], pts[b], pts[c], pts[d]) < 0 {
        [[a, b, c], [a, d, b], [b, d, c], [c, d, a]]
    } else {
        [[a, c, b], [a, b, d], [b, c, d], [c, a, d]]
    };
    Ok((faces, [a, b, c, d]))
}

/// Adds the polyhedron of `hull` to `arena`: the sides' opposites come
/// from the faces across them.
fn add_polygons(arena: &mut ConvexArena, hull: &HullPolygons) -> PolyId {
    let points: Vec<Point4> = hull
        .vertices
        .iter()
        .map(|&p| Point4::from(IntPoint::from_array(p).expect("input points are in budget")))
        .collect();
    let mut twins = Vec::with_capacity(hull.corners.len());
    for f in 0..hull.face_count() {
        let (start, face) = (hull.starts[f], hull.face(f));
        for (k, &g) in (start..).zip(&hull.across[start as usize..hull.starts[f + 1] as usize]) {
            // The side `from → to` of `f` runs `to → from` on `g`.
            let to = face[(k - start + 1) as usize % face.len()];
            let j = hull
                .face(g as usize)
                .iter()
                .position(|&c| c == to)
                .expect("neighbouring faces share the side");
            twins.push(hull.starts[g as usize] + j as u32);
        }
    }
    arena.add_polyhedron_linked(&points, &hull.planes, &hull.starts, &hull.corners, &twins)
}
