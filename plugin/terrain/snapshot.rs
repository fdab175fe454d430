//! Terrain snapshots: the terrain as it is now, for a peer that joins a
//! game or falls out of step with it.
//!
//! A snapshot holds what a peer needs to go on carving exactly as the
//! sender would: the grid, the base, the octree, the materials carves may
//! use, the debris rules (anchors and limits) and the undo depth limit.
//! Unlike a terrain file ([`super::file`]) it holds no journal and no undo
//! history, so its size follows the terrain's detail, not the number of
//! carves so far (after 10,000 carves in the `net` bench, 7.9 MB against the
//! file's 12.8 MB). The receiver's journal and undo history start empty;
//! its octree and state hash equal the sender's.
//!
//! Layout (version 1, little-endian):
//!
//! ```text
//! magic    8 bytes  "CHISELNS"
//! version  u32      SNAPSHOT_VERSION
//! unit f64, origin 3×f64
//! base     as in the terrain file
//! labels   u32 count, then a u8 each
//! debris   u8 (0: no debris search, 1: the fields below)
//!          max volume: u8 (0 none, 1 some) + u128
//!          max cells:  u8 (0 none, 1 some) + u64
//!          anchor sides: u32 count, each axis u8 + upper u8
//!          anchor boxes: u32 count, each min 3×i64 + max 3×i64
//! max_undo u64
//! octree   u64 length, then a kernel octree file of one snapshot
//! checksum u64      XXH64 of every byte before it
//! ```

use std::collections::VecDeque;

use chisel_bsp::octree::store::bytes::{Reader, Writer};
use chisel_bsp::octree::store::{snapshots_from_bytes, snapshots_to_bytes};
use chisel_bsp::octree::{Anchors, CellBox, CubeSide, DebrisConfig};
use chisel_bsp::tools::Quantization;

use super::component::Terrain;
use super::error::TerrainError;
use super::file::{ReadTerrain, WriteTerrain, corrupt, open_record, read_base, write_base};
use super::jobs::Runtime;

/// The first bytes of every terrain snapshot.
pub const SNAPSHOT_MAGIC: [u8; 8] = *b"CHISELNS";
/// The snapshot version written and read by this build.
pub const SNAPSHOT_VERSION: u32 = 1;

impl Terrain {
    /// The terrain's current state as snapshot bytes (see the
    /// [module docs](self)): everything but the journal and the undo
    /// history. Take it from an idle terrain ([`Terrain::is_idle`]);
    /// queued carves are not in it.
    #[must_use]
    pub fn to_snapshot_bytes(&self) -> Vec<u8> {
        let mut w = Writer::new();
        w.bytes(&SNAPSHOT_MAGIC);
        w.u32(SNAPSHOT_VERSION);
        w.f64(self.quantization.unit());
        for o in self.quantization.origin() {
            w.f64(o);
        }
        write_base(&mut w, &self.base);
        w.count(self.labels.len());
        self.labels.iter().for_each(|&l| w.u8(l));
        match &self.debris {
            None => w.u8(0),
            Some(config) => {
                w.u8(1);
                write_debris(&mut w, config);
            }
        }
        w.u64(self.max_undo as u64);
        let octree = snapshots_to_bytes(&[&self.octree]);
        w.u64(octree.len() as u64);
        w.bytes(&octree);
        let sum = chisel_bsp::octree::store::checksum(w.as_bytes());
        w.u64(sum);
        w.into_bytes()
    }

    /// A terrain from snapshot bytes: checks magic, version and checksum,
    /// then every record; the octree is checked by the kernel and must
    /// fill the base's cube. The terrain's journal and undo history are
    /// empty.
    ///
    /// # Errors
    /// [`TerrainError::BadMagic`], [`TerrainError::UnsupportedVersion`],
    /// [`TerrainError::Truncated`] or [`TerrainError::Corrupt`].
    pub fn from_snapshot_bytes(bytes: &[u8]) -> Result<Terrain, TerrainError> {
        let r = &mut open_record(bytes, SNAPSHOT_MAGIC, SNAPSHOT_VERSION..=SNAPSHOT_VERSION)?.0;
        let unit = r.f64()?;
        let origin = [r.f64()?, r.f64()?, r.f64()?];
        let quantization = Quantization::new(unit, origin).map_err(corrupt)?;
        let base = read_base(r)?;
        let labels = (0..r.list_len()?)
            .map(|_| r.u8())
            .collect::<Result<_, _>>()?;
        let debris = match r.u8()? {
            0 => None,
            1 => Some(read_debris(r)?),
            tag => return Err(corrupt(format!("unknown debris tag {tag}"))),
        };
        let max_undo = usize::try_from(r.u64()?)
            .map_err(|_| corrupt("the undo depth limit is beyond this machine's range"))?;
        let length = usize::try_from(r.u64()?).unwrap_or(usize::MAX);
        let octree_bytes = r.bytes(length)?;
        if r.remaining() != 0 {
            return Err(corrupt(format!(
                "{} unexpected bytes after the octree",
                r.remaining()
            )));
        }
        let mut octrees = snapshots_from_bytes(octree_bytes)
            .map_err(|e| corrupt(format!("octree snapshot: {e}")))?;
        let octree = match (octrees.pop(), octrees.is_empty()) {
            (Some(octree), true) => octree,
            _ => return Err(corrupt("a snapshot holds exactly one octree")),
        };
        if base.cube() != (octree.origin(), octree.size_log2()) {
            return Err(corrupt("the octree's cube is not the base's cube"));
        }
        Ok(Terrain {
            hash: chisel_bsp::octree::StateHash::of(&octree),
            last_request: None,
            octree,
            quantization,
            debris,
            labels,
            base: std::sync::Arc::new(base),
            journal: Vec::new(),
            history: VecDeque::new(),
            redo: Vec::new(),
            max_undo,
            runtime: Runtime::default(),
            detached_across: false,
        })
    }
}

fn write_debris(w: &mut Writer, config: &DebrisConfig) {
    match config.max_volume {
        None => w.u8(0),
        Some(volume) => {
            w.u8(1);
            w.bytes(&volume.to_le_bytes());
        }
    }
    match config.max_cells {
        None => w.u8(0),
        Some(cells) => {
            w.u8(1);
            w.u64(cells as u64);
        }
    }
    w.count(config.anchors.sides.len());
    for side in &config.anchors.sides {
        w.u8(side.axis as u8);
        w.u8(u8::from(side.upper));
    }
    w.count(config.anchors.boxes.len());
    for b in &config.anchors.boxes {
        w.point(b.min);
        w.point(b.max);
    }
}

fn read_debris(r: &mut Reader) -> Result<DebrisConfig, TerrainError> {
    let max_volume = match r.u8()? {
        0 => None,
        1 => Some(u128::from(r.u64()?) | (u128::from(r.u64()?) << 64)),
        tag => return Err(corrupt(format!("unknown debris volume tag {tag}"))),
    };
    let max_cells = match r.u8()? {
        0 => None,
        1 => Some(usize::try_from(r.u64()?).unwrap_or(usize::MAX)),
        tag => return Err(corrupt(format!("unknown debris cell tag {tag}"))),
    };
    let mut sides = Vec::new();
    for _ in 0..r.list_len()? {
        let (axis, upper) = (r.u8()?, r.u8()?);
        if axis > 2 || upper > 1 {
            return Err(corrupt(format!(
                "anchor side (axis {axis}, upper {upper}) names no side of the cube"
            )));
        }
        sides.push(CubeSide {
            axis: usize::from(axis),
            upper: upper == 1,
        });
    }
    let mut boxes = Vec::new();
    for _ in 0..r.list_len()? {
        let b = CellBox {
            min: r.point()?,
            max: r.point()?,
        };
        if (0..3).any(|i| b.min[i] > b.max[i]) {
            return Err(corrupt(format!("anchor box {b:?} has min above max")));
        }
        boxes.push(b);
    }
    Ok(DebrisConfig {
        anchors: Anchors { sides, boxes },
        max_volume,
        max_cells,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::GridTool;
    use chisel_bsp::octree::{Edit, OctreeConfig};

    fn terrain() -> Terrain {
        let base = crate::terrain::TerrainBase::Box {
            origin: [0; 3],
            size_log2: 6,
            solid: CellBox {
                min: [0; 3],
                max: [64, 32, 64],
            },
            label: 1,
        };
        let quantization = Quantization::new(0.25, [0.0; 3]).expect("a grid");
        Terrain::from_base(quantization, base, OctreeConfig::default()).expect("a terrain")
    }

    fn cube(at: [i64; 3], half: i64) -> GridTool {
        let mut points = Vec::new();
        for i in 0..8 {
            points.push([0, 1, 2].map(|a| at[a] + if i >> a & 1 == 1 { half } else { -half }));
        }
        GridTool {
            pieces: vec![points],
        }
    }

    #[test]
    fn round_trip_keeps_the_state_and_drops_the_history() {
        let mut terrain = terrain()
            .with_labels([1, 2])
            .with_debris(Some(DebrisConfig {
                anchors: Anchors {
                    sides: vec![
                        CubeSide::BOTTOM,
                        CubeSide {
                            axis: 0,
                            upper: true,
                        },
                    ],
                    boxes: vec![CellBox {
                        min: [1, 2, 3],
                        max: [4, 5, 6],
                    }],
                },
                max_volume: Some(u128::MAX - 7),
                max_cells: Some(99),
            }));
        terrain
            .apply_now(&cube([20, 32, 20], 6), Edit::Subtract)
            .expect("a carve");
        terrain
            .apply_now(&cube([40, 30, 40], 3), Edit::Add(2))
            .expect("a carve");
        let bytes = terrain.to_snapshot_bytes();
        let back = Terrain::from_snapshot_bytes(&bytes).expect("the snapshot reads back");
        assert_eq!(back.state_hash(), terrain.state_hash());
        assert!(back.octree().to_bytes() == terrain.octree().to_bytes());
        assert_eq!(back.debris(), terrain.debris());
        assert_eq!(back.labels(), terrain.labels());
        assert_eq!(back.max_undo, terrain.max_undo);
        assert!(back.journal().is_empty() && back.undo_depth() == 0);
        assert!(
            back.to_snapshot_bytes() == bytes,
            "re-encoding gives the same bytes"
        );
        assert!(bytes.len() < terrain.to_bytes().len());

        let none = terrain.with_debris(None);
        let back = Terrain::from_snapshot_bytes(&none.to_snapshot_bytes()).expect("reads back");
        assert_eq!(back.debris(), None);
    }

    #[test]
    fn damaged_snapshots_are_refused() {
        let bytes = terrain().to_snapshot_bytes();
        assert!(matches!(
            Terrain::from_snapshot_bytes(&terrain().to_bytes()),
            Err(TerrainError::BadMagic)
        ));
        for cut in [0, 7, 11, 12, 40, bytes.len() - 9, bytes.len() - 1] {
            assert!(
                Terrain::from_snapshot_bytes(&bytes[..cut]).is_err(),
                "cut at {cut}"
            );
        }
        for at in (8..bytes.len()).step_by(97) {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            assert!(Terrain::from_snapshot_bytes(&bad).is_err(), "flip at {at}");
        }
    }
}
