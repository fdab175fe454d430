//! What a chunk of a [`TerrainWorld`] is: its place in the grid, its
//! markers on the chunk entity, its state in the world, and how it is
//! built from the world's source or restored from its stored bytes.

use std::sync::Arc;
use std::time::Duration;

use bevy::prelude::*;
use bevy::tasks::Task;
use chisel_bsp::octree::{Anchors, CellKey, CubeSide, DebrisConfig};
use chisel_bsp::tree::Label;

use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::super::file::bytes_with_seeds;
#[cfg(doc)]
use super::WorldLod;
use super::{TerrainWorld, WorldLayout, WorldSource};

/// A chunk's position in its world's grid of chunks (x and z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Reflect)]
pub struct ChunkCoord {
    /// Chunk index along x.
    pub x: i64,
    /// Chunk index along z.
    pub z: i64,
}

/// A chunk entity of a [`TerrainWorld`] (it also has its [`Terrain`]).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component)]
pub struct WorldChunk {
    /// The world entity.
    pub world: Entity,
    /// Its place in the world.
    pub coord: ChunkCoord,
}

/// A live chunk that no focus has come near: built beyond every focus's
/// unload radius, only for work there (a carve routed to it, an undo, a
/// search for debris across borders; on a networked world's client, its
/// deferred carves once too many wait or [`TerrainWorld::build_deferred`]
/// asks), and released once that is done. Its cells get no
/// render meshes (colliders still, where the [`CellOutput`] and a
/// physics backend build them), and coarse chunks ([`WorldLod`]) stand in
/// for it. The marker is taken away, for good, once a focus comes within
/// the unload radius; the chunk then builds its meshes.
///
/// [`CellOutput`]: crate::terrain::CellOutput
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Component, Default)]
pub struct ChunkOffstage;

/// The state of one chunk the world knows.
pub(crate) enum Chunk {
    /// Being built or restored on the async compute pool.
    Building(Task<Built>),
    /// A terrain entity.
    Live(Entity),
    /// The build failed; not retried.
    Failed,
}

/// A chunk build's result, from the async compute pool.
pub(crate) struct Built {
    pub(crate) terrain: Result<Terrain, TerrainError>,
    pub(crate) time: Duration,
    /// Restored from stored bytes rather than generated.
    pub(crate) restored: bool,
}

/// The debris settings of a chunk: anchored by the cube's bottom and its
/// four sides (solid on a side continues into the neighbouring chunk), and
/// by the base's floor.
#[must_use]
pub fn chunk_debris(floor: chisel_bsp::octree::CellBox) -> DebrisConfig {
    let side = |axis, upper| CubeSide { axis, upper };
    DebrisConfig {
        anchors: Anchors {
            sides: vec![
                CubeSide::BOTTOM,
                side(0, false),
                side(0, true),
                side(2, false),
                side(2, true),
            ],
            boxes: vec![floor],
        },
        max_volume: None,
        max_cells: None,
    }
}

pub(crate) fn generate(
    layout: &WorldLayout,
    source: &dyn WorldSource,
    labels: &[Label],
    coord: ChunkCoord,
) -> Result<Terrain, TerrainError> {
    let base = layout.chunk_base(source, coord)?;
    let floor = base.floor();
    Ok(Terrain::from_base(
        layout.quantization,
        base,
        super::super::terrain_octree_config(),
    )?
    .with_labels(labels.iter().copied())
    .with_debris(Some(chunk_debris(floor))))
}

pub(crate) fn restore(bytes: &[u8], labels: &[Label]) -> Result<Terrain, TerrainError> {
    let terrain = Terrain::from_bytes(bytes)?;
    let floor = terrain.base().floor();
    Ok(terrain
        .with_labels(labels.iter().copied())
        .with_debris(Some(chunk_debris(floor))))
}

impl TerrainWorld {
    /// Gives `seeds` (cells to search for debris across borders from,
    /// `super::debris`) back to chunk `coord`, live or not (a world undo's,
    /// `super::undo`): into a live chunk's terrain; into the stored bytes
    /// of an edited chunk streamed out (and, while it is being restored,
    /// into its terrain once collected); into the terrain of a chunk being
    /// built from the source, or unedited and not live, once its build is
    /// collected. A chunk whose build failed drops them.
    pub(crate) fn give_seeds_back(
        &mut self,
        coord: ChunkCoord,
        seeds: Vec<CellKey>,
        terrains: &mut Query<&mut Terrain>,
    ) {
        let building = match self.chunks.get(&coord) {
            Some(Chunk::Live(entity)) => {
                if let Ok(mut terrain) = terrains.get_mut(*entity) {
                    (terrain.bypass_change_detection().runtime.border_seeds).extend(seeds);
                }
                return;
            }
            Some(Chunk::Failed) => return,
            Some(Chunk::Building(_)) => true,
            None => false,
        };
        if let Some(bytes) = self.stored.get_mut(&coord) {
            match bytes_with_seeds(bytes, &seeds) {
                Ok(with_seeds) => *bytes = Arc::new(with_seeds),
                Err(error) => warn!(
                    "terrain world chunk ({}, {}): seeds not stored: {error}",
                    coord.x, coord.z
                ),
            }
            if !building {
                return;
            }
        }
        self.seeds_back.entry(coord).or_default().extend(seeds);
    }
}
