//! The chunk files of a saved world on disk ([`super::store`]): writing
//! the planned files, each atomically, removing the stale ones, the
//! file names, and reading a saved world's files back.

use std::collections::BTreeSet;
use std::fs;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use super::super::asset::TERRAIN_EXTENSION;
use super::super::atomic_write::write_atomic;
use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::super::file::TerrainRecord;
use super::{ChunkCoord, TerrainWorld};

/// What the task did with one planned chunk file.
pub(super) struct FileOutcome {
    pub(super) coord: ChunkCoord,
    pub(super) len: usize,
    pub(super) checksum: u64,
    pub(super) written: bool,
}

/// Where a planned chunk file's bytes come from.
pub(super) enum ChunkBytes {
    /// A live chunk, serialized by the task.
    Live(Box<TerrainRecord>),
    /// A stored chunk's bytes.
    Stored(Arc<Vec<u8>>),
}

/// One chunk file to write unless the file holds it already.
pub(super) struct PlannedFile {
    pub(super) coord: ChunkCoord,
    pub(super) bytes: ChunkBytes,
    /// Length and checksum of what the file is known to hold.
    pub(super) known: Option<(usize, u64)>,
}

/// The checksum a terrain file ends with (the XXH64 of the bytes before
/// it), `None` for bytes too short to hold one.
pub(super) fn file_checksum(bytes: &[u8]) -> Option<u64> {
    let tail = bytes.get(bytes.len().checked_sub(8)?..)?;
    Some(u64::from_le_bytes(tail.try_into().ok()?))
}

/// Writes the `planned` chunk files into `folder` (created if missing),
/// each atomically unless it is known to hold those bytes already, then
/// removes the chunk files of chunks neither planned nor in `keep` and
/// syncs the folder. Stops at the first error: the files written before
/// it stay, and nothing is removed.
pub(super) fn write_chunk_files(
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

/// Removes the chunk files in `folder` of chunks not in `keep`, then syncs
/// the folder so that the removals survive a crash.
pub(super) fn remove_stale_chunk_files(
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
pub(super) fn parse_chunk_name(name: &str) -> Option<ChunkCoord> {
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

impl TerrainWorld {
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
