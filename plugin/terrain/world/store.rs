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

use std::collections::BTreeSet;
use std::fs;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use bevy::prelude::*;

use super::super::asset::TERRAIN_EXTENSION;
use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::super::file::write_atomic;
use super::{Chunk, ChunkCoord, TerrainWorld};

impl TerrainWorld {
    /// The file name of chunk `coord` in a saved world.
    #[must_use]
    pub fn chunk_file_name(coord: ChunkCoord) -> String {
        format!("chunk_{}_{}.{TERRAIN_EXTENSION}", coord.x, coord.z)
    }

    /// Writes every edited chunk (live ones through `terrain_of`, which
    /// gives a chunk entity's [`Terrain`], and stored ones) into `folder`,
    /// one file each, creating the folder; returns the chunks written.
    /// Then removes the folder's chunk files of chunks that are not edited
    /// now (see the module notes); a live chunk whose terrain `terrain_of`
    /// does not give keeps its file. Other files are left alone.
    ///
    /// # Errors
    /// [`TerrainError::WorldNotIdle`] while a carve waits for a chunk
    /// (deferred ones too: [`TerrainWorld::build_deferred`]) or
    /// an edited chunk has work in progress (nothing is written then);
    /// [`TerrainError::Io`] naming the file that could not be written or
    /// removed (files written before it stay, and nothing is removed
    /// before every file is written).
    pub fn save<'a>(
        &self,
        folder: impl AsRef<Path>,
        terrain_of: impl Fn(Entity) -> Option<&'a Terrain>,
    ) -> Result<Vec<ChunkCoord>, TerrainError> {
        let folder = folder.as_ref();
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
        fs::create_dir_all(folder).map_err(|e| TerrainError::Io {
            message: format!("cannot create {}: {e}", folder.display()),
        })?;
        for (coord, bytes) in &files {
            let path = folder.join(Self::chunk_file_name(*coord));
            write_atomic(&path, |file| file.write_all(bytes)).map_err(|e| TerrainError::Io {
                message: format!("cannot save {}: {e}", path.display()),
            })?;
        }
        let written: Vec<ChunkCoord> = files.into_iter().map(|(c, _)| c).collect();
        let keep: BTreeSet<ChunkCoord> = written.iter().copied().chain(unknown).collect();
        remove_stale_chunk_files(folder, &keep)?;
        Ok(written)
    }

    /// Reads the edited chunks saved in `folder` ([`TerrainWorld::save`])
    /// into this world's store: they stream in from them exactly as saved.
    /// Files whose names are not chunk files are ignored.
    ///
    /// # Errors
    /// [`TerrainError::Io`] when the folder or a file cannot be read; as
    /// [`Terrain::from_bytes`] for a bad file; [`TerrainError::InvalidWorld`]
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
            let terrain = Terrain::from_bytes(&bytes)?;
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
