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
//! 1. In the frame it is read (after the carve systems, so the carves
//!    applied that frame are in), the world takes of each edited chunk
//!    that changed since the last save to that folder what its file needs:
//!    a live chunk's octrees are persistent, so taking them copies no
//!    cell (its journal and the undo steps' cell lists are copied); a
//!    stored chunk's bytes are shared. A chunk counts as unchanged when
//!    its file was last written, or found equal, by a save to the same
//!    folder path: a live chunk when it is the same entity and its
//!    [`Terrain`] was not changed since (its `Changed<Terrain>` tick, see
//!    [`Terrain`], "Change detection"), a stored chunk when its bytes have
//!    the length and checksum (the file's own XXH64) of that file.
//! 2. A task on the [`IoTaskPool`] serializes the live chunks, skips those
//!    whose bytes have the length and checksum of their file (a chunk that
//!    streamed out or in since, unchanged), writes the others, each
//!    atomically, then removes the stale chunk files and syncs the folder
//!    exactly as [`TerrainWorld::save`] does. The I/O pool, not the async
//!    compute one: each file is synced to disk, which blocks its thread,
//!    and the chunk builds, carve jobs and debris searches on the compute
//!    pool should not wait behind that.
//! 3. A later frame reads the task's outcome and reports [`WorldSaved`]
//!    (the chunks written, the edited chunks left as they were, the bytes
//!    written) or [`WorldSaveFailed`]. Only a save that succeeded moves
//!    the folder's record on; one that failed forgets the record of every
//!    chunk it meant to write or remove, so the next save to that folder
//!    writes them all again.
//!
//! What is written is every edited chunk as it was in the frame the
//! request was read: carves, undos and streaming may go on while it
//! writes. The request is refused ([`WorldSaveFailed`]) when that frame
//! does not hold a whole state: a carve waits for a chunk (also a far
//! chunk's deferred carves on a networked world's client: call
//! [`TerrainWorld::build_deferred`] first), a
//! [`WorldUndo`](super::WorldUndo) waits, or a live chunk has a carve,
//! undo or detach queued or running ([`TerrainError::WorldNotIdle`]; ask
//! again in a later frame), so a saved world never holds half of a world
//! carve. A request while a save of the same world is being written is
//! refused too ([`TerrainError::WorldSaveRunning`]), not queued: the game
//! decides whether a newer state should be saved once it is done; so is a
//! [`TerrainWorld::save`] then. The world is not marked changed by any of
//! this (bookkeeping, [`TerrainWorld`], "Change detection"). The record
//! assumes that nothing else writes the folder's chunk files.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard};

use bevy::ecs::change_detection::Tick;
use bevy::prelude::*;
use bevy::tasks::futures::check_ready;
use bevy::tasks::{IoTaskPool, Task};

use super::super::asset::TERRAIN_EXTENSION;
use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::super::file::{TerrainRecord, write_atomic};
use super::{Chunk, ChunkCoord, TerrainWorld};

/// Save a world's edited chunks into `folder` off the main thread, only
/// those that changed since the last save to that folder ([module
/// docs](self)). Answered, a frame or more later, by [`WorldSaved`] or
/// [`WorldSaveFailed`].
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct SaveWorld {
    /// The world entity.
    pub world: Entity,
    /// The folder of the chunk files (created if missing).
    pub folder: PathBuf,
}

/// A [`SaveWorld`] was written: `folder` holds every chunk edited in the
/// frame the request was read, as it was then, and no other chunk file.
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
}

/// A [`SaveWorld`] was refused (nothing written) or failed: the files
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
    /// Why: [`TerrainError::Io`] naming the file or folder,
    /// [`TerrainError::WorldNotIdle`], [`TerrainError::WorldSaveRunning`],
    /// or [`TerrainError::InvalidWorld`] for an entity without a
    /// [`TerrainWorld`].
    #[reflect(ignore)]
    pub error: TerrainError,
}

/// A world's saves: what each folder's chunk files hold, as the last save
/// to it left them, and the background save being written.
#[derive(Default)]
pub(crate) struct WorldSaves {
    /// Per folder path, the chunk files known to hold what they were
    /// written with. Behind a lock so that [`TerrainWorld::save`] (`&self`)
    /// keeps it too.
    folders: Mutex<BTreeMap<PathBuf, FolderRecord>>,
    running: Option<RunningSave>,
}

/// What a folder's chunk files hold, by chunk.
type FolderRecord = BTreeMap<ChunkCoord, SavedChunk>;

/// One chunk file as a save left it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SavedChunk {
    /// The file's length and checksum (its last 8 bytes, the XXH64 of
    /// the others).
    len: usize,
    checksum: u64,
    /// The live chunk it was taken from: its entity and the tick of its
    /// terrain's last change then (`None` for bytes of a stored chunk or
    /// a [`TerrainWorld::save`]).
    live: Option<(Entity, Tick)>,
}

/// A background save being written.
struct RunningSave {
    folder: PathBuf,
    /// The records of the edited chunks left as they were (and of live
    /// chunks whose terrain could not be read), kept whatever the outcome.
    kept: FolderRecord,
    /// The live chunk each planned file comes from, for the record.
    live: BTreeMap<ChunkCoord, (Entity, Tick)>,
    /// Edited chunks found unchanged when the save was planned.
    unchanged: usize,
    task: Task<Result<Vec<FileOutcome>, TerrainError>>,
}

/// What the task did with one planned chunk file.
struct FileOutcome {
    coord: ChunkCoord,
    len: usize,
    checksum: u64,
    written: bool,
}

/// Where a planned chunk file's bytes come from.
enum ChunkBytes {
    /// A live chunk, serialized by the task.
    Live(Box<TerrainRecord>),
    /// A stored chunk's bytes.
    Stored(Arc<Vec<u8>>),
}

/// One chunk file to write unless the file holds it already.
struct PlannedFile {
    coord: ChunkCoord,
    bytes: ChunkBytes,
    /// Length and checksum of what the file is known to hold.
    known: Option<(usize, u64)>,
}

impl WorldSaves {
    fn folders(&self) -> MutexGuard<'_, BTreeMap<PathBuf, FolderRecord>> {
        // The record is replaced whole under the lock: a panic elsewhere
        // cannot leave it half written.
        self.folders
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Refuses a save while one is being written.
    fn check_not_running(&self) -> Result<(), TerrainError> {
        match &self.running {
            Some(running) => Err(TerrainError::WorldSaveRunning {
                folder: running.folder.display().to_string(),
            }),
            None => Ok(()),
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
    /// an edited chunk has work in progress (nothing is written then);
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
            files.push((*coord, Arc::new(terrain.to_bytes())));
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

    /// Plans a background save into `folder` ([module docs](self)) and
    /// starts its task.
    fn start_save(
        &mut self,
        folder: &Path,
        terrains: &Query<Ref<Terrain>>,
    ) -> Result<(), TerrainError> {
        self.saves.check_not_running()?;
        // A carve waiting for a chunk, or a chunk of a waiting undo.
        let waiting =
            (self.pending.keys().next().copied()).or_else(|| self.history.wanted().next());
        if let Some(coord) = waiting {
            return Err(TerrainError::WorldNotIdle {
                chunk: [coord.x, coord.z],
            });
        }
        let record = self
            .saves
            .folders()
            .get(folder)
            .cloned()
            .unwrap_or_default();
        // The records of the files this save leaves alone, and their chunks
        // (edited and unchanged, or live and not readable here).
        let mut kept = FolderRecord::new();
        let mut keep = BTreeSet::new();
        let mut live = BTreeMap::new();
        let mut planned = Vec::new();
        let (mut unchanged_live, mut unchanged_stored) = (0, 0);
        for (&coord, state) in &self.chunks {
            let Chunk::Live(entity) = *state else {
                continue;
            };
            let Ok(terrain) = terrains.get(entity) else {
                // Not readable here: its file stays as it is.
                kept.extend(record.get(&coord).map(|saved| (coord, *saved)));
                keep.insert(coord);
                continue;
            };
            if !content_settled(&terrain) {
                return Err(TerrainError::WorldNotIdle {
                    chunk: [coord.x, coord.z],
                });
            }
            if !self.chunk_edited(coord, &terrain) {
                continue;
            }
            let mark = (entity, terrain.last_changed());
            match record.get(&coord) {
                Some(saved) if saved.live == Some(mark) => {
                    kept.insert(coord, *saved);
                    keep.insert(coord);
                    unchanged_live += 1;
                }
                saved => {
                    live.insert(coord, mark);
                    planned.push(PlannedFile {
                        coord,
                        bytes: ChunkBytes::Live(Box::new(terrain.record_for_file())),
                        known: saved.map(|s| (s.len, s.checksum)),
                    });
                }
            }
        }
        for (&coord, bytes) in &self.stored {
            if live.contains_key(&coord) || keep.contains(&coord) {
                continue;
            }
            let saved = record.get(&coord);
            let known = saved.map(|s| (s.len, s.checksum));
            match (saved, file_checksum(bytes)) {
                (Some(saved), Some(sum)) if known == Some((bytes.len(), sum)) => {
                    kept.insert(
                        coord,
                        SavedChunk {
                            live: None,
                            ..*saved
                        },
                    );
                    keep.insert(coord);
                    unchanged_stored += 1;
                }
                _ => planned.push(PlannedFile {
                    coord,
                    bytes: ChunkBytes::Stored(bytes.clone()),
                    known,
                }),
            }
        }
        let unchanged = unchanged_live + unchanged_stored;
        let path = folder.to_path_buf();
        let task = IoTaskPool::get().spawn(async move {
            let _span = bevy::log::info_span!("chisel::world::save").entered();
            write_chunk_files(&path, planned, &keep)
        });
        self.saves.running = Some(RunningSave {
            folder: folder.to_path_buf(),
            kept,
            live,
            unchanged,
            task,
        });
        Ok(())
    }

    /// The outcome of the background save once its task is done: the
    /// folder and what was written, the folder's record updated.
    fn finish_save(&mut self) -> Option<(PathBuf, Result<WorldSaved, TerrainError>)> {
        let running = self.saves.running.as_mut()?;
        let outcome = check_ready(&mut running.task)?;
        let running = self.saves.running.take()?;
        let mut folders = self.saves.folders();
        let result = match outcome {
            Ok(files) => {
                let saved = WorldSaved {
                    world: Entity::PLACEHOLDER,
                    folder: running.folder.clone(),
                    written: (files.iter().filter(|f| f.written))
                        .map(|f| f.coord)
                        .collect(),
                    unchanged: running.unchanged + files.iter().filter(|f| !f.written).count(),
                    bytes: (files.iter().filter(|f| f.written)).map(|f| f.len).sum(),
                };
                let record = record_of(running.kept, &files, &running.live);
                folders.insert(running.folder.clone(), record);
                Ok(saved)
            }
            Err(error) => {
                // Files may have been written or removed: only the records
                // of files left alone stay.
                folders.insert(running.folder.clone(), running.kept);
                Err(error)
            }
        };
        Some((running.folder, result))
    }

    /// Reads the edited chunks saved in `folder` ([`TerrainWorld::save`])
    /// into this world's store: they stream in from them exactly as saved.
    /// Files whose names are not chunk files are ignored.
    ///
    /// # Errors
    /// [`TerrainError::Io`] when the folder or a file cannot be read;
    /// [`TerrainError::InFile`] naming a bad file, with the error of
    /// [`Terrain::from_bytes`]; [`TerrainError::InvalidWorld`]
    /// for a chunk file of another world (another grid or base). The world
    /// is unchanged then.
    pub fn load_edits(mut self, folder: impl AsRef<Path>) -> Result<Self, TerrainError> {
        let folder = folder.as_ref();
        let io = |e: std::io::Error| TerrainError::Io {
            message: format!("cannot read {}: {e}", folder.display()),
        };
        let mut found = Vec::new();
        let mut kept = Vec::new();
        for entry in fs::read_dir(folder).map_err(io)? {
            let entry = entry.map_err(io)?;
            let name = entry.file_name();
            let Some(coord) = name.to_str().and_then(parse_chunk_name) else {
                continue;
            };
            let path = entry.path();
            let bytes = fs::read(&path).map_err(|e| TerrainError::Io {
                message: format!("cannot read {}: {e}", path.display()),
            })?;
            let terrain = Terrain::from_bytes(&bytes).map_err(|e| e.at_path(&path))?;
            let base = self.layout.chunk_base(&*self.source, coord)?;
            if *terrain.quantization() != self.layout.quantization || *terrain.base() != base {
                return Err(TerrainError::InvalidWorld {
                    reason: format!(
                        "{} is not a chunk of this world (another grid or base)",
                        path.display()
                    ),
                });
            }
            if terrain.journal().is_empty() && terrain.undo_depth() == 0 {
                // Saved though it has no journal: a chunk installed from a
                // networked world's snapshot, edited all the same.
                kept.push(coord);
            }
            found.push((coord, Arc::new(bytes)));
        }
        self.kept.extend(kept);
        self.stored.extend(found);
        self.stats.stored = self.stored.len();
        self.stats.stored_bytes = self.stored.values().map(|b| b.len()).sum();
        Ok(self)
    }
}

/// Reads [`SaveWorld`]s and starts their background saves, and reports
/// the saves whose tasks are done ([module docs](self)). Runs after the
/// carve systems.
pub fn save_worlds(
    mut requests: MessageReader<SaveWorld>,
    mut worlds: Query<(Entity, &mut TerrainWorld)>,
    terrains: Query<Ref<Terrain>>,
    mut saved: MessageWriter<WorldSaved>,
    mut failed: MessageWriter<WorldSaveFailed>,
) {
    let _span = bevy::log::info_span!("chisel::world::save_worlds").entered();
    for (entity, mut world) in &mut worlds {
        // Bookkeeping: the world's chunks and edits are as they were.
        let Some((folder, result)) = world.bypass_change_detection().finish_save() else {
            continue;
        };
        match result {
            Ok(done) => {
                saved.write(WorldSaved {
                    world: entity,
                    ..done
                });
            }
            Err(error) => {
                warn!(
                    "terrain world: save to {} failed: {error}",
                    folder.display()
                );
                failed.write(WorldSaveFailed {
                    world: entity,
                    folder,
                    error,
                });
            }
        }
    }
    for request in requests.read() {
        let started = match worlds.get_mut(request.world) {
            Ok((_, mut world)) => {
                let _span = bevy::log::info_span!("chisel::world::save_request").entered();
                (world.bypass_change_detection()).start_save(&request.folder, &terrains)
            }
            Err(_) => Err(TerrainError::InvalidWorld {
                reason: format!("entity {} has no TerrainWorld to save", request.world),
            }),
        };
        if let Err(error) = started {
            failed.write(WorldSaveFailed {
                world: request.world,
                folder: request.folder.clone(),
                error,
            });
        }
    }
}

/// Whether a live chunk's octree, journal and undo history are at rest:
/// nothing queued or running would change them (sealing again at a
/// neighbour's points and building meshes do not).
fn content_settled(terrain: &Terrain) -> bool {
    let runtime = &terrain.runtime;
    (runtime.queue.iter()).all(|job| matches!(job, crate::terrain::jobs::Job::Reseal { .. }))
        && (runtime.task.is_none() || runtime.resealing)
        && (runtime.uploads.iter()).all(|u| u.reports.is_empty() && u.debris.is_empty())
}

/// The checksum a terrain file ends with (the XXH64 of the bytes before
/// it), `None` for bytes too short to hold one.
fn file_checksum(bytes: &[u8]) -> Option<u64> {
    let tail = bytes.get(bytes.len().checked_sub(8)?..)?;
    Some(u64::from_le_bytes(tail.try_into().ok()?))
}

/// Writes the `planned` chunk files into `folder` (created if missing),
/// each atomically unless it is known to hold those bytes already, then
/// removes the chunk files of chunks neither planned nor in `keep` and
/// syncs the folder. Stops at the first error: the files written before
/// it stay, and nothing is removed.
fn write_chunk_files(
    folder: &Path,
    planned: Vec<PlannedFile>,
    keep: &BTreeSet<ChunkCoord>,
) -> Result<Vec<FileOutcome>, TerrainError> {
    fs::create_dir_all(folder).map_err(|e| TerrainError::Io {
        message: format!("cannot create {}: {e}", folder.display()),
    })?;
    let mut keep = keep.clone();
    let mut outcome = Vec::with_capacity(planned.len());
    for file in planned {
        let bytes = match file.bytes {
            ChunkBytes::Live(record) => Arc::new(record.to_bytes()),
            ChunkBytes::Stored(bytes) => bytes,
        };
        let checksum = file_checksum(&bytes).ok_or_else(|| TerrainError::Io {
            message: format!("chunk {:?} has no terrain file bytes", file.coord),
        })?;
        let written = file.known != Some((bytes.len(), checksum));
        if written {
            let path = folder.join(TerrainWorld::chunk_file_name(file.coord));
            write_atomic(&path, |f| f.write_all(&bytes)).map_err(|e| TerrainError::Io {
                message: format!("cannot save {}: {e}", path.display()),
            })?;
        }
        keep.insert(file.coord);
        outcome.push(FileOutcome {
            coord: file.coord,
            len: bytes.len(),
            checksum,
            written,
        });
    }
    remove_stale_chunk_files(folder, &keep)?;
    outcome.sort_by_key(|f| f.coord);
    Ok(outcome)
}

/// A folder's record after a save that succeeded: `kept` and the files
/// the save wrote or found equal, those of live chunks with `live`'s mark.
fn record_of(
    kept: FolderRecord,
    files: &[FileOutcome],
    live: &BTreeMap<ChunkCoord, (Entity, Tick)>,
) -> FolderRecord {
    let mut record = kept;
    for file in files {
        let saved = SavedChunk {
            len: file.len,
            checksum: file.checksum,
            live: live.get(&file.coord).copied(),
        };
        record.insert(file.coord, saved);
    }
    record
}

/// Removes the chunk files in `folder` of chunks not in `keep`, then syncs
/// the folder so that the removals survive a crash.
fn remove_stale_chunk_files(
    folder: &Path,
    keep: &BTreeSet<ChunkCoord>,
) -> Result<(), TerrainError> {
    let io = |what: &Path, e: std::io::Error| TerrainError::Io {
        message: format!("cannot clean {}: {e}", what.display()),
    };
    let mut stale = Vec::new();
    for entry in fs::read_dir(folder).map_err(|e| io(folder, e))? {
        let entry = entry.map_err(|e| io(folder, e))?;
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        let coord = entry.file_name().to_str().and_then(parse_chunk_name);
        if let Some(coord) = coord
            && is_file
            && !keep.contains(&coord)
        {
            stale.push(entry.path());
        }
    }
    if stale.is_empty() {
        return Ok(());
    }
    stale.sort();
    for path in &stale {
        fs::remove_file(path).map_err(|e| io(path, e))?;
    }
    fs::File::open(folder)
        .and_then(|dir| dir.sync_all())
        .map_err(|e| io(folder, e))
}

/// The chunk of a file name `chunk_X_Z.chiselterrain`.
fn parse_chunk_name(name: &str) -> Option<ChunkCoord> {
    let rest = name
        .strip_prefix("chunk_")?
        .strip_suffix(TERRAIN_EXTENSION)?
        .strip_suffix('.')?;
    let (x, z) = rest.split_once('_')?;
    Some(ChunkCoord {
        x: x.parse().ok()?,
        z: z.parse().ok()?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunk_file_names_round_trip() {
        for coord in [
            ChunkCoord { x: 0, z: 0 },
            ChunkCoord { x: -3, z: 12 },
            ChunkCoord {
                x: i64::MIN,
                z: i64::MAX,
            },
        ] {
            let name = TerrainWorld::chunk_file_name(coord);
            assert_eq!(parse_chunk_name(&name), Some(coord), "{name}");
        }
        assert_eq!(parse_chunk_name("chunk_1.chiselterrain"), None);
        assert_eq!(parse_chunk_name("chunk_1_2.png"), None);
        assert_eq!(parse_chunk_name(".chunk_1_2.chiselterrain.9.0.tmp"), None);
    }
}
