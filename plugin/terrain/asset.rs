//! Terrain files and heightfields through Bevy's asset server.
//!
//! - [`TerrainAsset`]: a terrain file (`*.chiselterrain`, the format of
//!   [`super::file`]; not the command line's `.chisel` octree files) as an
//!   asset. Spawn a [`TerrainSource`] with its handle: the entity gets the
//!   [`Terrain`] once the file is loaded, and a new one whenever the asset
//!   changes (hot reload: the old cells are despawned, the new terrain is
//!   meshed from scratch).
//! - [`Heightfield`] as an asset, from a greyscale PNG through
//!   [`HeightfieldLoader`], tuned by [`HeightfieldSettings`]
//!   (`AssetServer::load_builder().with_settings(..)`, or a `.meta` file next to the
//!   image).
//!
//! Hot reload needs Bevy's `file_watcher` feature in the game's Bevy
//! dependency (`bevy = { version = "0.19", features = ["file_watcher"] }`,
//! or `--features bevy/file_watcher`); this crate does not switch it on.
//! Quadric prop scenes (`*.quadric.ron`) reload the same way.
//!
//! ```
//! use bevy::prelude::*;
//! use bevy_chisel::terrain::{Heightfield, HeightfieldSettings, TerrainSource};
//!
//! fn setup(mut commands: Commands, assets: Res<AssetServer>) {
//!     // A saved level, kept up to date with the file.
//!     commands.spawn(TerrainSource(assets.load("levels/quarry.chiselterrain")));
//!     // A heightfield: 0.5 m between samples, heights from 0 to 12 m.
//!     let _height: Handle<Heightfield> = assets
//!         .load_builder()
//!         .with_settings(|s: &mut HeightfieldSettings| {
//!             s.spacing = 0.5;
//!             s.high = 12.0;
//!         })
//!         .load("terrain/quarry_height.png");
//! }
//! # let _ = setup;
//! ```

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoader, LoadContext};
use bevy::prelude::*;
use chisel_bsp::tree::Label;
use serde::{Deserialize, Serialize};

use super::component::{Terrain, TerrainCell};
use super::error::TerrainError;
use super::jobs::Runtime;
use super::spawn::{HeightLayer, Heightfield};

/// The file extension of terrain files loaded as [`TerrainAsset`]s.
pub const TERRAIN_EXTENSION: &str = "chiselterrain";

/// A terrain file, loaded and checked (see [`Terrain::from_bytes`]).
/// [`TerrainAsset::instantiate`] makes a [`Terrain`] of it, as often as
/// wanted; the octrees are shared, so that costs little.
#[derive(Asset, TypePath)]
pub struct TerrainAsset {
    terrain: Terrain,
}

impl TerrainAsset {
    /// The terrain as loaded (idle, no cells yet).
    #[must_use]
    pub fn terrain(&self) -> &Terrain {
        &self.terrain
    }

    /// A new terrain, bit-identical to the file's, with its undo history.
    #[must_use]
    pub fn instantiate(&self) -> Terrain {
        let t = &self.terrain;
        Terrain {
            octree: t.octree.clone(),
            quantization: t.quantization,
            base: t.base.clone(),
            journal: t.journal.clone(),
            history: t.history.clone(),
            redo: Vec::new(),
            max_undo: t.max_undo,
            debris: t.debris.clone(),
            labels: t.labels.clone(),
            hash: t.hash.clone(),
            last_request: t.last_request,
            runtime: Runtime::default(),
            detached_across: t.detached_across,
        }
    }
}

impl From<Terrain> for TerrainAsset {
    fn from(terrain: Terrain) -> Self {
        Self { terrain }
    }
}

/// Loads [`TerrainAsset`]s from `*.chiselterrain` files. A damaged or
/// foreign file fails the load with a [`TerrainError`] naming the defect.
#[derive(Default, TypePath)]
pub struct TerrainFileLoader;

impl AssetLoader for TerrainFileLoader {
    type Asset = TerrainAsset;
    type Settings = ();
    type Error = TerrainError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        _load_context: &mut LoadContext<'_>,
    ) -> Result<TerrainAsset, TerrainError> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await?;
        Terrain::from_bytes(&bytes).map(TerrainAsset::from)
    }

    fn extensions(&self) -> &[&str] {
        &[TERRAIN_EXTENSION]
    }
}

/// On an entity: the terrain file it shows. The entity gets the file's
/// [`Terrain`] once it is loaded, and the new one each time the asset is
/// modified (hot reload); carves made in between are dropped then.
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(Component)]
pub struct TerrainSource(pub Handle<TerrainAsset>);

/// Gives [`TerrainSource`] entities their terrain when the file is loaded
/// or changes.
pub(crate) fn spawn_from_assets(
    mut events: MessageReader<AssetEvent<TerrainAsset>>,
    assets: Res<Assets<TerrainAsset>>,
    sources: Query<(Entity, &TerrainSource, Has<Terrain>)>,
    cells: Query<(Entity, &TerrainCell)>,
    mut commands: Commands,
) {
    let modified: Vec<AssetId<TerrainAsset>> = events
        .read()
        .filter_map(|e| match e {
            AssetEvent::Modified { id } => Some(*id),
            _ => None,
        })
        .collect();
    for (entity, source, has_terrain) in &sources {
        let reload = modified.contains(&source.0.id());
        if has_terrain && !reload {
            continue;
        }
        let Some(asset) = assets.get(&source.0) else {
            continue;
        };
        if reload {
            for (cell, _) in cells.iter().filter(|(_, c)| c.terrain == entity) {
                commands.entity(cell).despawn();
            }
        }
        commands.entity(entity).insert(asset.instantiate());
    }
}

/// How a [`HeightfieldLoader`] turns an image into a [`Heightfield`]: see
/// [`Heightfield::from_image`]. Black is `low`, white is `high`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeightfieldSettings {
    /// Distance between samples, in world units.
    pub spacing: f32,
    /// Height of black.
    pub low: f32,
    /// Height of white.
    pub high: f32,
    /// Depth of the solid below `low`.
    pub depth: f32,
    /// Material of the solid.
    pub label: Label,
    /// Bands of other materials under the surface.
    pub layers: Vec<HeightLayer>,
}

impl Default for HeightfieldSettings {
    fn default() -> Self {
        Self {
            spacing: 1.0,
            low: 0.0,
            high: 10.0,
            depth: 5.0,
            label: 1,
            layers: Vec::new(),
        }
    }
}

/// Loads a [`Heightfield`] from a PNG (16-bit grey keeps all its
/// precision). It is picked by asset type, so it shares `.png` with Bevy's
/// image loader: `assets.load::<Heightfield>("height.png")`; files named
/// `*.heightfield.png` are heightfields even when loaded untyped.
#[derive(Default, TypePath)]
pub struct HeightfieldLoader;

impl AssetLoader for HeightfieldLoader {
    type Asset = Heightfield;
    type Settings = HeightfieldSettings;
    type Error = TerrainError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        settings: &HeightfieldSettings,
        _load_context: &mut LoadContext<'_>,
    ) -> Result<Heightfield, TerrainError> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await?;
        let image =
            image::load_from_memory(&bytes).map_err(|e| TerrainError::InvalidHeightfield {
                reason: format!("cannot decode the image: {e}"),
            })?;
        let s = settings;
        Ok(
            Heightfield::from_image(&image, s.spacing, s.low, s.high, s.depth, s.label)
                .with_layers(s.layers.iter().copied()),
        )
    }

    fn extensions(&self) -> &[&str] {
        &["heightfield.png"]
    }
}
