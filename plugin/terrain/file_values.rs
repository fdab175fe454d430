//! The terrain files' values (an `f64`, a grid point, a list of cell
//! keys) on top of the kernel's byte writer and bounds-checked reader
//! ([`chisel_bsp::octree::store::bytes`]), shared by terrain files
//! ([`super::file`]) and snapshots ([`super::snapshot`]).

use chisel_bsp::octree::CellKey;
use chisel_bsp::octree::store::bytes::{ReadError, Reader, Writer};

use super::error::TerrainError;
use super::file::{MAX_LIST, corrupt};

/// A read of the shared byte reader that failed, as a terrain error: a
/// value past the end is [`TerrainError::Truncated`] at the value's offset.
impl From<ReadError> for TerrainError {
    fn from(e: ReadError) -> Self {
        match e {
            ReadError::Truncated { at, .. } => TerrainError::Truncated { at },
            ReadError::CountTooLarge { .. } => corrupt(e),
        }
    }
}

/// The terrain files' values on top of the kernel's byte writer.
pub(super) trait WriteTerrain {
    /// An `f64` as its bits.
    fn f64(&mut self, v: f64);
    /// A grid point.
    fn point(&mut self, p: [i64; 3]);
    /// A list of cell keys, counted.
    fn keys(&mut self, keys: &[CellKey]);
}

impl WriteTerrain for Writer {
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn point(&mut self, p: [i64; 3]) {
        p.iter().for_each(|&c| self.i64(c));
    }
    fn keys(&mut self, keys: &[CellKey]) {
        self.count(keys.len());
        for key in keys {
            self.u8(key.depth);
            key.pos.iter().for_each(|&p| self.u32(p));
        }
    }
}

/// The terrain files' values on top of the kernel's byte reader.
pub(super) trait ReadTerrain {
    /// An `f64` from its bits.
    fn f64(&mut self) -> Result<f64, TerrainError>;
    /// The length of a list, at most [`MAX_LIST`].
    fn list_len(&mut self) -> Result<usize, TerrainError>;
    /// A grid point.
    fn point(&mut self) -> Result<[i64; 3], TerrainError>;
    /// Cell keys; each must name a cell of a cube (position below
    /// `2^depth`, depth at most 27, the largest cube).
    fn keys(&mut self) -> Result<Vec<CellKey>, TerrainError>;
}

impl ReadTerrain for Reader<'_> {
    fn f64(&mut self) -> Result<f64, TerrainError> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn list_len(&mut self) -> Result<usize, TerrainError> {
        let n = self.u32()?;
        if n > MAX_LIST {
            return Err(corrupt(format!("list of {n} entries is implausibly long")));
        }
        Ok(n as usize)
    }
    fn point(&mut self) -> Result<[i64; 3], TerrainError> {
        Ok([self.i64()?, self.i64()?, self.i64()?])
    }
    fn keys(&mut self) -> Result<Vec<CellKey>, TerrainError> {
        let n = self.list_len()?;
        let mut keys = Vec::with_capacity(n.min(1 << 16));
        for _ in 0..n {
            let key = CellKey {
                depth: self.u8()?,
                pos: [self.u32()?, self.u32()?, self.u32()?],
            };
            if key.depth > 27 || key.pos.iter().any(|&p| u64::from(p) >> key.depth != 0) {
                return Err(corrupt(format!("{key:?} names no cell")));
            }
            keys.push(key);
        }
        Ok(keys)
    }
}
