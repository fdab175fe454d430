//! Debris colliders of few convex hulls.
//!
//! A debris piece arrives as an exact convex decomposition: its BSP cells.
//! A piece of a few cubic metres can have hundreds of them, most split
//! apart by planes that no longer bound anything, and a compound collider
//! of hundreds of hulls costs the physics engine for nothing. The cells are
//! therefore merged greedily into groups, each collided as the convex hull
//! of its cells' corners.
//!
//! Notation: a *group* is a set of the piece's cells that one hull stands
//! for; its *solid* volume is the exact volume of its cells, its *hull*
//! the convex hull of their corners (rounded to the grid, the exact hull
//! of `chisel_bsp::tools::convex_hull`); the *excess* of merging groups
//! `A` and `B` is `vol(hull(A ∪ B)) − solid(A) − solid(B)`, the empty space
//! the merged hull would add. Only groups whose boxes touch are merged.
//!
//! Two passes, each smallest first:
//! 1. *free* merges, whose excess is at most [`FREE_EXCESS`] of the two
//!    solids (cells that together are convex, up to rounding): the shape
//!    the collider gives does not change;
//! 2. while more than the allowed number of groups are left, the merge with
//!    the least excess: the collider grows where it matters least.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{DebrisCell, ExactVolume};
use chisel_bsp::tools::convex_hull;

/// Most convex hulls a debris body's collider gets by default
/// ([`super::TerrainSettings::max_debris_hulls`]).
pub const DEFAULT_MAX_DEBRIS_HULLS: usize = 16;

/// Excess, as a fraction of the solid volume, that a merge may add and
/// still count as free (it covers the rounding of corners to the grid).
pub const FREE_EXCESS: f64 = 0.01;

/// Cells of a group, the corners of its hull and its volumes.
#[derive(Clone, Debug)]
struct Group {
    /// The hull's corners in grid units, sorted, each once (all the
    /// cells' rounded corners when they span no volume).
    points: Vec<[i64; 3]>,
    /// The exact volume of its cells, in cubic grid units.
    solid: f64,
    /// The box of its points.
    lo: [i64; 3],
    hi: [i64; 3],
    /// Bumped by every merge, so that stale candidates are skipped.
    version: u32,
}

impl Group {
    fn touches(&self, other: &Group) -> bool {
        (0..3).all(|a| self.lo[a] <= other.hi[a] + 1 && other.lo[a] <= self.hi[a] + 1)
    }
}

/// The corners of each convex hull of a collider for these cells (in grid
/// units), at most `max_hulls` of them (at least one), merged as the
/// module docs say. Deterministic: the same cells give the same hulls.
#[must_use]
pub fn collider_hulls(cells: &[DebrisCell], max_hulls: usize) -> Vec<Vec<[f64; 3]>> {
    let max_hulls = max_hulls.max(1);
    let mut groups: Vec<Option<Group>> = cells
        .iter()
        .map(|cell| {
            let corners: Vec<[i64; 3]> = cell
                .vertices
                .iter()
                .map(|v| v.map(|c| c.round() as i64))
                .collect();
            Some(group_of(corners, cell.volume.to_f64()))
        })
        .collect();
    // Free merges by relative excess, then forced ones by absolute excess.
    let relative = |excess: f64, solid: f64| excess / solid.max(f64::MIN_POSITIVE);
    merge_while(&mut groups, relative, |_, key| key <= FREE_EXCESS);
    merge_while(&mut groups, |excess, _| excess, |live, _| live > max_hulls);
    groups
        .into_iter()
        .flatten()
        .map(|g| g.points.iter().map(|p| p.map(|c| c as f64)).collect())
        .collect()
}

/// The group of these corners and solid volume: its points are the
/// corners of their hull (all of them when they span no volume).
fn group_of(mut corners: Vec<[i64; 3]>, solid: f64) -> Group {
    corners.sort_unstable();
    corners.dedup();
    let points = hull_of(&corners).map_or(corners, |(_, hull)| hull);
    let lo = [0, 1, 2].map(|a| points.iter().map(|p| p[a]).min().unwrap_or(0));
    let hi = [0, 1, 2].map(|a| points.iter().map(|p| p[a]).max().unwrap_or(0));
    Group {
        points,
        solid,
        lo,
        hi,
        version: 0,
    }
}

/// The exact volume of the convex hull of `points` and its corners
/// (sorted), or `None` when they span no volume or lie off the grid.
fn hull_of(points: &[[i64; 3]]) -> Option<(f64, Vec<[i64; 3]>)> {
    let points: Vec<IntPoint> = points
        .iter()
        .map(|&[x, y, z]| IntPoint::new(x, y, z))
        .collect::<Result<_, _>>()
        .ok()?;
    let mut arena = ConvexArena::new();
    let poly = convex_hull(&mut arena, &points).ok()?;
    let volume = ExactVolume::of_polyhedron(&arena, poly).to_f64();
    let mut corners: Vec<[i64; 3]> = arena
        .vertices_of(poly)
        .into_iter()
        .map(|v| arena.position(v).map(|c| c.round() as i64))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    Some((volume, corners))
}

/// A merge candidate: the key it is ordered by, then the groups (by index
/// and version), smallest key first.
#[derive(Debug, PartialEq)]
struct Candidate {
    key: f64,
    a: usize,
    b: usize,
    versions: (u32, u32),
}

impl Eq for Candidate {}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> Ordering {
        self.key
            .total_cmp(&other.key)
            .then(self.a.cmp(&other.a))
            .then(self.b.cmp(&other.b))
    }
}

/// The candidate merging groups `a` and `b`, keyed by `key(excess, solid)`;
/// `None` when their union spans no volume.
fn candidate(
    groups: &[Option<Group>],
    a: usize,
    b: usize,
    key: &impl Fn(f64, f64) -> f64,
) -> Option<Candidate> {
    let (ga, gb) = (groups[a].as_ref()?, groups[b].as_ref()?);
    if !ga.touches(gb) {
        return None;
    }
    let mut union = ga.points.clone();
    union.extend_from_slice(&gb.points);
    union.sort_unstable();
    union.dedup();
    let (volume, _) = hull_of(&union)?;
    let solid = ga.solid + gb.solid;
    let excess = (volume - solid).max(0.0);
    Some(Candidate {
        key: key(excess, solid),
        a,
        b,
        versions: (ga.version, gb.version),
    })
}

/// Merges touching groups, the candidate with the smallest
/// `key(excess, solid)` first, while `go_on(live groups, key)` holds.
fn merge_while(
    groups: &mut [Option<Group>],
    key: impl Fn(f64, f64) -> f64,
    go_on: impl Fn(usize, f64) -> bool,
) {
    let mut live = groups.iter().flatten().count();
    let mut heap = BinaryHeap::new();
    for a in 0..groups.len() {
        for b in a + 1..groups.len() {
            if let Some(c) = candidate(groups, a, b, &key) {
                heap.push(Reverse(c));
            }
        }
    }
    while let Some(Reverse(c)) = heap.pop() {
        let current = match (&groups[c.a], &groups[c.b]) {
            (Some(ga), Some(gb)) => (ga.version, gb.version) == c.versions,
            _ => false,
        };
        if !current {
            continue;
        }
        if !go_on(live, c.key) {
            break;
        }
        let gb = groups[c.b].take().expect("a current candidate's group");
        let ga = groups[c.a].take().expect("a current candidate's group");
        let mut points = ga.points;
        points.extend(gb.points);
        let mut merged = group_of(points, ga.solid + gb.solid);
        merged.version = ga.version.max(gb.version) + 1;
        groups[c.a] = Some(merged);
        live -= 1;
        for other in 0..groups.len() {
            if other != c.a {
                let (a, b) = (other.min(c.a), other.max(c.a));
                if let Some(next) = candidate(groups, a, b, &key) {
                    heap.push(Reverse(next));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use chisel_bsp::octree::{CellBox, DebrisConfig, Edit, Octree, OctreeConfig, Tool};

    use super::*;

    /// The cells of the piece cut loose when a block standing on a thin
    /// stem over the floor loses its stem: the block, split by a small
    /// octree budget into many cells, and carved by `holes`.
    fn block_cells(holes: &[CellBox]) -> Vec<DebrisCell> {
        let config = OctreeConfig {
            max_bsp_nodes: 8,
            max_depth: 7,
        };
        let cube = |min, max| CellBox { min, max };
        let stem = cube([400, 0, 400], [440, 300, 440]);
        let mut octree = Octree::from_box([0; 3], 10, stem, 1, config).expect("a valid box");
        let block = Tool::cuboid(cube([200, 300, 200], [700, 500, 700])).expect("a box");
        octree.apply(&block, Edit::Add(1)).expect("the block");
        for &hole in holes {
            let tool = Tool::cuboid(hole).expect("a box");
            octree.apply(&tool, Edit::Subtract).expect("a hole");
        }
        let cut = Tool::cuboid(cube([390, 100, 390], [450, 150, 450])).expect("a box");
        let carved = octree
            .apply_detaching(&cut, Edit::Subtract, &DebrisConfig::default())
            .expect("a carve");
        let piece = carved
            .detached
            .pieces
            .into_iter()
            .max_by_key(|p| p.cells.len())
            .expect("the block falls");
        piece.cells
    }

    fn hull_volume(points: &[[f64; 3]]) -> f64 {
        let corners: Vec<[i64; 3]> = points.iter().map(|p| p.map(|c| c as i64)).collect();
        hull_of(&corners).expect("a hull with volume").0
    }

    #[test]
    fn a_convex_piece_of_many_cells_is_one_hull_of_its_exact_volume() {
        // The block and the stem's top part: two boxes, so two hulls.
        let cells = block_cells(&[]);
        assert!(cells.len() > 8, "{} cells", cells.len());
        let solid: f64 = cells.iter().map(|c| c.volume.to_f64()).sum();
        let hulls = collider_hulls(&cells, 64);
        assert_eq!(hulls.len(), 2, "the block and the stem");
        let total: f64 = hulls.iter().map(|h| hull_volume(h)).sum();
        assert_eq!(total, solid, "free merges keep the exact shape");
    }

    #[test]
    fn a_non_convex_piece_keeps_its_holes_within_the_limit() {
        // A notch through the block: no single hull fits it.
        let notch = CellBox {
            min: [300, 350, 150],
            max: [600, 550, 750],
        };
        let cells = block_cells(&[notch]);
        let solid: f64 = cells.iter().map(|c| c.volume.to_f64()).sum();
        for max in [1, 3, 16] {
            let hulls = collider_hulls(&cells, max);
            assert!(
                !hulls.is_empty() && hulls.len() <= max,
                "{} > {max}",
                hulls.len()
            );
            let total: f64 = hulls.iter().map(|h| hull_volume(h)).sum();
            assert!(total >= solid * (1.0 - 1e-9), "hulls cover the piece");
            if max == 16 {
                // The two walls, the floor of the notch and the stem each
                // fit a hull of their own.
                assert!(total <= solid * (1.0 + FREE_EXCESS), "{total} vs {solid}");
                assert!(hulls.len() >= 4, "{} hulls", hulls.len());
            }
        }
        let one = collider_hulls(&cells, 1);
        assert!(
            hull_volume(&one[0]) > solid * 1.2,
            "one hull fills the notch"
        );
    }

    #[test]
    fn the_same_cells_give_the_same_hulls() {
        let cells = block_cells(&[]);
        assert_eq!(collider_hulls(&cells, 4), collider_hulls(&cells, 4));
    }
}
