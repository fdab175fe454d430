//! Terrain files: a versioned, checked binary record of a terrain — its
//! grid, what it was built from and every carve since, and the octree
//! itself with the undo history.
//!
//! The octree is stored as an exact snapshot (the kernel's octree file,
//! [`chisel_bsp::octree::store`]), so loading costs about as much as reading
//! the leaves, whatever the number of carves: nothing is rebuilt or
//! replayed. The loaded octree is bit-identical to the saved one, and
//! saving it again gives the same bytes.
//!
//! What is saved:
//! - the grid (unit and origin) and the base, as built from;
//! - the journal of carves — a record of what was done, kept for tools and
//!   for rebuilding; it is not replayed on load;
//! - the undo history: every undo step's previous octree and its changed
//!   cells, so the loaded terrain undoes exactly as the saved one would
//!   have, up to the same depth; the previous octrees share their unchanged
//!   cells with the current one, in the file and after loading, so a deep
//!   history costs only the cells that the carves replaced;
//! - the undo depth limit ([`Terrain::with_max_undo`]);
//! - a world chunk's *seeds*: the cells its carves changed whose fall
//!   across chunk borders is still to be searched ([`super::world`],
//!   debris across chunk borders), sorted, each once. Loading puts them
//!   back, so a world that loads the chunk searches from them and a piece
//!   cut loose before the save falls after the load. A terrain outside a
//!   world has none.
//!
//! Not saved: carves still queued or running (save an idle terrain, see
//! [`Terrain::is_idle`]), meshes and cell entities (rebuilt on spawn).
//!
//! Layout (version 3, little-endian):
//!
//! ```text
//! magic    8 bytes  "CHISELTR"
//! version  u32      FORMAT_VERSION
//! unit f64, origin 3×f64
//! base     tag u8 (0 box, 1 heightfield, 2 triangles) + its fields
//! carves   u32 count, each: edit tag u8, label u8, pieces u32,
//!          per piece: points u32, per point 3×i64
//! max_undo u64
//! undo     u32 count, each: changed and removed cells, each a u32 count
//!          of keys (depth u8, pos 3×u32)
//! octrees  u64 length, then a kernel octree file of count + 1 snapshots:
//!          the octree before each undo step, oldest first, then the
//!          current octree
//! seeds    u32 count of keys (depth u8, pos 3×u32)
//! checksum u64      XXH64 of every byte before it
//!          (chisel_bsp::octree::store::checksum)
//! ```
//!
//! Version 2 files, the same without the seeds, load with none.
//!
//! Loading checks the magic, the version and the checksum first, then every
//! record; the octree snapshots are checked by the kernel (bit budgets of
//! every plane, every BSP a tree, the cells tiling the cube), and must
//! agree with the base's cube and the undo steps.
//!
//! Records go through the kernel's byte writer and bounds-checked reader
//! ([`chisel_bsp::octree::store::bytes`]), which the octree files use too:
//! a file cut short is [`TerrainError::Truncated`], never a panic.

use std::collections::VecDeque;
use std::io::Write;
use std::path::Path;

use chisel_bsp::octree::store::bytes::{Reader, Writer};
use chisel_bsp::octree::store::{checksum, snapshots_from_bytes, snapshots_to_bytes};
use chisel_bsp::octree::{CellBox, CellKey, Changes, Edit, Octree};
use chisel_bsp::tools::Quantization;

use super::atomic_write::write_atomic;
use super::base::{GridHeightfield, TerrainBase};
use super::component::{JournalEntry, Terrain, UndoStep};
use super::error::TerrainError;
pub(super) use super::file_values::{ReadTerrain, WriteTerrain};
use super::jobs::Runtime;
use super::tool::GridTool;

/// The first bytes of every terrain file.
pub const MAGIC: [u8; 8] = *b"CHISELTR";
/// The format version written by this build. Version 2, without the
/// seeds, is read too (with none); version 1 stored the carves only and
/// rebuilt the octree on load, and is not read.
pub const FORMAT_VERSION: u32 = 3;

/// The oldest format version read.
const OLDEST_READ_VERSION: u32 = 2;

/// Most points, triangles or carves accepted in one list (guards against
/// allocation bombs in corrupt files).
pub(super) const MAX_LIST: u32 = 1 << 28;

impl Terrain {
    /// The terrain as file bytes.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        self.to_bytes_with_seeds_taken(&[])
    }

    /// [`Terrain::to_bytes`] with `taken` among the seeds too: seeds of
    /// this world chunk that a search across chunk borders took out of it
    /// and has not applied yet (`world::debris`), still pending.
    pub(crate) fn to_bytes_with_seeds_taken(&self, taken: &[CellKey]) -> Vec<u8> {
        write_terrain(
            &self.quantization,
            &self.base,
            &self.journal,
            self.max_undo,
            &self.history,
            &self.octree,
            &file_seeds(&self.runtime.border_seeds, taken),
        )
    }

    /// The cells of this world chunk whose fall across chunk borders is
    /// still to be searched, not counting those a running search has
    /// taken (its file holds both).
    #[must_use]
    pub fn border_seeds(&self) -> &[CellKey] {
        &self.runtime.border_seeds
    }

    /// What [`Terrain::to_bytes`] writes, taken out of the terrain to be
    /// written later or on another thread ([`TerrainRecord::to_bytes`]).
    pub(crate) fn record_for_file(&self) -> TerrainRecord {
        TerrainRecord {
            quantization: self.quantization,
            base: self.base.clone(),
            journal: self.journal.clone(),
            max_undo: self.max_undo,
            history: self.history.clone(),
            octree: self.octree.clone(),
            seeds: file_seeds(&self.runtime.border_seeds, &[]),
        }
    }

    /// Writes the terrain to a file, whole or not at all: the bytes go to
    /// a new temporary file in the same folder (`.NAME.PID.N.tmp`), which
    /// is synced to disk and then renamed over `path`.
    ///
    /// # Errors
    /// [`TerrainError::Io`], naming the file, when any step fails (a
    /// missing or read-only folder, a full disk, `path` naming a folder).
    /// `path` is then as it was, an older file there intact, and the
    /// temporary file is removed.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), TerrainError> {
        let path = path.as_ref();
        let bytes = self.to_bytes();
        write_atomic(path, |file| file.write_all(&bytes)).map_err(|e| TerrainError::Io {
            message: format!("cannot save {}: {e}", path.display()),
        })
    }

    /// A terrain from file bytes: checks magic, version and checksum, then
    /// every record, and takes the stored octree and undo history as they
    /// are (nothing is replayed).
    ///
    /// # Errors
    /// [`TerrainError::BadMagic`], [`TerrainError::UnsupportedVersion`],
    /// [`TerrainError::Truncated`] or [`TerrainError::Corrupt`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Terrain, TerrainError> {
        let (mut record, version) =
            open_record(bytes, MAGIC, OLDEST_READ_VERSION..=FORMAT_VERSION)?;
        let r = &mut record;
        let Head {
            quantization,
            base,
            journal,
            max_undo,
            changes,
            snapshots: snapshot_bytes,
        } = read_head(r)?;
        let seeds = if version >= 3 { r.keys()? } else { Vec::new() };
        if r.remaining() != 0 {
            return Err(corrupt(format!(
                "{} unexpected bytes after the seeds",
                r.remaining()
            )));
        }
        let mut octrees = snapshots_from_bytes(snapshot_bytes)
            .map_err(|e| corrupt(format!("octree snapshot: {e}")))?;
        if octrees.len() != changes.len() + 1 {
            return Err(corrupt(format!(
                "{} octree snapshots for {} undo steps",
                octrees.len(),
                changes.len()
            )));
        }
        if changes.len() > max_undo || changes.len() > journal.len() {
            return Err(corrupt(format!(
                "{} undo steps for an undo limit of {max_undo} and {} carves",
                changes.len(),
                journal.len()
            )));
        }
        let octree = octrees.pop().ok_or_else(|| corrupt("no octree"))?;
        if base.cube() != (octree.origin(), octree.size_log2())
            || octrees
                .iter()
                .any(|o| (o.origin(), o.size_log2()) != base.cube())
        {
            return Err(corrupt("the octree's cube is not the base's cube"));
        }
        let history: VecDeque<UndoStep> = octrees
            .into_iter()
            .zip(changes)
            .map(|(before, changes)| UndoStep {
                before,
                changes,
                predicted: None,
                redo: Vec::new(),
            })
            .collect();
        Ok(Terrain {
            hash: chisel_bsp::octree::StateHash::of(&octree),
            last_request: None,
            octree,
            quantization,
            debris: Some(base.debris_config()),
            labels: base
                .labels()
                .into_iter()
                .chain(journal.iter().filter_map(|entry| match entry.edit {
                    Edit::Add(label) | Edit::Paint(label) => Some(label),
                    _ => None,
                }))
                .collect(),
            base: std::sync::Arc::new(base),
            journal,
            history,
            redo: Vec::new(),
            max_undo,
            runtime: Runtime {
                border_seeds: seeds,
                ..Runtime::default()
            },
            detached_across: false,
        })
    }

    /// Reads a terrain file.
    ///
    /// # Errors
    /// [`TerrainError::Io`] naming the file when it cannot be read;
    /// [`TerrainError::InFile`] naming it, with the error of
    /// [`Terrain::from_bytes`], when it is no valid terrain.
    pub fn load(path: impl AsRef<Path>) -> Result<Terrain, TerrainError> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| TerrainError::Io {
            message: format!("cannot read {}: {e}", path.display()),
        })?;
        Terrain::from_bytes(&bytes).map_err(|e| e.at_path(path))
    }
}

/// A terrain file's records before its seeds.
pub(super) struct Head<'a> {
    quantization: Quantization,
    base: TerrainBase,
    journal: Vec<JournalEntry>,
    max_undo: usize,
    changes: Vec<Changes>,
    /// The kernel octree file, not read yet.
    snapshots: &'a [u8],
}

/// Reads a terrain file's records from the grid up to its seeds (the
/// octree snapshots are taken as bytes), leaving `r` at the seeds.
pub(super) fn read_head<'a>(r: &mut Reader<'a>) -> Result<Head<'a>, TerrainError> {
    let unit = r.f64()?;
    let origin = [r.f64()?, r.f64()?, r.f64()?];
    let quantization = Quantization::new(unit, origin).map_err(corrupt)?;
    let base = read_base(r)?;
    let carves = r.list_len()?;
    let mut journal = Vec::with_capacity(carves.min(1 << 16));
    for _ in 0..carves {
        let tag = r.u8()?;
        let label = r.u8()?;
        let edit = match tag {
            0 => Edit::Subtract,
            1 => Edit::Add(label),
            2 => Edit::Paint(label),
            3 => Edit::Intersect,
            _ => return Err(corrupt(format!("unknown edit tag {tag}"))),
        };
        let pieces = r.list_len()?;
        let mut tool = GridTool {
            pieces: Vec::with_capacity(pieces.min(1 << 10)),
        };
        for _ in 0..pieces {
            let points = r.list_len()?;
            let mut piece = Vec::with_capacity(points.min(1 << 12));
            for _ in 0..points {
                piece.push(r.point()?);
            }
            tool.pieces.push(piece);
        }
        journal.push(JournalEntry { tool, edit });
    }
    let max_undo = usize::try_from(r.u64()?)
        .map_err(|_| corrupt("the undo depth limit is beyond this machine's range"))?;
    let steps = r.list_len()?;
    let mut changes = Vec::with_capacity(steps.min(1 << 10));
    for _ in 0..steps {
        changes.push(Changes {
            changed: r.keys()?,
            removed: r.keys()?,
        });
    }
    let length = usize::try_from(r.u64()?).unwrap_or(usize::MAX);
    let snapshots = r.bytes(length)?;
    Ok(Head {
        quantization,
        base,
        journal,
        max_undo,
        changes,
        snapshots,
    })
}

/// What a terrain file holds, owned: the octrees are persistent and
/// shared with the terrain (a clone copies no cell), the base is shared,
/// the journal and the undo steps' lists of changed cells are copied. So
/// taking it costs little on the main thread, and its bytes
/// ([`TerrainRecord::to_bytes`]) are those of [`Terrain::to_bytes`] at the
/// moment it was taken, wherever and whenever they are written.
#[derive(Clone)]
pub(crate) struct TerrainRecord {
    quantization: Quantization,
    base: std::sync::Arc<TerrainBase>,
    journal: Vec<JournalEntry>,
    max_undo: usize,
    history: VecDeque<UndoStep>,
    octree: Octree,
    /// The seeds, sorted, each once.
    seeds: Vec<CellKey>,
}

impl TerrainRecord {
    /// The record with `taken` among its seeds too: seeds of the chunk
    /// that a search across chunk borders took out of it and has not
    /// applied yet (`world::debris`), still pending.
    pub(crate) fn with_seeds_taken(mut self, taken: &[CellKey]) -> Self {
        self.seeds = file_seeds(&self.seeds, taken);
        self
    }

    /// The file bytes, as [`Terrain::to_bytes`] gave them when the record
    /// was taken (with the seeds added since).
    pub(crate) fn to_bytes(&self) -> Vec<u8> {
        write_terrain(
            &self.quantization,
            &self.base,
            &self.journal,
            self.max_undo,
            &self.history,
            &self.octree,
            &self.seeds,
        )
    }
}

/// The terrain file bytes of these parts (the layout in the module notes);
/// `seeds` sorted, each once.
fn write_terrain(
    quantization: &Quantization,
    base: &TerrainBase,
    journal: &[JournalEntry],
    max_undo: usize,
    history: &VecDeque<UndoStep>,
    octree: &Octree,
    seeds: &[CellKey],
) -> Vec<u8> {
    let mut w = Writer::new();
    w.bytes(&MAGIC);
    w.u32(FORMAT_VERSION);
    w.f64(quantization.unit());
    for o in quantization.origin() {
        w.f64(o);
    }
    write_base(&mut w, base);
    w.count(journal.len());
    for entry in journal {
        let (tag, label) = match entry.edit {
            Edit::Subtract => (0, 0),
            Edit::Add(l) => (1, l),
            Edit::Paint(l) => (2, l),
            Edit::Intersect => (3, 0),
        };
        w.u8(tag);
        w.u8(label);
        w.count(entry.tool.pieces.len());
        for piece in &entry.tool.pieces {
            w.count(piece.len());
            piece.iter().for_each(|&p| w.point(p));
        }
    }
    w.u64(max_undo as u64);
    w.count(history.len());
    for step in history {
        w.keys(&step.changes.changed);
        w.keys(&step.changes.removed);
    }
    let mut octrees: Vec<&Octree> = history.iter().map(|step| &step.before).collect();
    octrees.push(octree);
    let snapshots = snapshots_to_bytes(&octrees);
    w.u64(snapshots.len() as u64);
    w.bytes(&snapshots);
    w.keys(seeds);
    let sum = checksum(w.as_bytes());
    w.u64(sum);
    w.into_bytes()
}

/// Seeds as a file holds them: those of `a` and `b`, sorted, each once.
fn file_seeds(a: &[CellKey], b: &[CellKey]) -> Vec<CellKey> {
    let mut seeds: Vec<CellKey> = a.iter().chain(b).copied().collect();
    seeds.sort_unstable();
    seeds.dedup();
    seeds
}

/// Terrain file `bytes` with `seeds` among its seeds too: the bytes
/// [`Terrain::to_bytes_with_seeds_taken`] gives for the terrain they hold
/// with `seeds` taken (a version 2 file comes back as this version, which
/// only adds the seeds). Only the seeds and the checksum are written anew:
/// the octrees are not read.
///
/// # Errors
/// As [`Terrain::from_bytes`] for bytes that are not a terrain file.
pub(crate) fn bytes_with_seeds(bytes: &[u8], seeds: &[CellKey]) -> Result<Vec<u8>, TerrainError> {
    let (mut record, version) = open_record(bytes, MAGIC, OLDEST_READ_VERSION..=FORMAT_VERSION)?;
    read_head(&mut record)?;
    let at = record.at();
    let held = if version >= 3 {
        record.keys()?
    } else {
        Vec::new()
    };
    if record.remaining() != 0 {
        return Err(corrupt(format!(
            "{} unexpected bytes after the seeds",
            record.remaining()
        )));
    }
    let mut w = Writer::new();
    w.bytes(&bytes[..at]);
    w.overwrite(MAGIC.len(), &FORMAT_VERSION.to_le_bytes());
    w.keys(&file_seeds(&held, seeds));
    let sum = checksum(w.as_bytes());
    w.u64(sum);
    Ok(w.into_bytes())
}

/// The body of a record `magic, version u32, body, checksum u64`: checks
/// the magic, the version (one of `versions`; an unsupported one names
/// the newest as supported) and the checksum (XXH64 of every byte before
/// it); reads on from the body's first byte, and gives the version.
pub(super) fn open_record(
    bytes: &[u8],
    magic: [u8; 8],
    versions: std::ops::RangeInclusive<u32>,
) -> Result<(Reader<'_>, u32), TerrainError> {
    if bytes.len() < magic.len() || bytes[..magic.len()] != magic {
        return Err(TerrainError::BadMagic);
    }
    let mut r = Reader::new(bytes, magic.len());
    let found = r.u32()?;
    if !versions.contains(&found) {
        return Err(TerrainError::UnsupportedVersion {
            found,
            supported: *versions.end(),
        });
    }
    let body = bytes
        .len()
        .checked_sub(8)
        .filter(|&body| body >= r.at())
        .ok_or(TerrainError::Truncated { at: bytes.len() })?;
    let stored = u64::from_le_bytes(
        bytes[body..]
            .try_into()
            .map_err(|_| TerrainError::Truncated { at: body })?,
    );
    if checksum(&bytes[..body]) != stored {
        return Err(TerrainError::Corrupt {
            reason: "checksum mismatch".into(),
        });
    }
    Ok((Reader::new(&bytes[..body], r.at()), found))
}

pub(super) fn corrupt(e: impl ToString) -> TerrainError {
    TerrainError::Corrupt {
        reason: e.to_string(),
    }
}

pub(super) fn write_base(w: &mut Writer, base: &TerrainBase) {
    let (origin, size_log2) = base.cube();
    match base {
        TerrainBase::Box { solid, label, .. } => {
            w.u8(0);
            w.point(origin);
            w.u8(size_log2);
            w.point(solid.min);
            w.point(solid.max);
            w.u8(*label);
        }
        TerrainBase::Heightfield { field, .. } => {
            w.u8(1);
            w.point(origin);
            w.u8(size_log2);
            w.point(field.corner);
            w.u32(field.samples[0]);
            w.u32(field.samples[1]);
            w.i64(field.spacing);
            w.count(field.heights.len());
            field.heights.iter().for_each(|&h| w.i64(h));
            w.i64(field.bottom);
            w.u8(field.label);
            w.count(field.layers.len());
            for &(depth, label) in &field.layers {
                w.i64(depth);
                w.u8(label);
            }
        }
        TerrainBase::Triangles {
            triangles, label, ..
        } => {
            w.u8(2);
            w.point(origin);
            w.u8(size_log2);
            w.count(triangles.len());
            triangles.iter().flatten().for_each(|&p| w.point(p));
            w.u8(*label);
        }
    }
}

pub(super) fn read_base(r: &mut Reader) -> Result<TerrainBase, TerrainError> {
    let tag = r.u8()?;
    let origin = r.point()?;
    let size_log2 = r.u8()?;
    match tag {
        0 => Ok(TerrainBase::Box {
            origin,
            size_log2,
            solid: CellBox {
                min: r.point()?,
                max: r.point()?,
            },
            label: r.u8()?,
        }),
        1 => {
            let corner = r.point()?;
            let samples = [r.u32()?, r.u32()?];
            let spacing = r.i64()?;
            let n = r.list_len()?;
            let mut heights = Vec::with_capacity(n.min(1 << 20));
            for _ in 0..n {
                heights.push(r.i64()?);
            }
            let bottom = r.i64()?;
            let label = r.u8()?;
            let layers_len = r.list_len()?;
            let mut layers = Vec::with_capacity(layers_len.min(256));
            for _ in 0..layers_len {
                layers.push((r.i64()?, r.u8()?));
            }
            Ok(TerrainBase::Heightfield {
                origin,
                size_log2,
                field: GridHeightfield {
                    corner,
                    samples,
                    spacing,
                    heights,
                    bottom,
                    label,
                    layers,
                },
            })
        }
        2 => {
            let n = r.list_len()?;
            let mut triangles = Vec::with_capacity(n.min(1 << 20));
            for _ in 0..n {
                triangles.push([r.point()?, r.point()?, r.point()?]);
            }
            Ok(TerrainBase::Triangles {
                origin,
                size_log2,
                triangles,
                label: r.u8()?,
            })
        }
        _ => Err(corrupt(format!("unknown base tag {tag}"))),
    }
}

#[cfg(test)]
mod tests {
    use std::fs;
    use std::io;
    use std::path::PathBuf;

    use super::*;
    use chisel_bsp::octree::OctreeConfig;

    /// A fresh folder for one test.
    fn folder(tag: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("bevy_chisel_save_{tag}_{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("a temporary folder");
        dir
    }

    /// The temporary files left in `dir`.
    fn leftovers(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .expect("a readable folder")
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|name| name.ends_with(".tmp"))
            .collect()
    }

    fn terrain(height: i64) -> Terrain {
        let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
        let base = TerrainBase::Box {
            origin: [0; 3],
            size_log2: 5,
            solid: CellBox {
                min: [0; 3],
                max: [16, height, 16],
            },
            label: 1,
        };
        Terrain::from_base(grid, base, OctreeConfig::default()).expect("valid box")
    }

    /// A grid box tool from `min` to `max`.
    fn box_tool(min: [i64; 3], max: [i64; 3]) -> GridTool {
        let corners = (0..8)
            .map(|i| {
                let pick = |a: usize| if i >> a & 1 == 0 { min[a] } else { max[a] };
                [pick(0), pick(1), pick(2)]
            })
            .collect();
        GridTool {
            pieces: vec![corners],
        }
    }

    #[test]
    fn a_record_writes_the_bytes_of_the_moment_it_was_taken() {
        let mut terrain = terrain(8);
        let carve = |t: &mut Terrain, x: i64| {
            let tool = box_tool([x, 2, 2], [x + 3, 6, 6]);
            t.apply_now(&tool, Edit::Subtract).expect("carve applies");
        };
        carve(&mut terrain, 1);
        carve(&mut terrain, 6);
        let then = terrain.to_bytes();
        let record = terrain.record_for_file();
        // Later carves and an undo change the terrain, not the record.
        carve(&mut terrain, 11);
        terrain.undo_now().expect("undoes");
        terrain.undo_now().expect("undoes");
        assert!(terrain.to_bytes() != then);
        assert!(record.to_bytes() == then);
        let back = Terrain::from_bytes(&record.to_bytes()).expect("loads");
        assert_eq!(back.journal().len(), 2);
        assert_eq!(back.undo_depth(), 2);
        assert_eq!(
            back.state_hash(),
            Terrain::from_bytes(&then).expect("loads").state_hash()
        );
    }

    #[test]
    fn seeds_added_to_file_bytes_are_the_bytes_of_the_terrain_with_them() {
        let mut terrain = terrain(8);
        let tool = box_tool([1, 2, 2], [4, 6, 6]);
        terrain
            .apply_now(&tool, Edit::Subtract)
            .expect("carve applies");
        let key = |depth, x| CellKey {
            depth,
            pos: [x, 0, 0],
        };
        let plain = terrain.to_bytes();
        terrain.runtime.border_seeds = vec![key(3, 1), key(2, 0)];
        let more = [key(2, 0), key(4, 9)];
        let bytes = terrain.to_bytes();
        assert!(
            bytes_with_seeds(&bytes, &more).expect("a file")
                == terrain.to_bytes_with_seeds_taken(&more)
        );
        assert!(bytes_with_seeds(&bytes, &[]).expect("a file") == bytes);
        // Version 2, without the seeds' count, comes back as version 3.
        let mut old = plain[..plain.len() - 12].to_vec();
        old[8..12].copy_from_slice(&2u32.to_le_bytes());
        let sum = checksum(&old);
        old.extend_from_slice(&sum.to_le_bytes());
        terrain.runtime.border_seeds.clear();
        assert!(Terrain::from_bytes(&old).is_ok());
        assert!(
            bytes_with_seeds(&old, &more).expect("a file")
                == terrain.to_bytes_with_seeds_taken(&more)
        );
        let mut bad = bytes.clone();
        bad[40] ^= 1;
        assert!(matches!(
            bytes_with_seeds(&bad, &more),
            Err(TerrainError::Corrupt { .. })
        ));
    }

    #[test]
    fn a_failed_write_keeps_the_old_file_and_leaves_no_temporary_file() {
        let dir = folder("failed_write");
        let path = dir.join("level.chiselterrain");
        let old = terrain(4).to_bytes();
        fs::write(&path, &old).expect("the old file");
        // A disk that fills up halfway through the new file.
        let error = write_atomic(&path, |file| {
            file.write_all(&terrain(8).to_bytes()[..100])?;
            Err(io::Error::new(io::ErrorKind::StorageFull, "no space left"))
        })
        .expect_err("the write fails");
        assert_eq!(error.kind(), io::ErrorKind::StorageFull);
        assert!(fs::read(&path).expect("the old file") == old);
        assert_eq!(leftovers(&dir), Vec::<String>::new());
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn save_replaces_the_whole_file() {
        let dir = folder("replace");
        let path = dir.join("level.chiselterrain");
        terrain(4).save(&path).expect("first save");
        let newer = terrain(9);
        newer.save(&path).expect("second save");
        assert!(fs::read(&path).expect("saved") == newer.to_bytes());
        assert_eq!(
            Terrain::load(&path).expect("loads").state_hash(),
            newer.state_hash()
        );
        assert_eq!(leftovers(&dir), Vec::<String>::new());
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_failed_save_is_an_error_naming_the_file_and_changes_nothing() {
        let dir = folder("refused");
        // A folder that does not exist: nothing can be created.
        let missing = dir.join("no such folder").join("level.chiselterrain");
        match terrain(4).save(&missing) {
            Err(TerrainError::Io { message }) => {
                assert!(message.contains("no such folder"), "{message}");
            }
            other => panic!("expected an I/O error, got {other:?}"),
        }
        assert!(!dir.join("no such folder").exists());
        // A path naming a folder: the new file is written and synced, the
        // rename fails, and the temporary file goes; the folder and what
        // is in it stay.
        let occupied = dir.join("occupied");
        fs::create_dir(&occupied).expect("a folder");
        fs::write(occupied.join("keep"), b"kept").expect("a file inside");
        assert!(matches!(
            terrain(4).save(&occupied),
            Err(TerrainError::Io { .. })
        ));
        assert_eq!(fs::read(occupied.join("keep")).expect("kept"), b"kept");
        assert_eq!(leftovers(&dir), Vec::<String>::new());
        // No file name at all.
        assert!(matches!(
            terrain(4).save(dir.join("..")),
            Err(TerrainError::Io { .. })
        ));
        let _ = fs::remove_dir_all(&dir);
    }
}
