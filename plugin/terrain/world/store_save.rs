//! Background saves ([`SaveWorld`]): planning a save in the frame it
//! starts, writing it on the I/O pool, and reporting it (the rules are in
//! the [`super::store`] module docs).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use bevy::ecs::change_detection::Tick;
use bevy::prelude::*;
use bevy::tasks::IoTaskPool;
use bevy::tasks::futures::check_ready;

use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::store::{FolderRecord, RunningSave, SaveWorld, SavedChunk, WorldSaveFailed, WorldSaved};
use super::store_files::{ChunkBytes, FileOutcome, PlannedFile, file_checksum, write_chunk_files};
use super::{Chunk, ChunkCoord, TerrainWorld};

impl TerrainWorld {
    /// Starts the waiting [`SaveWorld`] requests' saves in turn, oldest
    /// first, while none is being written and this frame holds a whole
    /// state (or, after the settle frames, a consistent one); counts the
    /// frame against the oldest otherwise ([module
    /// docs](self)). Returns the requests that gave up, with why.
    fn start_waiting_saves(
        &mut self,
        terrains: &Query<Ref<Terrain>>,
    ) -> Vec<(PathBuf, TerrainError)> {
        let mut gave_up = Vec::new();
        let mut holding = false;
        while self.saves.running.is_none() {
            let Some(mut next) = self.saves.waiting.pop_front() else {
                break;
            };
            // After `settle` frames of its turn with no whole state, a
            // consistent one does.
            let cut = next.refused >= self.saves.settle;
            match self.start_save(&next.folder, terrains, cut) {
                Ok(()) => {}
                Err(error @ TerrainError::WorldNotIdle { .. }) => {
                    next.refused += 1;
                    if next.refused > self.saves.max_wait {
                        gave_up.push((next.folder, error));
                    } else {
                        holding = cut && self.hold_for_cut(&mut next.held);
                        self.saves.waiting.push_front(next);
                        break;
                    }
                }
                Err(error) => gave_up.push((next.folder, error)),
            }
        }
        if !holding {
            self.saves.barrier = None;
        }
        gave_up
    }

    /// Plans a background save into `folder` ([module docs](super::store)) and
    /// starts its task: of a whole state, or with `cut` of a consistent
    /// one when this frame holds no whole state.
    ///
    /// # Errors
    /// [`TerrainError::WorldSaveRunning`] while a save is being written,
    /// [`TerrainError::WorldNotIdle`] when this frame holds no whole state
    /// (with `cut`, no consistent one); nothing is started then.
    fn start_save(
        &mut self,
        folder: &Path,
        terrains: &Query<Ref<Terrain>>,
        cut: bool,
    ) -> Result<(), TerrainError> {
        self.saves.check_not_running()?;
        let left_out = match self.check_whole(terrains) {
            Ok(()) => 0,
            Err(_) if cut => self.check_consistent(terrains)?,
            Err(error) => return Err(error),
        };
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
            if !self.chunk_edited(coord, &terrain) {
                continue;
            }
            let mark = (entity, terrain.last_changed());
            let taken = self.seeds_taken(entity);
            let seeded = !taken.is_empty() || !terrain.runtime.border_seeds.is_empty();
            match record.get(&coord) {
                Some(saved) if saved.live == Some(mark) && !seeded => {
                    kept.insert(coord, *saved);
                    keep.insert(coord);
                    unchanged_live += 1;
                }
                saved => {
                    live.insert(coord, (!seeded).then_some(mark));
                    let file = terrain.record_for_file().with_seeds_taken(taken);
                    planned.push(PlannedFile {
                        coord,
                        bytes: ChunkBytes::Live(Box::new(file)),
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
            left_out,
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
                    left_out: running.left_out,
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
}

/// Reports the saves whose tasks are done, reads [`SaveWorld`]s into
/// their worlds' waiting requests and starts those whose turn it is in a
/// frame that holds a whole (or consistent) state, or gives them up ([module docs](super::store)).
/// Runs after the carve systems.
pub fn save_worlds(
    mut requests: MessageReader<SaveWorld>,
    mut worlds: Query<(Entity, &mut TerrainWorld)>,
    terrains: Query<Ref<Terrain>>,
    mut saved: MessageWriter<WorldSaved>,
    mut failed: MessageWriter<WorldSaveFailed>,
) {
    let _span = bevy::log::info_span!("chisel::world::save_worlds").entered();
    // Bookkeeping, all of it: the worlds' chunks and edits are as they
    // were, so no world is marked changed.
    for (entity, mut world) in &mut worlds {
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
        match worlds.get_mut(request.world) {
            Ok((_, mut world)) => {
                (world.bypass_change_detection().saves).enqueue(&request.folder);
            }
            Err(_) => {
                failed.write(WorldSaveFailed {
                    world: request.world,
                    folder: request.folder.clone(),
                    error: TerrainError::InvalidWorld {
                        reason: format!("entity {} has no TerrainWorld to save", request.world),
                    },
                });
            }
        }
    }
    for (entity, mut world) in &mut worlds {
        if !world.save_waiting() || world.is_saving() {
            continue;
        }
        let _span = bevy::log::info_span!("chisel::world::save_request").entered();
        for (folder, error) in world
            .bypass_change_detection()
            .start_waiting_saves(&terrains)
        {
            warn!(
                "terrain world: save to {} gave up: {error}",
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

/// A folder's record after a save that succeeded: `kept` and the files
/// the save wrote or found equal, those of live chunks with `live`'s mark.
pub(super) fn record_of(
    kept: FolderRecord,
    files: &[FileOutcome],
    live: &BTreeMap<ChunkCoord, Option<(Entity, Tick)>>,
) -> FolderRecord {
    let mut record = kept;
    for file in files {
        let saved = SavedChunk {
            len: file.len,
            checksum: file.checksum,
            live: live.get(&file.coord).copied().flatten(),
        };
        record.insert(file.coord, saved);
    }
    record
}
