//! A world's edits on disk: one terrain file per edited chunk
//! (`chunk_X_Z.chiselterrain`, the format of [`super::super::file`]), and
//! nothing for chunks nobody carved — they are rebuilt from the source.
//!
//! Saving writes each file whole or not at all (temporary file, sync,
//! rename, as [`Terrain::save`]), and only when every file is written
//! removes the chunk files of chunks no longer edited (undone back to the
//! base), then syncs the folder. A crash never leaves an edited chunk
//! without a complete file: before the removals the folder holds the new
//! files and, at worst, the old file of a chunk since undone, which
//! loads as that earlier edit and goes at the next save. Loading checks that every file belongs
//! to this world: the same grid, and the base this world's source gives
//! for that chunk, so a chunk restored from its file is bit-identical to
//! the saved one and meets its unedited neighbours exactly.
//!
//! ## Saving in the background
//!
//! [`TerrainWorld::save`] does everything at once on the calling thread:
//! it serializes every edited chunk and syncs every file, which stalls a
//! frame for as long as that takes. A [`SaveWorld`] message does the same
//! off the main thread, and only for what changed:
//!
//! 1. In the frame it starts (the frame it is read, or a later one when
//!    that frame holds no whole state, see below; after the carve
//!    systems, so the carves applied that frame are in), the world takes
//!    of each edited chunk that changed since the last save to that
//!    folder what its file needs:
//!    a live chunk's octrees are persistent, so taking them copies no
//!    cell (its journal and the undo steps' cell lists are copied); a
//!    stored chunk's bytes are shared. A chunk counts as unchanged when
//!    its file was last written, or found equal, by a save to the same
//!    folder path: a live chunk when it is the same entity and its
//!    [`Terrain`] was not changed since (its `Changed<Terrain>` tick, see
//!    [`Terrain`], "Change detection"), a stored chunk when its bytes have
//!    the length and checksum (the file's own XXH64) of that file.
//! 2. A task on the [`IoTaskPool`](bevy::tasks::IoTaskPool) serializes the live chunks, skips those
//!    whose bytes have the length and checksum of their file (a chunk that
//!    streamed out or in since, unchanged), writes the others, each
//!    atomically, then removes the stale chunk files and syncs the folder
//!    exactly as [`TerrainWorld::save`] does. The I/O pool, not the async
//!    compute one: each file is synced to disk, which blocks its thread,
//!    and the chunk builds, carve jobs and debris searches on the compute
//!    pool should not wait behind that.
//! 3. A later frame reads the task's outcome and reports [`WorldSaved`]
//!    (the chunks written, the edited chunks left as they were, the bytes
//!    written, the carves in flight left out) or [`WorldSaveFailed`]. Only a save that succeeded moves
//!    the folder's record on; one that failed forgets the record of every
//!    chunk it meant to write or remove, so the next save to that folder
//!    writes them all again.
//!
//! What is written is every edited chunk as it was in the frame the save
//! started (before the jobs in flight then, see below): carves, undos and
//! streaming may go on while it writes.
//!
//! ## Waiting for a whole state
//!
//! A save starts in a frame that holds a whole state when one comes, so
//! that it holds every carve asked for before it. A frame does not when a
//! carve waits for a chunk (also a far chunk's deferred carves on a
//! networked world's client: [`TerrainWorld::build_deferred`] builds
//! them), a [`WorldUndo`](super::WorldUndo) or
//! [`WorldRedo`](super::WorldRedo) waits for a chunk, or a live
//! chunk has a carve, undo or detach queued or running.
//!
//! A fall across chunk borders on its way does not keep a frame from
//! being whole: it is saved. Each chunk file holds the chunk's *seeds*
//! ([`super::super::file`]), the cells its carves changed whose search for
//! debris across borders ([`super::debris`]) is still to come: those in
//! the chunk and those a search running or waiting to be applied took
//! out of it (a chunk streamed out keeps both in its stored bytes, which
//! a save writes as they are). A world loaded from the files puts them
//! back into their chunks as they stream in, searches from them (once
//! the neighbours streaming in beside them are live) and the piece falls
//! there as in the saved world (the same search, over the chunks live then),
//! so a saved world never holds forever a piece that a carve already
//! freed. Two such falls still make a frame not whole, as no file
//! holds them: seeds in a live chunk that is not edited (it has no file;
//! rare: a [`WorldUndo`](super::WorldUndo) back to the base gives a
//! detach's seeds back), and on a networked world's client a detach its
//! server ordered, still to be carried out. A detach being applied
//! (its chunks' jobs rebuilding the cells, already taken out of the
//! octrees) is a chunk job as any: the frame waits for it, a frame or
//! two. So a world cratered every other frame saves within a frame or
//! two (`world_save_seeds`), where before it waited for seeds and
//! searches it never was without.
//!
//! ## Saving a busy world
//!
//! A world carved in every frame (a player holding a drill) has a carve
//! job running in every frame and may never be whole. Its chunks still
//! hold a state worth saving: a live chunk's [`Terrain`] (octree, journal,
//! undo history, seeds) is its state *before* its queued and running
//! jobs, whose results are swapped in when they are collected. That state
//! is *consistent* when every world carve has landed (been applied or
//! refused) in all of the chunks it was routed to or in none of them; a
//! carve waiting for a chunk that is not live has not landed there.
//! Carves of one chunk, detaches across chunk borders and world undos
//! (each changes all its chunks in one frame) never split it; a waiting
//! [`WorldUndo`](super::WorldUndo) and the two falls above make a frame
//! neither whole nor consistent. The world notes, per world carve routed
//! to several chunks, those chunks until each has reported it
//! (`store_cut`).
//!
//! A request whose turn has seen no whole state in
//! [`TerrainWorld::save_settle_frames`] frames
//! ([`DEFAULT_SAVE_SETTLE_FRAMES`], 10 by default) saves the first
//! consistent state: each chunk as it was before its jobs in flight. Those
//! land after it and are written by the next save (the chunks they change
//! are marked changed then); [`WorldSaved::left_out`] counts them, a world
//! carve once, 0 for a whole state.
//!
//! Each chunk runs its own jobs, so chunks that share carves need not come
//! to the same carve in the same frame. When a request finds no consistent
//! state after its settle frames, the chunks start no carve routed after
//! that frame (a request id above the last one routed) until one comes,
//! for at most [`TerrainWorld::save_hold_frames`] frames per request
//! ([`DEFAULT_SAVE_HOLD_FRAMES`], 15 by default; not while carves wait
//! deferred for far chunks of a networked world's client): each finishes
//! the carves it has, the carves after wait queued in all of their
//! chunks, and the state is consistent once the slowest chunk's job is
//! in. With 0 hold frames no carve is held back: the request saves only
//! a consistent state the chunks come to by themselves, and gives up as
//! below when none comes. A world carved in every
//! frame across chunk borders thus saves a few frames after the settle
//! frames (`world_save_cut`); the carves held back show those frames
//! later.
//!
//! ## Waiting requests
//!
//! A request read in a frame that holds no state it may save, or while a
//! save of the same world is being written, is not refused: the world
//! keeps it, oldest first, and starts it in the first later frame that
//! holds such a state with no save of the world running (requests for
//! several folders one after the other, in the order they were read),
//! saving the state of *that* frame. [`TerrainWorld::waiting_saves`]
//! lists them, for a game's "saving…".
//!
//! - A request for a folder that already has a request waiting (one read
//!   in an earlier frame, or in the same frame) is merged into it: it
//!   keeps the earlier one's place and both get its one answer (the state
//!   saved is that of the frame the save starts, as new as both
//!   requests). A request while a save to the same folder is being
//!   written is not merged: it waits, and gets its own answer after that
//!   save's, writing what changed since.
//! - Saving holds back no carve but as above: carves, undos and streaming
//!   go on while a request waits. A request gives up once the world held
//!   neither a whole state nor, after the settle frames, a consistent one
//!   in [`TerrainWorld::max_save_wait`] frames of its turn (frames in
//!   which it is the oldest request and no save of the world runs;
//!   [`DEFAULT_MAX_SAVE_WAIT`], 300 by default, 5 s at 60 frames a
//!   second), answered by [`WorldSaveFailed`] with
//!   [`TerrainError::WorldNotIdle`] naming a busy chunk of the last frame
//!   it tried (a world undo waiting all that time, say). Frames spent
//!   behind a save being written or another request do not count. With a
//!   bound of 0 a request gives up in the first frame of its turn unless
//!   it can start then (with settle frames 0, on a consistent state).
//! - Despawning the world drops its waiting requests, unanswered.
//!
//! [`TerrainWorld::save`] does not wait, nor take a consistent state: it
//! refuses a world that is not whole ([`TerrainError::WorldNotIdle`]) or while a [`SaveWorld`] of it is
//! being written ([`TerrainError::WorldSaveRunning`]); waiting requests do
//! not hold it back. The world is not marked changed by any of
//! this (bookkeeping, [`TerrainWorld`], "Change detection"). The record
//! assumes that nothing else writes the folder's chunk files.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};

use bevy::ecs::change_detection::Tick;
use bevy::prelude::*;
use bevy::tasks::Task;
use chisel_bsp::octree::CellKey;

use super::super::asset::TERRAIN_EXTENSION;
use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::store_cut::{DEFAULT_SAVE_HOLD_FRAMES, DEFAULT_SAVE_SETTLE_FRAMES};
use super::store_files::{ChunkBytes, FileOutcome, PlannedFile, write_chunk_files};
use super::store_save::record_of;
use super::{Chunk, ChunkCoord, TerrainWorld};

pub use super::store_save::save_worlds;

/// The frames a [`SaveWorld`] waits, by default, for its world to hold a
/// state it may save (whole, or after the settle frames consistent) before
/// it gives up ([`TerrainWorld::with_max_save_wait`]): 5 s at 60 frames a
/// second.
pub const DEFAULT_MAX_SAVE_WAIT: u32 = 300;

/// Save a world's edited chunks into `folder` off the main thread, only
/// those that changed since the last save to that folder ([module
/// docs](self)). It starts in the first frame, from the one it is read
/// on, that holds a whole state (no carve, undo or detach in flight in a
/// chunk or waiting for one) with no save of the world being written;
/// after [`TerrainWorld::save_settle_frames`] frames of its turn without
/// one, in the first that holds a consistent state (every world carve in
/// all of its chunks or in none; the chunks hold back later carves a few
/// frames for one if need be), saving the chunks as they were before
/// their carves in flight. It waits at most
/// [`TerrainWorld::max_save_wait`] frames of its turn; a second request
/// for a folder whose request waits is merged into it. Falls across chunk borders still on their way are saved with
/// the chunks (their seeds), so a world loaded from the files lets those
/// pieces fall: a save does not wait for them. Answered, a frame or more
/// later, by one [`WorldSaved`] or [`WorldSaveFailed`].
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct SaveWorld {
    /// The world entity.
    pub world: Entity,
    /// The folder of the chunk files (created if missing).
    pub folder: PathBuf,
}

/// A [`SaveWorld`] was written: `folder` holds every chunk edited in the
/// frame the save started, as it was then (before the carves in flight
/// then, when `left_out` is not 0), and no other chunk file.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldSaved {
    /// The world entity.
    pub world: Entity,
    /// The folder.
    pub folder: PathBuf,
    /// The chunks whose files were written, in coordinate order.
    pub written: Vec<ChunkCoord>,
    /// The edited chunks whose files already held them.
    pub unchanged: usize,
    /// The bytes written (the files' lengths).
    pub bytes: usize,
    /// The carves and undos that were in flight in the chunks (queued,
    /// running or waiting for a chunk) when the save started and are not
    /// in the files: a world carve counts once, however many chunks it
    /// reaches. 0 when the save found a whole state. They land after the
    /// save, and the next save to the folder writes the chunks they
    /// change ([module docs](self), "Saving a busy world").
    pub left_out: usize,
}

/// A [`SaveWorld`] gave up (nothing written) or failed: the files
/// written before the failure stay, each whole; stale chunk files are
/// removed only once every file is written (as [`TerrainWorld::save`]);
/// and the next save to that folder writes every chunk this one meant to.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct WorldSaveFailed {
    /// The world entity.
    pub world: Entity,
    /// The folder.
    pub folder: PathBuf,
    /// Why: [`TerrainError::Io`] naming the file or folder;
    /// [`TerrainError::WorldNotIdle`] when the world held no whole state,
    /// nor after the settle frames a consistent one, in
    /// [`TerrainWorld::max_save_wait`] frames of the request's turn (it
    /// waited, then gave up, nothing written; [module docs](self)); or
    /// [`TerrainError::InvalidWorld`] for an entity without a
    /// [`TerrainWorld`] (in the frame the request is read).
    #[reflect(ignore)]
    pub error: TerrainError,
}

/// A world's saves: what each folder's chunk files hold, as the last save
/// to it left them, the background save being written and the requests
/// waiting for their turn.
pub(crate) struct WorldSaves {
    /// Per folder path, the chunk files known to hold what they were
    /// written with. Behind a lock so that [`TerrainWorld::save`] (`&self`)
    /// keeps it too.
    pub(super) folders: Mutex<BTreeMap<PathBuf, FolderRecord>>,
    pub(super) running: Option<RunningSave>,
    /// The [`SaveWorld`] requests not started yet, oldest first, at most
    /// one per folder.
    pub(super) waiting: VecDeque<WaitingSave>,
    /// Frames of its turn a request waits before it gives up.
    pub(super) max_wait: u32,
    /// Frames of its turn a request waits for a whole state before it
    /// takes a consistent one.
    pub(super) settle: u32,
    /// While the oldest request waits for a consistent state: the last
    /// world carve routed when it began to; the chunks start no carve
    /// routed after it (`store_cut`).
    pub(super) barrier: Option<u64>,
    /// The most frames a request holds carves back for a consistent state.
    pub(super) hold: u32,
}

impl Default for WorldSaves {
    fn default() -> Self {
        Self {
            folders: Mutex::default(),
            running: None,
            waiting: VecDeque::new(),
            max_wait: DEFAULT_MAX_SAVE_WAIT,
            settle: DEFAULT_SAVE_SETTLE_FRAMES,
            barrier: None,
            hold: DEFAULT_SAVE_HOLD_FRAMES,
        }
    }
}

/// A [`SaveWorld`] request waiting for its turn and a whole state.
pub(super) struct WaitingSave {
    pub(super) folder: PathBuf,
    /// The frames of its turn in which the world held no whole state.
    pub(super) refused: u32,
    /// The frames it held carves back for a consistent state.
    pub(super) held: u32,
}

/// What a folder's chunk files hold, by chunk.
pub(super) type FolderRecord = BTreeMap<ChunkCoord, SavedChunk>;

/// One chunk file as a save left it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct SavedChunk {
    /// The file's length and checksum (its last 8 bytes, the XXH64 of
    /// the others).
    pub(super) len: usize,
    pub(super) checksum: u64,
    /// The live chunk it was taken from: its entity and the tick of its
    /// terrain's last change then (`None` for bytes of a stored chunk, a
    /// [`TerrainWorld::save`], or a chunk saved with seeds: seeds come and
    /// go without a change of the terrain, so such a chunk is serialized
    /// again and compared by its bytes).
    pub(super) live: Option<(Entity, Tick)>,
}

/// A background save being written.
pub(super) struct RunningSave {
    pub(super) folder: PathBuf,
    /// The records of the edited chunks left as they were (and of live
    /// chunks whose terrain could not be read), kept whatever the outcome.
    pub(super) kept: FolderRecord,
    /// The live chunk each planned file comes from, for the record (no
    /// mark for a chunk saved with seeds, see [`SavedChunk::live`]).
    pub(super) live: BTreeMap<ChunkCoord, Option<(Entity, Tick)>>,
    /// Edited chunks found unchanged when the save was planned.
    pub(super) unchanged: usize,
    /// Carves and undos in flight left out of the files.
    pub(super) left_out: usize,
    pub(super) task: Task<Result<Vec<FileOutcome>, TerrainError>>,
}

impl WorldSaves {
    pub(super) fn folders(&self) -> MutexGuard<'_, BTreeMap<PathBuf, FolderRecord>> {
        // The record is replaced whole under the lock: a panic elsewhere
        // cannot leave it half written.
        self.folders
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Refuses a save while one is being written.
    pub(super) fn check_not_running(&self) -> Result<(), TerrainError> {
        match &self.running {
            Some(running) => Err(TerrainError::WorldSaveRunning {
                folder: running.folder.display().to_string(),
            }),
            None => Ok(()),
        }
    }

    /// Keeps a request for `folder` until it can start, merged into the
    /// one waiting for the same folder if there is one.
    pub(super) fn enqueue(&mut self, folder: &Path) {
        if !self.waiting.iter().any(|w| w.folder == folder) {
            self.waiting.push_back(WaitingSave {
                folder: folder.to_path_buf(),
                refused: 0,
                held: 0,
            });
        }
    }
}

impl TerrainWorld {
    /// The file name of chunk `coord` in a saved world.
    #[must_use]
    pub fn chunk_file_name(coord: ChunkCoord) -> String {
        format!("chunk_{}_{}.{TERRAIN_EXTENSION}", coord.x, coord.z)
    }

    /// Whether a background save ([`SaveWorld`]) of this world is being
    /// written.
    #[must_use]
    pub fn is_saving(&self) -> bool {
        self.saves.running.is_some()
    }

    /// The folders of the [`SaveWorld`] requests waiting to start (for a
    /// whole state, or for the save being written), in the order they
    /// will start ([module docs](self)). A game shows "saving…" while
    /// this is not empty or [`TerrainWorld::is_saving`].
    pub fn waiting_saves(&self) -> impl Iterator<Item = &Path> + '_ {
        self.saves.waiting.iter().map(|w| w.folder.as_path())
    }

    /// Whether a [`SaveWorld`] request of this world waits to start.
    #[must_use]
    pub fn save_waiting(&self) -> bool {
        !self.saves.waiting.is_empty()
    }

    /// A [`SaveWorld`] request gives up, answered by [`WorldSaveFailed`]
    /// with [`TerrainError::WorldNotIdle`], once the world held no whole
    /// state, nor after [`TerrainWorld::save_settle_frames`] a consistent
    /// one, in `frames` frames of its turn: frames (runs of the save
    /// system) in which it is the oldest waiting request and no save of the
    /// world is being written ([module docs](self)).
    /// [`DEFAULT_MAX_SAVE_WAIT`] by default; with 0 a request gives up in
    /// the first frame of its turn (the frame it is read in, unless a save
    /// runs or another request waits) when that frame holds no state it
    /// may save. Carves never wait for a save; a world carved in every
    /// frame saves a consistent state after the settle frames.
    #[must_use]
    pub fn with_max_save_wait(mut self, frames: u32) -> Self {
        self.saves.max_wait = frames;
        self
    }

    /// The frames a [`SaveWorld`] request waits before it gives up
    /// ([`TerrainWorld::with_max_save_wait`]).
    #[must_use]
    pub fn max_save_wait(&self) -> u32 {
        self.saves.max_wait
    }

    /// Writes every edited chunk (live ones through `terrain_of`, which
    /// gives a chunk entity's [`Terrain`], and stored ones) into `folder`,
    /// one file each, creating the folder; returns the chunks written.
    /// Then removes the folder's chunk files of chunks that are not edited
    /// now (see the module notes); a live chunk whose terrain `terrain_of`
    /// does not give keeps its file. Other files are left alone. All of it
    /// on the calling thread; [`SaveWorld`] saves in the background, only
    /// what changed, and a [`SaveWorld`] after this writes only the chunks
    /// that changed since.
    ///
    /// # Errors
    /// [`TerrainError::WorldNotIdle`] while a carve waits for a chunk
    /// (deferred ones too: [`TerrainWorld::build_deferred`]) or
    /// an edited chunk has work in progress (nothing is written then).
    /// Falls across chunk borders on their way are written as
    /// [`SaveWorld`] writes them (each chunk's seeds, [module docs](self));
    /// [`TerrainError::WorldSaveRunning`] while a [`SaveWorld`] of this
    /// world is being written;
    /// [`TerrainError::Io`] naming the file that could not be written or
    /// removed (files written before it stay, and nothing is removed
    /// before every file is written).
    pub fn save<'a>(
        &self,
        folder: impl AsRef<Path>,
        terrain_of: impl Fn(Entity) -> Option<&'a Terrain>,
    ) -> Result<Vec<ChunkCoord>, TerrainError> {
        let folder = folder.as_ref();
        self.saves.check_not_running()?;
        if let Some(coord) = self.pending.keys().next() {
            return Err(TerrainError::WorldNotIdle {
                chunk: [coord.x, coord.z],
            });
        }
        let mut files: Vec<(ChunkCoord, Arc<Vec<u8>>)> = Vec::new();
        // Chunks whose state is not known here: their files stay.
        let mut unknown: BTreeSet<ChunkCoord> = BTreeSet::new();
        for (coord, state) in &self.chunks {
            let Chunk::Live(entity) = state else {
                continue;
            };
            let Some(terrain) = terrain_of(*entity) else {
                unknown.insert(*coord);
                continue;
            };
            if !self.chunk_edited(*coord, terrain) {
                continue;
            }
            if !terrain.is_idle() {
                return Err(TerrainError::WorldNotIdle {
                    chunk: [coord.x, coord.z],
                });
            }
            let record = (terrain.record_for_file()).with_seeds_taken(self.seeds_taken(*entity));
            files.push((*coord, Arc::new(record.to_bytes())));
        }
        for (coord, bytes) in &self.stored {
            if !files.iter().any(|(c, _)| c == coord) {
                files.push((*coord, bytes.clone()));
            }
        }
        files.sort_by_key(|(c, _)| *c);
        let planned = (files.into_iter())
            .map(|(coord, bytes)| PlannedFile {
                coord,
                bytes: ChunkBytes::Stored(bytes),
                known: None,
            })
            .collect();
        let mut folders = self.saves.folders();
        // Only the records of files left alone stay, whatever the outcome.
        let kept: FolderRecord = (folders.remove(folder).unwrap_or_default().into_iter())
            .filter(|(c, _)| unknown.contains(c))
            .collect();
        let outcome = write_chunk_files(folder, planned, &unknown);
        let record = match &outcome {
            Ok(files) => record_of(kept, files, &BTreeMap::new()),
            Err(_) => kept,
        };
        folders.insert(folder.to_path_buf(), record);
        Ok(outcome?.into_iter().map(|f| f.coord).collect())
    }

    /// The seeds the world's search across chunk borders took out of the
    /// chunk of terrain `entity` and has not applied: pending, saved with
    /// the chunk (and stored with it when it streams out, `stream`).
    pub(super) fn seeds_taken(&self, entity: Entity) -> &[CellKey] {
        (self.debris_search.as_ref()).map_or(&[], |search| search.seeds_taken(entity))
    }
}
