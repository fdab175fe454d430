//! Carving in the ECS, the vocabulary: the messages in ([`Carve`],
//! [`GridCarve`], [`UndoCarve`], [`RedoCarve`]) and out ([`CarveApplied`],
//! [`CarveRejected`], [`TerrainCellChanged`]), and the
//! [`TerrainSettings`] of the systems that run them.
//!
//! A carve reads straight down through the terrain modules, per terrain
//! one job at a time and in request order:
//!
//! 1. Here, a [`Carve`] or [`GridCarve`] message ([`UndoCarve`] for an
//!    undo, [`RedoCarve`] for a redo).
//! 2. In [`super::queue`], [`read_requests`](super::queue::read_requests)
//!    turns the messages into jobs on the terrain's queue (tools are
//!    rounded to the grid there; a bad tool is rejected at once with
//!    [`CarveRejected`]); [`start_jobs`](super::queue::start_jobs) takes
//!    the consecutive carves at the head of the queue and starts them as
//!    one job on a snapshot of the octree (a cheap persistent clone), on
//!    the async compute pool. An undo swaps the previous snapshot in and
//!    rebuilds the cells its carve had changed; a redo swaps the snapshot
//!    the undo took back in again, and rebuilds the same cells.
//! 3. In the job runtime (module `jobs`), the job applies the exact
//!    carves and builds the meshes and colliders of every cell they
//!    changed, in parallel, off the main thread.
//! 4. In [`super::upload`], [`finish_jobs`](super::upload::finish_jobs)
//!    swaps the new octree in, records undo steps and queues the cells;
//!    [`upload_meshes`](super::upload::upload_meshes) adds them as assets
//!    and entities, with their colliders: all cells of a carve in the same
//!    frame, so that neighbouring cells always meet and the colliders
//!    match what is drawn. It writes a [`TerrainCellChanged`] per cell and
//!    each carve's [`CarveApplied`]. Only the first full build of a terrain
//!    is spread over frames, within [`TerrainSettings::mesh_budget`].

use std::collections::BTreeMap;
use std::time::Duration;

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, Edit};
use chisel_bsp::tree::Label;

use super::debris::DEFAULT_DEBRIS_DENSITY;
use super::debris_hulls::DEFAULT_MAX_DEBRIS_HULLS;
use super::error::TerrainError;
use super::mesh::DEFAULT_SMOOTHING_DEGREES;
use super::tool::{CarveTool, GridTool};

/// Carve a terrain: remove material inside the tool, add material to its
/// empty space, paint it, or keep only what is inside.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct Carve {
    /// The terrain entity.
    pub terrain: Entity,
    /// The tool, in the terrain's local frame.
    pub tool: CarveTool,
    /// What to do inside the tool.
    #[reflect(ignore)]
    pub edit: Edit,
}

/// A carve already on the terrain's grid, with a request id that its
/// [`CarveApplied`] or [`CarveRejected`] echoes: what a replicated carve
/// is. No floats are involved, so every peer applies the same exact tool.
/// Grid carves and [`Carve`]s of one frame are queued grid carves first.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct GridCarve {
    /// The terrain entity.
    pub terrain: Entity,
    /// The tool on the terrain's grid.
    #[reflect(ignore)]
    pub tool: GridTool,
    /// What to do inside the tool.
    #[reflect(ignore)]
    pub edit: Edit,
    /// Chosen by the sender; echoed in the result and recorded as
    /// [`Terrain::last_request`](super::Terrain::last_request) once the
    /// carve is in the octree.
    pub request: u64,
}

/// Undo the last carve of a terrain. For a world carve over several chunks
/// of a [`super::TerrainWorld`], send [`super::WorldUndo`] instead: it
/// undoes the carve in every chunk at once, with its debris across borders.
/// On a replicated terrain (feature `net`), see [`RedoCarve`].
#[derive(Message, Reflect, Clone, Copy, Debug)]
pub struct UndoCarve {
    /// The terrain entity.
    pub terrain: Entity,
}

/// Redo the carve the last [`UndoCarve`] of a terrain took back: its
/// octree and state hash become bit-identical to those right after that
/// carve, and the carve goes back on the journal and the undo history
/// (undo it again with [`UndoCarve`]). Undos since the last carve are
/// redone latest first; a new carve,
/// [`Terrain::clear_undo`](super::Terrain::clear_undo), a load, a detach
/// across chunk borders ([`super::TerrainWorld`]) or a
/// [`super::WorldUndo`] of the chunk forgets them. Undos and redos sent in
/// the same frame are queued undos first. With nothing to redo the
/// terrain is unchanged and a [`CarveRejected`] says
/// [`TerrainError::NothingToRedo`].
///
/// A piece of debris the carve cut loose is taken out of the terrain
/// again, as after the carve. As an undo leaves the piece's body alone
/// (its solid comes back into the terrain, the body stays where the game
/// left it), a redo spawns no new body and writes no
/// [`DebrisDetached`](super::DebrisDetached); its
/// [`CarveApplied::volume_change`] counts the piece in what it took out.
///
/// On a replicated terrain (`NetTerrain`, feature `net`) undos and redos
/// are ops of the terrain's network order, like its carves (module
/// `bevy_chisel::net::undo`): the server's go to every client, which
/// applies them exactly; a client's are requests the server allows or
/// refuses (`NetLimits::undo`), answered by a `NetUndoResult`. A
/// [`super::WorldUndo`] is redone with [`super::WorldRedo`], not with
/// this. A chunk of a world keeps its redo steps when it streams out and
/// back in unchanged (`world::redo`, "Streaming").
#[derive(Message, Reflect, Clone, Copy, Debug)]
pub struct RedoCarve {
    /// The terrain entity.
    pub terrain: Entity,
}

/// A carve (or undo, or redo) is applied and every mesh and collider it
/// changed is in place. A carve has its edit and `redo: false`, an undo
/// no edit, a redo the edit it redid and `redo: true`.
///
/// A mining game paying out the ore each carve digs up (material 4 here),
/// with [`TerrainSettings::measure_volumes`] on:
///
/// ```
/// use bevy::prelude::*;
/// use bevy_chisel::terrain::{CarveApplied, TerrainPlugin, TerrainSettings};
///
/// const ORE: u8 = 4;
///
/// #[derive(Resource, Default)]
/// struct Wallet {
///     /// Cubic metres of ore dug up.
///     ore: f64,
/// }
///
/// fn pay_out_ore(mut applied: MessageReader<CarveApplied>, mut wallet: ResMut<Wallet>) {
///     for carve in applied.read() {
///         let change = carve.volume_change.as_ref().and_then(|c| c.get(&ORE));
///         // Negative where the carve took ore out; an undo gives it back.
///         wallet.ore -= change.copied().unwrap_or(0.0);
///     }
/// }
///
/// let mut app = App::new();
/// app.add_plugins((MinimalPlugins, TerrainPlugin))
///     .insert_resource(TerrainSettings {
///         measure_volumes: true,
///         ..default()
///     })
///     .init_resource::<Wallet>()
///     .add_systems(Update, pay_out_ore);
/// app.update();
/// ```
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct CarveApplied {
    /// The terrain entity.
    pub terrain: Entity,
    /// The edit (`None` for an undo; for a redo, the edit redone).
    #[reflect(ignore)]
    pub edit: Option<Edit>,
    /// Whether this is a [`RedoCarve`] rather than a carve.
    pub redo: bool,
    /// The request id of a [`GridCarve`] (`None` for a [`Carve`], an undo
    /// or a redo).
    pub request: Option<u64>,
    /// `Some` for a carve a networked client applied ahead of the server,
    /// as a prediction of its own request (feature `net`,
    /// `NetClientSettings::predict_own_carves`), and for the undo that
    /// takes such a carve back when the server ordered another carve
    /// first or refused the request (a roll back); `None` for every
    /// other carve and undo. The number is the client's, one per
    /// application of a prediction (a prediction applied again after a
    /// roll back gets a new one); `request` is then `None`. A prediction
    /// the server confirms reports nothing more: the server's carve is
    /// not applied a second time.
    pub predicted: Option<u64>,
    /// The terrain's state hash right after this carve
    /// ([`Terrain::state_hash`](super::Terrain::state_hash); later carves
    /// of the same batch may already be in the octree when this message is
    /// read).
    pub hash: u64,
    /// Leaf cells this carve (or undo) changed, split or merged: their
    /// meshes were rebuilt or removed.
    pub cells: usize,
    /// What this carve changed of each material, in cubic world units:
    /// negative where it took material out, positive where it added some
    /// (a paint moves volume from the materials it covers to its own).
    /// Materials it left as they were are not listed. `None` unless
    /// [`TerrainSettings::measure_volumes`] is on.
    ///
    /// The regions are exact and only their volumes' sums rounded, so the
    /// changes of a terrain's carves add up to its volumes after less
    /// before ([`Terrain::volumes`](super::Terrain::volumes)) to about
    /// 1e-15 of the cells they changed. A piece the carve cut loose is not
    /// counted here: it has its volumes
    /// ([`TerrainDebris`](super::TerrainDebris)). An undo lists what it
    /// gave back, the pieces it brought back included; a redo what it took
    /// out again, those pieces included.
    pub volume_change: Option<BTreeMap<Label, f64>>,
    /// Time in the exact kernel (off the main thread).
    pub apply_time: Duration,
    /// Time building the cell meshes (off the main thread), shared by the
    /// carves of one batch.
    pub mesh_time: Duration,
    /// Time building the cell colliders (off the main thread; zero without
    /// a physics backend), shared by the carves of one batch.
    pub collider_time: Duration,
    /// From reading the request to the last changed mesh and collider
    /// being in place.
    pub latency: Duration,
}

impl CarveApplied {
    /// The material this carve took out, all materials together, in cubic
    /// world units (the negative part of [`CarveApplied::volume_change`];
    /// `None` when not measured).
    #[must_use]
    pub fn removed_volume(&self) -> Option<f64> {
        let change = self.volume_change.as_ref()?;
        Some(-change.values().filter(|v| **v < 0.0).sum::<f64>())
    }

    /// The material this carve put in, all materials together, in cubic
    /// world units (the positive part of [`CarveApplied::volume_change`];
    /// `None` when not measured).
    #[must_use]
    pub fn added_volume(&self) -> Option<f64> {
        let change = self.volume_change.as_ref()?;
        Some(change.values().filter(|v| **v > 0.0).sum())
    }
}

/// A carve, undo or redo that was refused; the terrain is unchanged.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct CarveRejected {
    /// The terrain entity.
    pub terrain: Entity,
    /// The request id of a [`GridCarve`] (`None` for a [`Carve`], an undo
    /// or a redo).
    pub request: Option<u64>,
    /// The number of a networked client's prediction the kernel refused
    /// ([`CarveApplied::predicted`]); `None` otherwise.
    pub predicted: Option<u64>,
    /// Why.
    #[reflect(ignore)]
    pub error: TerrainError,
}

/// The meshes (and colliders) of one leaf cell of a terrain were rebuilt,
/// or removed (no entities).
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
#[reflect(from_reflect = false)]
pub struct TerrainCellChanged {
    /// The terrain entity.
    pub terrain: Entity,
    /// The octree cell.
    #[reflect(ignore)]
    pub key: CellKey,
    /// Its entities now, one per visible material (empty when the cell is
    /// gone or has no surface).
    pub entities: Vec<Entity>,
}

/// Tuning of the terrain systems.
#[derive(Resource, Reflect, Clone, Debug)]
#[reflect(Resource, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TerrainSettings {
    /// Main-thread time per frame for adding the cells of a terrain's first
    /// full build (at least one cell per terrain and frame). A carve's
    /// cells are always added in one frame.
    pub mesh_budget: Duration,
    /// Most carves applied in one background job.
    pub max_batch: usize,
    /// Threads that apply carves and build cells in the background. The
    /// default is every core but one (at least one), so that the main
    /// thread keeps a core to itself however large the carve; results are
    /// bit-identical for any number.
    pub worker_threads: usize,
    /// Faces meeting at less than this angle (degrees) share smooth
    /// normals; sharper edges, such as crater rims, stay sharp. 0 gives
    /// flat shading.
    pub smoothing_degrees: f32,
    /// Whether a vertex on a cell border is smoothed over the faces of
    /// every cell around it (the default), so that shading shows no line
    /// along cell borders. Off, each cell smooths over its own faces only,
    /// which saves about 0.3 ms of meshing per crater carve (BENCHMARKS.md,
    /// "Terrain crater carves"). Only render meshes with smooth normals
    /// use it ([`TerrainSettings::shares_border_normals`]); read at each
    /// terrain's full build.
    pub smooth_across_cells: bool,
    /// Mass per cubic world unit of debris bodies.
    pub debris_density: f32,
    /// Most convex hulls in a debris body's collider: the piece's convex
    /// cells are merged where that adds no empty space, then where it adds
    /// the least, until this many are left.
    pub max_debris_hulls: usize,
    /// What is built for the cells a carve changed: render meshes (a game),
    /// colliders only (a dedicated server running physics) or nothing (a
    /// server or tool that needs the octree and its hash alone).
    pub output: CellOutput,
    /// Whether each [`CarveApplied`] says what its carve changed of each
    /// material ([`CarveApplied::volume_change`]), as a mining game needs.
    /// Off by default: it measures the changed cells before and after each
    /// carve, about 0.13 ms of a crater's job (`crater_job`: 1.1 ms
    /// without it).
    pub measure_volumes: bool,
}

impl TerrainSettings {
    /// Whether cell meshes share normals at cell borders: with
    /// [`TerrainSettings::smooth_across_cells`], smooth shading
    /// (`smoothing_degrees > 0`) and render meshes to build
    /// ([`CellOutput::Meshes`]).
    #[must_use]
    pub fn shares_border_normals(&self) -> bool {
        self.smooth_across_cells
            && self.smoothing_degrees > 0.0
            && self.output == CellOutput::Meshes
    }
}

/// What the terrain systems build for each cell a carve changes
/// ([`TerrainSettings::output`]). The octree, its state hash, undo and
/// debris detection are the same in every mode, so peers that build
/// different outputs still agree exactly.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CellOutput {
    /// Sealed render meshes, and colliders when a physics backend is set.
    #[default]
    Meshes,
    /// Colliders only (when a physics backend is set): cell entities have
    /// no mesh, and nothing is uploaded for rendering.
    Colliders,
    /// No cell entities, meshes or colliders. Switching back to another
    /// output rebuilds every cell once.
    Nothing,
}

impl CellOutput {
    /// What a chunk out of sight ([`ChunkOffstage`](super::ChunkOffstage))
    /// builds: no render meshes, colliders where this output builds them.
    #[must_use]
    pub fn out_of_sight(self) -> Self {
        match self {
            CellOutput::Meshes | CellOutput::Colliders => CellOutput::Colliders,
            CellOutput::Nothing => CellOutput::Nothing,
        }
    }
}

impl Default for TerrainSettings {
    fn default() -> Self {
        Self {
            mesh_budget: Duration::from_micros(1000),
            max_batch: 16,
            worker_threads: std::thread::available_parallelism()
                .map_or(1, |n| n.get().saturating_sub(1).max(1)),
            smoothing_degrees: DEFAULT_SMOOTHING_DEGREES,
            smooth_across_cells: true,
            debris_density: DEFAULT_DEBRIS_DENSITY,
            max_debris_hulls: DEFAULT_MAX_DEBRIS_HULLS,
            output: CellOutput::Meshes,
            measure_volumes: false,
        }
    }
}
