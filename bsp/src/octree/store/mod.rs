//! Octree files: an exact, versioned, checked binary format for octrees of
//! BSPs.
//!
//! Every plane is stored as its exact integer coefficients, so a file reads
//! back into a bit-identical octree: the same cells, the same BSP nodes over
//! the same planes, the same labels — and the same results from every later
//! edit. A mesh export (OBJ, PLY, glTF) rounds vertices to floats and cannot
//! promise that.
//!
//! One file holds one or more octrees ("snapshots", e.g. an undo history)
//! over one table of BSPs: a BSP shared by several snapshots (the same
//! [`Arc`]) is stored once and is shared again after loading.
//!
//! ## Layout (version 1, little-endian)
//!
//! ```text
//! magic        8 bytes  "CHISELOC"                               MAGIC
//! version      u32      1                                        FORMAT_VERSION
//! length       u64      bytes in the whole file, checksum included
//! bsp_count    u32
//!   per BSP:   plane_count u32, node_count u32,
//!              planes: a i64, b i64, c i64, d i128               (40 bytes each)
//!              nodes:  tag u8 = 0 (leaf): label u8
//!                      tag u8 = 1 (split): plane u32, below u32, above u32
//! octree_count u32      at least 1
//!   per octree: origin 3×i64, size_log2 u8,
//!              max_bsp_nodes u64, max_depth u8                   (OctreeConfig)
//!              leaf_count u32
//!              per leaf: depth u8, pos 3×u32                     (CellKey)
//!                        tag u8 = 0 (uniform): label u8
//!                        tag u8 = 1 (BSP): index u32 into the BSP table
//! checksum     u64      XXH64 (seed 0) of every byte before it
//! ```
//!
//! Node and plane indices, labels and cell keys are those of
//! [`Bsp::nodes`], [`Bsp::planes`] and [`Octree::leaves`] (whose order the
//! writer follows); a node's `below` subtree is `n·x + d < 0`.
//!
//! ## Checks on load
//!
//! Nothing in a file is trusted. In order: the magic
//! ([`Error::NotAnOctreeFile`]), the version
//! ([`Error::UnsupportedFormatVersion`]), the length
//! ([`Error::TruncatedFile`]), the checksum ([`Error::ChecksumMismatch`]);
//! then every record: counts no larger than the rest of the file can hold,
//! known tags, every plane within the bit budget of
//! [`crate::exact::budget`] through [`Plane::new`]
//! ([`Error::StoredPlaneOutOfBudget`]), every BSP one tree over in-range
//! plane indices through [`Bsp::from_stored_parts`]
//! ([`Error::InvalidStoredBsp`]), every BSP index in range and every stored
//! BSP used, the cube and the leaves tiling it through
//! [`Octree::from_leaves`] ([`Error::OctreeSize`],
//! [`Error::InvalidOctree`]), and no bytes left over
//! ([`Error::CorruptFile`]). Loading never panics and never allocates more
//! than a small multiple of the file's size.

mod bytes;
mod xxh64;

use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::Path;
use std::sync::Arc;

use self::bytes::{Reader, Writer};
use super::cell::CellKey;
use super::tree::{Leaf, Octree, OctreeConfig};
use crate::Error;
use crate::exact::Plane;
use crate::exact::budget::MAX_COORD;
use crate::tree::{Bsp, Node};

/// The first eight bytes of every octree file.
pub const MAGIC: [u8; 8] = *b"CHISELOC";

/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// Bytes before the first record: magic, version, length.
const HEADER_BYTES: usize = 8 + 4 + 8;
/// Bytes of the trailing checksum.
const CHECKSUM_BYTES: usize = 8;
/// Bytes of one stored plane.
const PLANE_BYTES: usize = 8 * 3 + 16;
/// Fewest bytes of one stored node (a leaf).
const MIN_NODE_BYTES: usize = 2;
/// Fewest bytes of one stored BSP (two counts, one leaf node).
const MIN_BSP_BYTES: usize = 8 + MIN_NODE_BYTES;
/// Fewest bytes of one stored leaf cell (key, tag, label).
const MIN_LEAF_BYTES: usize = 1 + 12 + 2;
/// Fewest bytes of one stored octree (cube, config, no leaves).
const MIN_OCTREE_BYTES: usize = 24 + 1 + 8 + 1 + 4;

const NODE_LEAF: u8 = 0;
const NODE_SPLIT: u8 = 1;
const CELL_UNIFORM: u8 = 0;
const CELL_BSP: u8 = 1;

/// The checksum of an octree file: XXH64 with seed 0 of `bytes` (the file
/// up to its last eight bytes).
#[must_use]
pub fn checksum(bytes: &[u8]) -> u64 {
    xxh64::xxh64(bytes)
}

/// Several octrees in one file, each BSP they share stored once.
#[must_use]
pub fn snapshots_to_bytes(octrees: &[&Octree]) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    w.0.extend_from_slice(&MAGIC);
    w.u32(FORMAT_VERSION);
    w.u64(0); // length, filled in below
    let mut table: HashMap<*const Bsp, usize> = HashMap::new();
    let mut bsps: Vec<&Bsp> = Vec::new();
    for octree in octrees {
        for (_, leaf) in octree.leaves() {
            if let Leaf::Bsp(bsp) = leaf {
                table.entry(Arc::as_ptr(bsp)).or_insert_with(|| {
                    bsps.push(bsp);
                    bsps.len() - 1
                });
            }
        }
    }
    w.index(bsps.len());
    for bsp in &bsps {
        write_bsp(&mut w, bsp);
    }
    w.index(octrees.len());
    for octree in octrees {
        write_octree(&mut w, octree, &table);
    }
    let length = (w.0.len() + CHECKSUM_BYTES) as u64;
    w.0[12..HEADER_BYTES].copy_from_slice(&length.to_le_bytes());
    let sum = checksum(&w.0);
    w.u64(sum);
    w.0
}

/// The octrees of a file written by [`snapshots_to_bytes`], checked (see
/// the module documentation); BSPs stored once are shared again.
///
/// # Errors
/// The first defect found, as a typed [`Error`]; nothing is returned then.
pub fn snapshots_from_bytes(bytes: &[u8]) -> Result<Vec<Octree>, Error> {
    let end = check_envelope(bytes)?;
    let mut r = Reader::new(&bytes[..end], HEADER_BYTES);
    read_records(&mut r).map_err(|e| match e {
        // The file is whole (its length and checksum agree), so a record
        // running out of bytes is a malformed record.
        Error::TruncatedFile { at } => {
            Reader::corrupt(at, "a record runs past the end of the records")
        }
        e => e,
    })
}

fn read_records(r: &mut Reader) -> Result<Vec<Octree>, Error> {
    let bsp_count = r.count(MIN_BSP_BYTES)?;
    let mut bsps = Vec::with_capacity(bsp_count);
    for index in 0..bsp_count {
        bsps.push(Arc::new(read_bsp(r, index)?));
    }
    let mut used = vec![false; bsp_count];
    let at = r.at();
    let octree_count = r.count(MIN_OCTREE_BYTES)?;
    if octree_count == 0 {
        return Err(Reader::corrupt(at, "a file holds at least one octree"));
    }
    let mut octrees = Vec::with_capacity(octree_count);
    for _ in 0..octree_count {
        octrees.push(read_octree(r, &bsps, &mut used)?);
    }
    if r.remaining() != 0 {
        return Err(Reader::corrupt(r.at(), "bytes after the last octree"));
    }
    if used.contains(&false) {
        return Err(Reader::corrupt(
            HEADER_BYTES,
            "a stored BSP is used by no leaf",
        ));
    }
    Ok(octrees)
}

impl Octree {
    /// The octree as file bytes (see [`crate::octree::store`] for the
    /// layout): exact, so [`Octree::from_bytes`] gives it back
    /// bit-identically.
    #[must_use]
    pub fn to_bytes(&self) -> Vec<u8> {
        snapshots_to_bytes(&[self])
    }

    /// An octree from file bytes, checked (see [`crate::octree::store`]).
    ///
    /// # Errors
    /// The first defect found, as a typed [`Error`]; a file of several
    /// snapshots is [`Error::CorruptFile`] (read it with
    /// [`snapshots_from_bytes`]).
    pub fn from_bytes(bytes: &[u8]) -> Result<Octree, Error> {
        let mut octrees = snapshots_from_bytes(bytes)?;
        match octrees.pop() {
            Some(octree) if octrees.is_empty() => Ok(octree),
            _ => Err(Reader::corrupt(
                HEADER_BYTES,
                "the file holds several octrees where one was expected",
            )),
        }
    }

    /// Writes [`Octree::to_bytes`] to `out`.
    ///
    /// # Errors
    /// [`Error::Io`] when writing fails.
    pub fn write_to(&self, mut out: impl Write) -> Result<(), Error> {
        out.write_all(&self.to_bytes()).map_err(io_error)
    }

    /// Reads an octree written by [`Octree::write_to`] from `input` (to
    /// its end).
    ///
    /// # Errors
    /// [`Error::Io`] when reading fails, or as [`Octree::from_bytes`].
    pub fn read_from(mut input: impl Read) -> Result<Octree, Error> {
        let mut bytes = Vec::new();
        input.read_to_end(&mut bytes).map_err(io_error)?;
        Octree::from_bytes(&bytes)
    }

    /// Writes the octree to the file at `path`.
    ///
    /// # Errors
    /// [`Error::Io`] naming the path.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), Error> {
        let path = path.as_ref();
        std::fs::write(path, self.to_bytes()).map_err(|e| Error::Io {
            message: format!("{}: {e}", path.display()),
        })
    }

    /// Reads the octree file at `path`.
    ///
    /// # Errors
    /// [`Error::Io`] naming the path, or as [`Octree::from_bytes`].
    pub fn load(path: impl AsRef<Path>) -> Result<Octree, Error> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| Error::Io {
            message: format!("{}: {e}", path.display()),
        })?;
        Octree::from_bytes(&bytes)
    }
}

fn io_error(e: std::io::Error) -> Error {
    Error::Io {
        message: e.to_string(),
    }
}

/// Checks magic, version, length and checksum; returns where the records
/// end (the checksum's offset).
fn check_envelope(bytes: &[u8]) -> Result<usize, Error> {
    let magic_len = bytes.len().min(MAGIC.len());
    if bytes.is_empty() || bytes[..magic_len] != MAGIC[..magic_len] {
        return Err(Error::NotAnOctreeFile);
    }
    let mut r = Reader::new(bytes, MAGIC.len());
    let version = r.u32()?;
    if version != FORMAT_VERSION {
        return Err(Error::UnsupportedFormatVersion {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let length = r.u64()?;
    let Ok(length) = usize::try_from(length) else {
        return Err(Reader::corrupt(12, "the stated file length is impossible"));
    };
    if length < bytes.len() || length < HEADER_BYTES + CHECKSUM_BYTES {
        return Err(Reader::corrupt(
            12,
            "the stated file length does not match the bytes given",
        ));
    }
    if length > bytes.len() {
        return Err(Error::TruncatedFile { at: bytes.len() });
    }
    let end = length - CHECKSUM_BYTES;
    let stored = Reader::new(bytes, end).u64()?;
    let computed = checksum(&bytes[..end]);
    if stored != computed {
        return Err(Error::ChecksumMismatch { stored, computed });
    }
    Ok(end)
}

fn write_bsp(w: &mut Writer, bsp: &Bsp) {
    w.index(bsp.planes().len());
    w.index(bsp.nodes().len());
    for plane in bsp.planes() {
        let [a, b, c] = plane.normal();
        w.i64(a);
        w.i64(b);
        w.i64(c);
        w.i128(plane.offset());
    }
    for node in bsp.nodes() {
        match *node {
            Node::Leaf(label) => {
                w.u8(NODE_LEAF);
                w.u8(label);
            }
            Node::Split {
                plane,
                below,
                above,
            } => {
                w.u8(NODE_SPLIT);
                w.u32(plane);
                w.u32(below);
                w.u32(above);
            }
        }
    }
}

fn read_bsp(r: &mut Reader, index: usize) -> Result<Bsp, Error> {
    let plane_count = r.count(0)?;
    let node_count = r.count(0)?;
    if plane_count
        .saturating_mul(PLANE_BYTES)
        .saturating_add(node_count.saturating_mul(MIN_NODE_BYTES))
        > r.remaining()
    {
        return Err(Reader::corrupt(
            r.at() - 8,
            "a BSP larger than the rest of the file",
        ));
    }
    let mut planes = Vec::with_capacity(plane_count);
    for _ in 0..plane_count {
        let at = r.at();
        let (a, b, c, d) = (r.i64()?, r.i64()?, r.i64()?, r.i128()?);
        let plane = Plane::new(a, b, c, d).map_err(|cause| Error::StoredPlaneOutOfBudget {
            at,
            cause: Box::new(cause),
        })?;
        planes.push(plane);
    }
    let mut nodes = Vec::with_capacity(node_count);
    for _ in 0..node_count {
        let at = r.at();
        nodes.push(match r.u8()? {
            NODE_LEAF => Node::Leaf(r.u8()?),
            NODE_SPLIT => Node::Split {
                plane: r.u32()?,
                below: r.u32()?,
                above: r.u32()?,
            },
            _ => return Err(Reader::corrupt(at, "an unknown BSP node tag")),
        });
    }
    Bsp::from_stored_parts(planes, nodes)
        .map_err(|e| Error::InvalidStoredBsp { index, reason: e.0 })
}

fn write_octree(w: &mut Writer, octree: &Octree, table: &HashMap<*const Bsp, usize>) {
    for o in octree.origin() {
        w.i64(o);
    }
    w.u8(octree.size_log2());
    let config = octree.config();
    w.u64(config.max_bsp_nodes as u64);
    w.u8(config.max_depth);
    let leaves = octree.leaves();
    w.index(leaves.len());
    for (key, leaf) in leaves {
        w.u8(key.depth);
        key.pos.iter().for_each(|&p| w.u32(p));
        match leaf {
            Leaf::Uniform(label) => {
                w.u8(CELL_UNIFORM);
                w.u8(*label);
            }
            Leaf::Bsp(bsp) => {
                w.u8(CELL_BSP);
                w.index(table[&Arc::as_ptr(bsp)]);
            }
        }
    }
}

fn read_octree(r: &mut Reader, bsps: &[Arc<Bsp>], used: &mut [bool]) -> Result<Octree, Error> {
    let origin = [r.i64()?, r.i64()?, r.i64()?];
    let size_log2 = r.u8()?;
    // Refused here already so that no range check downstream sees a
    // coordinate near the ends of `i64`.
    if origin.iter().any(|o| o.unsigned_abs() > MAX_COORD as u64) {
        return Err(Error::OctreeSize { origin, size_log2 });
    }
    let at = r.at();
    let max_bsp_nodes = usize::try_from(r.u64()?)
        .map_err(|_| Reader::corrupt(at, "a node budget beyond this machine's range"))?;
    let config = OctreeConfig {
        max_bsp_nodes,
        max_depth: r.u8()?,
    };
    let leaf_count = r.count(MIN_LEAF_BYTES)?;
    let mut leaves = Vec::with_capacity(leaf_count);
    for _ in 0..leaf_count {
        let key = CellKey {
            depth: r.u8()?,
            pos: [r.u32()?, r.u32()?, r.u32()?],
        };
        let at = r.at();
        let leaf = match r.u8()? {
            CELL_UNIFORM => Leaf::Uniform(r.u8()?),
            CELL_BSP => {
                let index = r.u32()? as usize;
                let bsp = bsps
                    .get(index)
                    .ok_or(Reader::corrupt(at, "a leaf names a BSP beyond the table"))?;
                used[index] = true;
                Leaf::Bsp(Arc::clone(bsp))
            }
            _ => return Err(Reader::corrupt(at, "an unknown leaf tag")),
        };
        leaves.push((key, leaf));
    }
    Octree::from_leaves(origin, size_log2, config, leaves)
}
