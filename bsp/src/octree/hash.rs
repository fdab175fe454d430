//! A state hash of an octree's content: equal octrees (the same leaf
//! cells with the same stored BSPs) give equal hashes on every machine and
//! for any thread count, and an edit updates the hash from the cells it
//! changed only.
//!
//! Notation: for a leaf cell with key `(d, x, y, z)` and record `r` (the
//! leaf's bytes as an octree file stores them: a uniform label, or the
//! BSP's exact planes and nodes, see [`super::store`]),
//!
//! ```text
//! h(cell)  = XXH64( d u8 · x u32 · y u32 · z u32 · XXH64(r) u64 )   (little-endian)
//! sum      = Σ h(cell) over every leaf, mod 2^64
//! hash     = XXH64( origin 3×i64 · size_log2 u8 · sum u64 )
//! ```
//!
//! XXH64 is the file checksum's ([`super::store::checksum`], seed 0), so the
//! hash is fixed by this definition, not by a library version. The sum
//! makes the hash independent of the order cells are visited in and lets
//! an edit subtract the cells it replaced and add the new ones. It detects
//! accidental divergence (a desync between peers), not a forger: it is not
//! a cryptographic hash.

use std::collections::HashMap;

use super::cell::CellKey;
use super::store::{checksum, leaf_record};
use super::tree::{Leaf, Octree};

/// The hash of one leaf cell, `h(cell)` in the module notation.
#[must_use]
pub fn cell_hash(key: CellKey, leaf: &Leaf) -> u64 {
    let mut bytes = Vec::with_capacity(21);
    bytes.push(key.depth);
    for p in key.pos {
        bytes.extend_from_slice(&p.to_le_bytes());
    }
    bytes.extend_from_slice(&checksum(&leaf_record(leaf)).to_le_bytes());
    checksum(&bytes)
}

/// The state hash of an octree, kept up to date across edits: the hash of
/// every leaf cell and their sum.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StateHash {
    cells: HashMap<CellKey, u64>,
    sum: u64,
    cube: ([i64; 3], u8),
}

impl StateHash {
    /// The hash of every leaf of `octree`.
    #[must_use]
    pub fn of(octree: &Octree) -> Self {
        let mut out = Self {
            cube: (octree.origin(), octree.size_log2()),
            ..Self::default()
        };
        for (key, leaf) in octree.leaves() {
            let h = cell_hash(key, leaf);
            out.sum = out.sum.wrapping_add(h);
            out.cells.insert(key, h);
        }
        out
    }

    /// Brings the hash up to date with `octree` after a change confined to
    /// the cells `keys`: every leaf of the octree before or after the
    /// change that differs (for an edit, [`super::Changes::changed`] and
    /// [`super::Changes::removed`]; for an undo, the same keys of the edit
    /// undone). Cells not named must be unchanged.
    pub fn update<'a>(&mut self, octree: &Octree, keys: impl IntoIterator<Item = &'a CellKey>) {
        for key in keys {
            if let Some(old) = self.cells.remove(key) {
                self.sum = self.sum.wrapping_sub(old);
            }
            if let Some(leaf) = octree.leaf(*key) {
                let h = cell_hash(*key, leaf);
                self.sum = self.sum.wrapping_add(h);
                self.cells.insert(*key, h);
            }
        }
        self.cube = (octree.origin(), octree.size_log2());
    }

    /// The hash (`hash` in the module notation).
    #[must_use]
    pub fn value(&self) -> u64 {
        let mut bytes = Vec::with_capacity(33);
        for o in self.cube.0 {
            bytes.extend_from_slice(&o.to_le_bytes());
        }
        bytes.push(self.cube.1);
        bytes.extend_from_slice(&self.sum.to_le_bytes());
        checksum(&bytes)
    }

    /// Leaf cells hashed.
    #[must_use]
    pub fn cells(&self) -> usize {
        self.cells.len()
    }
}

impl Octree {
    /// The state hash of the octree's content ([`StateHash`]), computed
    /// from every leaf.
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        StateHash::of(self).value()
    }
}
