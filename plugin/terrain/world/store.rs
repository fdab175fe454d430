//! A world's edits on disk: one terrain file per edited chunk
//! (`chunk_X_Z.chiselterrain`, the format of [`super::super::file`]), and
//! nothing for chunks nobody carved — they are rebuilt from the source.
//!
//! Saving writes each file whole or not at all (temporary file, sync,
//! rename, as [`Terrain::save`]). Loading checks that every file belongs
//! to this world: the same grid, and the base this world's source gives
//! for that chunk, so a chunk restored from its file is bit-identical to
//! the saved one and meets its unedited neighbours exactly.

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
    /// Other files in the folder are left alone.
    ///
    /// # Errors
    /// [`TerrainError::WorldNotIdle`] while a carve waits for a chunk or
    /// an edited chunk has work in progress (nothing is written then);
    /// [`TerrainError::Io`] naming the file that could not be written
    /// (files written before it stay).
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
        for (coord, state) in &self.chunks {
            let Chunk::Live(entity) = state else {
                continue;
            };
            let Some(terrain) = terrain_of(*entity) else {
                continue;
            };
            if terrain.journal().is_empty() && terrain.undo_depth() == 0 {
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
        Ok(files.into_iter().map(|(c, _)| c).collect())
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
            found.push((coord, Arc::new(bytes)));
        }
        self.stored.extend(found);
        self.stats.stored = self.stored.len();
        self.stats.stored_bytes = self.stored.values().map(|b| b.len()).sum();
        Ok(self)
    }
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
