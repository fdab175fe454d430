//! Debris across chunk borders: a piece a carve cuts loose that reaches
//! over one or more chunk borders falls as one body.
//!
//! Each chunk's carve job detaches, on its own, the pieces that lie within
//! the chunk ([`super::chunk_debris`] anchors the chunk's four sides, so a
//! job never detaches what may rest on a neighbour). Solid that touches a
//! side is left for this pass, which sees all live chunks of the world
//! together ([`chisel_bsp::octree::detach_across_chunks`]):
//!
//! 1. Every carve a chunk's job applies leaves the leaves it changed as
//!    *seeds* in the chunk's runtime ([`crate::terrain::upload::finish_jobs`]).
//! 2. [`detach_across_borders`] runs between collecting finished jobs and
//!    starting new ones. When a live chunk has seeds and the world has no
//!    search, it *starts* one: it takes the seeds out of the chunks and
//!    hands the octrees of all live chunks (cheap persistent clones), their
//!    anchors and the seeds to the async compute pool, noting each chunk's
//!    entity and state hash. The search joins the chunks: cells connect
//!    across a shared side where their faces there overlap with positive
//!    area, exactly, and the chunks' own anchors hold (the bottom and the
//!    base's floor). A side towards a chunk that is not live anchors, so
//!    nothing falls that leans on solid the world cannot see. Each piece
//!    no anchor holds, over two chunks across a side or four around a
//!    corner, is found as one and taken out of the clones exactly. The
//!    frame only clones and hands over: a search that explores a large
//!    piece (milliseconds, `debris_across_chunk_borders` in the terrain
//!    bench) runs beside the frames.
//! 3. A later frame finds the search done and *applies* it when it still
//!    holds (the rules below): each chunk that lost a part swaps in its
//!    octree with the part taken out, updates its state hash, and queues a
//!    job at the head of its queue that rebuilds the changed cells; the
//!    chunk of the piece's first part also builds the piece there, as one
//!    [`TerrainDebris`] (one body and collider of all parts, a mesh per
//!    part and material) that it spawns and reports ([`DebrisDetached`])
//!    when its cells are shown. Both name that chunk's terrain entity.
//!    Then, when chunks have new seeds, the next search starts.
//!
//! Rules across chunks:
//! - **One search per world.** Seeds that come while a search runs wait
//!   in their chunks for the next one. A world with seeds waiting is not
//!   settled ([`TerrainWorld::is_settled`]): a search is still to come.
//! - **Carves beside the seeds first.** While a chunk with seeds, or a
//!   neighbour of one across a side, has a job running or a carve or undo
//!   waiting, its seeds wait: a carve that reaches several chunks
//!   finishes in each at its own frame, and a search over the half-done
//!   carve would have to run again (`debris_across_chunk_borders`: one
//!   search per block instead of two). The other chunks' seeds are
//!   searched without them, so that carves elsewhere in the world never
//!   hold a piece back (`debris_latency_across_borders`: with a crater
//!   carved every frame in chunks far away, a block fell 4–6 frames after
//!   its cut, median of each run, instead of 54–204, largest 1014).
//!   Seeds beside a chunk that streaming wants and has not made live yet
//!   (building, or waiting for its build to start) wait for it too: its
//!   side would anchor a piece leaning on it, and the seeds, searched,
//!   would be gone before the chunk is in.
//! - **Stale results.** A search depends on the chunks it takes solid from
//!   and on their neighbours across a side (whose solid could hold the
//!   piece, or whose absence anchors it); on every chunk when it failed.
//!   When one of them left or its state hash changed since the search
//!   started (a carve or undo landed there), the result is dropped, its
//!   seeds go back to their chunks (a chunk streamed out took its own
//!   into its stored bytes) and a new search starts in the same
//!   frame, over the chunks as they are now: it finds what a single pass
//!   over that state finds. [`WorldStats::debris_searches_dropped`]
//!   counts them.
//! - **Busy chunks.** A chunk whose job is running would overwrite a
//!   detach when its job finishes, and a carve or undo waiting in its
//!   queue was asked for before the detach is applied. When a piece has a
//!   part in such a chunk, the result waits (frames go on) until the
//!   chunk is idle: it is then applied if the chunk's state is still the
//!   one searched, or dropped and searched again when the job changed it.
//!   A chunk carved without pause keeps the detach waiting.
//! - **Priority on the pool.** Bevy's async compute pool runs its tasks
//!   in the order they came, on one thread on a machine with up to seven
//!   cores, and a streaming world keeps up to
//!   [`StreamSettings::max_building`](super::StreamSettings::max_building)
//!   chunk builds there. The search, each chunk's job that takes a
//!   result's pieces out and builds them, and the chunks' carve and undo
//!   jobs go before every chunk build and coarse chunk build of the world
//!   that has not started: such a build, coming to run while one of them
//!   waits, steps back behind it (builds already running finish; other
//!   tasks keep their place). A build steps back for at most eight of them
//!   spawned after it came to run, so chunks keep streaming in. With a
//!   second focus streaming a chunk in every four frames, a block cut
//!   loose fell 6–7 frames after its cut (median of each of five runs)
//!   against 6–14 (median 9.5 over eight runs) without the rule, 4 in an
//!   idle world (`debris_latency_across_borders`, one pool thread, 60
//!   frames per second, a shared machine); the carve jobs that come
//!   before the search no longer wait behind the builds either.
//! - **Limits.** [`TerrainWorld::with_debris_limits`] bounds what one
//!   search takes out across borders, all pieces in all chunks together.
//!   The carves that cut them loose are already applied, each in its own
//!   chunk (a chunk's job refuses a carve over the chunk's own
//!   [`DebrisConfig`](crate::terrain::DebrisConfig) limits as a single
//!   terrain does). Over the world's limits the search takes out nothing:
//!   the pieces stay in place, held, and a warning is logged; a later
//!   carve next to them looks again. The limits also bound how long a
//!   search runs only through the kernel's early stop; the frames never
//!   wait for it.
//! - **Undo.** The removal joins the chunk's last undo step: undoing that
//!   carve brings the chunk's part back, as undo does for debris within a
//!   terrain; a chunk's own undo leaves the other chunks' parts out. The
//!   world also notes the detach in its last world carve's step
//!   ([`super::undo`]), so one [`super::WorldUndo`] brings every part
//!   back, in every chunk.
//! - **Streaming and files.** A chunk that lost a part counts as edited
//!   even with no carve of its own: it is kept while streamed out and
//!   saved with the world. A chunk's seeds are part of its file
//!   ([`crate::terrain::file`]): a save writes those still in the chunk
//!   and those the world's search took out of it and has not applied,
//!   so a save need not wait for a fall
//!   on its way, and a world loaded from the files searches from them
//!   and lets the piece fall ([`super::store`]). A chunk streamed out
//!   keeps its seeds in its stored bytes the same way, those still in it
//!   and those the world's search took out of it and has not applied,
//!   and searches from them when it streams back in (once its side
//!   neighbours that streaming wants are live too): a chunk that streams
//!   out while a search that depends on it runs makes the search stale,
//!   the search gives the seeds of the chunks still live back to them,
//!   and the piece cut loose falls when the chunk is back. So no seed is
//!   lost to streaming; an unedited chunk with seeds (a
//!   [`super::WorldUndo`] back to its base gives seeds back) has no
//!   stored bytes, and streams out only once they are searched. A
//!   [`super::WorldUndo`] gives seeds back to chunks that are not live
//!   too: into a stored chunk's bytes, or into a chunk built later
//!   ([`super::undo`], "Debris and searches"). A
//!   search that fails (over the world's limits) drops its seeds, as
//!   the limits say; a chunk despawned by the game loses them with its
//!   state.
//! - **Determinism.** The chunks' octrees, the seeds and the kernel's
//!   search are exact, and a result is applied only to the state it was
//!   found in, so the same carves give the same pieces and the same
//!   chunks, bit for bit, however long searches take. The state a search
//!   saw is known by each chunk's entity and 64-bit state hash
//!   ([`chisel_bsp::octree::StateHash`]). Journals record carves only:
//!   replaying one chunk's journal alone gives its state before any detach
//!   across borders.
//!
//! - **Networked worlds.** The pass depends on which chunks are live, so
//!   in a networked world only the server runs it, with three rules more
//!   (a search looks past sides towards chunks that are not live, and the
//!   server builds those where only such sides hold what it found, then
//!   searches again; the chunks with seeds, those a search saw and those
//!   it wants built are kept whatever the foci; every chunk a result
//!   depends on idle with no carve waiting before it is applied), and
//!   records each result it applies, which the server numbers in the
//!   world's order. A client drops its own seeds and carries out each
//!   ordered detach at its place: the same search over the chunks it
//!   names from the seeds it names ([`super::debris_order`]). A world
//!   that becomes networked drops the search its own pass runs, giving
//!   the seeds back to their chunks for the server's pass.
//!
//! Cost on the frame (`debris_across_chunk_borders` in the terrain bench:
//! 1 cm grid, 20.48 m chunks, the four chunks around a corner live):
//! starting a search clones the live chunks' octrees and sorts the seeds;
//! applying one swaps octrees and updates the state hashes of the changed
//! cells. Blocks of ground 6, 12 and 20 m wide cut loose around the corner
//! (74, 194 and 427 cells) cost their largest frame 0.07–0.17 ms so,
//! against 8.5–13.5 ms (2.6–9.4 ms of CPU) searched in the frame; a crater
//! on a border, whose search stops at the first anchored cell, 0.014 ms
//! against 0.35 ms. Nothing but the limits bounds a search: at the default
//! (none) it explores the whole piece, here 3–16 ms of pool time per
//! block, beside the frames.
//!
//! [`TerrainDebris`]: crate::terrain::TerrainDebris
//! [`DebrisDetached`]: crate::terrain::DebrisDetached
//! [`WorldStats::debris_searches_dropped`]: super::WorldStats::debris_searches_dropped

use std::collections::{BTreeMap, BTreeSet};

use bevy::prelude::*;
use bevy::tasks::Task;
use bevy::tasks::futures::check_ready;
use chisel_bsp::octree::{
    CellKey, ChunkOctree, ChunkedDetached, ChunkedPiece, CubeSide, DebrisLimits, Octree,
    detach_across_chunks_with_open_sides,
};

use super::debris_order::{self, AppliedDetach, DebrisRole};
use super::history::DetachedChunk;
use super::{ChunkCoord, TerrainWorld};
use crate::terrain::component::Terrain;
use crate::terrain::jobs::Job;

/// A search for debris across chunk borders, on the async compute pool
/// or finished and waiting to be applied (at most one per world).
pub(crate) struct DebrisSearch {
    /// The running search; `None` once its result is in `searched`.
    task: Option<Task<Searched>>,
    /// Its result, while it waits for the chunks it touches to be idle.
    searched: Option<Searched>,
    /// The chunks it joined, by its chunk index, as it saw them.
    seen: Vec<SeenChunk>,
    /// The seeds taken out of each chunk for it, given back when it is
    /// dropped.
    seeds: Vec<(Entity, Vec<CellKey>)>,
    /// The seeds it searched from, by its chunk index, sorted.
    near: Vec<(usize, CellKey)>,
    /// The detach of a networked world's order it carries out (a
    /// follower's search), by its place in the order.
    ordered: Option<u64>,
}

impl DebrisSearch {
    /// The chunks it joined.
    pub(super) fn chunks(&self) -> impl Iterator<Item = ChunkCoord> + '_ {
        self.seen.iter().map(|c| c.coord)
    }

    /// The indices (into [`DebrisSearch::chunks`]) of the chunks it
    /// searched from, each once.
    pub(super) fn seeded(&self) -> impl Iterator<Item = usize> + '_ {
        let mut last = None;
        self.near.iter().filter_map(move |&(i, _)| {
            let new = last != Some(i);
            last = Some(i);
            new.then_some(i)
        })
    }

    /// The seeds it took out of the chunk of terrain `entity`, pending
    /// until it is applied (or given back when it is dropped): a save
    /// writes them with the chunk ([`super::store`]).
    pub(super) fn seeds_taken(&self, entity: Entity) -> &[CellKey] {
        (self.seeds.iter())
            .find(|(e, _)| *e == entity)
            .map_or(&[], |(_, seeds)| seeds.as_slice())
    }

    /// Whether it carries out a detach of a networked world's order (a
    /// follower's search).
    pub(super) fn is_ordered(&self) -> bool {
        self.ordered.is_some()
    }

    /// What it found, once it is done and did not fail.
    pub(super) fn detached(&self) -> Option<&ChunkedDetached> {
        self.searched
            .as_ref()
            .and_then(|s| s.detached.as_ref().ok())
    }

    /// Whether the search still runs.
    fn running(&mut self) -> bool {
        if let Some(task) = self.task.as_mut() {
            match check_ready(task) {
                Some(searched) => {
                    self.task = None;
                    self.searched = Some(searched);
                }
                None => return true,
            }
        }
        false
    }
}

/// A chunk as a search saw it.
pub(super) struct SeenChunk {
    pub(super) coord: ChunkCoord,
    pub(super) entity: Entity,
    /// Its state hash then.
    pub(super) hash: u64,
}

/// What a search found: the pieces and each chunk's octree with them taken
/// out (by the search's chunk index), or why nothing is taken out.
struct Searched {
    detached: Result<ChunkedDetached, chisel_bsp::Error>,
    octrees: Vec<Octree>,
}

/// What to do with a finished search.
enum Verdict {
    /// A chunk it depends on changed or left: search again.
    Stale,
    /// A chunk it takes solid from has a job running or a carve or undo
    /// waiting: look again next frame.
    Wait,
    /// Every chunk it depends on is as it saw it: take the pieces out.
    Apply,
}

/// Collects the world's debris search when it is done and applies it (or
/// drops it when it is stale), then starts a search when a live chunk has
/// seeds and none runs. The search itself runs on the async compute pool.
/// In a networked world (`DebrisRole`) the server's searches are
/// recorded to be ordered, and a follower searches only for the detaches
/// the server ordered ([`super::debris_order`]). The world and the chunks
/// a detach takes solid out of are marked changed in the frame it is
/// applied; searching marks nothing.
pub fn detach_across_borders(
    mut worlds: Query<&mut TerrainWorld>,
    mut terrains: Query<&mut Terrain>,
) {
    for mut world_mut in &mut worlds {
        // Searching is the plugin's bookkeeping: the world and its chunks
        // are marked changed only when a detach takes solid out.
        let world = world_mut.bypass_change_detection();
        let mut detached = false;
        let follow = world.debris_role == DebrisRole::Follow;
        if !world.debris_across_borders || follow {
            world.debris_seeded = false;
            if !follow {
                world.debris_search = None;
                world.debris_keep.clear();
                world.debris_wanted.clear();
            }
            for (_, entity) in world.live_chunks() {
                if let Ok(mut terrain) = terrains.get_mut(entity)
                    && !terrain.runtime.border_seeds.is_empty()
                {
                    (terrain.bypass_change_detection().runtime.border_seeds).clear();
                }
            }
            if !follow {
                continue;
            }
        }
        if world.debris_role != DebrisRole::Local {
            debris_order::keep_chunks(world, &terrains);
        }
        if let Some(search) = world.debris_search.as_mut() {
            if search.running() {
                continue;
            }
            let _span = bevy::log::info_span!("chisel::world::detach_across_borders").entered();
            match verdict(world, &terrains) {
                Verdict::Wait => continue,
                Verdict::Stale => {
                    world.stats.debris_searches_dropped += 1;
                    if let Some(search) = world.debris_search.take() {
                        give_back_seeds(search, &mut terrains);
                    }
                }
                Verdict::Apply => {
                    let Some(search) = world.debris_search.take() else {
                        continue;
                    };
                    let wanted = debris_order::chunks_across_open_sides(world, &search);
                    if wanted.is_empty() {
                        world.debris_wanted.clear();
                        detached = apply_search(world, &mut terrains, search);
                    } else {
                        // A server's search stopped where a chunk it did
                        // not load could go on: build it, search again.
                        world.debris_wanted.extend(wanted);
                        give_back_seeds(search, &mut terrains);
                    }
                }
            }
        }
        if follow {
            debris_order::start_ordered(world, &terrains);
        } else {
            start_search(world, &mut terrains);
        }
        if world.debris_role != DebrisRole::Local {
            // Kept from the next frame's streaming on: the chunks a search
            // started now sees, and those a dropped result wants built.
            debris_order::keep_chunks(world, &terrains);
        }
        if detached {
            world_mut.set_changed();
        }
    }
}

/// Drops the world's search, putting the seeds it took back into their
/// chunks (a world that becomes networked: its role changes).
#[cfg(feature = "net")]
pub(crate) fn drop_search(world: &mut TerrainWorld, terrains: &mut Query<&mut Terrain>) {
    if let Some(search) = world.debris_search.take() {
        give_back_seeds(search, terrains);
    }
}

/// Puts a dropped search's seeds back into their chunks.
fn give_back_seeds(search: DebrisSearch, terrains: &mut Query<&mut Terrain>) {
    for (entity, seeds) in search.seeds {
        if let Ok(mut terrain) = terrains.get_mut(entity) {
            (terrain.bypass_change_detection().runtime.border_seeds).extend(seeds);
        }
    }
}

/// Applies a search that holds, and records it in a networked world;
/// returns whether it took solid out of a chunk.
fn apply_search(
    world: &mut TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    search: DebrisSearch,
) -> bool {
    let seen: Vec<ChunkCoord> = search.seen.iter().map(|c| c.coord).collect();
    if let Some(seq) = search.ordered {
        // A follower: every chunk of the order reports, changed or not.
        world.detach_ordered = None;
        let changed = apply(world, terrains, search);
        let hashes = (seen.iter().enumerate())
            .map(|(i, &c)| (c, changed.get(&i).copied()))
            .collect();
        world.detaches_applied.push(AppliedDetach {
            seq: Some(seq),
            chunks: seen,
            seeds: Vec::new(),
            hashes,
        });
        return !changed.is_empty();
    }
    if world.debris_role != DebrisRole::Serve {
        return !apply(world, terrains, search).is_empty();
    }
    let Some(Searched {
        detached: Ok(detached),
        ..
    }) = &search.searched
    else {
        return !apply(world, terrains, search).is_empty();
    };
    if detached.pieces.is_empty() {
        return false;
    }
    let (_, depends) = touched_and_depends(&search);
    let record = debris_order::record(detached, &search.near, &seen, &depends);
    let record = match record {
        Ok(record) => record,
        Err(why) => {
            warn!("terrain world: no debris detached across chunk borders: {why}");
            return false;
        }
    };
    let changed = apply(world, terrains, search);
    let hashes = (depends.iter())
        .map(|&j| (seen[j], changed.get(&j).copied()))
        .collect();
    world
        .detaches_applied
        .push(AppliedDetach { hashes, ..record });
    !changed.is_empty()
}

/// Whether the world's finished search still holds, by the rules of the
/// module docs.
fn verdict(world: &TerrainWorld, terrains: &Query<&mut Terrain>) -> Verdict {
    let Some(search) = world
        .debris_search
        .as_ref()
        .filter(|s| s.searched.is_some())
    else {
        return Verdict::Stale;
    };
    let seen = &search.seen;
    let (touched, depends) = touched_and_depends(search);
    let unchanged = depends.iter().all(|&j| {
        let chunk = &seen[j];
        world.chunk_entity(chunk.coord) == Some(chunk.entity)
            && terrains
                .get(chunk.entity)
                .is_ok_and(|t| t.hash.value() == chunk.hash)
    });
    if !unchanged {
        return Verdict::Stale;
    }
    // In a networked world every chunk it depends on must also hold every
    // carve ordered before it (none waiting): see `debris_order`.
    let ordered = world.debris_role != DebrisRole::Local;
    let waits = if ordered { &depends } else { &touched };
    let busy = waits.iter().any(|&i| {
        terrains.get(seen[i].entity).is_ok_and(busy)
            || (ordered && world.pending.contains_key(&seen[i].coord))
    });
    if busy { Verdict::Wait } else { Verdict::Apply }
}

/// The chunks a finished search takes solid from, and those it depends
/// on: these and their neighbours across a side (all chunks when it
/// failed, or when it carries out an ordered detach), by its chunk index.
fn touched_and_depends(search: &DebrisSearch) -> (Vec<usize>, Vec<usize>) {
    let seen = &search.seen;
    let all = || (0..seen.len()).collect();
    match search.searched.as_ref().map(|s| &s.detached) {
        Some(Ok(detached)) => {
            let touched: Vec<usize> = (detached.changes.iter().enumerate())
                .filter(|(_, c)| !(c.changed.is_empty() && c.removed.is_empty()))
                .map(|(i, _)| i)
                .collect();
            if search.ordered.is_some() {
                return (touched, all());
            }
            let near: BTreeSet<ChunkCoord> = touched.iter().map(|&i| seen[i].coord).collect();
            let depends = (0..seen.len())
                .filter(|&j| {
                    let c = seen[j].coord;
                    near.contains(&c) || side_neighbours(c).any(|n| near.contains(&n))
                })
                .collect();
            (touched, depends)
        }
        _ => (Vec::new(), all()),
    }
}

/// The four chunks across a side of `coord`.
pub(super) fn side_neighbours(coord: ChunkCoord) -> impl Iterator<Item = ChunkCoord> {
    [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .map(|(dx, dz)| ChunkCoord {
            x: coord.x + dx,
            z: coord.z + dz,
        })
        .into_iter()
}

/// Whether a chunk has a job running, or a carve, undo or redo waiting: its
/// octree is about to change.
pub(super) fn busy(terrain: &Terrain) -> bool {
    terrain.runtime.task.is_some()
        || (terrain.runtime.queue.iter()).any(|job| {
            matches!(
                job,
                Job::Carve { .. }
                    | Job::Undo { .. }
                    | Job::Redo { .. }
                    | Job::HoldForWorldUndo { .. }
            )
        })
}

/// Takes the pieces of a search that holds out of their chunks and queues
/// their rebuild and spawn; returns the chunks changed (by the search's
/// chunk index) with their new state hashes.
fn apply(
    world: &mut TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    search: DebrisSearch,
) -> BTreeMap<usize, u64> {
    let mut changed = BTreeMap::new();
    let Some(Searched { detached, octrees }) = search.searched else {
        return changed;
    };
    let detached = match detached {
        Ok(detached) => detached,
        Err(error) => {
            warn!("terrain world: no debris detached across chunk borders: {error}");
            return changed;
        }
    };
    world.stats.detached_across += detached.pieces.len() as u64;
    // Each piece is built and spawned by the chunk of its first part.
    let mut spawned_by: BTreeMap<usize, Vec<ChunkedPiece>> = BTreeMap::new();
    for piece in detached.pieces {
        if let Some(first) = piece.parts.first() {
            spawned_by.entry(first.chunk).or_default().push(piece);
        }
    }
    let mut undo_chunks = Vec::new();
    for (i, (octree, changes)) in octrees.into_iter().zip(detached.changes).enumerate() {
        let pieces = spawned_by.remove(&i).unwrap_or_default();
        if changes.changed.is_empty() && changes.removed.is_empty() && pieces.is_empty() {
            continue;
        }
        let Ok(mut terrain) = terrains.get_mut(search.seen[i].entity) else {
            continue;
        };
        let terrain = &mut *terrain;
        let (hash_before, was) = (terrain.hash.value(), terrain.detached_across);
        let before = std::mem::replace(&mut terrain.octree, octree);
        terrain.hash.update(
            &terrain.octree,
            changes.changed.iter().chain(&changes.removed),
        );
        if let Some(step) = terrain.history.back_mut() {
            step.changes = step.changes.then(&changes);
        }
        // What was undone before cannot be redone over the detach.
        terrain.redo.clear();
        terrain.detached_across = true;
        let mut keys: Vec<CellKey> = changes.changed.into_iter().chain(changes.removed).collect();
        keys.sort_unstable();
        keys.dedup();
        let coord = search.seen[i].coord;
        let chunk = DetachedChunk::new(coord, terrain, before, hash_before, was, &keys);
        undo_chunks.push(chunk);
        terrain
            .runtime
            .queue
            .push_front(Job::Detached { keys, pieces });
        changed.insert(i, terrain.hash.value());
    }
    let coord_of = |e: Entity| search.seen.iter().find(|c| c.entity == e).map(|c| c.coord);
    let seeds = (search.seeds.into_iter())
        .filter_map(|(e, keys)| Some((coord_of(e)?, keys)))
        .collect();
    super::history::note_detach(world, undo_chunks, seeds);
    changed
}

/// Starts a search over every live chunk when one of them has seeds and
/// the world has no search: the chunks' octrees (cheap persistent
/// clones), anchors and seeds go to the async compute pool.
fn start_search(world: &mut TerrainWorld, terrains: &mut Query<&mut Terrain>) {
    if world.debris_search.is_some() {
        return;
    }
    let live: Vec<(ChunkCoord, Entity)> = world.live_chunks().collect();
    let seeded: BTreeSet<ChunkCoord> = (live.iter())
        .filter(|&&(_, e)| {
            terrains
                .get(e)
                .is_ok_and(|t| !t.runtime.border_seeds.is_empty())
        })
        .map(|&(coord, _)| coord)
        .collect();
    // Seeds that wait (for a chunk beside them, or one a search wants
    // built) keep the world from being settled.
    world.debris_seeded = !seeded.is_empty();
    if seeded.is_empty() {
        return;
    }
    // A carve still running beside a chunk's seeds (one that reaches
    // several chunks finishes in each at its own frame) would change what
    // the search finds: those seeds wait for it rather than search twice.
    // The other chunks' seeds are searched now, so that carves elsewhere
    // in the world never hold them back.
    // So do seeds beside a chunk streaming in: its side would anchor
    // what leans on it until it is live, and the piece never fall.
    let busy_chunks: BTreeSet<ChunkCoord> = (live.iter())
        .filter(|&&(_, e)| terrains.get(e).is_ok_and(busy))
        .map(|&(coord, _)| coord)
        .chain(world.loading.iter().copied())
        .collect();
    let ready: BTreeSet<ChunkCoord> = (seeded.iter())
        .filter(|&&c| {
            !busy_chunks.contains(&c) && !side_neighbours(c).any(|n| busy_chunks.contains(&n))
        })
        .copied()
        .collect();
    // A server whose last search stopped on a side towards a chunk it did
    // not load searches again once that chunk is built.
    if ready.is_empty() || !debris_order::wanted_built(world) {
        return;
    }
    let _span = bevy::log::info_span!("chisel::world::detach_across_borders").entered();
    let (mut chunks, mut seen, mut seeds) = (Vec::new(), Vec::new(), Vec::new());
    let mut near: Vec<(usize, CellKey)> = Vec::new();
    for (coord, entity) in live {
        let Ok(mut terrain) = terrains.get_mut(entity) else {
            continue;
        };
        // Taking the seeds is bookkeeping, not a change of the chunk.
        let terrain = terrain.bypass_change_detection();
        let taken = if ready.contains(&coord) {
            std::mem::take(&mut terrain.runtime.border_seeds)
        } else {
            Vec::new()
        };
        // A chunk without debris detection is left out: it anchors what
        // touches it, as a chunk not loaded does.
        let Some(config) = &terrain.debris else {
            continue;
        };
        let i = chunks.len();
        let mut keys = taken.clone();
        keys.sort_unstable();
        keys.dedup();
        near.extend(keys.into_iter().map(|key| (i, key)));
        chunks.push(ChunkOctree {
            octree: terrain.octree.clone(),
            anchors: config.anchors.clone(),
        });
        seen.push(SeenChunk {
            coord,
            entity,
            hash: terrain.hash.value(),
        });
        if !taken.is_empty() {
            seeds.push((entity, taken));
        }
    }
    world.debris_seeded = seeded.len() > ready.len();
    if near.is_empty() {
        return;
    }
    let limits = world.debris_limits;
    launch(world, chunks, seen, seeds, near, limits, None);
}

/// Hands a search over `chunks` (as `seen`) from `near` to the async
/// compute pool as the world's search.
pub(super) fn launch(
    world: &mut TerrainWorld,
    mut chunks: Vec<ChunkOctree>,
    seen: Vec<SeenChunk>,
    seeds: Vec<(Entity, Vec<CellKey>)>,
    near: Vec<(usize, CellKey)>,
    limits: DebrisLimits,
    ordered: Option<u64>,
) {
    let searched_from = near.clone();
    // A server looks past the sides towards chunks it did not load, to
    // build them when only those hold what it found (`debris_order`).
    let open: &[CubeSide] = if world.debris_role == DebrisRole::Serve && ordered.is_none() {
        &CubeSide::HORIZONTAL
    } else {
        &[]
    };
    let task = world.pool_order.spawn_first(async move {
        let _span = bevy::log::info_span!("chisel::world::debris_search").entered();
        let detached = detach_across_chunks_with_open_sides(&mut chunks, &near, limits, open);
        Searched {
            detached,
            octrees: chunks.into_iter().map(|c| c.octree).collect(),
        }
    });
    world.stats.debris_searches += 1;
    world.debris_search = Some(DebrisSearch {
        task: Some(task),
        searched: None,
        seen,
        seeds,
        near: searched_from,
        ordered,
    });
}
