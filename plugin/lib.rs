//! # bevy_chisel — exact, local solid modelling for Bevy
//!
//! `bevy_chisel` brings two kernels into Bevy:
//!
//! - [`chisel_bsp`] (re-exported as `bsp`): exact integer plane geometry,
//!   the foundation of destructible octree-BSP terrain whose carves never
//!   fail, never crack and are bit-identical on every machine.
//! - [`chisel_quadric`] (re-exported as `quadric`): quadric CSG trees for
//!   level-design props drawn pixel-exact by splat ray tracing.
//!
//! Add [`ChiselPlugins`] after Bevy's `DefaultPlugins`, and `use
//! bevy_chisel::prelude::*;`. The README's "Use it in your game" program
//! is `examples/use_in_game.rs`, and runs as a test of this crate.
//!
//! ## Modules
//!
//! - `terrain` (feature `terrain`) is destructible terrain: a `Terrain`
//!   component owning an octree of exact BSPs, carved by `Carve` messages
//!   on the async compute pool, re-meshed only in the cells that changed,
//!   with undo, ray casts, versioned files through the asset server
//!   (`*.chiselterrain`), entity events for observers, and physics
//!   colliders with avian3d (feature `avian`) or bevy_rapier3d (feature
//!   `rapier`). With `render`, terrain cells
//!   get materials (`TerrainMaterials`, `TriplanarMaterial`). Carve tools
//!   (`CarveTool`) are unions of dodecahedra, boxes, prisms, hulls of
//!   points, and spheres, cylinders and capsules carved as exact polyhedra
//!   within a stated tolerance of the true surface; with `props`,
//!   `CarveTool::from_prop` carves with a convex quadric prop's shape.
//!   Large worlds (`TerrainWorld`) are grids of terrain chunks streamed
//!   around `TerrainFocus` entities from a procedural source, with coarse
//!   chunks to the horizon (`WorldLod`), carves and undos across chunk
//!   borders (`WorldCarve`, `WorldUndo`), and background saves of only
//!   the chunks changed since the last one (`SaveWorld`).
//! - `splat` (feature `props`) draws quadric CSG props: a `QuadricProp`
//!   component (a `*.quadric.ron` scene file or an in-memory scene),
//!   sampled on the async compute pool, rendered by a splat pass with
//!   per-fragment ray tracing, clipping and depth writes.
//! - `presentation` and `viewer` (feature `viewer`) are what the bundled
//!   examples and render tests share: windowed or headless runs with
//!   screenshots, an orbit camera, text overlays, carving under the
//!   cursor. They are not part of the API a game needs.
//! - `net` (feature `net`) replicates carves from one authoritative server
//!   to its clients: integer carves in sequence order, state hashes and
//!   snapshots, never meshes; for single terrains (`NetTerrain`) and
//!   streamed worlds (`NetWorld`), each peer streaming its own chunks.
//!
//! ## Features
//!
//! | feature   | default | adds |
//! |-----------|---------|------|
//! | `terrain` | yes | destructible terrain without a renderer (octree, carves, meshes as assets, journal, files, ray casts, debris, physics hooks) |
//! | `render`  | yes | Bevy's renderer and PBR: terrain materials, the triplanar material |
//! | `props`   | yes | quadric CSG props and the splat render pass (implies `render`) |
//! | `avian`   | no  | colliders and debris bodies with avian3d (implies `terrain`) |
//! | `rapier`  | no  | the same with bevy_rapier3d (implies `terrain`) |
//! | `serde`   | no  | `Serialize`/`Deserialize` on tools, settings and bounds |
//! | `viewer`  | no  | the examples' helpers: window or headless screenshots, orbit camera, overlays |
//! | `net`     | no  | server-authoritative replicated carves with bevy_replicon and renet (implies `terrain`, `serde`) |
//!
//! A dedicated server is `default-features = false, features = ["terrain",
//! "serde"]`: no window, UI or render crate is built.
//!
//! ## Bevy versions
//!
//! | bevy_chisel | Bevy |
//! |-------------|------|
//! | 0.1         | 0.19 |

#![warn(missing_docs)]
// docs.rs builds with `--cfg docsrs` on nightly: each item behind a cargo
// feature then says which one.
#![cfg_attr(docsrs, feature(doc_cfg))]

#[cfg(feature = "net")]
pub mod net;
#[cfg(feature = "viewer")]
pub mod presentation;
#[cfg(feature = "props")]
pub mod splat;
#[cfg(feature = "terrain")]
pub mod terrain;
#[cfg(feature = "viewer")]
pub mod viewer;

/// The README's "Use it in your game" program (`examples/use_in_game.rs`),
/// run headless: Bevy's `DefaultPlugins` rendering offscreen, the game's
/// plugins and systems unchanged, for a few frames.
#[cfg(all(doctest, feature = "viewer"))]
#[doc = concat!(
    "```\n",
    "# #[allow(dead_code)]\n",
    "# mod use_in_game {\n",
    include_str!("../examples/use_in_game.rs"),
    "# }\n",
    include_str!("use_in_game.doctest"),
    "```\n"
)]
pub struct UseInGame;

#[cfg(all(feature = "serde", feature = "terrain"))]
mod serde_transform;

#[cfg(feature = "terrain")]
pub use chisel_bsp as bsp;
#[cfg(feature = "props")]
pub use chisel_quadric as quadric;

use bevy::app::{PluginGroup, PluginGroupBuilder};

/// Every plugin of the enabled features, in one group:
/// [`terrain::TerrainPlugin`] (feature `terrain`), with
/// [`terrain::TriplanarMaterialPlugin`] (`terrain` and `render`),
/// [`splat::ChiselSplatPlugin`] (`props`) and the terrain's physics:
/// `terrain::avian::TerrainAvianPlugin` (`avian`; add avian's
/// `PhysicsPlugins` yourself), or `terrain::rapier::TerrainRapierPlugin`
/// (`rapier` without `avian`; add `RapierPhysicsPlugin` yourself). Not in
/// the group, to add on their own: the props' colliders
/// (`splat::avian::PropAvianPlugin`, `splat::rapier::PropRapierPlugin`),
/// the `net` plugins and `viewer::ViewerPlugin`. Add it after `DefaultPlugins`; on a server
/// without a renderer, after `MinimalPlugins`. As in any Bevy group, single
/// plugins can be disabled or replaced; terrain systems in `FixedUpdate`:
///
/// ```
/// # use bevy::prelude::*;
/// # use bevy_chisel::prelude::*;
/// let plugins = ChiselPlugins
///     .build()
///     .disable::<TerrainPlugin>()
///     .add(TerrainPlugin::in_schedule(FixedUpdate));
/// // App::new().add_plugins((DefaultPlugins, plugins)).run();
/// # let _ = plugins;
/// ```
pub struct ChiselPlugins;

impl PluginGroup for ChiselPlugins {
    fn build(self) -> PluginGroupBuilder {
        let group = PluginGroupBuilder::start::<Self>();
        #[cfg(feature = "terrain")]
        let group = group.add(terrain::TerrainPlugin);
        #[cfg(all(feature = "terrain", feature = "render"))]
        let group = group.add(terrain::TriplanarMaterialPlugin);
        #[cfg(feature = "props")]
        let group = group.add(splat::ChiselSplatPlugin);
        #[cfg(feature = "avian")]
        let group = group.add(terrain::avian::TerrainAvianPlugin::default());
        #[cfg(all(feature = "rapier", not(feature = "avian")))]
        let group = group.add(terrain::rapier::TerrainRapierPlugin::default());
        group
    }
}

/// What a game usually needs: `use bevy_chisel::prelude::*;`.
pub mod prelude {
    pub use crate::ChiselPlugins;
    #[cfg(feature = "props")]
    pub use crate::splat::{
        ChiselSplatPlugin, PropBounds, PropMaterial, QuadricProp, QuadricScene, SplatMode,
        SplatRadius, SplatSettings, SplatViewSettings,
    };
    #[cfg(feature = "avian")]
    pub use crate::terrain::avian::TerrainAvianPlugin;
    #[cfg(feature = "rapier")]
    pub use crate::terrain::rapier::TerrainRapierPlugin;
    #[cfg(feature = "terrain")]
    pub use crate::terrain::{
        Carve, CarveApplied, CarveRejected, CarveShape, CarveTool, CellOutput, DebrisDetached,
        HeightLayer, Heightfield, RedoCarve, Terrain, TerrainCarveRejected, TerrainCarved,
        TerrainCell, TerrainCellChanged, TerrainCellRebuilt, TerrainDebris, TerrainError,
        TerrainHit, TerrainPlugin, TerrainSettings, TerrainSystems, TerrainWorld, UndoCarve,
        WorldCarve, WorldRedo, WorldRedoRejected, WorldRedone, WorldUndo, WorldUndoRejected,
        WorldUndone,
    };
    #[cfg(all(feature = "terrain", feature = "render"))]
    pub use crate::terrain::{
        TerrainMaterialPlugin, TerrainMaterials, TerrainSurface, TriplanarMaterial,
        TriplanarMaterialPlugin, surface_table,
    };
    #[cfg(feature = "terrain")]
    pub use chisel_bsp::octree::Edit;
    #[cfg(feature = "terrain")]
    pub use chisel_bsp::tools::Quantization;
}
