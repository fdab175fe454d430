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
//! over one table of octree nodes, children before parents. Octrees share
//! their unchanged subtrees in memory ([`Arc`]s: an edit copies only the
//! path to the cells it changes); a shared subtree, and a shared BSP, is
//! stored once and is shared again after loading, so a history of edits
//! costs only the cells the edits replaced.
//!
//! ## Layout (version 1, little-endian)
//!
//! ```text
//! magic        8 bytes  "CHISELOC"                               MAGIC
//! version      u32      1                                        FORMAT_VERSION
//! length       u64      bytes in the whole file, checksum included
//! node_count   u32
//!   per node:  tag u8 = 0 (uniform leaf): label u8
//!              tag u8 = 1 (BSP leaf):     plane_count u32, bsp_node_count u32,
//!                  planes: a i64, b i64, c i64, d i128           (40 bytes each)
//!                  BSP nodes: tag u8 = 0 (leaf): label u8
//!                             tag u8 = 1 (split): plane u32, below u32, above u32
//!              tag u8 = 2 (inner cell):   8 × child u32, each an earlier node
//! octree_count u32      at least 1
//!   per octree: origin 3×i64, size_log2 u8,
//!              max_bsp_nodes u64, max_depth u8                   (OctreeConfig)
//!              root u32  (a node index)
//! checksum     u64      XXH64 (seed 0) of every byte before it
//! ```
//!
//! Child `i` of an inner cell is the cell's octant `i` (bit 0: upper x
//! half, bit 1: upper y, bit 2: upper z; see [`super::CellKey::child`]).
//! BSP node and plane indices are those of [`Bsp::nodes`] and
//! [`Bsp::planes`]; a BSP node's `below` subtree is `n·x + d < 0`. The
//! writer numbers nodes in post-order, each shared node once.
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
//! ([`Error::InvalidStoredBsp`]) at most [`MAX_STORED_BSP_DEPTH`] levels
//! deep, every child an earlier node (so the
//! nodes form no cycle) and every node used, the cube within the exact
//! range ([`Error::OctreeSize`]), no octree deeper than its cube allows and
//! none with more cells than its nodes can make without repeating a
//! subtree ([`Error::InvalidOctree`]), and no bytes left over
//! ([`Error::CorruptFile`]). Loading never panics, never allocates more
//! than a small multiple of the file's size, and gives no octree with more
//! cells than a tree of its stored nodes has, so later walks over it cost
//! in proportion to the file.
//!
//! ## Use
//!
//! [`Octree::to_bytes`] / [`Octree::from_bytes`] for one octree, with
//! [`Octree::save`] / [`Octree::load`] (files) and [`Octree::write_to`] /
//! [`Octree::read_from`] (streams); [`snapshots_to_bytes`] /
//! [`snapshots_from_bytes`] for several sharing their cells.
//!
//! ```
//! use chisel_bsp::octree::{CellBox, Octree, OctreeConfig};
//!
//! let block = CellBox { min: [0; 3], max: [600, 400, 300] };
//! let octree = Octree::from_box([0; 3], 10, block, 1, OctreeConfig::default())?;
//! let bytes = octree.to_bytes();
//! let back = Octree::from_bytes(&bytes)?;
//! assert_eq!(back.to_bytes(), bytes);
//! assert_eq!(back.solid_volume(), 600.0 * 400.0 * 300.0);
//! # Ok::<(), chisel_bsp::Error>(())
//! ```

pub mod bytes;
mod xxh64;

use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::Path;
use std::sync::Arc;

use self::bytes::{Reader, Writer};
use super::tree::{Leaf, OctNode, Octree, OctreeConfig};
use crate::Error;
use crate::exact::Plane;
use crate::exact::budget::MAX_COORD;
use crate::tree::{Bsp, EMPTY, Label, Node};

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
/// Fewest bytes of one stored BSP node (a leaf).
const MIN_BSP_NODE_BYTES: usize = 2;
/// Fewest bytes of one stored octree node (a uniform leaf).
const MIN_NODE_BYTES: usize = 2;
/// Bytes of one stored octree (cube, settings, root).
const OCTREE_BYTES: usize = 24 + 1 + 8 + 1 + 4;

/// Deepest stored BSP accepted. A leaf within the node budget has at
/// most `max_bsp_nodes` levels, so the kernel's own BSPs stay far below
/// this; a deeper one from a crafted file would overflow the stack of the
/// recursive walks of later edits.
pub const MAX_STORED_BSP_DEPTH: usize = 4096;

const BSP_LEAF: u8 = 0;
const BSP_SPLIT: u8 = 1;
const NODE_UNIFORM: u8 = 0;
const NODE_BSP: u8 = 1;
const NODE_INNER: u8 = 2;

/// The checksum of an octree file: XXH64 with seed 0 of `bytes` (the file
/// up to its last eight bytes).
#[must_use]
pub fn checksum(bytes: &[u8]) -> u64 {
    xxh64::xxh64(bytes)
}

/// Identity of a stored node: shared subtrees and BSPs by address,
/// uniform leaves by label.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum NodeId {
    Uniform(Label),
    Bsp(*const Bsp),
    Inner(*const [OctNode; 8]),
}

/// The node table being written: each distinct node once, children first.
struct NodeTable<'a> {
    index: HashMap<NodeId, u32>,
    w: &'a mut Writer,
    count: u32,
}

impl NodeTable<'_> {
    /// The index of `node`, writing it (and its children) when new.
    fn add(&mut self, node: &OctNode) -> u32 {
        let id = match node {
            OctNode::Leaf(Leaf::Uniform(label)) => NodeId::Uniform(*label),
            OctNode::Leaf(Leaf::Bsp(bsp)) => NodeId::Bsp(Arc::as_ptr(bsp)),
            OctNode::Inner(children) => NodeId::Inner(Arc::as_ptr(children)),
        };
        if let Some(&i) = self.index.get(&id) {
            return i;
        }
        match node {
            OctNode::Leaf(Leaf::Uniform(label)) => {
                self.w.u8(NODE_UNIFORM);
                self.w.u8(*label);
            }
            OctNode::Leaf(Leaf::Bsp(bsp)) => {
                self.w.u8(NODE_BSP);
                write_bsp(self.w, bsp);
            }
            OctNode::Inner(children) => {
                let ids = [0, 1, 2, 3, 4, 5, 6, 7].map(|k| self.add(&children[k]));
                self.w.u8(NODE_INNER);
                ids.iter().for_each(|&i| self.w.u32(i));
            }
        }
        let i = self.count;
        self.count += 1;
        self.index.insert(id, i);
        i
    }
}

/// Several octrees in one file, each subtree and BSP they share stored
/// once.
#[must_use]
pub fn snapshots_to_bytes(octrees: &[&Octree]) -> Vec<u8> {
    let mut w = Writer::new();
    w.bytes(&MAGIC);
    w.u32(FORMAT_VERSION);
    w.u64(0); // length, filled in below
    w.u32(0); // node count, filled in below
    let mut table = NodeTable {
        index: HashMap::new(),
        w: &mut w,
        count: 0,
    };
    let roots: Vec<u32> = octrees.iter().map(|o| table.add(&o.root)).collect();
    let count = table.count;
    w.overwrite(HEADER_BYTES, &count.to_le_bytes());
    w.count(octrees.len());
    for (octree, root) in octrees.iter().zip(roots) {
        for o in octree.origin() {
            w.i64(o);
        }
        w.u8(octree.size_log2());
        let config = octree.config();
        w.u64(config.max_bsp_nodes as u64);
        w.u8(config.max_depth);
        w.u32(root);
    }
    let length = (w.as_bytes().len() + CHECKSUM_BYTES) as u64;
    w.overwrite(12, &length.to_le_bytes());
    let sum = checksum(w.as_bytes());
    w.u64(sum);
    w.into_bytes()
}

/// The octrees of a file written by [`snapshots_to_bytes`], checked (see
/// the module documentation); subtrees and BSPs stored once are shared
/// again.
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

/// What the loader knows of each stored node.
struct Stored {
    node: OctNode,
    /// Levels of inner cells below and including this one (0 for a leaf).
    height: u8,
    /// Leaf cells under it, counting a repeated subtree each time
    /// (saturating).
    cells: u64,
    used: bool,
}

fn read_records(r: &mut Reader) -> Result<Vec<Octree>, Error> {
    let node_count = r.count(MIN_NODE_BYTES)?;
    let mut nodes: Vec<Stored> = Vec::with_capacity(node_count);
    let mut inner_count: u64 = 0;
    for index in 0..node_count {
        let at = r.at();
        let stored = match r.u8()? {
            NODE_UNIFORM => Stored {
                node: OctNode::Leaf(Leaf::Uniform(r.u8()?)),
                height: 0,
                cells: 1,
                used: false,
            },
            NODE_BSP => Stored {
                node: OctNode::Leaf(Leaf::Bsp(Arc::new(read_bsp(r, index)?))),
                height: 0,
                cells: 1,
                used: false,
            },
            NODE_INNER => {
                let mut children = Vec::with_capacity(8);
                let (mut height, mut cells) = (0u8, 0u64);
                for _ in 0..8 {
                    let at = r.at();
                    let child = r.u32()? as usize;
                    let Some(c) = nodes.get_mut(child) else {
                        return Err(Reader::corrupt(
                            at,
                            "a child that is not stored before its parent",
                        ));
                    };
                    c.used = true;
                    height = height.max(c.height.saturating_add(1));
                    cells = cells.saturating_add(c.cells);
                    children.push(c.node.clone());
                }
                let children: [OctNode; 8] = children
                    .try_into()
                    .unwrap_or_else(|_| unreachable!("eight children"));
                inner_count += 1;
                Stored {
                    node: OctNode::Inner(Arc::new(children)),
                    height,
                    cells,
                    used: false,
                }
            }
            _ => return Err(Reader::corrupt(at, "an unknown octree node tag")),
        };
        nodes.push(stored);
    }
    let at = r.at();
    let octree_count = r.count(OCTREE_BYTES)?;
    if octree_count == 0 {
        return Err(Reader::corrupt(at, "a file holds at least one octree"));
    }
    let mut octrees = Vec::with_capacity(octree_count);
    for _ in 0..octree_count {
        octrees.push(read_octree(r, &mut nodes, inner_count)?);
    }
    if r.remaining() != 0 {
        return Err(Reader::corrupt(r.at(), "bytes after the last octree"));
    }
    if nodes.iter().any(|n| !n.used) {
        return Err(Reader::corrupt(
            HEADER_BYTES,
            "a stored node is used by no octree",
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

/// One leaf's record as an octree file stores it (tag, then the label or
/// the BSP's planes and nodes): the bytes [`super::hash`] hashes.
pub(crate) fn leaf_record(leaf: &Leaf) -> Vec<u8> {
    let mut w = Writer::new();
    match leaf {
        Leaf::Uniform(label) => {
            w.u8(NODE_UNIFORM);
            w.u8(*label);
        }
        Leaf::Bsp(bsp) => {
            w.u8(NODE_BSP);
            write_bsp(&mut w, bsp);
        }
    }
    w.into_bytes()
}

fn write_bsp(w: &mut Writer, bsp: &Bsp) {
    w.count(bsp.planes().len());
    w.count(bsp.nodes().len());
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
                w.u8(BSP_LEAF);
                w.u8(label);
            }
            Node::Split {
                plane,
                below,
                above,
            } => {
                w.u8(BSP_SPLIT);
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
        .saturating_add(node_count.saturating_mul(MIN_BSP_NODE_BYTES))
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
            BSP_LEAF => Node::Leaf(r.u8()?),
            BSP_SPLIT => Node::Split {
                plane: r.u32()?,
                below: r.u32()?,
                above: r.u32()?,
            },
            _ => return Err(Reader::corrupt(at, "an unknown BSP node tag")),
        });
    }
    let bsp = Bsp::from_stored_parts(planes, nodes)
        .map_err(|e| Error::InvalidStoredBsp { index, reason: e.0 })?;
    if bsp_depth(&bsp) > MAX_STORED_BSP_DEPTH {
        return Err(Error::InvalidStoredBsp {
            index,
            reason: format!("more than {MAX_STORED_BSP_DEPTH} levels deep"),
        });
    }
    Ok(bsp)
}

/// Levels of splits on the longest path from the root to a leaf, of a
/// checked tree.
fn bsp_depth(bsp: &Bsp) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 0usize)];
    while let Some((n, depth)) = stack.pop() {
        match bsp.nodes()[n as usize] {
            Node::Leaf(_) => deepest = deepest.max(depth),
            Node::Split { below, above, .. } => {
                stack.extend([(below, depth + 1), (above, depth + 1)]);
            }
        }
    }
    deepest
}

fn read_octree(r: &mut Reader, nodes: &mut [Stored], inner_count: u64) -> Result<Octree, Error> {
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
    if max_bsp_nodes < OctreeConfig::MIN_BSP_NODES {
        return Err(Reader::corrupt(at, "a node budget below 8"));
    }
    let config = OctreeConfig {
        max_bsp_nodes,
        max_depth: r.u8()?,
    };
    let at = r.at();
    let root = r.u32()? as usize;
    let Some(stored) = nodes.get_mut(root) else {
        return Err(Reader::corrupt(at, "an octree root beyond the node table"));
    };
    stored.used = true;
    let mut octree = Octree::new(origin, size_log2, EMPTY, config)?;
    if stored.height > size_log2 {
        return Err(Error::InvalidOctree {
            reason: "cells nested deeper than the cube can be divided",
        });
    }
    // A tree of `n` inner cells has `7n + 1` leaf cells; more means a
    // subtree is repeated, and only so often that the octree stays as
    // small as the file.
    if stored.cells > 7 * inner_count + 1 {
        return Err(Error::InvalidOctree {
            reason: "more cells than the stored nodes can make",
        });
    }
    octree.root = stored.node.clone();
    Ok(octree)
}
