//! Terrain files: a versioned binary record of a terrain's grid, octree
//! settings, base and carves.
//!
//! The octree is a pure function of those (the kernel is exact and
//! deterministic), so loading rebuilds the base and replays the carves: the
//! loaded octree is bit-identical to the saved one, and saving it again
//! gives the same bytes. The last carves come back as undo steps.
//!
//! Layout (little-endian):
//!
//! ```text
//! magic    8 bytes  "CHISELTR"
//! version  u32      FORMAT_VERSION
//! unit f64, origin 3×f64, max_bsp_nodes u32, max_depth u8
//! base     tag u8 (0 box, 1 heightfield, 2 triangles) + its fields
//! carves   u32 count, each: edit tag u8, label u8, pieces u32,
//!          per piece: points u32, per point 3×i64
//! checksum u64      FNV-1a of every byte before it
//! ```

use std::path::Path;

use chisel_bsp::octree::{CellBox, Edit, OctreeConfig};
use chisel_bsp::tools::Quantization;

use super::base::{GridHeightfield, TerrainBase};
use super::component::{JournalEntry, Terrain};
use super::error::TerrainError;
use super::tool::GridTool;

/// The first bytes of every terrain file.
pub const MAGIC: [u8; 8] = *b"CHISELTR";
/// The format version written and read by this build.
pub const FORMAT_VERSION: u32 = 1;

/// Most points, triangles or carves accepted in one list (guards against
/// allocation bombs in corrupt files).
const MAX_LIST: u32 = 1 << 28;

impl Terrain {
    /// The terrain as file bytes.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer(Vec::new());
        w.0.extend_from_slice(&MAGIC);
        w.u32(FORMAT_VERSION);
        w.f64(self.quantization.unit());
        for o in self.quantization.origin() {
            w.f64(o);
        }
        let config = self.octree.config();
        w.u32(u32::try_from(config.max_bsp_nodes).unwrap_or(u32::MAX));
        w.u8(config.max_depth);
        write_base(&mut w, &self.base);
        w.len(self.journal.len());
        for entry in &self.journal {
            let (tag, label) = match entry.edit {
                Edit::Subtract => (0, 0),
                Edit::Add(l) => (1, l),
                Edit::Paint(l) => (2, l),
                Edit::Intersect => (3, 0),
            };
            w.u8(tag);
            w.u8(label);
            w.len(entry.tool.pieces.len());
            for piece in &entry.tool.pieces {
                w.len(piece.len());
                piece.iter().for_each(|&p| w.point(p));
            }
        }
        let sum = fnv1a(&w.0);
        w.u64(sum);
        w.0
    }

    /// Writes the terrain to a file.
    ///
    /// # Errors
    /// [`TerrainError::Io`].
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), TerrainError> {
        Ok(std::fs::write(path, self.to_bytes())?)
    }

    /// A terrain from file bytes: checks magic, version and checksum, then
    /// rebuilds the base and replays the carves.
    ///
    /// # Errors
    /// [`TerrainError::BadMagic`], [`TerrainError::UnsupportedVersion`],
    /// [`TerrainError::Truncated`] or [`TerrainError::Corrupt`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Terrain, TerrainError> {
        if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
            return Err(TerrainError::BadMagic);
        }
        let mut r = Reader { bytes, at: 8 };
        let version = r.u32()?;
        if version != FORMAT_VERSION {
            return Err(TerrainError::UnsupportedVersion {
                found: version,
                supported: FORMAT_VERSION,
            });
        }
        let body = bytes
            .len()
            .checked_sub(8)
            .ok_or(TerrainError::Truncated { at: bytes.len() })?;
        if body < r.at {
            return Err(TerrainError::Truncated { at: bytes.len() });
        }
        let stored = u64::from_le_bytes(
            bytes[body..]
                .try_into()
                .map_err(|_| TerrainError::Truncated { at: body })?,
        );
        if fnv1a(&bytes[..body]) != stored {
            return Err(TerrainError::Corrupt {
                reason: "checksum mismatch".into(),
            });
        }
        let r = &mut Reader {
            bytes: &bytes[..body],
            at: r.at,
        };
        let unit = r.f64()?;
        let origin = [r.f64()?, r.f64()?, r.f64()?];
        let quantization = Quantization::new(unit, origin).map_err(corrupt)?;
        let config = OctreeConfig {
            max_bsp_nodes: r.u32()? as usize,
            max_depth: r.u8()?,
        };
        let base = read_base(r)?;
        let carves = r.len()?;
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
            let pieces = r.len()?;
            let mut tool = GridTool {
                pieces: Vec::with_capacity(pieces.min(1 << 10)),
            };
            for _ in 0..pieces {
                let points = r.len()?;
                let mut piece = Vec::with_capacity(points.min(1 << 12));
                for _ in 0..points {
                    piece.push(r.point()?);
                }
                tool.pieces.push(piece);
            }
            journal.push(JournalEntry { tool, edit });
        }
        if r.at != r.bytes.len() {
            return Err(corrupt(format!(
                "{} unexpected bytes after the last carve",
                r.bytes.len() - r.at
            )));
        }
        let mut terrain = Terrain::from_base(quantization, base, config).map_err(corrupt)?;
        for (k, entry) in journal.into_iter().enumerate() {
            terrain
                .apply_now(&entry.tool, entry.edit)
                .map_err(|e| corrupt(format!("carve {k} does not replay: {e}")))?;
        }
        Ok(terrain)
    }

    /// Reads a terrain file.
    ///
    /// # Errors
    /// [`TerrainError::Io`] or as [`Terrain::from_bytes`].
    pub fn load(path: impl AsRef<Path>) -> Result<Terrain, TerrainError> {
        Terrain::from_bytes(&std::fs::read(path)?)
    }
}

fn corrupt(e: impl ToString) -> TerrainError {
    TerrainError::Corrupt {
        reason: e.to_string(),
    }
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn write_base(w: &mut Writer, base: &TerrainBase) {
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
            w.len(field.heights.len());
            field.heights.iter().for_each(|&h| w.i64(h));
            w.i64(field.bottom);
            w.u8(field.label);
            w.len(field.layers.len());
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
            w.len(triangles.len());
            triangles.iter().flatten().for_each(|&p| w.point(p));
            w.u8(*label);
        }
    }
}

fn read_base(r: &mut Reader) -> Result<TerrainBase, TerrainError> {
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
            let n = r.len()?;
            let mut heights = Vec::with_capacity(n.min(1 << 20));
            for _ in 0..n {
                heights.push(r.i64()?);
            }
            let bottom = r.i64()?;
            let label = r.u8()?;
            let layers_len = r.len()?;
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
            let n = r.len()?;
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

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn len(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }
    fn point(&mut self, p: [i64; 3]) {
        p.iter().for_each(|&c| self.i64(c));
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], TerrainError> {
        let end = self.at + N;
        let slice = self
            .bytes
            .get(self.at..end)
            .ok_or(TerrainError::Truncated { at: self.at })?;
        self.at = end;
        slice
            .try_into()
            .map_err(|_| TerrainError::Truncated { at: self.at })
    }
    fn u8(&mut self) -> Result<u8, TerrainError> {
        Ok(self.take::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32, TerrainError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn i64(&mut self) -> Result<i64, TerrainError> {
        Ok(i64::from_le_bytes(self.take()?))
    }
    fn f64(&mut self) -> Result<f64, TerrainError> {
        Ok(f64::from_le_bytes(self.take()?))
    }
    fn len(&mut self) -> Result<usize, TerrainError> {
        let n = self.u32()?;
        if n > MAX_LIST {
            return Err(corrupt(format!("list of {n} entries is implausibly long")));
        }
        Ok(n as usize)
    }
    fn point(&mut self) -> Result<[i64; 3], TerrainError> {
        Ok([self.i64()?, self.i64()?, self.i64()?])
    }
}
