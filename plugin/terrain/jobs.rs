//! The carve job runtime: a terrain's work in progress, and what a job
//! does on the worker threads.
//!
//! A carve goes through the terrain modules in this order, each once:
//!
//! 1. [`super::carve`] — the [`Carve`](super::Carve),
//!    [`GridCarve`](super::GridCarve), [`UndoCarve`](super::UndoCarve)
//!    and [`RedoCarve`](super::RedoCarve) messages.
//! 2. [`super::queue`] — reads them into the terrain's queue of [`Job`]s
//!    (in its [`Runtime`]) and starts the next job on a snapshot of the
//!    octree (a cheap persistent clone).
//! 3. This module — the job itself, off the main thread: it applies a
//!    batch of carves in order ([`carve_batch`], each through
//!    [`apply_carve_with_faces`]) or takes the octree an undo restored,
//!    then builds everything the main thread will show for every cell
//!    that changed ([`remesh`]): the cell meshes and, with a physics
//!    backend, their colliders. It hands back a [`JobOutput`].
//! 4. [`super::upload`] — swaps the job's octree in, records undo steps,
//!    queues the cells as an [`Upload`] and adds them as assets and
//!    entities, then writes the reports.
//!
//! [`apply_carve`] is the same exact step for code outside the ECS.

use std::collections::{BTreeMap, BTreeSet, HashMap, VecDeque};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::tasks::Task;
use chisel_bsp::exact::Point4;
use chisel_bsp::octree::{
    CellFaces, CellKey, Changes, ChunkedPiece, DebrisConfig, DebrisPiece, Edit, Octree,
    PointWedges, SeamedMesher, Tool,
};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::{BoundaryFace, Label};
use rayon::prelude::*;

use super::carve::{CarveApplied, CellOutput};
use super::debris::{BuiltDebris, build_debris, build_debris_of};
use super::error::TerrainError;
use super::mesh::{ColliderMesh, cell_meshes_around};
use super::physics::{PhysicsInsert, TerrainPhysics};
use super::tool::GridTool;
use super::world::seams::BorderPoints;

/// Work in progress of a terrain (main-world only).
pub(crate) struct Runtime {
    pub(crate) queue: VecDeque<Job>,
    pub(crate) task: Option<Task<JobOutput>>,
    pub(crate) uploads: VecDeque<Upload>,
    pub(crate) cells: HashMap<CellKey, Vec<(Label, Entity, usize)>>,
    pub(crate) triangles: usize,
    pub(crate) needs_full_mesh: bool,
    /// Whether the settings ask for cells ([`CellOutput`]): when
    /// not, a pending full build does not keep the terrain busy.
    pub(crate) builds_cells: bool,
    /// The output the cells shown were built for (`None` before the
    /// first job that built cells): another output rebuilds every cell.
    pub(crate) cells_output: Option<CellOutput>,
    /// The border vertices of the cells shown (in the running job while
    /// there is one).
    pub(crate) mesher: SeamedMesher,
    /// The labels the terrain's material table has materials for, kept up
    /// to date from its `TerrainMaterials` (feature `render`); `None`
    /// without a table.
    pub(crate) material_labels: Option<BTreeSet<Label>>,
    /// Whether jobs hand back the wall points on the cube's sides (a chunk
    /// of a [`super::TerrainWorld`]).
    pub(crate) publishes_border: bool,
    /// Those wall points as of the meshes shown (`None` before the first
    /// job that built cells).
    pub(crate) border: Option<Arc<BorderPoints>>,
    /// Whether the running job only seals cells again ([`Job::Reseal`]).
    pub(crate) resealing: bool,
    /// Leaves that carves of a chunk changed since the last detach across
    /// chunk borders (`world::debris`), sorted on use.
    pub(crate) border_seeds: Vec<CellKey>,
    /// Whether tracked carves are noted in `landed` (a chunk of a world:
    /// its undo steps, `world::undo`, and its saves, `world::store`).
    pub(crate) records_landed: bool,
    /// Tracked carves applied or refused since the world last looked.
    pub(crate) landed: Vec<super::world::history::Landed>,
    /// The request ids of the carves in the running job (`None` for an
    /// untracked one); empty while no carve job runs. Not in the octree
    /// yet: a world's save may leave them out (`world::store`).
    pub(crate) running_carves: Vec<Option<u64>>,
}

/// A request waiting for its turn.
pub(crate) enum Job {
    Carve {
        tool: GridTool,
        edit: Edit,
        requested: Instant,
        request: Option<u64>,
        /// The number of a networked client's prediction (`net`): the
        /// carve is applied ahead of the server, untracked, and its undo
        /// step remembers the number.
        predicted: Option<u64>,
    },
    Undo {
        requested: Instant,
        /// A replicated undo's place in its terrain's order (`net`):
        /// [`Terrain::last_request`](super::Terrain::last_request) moves
        /// to it whether it applies or not; `None` for an untracked undo.
        request: Option<u64>,
        /// Undo only the step of this prediction, if it is the last
        /// step (a prediction the kernel refused left none); `None`:
        /// the last step, whatever it is.
        predicted: Option<u64>,
    },
    Redo {
        requested: Instant,
        /// As [`Job::Undo`]'s `request`.
        request: Option<u64>,
    },
    /// Holds the queue until the world's undo or redo whose hold is
    /// `hold` is carried out in every chunk it changes (`world::undo`,
    /// `world::redo`): the jobs behind it were asked for after it.
    HoldForWorldUndo { hold: u64 },
    /// Seal the cells again at new outside points (the wall points of
    /// neighbouring chunks on the cube's sides), and shade them again with
    /// new outside wedges (those chunks' surface around the points).
    Reseal {
        outside: Vec<Point4>,
        wedges: PointWedges,
    },
    /// Rebuild the cells a detach across chunk borders changed (already
    /// in the octree) and build the pieces this chunk spawns
    /// ([`super::world::debris`]).
    Detached {
        keys: Vec<CellKey>,
        pieces: Vec<ChunkedPiece>,
    },
}

impl Default for Runtime {
    fn default() -> Self {
        Self {
            queue: VecDeque::new(),
            task: None,
            uploads: VecDeque::new(),
            cells: HashMap::new(),
            triangles: 0,
            needs_full_mesh: true,
            builds_cells: true,
            cells_output: None,
            mesher: SeamedMesher::with_shading(),
            material_labels: None,
            publishes_border: false,
            border: None,
            resealing: false,
            border_seeds: Vec::new(),
            records_landed: false,
            landed: Vec::new(),
            running_carves: Vec::new(),
        }
    }
}

/// A finished job's cells and reports, waiting for the upload
/// ([`super::upload::upload_meshes`]), or cells to take away when a
/// terrain stops building cells.
pub(crate) struct Upload {
    /// Cells still to add, in key order.
    pub(crate) cells: VecDeque<CellUpdate>,
    /// Whether the cells may be spread over frames (a first full build).
    pub(crate) spread: bool,
    /// The reports to write once every cell is in place.
    pub(crate) reports: Vec<(CarveApplied, Instant)>,
    /// The pieces to spawn then, with the prediction that cut each loose
    /// ([`Job::Carve`]).
    pub(crate) debris: Vec<(BuiltDebris, Option<u64>)>,
}

/// Applies `tool` with `edit` to `octree`: builds the exact tool, checks
/// that it reaches into the octree's cube, then applies it.
///
/// # Errors
/// [`TerrainError::Kernel`] for a degenerate or out-of-range tool or an
/// invalid edit, [`TerrainError::OutsideTerrain`] for a tool that misses
/// the cube. The octree is unchanged on error.
pub fn apply_carve(
    octree: &mut Octree,
    tool: &GridTool,
    edit: Edit,
) -> Result<Changes, TerrainError> {
    let built = built_inside(octree, tool)?;
    Ok(octree.apply(&built, edit)?)
}

/// [`apply_carve`], also handing back the boundary faces of the cells whose
/// content the carve replaced ([`Octree::apply_with_faces`]), from which
/// [`super::mesh::cell_meshes_from`] meshes those cells without cutting
/// their BSPs again.
///
/// # Errors
/// As [`apply_carve`]; the octree is unchanged on error.
pub fn apply_carve_with_faces(
    octree: &mut Octree,
    tool: &GridTool,
    edit: Edit,
) -> Result<(Changes, CellFaces), TerrainError> {
    let built = built_inside(octree, tool)?;
    Ok(octree.apply_with_faces(&built, edit)?)
}

/// The exact tool, checked to reach into the octree's cube.
fn built_inside(octree: &Octree, tool: &GridTool) -> Result<Tool, TerrainError> {
    let built = tool.build()?;
    let bounds = built.bounds();
    if !bounds.overlaps(&octree.root_box()) {
        return Err(TerrainError::OutsideTerrain {
            tool_min: bounds.min,
            tool_max: bounds.max,
        });
    }
    Ok(built)
}

/// What a job needs besides its octree: the grid, the shading and the
/// physics backend.
#[derive(Clone)]
pub(crate) struct JobContext {
    pub quantization: Quantization,
    pub smoothing_degrees: f32,
    pub physics: Option<Arc<dyn TerrainPhysics>>,
    /// What anchors the terrain (`None`: no debris detection).
    pub debris: Option<DebrisConfig>,
    pub debris_density: f32,
    /// Most convex hulls per debris collider.
    pub max_debris_hulls: usize,
    /// What to build for the changed cells.
    pub output: CellOutput,
    /// Whether to hand back the wall points on the cube's sides.
    pub publish_border: bool,
    /// Whether to measure what each carve changed of each material.
    pub measure_volumes: bool,
}

impl JobContext {
    /// Whether the job builds cells at all: not for [`CellOutput::Nothing`],
    /// nor for colliders alone without a physics backend.
    pub fn builds_cells(&self) -> bool {
        match self.output {
            CellOutput::Meshes => true,
            CellOutput::Colliders => self.physics.is_some(),
            CellOutput::Nothing => false,
        }
    }
}

/// One step of a background job.
pub(crate) enum StepOutcome {
    Applied {
        before: Octree,
        changes: Changes,
        tool: GridTool,
        edit: Edit,
        /// What the carve changed of each material, in cubic world units
        /// (`None` when not measured).
        volume_change: Option<BTreeMap<Label, f64>>,
        apply_time: Duration,
        requested: Instant,
        request: Option<u64>,
        predicted: Option<u64>,
        debris: Vec<BuiltDebris>,
    },
    Rejected {
        error: TerrainError,
        request: Option<u64>,
        predicted: Option<u64>,
    },
    /// An undo, or a redo (with the edit redone, `None` where the journal
    /// had lost it).
    Undone {
        redone: Option<Option<Edit>>,
        cells: usize,
        /// What the undo changed of each material, in cubic world units
        /// (`None` when not measured).
        volume_change: Option<BTreeMap<Label, f64>>,
        requested: Instant,
        /// The replicated undo's place in its terrain's order (`net`).
        request: Option<u64>,
        /// The prediction it took back (`None` for a plain undo).
        predicted: Option<u64>,
    },
    /// Pieces cut loose across chunk borders, built to spawn.
    Detached { debris: Vec<BuiltDebris> },
}

/// One material's mesh of a cell, built off the main thread, with its
/// collider (no render mesh for [`CellOutput::Colliders`]).
pub(crate) struct BuiltMesh {
    pub label: Label,
    pub triangles: usize,
    pub mesh: Option<Mesh>,
    pub collider: CellCollider,
}

/// The collider side of a [`BuiltMesh`].
pub(crate) enum CellCollider {
    /// Built from the new mesh: `None` where the mesh gives none (or no
    /// physics backend is set), and any old collider goes.
    Built(Option<PhysicsInsert>),
    /// The cell's surface is the one its collider was built from; only its
    /// seams moved (new vertices on its border edges, where a neighbour
    /// changed) or its normals at border vertices (a neighbour's faces
    /// around them changed), which a collider does not need. The cell's entity keeps
    /// its collider; the triangles serve an entity that has none yet.
    Unchanged(ColliderMesh),
}

/// What a cell shows now: `None` when it is no longer a leaf.
pub(crate) struct CellUpdate {
    pub key: CellKey,
    pub meshes: Option<Vec<BuiltMesh>>,
}

/// What a background job hands back.
pub(crate) struct JobOutput {
    pub octree: Octree,
    /// The border vertices of the cells now shown, for the next job.
    pub mesher: SeamedMesher,
    pub steps: Vec<StepOutcome>,
    pub cells: Vec<CellUpdate>,
    /// Whether the cells are the first full build, which may reach the
    /// screen over several frames; a carve's cells are shown together.
    pub full: bool,
    pub mesh_time: Duration,
    pub collider_time: Duration,
    /// The wall points on the cube's sides after this job, when the
    /// context asks for them and cells were built.
    pub border: Option<Arc<BorderPoints>>,
}

/// The thread pool of the background jobs, rebuilt when the number of
/// threads asked for changes (`None`: rayon's global pool, if a pool could
/// not be built).
#[derive(Default)]
pub struct Workers {
    threads: usize,
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl Workers {
    pub(crate) fn pool(&mut self, threads: usize) -> Option<Arc<rayon::ThreadPool>> {
        let threads = threads.max(1);
        if self.threads != threads {
            self.threads = threads;
            self.pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(|i| format!("chisel-terrain-{i}"))
                .build()
                .ok()
                .map(Arc::new);
        }
        self.pool.clone()
    }
}

/// Runs `job` on `pool` (or on rayon's global pool).
pub(crate) fn on_pool<T>(pool: Option<Arc<rayon::ThreadPool>>, job: impl FnOnce() -> T + Send) -> T
where
    T: Send,
{
    match pool {
        Some(pool) => pool.install(job),
        None => job(),
    }
}

/// One carve of a batch: the tool, the edit, when it was asked for, its
/// request id and its prediction number ([`Job::Carve`]).
pub(crate) struct BatchCarve {
    pub tool: GridTool,
    pub edit: Edit,
    pub requested: Instant,
    pub request: Option<u64>,
    pub predicted: Option<u64>,
}

/// Applies a batch of carves in order to `octree` and builds the cells
/// they changed.
pub(crate) fn carve_batch(
    mut octree: Octree,
    mesher: SeamedMesher,
    context: &JobContext,
    batch: Vec<BatchCarve>,
) -> JobOutput {
    let mut steps = Vec::with_capacity(batch.len());
    let mut keys = Vec::new();
    // The latest faces handed back for each cell whose content a carve of
    // the batch replaced; a later carve that changes the cell otherwise
    // (relabels it, splits it, or only touches it) drops them.
    let mut fresh: BTreeMap<CellKey, Vec<BoundaryFace>> = BTreeMap::new();
    for carve in batch {
        let BatchCarve {
            tool,
            edit,
            requested,
            request,
            predicted,
        } = carve;
        let before = octree.clone();
        let start = Instant::now();
        let carved =
            apply_carve_with_faces(&mut octree, &tool, edit).and_then(|(changes, faces)| {
                // The carve's own change, before any piece it cut loose
                // is taken out (the pieces report their own volumes).
                let volume_change = (context.measure_volumes).then(|| {
                    context
                        .quantization
                        .to_world_volumes(changes.volume_change(&before, &octree))
                });
                detach(&mut octree, changes, context)
                    .map(|(c, pieces)| (c, faces, pieces, volume_change))
            });
        match carved {
            Ok((changes, faces, pieces, volume_change)) => {
                for key in changes.changed.iter().chain(&changes.removed) {
                    fresh.remove(key);
                }
                // Faces of cells the detach rebuilt again are stale.
                fresh.extend(
                    faces
                        .into_iter()
                        .filter(|(key, _)| !pieces.iter().any(|p| p.leaves.contains(key))),
                );
                keys.extend(changes.changed.iter().copied());
                keys.extend(changes.removed.iter().copied());
                let apply_time = start.elapsed();
                let debris = pieces
                    .par_iter()
                    .map(|piece| build_debris(piece, context))
                    .collect();
                steps.push(StepOutcome::Applied {
                    before,
                    changes,
                    tool,
                    edit,
                    volume_change,
                    apply_time,
                    requested,
                    request,
                    predicted,
                    debris,
                });
            }
            Err(error) => {
                octree = before;
                steps.push(StepOutcome::Rejected {
                    error,
                    request,
                    predicted,
                });
            }
        }
    }
    remesh(octree, context, steps, keys, fresh, mesher, false)
}

/// The step of an undo (or of a redo, `redone`) that turned `before`
/// into `after`, changing the cells `keys` (taking back prediction
/// `predicted`, if any; replicated as `request`, if any).
#[allow(clippy::too_many_arguments)]
pub(crate) fn undone_step(
    before: &Octree,
    after: &Octree,
    keys: &[CellKey],
    context: &JobContext,
    requested: Instant,
    redone: Option<Option<Edit>>,
    request: Option<u64>,
    predicted: Option<u64>,
) -> StepOutcome {
    let changes = Changes {
        changed: keys.to_vec(),
        removed: Vec::new(),
    };
    StepOutcome::Undone {
        redone,
        cells: keys.len(),
        volume_change: (context.measure_volumes).then(|| {
            context
                .quantization
                .to_world_volumes(changes.volume_change(before, after))
        }),
        requested,
        request,
        predicted,
    }
}

/// Builds the pieces a detach across chunk borders cut loose (each as
/// one body of all its parts) and the cells of `keys` it changed in
/// `octree` (the chunk after the detach).
pub(crate) fn detached_batch(
    octree: Octree,
    mesher: SeamedMesher,
    context: &JobContext,
    keys: Vec<CellKey>,
    pieces: Vec<ChunkedPiece>,
) -> JobOutput {
    let debris = pieces
        .par_iter()
        .map(|piece| {
            let parts: Vec<&DebrisPiece> = piece.parts.iter().map(|p| &p.piece).collect();
            build_debris_of(&parts, context)
        })
        .collect();
    let steps = vec![StepOutcome::Detached { debris }];
    remesh(octree, context, steps, keys, BTreeMap::new(), mesher, false)
}

/// Takes the pieces the carve `changes` cut loose out of `octree` (the
/// terrain after the carve), returning the carve's and the detach's
/// changes together, against the terrain before the carve.
fn detach(
    octree: &mut Octree,
    changes: Changes,
    context: &JobContext,
) -> Result<(Changes, Vec<DebrisPiece>), TerrainError> {
    let Some(config) = &context.debris else {
        return Ok((changes, Vec::new()));
    };
    let carved = octree.detach_after(&changes, config)?;
    Ok((carved.changes, carved.detached.pieces))
}

/// Builds `keys` of `octree` (a key that is no longer a leaf gets `None`),
/// from the faces in `fresh` where a carve handed them back, and every
/// neighbour whose border the change split differently or whose border
/// normals it changed: `mesher` keeps the cells' border vertices and the
/// faces around them, so that neighbouring meshes meet edge to edge with
/// the same normals there.
pub(crate) fn remesh(
    octree: Octree,
    context: &JobContext,
    steps: Vec<StepOutcome>,
    keys: Vec<CellKey>,
    fresh: BTreeMap<CellKey, Vec<BoundaryFace>>,
    mut mesher: SeamedMesher,
    full: bool,
) -> JobOutput {
    let start = Instant::now();
    if !context.builds_cells() {
        // The mesher is left as it was: the terrain rebuilds every cell
        // when it is asked for cells again.
        return JobOutput {
            octree,
            mesher,
            steps,
            cells: Vec::new(),
            full,
            mesh_time: Duration::ZERO,
            collider_time: Duration::ZERO,
            border: None,
        };
    }
    let render = context.output == CellOutput::Meshes;
    // Cells outside the change keep their surface (`Changes::changed`);
    // the mesher re-seals some of them, and only their meshes change.
    let edited: BTreeSet<CellKey> = keys.iter().chain(fresh.keys()).copied().collect();
    let keys: BTreeSet<CellKey> = keys.into_iter().collect();
    let sealed = mesher.update_shaded(&octree, keys, fresh);
    let border = context
        .publish_border
        .then(|| Arc::new(BorderPoints::of(&mesher, &octree)));
    // Meshes first (the collider triangles kept aside), then colliders,
    // so that each is timed on its own.
    let meshed: Vec<(CellKey, Option<Vec<(BuiltMesh, ColliderMesh)>>)> = sealed
        .into_par_iter()
        .map(|(key, surface)| {
            let meshes = surface.map(|cell| {
                cell_meshes_around(
                    &cell.mesh,
                    &cell.around,
                    &context.quantization,
                    context.smoothing_degrees,
                )
                .into_iter()
                .map(|mut mesh| {
                    let collider = std::mem::take(&mut mesh.collider);
                    let built = BuiltMesh {
                        label: mesh.label,
                        triangles: mesh.triangle_count(),
                        mesh: render.then(|| mesh.into_mesh()),
                        collider: CellCollider::Built(None),
                    };
                    (built, collider)
                })
                .collect()
            });
            (key, meshes)
        })
        .collect();
    let mesh_time = start.elapsed();
    let start = Instant::now();
    let cells = meshed
        .into_par_iter()
        .map(|(key, meshes)| {
            let unchanged = !edited.contains(&key);
            CellUpdate {
                key,
                meshes: meshes.map(|meshes| {
                    meshes
                        .into_iter()
                        .map(|(mut built, collider)| {
                            built.collider = match &context.physics {
                                Some(_) if unchanged => CellCollider::Unchanged(collider),
                                Some(physics) => {
                                    CellCollider::Built(physics.cell_collider(&collider))
                                }
                                None => CellCollider::Built(None),
                            };
                            built
                        })
                        .collect()
                }),
            }
        })
        .collect();
    JobOutput {
        octree,
        mesher,
        steps,
        cells,
        full,
        mesh_time,
        collider_time: start.elapsed(),
        border,
    }
}
