//! Seams across chunk borders: every chunk's border edges are split at the
//! neighbouring chunks' wall points on its cube, so that the chunks' cell
//! meshes meet edge to edge with identical exact vertices (paper 1 §3.4,
//! carried across octrees by [`SeamedMesher::set_outside_points`]).
//!
//! Notation: a chunk's *border points* toward a neighbour are the wall
//! points of its kept cell meshes that lie on the side or the corner line
//! it shares with that neighbour (`BorderPoints`); a chunk's *outside
//! points* are the border points of its live neighbours toward it. Its
//! *border wedges* there are, at each vertex of its sealed cell meshes on
//! that side or line, the exact surface of its own cells around the
//! vertex ([`SeamedMesher::border_wedges_in`]); its *outside wedges* are
//! its live neighbours' border wedges toward it.
//!
//! Every job of a chunk hands back its border points and wedges as of
//! the meshes it built (`BorderPoints::of`, on the worker).
//! [`stitch_chunk_borders`] then gathers the outside points and wedges of
//! each neighbour of a chunk whose border changed and, where they differ
//! from those the neighbour was last given, queues a job that seals the
//! neighbour's cells again at the points and shades them again with the
//! wedges (only the cells whose seams or border vertices' surroundings
//! change are rebuilt; their colliders stay). A chunk that has just
//! streamed in takes its live neighbours' points and wedges before its
//! first build. Wall points come from the unsealed meshes, so one
//! exchange settles the points of a border: no chunk's border points
//! depend on its neighbours'.
//!
//! Normals ([`super::super::mesh`]): a vertex on a chunk's side is
//! smoothed over the merged wedges of every cell around it in every chunk
//! that has it, its own and the outside wedges
//! ([`SeamedMesher::set_outside_wedges`]): all chunks sharing the vertex
//! sum the same exact wedges in the same order and give it the same
//! normal bits, as the cells of one chunk do, and an incremental update
//! gives what a build from scratch gives. Border wedges come from the
//! chunk's own cells, never from its outside wedges; which vertices carry
//! them depends on its outside points, so a carve settles in at most two
//! exchanges (the carved chunk's points and wedges, then its neighbours'
//! wedges at those points). A chunk whose mesher keeps no shading
//! (`TerrainSettings::smooth_across_cells` off, flat shading, no render
//! meshes) hands back no wedges, and its cells are smoothed over its own
//! faces at its sides.
//!
//! A frame in which no chunk streamed in or out and no chunk's border
//! points changed costs one look at the live chunks, not a pass.
//!
//! A chunk that streams out leaves its points and wedges with its
//! neighbours until they are given new ones: splitting at a point where
//! no neighbour meets the edge any more only adds a vertex on a straight
//! edge, and the wedges are those the chunk has when it streams back. It
//! drops its own re-seal jobs, queued or running
//! (`Terrain::is_idle_but_for_seams`): they change no octree, journal or
//! undo step, and would hold it live while they wait on the pool.

use std::collections::BTreeMap;
use std::sync::Arc;

use bevy::prelude::*;
use chisel_bsp::exact::Point4;
use chisel_bsp::mesh::Wedge;
use chisel_bsp::octree::{CellBox, Octree, PointWedges, SeamedMesher};

use super::super::component::Terrain;
use super::super::jobs::Job;
use super::{ChunkCoord, TerrainWorld};

/// The eight neighbours of a chunk, as steps in x and z.
const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// A chunk's wall points on the sides of its cube, toward each neighbour
/// (in the order of `NEIGHBOURS`): on the shared side for the four across
/// a side, on the shared vertical corner line for the four across a
/// corner; and its border wedges there (none when its mesher keeps no
/// shading).
#[derive(Debug, Default)]
pub(crate) struct BorderPoints {
    toward: [Vec<Point4>; 8],
    wedges: [PointWedges; 8],
}

impl BorderPoints {
    /// The border points and wedges of the cells `mesher` keeps for
    /// `octree` (a chunk's octree, its cube one chunk of the world's
    /// grid).
    pub(crate) fn of(mesher: &SeamedMesher, octree: &Octree) -> Self {
        let cube = octree.root_box();
        let wedges = if mesher.keeps_shading() {
            NEIGHBOURS.map(|step| mesher.border_wedges_in(octree, &shared_with(&cube, step)))
        } else {
            Default::default()
        };
        Self {
            toward: NEIGHBOURS.map(|step| mesher.wall_points_in(octree, &shared_with(&cube, step))),
            wedges,
        }
    }

    /// The index of the neighbour `step` away in `NEIGHBOURS`.
    fn index(step: (i64, i64)) -> Option<usize> {
        NEIGHBOURS.iter().position(|&s| s == step)
    }

    /// The points toward the neighbour `step` away.
    fn toward(&self, step: (i64, i64)) -> &[Point4] {
        Self::index(step).map_or(&[][..], |i| self.toward[i].as_slice())
    }

    /// The border wedges toward the neighbour `step` away.
    fn wedges_toward(&self, step: (i64, i64)) -> &[(Point4, Vec<Wedge>)] {
        Self::index(step).map_or(&[][..], |i| self.wedges[i].as_slice())
    }
}

/// What a chunk is given of its neighbours: their border points and
/// border wedges toward it.
#[derive(Debug, Default)]
struct Outside {
    points: Vec<Point4>,
    wedges: PointWedges,
}

impl Outside {
    /// Whether both hold the same points and wedges in the same order.
    fn same_as(&self, other: &Self) -> bool {
        same_points(&self.points, &other.points)
            && self.wedges.len() == other.wedges.len()
            && self
                .wedges
                .iter()
                .zip(&other.wedges)
                .all(|((p, a), (q, b))| a == b && same_point(p, q))
    }
}

/// The part of `cube`'s boundary it shares with the cube `step` away in x
/// and z: a side, or a vertical line.
fn shared_with(cube: &CellBox, (dx, dz): (i64, i64)) -> CellBox {
    let mut region = *cube;
    for (axis, d) in [(0, dx), (2, dz)] {
        match d {
            -1 => region.max[axis] = cube.min[axis],
            1 => region.min[axis] = cube.max[axis],
            _ => {}
        }
    }
    region
}

/// What a world knows of its chunks' seams.
#[derive(Default)]
pub(crate) struct WorldSeams {
    /// Per live chunk, its terrain entity and the border points last seen.
    seen: BTreeMap<ChunkCoord, (Entity, Arc<BorderPoints>)>,
    /// Per live chunk, its terrain entity and the outside points and
    /// wedges it was last given.
    given: BTreeMap<ChunkCoord, (Entity, Outside)>,
    /// The live chunks and their terrain entities at the last pass, in
    /// coordinate order.
    live: Vec<(ChunkCoord, Entity)>,
    /// Passes over the seams so far: frames in which a chunk streamed in
    /// or out, a chunk's border points changed, or a chunk still waited
    /// for its first outside points. Other frames only look whether one
    /// of these happened.
    pub(crate) passes: u64,
}

impl WorldSeams {
    /// Live chunks given their neighbours' outside points.
    pub(crate) fn seamed(&self) -> usize {
        self.given.len()
    }

    /// Whether the seams have nothing to do: the same live chunks as at
    /// the last pass, every one of them given outside points, and no
    /// border points other than those seen.
    fn at_rest(&self, world: &TerrainWorld, terrains: &Query<&mut Terrain>) -> bool {
        world.live_chunks().eq(self.live.iter().copied())
            && self.given.len() == self.live.len()
            && self.live.iter().all(|(coord, entity)| {
                let border = terrains
                    .get(*entity)
                    .ok()
                    .and_then(|t| t.runtime.border.as_ref());
                border.is_none_or(|border| {
                    self.seen
                        .get(coord)
                        .is_some_and(|(_, seen)| Arc::ptr_eq(seen, border))
                })
            })
    }
}

/// Keeps the chunks' seams closed: gives chunks that just streamed in
/// their neighbours' border points before their first build, and queues a
/// re-seal of the live neighbours of every chunk whose border points
/// changed (see the module docs).
pub fn stitch_chunk_borders(
    mut worlds: Query<&mut TerrainWorld>,
    mut terrains: Query<&mut Terrain>,
) {
    let _span = bevy::log::info_span!("chisel::seams::stitch").entered();
    for mut world in &mut worlds {
        // Most frames: nothing streamed, nothing rebuilt.
        if world.seams.at_rest(&world, &terrains) {
            continue;
        }
        // Seams are the plugin's bookkeeping: neither the world nor its
        // chunks change content here.
        let world = world.bypass_change_detection();
        let live: BTreeMap<ChunkCoord, Entity> = world.live_chunks().collect();
        let seams = &mut world.seams;
        seams.passes += 1;
        seams.live = live.iter().map(|(&c, &e)| (c, e)).collect();
        seams.seen.retain(|c, (e, _)| live.get(c) == Some(e));
        seams.given.retain(|c, (e, _)| live.get(c) == Some(e));

        // Border points that changed since the last frame.
        let mut changed = Vec::new();
        for (&coord, &entity) in &live {
            let Ok(terrain) = terrains.get(entity) else {
                continue;
            };
            let Some(border) = &terrain.runtime.border else {
                continue;
            };
            let fresh = seams
                .seen
                .get(&coord)
                .is_none_or(|(_, seen)| !Arc::ptr_eq(seen, border));
            if fresh {
                seams.seen.insert(coord, (entity, border.clone()));
                changed.push(coord);
            }
        }

        // Chunks never given outside points, and the neighbours of
        // chunks whose border points changed.
        let mut targets: Vec<ChunkCoord> = live
            .keys()
            .filter(|c| !seams.given.contains_key(c))
            .copied()
            .collect();
        for coord in changed {
            targets.extend(NEIGHBOURS.iter().map(|&(dx, dz)| ChunkCoord {
                x: coord.x + dx,
                z: coord.z + dz,
            }));
        }
        targets.sort_unstable();
        targets.dedup();
        for coord in targets {
            let Some(&entity) = live.get(&coord) else {
                continue;
            };
            let outside = outside_of(&seams.seen, coord);
            let first = !seams.given.contains_key(&coord);
            if seams
                .given
                .get(&coord)
                .is_some_and(|(_, given)| given.same_as(&outside))
            {
                continue;
            }
            let Ok(mut terrain) = terrains.get_mut(entity) else {
                continue;
            };
            let runtime = &mut terrain.bypass_change_detection().runtime;
            runtime.publishes_border = true;
            if first && runtime.task.is_none() && runtime.needs_full_mesh {
                // Before the first build: it seals and shades with them.
                runtime.mesher.set_outside_points(outside.points.clone());
                runtime.mesher.set_outside_wedges(outside.wedges.clone());
            } else if let Some(Job::Reseal {
                outside: queued,
                wedges,
            }) = runtime
                .queue
                .iter_mut()
                .find(|job| matches!(job, Job::Reseal { .. }))
            {
                queued.clone_from(&outside.points);
                wedges.clone_from(&outside.wedges);
            } else {
                runtime.queue.push_back(Job::Reseal {
                    outside: outside.points.clone(),
                    wedges: outside.wedges.clone(),
                });
            }
            seams.given.insert(coord, (entity, outside));
        }
    }
}

/// The border points and wedges of the chunks around `coord` toward it.
fn outside_of(
    seen: &BTreeMap<ChunkCoord, (Entity, Arc<BorderPoints>)>,
    coord: ChunkCoord,
) -> Outside {
    let mut out = Outside::default();
    for (dx, dz) in NEIGHBOURS {
        let neighbour = ChunkCoord {
            x: coord.x + dx,
            z: coord.z + dz,
        };
        if let Some((_, border)) = seen.get(&neighbour) {
            out.points.extend_from_slice(border.toward((-dx, -dz)));
            out.wedges
                .extend_from_slice(border.wedges_toward((-dx, -dz)));
        }
    }
    out
}

/// Whether the lists hold the same points in the same order. Points with
/// the same `W` are the same exactly when their `X, Y, Z` are (`W > 0`),
/// which spares the cross-multiplied comparison for the points a chunk's
/// rebuilt cells share with the last ones (most of them).
fn same_points(a: &[Point4], b: &[Point4]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| same_point(p, q))
}

/// Whether `p` and `q` are the same point (see [`same_points`]).
fn same_point(p: &Point4, q: &Point4) -> bool {
    if p.w() == q.w() {
        p.xyz() == q.xyz()
    } else {
        p.same_position(q)
    }
}
