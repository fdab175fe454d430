//! The states of a world a [`SaveWorld`](super::SaveWorld) may save
//! ([`super::store`]): whole ones, and for a busy world consistent ones
//! ("Saving a busy world"): the world carves routed to several chunks, and
//! whether the chunks hold each of them in all of those chunks or in none.
//!
//! A live chunk's [`Terrain`] fields are its state before its queued and
//! running jobs (a job's octree, journal and undo step are swapped in when
//! it is collected), and a chunk that is not live holds none of the carves
//! waiting for it. So a world carve is *in flight* in a chunk while it
//! waits for the chunk, is queued there or is in the chunk's running job,
//! and has *landed* there once the chunk's job applied or refused it. The
//! chunks hold a consistent state when no world carve has landed in some
//! of its chunks and is in flight in others. Detaches across chunk borders
//! and world undos change all their chunks in one frame, so they never
//! split; a carve of one chunk never does.

use std::collections::{BTreeMap, BTreeSet};

use bevy::prelude::*;

use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::super::jobs::Job;
use super::history::Landed;
use super::{Chunk, ChunkCoord, TerrainWorld};

/// The frames of its turn a [`SaveWorld`](super::SaveWorld) waits, by
/// default, for a whole state before it saves a consistent one
/// ([`TerrainWorld::with_save_settle_frames`]).
pub const DEFAULT_SAVE_SETTLE_FRAMES: u32 = 10;

/// The most frames, by default, a [`SaveWorld`](super::SaveWorld) waiting
/// for a consistent state holds back the world carves routed after it
/// began to ([`TerrainWorld::with_save_hold_frames`]).
pub const DEFAULT_SAVE_HOLD_FRAMES: u32 = 15;

/// The world carves routed to more than one chunk that may still be in
/// flight in one of them. A carve routed to one chunk never splits and is
/// not kept.
#[derive(Default)]
pub(crate) struct RoutedCarves {
    /// By request id.
    carves: BTreeMap<u64, RoutedCarve>,
}

/// One world carve's chunks.
struct RoutedCarve {
    /// The chunks it was routed to.
    chunks: BTreeSet<ChunkCoord>,
    /// Those whose jobs have not reported it yet.
    open: BTreeSet<ChunkCoord>,
}

impl RoutedCarves {
    /// Notes a world carve routed to `coords` under `request`.
    pub(crate) fn route(&mut self, request: u64, coords: &[ChunkCoord]) {
        if coords.len() < 2 && !self.carves.contains_key(&request) {
            return;
        }
        let carve = self.carves.entry(request).or_insert_with(|| RoutedCarve {
            chunks: BTreeSet::new(),
            open: BTreeSet::new(),
        });
        carve.chunks.extend(coords);
        carve.open.extend(coords);
    }

    /// Notes the tracked carves chunk `coord`'s jobs applied or refused;
    /// forgets a carve once every chunk of it did.
    pub(crate) fn land(&mut self, coord: ChunkCoord, landed: &[Landed]) {
        for (request, _) in landed {
            if let Some(carve) = self.carves.get_mut(request) {
                carve.open.remove(&coord);
                if carve.open.is_empty() {
                    self.carves.remove(request);
                }
            }
        }
    }

    /// Forgets every carve (a networked world's reset).
    #[cfg(feature = "net")]
    pub(crate) fn clear(&mut self) {
        self.carves.clear();
    }
}

/// What is in flight in the chunks now.
struct InFlight {
    /// By chunk, the request ids of the tracked carves waiting for it,
    /// queued in it or in its running job.
    tracked: BTreeMap<ChunkCoord, BTreeSet<u64>>,
    /// The carves without request id and the undos queued in the live
    /// chunks or in their running jobs.
    untracked: usize,
}

impl InFlight {
    fn holds(&self, coord: ChunkCoord, request: u64) -> bool {
        self.tracked
            .get(&coord)
            .is_some_and(|r| r.contains(&request))
    }

    /// Carves and undos in flight, a carve of several chunks once.
    fn count(&self) -> usize {
        let tracked: BTreeSet<u64> = self.tracked.values().flatten().copied().collect();
        tracked.len() + self.untracked
    }
}

impl TerrainWorld {
    /// A [`SaveWorld`](super::SaveWorld) that saw no whole state in `frames`
    /// frames of its turn saves the first consistent one instead: each
    /// chunk as it was before its carves in flight, every world carve in
    /// all of its chunks or in none ([`super::store`], "Saving a busy
    /// world"). [`DEFAULT_SAVE_SETTLE_FRAMES`] by default; 0 saves the
    /// first consistent state at once. A bound of
    /// [`TerrainWorld::with_max_save_wait`] below it leaves no frame for
    /// one: such a request waits for a whole state only.
    #[must_use]
    pub fn with_save_settle_frames(mut self, frames: u32) -> Self {
        self.saves.settle = frames;
        self
    }

    /// The frames a [`SaveWorld`](super::SaveWorld) waits for a whole
    /// state before it saves a consistent one
    /// ([`TerrainWorld::with_save_settle_frames`]).
    #[must_use]
    pub fn save_settle_frames(&self) -> u32 {
        self.saves.settle
    }

    /// A [`SaveWorld`](super::SaveWorld) that found no consistent state
    /// after its settle frames ([`TerrainWorld::with_save_settle_frames`])
    /// holds back the world carves routed after that frame for at most
    /// `frames` frames, until the chunks come to a consistent state: each
    /// chunk finishes the carves it has while the later ones wait queued
    /// in all of their chunks ([`super::store`], "Saving a busy world").
    /// Those carves show as many frames later. [`DEFAULT_SAVE_HOLD_FRAMES`]
    /// by default. With 0 no carve is ever held back for a save: the
    /// request takes a consistent state only when the chunks come to one
    /// by themselves (a frame in which no world carve has landed in some
    /// of its chunks and not in others), and gives up as any request
    /// after [`TerrainWorld::max_save_wait`] frames of its turn. Every
    /// value is valid; a request holds carves back only within its bound
    /// of [`TerrainWorld::max_save_wait`] frames.
    #[must_use]
    pub fn with_save_hold_frames(mut self, frames: u32) -> Self {
        self.saves.hold = frames;
        self
    }

    /// The most frames a [`SaveWorld`](super::SaveWorld) holds back later
    /// carves for a consistent state
    /// ([`TerrainWorld::with_save_hold_frames`]).
    #[must_use]
    pub fn save_hold_frames(&self) -> u32 {
        self.saves.hold
    }

    /// Whether a [`SaveWorld`](super::SaveWorld) waiting for a consistent
    /// state holds back the world carves routed after it began to, as of
    /// the last run of the save system
    /// ([`TerrainWorld::with_save_hold_frames`]).
    #[must_use]
    pub fn save_holds_carves(&self) -> bool {
        self.saves.barrier.is_some()
    }

    /// Whether this frame holds a whole state ([`super::store`]): no
    /// carve waits for a chunk, no undo waits for one, every live chunk
    /// readable here is settled, and no fall across chunk borders is on
    /// its way that the files cannot hold (seeds are saved with their
    /// chunks).
    ///
    /// # Errors
    /// [`TerrainError::WorldNotIdle`] naming a busy chunk.
    pub(super) fn check_whole(&self, terrains: &Query<Ref<Terrain>>) -> Result<(), TerrainError> {
        // A carve waiting for a chunk, or a chunk of a waiting undo.
        let waiting =
            (self.pending.keys().next().copied()).or_else(|| self.history.wanted().next());
        let busy = waiting.or_else(|| {
            self.live_chunks()
                .find(|&(_, entity)| terrains.get(entity).is_ok_and(|t| !content_settled(&t)))
                .map(|(coord, _)| coord)
        });
        let busy = busy.or_else(|| self.unsaved_fall(terrains));
        match busy {
            Some(coord) => Err(TerrainError::WorldNotIdle {
                chunk: [coord.x, coord.z],
            }),
            None => Ok(()),
        }
    }

    /// A fall across chunk borders on its way that no file would hold:
    /// seeds of a live chunk that is not edited (it has no file), or a
    /// detach a networked server ordered (its seeds are the server's).
    /// Returns a chunk of it.
    pub(super) fn unsaved_fall(&self, terrains: &Query<Ref<Terrain>>) -> Option<ChunkCoord> {
        let unsaved = self.live_chunks().find(|&(coord, entity)| {
            terrains.get(entity).is_ok_and(|t| {
                let seeded =
                    !t.runtime.border_seeds.is_empty() || !self.seeds_taken(entity).is_empty();
                seeded && !self.chunk_edited(coord, &t)
            })
        });
        let ordered = self.detach_ordered.is_some()
            || (self.debris_search.as_ref()).is_some_and(|s| s.is_ordered());
        // An order is the world's: it names any live chunk.
        let any = || {
            self.live_chunks()
                .next()
                .map_or(ChunkCoord { x: 0, z: 0 }, |c| c.0)
        };
        (unsaved.map(|(coord, _)| coord)).or_else(|| ordered.then(any))
    }

    /// Whether a chunk of this world holds back carve `request` (not
    /// started yet): a save waiting for a consistent state holds back the
    /// world carves routed after it began to wait
    /// ([`TerrainWorld::with_save_hold_frames`]).
    pub(crate) fn holds_back(&self, request: Option<u64>) -> bool {
        matches!((self.saves.barrier, request), (Some(last), Some(r)) if r > last)
    }

    /// A request that found no consistent state this frame: holds back
    /// the carves routed after now (in its first such frame) until a
    /// consistent state comes, for at most
    /// [`TerrainWorld::save_hold_frames`] frames (`held` counts them; none
    /// with 0); returns whether it holds them. Not while
    /// carves wait deferred for far chunks (a networked world's client):
    /// those land only when the chunks are built, holding back would not
    /// bring them.
    pub(super) fn hold_for_cut(&mut self, held: &mut u32) -> bool {
        let deferred = self.pending.keys().any(|c| self.deferred.contains(c));
        if *held >= self.saves.hold || deferred {
            return false;
        }
        if *held == 0 {
            self.saves.barrier = self.next_request.checked_sub(1);
        }
        *held += 1;
        true
    }

    /// The carves and undos in flight in the chunks (module docs).
    fn in_flight(&self, terrains: &Query<Ref<Terrain>>) -> InFlight {
        let mut tracked: BTreeMap<ChunkCoord, BTreeSet<u64>> = BTreeMap::new();
        let mut untracked = 0;
        for (&coord, carves) in &self.pending {
            (tracked.entry(coord).or_default()).extend(carves.iter().map(|c| c.2));
        }
        for (coord, entity) in self.live_chunks() {
            let Ok(terrain) = terrains.get(entity) else {
                continue;
            };
            let runtime = &terrain.runtime;
            let queued = runtime.queue.iter().filter_map(|job| match job {
                Job::Carve { request, .. } => Some(*request),
                Job::Undo { .. } | Job::Redo { .. } => Some(None),
                _ => None,
            });
            for request in queued.chain(runtime.running_carves.iter().copied()) {
                match request {
                    Some(request) => {
                        tracked.entry(coord).or_default().insert(request);
                    }
                    None => untracked += 1,
                }
            }
        }
        InFlight { tracked, untracked }
    }

    /// Whether the chunks hold a consistent state now (module docs), with
    /// no world undo waiting and no fall across chunk borders on its way
    /// that the files cannot hold; returns how many carves and undos in
    /// flight the state leaves out (a world carve once). Forgets the world
    /// carves no chunk has in flight.
    ///
    /// # Errors
    /// [`TerrainError::WorldNotIdle`] naming a chunk a world carve is in
    /// flight in while it landed in another, or a chunk of a waiting
    /// undo, or of a fall the files cannot hold.
    pub(super) fn check_consistent(
        &mut self,
        terrains: &Query<Ref<Terrain>>,
    ) -> Result<usize, TerrainError> {
        let not_idle = |coord: ChunkCoord| TerrainError::WorldNotIdle {
            chunk: [coord.x, coord.z],
        };
        if self.history.holds_carves() {
            let coord = self.history.wanted().next();
            return Err(not_idle(coord.unwrap_or(ChunkCoord { x: 0, z: 0 })));
        }
        if let Some(coord) = self.unsaved_fall(terrains) {
            return Err(not_idle(coord));
        }
        let flight = self.in_flight(terrains);
        // A chunk that failed to build holds nothing; one whose terrain
        // cannot be read here keeps its file as it is.
        let chunks = &self.chunks;
        let known = |coord: &ChunkCoord| match chunks.get(coord) {
            Some(Chunk::Failed) => false,
            Some(Chunk::Live(entity)) => terrains.contains(*entity),
            _ => true,
        };
        let carves = &mut self.routed.carves;
        carves.retain(|&request, carve| carve.chunks.iter().any(|&c| flight.holds(c, request)));
        for (&request, carve) in carves.iter() {
            let (mut landed, mut waiting) = (false, None);
            for &coord in carve.chunks.iter().filter(|c| known(c)) {
                if flight.holds(coord, request) {
                    waiting = Some(coord);
                } else {
                    landed = true;
                }
            }
            if let (true, Some(coord)) = (landed, waiting) {
                return Err(not_idle(coord));
            }
        }
        Ok(flight.count())
    }
}

/// Whether a live chunk's octree, journal and undo history are at rest:
/// nothing queued or running would change them (sealing again at a
/// neighbour's points does not). A finished job waiting to show its cells
/// and write its reports and debris (its upload) counts as at rest: it
/// swapped its octree, journal and undo step in when it was collected.
fn content_settled(terrain: &Terrain) -> bool {
    let runtime = &terrain.runtime;
    (runtime.queue.iter()).all(|job| matches!(job, crate::terrain::jobs::Job::Reseal { .. }))
        && (runtime.task.is_none() || runtime.resealing)
}
