//! Undo across a world: [`WorldUndo`] takes back the world's last
//! [`WorldCarve`](super::WorldCarve) in every chunk it changed, with the
//! parts of the pieces it cut loose across chunk borders, exactly.
//!
//! ## What the world records
//!
//! Each chunk keeps its own undo steps ([`Terrain::undo_depth`]); the world
//! keeps one *world step* per routed world carve, up to
//! [`TerrainWorld::with_max_undo`] of them (the terrains' default,
//! [`DEFAULT_MAX_UNDO`]; the chunks keep as many steps each). A world step
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
//!    queue, and [`WorldUndone`] lists the chunks.
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

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, Edit, Octree};

use super::debris_order::DebrisRole;
use super::{Chunk, ChunkCoord, TerrainWorld};
use crate::terrain::component::{DEFAULT_MAX_UNDO, Terrain};
use crate::terrain::jobs::Job;
use crate::terrain::tool::GridTool;

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
    /// An earlier [`WorldUndo`] of the same world was refused; this one
    /// would undo an older carve before the newer one.
    #[error("an earlier undo of this world was refused")]
    EarlierUndoRefused,
}

/// The world's undo steps and the undos waiting to be carried out.
pub(crate) struct WorldHistory {
    /// Most steps kept (and undo steps kept per chunk).
    pub(crate) max: usize,
    steps: VecDeque<WorldStep>,
    /// Undos asked for and not yet carried out, oldest first.
    undos: VecDeque<WaitingUndo>,
    /// World carves asked for after a waiting undo, routed after it.
    held: Vec<(GridTool, Edit, Vec<ChunkCoord>)>,
}

impl Default for WorldHistory {
    fn default() -> Self {
        Self {
            max: DEFAULT_MAX_UNDO,
            steps: VecDeque::new(),
            undos: VecDeque::new(),
            held: Vec::new(),
        }
    }
}

/// One world carve's record.
struct WorldStep {
    /// The request id of its chunk carves.
    request: u64,
    chunks: BTreeMap<ChunkCoord, StepChunk>,
    /// Seeds its detaches searched from, given back on undo.
    seeds: BTreeMap<ChunkCoord, Vec<CellKey>>,
}

/// What a world step did to one chunk.
struct StepChunk {
    carve: CarveState,
    /// State hash and journal length of the chunk as the step left it.
    after: u64,
    journal: usize,
    /// The chunk before a detach of the step that did not join its own
    /// undo step.
    detach: Option<BeforeDetach>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum CarveState {
    /// Routed, not applied yet.
    Waiting,
    /// Applied: the chunk's undo step holds its octree before.
    Landed,
    /// Refused by the chunk, or not routed to it.
    None,
}

struct BeforeDetach {
    octree: Octree,
    keys: Vec<CellKey>,
    detached_across: bool,
}

/// A [`WorldUndo`] waiting for its chunks to hold every earlier request.
struct WaitingUndo {
    request: u64,
    /// Chunks whose queues hold it.
    held: BTreeSet<ChunkCoord>,
}

/// A tracked carve a chunk's job applied or refused: its request id and,
/// when applied, the chunk's state hash and journal length right after.
pub(crate) type Landed = (u64, Option<(u64, usize)>);

/// One chunk a detach across chunk borders changed, as the world's undo
/// needs it ([`note_detach`]).
pub(crate) struct DetachedChunk {
    coord: ChunkCoord,
    before: Octree,
    hash_before: u64,
    hash_after: u64,
    journal: usize,
    detached_across: bool,
    keys: Vec<CellKey>,
    landed: Vec<Landed>,
}

impl DetachedChunk {
    /// `terrain` (chunk `coord`) right after a detach swapped in its
    /// octree: `before` and `hash_before` are its octree and hash before,
    /// `detached_across` its flag before, `keys` the cells changed.
    pub(crate) fn new(
        coord: ChunkCoord,
        terrain: &mut Terrain,
        before: Octree,
        hash_before: u64,
        detached_across: bool,
        keys: &[CellKey],
    ) -> Self {
        Self {
            coord,
            before,
            hash_before,
            hash_after: terrain.hash.value(),
            journal: terrain.journal.len(),
            detached_across,
            keys: keys.to_vec(),
            landed: std::mem::take(&mut terrain.runtime.landed),
        }
    }
}

impl WorldHistory {
    /// World steps that can be undone now.
    pub(crate) fn depth(&self) -> usize {
        self.steps.len()
    }

    /// Forgets every step and waiting undo (a networked world's reset).
    #[cfg(feature = "net")]
    pub(crate) fn clear(&mut self) {
        self.steps.clear();
        self.undos.clear();
        self.held.clear();
    }

    /// Whether world carves wait for an undo ([`WorldHistory::hold`]).
    pub(crate) fn holds_carves(&self) -> bool {
        !self.undos.is_empty()
    }

    /// Keeps a world carve asked for while an undo waits.
    pub(crate) fn hold(&mut self, tool: GridTool, edit: Edit, coords: Vec<ChunkCoord>) {
        self.held.push((tool, edit, coords));
    }

    /// The chunks waiting undos need live.
    pub(crate) fn wanted(&self) -> impl Iterator<Item = ChunkCoord> + '_ {
        self.undos.iter().flat_map(|undo| {
            (self.steps.iter())
                .find(|s| s.request == undo.request)
                .into_iter()
                .flat_map(|s| s.chunks.iter())
                .filter(|(_, c)| c.needs_hold())
                .map(|(&coord, _)| coord)
        })
    }

    /// Records a world carve routed to `coords` under `request`.
    pub(crate) fn push_step(&mut self, request: u64, coords: &[ChunkCoord]) {
        if self.max == 0 {
            return;
        }
        let chunks = coords
            .iter()
            .map(|&coord| {
                let chunk = StepChunk {
                    carve: CarveState::Waiting,
                    after: 0,
                    journal: 0,
                    detach: None,
                };
                (coord, chunk)
            })
            .collect();
        self.steps.push_back(WorldStep {
            request,
            chunks,
            seeds: BTreeMap::new(),
        });
        while self.steps.len() > self.max {
            self.steps.pop_front();
        }
    }

    /// Notes what chunk `coord`'s jobs applied or refused.
    fn land(&mut self, coord: ChunkCoord, landed: Vec<Landed>) {
        for (request, outcome) in landed {
            let Some(step) = self.steps.iter_mut().rev().find(|s| s.request == request) else {
                continue;
            };
            let Some(chunk) = step.chunks.get_mut(&coord) else {
                continue;
            };
            match outcome {
                Some((hash, journal)) => {
                    chunk.carve = CarveState::Landed;
                    chunk.after = hash;
                    chunk.journal = journal;
                }
                None => chunk.carve = CarveState::None,
            }
        }
    }
}

impl StepChunk {
    /// Whether the undo has anything to do in this chunk (and so holds it).
    fn needs_hold(&self) -> bool {
        self.carve != CarveState::None || self.detach.is_some()
    }
}

/// Records a detach across chunk borders in the world step it belongs to
/// (the [module docs](self)): `chunks` are those it changed, `seeds` those
/// it searched from, by chunk.
pub(crate) fn note_detach(
    world: &mut TerrainWorld,
    chunks: Vec<DetachedChunk>,
    seeds: Vec<(ChunkCoord, Vec<CellKey>)>,
) {
    let history = &mut world.history;
    let mut chunks = chunks;
    for chunk in &mut chunks {
        world.routed.land(chunk.coord, &chunk.landed);
        history.land(chunk.coord, std::mem::take(&mut chunk.landed));
    }
    if world.debris_role != DebrisRole::Local {
        return;
    }
    let near: BTreeSet<ChunkCoord> = (chunks.iter().map(|c| c.coord))
        .chain(seeds.iter().map(|(c, _)| *c))
        .collect();
    let Some(step) = history.steps.iter_mut().rev().find(|s| {
        (s.chunks.iter()).any(|(c, chunk)| chunk.carve == CarveState::Landed && near.contains(c))
    }) else {
        return;
    };
    for chunk in chunks {
        let entry = step.chunks.entry(chunk.coord).or_insert(StepChunk {
            carve: CarveState::None,
            after: chunk.hash_before,
            journal: chunk.journal,
            detach: None,
        });
        if entry.carve == CarveState::Landed || entry.detach.is_some() {
            // Its own step of this carve holds it (the removal joined the
            // chunk's last step), or an earlier detach of this step kept
            // its state: move on with it unless something else changed
            // the chunk in between (the undo then refuses).
            if entry.after == chunk.hash_before && entry.journal == chunk.journal {
                entry.after = chunk.hash_after;
                if let Some(before) = &mut entry.detach {
                    before.keys.extend(chunk.keys);
                    before.keys.sort_unstable();
                    before.keys.dedup();
                }
            }
        } else {
            entry.after = chunk.hash_after;
            entry.journal = chunk.journal;
            entry.detach = Some(BeforeDetach {
                octree: chunk.before,
                keys: chunk.keys,
                detached_across: chunk.detached_across,
            });
        }
    }
    for (coord, keys) in seeds {
        step.seeds.entry(coord).or_default().extend(keys);
    }
}

/// Reads [`WorldUndo`]s, notes what the chunks' jobs applied, holds the
/// chunks of waiting undos and carries out each undo whose chunks all
/// reached its hold ([module docs](self)); routes the world carves held
/// meanwhile once no undo waits.
pub fn undo_world_carves(
    mut undos: MessageReader<WorldUndo>,
    mut worlds: Query<(Entity, &mut TerrainWorld)>,
    mut terrains: Query<&mut Terrain>,
    mut undone: MessageWriter<WorldUndone>,
    mut rejected: MessageWriter<WorldUndoRejected>,
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
    for undo in undos.read() {
        let Ok((_, mut world)) = worlds.get_mut(undo.world) else {
            refuse(&mut rejected, undo.world, WorldUndoRefusal::NoSuchWorld);
            continue;
        };
        if world.debris_role != DebrisRole::Local {
            refuse(&mut rejected, undo.world, WorldUndoRefusal::Networked);
            continue;
        }
        let claimed = world.history.undos.len();
        let Some(index) = world.history.steps.len().checked_sub(claimed + 1) else {
            refuse(&mut rejected, undo.world, WorldUndoRefusal::NothingToUndo);
            continue;
        };
        // A claimed undo marks the world changed; a refused one does not.
        let history = &mut world.history;
        let request = history.steps[index].request;
        history.undos.push_back(WaitingUndo {
            request,
            held: BTreeSet::new(),
        });
    }
    for (world_entity, mut world_mut) in &mut worlds {
        // Waiting is bookkeeping: the world is marked changed when an undo
        // is carried out or refused, or the carves it held are routed.
        let world = world_mut.bypass_change_detection();
        let mut changed = false;
        while !world.history.undos.is_empty() {
            let outcome = advance(world, &mut terrains);
            changed |= !matches!(outcome, Progress::Waiting);
            match outcome {
                Progress::Waiting => break,
                Progress::Undone(done) => {
                    undone.write(WorldUndone {
                        world: world_entity,
                        request: done.0,
                        chunks: done.1,
                    });
                }
                Progress::Refused(reason) => {
                    warn!("terrain world: undo refused: {reason}");
                    refuse(&mut rejected, world_entity, reason);
                    for undo in std::mem::take(&mut world.history.undos) {
                        release_holds(world, &mut terrains, &undo);
                        refuse(
                            &mut rejected,
                            world_entity,
                            WorldUndoRefusal::EarlierUndoRefused,
                        );
                    }
                }
            }
        }
        if world.history.undos.is_empty() && !world.history.held.is_empty() {
            for (tool, edit, coords) in std::mem::take(&mut world.history.held) {
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

fn refuse(
    rejected: &mut MessageWriter<WorldUndoRejected>,
    world: Entity,
    reason: WorldUndoRefusal,
) {
    rejected.write(WorldUndoRejected { world, reason });
}

enum Progress {
    Waiting,
    Undone((u64, Vec<ChunkCoord>)),
    Refused(WorldUndoRefusal),
}

/// Holds the chunks of every waiting undo that are live, and carries out
/// the first when all its chunks reached its hold.
fn advance(world: &mut TerrainWorld, terrains: &mut Query<&mut Terrain>) -> Progress {
    // Later undos hold their live chunks now too, so that requests made
    // after them wait behind them; a chunk that cannot come back refuses
    // an undo when it is the first.
    for i in 0..world.history.undos.len() {
        let held = hold_chunks(world, terrains, i);
        if let (0, Err(reason)) = (i, held) {
            return refuse_first(world, terrains, reason);
        }
    }
    let Some(request) = world.history.undos.front().map(|u| u.request) else {
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
        let at_hold = terrain.runtime.task.is_none()
            && matches!(
                terrain.runtime.queue.front(),
                Some(Job::HoldForWorldUndo { request: r }) if *r == request
            );
        if !at_hold {
            return Progress::Waiting;
        }
        // Every chunk holds every earlier request: check them all before
        // changing any.
        if chunk.carve == CarveState::Waiting && chunk.detach.is_none() {
            // Its carve never reached the chunk's jobs: nothing to undo.
            targets.push((coord, false));
            continue;
        }
        let same = terrain.hash.value() == chunk.after && terrain.journal.len() == chunk.journal;
        if !same {
            refusal.get_or_insert(WorldUndoRefusal::ChunkChanged { coord });
        } else if chunk.carve == CarveState::Landed && terrain.history.is_empty() {
            refusal.get_or_insert(WorldUndoRefusal::HistoryTrimmed { coord });
        }
        targets.push((coord, true));
    }
    if let Some(reason) = refusal {
        return refuse_first(world, terrains, reason);
    }
    let Some(step) = world.history.steps.remove(position) else {
        return Progress::Waiting;
    };
    // A chunk held while its carve waited, that then refused the carve,
    // has nothing to undo: its hold is taken out with the others.
    if let Some(undo) = world.history.undos.pop_front() {
        release_holds(world, terrains, &undo);
    }
    let mut changed = Vec::new();
    for (coord, undoes) in targets {
        let Some(mut chunk_terrain) =
            (world.chunk_entity(coord)).and_then(|e| terrains.get_mut(e).ok())
        else {
            continue;
        };
        let Some(chunk) = step.chunks.get(&coord).filter(|_| undoes) else {
            continue;
        };
        let terrain = chunk_terrain.bypass_change_detection();
        let mut keys = Vec::new();
        let mut undone = false;
        if chunk.carve == CarveState::Landed {
            match terrain.undo_now() {
                Ok(cells) => {
                    keys.extend(cells);
                    undone = true;
                }
                Err(error) => warn!("terrain world: chunk undo: {error}"),
            }
        }
        // A world has no redo: the chunk's undo is not redone on its own.
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
    for (coord, seeds) in step.seeds {
        world.give_seeds_back(coord, seeds, terrains);
    }
    Progress::Undone((request, changed))
}

/// Drops the first waiting undo, taking its holds out, refused for
/// `reason`.
fn refuse_first(
    world: &mut TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    reason: WorldUndoRefusal,
) -> Progress {
    if let Some(undo) = world.history.undos.pop_front() {
        release_holds(world, terrains, &undo);
    }
    Progress::Refused(reason)
}

/// Puts the hold of waiting undo `index` in every chunk of its step that
/// is live with no world carve waiting for it; fails, holding none, for a
/// chunk that cannot come back.
fn hold_chunks(
    world: &mut TerrainWorld,
    terrains: &mut Query<&mut Terrain>,
    index: usize,
) -> Result<(), WorldUndoRefusal> {
    let request = world.history.undos[index].request;
    let Some(step) = world.history.steps.iter().find(|s| s.request == request) else {
        return Ok(());
    };
    let held = &world.history.undos[index].held;
    let chunks = (step.chunks.iter()).filter(|&(c, chunk)| chunk.needs_hold() && !held.contains(c));
    let mut live = Vec::new();
    // Every chunk is looked at before any is held: a refused undo takes
    // out only the holds it noted (`release_holds`), so it notes them all.
    for (&coord, _) in chunks {
        match world.chunks.get(&coord) {
            Some(Chunk::Live(entity)) if !world.pending.contains_key(&coord) => {
                live.push((coord, *entity));
            }
            Some(Chunk::Failed) => return Err(WorldUndoRefusal::ChunkLost { coord }),
            Some(_) => {}
            None if world.stored.contains_key(&coord) || world.pending.contains_key(&coord) => {}
            // Neither live nor stored: unedited, the source's again, so its
            // own undo took the carve back (as a live chunk would answer).
            None => return Err(WorldUndoRefusal::ChunkChanged { coord }),
        }
    }
    for (coord, entity) in live {
        if let Ok(mut terrain) = terrains.get_mut(entity) {
            (terrain.bypass_change_detection().runtime.queue)
                .push_back(Job::HoldForWorldUndo { request });
            world.history.undos[index].held.insert(coord);
        }
    }
    Ok(())
}

/// Takes a refused undo's holds out of its chunks' queues.
fn release_holds(world: &TerrainWorld, terrains: &mut Query<&mut Terrain>, undo: &WaitingUndo) {
    for &coord in &undo.held {
        let Some(entity) = world.chunk_entity(coord) else {
            continue;
        };
        if let Ok(mut terrain) = terrains.get_mut(entity) {
            (terrain.bypass_change_detection().runtime.queue).retain(
                |job| !matches!(job, Job::HoldForWorldUndo { request } if *request == undo.request),
            );
        }
    }
}
