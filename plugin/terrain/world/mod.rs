//! Large worlds: a grid of terrain chunks streamed around focus entities,
//! built from a procedural source, with only the edited chunks stored.
//!
//! ## Design
//!
//! A [`TerrainWorld`] entity covers an unbounded area in x and z with a
//! grid of chunks ([`WorldLayout`]). Each chunk is an ordinary [`Terrain`]
//! entity, a child of the world: its own octree over one cube of edge
//! `2^chunk_log2` grid units, with its own cell meshes, colliders, carve
//! jobs and undo. Everything the single-terrain code does (exact carves,
//! seamed meshes, debris, physics, files) is reused per chunk unchanged;
//! the world only decides which chunks exist and routes carves to them.
//!
//! The alternative — one octree whose unedited leaves are regenerated on
//! demand — would save the per-chunk roots but needs the kernel to hold
//! "virtual" leaves; chunks as terrains need no kernel change and keep
//! every chunk's state hash, file and journal exact on its own.
//!
//! 1. **Source** ([`source`]): a [`WorldSource`] gives the exact grid
//!    height of every lattice sample (a closure, integer [`ValueNoise`],
//!    or a [`HeightArray`] from a heightfield image). A chunk's base is the heightfield of the
//!    samples on and inside its square, its walls on the cube's sides.
//! 2. **Streaming** ([`stream`]): chunks whose square comes within
//!    [`StreamSettings::load_radius`] of a [`TerrainFocus`] are built on
//!    the async compute pool, nearest first, at most
//!    [`StreamSettings::max_building`] at a time; chunks farther than
//!    [`StreamSettings::unload_radius`] from every focus are despawned
//!    (hysteresis between the two radii). [`TerrainWorld::stats`] counts
//!    what is live, building and stored.
//! 3. **Sparse edits**: a chunk nobody carved is never stored; it is
//!    rebuilt from the source when it streams in again. An edited chunk is
//!    kept as its terrain file bytes ([`Terrain::to_bytes`]: octree, undo
//!    history and journal, exact; with the seeds of a fall across chunk
//!    borders still on its way, [`debris`]) when it streams out, and
//!    restored from them bit-identically when it streams back in. A
//!    [`WorldCarve`] is rounded to the grid once and sent to every chunk
//!    its tool overlaps (as a [`GridCarve`](super::GridCarve)); a chunk that is not live
//!    then is built at once, whatever its distance, and holds the carve
//!    until it is. On a networked world's client (feature `net`) a chunk
//!    beyond every focus's unload radius instead keeps the carves waiting,
//!    in order, until it streams in, a detach across chunk borders needs
//!    it, [`TerrainWorld::with_max_deferred_carves`] of them wait, or
//!    [`TerrainWorld::build_deferred`] is called: a client then spends
//!    nothing on the carving far from it.
//! 4. **Files** ([`store`]): [`TerrainWorld::save`] writes one terrain
//!    file per edited chunk (`chunk_X_Z.chiselterrain`, atomically, as
//!    [`Terrain::save`]); [`TerrainWorld::load_edits`] reads them back,
//!    checking that each belongs to this world (same grid, same base).
//!    A [`SaveWorld`] message saves in the background instead, writing
//!    only the chunks changed since the last save to that folder; asked
//!    while the world is busy, it waits for a whole state, and after a few
//!    frames saves a consistent one (a world carved in every frame).
//! 5. **Multiplayer** (feature `net`, module `net::world`): the server
//!    numbers world carves and every peer routes them to its own chunks
//!    in that order ([`TerrainWorld::chunks_reached`], with the carve's
//!    number as the chunks' request id), so every chunk any peer holds is
//!    the server's whatever each streams in. Chunks installed from the
//!    server's snapshot count as edited ([`TerrainWorld::chunk_edited`])
//!    though they have no journal. Debris across chunk borders is the
//!    server's to decide and is ordered with the carves ([`debris_order`]).
//!
//! ## Chunk borders
//!
//! Neighbouring chunks see the same samples and the same diagonals on
//! their shared side, so their solids meet there exactly and a carve
//! across the border removes exactly the tool's volume from the two
//! together (tested against one terrain over both chunks). Each chunk
//! closes its own solid with a wall on the shared side; the two walls
//! coincide, face into the neighbour's solid and stay hidden under the
//! surface, and a carve that opens the border cuts both with the same
//! exact tool.
//!
//! Seams ([`seams`]): within a terrain the seamed mesher splits every
//! cell's border edges at its neighbours' wall points
//! ([`chisel_bsp::octree::SeamedMesher`]); across a chunk border each
//! chunk's mesher also takes, as *outside points*, the wall points of its
//! live neighbours' cells on its cube's sides and corner lines. Every job
//! of a chunk hands back its own such points; when they change (a carve,
//! an undo, a first build), [`seams::stitch_chunk_borders`] queues a
//! re-seal of each neighbour whose outside points change, which rebuilds
//! only the cells whose seams change (their colliders stay). So the
//! chunks' meshes meet edge to edge with identical exact vertices, as the
//! cells of one terrain do: no T-junctions across borders, also where four
//! chunks meet. A neighbour's meshes follow a carve one job later, so for
//! a frame or two after a carve the border may show a T-junction.
//!
//! Normals across borders: with the seams, each chunk hands back the exact
//! surface of its cells around its vertices on its sides (*border
//! wedges*, [`chisel_bsp::octree::SeamedMesher::border_wedges_in`]), and
//! each neighbour smooths its own vertices there over them too
//! ([`chisel_bsp::octree::SeamedMesher::set_outside_wedges`]). So a vertex
//! on a chunk border gets the same normal bits in every chunk that has it,
//! smoothed over the faces of every chunk around it, as a vertex on a cell
//! border inside a chunk does: shading shows no line along chunk borders
//! ([`TerrainSettings::smooth_across_cells`](super::TerrainSettings::smooth_across_cells)
//! off: each chunk smooths over its own faces). A neighbour is shaded
//! again only where the wedges it is given change.
//!
//! ## Debris
//!
//! Each chunk's jobs detach the pieces within the chunk, its sides
//! anchoring ([`chunk_debris`]); a pass over all live chunks
//! ([`debris`]) then joins the chunks exactly across their shared sides,
//! so a piece cut loose over one or more borders falls as one
//! [`TerrainDebris`](super::TerrainDebris), taken out of every chunk it
//! spans. A side towards a chunk that is not live anchors. The search runs
//! on the async compute pool, one per world; a frame only starts it and
//! later applies its result, and only to chunks still in the state it
//! searched (otherwise it searches again). The pass depends on which
//! chunks are live, so in a networked world (feature `net`) only the
//! server's runs: each result it applies is numbered in the world's order
//! of carves, and every client carries it out at that place over the same
//! chunks from the same seeds, with the same pieces ([`debris_order`]).
//!
//! ## Undo
//!
//! A chunk's own [`UndoCarve`](super::UndoCarve) takes back only that
//! chunk's last carve; [`WorldUndo`] takes back the world's last
//! [`WorldCarve`] in every chunk it changed, with the parts that its
//! detaches across chunk borders took out of chunks it never reached
//! ([`undo`]). The world keeps one step per world carve, up to
//! [`TerrainWorld::with_max_undo`] (a terrain's default), noting per chunk
//! the state the carve left; the undo waits until every chunk of the step
//! holds every request made before it (world carves asked for meanwhile
//! wait for it, chunks streamed out are restored for it), checks them all,
//! and then changes all or none: a chunk changed since by anything else,
//! or whose undo history was trimmed, refuses it with a
//! [`WorldUndoRejected`] naming the chunk. A networked world refuses it.
//! [`WorldRedo`] re-applies what the last world undo took back, in the
//! same line and all or nothing, bit for bit ([`redo`]); a new
//! [`WorldCarve`] forgets it. Streaming keeps every redo step: the
//! world's own, and a chunk's (kept by the world while it is out).
//!
//! ## Level of detail
//!
//! A [`WorldLod`] beside the world ([`lod`], meshes in [`lod_mesh`])
//! draws the chunks beyond the full-detail ones, out to
//! [`LodSettings::far_radius`], from coarse meshes built on the async
//! compute pool, no BSP and no collider: an unedited chunk as the source
//! sampled at every `2^k`-th lattice sample (its error `e_k` the exact
//! largest vertical distance to the full surface), an edited chunk as its
//! exact surface simplified by vertex clustering on cubes of edge
//! `s·2^(k−1)` (every point within the cube diagonal of the exact
//! surface, so an edit shows at every level within that bound). Each
//! chunk is drawn at the coarsest level whose error, projected from the
//! nearest focus's distance with the focus camera's field of view and
//! viewport height, stays within [`LodSettings::pixel_tolerance`], with
//! hysteresis. An edited chunk's coarse border stays exact, and every
//! coarse mesh hangs skirts along its sides, deeper than any two levels'
//! borders there can be apart (full-detail chunks have walls there), so no
//! crack opens between chunks of different levels, full detail included.

mod chunk;
pub mod debris;
pub mod debris_order;
pub(crate) mod history;
pub mod lod;
pub mod lod_mesh;
pub mod redo;
pub mod seams;
pub mod source;
pub mod store;
mod store_cut;
mod store_files;
mod store_save;
pub mod stream;
pub mod undo;

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Duration;

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, DebrisLimits, Edit};
use chisel_bsp::tree::Label;

use super::component::Terrain;
use super::error::TerrainError;
use super::pool_order::PoolOrder;
use super::tool::{CarveTool, GridTool};

pub(crate) use chunk::{Built, Chunk, generate, restore};
pub use chunk::{ChunkCoord, ChunkOffstage, WorldChunk, chunk_debris};
pub use lod::{LodMesh, LodSettings, LodStats, LodView, WorldLod, choose_level};
pub use lod_mesh::{LevelMesh, LodBasis, LodPyramid};
pub use redo::{WorldRedo, WorldRedoRefusal, WorldRedoRejected, WorldRedone};
pub use source::{HeightArray, NoiseOctave, SharedSource, ValueNoise, WorldLayout, WorldSource};
pub use store::{DEFAULT_MAX_SAVE_WAIT, SaveWorld, WorldSaveFailed, WorldSaved};
pub use store_cut::{DEFAULT_SAVE_HOLD_FRAMES, DEFAULT_SAVE_SETTLE_FRAMES};
pub use stream::DEFAULT_MAX_DEFERRED_CARVES;
pub use undo::{WorldUndo, WorldUndoRefusal, WorldUndoRejected, WorldUndone};

/// Marks an entity (camera, player) around which a world's chunks are
/// streamed in.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Default)]
pub struct TerrainFocus;

/// How far around the foci chunks are kept, and how many build at once.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamSettings {
    /// Chunks whose square comes this close (world units, horizontally)
    /// to a focus are streamed in.
    pub load_radius: f32,
    /// Chunks farther than this from every focus are streamed out (at
    /// least `load_radius`; the gap is the hysteresis).
    pub unload_radius: f32,
    /// Most chunk builds on the async compute pool at once (as many more
    /// coarse chunk builds of a [`WorldLod`]). A build that has not
    /// started steps back behind the world's carve, undo and debris work
    /// waiting there, for at most eight such tasks spawned after it came
    /// to run: craters show and pieces fall without waiting for the
    /// builds, and chunks keep streaming in under a constant stream of
    /// carves. See [`debris`], *Priority on the pool*.
    pub max_building: usize,
}

impl Default for StreamSettings {
    fn default() -> Self {
        Self {
            load_radius: 64.0,
            unload_radius: 96.0,
            max_building: 4,
        }
    }
}

/// Counts of a world's chunks and its streaming work so far.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WorldStats {
    /// Chunks with a terrain entity now.
    pub live: usize,
    /// Chunks being built or restored now.
    pub building: usize,
    /// Edited chunks kept while streamed out.
    pub stored: usize,
    /// Bytes of the stored chunks.
    pub stored_bytes: usize,
    /// Chunks built from the source so far.
    pub generated: u64,
    /// Chunks restored from their stored state so far.
    pub restored: u64,
    /// Chunks streamed out so far.
    pub released: u64,
    /// Chunk builds that failed (a bad source sample); see the log.
    pub failed: u64,
    /// Time spent building chunks on the pool (generated and restored).
    pub build_time: Duration,
    /// Pieces cut loose across chunk borders so far ([`debris`]).
    pub detached_across: u64,
    /// Searches for debris across chunk borders started so far, on the
    /// async compute pool ([`debris`]).
    pub debris_searches: u64,
    /// Of those, the searches dropped because a chunk they depend on
    /// changed or streamed out while they ran (each searched again).
    pub debris_searches_dropped: u64,
}

/// A streamed world of terrain chunks. Spawn it with a
/// [`WorldLayout`] and a [`WorldSource`]; put [`TerrainFocus`] on the
/// entities chunks should stream around, and carve it with [`WorldCarve`].
///
/// # Change detection
///
/// `Changed<TerrainWorld>` marks the frames in which the world's chunks or
/// edits changed: a chunk build started or collected (a chunk goes live
/// or fails), a chunk released or stored, waiting carves handed to a
/// chunk, a [`WorldCarve`] routed, a [`WorldUndo`] or [`WorldRedo`] accepted and then
/// carried out or refused, a detach across chunk borders applied, the chunks replaced
/// from a snapshot (feature `net`), and any write of the game's own
/// through `&mut TerrainWorld`. Frames that only poll builds, seams and
/// debris searches, or start or finish a save ([`SaveWorld`]), mark
/// nothing, so a settled world with still foci is never marked. The chunks' own content is each chunk's
/// `Changed<Terrain>` ([`Terrain`], "Change detection"): a world carve
/// marks exactly the chunks it reached, each in the frame it lands there.
#[derive(Component)]
#[require(Transform)]
#[cfg_attr(feature = "render", require(Visibility))]
pub struct TerrainWorld {
    pub(crate) layout: WorldLayout,
    pub(crate) source: SharedSource,
    pub(crate) settings: StreamSettings,
    /// Labels carves may add or paint besides the layout's.
    pub(crate) labels: Vec<Label>,
    pub(crate) chunks: BTreeMap<ChunkCoord, Chunk>,
    /// Terrain file bytes of edited chunks that are not live.
    pub(crate) stored: BTreeMap<ChunkCoord, Arc<Vec<u8>>>,
    /// Seeds a [`WorldUndo`] gave back to chunks being built or not built
    /// and not stored, put into each chunk's terrain when its build is
    /// collected ([`undo`]).
    pub(crate) seeds_back: BTreeMap<ChunkCoord, Vec<CellKey>>,
    /// Carves for chunks that are not live yet, in order, each with the
    /// request id of its world carve.
    pub(crate) pending: BTreeMap<ChunkCoord, Vec<(GridTool, Edit, u64)>>,
    /// The chunks of `pending` that streaming left unbuilt in its last
    /// pass: far chunks of a networked world's client (`stream`).
    pub(crate) deferred: BTreeSet<ChunkCoord>,
    /// Deferred chunks [`TerrainWorld::build_deferred`] asked to build.
    pub(crate) deferred_wanted: BTreeSet<ChunkCoord>,
    /// Most carves a deferred chunk keeps waiting before it is built.
    pub(crate) max_deferred_carves: usize,
    /// Chunks kept as edited whatever their journal says: chunks installed
    /// from a snapshot (no journal, yet not the source's).
    pub(crate) kept: BTreeSet<ChunkCoord>,
    pub(crate) stats: WorldStats,
    /// The request id of the next world carve routed (every chunk carve of
    /// one world carve shares it).
    pub(crate) next_request: u64,
    /// The chunks' border points and the outside points they were given.
    pub(crate) seams: seams::WorldSeams,
    /// What one detach across chunk borders may take out ([`debris`]).
    pub(crate) debris_limits: DebrisLimits,
    /// Whether pieces cut loose across chunk borders are detached
    /// ([`debris`]); off in a networked world.
    pub(crate) debris_across_borders: bool,
    /// The search for debris across chunk borders running or waiting to
    /// be applied ([`debris`]).
    pub(crate) debris_search: Option<debris::DebrisSearch>,
    /// Who decides what falls across chunk borders ([`debris_order`]).
    pub(crate) debris_role: debris_order::DebrisRole,
    /// Chunks built and kept for debris across borders in a networked
    /// world ([`debris_order`]), whatever the foci.
    pub(crate) debris_keep: BTreeSet<ChunkCoord>,
    /// A server's chunks to build before it searches again: the chunks
    /// across the open sides where its last search stopped
    /// ([`debris_order`]).
    pub(crate) debris_wanted: BTreeSet<ChunkCoord>,
    /// The chunks streaming wants that are not live yet (building, or
    /// waiting for a build to start), as of its last pass: seeds beside
    /// them wait for them ([`debris`]).
    pub(crate) loading: BTreeSet<ChunkCoord>,
    /// Whether a live chunk held seeds that no search took when the pass
    /// last looked ([`debris`]): a search is still to come.
    pub(crate) debris_seeded: bool,
    /// The detach a networked world's server ordered, waiting to be
    /// carried out here ([`debris_order`]).
    pub(crate) detach_ordered: Option<debris_order::OrderedDetach>,
    /// Detaches applied and not yet read by the networked world's side
    /// ([`debris_order`]).
    pub(crate) detaches_applied: Vec<debris_order::AppliedDetach>,
    /// The world carves that can be undone and the undos waiting
    /// ([`undo`]).
    pub(crate) history: history::WorldHistory,
    /// What the folders saved to hold and the save being written ([`store`]).
    pub(crate) saves: store::WorldSaves,
    /// The world carves of several chunks that may be in flight in one
    /// of them, for a save of a busy world ([`store`]).
    pub(crate) routed: store_cut::RoutedCarves,
    /// Its carves and debris work before its builds (`pool_order`).
    pub(crate) pool_order: PoolOrder,
}

impl TerrainWorld {
    /// A world cut as `layout`, its surface from `source`.
    ///
    /// # Errors
    /// [`TerrainError::InvalidWorld`] for bad sizes ([`WorldLayout::check`]).
    pub fn new(layout: WorldLayout, source: impl WorldSource) -> Result<Self, TerrainError> {
        layout.check()?;
        Ok(Self {
            layout,
            source: Arc::new(source),
            settings: StreamSettings::default(),
            labels: Vec::new(),
            chunks: BTreeMap::new(),
            stored: BTreeMap::new(),
            seeds_back: BTreeMap::new(),
            pending: BTreeMap::new(),
            deferred: BTreeSet::new(),
            deferred_wanted: BTreeSet::new(),
            max_deferred_carves: DEFAULT_MAX_DEFERRED_CARVES,
            kept: BTreeSet::new(),
            stats: WorldStats::default(),
            next_request: 0,
            seams: seams::WorldSeams::default(),
            debris_limits: DebrisLimits::default(),
            debris_across_borders: true,
            debris_search: None,
            debris_role: debris_order::DebrisRole::Local,
            debris_keep: BTreeSet::new(),
            debris_wanted: BTreeSet::new(),
            loading: BTreeSet::new(),
            debris_seeded: false,
            detach_ordered: None,
            detaches_applied: Vec::new(),
            history: history::WorldHistory::default(),
            saves: store::WorldSaves::default(),
            routed: store_cut::RoutedCarves::default(),
            pool_order: PoolOrder::default(),
        })
    }

    /// Bounds what one detach across chunk borders takes out, all pieces
    /// in all chunks together, in cubic grid units and convex cells; over
    /// them the pieces stay in place ([`debris`]). No limit by default.
    #[must_use]
    pub fn with_debris_limits(mut self, limits: DebrisLimits) -> Self {
        self.debris_limits = limits;
        self
    }

    /// The limits of a detach across chunk borders
    /// ([`TerrainWorld::with_debris_limits`]).
    #[must_use]
    pub fn debris_limits(&self) -> DebrisLimits {
        self.debris_limits
    }

    /// Whether pieces cut loose across chunk borders fall ([`debris`]; on
    /// by default). Off, each chunk detaches only what lies within it and
    /// a piece over a border stays, held by it. In a networked world
    /// (feature `net`) the server's setting decides: a client carries out
    /// the detaches its server orders ([`debris_order`]) whatever its own.
    #[must_use]
    pub fn with_debris_across_borders(mut self, on: bool) -> Self {
        self.debris_across_borders = on;
        self
    }

    /// Whether pieces cut loose across chunk borders fall
    /// ([`TerrainWorld::with_debris_across_borders`]).
    #[must_use]
    pub fn debris_across_borders(&self) -> bool {
        self.debris_across_borders
    }

    /// Whether a search for debris across chunk borders runs on the async
    /// compute pool or waits, done, to be applied ([`debris`]).
    #[must_use]
    pub fn debris_searching(&self) -> bool {
        self.debris_search.is_some()
    }

    /// Keeps at most `steps` world carves for [`WorldUndo`] (older ones are
    /// forgotten), and as many undo steps in each chunk
    /// ([`Terrain::with_max_undo`]), so that the chunks hold every step
    /// the world may undo. The default is a terrain's,
    /// [`DEFAULT_MAX_UNDO`](crate::terrain::component::DEFAULT_MAX_UNDO);
    /// 0 turns undo off.
    #[must_use]
    pub fn with_max_undo(mut self, steps: usize) -> Self {
        self.history.max = steps;
        self
    }

    /// The most world carves kept for undo ([`TerrainWorld::with_max_undo`]).
    #[must_use]
    pub fn max_undo(&self) -> usize {
        self.history.max
    }

    /// How many world carves a [`WorldUndo`] can take back now (those
    /// already claimed by a waiting [`WorldUndo`] included).
    #[must_use]
    pub fn undo_depth(&self) -> usize {
        self.history.depth()
    }

    /// How many world undos a [`WorldRedo`] can re-apply now: the
    /// [`WorldUndo`]s carried out since the last world carve, less the
    /// [`WorldRedo`]s carried out since (waiting ones not counted).
    #[must_use]
    pub fn redo_depth(&self) -> usize {
        self.history.redo_depth()
    }

    /// With these streaming radii and build limit.
    ///
    /// # Errors
    /// [`TerrainError::InvalidWorld`] for a non-finite or negative radius,
    /// an unload radius below the load radius, or no builds allowed.
    pub fn with_streaming(mut self, settings: StreamSettings) -> Result<Self, TerrainError> {
        let ok = settings.load_radius.is_finite()
            && settings.load_radius >= 0.0
            && settings.unload_radius.is_finite()
            && settings.unload_radius >= settings.load_radius
            && settings.max_building > 0;
        if !ok {
            return Err(TerrainError::InvalidWorld {
                reason: format!(
                    "streaming needs 0 <= load_radius <= unload_radius and max_building > 0, \
                     got {settings:?}"
                ),
            });
        }
        self.settings = settings;
        Ok(self)
    }

    /// Declares materials that carves may add or paint in every chunk
    /// ([`Terrain::with_labels`]).
    #[must_use]
    pub fn with_labels(mut self, labels: impl IntoIterator<Item = Label>) -> Self {
        self.labels.extend(labels);
        self
    }

    /// The layout.
    #[must_use]
    pub fn layout(&self) -> &WorldLayout {
        &self.layout
    }

    /// The streaming settings.
    #[must_use]
    pub fn streaming(&self) -> &StreamSettings {
        &self.settings
    }

    /// Counts of chunks and streaming work.
    #[must_use]
    pub fn stats(&self) -> &WorldStats {
        &self.stats
    }

    /// Passes over the chunk-border seams so far: frames in which a chunk
    /// streamed in or out, a chunk's border points changed, or a chunk
    /// still waited for its first outside points ([`seams`]). Other frames
    /// only look whether one of these happened.
    #[must_use]
    pub fn seam_passes(&self) -> u64 {
        self.seams.passes
    }

    /// Live chunks given their live neighbours' outside points ([`seams`]).
    #[must_use]
    pub fn seamed_chunks(&self) -> usize {
        self.seams.seamed()
    }

    /// The terrain entity of chunk `coord`, when it is live.
    #[must_use]
    pub fn chunk_entity(&self, coord: ChunkCoord) -> Option<Entity> {
        match self.chunks.get(&coord) {
            Some(Chunk::Live(entity)) => Some(*entity),
            _ => None,
        }
    }

    /// Every live chunk with its terrain entity, in coordinate order.
    pub fn live_chunks(&self) -> impl Iterator<Item = (ChunkCoord, Entity)> + '_ {
        self.chunks.iter().filter_map(|(c, s)| match s {
            Chunk::Live(e) => Some((*c, *e)),
            _ => None,
        })
    }

    /// The edited chunks kept while streamed out.
    pub fn stored_chunks(&self) -> impl Iterator<Item = ChunkCoord> + '_ {
        self.stored.keys().copied()
    }

    /// The terrain file bytes ([`Terrain::to_bytes`]) of edited chunk
    /// `coord` while it is streamed out (`None` when it is live or
    /// unedited).
    #[must_use]
    pub fn stored_chunk(&self, coord: ChunkCoord) -> Option<&[u8]> {
        self.stored.get(&coord).map(|bytes| bytes.as_slice())
    }

    /// Whether live chunk `coord` with `terrain` (its terrain entity's
    /// [`Terrain`]) is edited, not what the source gives: it has a journal
    /// or undo history, a detach across chunk borders took solid out of it
    /// ([`debris`]), or it was installed from a snapshot of a networked
    /// world (feature `net`). Edited chunks are stored when they
    /// stream out and written by [`TerrainWorld::save`].
    #[must_use]
    pub fn chunk_edited(&self, coord: ChunkCoord, terrain: &Terrain) -> bool {
        terrain.is_edited() || self.kept.contains(&coord)
    }

    /// Checks that `edit` adds or paints only materials the world knows
    /// (the layout's and [`TerrainWorld::with_labels`]).
    ///
    /// # Errors
    /// [`TerrainError::UnknownLabel`].
    pub fn check_edit(&self, edit: Edit) -> Result<(), TerrainError> {
        if let Edit::Add(label) | Edit::Paint(label) = edit {
            let known = std::iter::once(self.layout.label)
                .chain(self.layout.layers.iter().map(|&(_, l)| l))
                .chain(self.labels.iter().copied())
                .collect::<BTreeSet<_>>();
            if label != chisel_bsp::tree::EMPTY && !known.contains(&label) {
                return Err(TerrainError::UnknownLabel {
                    label,
                    known: known.into_iter().collect(),
                });
            }
        }
        Ok(())
    }

    /// The chunks a grid tool reaches, in coordinate order: those whose
    /// cubes the grid boxes of its pieces overlap, open (a piece that only
    /// touches a chunk's side does not reach it).
    ///
    /// # Errors
    /// [`TerrainError::OutsideTerrain`] when it reaches no chunk.
    pub fn chunks_reached(&self, tool: &GridTool) -> Result<Vec<ChunkCoord>, TerrainError> {
        let layout = &self.layout;
        let edge = layout.chunk_edge();
        let (bottom, top) = (layout.floor, layout.floor + edge);
        let mut coords = BTreeSet::new();
        let (mut lo, mut hi) = ([i64::MAX; 3], [i64::MIN; 3]);
        for piece in &tool.pieces {
            let (mut min, mut max) = ([i64::MAX; 3], [i64::MIN; 3]);
            for p in piece {
                for a in 0..3 {
                    min[a] = min[a].min(p[a]);
                    max[a] = max[a].max(p[a]);
                }
            }
            for a in 0..3 {
                lo[a] = lo[a].min(min[a]);
                hi[a] = hi[a].max(max[a]);
            }
            if max[1] <= bottom || min[1] >= top || max[0] <= min[0] || max[2] <= min[2] {
                continue;
            }
            for x in min[0].div_euclid(edge)..=(max[0] - 1).div_euclid(edge) {
                for z in min[2].div_euclid(edge)..=(max[2] - 1).div_euclid(edge) {
                    coords.insert(ChunkCoord { x, z });
                }
            }
        }
        if coords.is_empty() {
            return Err(TerrainError::OutsideTerrain {
                tool_min: lo,
                tool_max: hi,
            });
        }
        Ok(coords.into_iter().collect())
    }

    /// Queues one world carve for chunks `coords` under request id
    /// `request` (what their [`CarveApplied`](super::CarveApplied) and
    /// [`CarveRejected`](super::CarveRejected) reports name); chunks that
    /// are not live are built for it.
    pub(crate) fn route(
        &mut self,
        tool: &GridTool,
        edit: Edit,
        request: u64,
        coords: &[ChunkCoord],
    ) {
        for &coord in coords {
            self.pending
                .entry(coord)
                .or_default()
                .push((tool.clone(), edit, request));
        }
        self.next_request = self.next_request.max(request.saturating_add(1));
        self.routed.route(request, coords);
        if self.debris_role == debris_order::DebrisRole::Local {
            self.history.push_step(request, coords);
        }
    }

    /// Whether chunk `coord` failed to build (its carves were dropped).
    #[cfg(feature = "net")]
    pub(crate) fn chunk_failed(&self, coord: ChunkCoord) -> bool {
        matches!(self.chunks.get(&coord), Some(Chunk::Failed))
    }

    /// Replaces every chunk's state with `edited` (terrain file bytes of
    /// the edited chunks; every other chunk is the source's): live chunks
    /// are despawned but those in `keep` (live chunks that already hold
    /// their new state), builds dropped and waiting carves cleared, and
    /// the chunks stream in again from `edited` or the source. The chunks
    /// in `edited` count as edited whatever their journals say.
    #[cfg(feature = "net")]
    pub(crate) fn reset_chunks(
        &mut self,
        commands: &mut Commands,
        mut edited: BTreeMap<ChunkCoord, Arc<Vec<u8>>>,
        keep: &BTreeMap<ChunkCoord, Entity>,
    ) {
        for (coord, state) in std::mem::take(&mut self.chunks) {
            if let Chunk::Live(entity) = state {
                if keep.get(&coord) == Some(&entity) {
                    self.chunks.insert(coord, Chunk::Live(entity));
                } else {
                    commands.entity(entity).try_despawn();
                    self.stats.released += 1;
                }
            }
        }
        let kept_edited: Vec<ChunkCoord> = (edited.keys())
            .filter(|c| self.chunks.contains_key(c))
            .copied()
            .collect();
        self.kept = edited.keys().copied().collect();
        for coord in kept_edited {
            edited.remove(&coord);
        }
        self.pending.clear();
        self.deferred.clear();
        self.deferred_wanted.clear();
        self.debris_search = None;
        self.debris_keep.clear();
        self.debris_wanted.clear();
        self.loading.clear();
        self.debris_seeded = false;
        self.detach_ordered = None;
        self.detaches_applied.clear();
        self.history.clear();
        self.routed.clear();
        self.stored = edited;
        self.seeds_back.clear();
        self.stats.stored = self.stored.len();
        self.stats.stored_bytes = self.stored.values().map(|b| b.len()).sum();
    }

    /// Whether no chunk is building, no carve waits for a chunk (but the
    /// deferred ones, [`TerrainWorld::deferred_chunks`], which wait by
    /// design), no [`WorldUndo`] or [`WorldRedo`] waits, and no search for debris across
    /// chunk borders runs, waits to be applied or waits to start (seeds in
    /// a chunk; nor, in a networked world, a detach its server ordered).
    #[must_use]
    pub fn is_settled(&self) -> bool {
        self.pending.keys().all(|c| self.deferred.contains(c))
            && !self.history.holds_carves()
            && self.debris_search.is_none()
            && !self.debris_seeded
            && self.detach_ordered.is_none()
            && !self
                .chunks
                .values()
                .any(|c| matches!(c, Chunk::Building(_)))
    }

    /// The terrain of chunk `coord` as generated from the source, without
    /// any edit (what an unedited chunk streams in as).
    ///
    /// # Errors
    /// As [`WorldLayout::chunk_base`] and [`Terrain::from_base`].
    pub fn generate_chunk(&self, coord: ChunkCoord) -> Result<Terrain, TerrainError> {
        generate(&self.layout, &*self.source, &self.labels, coord)
    }
}

/// Carve a world: the tool (in the world entity's local frame) is rounded
/// to the grid once and applied to every chunk it overlaps, each reporting
/// its own [`CarveApplied`](super::CarveApplied) or
/// [`CarveRejected`](super::CarveRejected) for its terrain entity (their
/// `volume_change`s add up to what the carve changed of each material in
/// the world). A tool
/// that reaches no chunk's cube, or adds or paints a material the world
/// does not know, is rejected for the world entity. A chunk that is not
/// live is built for the carve; if its build fails (a bad source sample)
/// its waiting carves are dropped with a warning in the log. [`WorldUndo`]
/// takes the last one back in every chunk, [`WorldRedo`] re-applies it;
/// a new one forgets what was undone before it. A networked world (feature
/// `net`) refuses it ([`TerrainError::NetworkedWorld`]): its server orders
/// every carve.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct WorldCarve {
    /// The world entity.
    pub world: Entity,
    /// The tool, in the world's local frame.
    pub tool: CarveTool,
    /// What to do inside the tool.
    #[reflect(ignore)]
    pub edit: Edit,
}
