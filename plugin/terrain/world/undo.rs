//! Undo across a world: [`WorldUndo`] takes back the world's last
//! [`WorldCarve`](super::WorldCarve) in every chunk it changed, with the
//! parts of the pieces it cut loose across chunk borders, exactly.
//!
//! ## What the world records
//!
//! Each chunk keeps its own undo steps ([`Terrain::undo_depth`]); the world
//! keeps one *world step* per routed world carve, up to
//! [`TerrainWorld::with_max_undo`] of them (the terrains' default,
//! [`DEFAULT_MAX_UNDO`](crate::terrain::component::DEFAULT_MAX_UNDO); the chunks keep as many steps each). A world step
//! names, per chunk:
//!
//! - the chunks the carve was routed to, and for each, once its job
//!   applied it, the chunk's state hash and journal length right after
//!   (the chunk's own undo step of that carve holds the octree before it);
//!   a chunk that refused the carve has nothing to undo;
//! - the chunks a detach across chunk borders ([`super::debris`]) took a
//!   part from after the carve: for a chunk whose own last step is this
//!   carve's, the removal joins that step (as the debris rules say) and the
//!   recorded state moves on with it; for any other chunk — one the carve
//!   did not reach, or one it reached only through an older carve — the
//!   world keeps the chunk's octree before the detach (a cheap persistent
//!   clone), the cells it changed and the state after;
//! - the seeds that the detaches it owns searched from, per chunk.
//!
//! A detach belongs to the latest world step whose carve has landed in a
//! chunk the detach takes solid from or searched from: a piece only falls
//! where a carve cut into it or next to it.
//!
//! The steps live in memory only: [`TerrainWorld::save`] writes each
//! chunk's own history, and a world loaded with
//! [`TerrainWorld::load_edits`] starts with no world step (its chunks
//! still undo their own carves with [`UndoCarve`](crate::terrain::UndoCarve)).
//!
//! ## Undo
//!
//! A [`WorldUndo`] takes the last world step not yet claimed by an earlier
//! [`WorldUndo`]. It is carried out once every chunk of that step holds
//! every request made before it: a hold is put in each chunk's job queue
//! (behind the carves already there; a chunk that is streamed out is
//! built or restored from its stored bytes for it, and a chunk that holds
//! an undo is not streamed out), and world carves asked for meanwhile wait
//! in the world and are routed after it, so the same sequence of carves
//! and undos always gives the same chunks, bit for bit, however long the
//! jobs take. When every chunk has reached its hold, in one frame:
//!
//! 1. every chunk is checked: its state hash and journal length must be
//!    those recorded (nothing else changed it since), and a chunk the carve
//!    reached must still have an undo step;
//! 2. if one fails, nothing changes: [`WorldUndoRejected`] names the chunk
//!    and why ([`WorldUndoRefusal`]), a warning is logged, and the
//!    [`WorldUndo`]s asked after it are refused too (they would undo an
//!    older carve before this one);
//! 3. otherwise each chunk the carve reached undoes its own last step
//!    ([`Terrain::undo_now`]), each chunk a detach took from without its
//!    own step gets its octree before the detach back, their state hashes
//!    follow, the changed cells are rebuilt by a job at the head of each
//!    queue, and [`WorldUndone`] lists the chunks. The chunks' own redo
//!    steps are forgotten; the world keeps what it undid for a
//!    [`WorldRedo`] ([`super::redo`]), which waits in the same line as
//!    the undos.
//!
//! So when nothing else happened in between, every chunk's octree and
//! state hash are again those before the carve. What counts as something
//! else: a later per-chunk [`Carve`](crate::terrain::Carve),
//! [`GridCarve`](crate::terrain::GridCarve) or
//! [`UndoCarve`](crate::terrain::UndoCarve) to one of its chunks (live,
//! or streamed out since, unedited again), or a detach that belongs to a
//! later carve (refused: [`WorldUndoRefusal::ChunkChanged`]);
//! a chunk whose undo history was cut by the depth limit or
//! [`Terrain::clear_undo`] ([`WorldUndoRefusal::HistoryTrimmed`]); a chunk
//! whose build failed ([`WorldUndoRefusal::ChunkLost`]). A chunk streamed
//! out and back in is no change: its file bytes hold its octree, journal
//! and undo history exactly, so the undo restores it like a carve would.
//!
//! ## Debris and searches
//!
//! Bodies already spawned stay, as after a single terrain's undo: the
//! solid comes back in the chunks and the body falls on. A search for
//! debris across borders that runs while the undo lands is made stale by
//! the changed state hashes and runs again over the chunks as they are
//! then ([`super::debris`]). The seeds the step's detaches searched from
//! go back to their chunks: a piece cut loose by an earlier carve that
//! fell only after this one (its search waited for this carve) is searched
//! for again, and falls again, as it would have before this carve. A
//! chunk the step did not change may have streamed out meanwhile: an
//! edited one gets the seeds in its stored bytes (only their seeds and
//! checksum are written anew), which a save writes as they are and which
//! it searches from when it streams back in; one being built, or
//! unedited and not live, gets them when its build is collected (an
//! unedited chunk has no file: a save does not hold these). So the piece
//! falls once the chunk is back, as if it had stayed.
//!
//! ## Networked worlds
//!
//! A networked world (feature `net`) orders carves and detaches on its
//! server and every peer replays them; a local undo would put a client or
//! the server out of that order, so a networked world records no steps and
//! refuses [`WorldUndo`] with [`WorldUndoRefusal::Networked`].

use bevy::prelude::*;

use super::debris_order::DebrisRole;
use super::history::{CarveState, Waiting, WorldOp};
use super::redo::{
    RedoChunk, UndoneStep, WorldRedo, WorldRedoRefusal, WorldRedoRejected, WorldRedone,
};
use super::{Chunk, ChunkCoord, TerrainWorld};
use crate::terrain::component::Terrain;
use crate::terrain::jobs::Job;

/// Undo a world's last [`WorldCarve`](super::WorldCarve) in every chunk it
/// changed, with the parts of the pieces it cut loose across chunk
/// borders ([module docs](self)). Answered by [`WorldUndone`] or
/// [`WorldUndoRejected`].
#[derive(Message, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorldUndo {
    /// The world entity.
    pub world: Entity,
}

/// A [`WorldUndo`] was carried out: every chunk it changed has its octree
/// and state hash of before the carve; their meshes follow one job later.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldUndone {
    /// The world entity.
    pub world: Entity,
    /// The request id the undone carve's chunk carves had
    /// ([`CarveApplied::request`](crate::terrain::CarveApplied)).
    pub request: u64,
    /// The chunks changed back, in coordinate order.
    pub chunks: Vec<ChunkCoord>,
}

/// A [`WorldUndo`] was refused; no chunk changed.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldUndoRejected {
    /// The world entity.
    pub world: Entity,
    /// Why.
    pub reason: WorldUndoRefusal,
}

/// Why a [`WorldUndo`] was refused.
#[derive(Reflect, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WorldUndoRefusal {
    /// The entity has no [`TerrainWorld`].
    #[error("the entity has no TerrainWorld")]
    NoSuchWorld,
    /// No world carve is left to undo (none was made, all were undone, or
    /// the older ones were dropped by the depth limit).
    #[error("there is no world carve left to undo")]
    NothingToUndo,
    /// The world is networked (feature `net`): its server orders every
    /// change, and a local undo would desynchronise it.
    #[error("a networked world does not undo")]
    Networked,
    /// Something other than the carve changed this chunk since: a later
    /// carve or undo of its own, or a detach of a later carve.
    #[error("chunk ({}, {}) changed since the carve", coord.x, coord.z)]
    ChunkChanged {
        /// The chunk.
        coord: ChunkCoord,
    },
    /// This chunk no longer holds the carve's undo step: its history was
    /// cut by the depth limit or cleared.
    #[error("chunk ({}, {}) no longer holds the carve's undo step", coord.x, coord.z)]
    HistoryTrimmed {
        /// The chunk.
        coord: ChunkCoord,
    },
    /// This chunk cannot be built: its build failed.
    #[error("chunk ({}, {}) cannot be built", coord.x, coord.z)]
    ChunkLost {
        /// The chunk.
        coord: ChunkCoord,
    },
    /// An earlier [`WorldUndo`] or [`WorldRedo`] of the same world was
    /// refused; this one would undo another carve than the one asked for.
    #[error("an earlier undo or redo of this world was refused")]
    EarlierUndoRefused,
}

/// The messages [`undo_world_carves`] writes.
#[derive(bevy::ecs::system::SystemParam)]
pub struct WorldUndoAnswers<'w> {
    undone: MessageWriter<'w, WorldUndone>,
    undo_rejected: MessageWriter<'w, WorldUndoRejected>,
    redone: MessageWriter<'w, WorldRedone>,
    redo_rejected: MessageWriter<'w, WorldRedoRejected>,
}

impl WorldUndoAnswers<'_> {
    /// Refuses a request of kind `op` for `reason` (a [`WorldUndoRefusal`],
    /// told as the matching [`WorldRedoRefusal`] for a redo).
    fn refuse(&mut self, world: Entity, op: WorldOp, reason: WorldUndoRefusal) {
        match op {
            WorldOp::Undo => {
                self.undo_rejected
                    .write(WorldUndoRejected { world, reason });
            }
            WorldOp::Redo => {
                let reason = WorldRedoRefusal::from_undo(reason);
                self.redo_rejected
                    .write(WorldRedoRejected { world, reason });
            }
        }
    }
}

/// Reads [`WorldUndo`]s and then [`WorldRedo`]s, notes what the chunks'
/// jobs applied, holds the chunks of waiting undos and redos and carries
/// out each whose chunks all reached its hold ([module docs](self),
/// [`super::redo`]); routes the world carves held meanwhile once none
/// waits.
pub fn undo_world_carves(
    mut undos: MessageReader<WorldUndo>,
    mut redos: MessageReader<WorldRedo>,
    mut worlds: Query<(Entity, &mut TerrainWorld)>,
    mut terrains: Query<&mut Terrain>,
    mut answers: WorldUndoAnswers,
) {
    for (_, mut world) in &mut worlds {
        // What the chunks' jobs applied, noted: bookkeeping.
        let world = world.bypass_change_detection();
        let local = world.debris_role == DebrisRole::Local;
        let live: Vec<(ChunkCoord, Entity)> = world.live_chunks().collect();
        for (coord, entity) in live {
            if let Ok(mut terrain) = terrains.get_mut(entity) {
                let terrain = terrain.bypass_change_detection();
                // Every world notes them for its saves; a local one for
                // its undo steps too.
                terrain.runtime.records_landed = true;
                let landed = std::mem::take(&mut terrain.runtime.landed);
                world.routed.land(coord, &landed);
                if local && !landed.is_empty() {
                    world.history.land(coord, landed);
                }
            }
        }
    }
    let requests = (undos.read().map(|u| (u.world, WorldOp::Undo)))
        .chain(redos.read().map(|r| (r.world, WorldOp::Redo)));
    for (entity, op) in requests {
        let Ok((_, mut world)) = worlds.get_mut(entity) else {
            answers.refuse(entity, op, WorldUndoRefusal::NoSuchWorld);
            continue;
        };
        if world.debris_role != DebrisRole::Local {
            answers.refuse(entity, op, WorldUndoRefusal::Networked);
            continue;
        }
        // A claimed request marks the world changed; a refused one does not.
        if !world.bypass_change_detection().history.claim(op) {
            answers.refuse(entity, op, WorldUndoRefusal::NothingToUndo);
        }
    }
    for (world_entity, mut world_mut) in &mut worlds {
        // Waiting is bookkeeping: the world is marked changed when a
        // request is carried out or refused, or the carves it held are
        // routed.
        let world = world_mut.bypass_change_detection();
        let mut changed = false;
        while let Some(op) = world.history.waiting.front().map(|w| w.op) {
            let outcome = advance(world, &mut terrains);
            changed |= !matches!(outcome, Progress::Waiting);
            match outcome {
                Progress::Waiting => break,
                Progress::Done(request, chunks) if op == WorldOp::Undo => {
                    let world = world_entity;
                    answers.undone.write(WorldUndone {
                        world,
                        request,
                        chunks,
                    });
                }
                Progress::Done(request, chunks) => {
                    let world = world_entity;
                    answers.redone.write(WorldRedone {
                        world,
                        request,
                        chunks,
                    });
                }
                Progress::Refused(reason) => {
                    let what = if op == WorldOp::Undo { "undo" } else { "redo" };
                    warn!("terrain world: {what} refused: {reason}");
                    answers.refuse(world_entity, op, reason);
                    for later in std::mem::take(&mut world.history.waiting) {
                        release_holds(world, &mut terrains, &later);
                        let reason = WorldUndoRefusal::EarlierUndoRefused;
                        answers.refuse(world_entity, later.op, reason);
                    }
                }
            }
        }
        let held = world.history.take_held();
        if !held.is_empty() {
            for (tool, edit, coords) in held {
                let request = world.next_request;
                world.route(&tool, edit, request, &coords);
            }
            changed = true;
        }
        if changed {
            world_mut.set_changed();
        }
    }
}

/// What became of the first waiting request.
pub(super) enum Progress {
    Waiting,
    /// Carried out: the step's request id and the chunks changed.
    Done(u64, Vec<ChunkCoord>),
    Refused(WorldUndoRefusal),
}

/// Holds the chunks of every waiting request that are live, and carries
/// out the first when all its chunks reached its hold.
fn advance(world: &mut TerrainWorld, terrains: &mut Query<&mut Terrain>) -> Progress {
    // Later requests hold their live chunks now too, so that requests made
    // after them wait behind them; a chunk that cannot come back refuses
    // a request when it is the first.
    for i in 0..world.history.waiting.len() {
        let held = hold_chunks(world, terrains, i);
        if let (0, Err(reason)) = (i, held) {
            return refuse_first(world, terrains, reason);
        }
    }
    let Some(first) = world.history.waiting.front() else {
        return Progress::Waiting;
    };
    match first.op {
        WorldOp::Undo => undo_first(world, terrains),
        WorldOp::Redo => super::redo::redo_first(world, terrains),
    }
}

/// Whether the chunk of `terrain` has reached the hold `hold`, with no
/// job running.
pub(super) fn at_hold(terrain: &Terrain, hold: u64) -> bool {
    terrain.runtime.task.is_none()
        && matches!(
            terrain.runtime.queue.front(),
            Some(Job::HoldForWorldUndo { hold: h }) if *h == hold
        )
}

/// Carries out the first waiting request, an undo, once every chunk of
/// its step reached its hold.
fn undo_first(world: &mut TerrainWorld, terrains: &mut Query<&mut Terrain>) -> Progress {
    let Some((request, hold)) = (world.history.waiting.front()).map(|w| (w.request, w.hold)) else {
        return Progress::Waiting;
    };
    let Some(position) = (world.history.steps.iter()).rposition(|s| s.request == request) else {
        // Dropped by the depth limit while it waited.
        return refuse_first(world, terrains, WorldUndoRefusal::NothingToUndo);
    };
    let mut targets = Vec::new();
    let mut refusal = None;
    for (&coord, chunk) in &world.history.steps[position].chunks {
        if !chunk.needs_hold() {
            continue;
        }
        let Some(terrain) = (world.chunk_entity(coord)).and_then(|e| terrains.get(e).ok()) else {
            return Progress::Waiting;
        };
        if !at_hold(terrain, hold) {
            return Progress::Waiting;
        }
        // Every chunk holds every earlier request: check them all before
        // changing any.
        if chunk.carve == CarveState::Waiting && chunk.detach.is_none() {
            // Its carve never reached the chunk's jobs: nothing to undo.
            continue;
        }
        let same = terrain.hash.value() == chunk.after && terrain.journal.len() == chunk.journal;
        if !same {
            refusal.get_or_insert(WorldUndoRefusal::ChunkChanged { coord });
        } else if chunk.carve == CarveState::Landed && terrain.history.is_empty() {
            refusal.get_or_insert(WorldUndoRefusal::HistoryTrimmed { coord });
        }
        targets.push(coord);
    }
    if let Some(reason) = refusal {
        return refuse_first(world, terrains, reason);
    }
    let Some(step) = world.history.steps.remove(position) else {
        return Progress::Waiting;
    };
    // A chunk held while its carve waited, that then refused the carve,
    // has nothing to undo: its hold is taken out with the others.
    if let Some(undo) = world.history.waiting.pop_front() {
        release_holds(world, terrains, &undo);
    }
    let mut changed = Vec::new();
    let mut redo = Vec::new();
    for coord in targets {
        let Some(mut chunk_terrain) =
            (world.chunk_entity(coord)).and_then(|e| terrains.get_mut(e).ok())
        else {
            continue;
        };
        let Some(chunk) = step.chunks.get(&coord) else {
            continue;
        };
        let terrain = chunk_terrain.bypass_change_detection();
        // The chunk as the step left it, for the world's redo.
        let mut kept = RedoChunk::before_undo(terrain);
        let mut keys = Vec::new();
        let mut undone = false;
        if chunk.carve == CarveState::Landed {
            let entry = terrain.journal.last().cloned();
            let undo_step = terrain.history.back().cloned();
            match terrain.undo_now() {
                Ok(cells) => {
                    keys.extend(cells);
                    kept.took_step(entry, undo_step);
                    undone = true;
                }
                Err(error) => warn!("terrain world: chunk undo: {error}"),
            }
        }
        // The chunk's own redo steps go: the world redoes this undo.
        terrain.redo.clear();
        if let Some(before) = &chunk.detach {
            terrain.octree = before.octree.clone();
            terrain.hash.update(&terrain.octree, &before.keys);
            terrain.detached_across = before.detached_across;
            keys.extend(before.keys.iter().copied());
            undone = true;
        }
        keys.sort_unstable();
        keys.dedup();
        redo.push((coord, kept.after_undo(terrain, keys.clone())));
        terrain.runtime.queue.push_front(Job::Detached {
            keys,
            pieces: Vec::new(),
        });
        if undone {
            chunk_terrain.set_changed();
        }
        changed.push(coord);
    }
    // The seeds its detaches searched from go back to their chunks, live
    // or not.
    for (coord, seeds) in &step.seeds {
        world.give_seeds_back(*coord, seeds.clone(), terrains);
    }
    world.history.undone.push(UndoneStep::new(step, redo));
    Progress::Done(request, changed)
}

/// Drops the first waiting request, taking its holds out, refused for
/// `reason`.
pub(super) fn refuse_first(
    world: &mut TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    reason: WorldUndoRefusal,
) -> Progress {
    if let Some(first) = world.history.waiting.pop_front() {
        release_holds(world, terrains, &first);
    }
    Progress::Refused(reason)
}

/// Puts the hold of waiting request `index` in every chunk of its step
/// that is live with no world carve waiting for it; fails, holding none,
/// for a chunk that cannot come back.
fn hold_chunks(
    world: &mut TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    index: usize,
) -> Result<(), WorldUndoRefusal> {
    let waiting = &world.history.waiting[index];
    let (request, hold, op) = (waiting.request, waiting.hold, waiting.op);
    let Some(step) = world.history.step(request) else {
        return Ok(());
    };
    let held = &waiting.held;
    let chunks = (step.chunks.iter()).filter(|&(c, chunk)| chunk.needs_hold() && !held.contains(c));
    let mut live = Vec::new();
    // Every chunk is looked at before any is held: a refused request
    // takes out only the holds it noted (`release_holds`), so it notes
    // them all.
    for (&coord, _) in chunks {
        match world.chunks.get(&coord) {
            Some(Chunk::Live(entity)) if !world.pending.contains_key(&coord) => {
                live.push((coord, *entity));
            }
            Some(Chunk::Failed) => return Err(WorldUndoRefusal::ChunkLost { coord }),
            Some(_) => {}
            None if world.stored.contains_key(&coord) || world.pending.contains_key(&coord) => {}
            // Neither live nor stored: unedited, the source's again. An
            // undo finds its carve gone (its own undo took it back, as a
            // live chunk would answer); a redo may find the state its
            // undo left, and builds it to check.
            None if op == WorldOp::Redo => {}
            None => return Err(WorldUndoRefusal::ChunkChanged { coord }),
        }
    }
    for (coord, entity) in live {
        if let Ok(mut terrain) = terrains.get_mut(entity) {
            (terrain.bypass_change_detection().runtime.queue)
                .push_back(Job::HoldForWorldUndo { hold });
            world.history.waiting[index].held.insert(coord);
        }
    }
    Ok(())
}

/// Takes a request's holds out of its chunks' queues.
pub(super) fn release_holds(
    world: &TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    waiting: &Waiting,
) {
    for &coord in &waiting.held {
        let Some(entity) = world.chunk_entity(coord) else {
            continue;
        };
        if let Ok(mut terrain) = terrains.get_mut(entity) {
            (terrain.bypass_change_detection().runtime.queue).retain(
                |job| !matches!(job, Job::HoldForWorldUndo { hold } if *hold == waiting.hold),
            );
        }
    }
}
