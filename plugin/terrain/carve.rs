//! Carving in the ECS: messages in, exact edits on the async compute pool,
//! meshes of the changed cells out within a per-frame time budget.
//!
//! Flow per terrain, one job at a time and in request order:
//!
//! 1. [`read_requests`] turns [`Carve`] and [`UndoCarve`] messages into
//!    jobs (tools are rounded to the grid here; a bad tool is rejected at
//!    once with [`CarveRejected`]).
//! 2. [`start_jobs`] takes the consecutive carves at the head of the queue
//!    and runs them on a snapshot of the octree (a cheap persistent clone)
//!    on the [`AsyncComputeTaskPool`], then meshes every cell they changed
//!    (in parallel), still off the main thread. An undo swaps the previous
//!    snapshot in and meshes the cells its carve had changed.
//! 3. [`finish_jobs`] swaps the new octree in, records undo steps and queues
//!    the cell meshes.
//! 4. [`upload_meshes`] adds the queued cell meshes (built in step 2) as
//!    assets and entities until the frame's budget
//!    ([`TerrainSettings::mesh_budget`]) is spent, writes a [`TerrainCellChanged`] per cell and, once a carve is fully
//!    visible, its [`CarveApplied`].

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, futures::check_ready};
use chisel_bsp::octree::{CellKey, Changes, Edit, Octree};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::BoundaryFace;
use rayon::prelude::*;

use super::component::{Job, Terrain, TerrainCell, apply_carve_with_faces};
use super::error::TerrainError;
use super::mesh::{ReadyMesh, cell_meshes, cell_meshes_from, cell_translation};
use super::tool::{CarveTool, GridTool};

/// Carve a terrain: remove material inside the tool, add material to its
/// empty space, paint it, or keep only what is inside.
#[derive(Message, Clone, Debug)]
pub struct Carve {
    /// The terrain entity.
    pub terrain: Entity,
    /// The tool, in the terrain's local frame.
    pub tool: CarveTool,
    /// What to do inside the tool.
    pub edit: Edit,
}

/// Undo the last carve of a terrain.
#[derive(Message, Clone, Copy, Debug)]
pub struct UndoCarve {
    /// The terrain entity.
    pub terrain: Entity,
}

/// A carve (or undo) is applied and every mesh it changed is visible.
#[derive(Message, Clone, Debug)]
pub struct CarveApplied {
    /// The terrain entity.
    pub terrain: Entity,
    /// The edit (`None` for an undo).
    pub edit: Option<Edit>,
    /// Leaf cells whose meshes were rebuilt or removed.
    pub cells: usize,
    /// Time in the exact kernel (off the main thread).
    pub apply_time: Duration,
    /// Time computing the cell meshes (off the main thread), shared by the
    /// carves of one batch.
    pub mesh_time: Duration,
    /// From reading the request to the last changed mesh being in place.
    pub latency: Duration,
}

/// A carve or undo that was refused; the terrain is unchanged.
#[derive(Message, Clone, Debug)]
pub struct CarveRejected {
    /// The terrain entity.
    pub terrain: Entity,
    /// Why.
    pub error: TerrainError,
}

/// The meshes of one leaf cell of a terrain were rebuilt (or removed, with
/// no entities): rebuild its physics collider here.
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub struct TerrainCellChanged {
    /// The terrain entity.
    pub terrain: Entity,
    /// The octree cell.
    pub key: CellKey,
    /// Its entities now, one per visible material (empty when the cell is
    /// gone or has no surface).
    pub entities: Vec<Entity>,
}

/// Tuning of the terrain systems.
#[derive(Resource, Clone, Debug)]
pub struct TerrainSettings {
    /// Main-thread time per frame for turning cell meshes into assets and
    /// entities (at least one cell is uploaded per frame).
    pub mesh_budget: Duration,
    /// Most carves applied in one background job.
    pub max_batch: usize,
    /// Threads that apply carves and mesh cells in the background. The
    /// default is every core but one (at least one), so that the main
    /// thread keeps a core to itself however large the carve; results are
    /// bit-identical for any number.
    pub worker_threads: usize,
}

impl Default for TerrainSettings {
    fn default() -> Self {
        Self {
            mesh_budget: Duration::from_micros(1000),
            max_batch: 16,
            worker_threads: std::thread::available_parallelism()
                .map_or(1, |n| n.get().saturating_sub(1).max(1)),
        }
    }
}

/// The thread pool of the background jobs (state of [`start_jobs`]), rebuilt when
/// [`TerrainSettings::worker_threads`] changes (`None`: rayon's global pool,
/// if a pool could not be built).
#[derive(Default)]
pub struct Workers {
    threads: usize,
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl Workers {
    fn pool(&mut self, threads: usize) -> Option<Arc<rayon::ThreadPool>> {
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
fn on_pool<T>(pool: Option<Arc<rayon::ThreadPool>>, job: impl FnOnce() -> T + Send) -> T
where
    T: Send,
{
    match pool {
        Some(pool) => pool.install(job),
        None => job(),
    }
}

/// One step of a background job.
pub(crate) enum StepOutcome {
    Applied {
        before: Octree,
        changes: Changes,
        tool: GridTool,
        edit: Edit,
        apply_time: Duration,
        requested: Instant,
    },
    Rejected {
        error: TerrainError,
    },
    Undone {
        requested: Instant,
    },
}

/// What a background job hands back.
pub(crate) struct JobOutput {
    octree: Octree,
    steps: Vec<StepOutcome>,
    meshes: Vec<(CellKey, Option<Vec<ReadyMesh>>)>,
    mesh_time: Duration,
}

/// Work for [`upload_meshes`].
pub(crate) enum Upload {
    Cell {
        key: CellKey,
        translation: Vec3,
        meshes: Option<Vec<ReadyMesh>>,
    },
    Report(CarveApplied, Instant),
}

/// Reads [`Carve`] and [`UndoCarve`] into the terrains' queues.
pub fn read_requests(
    mut carves: MessageReader<Carve>,
    mut undos: MessageReader<UndoCarve>,
    mut terrains: Query<&mut Terrain>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    let now = Instant::now();
    for carve in carves.read() {
        let Ok(mut terrain) = terrains.get_mut(carve.terrain) else {
            rejected.write(CarveRejected {
                terrain: carve.terrain,
                error: TerrainError::NoSuchTerrain,
            });
            continue;
        };
        match carve.tool.to_grid(&terrain.quantization) {
            Ok(tool) => terrain.runtime.queue.push_back(Job::Carve {
                tool,
                edit: carve.edit,
                requested: now,
            }),
            Err(error) => {
                rejected.write(CarveRejected {
                    terrain: carve.terrain,
                    error,
                });
            }
        }
    }
    for undo in undos.read() {
        match terrains.get_mut(undo.terrain) {
            Ok(mut terrain) => terrain
                .runtime
                .queue
                .push_back(Job::Undo { requested: now }),
            Err(_) => {
                rejected.write(CarveRejected {
                    terrain: undo.terrain,
                    error: TerrainError::NoSuchTerrain,
                });
            }
        }
    }
}

/// Starts the next job of every terrain that has none running.
pub fn start_jobs(
    settings: Res<TerrainSettings>,
    mut workers: Local<Workers>,
    mut terrains: Query<(Entity, &mut Terrain)>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    for (entity, mut terrain) in &mut terrains {
        let pool = workers.pool(settings.worker_threads);
        let terrain = &mut *terrain;
        if terrain.runtime.task.is_some() {
            continue;
        }
        let quantization = terrain.quantization;
        if terrain.runtime.needs_full_mesh {
            terrain.runtime.needs_full_mesh = false;
            let keys: Vec<CellKey> = terrain.octree.leaves().iter().map(|(k, _)| *k).collect();
            let octree = terrain.octree.clone();
            terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                on_pool(pool, || {
                    remesh(octree, quantization, Vec::new(), keys, BTreeMap::new())
                })
            }));
            continue;
        }
        match terrain.runtime.queue.pop_front() {
            None => {}
            Some(Job::Undo { requested }) => match terrain.undo_now() {
                Ok(keys) => {
                    let octree = terrain.octree.clone();
                    let steps = vec![StepOutcome::Undone { requested }];
                    terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                        on_pool(pool, || {
                            remesh(octree, quantization, steps, keys, BTreeMap::new())
                        })
                    }));
                }
                Err(error) => {
                    rejected.write(CarveRejected {
                        terrain: entity,
                        error,
                    });
                }
            },
            Some(Job::Carve {
                tool,
                edit,
                requested,
            }) => {
                let mut batch = vec![(tool, edit, requested)];
                while batch.len() < settings.max_batch.max(1)
                    && matches!(terrain.runtime.queue.front(), Some(Job::Carve { .. }))
                {
                    if let Some(Job::Carve {
                        tool,
                        edit,
                        requested,
                    }) = terrain.runtime.queue.pop_front()
                    {
                        batch.push((tool, edit, requested));
                    }
                }
                let octree = terrain.octree.clone();
                terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                    on_pool(pool, || carve_batch(octree, quantization, batch))
                }));
            }
        }
    }
}

/// Applies a batch of carves in order to `octree` and meshes the cells
/// they changed.
fn carve_batch(
    mut octree: Octree,
    quantization: Quantization,
    batch: Vec<(GridTool, Edit, Instant)>,
) -> JobOutput {
    let mut steps = Vec::with_capacity(batch.len());
    let mut keys = Vec::new();
    // The latest faces handed back for each cell whose content a carve of
    // the batch replaced; a later carve that changes the cell otherwise
    // (relabels it, splits it, or only touches it) drops them.
    let mut fresh: BTreeMap<CellKey, Vec<BoundaryFace>> = BTreeMap::new();
    for (tool, edit, requested) in batch {
        let before = octree.clone();
        let start = Instant::now();
        match apply_carve_with_faces(&mut octree, &tool, edit) {
            Ok((changes, faces)) => {
                for key in changes.changed.iter().chain(&changes.removed) {
                    fresh.remove(key);
                }
                fresh.extend(faces);
                keys.extend(changes.changed.iter().copied());
                keys.extend(changes.removed.iter().copied());
                steps.push(StepOutcome::Applied {
                    before,
                    changes,
                    tool,
                    edit,
                    apply_time: start.elapsed(),
                    requested,
                });
            }
            Err(error) => steps.push(StepOutcome::Rejected { error }),
        }
    }
    remesh(octree, quantization, steps, keys, fresh)
}

/// Meshes `keys` of `octree` (a key that is no longer a leaf gets `None`),
/// from the faces in `fresh` where a carve handed them back.
fn remesh(
    octree: Octree,
    quantization: Quantization,
    steps: Vec<StepOutcome>,
    keys: Vec<CellKey>,
    mut fresh: BTreeMap<CellKey, Vec<BoundaryFace>>,
) -> JobOutput {
    let start = Instant::now();
    let keys: BTreeSet<CellKey> = keys.into_iter().collect();
    let jobs: Vec<(CellKey, Option<Vec<BoundaryFace>>)> = keys
        .into_iter()
        .map(|key| (key, fresh.remove(&key)))
        .collect();
    let meshes = jobs
        .into_par_iter()
        .map(|(key, faces)| {
            let meshes = octree.leaf(key).map(|_| {
                match faces {
                    Some(faces) => cell_meshes_from(&octree, &quantization, key, faces),
                    None => cell_meshes(&octree, &quantization, key),
                }
                .into_iter()
                .map(ReadyMesh::from)
                .collect()
            });
            (key, meshes)
        })
        .collect();
    JobOutput {
        octree,
        steps,
        meshes,
        mesh_time: start.elapsed(),
    }
}

/// Collects finished jobs: swaps the new octree in, records undo steps and
/// queues the meshes.
pub fn finish_jobs(
    mut terrains: Query<(Entity, &mut Terrain)>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    for (entity, mut terrain) in &mut terrains {
        let terrain = &mut *terrain;
        let Some(task) = terrain.runtime.task.as_mut() else {
            continue;
        };
        let Some(output) = check_ready(task) else {
            continue;
        };
        terrain.runtime.task = None;
        let cells = output.meshes.len();
        for (key, meshes) in output.meshes {
            let translation = cell_translation(&output.octree, &terrain.quantization, key);
            terrain.runtime.uploads.push_back(Upload::Cell {
                key,
                translation,
                meshes,
            });
        }
        for step in output.steps {
            match step {
                StepOutcome::Applied {
                    before,
                    changes,
                    tool,
                    edit,
                    apply_time,
                    requested,
                } => {
                    terrain.record(before, changes, tool, edit);
                    terrain.runtime.uploads.push_back(Upload::Report(
                        CarveApplied {
                            terrain: entity,
                            edit: Some(edit),
                            cells,
                            apply_time,
                            mesh_time: output.mesh_time,
                            latency: Duration::ZERO,
                        },
                        requested,
                    ));
                }
                StepOutcome::Undone { requested } => {
                    terrain.runtime.uploads.push_back(Upload::Report(
                        CarveApplied {
                            terrain: entity,
                            edit: None,
                            cells,
                            apply_time: Duration::ZERO,
                            mesh_time: output.mesh_time,
                            latency: Duration::ZERO,
                        },
                        requested,
                    ));
                }
                StepOutcome::Rejected { error } => {
                    rejected.write(CarveRejected {
                        terrain: entity,
                        error,
                    });
                }
            }
        }
        // For an undo or a full remesh this is the octree already in place.
        terrain.octree = output.octree;
    }
}

/// Turns queued cell meshes into assets and entities within the frame's
/// budget.
#[allow(clippy::too_many_arguments)]
pub fn upload_meshes(
    settings: Res<TerrainSettings>,
    mut terrains: Query<(Entity, &mut Terrain)>,
    mut cells: Query<&mut Mesh3d, With<TerrainCell>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut commands: Commands,
    mut changed: MessageWriter<TerrainCellChanged>,
    mut applied: MessageWriter<CarveApplied>,
) {
    let start = Instant::now();
    let mut uploaded = 0usize;
    for (entity, mut terrain) in &mut terrains {
        let runtime = &mut terrain.runtime;
        while let Some(upload) = runtime.uploads.front() {
            if uploaded > 0
                && matches!(upload, Upload::Cell { .. })
                && start.elapsed() >= settings.mesh_budget
            {
                return;
            }
            let Some(upload) = runtime.uploads.pop_front() else {
                break;
            };
            match upload {
                Upload::Report(mut report, requested) => {
                    report.latency = requested.elapsed();
                    applied.write(report);
                }
                Upload::Cell {
                    key,
                    translation,
                    meshes: new,
                } => {
                    uploaded += 1;
                    let old = runtime.cells.remove(&key).unwrap_or_default();
                    let mut new = new.unwrap_or_default();
                    let mut kept = Vec::new();
                    for (label, cell_entity, triangles) in old {
                        runtime.triangles -= triangles;
                        let reused = new.iter().position(|m| m.label == label);
                        match (reused, cells.get_mut(cell_entity)) {
                            (Some(i), Ok(mut handle)) => {
                                let mesh = new.swap_remove(i);
                                handle.0 = meshes.add(mesh.mesh);
                                commands
                                    .entity(cell_entity)
                                    .insert(Transform::from_translation(translation));
                                kept.push((label, cell_entity, mesh.triangles));
                            }
                            _ => commands.entity(cell_entity).despawn(),
                        }
                    }
                    for mesh in new {
                        let cell_entity = commands
                            .spawn((
                                TerrainCell {
                                    terrain: entity,
                                    key,
                                    label: mesh.label,
                                },
                                Mesh3d(meshes.add(mesh.mesh)),
                                Transform::from_translation(translation),
                                ChildOf(entity),
                            ))
                            .id();
                        kept.push((mesh.label, cell_entity, mesh.triangles));
                    }
                    kept.sort_by_key(|&(l, _, _)| l);
                    runtime.triangles += kept.iter().map(|&(_, _, t)| t).sum::<usize>();
                    let entities = kept.iter().map(|&(_, e, _)| e).collect();
                    if !kept.is_empty() {
                        runtime.cells.insert(key, kept);
                    }
                    changed.write(TerrainCellChanged {
                        terrain: entity,
                        key,
                        entities,
                    });
                }
            }
        }
    }
}
