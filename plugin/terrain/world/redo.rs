//! Redo across a world: [`WorldRedo`] re-applies the world step the last
//! [`WorldUndo`] took back, in every chunk that undo changed, exactly.
//!
//! ## What the world keeps
//!
//! When a [`WorldUndo`] is carried out, the world keeps the step it took
//! back, and for each chunk it changed: the chunk's octree, state hash and
//! detach flag as the step left them (a cheap persistent clone), the
//! journal entry and undo step the chunk's own undo took out, the cells
//! the undo changed, and the state hash and journal length the undo left.
//! Undos since the last world carve are redone latest first. A new
//! [`WorldCarve`](super::WorldCarve) routed (also one asked for while an
//! undo or redo waits, which is routed after it) forgets them, and a
//! [`WorldRedo`] asked for after it is refused with
//! [`WorldRedoRefusal::NothingToRedo`]. Like the world's undo steps, they
//! live in memory only: a world loaded with
//! [`TerrainWorld::load_edits`] has nothing to redo.
//!
//! ## Redo
//!
//! A [`WorldRedo`] waits in the same line as the world's undos (those
//! asked for in one frame first, as with
//! [`RedoCarve`](crate::terrain::RedoCarve)): it is carried out once every
//! chunk of its step holds every request made before it, and world carves
//! asked for meanwhile wait and are routed after it. A chunk streamed out
//! since the undo is built or restored for it, and is not streamed out
//! while the redo waits. When every chunk has reached its hold, in one
//! frame:
//!
//! 1. every chunk the undo changed is checked: its state hash and journal
//!    length must be those the undo left. Anything else that changed the
//!    chunk since refuses the redo with [`WorldRedoRefusal::ChunkChanged`]:
//!    a carve, undo or redo of the chunk's own, or a piece that fell
//!    across its border (a search from the seeds the undo gave back may
//!    find a piece an earlier carve cut loose; if it falls before the
//!    redo lands, the redo is refused). A chunk whose build failed refuses
//!    it with [`WorldRedoRefusal::ChunkLost`];
//! 2. if one fails, nothing changes: [`WorldRedoRejected`] names the chunk
//!    and why, a warning is logged, and the undos and redos asked after it
//!    are refused too (with [`WorldRedoRefusal::EarlierRequestRefused`] or
//!    [`WorldUndoRefusal::EarlierUndoRefused`](super::WorldUndoRefusal));
//!    the step stays to redo;
//! 3. otherwise every chunk gets back its octree, state hash, journal
//!    entry and undo step of before the undo, bit for bit, the changed
//!    cells are rebuilt by a job at the head of each queue, the step is
//!    the world's last again (a [`WorldUndo`] takes it back again), and
//!    [`WorldRedone`] lists the chunks.
//!
//! Pieces of debris the step cut loose are taken out of the chunks again,
//! as after the step. As with [`RedoCarve`](crate::terrain::RedoCarve), no
//! new body is spawned (the bodies spawned by the step stayed through the
//! undo) and no [`DebrisDetached`](crate::terrain::DebrisDetached) is
//! written. A world redo forgets the chunks' own redo steps, as a carve
//! does.
//!
//! ## Streaming
//!
//! A world redo is kept by the world, not by its chunks: a chunk streamed
//! out after the undo — stored, or dropped when the undo took it back to
//! the source's state — streams back in bit-identical, so the redo still
//! finds the state the undo left and is carried out.
//!
//! A chunk's own redo steps (a [`RedoCarve`](crate::terrain::RedoCarve)
//! after an [`UndoCarve`](crate::terrain::UndoCarve) of the chunk) are not
//! written in its stored bytes or files. When the chunk streams out, the
//! world keeps them in memory (cheap persistent clones) with the chunk's
//! state hash and journal length, and hands them back when the chunk
//! streams in again with that same state; otherwise they are dropped
//! with a warning in the log. So streaming alone drops no redo step: a
//! chunk undone back to its source's state streams out and in and still
//! redoes. A save does not hold them, nor a loaded world.
//!
//! ## Networked worlds
//!
//! A networked world (feature `net`) records no world steps and refuses
//! [`WorldRedo`] with [`WorldRedoRefusal::Networked`].

use std::collections::BTreeMap;

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, Octree, StateHash};

use super::history::WorldStep;
#[cfg(doc)]
use super::undo::WorldUndo;
use super::undo::{Progress, WorldUndoRefusal, at_hold, refuse_first, release_holds};
use super::{ChunkCoord, TerrainWorld};
use crate::terrain::component::{JournalEntry, RedoStep, Terrain, UndoStep};
use crate::terrain::jobs::Job;

/// Redo the world step the last [`WorldUndo`] of a world took back, in
/// every chunk it changed ([module docs](self)). Answered by
/// [`WorldRedone`] or [`WorldRedoRejected`].
#[derive(Message, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorldRedo {
    /// The world entity.
    pub world: Entity,
}

/// A [`WorldRedo`] was carried out: every chunk the undo had changed has
/// its octree and state hash of before the undo again; their meshes
/// follow one job later.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldRedone {
    /// The world entity.
    pub world: Entity,
    /// The request id the redone carve's chunk carves had
    /// ([`CarveApplied::request`](crate::terrain::CarveApplied)).
    pub request: u64,
    /// The chunks changed, in coordinate order.
    pub chunks: Vec<ChunkCoord>,
}

/// A [`WorldRedo`] was refused; no chunk changed.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldRedoRejected {
    /// The world entity.
    pub world: Entity,
    /// Why.
    pub reason: WorldRedoRefusal,
}

/// Why a [`WorldRedo`] was refused.
#[derive(Reflect, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WorldRedoRefusal {
    /// The entity has no [`TerrainWorld`].
    #[error("the entity has no TerrainWorld")]
    NoSuchWorld,
    /// No world undo is left to redo: none was made, all were redone, or
    /// a world carve since forgot them.
    #[error("there is no world undo left to redo")]
    NothingToRedo,
    /// The world is networked (feature `net`): its server orders every
    /// change, and a local redo would desynchronise it.
    #[error("a networked world does not redo")]
    Networked,
    /// Something other than the undo changed this chunk since: a carve,
    /// undo or redo of its own, or a piece that fell across its border.
    #[error("chunk ({}, {}) changed since the undo", coord.x, coord.z)]
    ChunkChanged {
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
    /// refused; this one would redo another step than the one asked for.
    #[error("an earlier undo or redo of this world was refused")]
    EarlierRequestRefused,
}

impl WorldRedoRefusal {
    /// The redo's refusal for the reason the shared line of undos and
    /// redos gives.
    pub(super) fn from_undo(reason: WorldUndoRefusal) -> Self {
        match reason {
            WorldUndoRefusal::NoSuchWorld => Self::NoSuchWorld,
            WorldUndoRefusal::NothingToUndo => Self::NothingToRedo,
            WorldUndoRefusal::Networked => Self::Networked,
            WorldUndoRefusal::ChunkChanged { coord }
            | WorldUndoRefusal::HistoryTrimmed { coord } => Self::ChunkChanged { coord },
            WorldUndoRefusal::ChunkLost { coord } => Self::ChunkLost { coord },
            WorldUndoRefusal::EarlierUndoRefused => Self::EarlierRequestRefused,
        }
    }
}

/// A world step a [`WorldUndo`] took back, kept for [`WorldRedo`].
pub(crate) struct UndoneStep {
    step: WorldStep,
    chunks: BTreeMap<ChunkCoord, RedoChunk>,
}

impl UndoneStep {
    /// `step`, taken back from `chunks`.
    pub(super) fn new(step: WorldStep, chunks: Vec<(ChunkCoord, RedoChunk)>) -> Self {
        Self {
            step,
            chunks: chunks.into_iter().collect(),
        }
    }

    /// The request id of the step.
    pub(super) fn request(&self) -> u64 {
        self.step.request
    }

    /// The step, when it is world step `request`.
    pub(super) fn for_request(&self, request: u64) -> Option<&WorldStep> {
        (self.step.request == request).then_some(&self.step)
    }
}

/// One chunk a world undo changed, as the redo needs it.
pub(crate) struct RedoChunk {
    /// The octree, state hash and detach flag as the step left them.
    after: Octree,
    hash_after: u64,
    detached_across: bool,
    /// The journal entry and undo step the chunk's own undo took out.
    entry: Option<JournalEntry>,
    undo: Option<UndoStep>,
    /// The cells the undo changed.
    keys: Vec<CellKey>,
    /// The state hash and journal length the undo left.
    hash: u64,
    journal: usize,
}

impl RedoChunk {
    /// `terrain` as it is before the world undo changes it.
    pub(super) fn before_undo(terrain: &Terrain) -> Self {
        Self {
            after: terrain.octree.clone(),
            hash_after: terrain.hash.value(),
            detached_across: terrain.detached_across,
            entry: None,
            undo: None,
            keys: Vec::new(),
            hash: 0,
            journal: 0,
        }
    }

    /// The chunk's own undo took out `entry` and `step`.
    pub(super) fn took_step(&mut self, entry: Option<JournalEntry>, step: Option<UndoStep>) {
        self.entry = entry;
        self.undo = step;
    }

    /// `terrain` as the world undo left it, `keys` the cells it changed.
    pub(super) fn after_undo(mut self, terrain: &Terrain, keys: Vec<CellKey>) -> Self {
        self.keys = keys;
        self.hash = terrain.hash.value();
        self.journal = terrain.journal.len();
        self
    }
}

/// Carries out the first waiting request, a redo, once every chunk its
/// undo changed reached its hold.
pub(super) fn redo_first(world: &mut TerrainWorld, terrains: &mut Query<&mut Terrain>) -> Progress {
    let Some((request, hold)) = (world.history.waiting.front()).map(|w| (w.request, w.hold)) else {
        return Progress::Waiting;
    };
    let Some(top) = (world.history.undone.last()).filter(|u| u.request() == request) else {
        // Forgotten by a world carve while it waited.
        return refuse_first(world, terrains, WorldUndoRefusal::NothingToUndo);
    };
    // Every chunk holds every earlier request: check them all before
    // changing any.
    let mut refusal = None;
    for (&coord, chunk) in &top.chunks {
        let Some(terrain) = (world.chunk_entity(coord)).and_then(|e| terrains.get(e).ok()) else {
            return Progress::Waiting;
        };
        if !at_hold(terrain, hold) {
            return Progress::Waiting;
        }
        if terrain.hash.value() != chunk.hash || terrain.journal.len() != chunk.journal {
            refusal.get_or_insert(WorldUndoRefusal::ChunkChanged { coord });
        }
    }
    if let Some(reason) = refusal {
        return refuse_first(world, terrains, reason);
    }
    let Some(top) = world.history.undone.pop() else {
        return Progress::Waiting;
    };
    if let Some(redo) = world.history.waiting.pop_front() {
        release_holds(world, terrains, &redo);
    }
    let mut changed = Vec::new();
    for (coord, chunk) in top.chunks {
        let Some(mut chunk_terrain) =
            (world.chunk_entity(coord)).and_then(|e| terrains.get_mut(e).ok())
        else {
            continue;
        };
        let terrain = chunk_terrain.bypass_change_detection();
        terrain.octree = chunk.after;
        terrain.hash.update(&terrain.octree, &chunk.keys);
        if terrain.hash.value() != chunk.hash_after {
            warn!("terrain world: chunk redo: state hash rebuilt");
            terrain.hash = StateHash::of(&terrain.octree);
        }
        terrain.detached_across = chunk.detached_across;
        terrain.journal.extend(chunk.entry);
        if let Some(step) = chunk.undo {
            terrain.history.push_back(step);
            while terrain.history.len() > terrain.max_undo {
                terrain.history.pop_front();
            }
        }
        // What the chunk undid on its own before is not redone over this.
        terrain.redo.clear();
        terrain.runtime.queue.push_front(Job::Detached {
            keys: chunk.keys,
            pieces: Vec::new(),
        });
        chunk_terrain.set_changed();
        changed.push(coord);
    }
    world.history.steps.push_back(top.step);
    while world.history.steps.len() > world.history.max {
        world.history.steps.pop_front();
    }
    Progress::Done(request, changed)
}

/// A streamed-out chunk's own redo steps, kept by the world with the
/// state they redo from.
pub(crate) struct StreamedRedo {
    hash: u64,
    journal: usize,
    steps: Vec<RedoStep>,
}

impl TerrainWorld {
    /// Keeps the redo steps of chunk `coord`, streaming out with
    /// `terrain` ([module docs](self), "Streaming").
    pub(super) fn keep_streamed_redo(&mut self, coord: ChunkCoord, terrain: &Terrain) {
        if terrain.redo.is_empty() {
            return;
        }
        let kept = StreamedRedo {
            hash: terrain.hash.value(),
            journal: terrain.journal.len(),
            steps: terrain.redo.clone(),
        };
        self.history.streamed_redo.insert(coord, kept);
    }

    /// Hands chunk `coord`'s kept redo steps back to `terrain`, just
    /// built, when it has the state they redo from.
    pub(super) fn give_streamed_redo(&mut self, coord: ChunkCoord, terrain: &mut Terrain) {
        let Some(kept) = self.history.streamed_redo.remove(&coord) else {
            return;
        };
        if terrain.hash.value() == kept.hash && terrain.journal.len() == kept.journal {
            terrain.redo = kept.steps;
        } else {
            warn!(
                "terrain world chunk ({}, {}): changed while streamed out, its redo steps are dropped",
                coord.x, coord.z
            );
        }
    }

    /// Forgets chunk `coord`'s kept redo steps (its build failed).
    pub(super) fn drop_streamed_redo(&mut self, coord: ChunkCoord) {
        self.history.streamed_redo.remove(&coord);
    }
}
