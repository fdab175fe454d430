//! Carving in the ECS: messages in, exact edits on worker threads, meshes
//! and colliders of the changed cells out.
//!
//! Flow per terrain, one job at a time and in request order:
//!
//! 1. [`read_requests`] turns [`Carve`] and [`UndoCarve`] messages into
//!    jobs (tools are rounded to the grid here; a bad tool is rejected at
//!    once with [`CarveRejected`]).
//! 2. [`start_jobs`] takes the consecutive carves at the head of the queue
//!    and runs them on a snapshot of the octree (a cheap persistent clone)
//!    on the [`AsyncComputeTaskPool`], which then builds the meshes and
//!    colliders of every cell they changed, in parallel, still off the main
//!    thread ([`super::jobs`]). An undo swaps the previous snapshot in and
//!    rebuilds the cells its carve had changed.
//! 3. [`finish_jobs`] swaps the new octree in, records undo steps and queues
//!    the cells.
//! 4. [`upload_meshes`] adds the queued meshes as assets and entities, with
//!    their colliders: all cells of a carve in the same frame, so that
//!    neighbouring cells always meet and the colliders match what is
//!    drawn. It writes a [`TerrainCellChanged`] per cell and each carve's
//!    [`CarveApplied`]. Only the first full build of a terrain is spread
//!    over frames, within [`TerrainSettings::mesh_budget`].

use std::collections::{BTreeMap, VecDeque};
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, futures::check_ready};
use chisel_bsp::octree::{CellKey, Edit, Octree, SeamedMesher};

use super::component::{Job, Runtime, Terrain, TerrainCell};
use super::debris::{
    BuiltDebris, DEFAULT_DEBRIS_DENSITY, DebrisDetached, DebrisPart, TerrainDebris,
};
use super::debris_hulls::DEFAULT_MAX_DEBRIS_HULLS;
use super::error::TerrainError;
use super::jobs::{
    BuiltMesh, CellUpdate, JobContext, StepOutcome, Workers, carve_batch, on_pool, remesh,
};
use super::mesh::DEFAULT_SMOOTHING_DEGREES;
use super::physics::TerrainPhysicsBackend;
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
    /// [`Terrain::last_request`] once the carve is in the octree.
    pub request: u64,
}

/// Undo the last carve of a terrain.
#[derive(Message, Reflect, Clone, Copy, Debug)]
pub struct UndoCarve {
    /// The terrain entity.
    pub terrain: Entity,
}

/// A carve (or undo) is applied and every mesh and collider it changed is
/// in place.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct CarveApplied {
    /// The terrain entity.
    pub terrain: Entity,
    /// The edit (`None` for an undo).
    #[reflect(ignore)]
    pub edit: Option<Edit>,
    /// The request id of a [`GridCarve`] (`None` for a [`Carve`] or an
    /// undo).
    pub request: Option<u64>,
    /// The terrain's state hash right after this carve
    /// ([`Terrain::state_hash`]; later carves of the same batch may already
    /// be in the octree when this message is read).
    pub hash: u64,
    /// Leaf cells this carve (or undo) changed, split or merged: their
    /// meshes were rebuilt or removed.
    pub cells: usize,
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

/// A carve or undo that was refused; the terrain is unchanged.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct CarveRejected {
    /// The terrain entity.
    pub terrain: Entity,
    /// The request id of a [`GridCarve`] (`None` for a [`Carve`] or an
    /// undo).
    pub request: Option<u64>,
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

impl Default for TerrainSettings {
    fn default() -> Self {
        Self {
            mesh_budget: Duration::from_micros(1000),
            max_batch: 16,
            worker_threads: std::thread::available_parallelism()
                .map_or(1, |n| n.get().saturating_sub(1).max(1)),
            smoothing_degrees: DEFAULT_SMOOTHING_DEGREES,
            debris_density: DEFAULT_DEBRIS_DENSITY,
            max_debris_hulls: DEFAULT_MAX_DEBRIS_HULLS,
            output: CellOutput::Meshes,
        }
    }
}

/// A finished job's cells and reports, waiting for [`upload_meshes`].
pub(crate) struct Upload {
    /// Cells still to add, in key order.
    cells: VecDeque<CellUpdate>,
    /// Whether the cells may be spread over frames (a first full build).
    spread: bool,
    /// The reports to write once every cell is in place.
    reports: Vec<(CarveApplied, Instant)>,
    /// The pieces to spawn then.
    debris: Vec<BuiltDebris>,
}

/// Reads [`GridCarve`], [`Carve`] and [`UndoCarve`] into the terrains'
/// queues.
pub fn read_requests(
    mut grid_carves: MessageReader<GridCarve>,
    mut carves: MessageReader<Carve>,
    mut undos: MessageReader<UndoCarve>,
    mut terrains: Query<&mut Terrain>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    let now = Instant::now();
    for carve in grid_carves.read() {
        let request = Some(carve.request);
        let queued = terrains
            .get_mut(carve.terrain)
            .map_err(|_| TerrainError::NoSuchTerrain)
            .and_then(|mut terrain| {
                terrain.check_label(carve.edit)?;
                terrain.runtime.queue.push_back(Job::Carve {
                    tool: carve.tool.clone(),
                    edit: carve.edit,
                    requested: now,
                    request,
                });
                Ok(())
            });
        if let Err(error) = queued {
            rejected.write(CarveRejected {
                terrain: carve.terrain,
                request,
                error,
            });
        }
    }
    for carve in carves.read() {
        let Ok(mut terrain) = terrains.get_mut(carve.terrain) else {
            rejected.write(CarveRejected {
                terrain: carve.terrain,
                request: None,
                error: TerrainError::NoSuchTerrain,
            });
            continue;
        };
        let tool = terrain
            .check_edit(carve.edit)
            .and_then(|()| carve.tool.to_grid(&terrain.quantization));
        match tool {
            Ok(tool) => terrain.runtime.queue.push_back(Job::Carve {
                tool,
                edit: carve.edit,
                requested: now,
                request: None,
            }),
            Err(error) => {
                rejected.write(CarveRejected {
                    terrain: carve.terrain,
                    request: None,
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
                    request: None,
                    error: TerrainError::NoSuchTerrain,
                });
            }
        }
    }
}

/// Starts the next job of every terrain that has none running.
pub fn start_jobs(
    settings: Res<TerrainSettings>,
    physics: Res<TerrainPhysicsBackend>,
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
        let context = JobContext {
            quantization: terrain.quantization,
            smoothing_degrees: settings.smoothing_degrees,
            physics: physics.0.clone(),
            debris: terrain.debris.clone(),
            debris_density: settings.debris_density,
            max_debris_hulls: settings.max_debris_hulls,
            output: settings.output,
        };
        terrain.runtime.builds_cells = context.builds_cells();
        if !terrain.runtime.builds_cells {
            // Cells shown before the output changed are taken away, and
            // every cell is built again once cells are asked for again.
            if !terrain.runtime.cells.is_empty() && terrain.runtime.uploads.is_empty() {
                let cells = terrain
                    .runtime
                    .cells
                    .keys()
                    .map(|&key| CellUpdate { key, meshes: None })
                    .collect();
                terrain.runtime.uploads.push_back(Upload {
                    cells,
                    spread: false,
                    reports: Vec::new(),
                    debris: Vec::new(),
                });
            }
            terrain.runtime.needs_full_mesh = true;
        } else if terrain.runtime.needs_full_mesh {
            terrain.runtime.needs_full_mesh = false;
            let keys: Vec<CellKey> = terrain.octree.leaves().iter().map(|(k, _)| *k).collect();
            let octree = terrain.octree.clone();
            // A first build starts the border vertices afresh.
            let mesher = SeamedMesher::new();
            terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                on_pool(pool, || {
                    remesh(
                        octree,
                        &context,
                        Vec::new(),
                        keys,
                        BTreeMap::new(),
                        mesher,
                        true,
                    )
                })
            }));
            continue;
        }
        match terrain.runtime.queue.pop_front() {
            None => {}
            Some(Job::Undo { requested }) => match terrain.undo_now() {
                Ok(keys) => {
                    let octree = terrain.octree.clone();
                    let steps = vec![StepOutcome::Undone {
                        cells: keys.len(),
                        requested,
                    }];
                    let mesher = std::mem::take(&mut terrain.runtime.mesher);
                    terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                        on_pool(pool, || {
                            remesh(
                                octree,
                                &context,
                                steps,
                                keys,
                                BTreeMap::new(),
                                mesher,
                                false,
                            )
                        })
                    }));
                }
                Err(error) => {
                    rejected.write(CarveRejected {
                        terrain: entity,
                        request: None,
                        error,
                    });
                }
            },
            Some(Job::Carve {
                tool,
                edit,
                requested,
                request,
            }) => {
                let mut batch = vec![(tool, edit, requested, request)];
                while batch.len() < settings.max_batch.max(1)
                    && matches!(terrain.runtime.queue.front(), Some(Job::Carve { .. }))
                {
                    if let Some(Job::Carve {
                        tool,
                        edit,
                        requested,
                        request,
                    }) = terrain.runtime.queue.pop_front()
                    {
                        batch.push((tool, edit, requested, request));
                    }
                }
                let octree = terrain.octree.clone();
                let mesher = std::mem::take(&mut terrain.runtime.mesher);
                terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                    on_pool(pool, || carve_batch(octree, mesher, &context, batch))
                }));
            }
        }
    }
}

/// Collects finished jobs: swaps the new octree in, records undo steps and
/// queues the cells.
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
        let mut reports = Vec::new();
        let mut debris = Vec::new();
        let report = |edit, request, hash, cells, apply_time| CarveApplied {
            terrain: entity,
            edit,
            request,
            hash,
            cells,
            apply_time,
            mesh_time: output.mesh_time,
            collider_time: output.collider_time,
            latency: Duration::ZERO,
        };
        // The octree after each applied step: the next applied step's
        // `before`, or the job's octree after the last.
        let afters: Vec<Octree> = {
            let mut next = output.octree.clone();
            let mut out: Vec<Octree> = output
                .steps
                .iter()
                .rev()
                .map(|step| match step {
                    StepOutcome::Applied { before, .. } => {
                        std::mem::replace(&mut next, before.clone())
                    }
                    _ => next.clone(),
                })
                .collect();
            out.reverse();
            out
        };
        for (step, after) in output.steps.into_iter().zip(afters) {
            match step {
                StepOutcome::Applied {
                    before,
                    changes,
                    tool,
                    edit,
                    apply_time,
                    requested,
                    request,
                    debris: pieces,
                } => {
                    debris.extend(pieces);
                    let cells = changes.changed.len() + changes.removed.len();
                    terrain
                        .hash
                        .update(&after, changes.changed.iter().chain(&changes.removed));
                    if request.is_some() {
                        terrain.last_request = request;
                    }
                    let hash = terrain.hash.value();
                    reports.push((
                        report(Some(edit), request, hash, cells, apply_time),
                        requested,
                    ));
                    terrain.record(before, changes, tool, edit);
                }
                StepOutcome::Undone { cells, requested } => {
                    let hash = terrain.hash.value();
                    reports.push((report(None, None, hash, cells, Duration::ZERO), requested));
                }
                StepOutcome::Rejected { error, request } => {
                    if request.is_some() {
                        terrain.last_request = request;
                    }
                    rejected.write(CarveRejected {
                        terrain: entity,
                        request,
                        error,
                    });
                }
            }
        }
        terrain.runtime.uploads.push_back(Upload {
            cells: output.cells.into(),
            spread: output.full,
            reports,
            debris,
        });
        // For an undo or a full build this is the octree already in place.
        terrain.octree = output.octree;
        terrain.runtime.mesher = output.mesher;
    }
}

/// Adds queued cells as assets and entities, with their colliders, and
/// writes the reports of the carves whose cells are all in place.
///
/// Every terrain gets its turn each frame: a terrain whose first full
/// build is still being added does not hold the others back.
#[allow(clippy::too_many_arguments)]
pub fn upload_meshes(
    settings: Res<TerrainSettings>,
    physics: Res<TerrainPhysicsBackend>,
    mut terrains: Query<(Entity, &mut Terrain, Option<&GlobalTransform>)>,
    mut cells: Query<Option<&mut Mesh3d>, With<TerrainCell>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut commands: Commands,
    mut changed: MessageWriter<TerrainCellChanged>,
    mut applied: MessageWriter<CarveApplied>,
    mut detached: MessageWriter<DebrisDetached>,
) {
    let start = Instant::now();
    let over_budget = |added: usize| added > 0 && start.elapsed() >= settings.mesh_budget;
    for (entity, mut terrain, placed) in &mut terrains {
        let placed = placed.copied().unwrap_or_default();
        let runtime = &mut terrain.runtime;
        let mut added = 0usize;
        while let Some(mut upload) = runtime.uploads.pop_front() {
            if !upload.spread && over_budget(added) {
                runtime.uploads.push_front(upload);
                break;
            }
            while !(upload.spread && over_budget(added)) {
                let Some(cell) = upload.cells.pop_front() else {
                    break;
                };
                added += 1;
                let mut place = CellPlacement {
                    terrain: entity,
                    physics: &physics,
                    commands: &mut commands,
                };
                let entities = place.show(runtime, &mut cells, &mut meshes, cell);
                changed.write(TerrainCellChanged {
                    terrain: entity,
                    key: entities.0,
                    entities: entities.1,
                });
            }
            if !upload.cells.is_empty() {
                runtime.uploads.push_front(upload);
                break;
            }
            for piece in upload.debris {
                detached.write(spawn_debris(
                    &mut commands,
                    &mut meshes,
                    entity,
                    &placed,
                    piece,
                ));
            }
            for (mut report, requested) in upload.reports {
                report.latency = requested.elapsed();
                applied.write(report);
            }
        }
    }
}

/// Spawns a piece cut loose from `terrain` (placed at `placed`) where it
/// was, as a [`TerrainDebris`] with one [`DebrisPart`] child per material.
fn spawn_debris(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    terrain: Entity,
    placed: &GlobalTransform,
    piece: BuiltDebris,
) -> DebrisDetached {
    let main_label = piece.main_label();
    let at = placed.compute_transform() * Transform::from_translation(piece.centre);
    let mut body = commands.spawn((
        TerrainDebris {
            terrain,
            exact_volume: piece.exact_volume.clone(),
            volumes: piece.volumes,
            volume: piece.volume,
        },
        at,
    ));
    #[cfg(feature = "render")]
    body.insert(Visibility::default());
    if let Some(insert) = piece.body {
        insert.apply(&mut body);
    }
    let entity = body.id();
    let mut handles = Vec::new();
    for (label, mesh) in piece.meshes {
        let handle = meshes.add(mesh);
        handles.push((label, handle.clone()));
        commands.spawn((
            DebrisPart { terrain, label },
            Mesh3d(handle),
            Transform::IDENTITY,
            ChildOf(entity),
        ));
    }
    DebrisDetached {
        terrain,
        entity,
        meshes: handles,
        centre: piece.centre,
        volume: piece.volume,
        exact_volume: piece.exact_volume,
        main_label,
    }
}

/// What adding a cell needs besides the queries and assets.
struct CellPlacement<'a, 'w, 's> {
    terrain: Entity,
    physics: &'a TerrainPhysicsBackend,
    commands: &'a mut Commands<'w, 's>,
}

impl CellPlacement<'_, '_, '_> {
    /// Shows a cell's new meshes: reuses the cell's entities per material,
    /// despawns those of materials it no longer has, spawns the others;
    /// returns the cell and its entities now.
    fn show(
        &mut self,
        runtime: &mut Runtime,
        cells: &mut Query<Option<&mut Mesh3d>, With<TerrainCell>>,
        meshes: &mut Assets<Mesh>,
        update: CellUpdate,
    ) -> (CellKey, Vec<Entity>) {
        let key = update.key;
        let old = runtime.cells.remove(&key).unwrap_or_default();
        let mut new = update.meshes.unwrap_or_default();
        let mut kept = Vec::new();
        for (label, cell_entity, triangles) in old {
            runtime.triangles -= triangles;
            let reused = new.iter().position(|m| m.label == label);
            match (reused, cells.get_mut(cell_entity)) {
                (Some(i), Ok(handle)) => {
                    let mesh: BuiltMesh = new.swap_remove(i);
                    let mut cell = self.commands.entity(cell_entity);
                    match (mesh.mesh, handle) {
                        (Some(built), Some(mut handle)) => handle.0 = meshes.add(built),
                        (Some(built), None) => {
                            cell.insert(Mesh3d(meshes.add(built)));
                        }
                        (None, Some(_)) => {
                            cell.remove::<Mesh3d>();
                        }
                        (None, None) => {}
                    }
                    match mesh.collider {
                        Some(collider) => collider.apply(&mut cell),
                        None => {
                            if let Some(physics) = &self.physics.0 {
                                physics.remove_cell_collider(&mut cell);
                            }
                        }
                    }
                    kept.push((label, cell_entity, mesh.triangles));
                }
                _ => self.commands.entity(cell_entity).despawn(),
            }
        }
        for mesh in new {
            let mut cell = self.commands.spawn((
                TerrainCell {
                    terrain: self.terrain,
                    key,
                    label: mesh.label,
                },
                Transform::IDENTITY,
                ChildOf(self.terrain),
            ));
            if let Some(built) = mesh.mesh {
                cell.insert(Mesh3d(meshes.add(built)));
            }
            if let Some(collider) = mesh.collider {
                collider.apply(&mut cell);
            }
            kept.push((mesh.label, cell.id(), mesh.triangles));
        }
        kept.sort_by_key(|&(l, _, _)| l);
        runtime.triangles += kept.iter().map(|&(_, _, t)| t).sum::<usize>();
        let entities = kept.iter().map(|&(_, e, _)| e).collect();
        if !kept.is_empty() {
            runtime.cells.insert(key, kept);
        }
        (key, entities)
    }
}
