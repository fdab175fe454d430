//! Requests in: carve, undo and redo messages onto each terrain's queue, and
//! the next job started.
//!
//! The second step of a carve (see [`super::carve`] for the whole path):
//! [`read_requests`] turns [`Carve`], [`GridCarve`], [`UndoCarve`] and
//! [`RedoCarve`] messages into jobs, and [`start_jobs`] runs the next one on the async
//! compute pool, where the job runtime (module `jobs`) applies it and
//! builds the changed cells. [`super::upload`] collects the result.
//!
//! A world chunk's carve, undo and detach jobs go before the world's
//! builds that have not started (module `pool_order`); a first full build
//! and a border reseal keep their place, and a single terrain's jobs
//! spawn plainly.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use bevy::prelude::*;
use bevy::tasks::AsyncComputeTaskPool;
use chisel_bsp::octree::{CellKey, Edit, Octree, SeamedMesher};

use super::carve::{
    Carve, CarveRejected, CellOutput, GridCarve, RedoCarve, TerrainSettings, UndoCarve,
};
use super::component::Terrain;
use super::error::TerrainError;
use super::jobs::{
    BatchCarve, CellUpdate, Job, JobContext, Upload, Workers, carve_batch, detached_batch, on_pool,
    remesh, undone_step,
};
use super::physics::TerrainPhysicsBackend;
use super::pool_order::spawn_in_order;
use super::world::{ChunkOffstage, TerrainWorld, WorldChunk};

/// Reads [`GridCarve`], [`Carve`], [`UndoCarve`] and [`RedoCarve`] into
/// the terrains' queues (undos of one frame before its redos).
pub fn read_requests(
    mut grid_carves: MessageReader<GridCarve>,
    mut carves: MessageReader<Carve>,
    mut undos: MessageReader<UndoCarve>,
    mut redos: MessageReader<RedoCarve>,
    mut terrains: Query<(&mut Terrain, Has<UndoRouted>)>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    let now = Instant::now();
    for carve in grid_carves.read() {
        let request = Some(carve.request);
        let queued = terrains
            .get_mut(carve.terrain)
            .map_err(|_| TerrainError::NoSuchTerrain)
            .and_then(|(mut terrain, _)| {
                terrain.check_label(carve.edit)?;
                // A request, not a change of the terrain's content yet.
                let runtime = &mut terrain.bypass_change_detection().runtime;
                runtime.queue.push_back(Job::Carve {
                    tool: carve.tool.clone(),
                    edit: carve.edit,
                    requested: now,
                    request,
                    predicted: None,
                });
                Ok(())
            });
        if let Err(error) = queued {
            rejected.write(CarveRejected {
                terrain: carve.terrain,
                request,
                predicted: None,
                error,
            });
        }
    }
    for carve in carves.read() {
        let Ok((mut terrain, _)) = terrains.get_mut(carve.terrain) else {
            rejected.write(CarveRejected {
                terrain: carve.terrain,
                request: None,
                predicted: None,
                error: TerrainError::NoSuchTerrain,
            });
            continue;
        };
        let tool = terrain
            .check_edit(carve.edit)
            .and_then(|()| carve.tool.to_grid(&terrain.quantization));
        match tool {
            Ok(tool) => {
                let runtime = &mut terrain.bypass_change_detection().runtime;
                runtime.queue.push_back(Job::Carve {
                    tool,
                    edit: carve.edit,
                    requested: now,
                    request: None,
                    predicted: None,
                });
            }
            Err(error) => {
                rejected.write(CarveRejected {
                    terrain: carve.terrain,
                    request: None,
                    predicted: None,
                    error,
                });
            }
        }
    }
    let undos = undos.read().map(|u| {
        let job = Job::Undo {
            requested: now,
            request: None,
            predicted: None,
        };
        (u.terrain, job)
    });
    let redos = redos.read().map(|r| {
        let job = Job::Redo {
            requested: now,
            request: None,
        };
        (r.terrain, job)
    });
    for (entity, job) in undos.chain(redos) {
        match terrains.get_mut(entity) {
            // A replicated terrain's undos go through its network order
            // (`crate::net`), which queues them itself.
            Ok((_, true)) => {}
            Ok((mut terrain, false)) => {
                (terrain.bypass_change_detection().runtime.queue).push_back(job);
            }
            Err(_) => {
                rejected.write(CarveRejected {
                    terrain: entity,
                    request: None,
                    predicted: None,
                    error: TerrainError::NoSuchTerrain,
                });
            }
        }
    }
}

/// Marks a terrain whose [`UndoCarve`]s and [`RedoCarve`]s another part
/// of the plugin takes in and queues (a replicated terrain, feature
/// `net`): [`read_requests`] leaves them alone.
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct UndoRouted;

/// Starts the next job of every terrain that has none running.
pub fn start_jobs(
    settings: Res<TerrainSettings>,
    physics: Res<TerrainPhysicsBackend>,
    mut workers: Local<Workers>,
    mut terrains: Query<(
        Entity,
        &mut Terrain,
        Has<ChunkOffstage>,
        Option<&WorldChunk>,
    )>,
    worlds: Query<&TerrainWorld>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    let _span = bevy::log::info_span!("chisel::queue::start_jobs").entered();
    for (entity, mut terrain, offstage, chunk) in &mut terrains {
        let pool = workers.pool(settings.worker_threads);
        if terrain.runtime.task.is_some() {
            continue;
        }
        // The plugin's bookkeeping; only an undo or a redo changes the
        // content here.
        let terrain_now = terrain.bypass_change_detection();
        // A chunk built only for work out of sight draws nothing.
        let output = if offstage {
            settings.output.out_of_sight()
        } else {
            settings.output
        };
        // A world's chunk: its carves go before the world's builds, and
        // wait while a save holds them back.
        let world = chunk.and_then(|c| worlds.get(c.world).ok());
        if start_next(
            entity,
            terrain_now,
            world,
            output,
            &settings,
            &physics,
            pool,
            &mut rejected,
        ) {
            terrain.set_changed();
        }
    }
}

/// Starts the next job of `terrain` (which has none running); returns
/// whether its content changed: an undo or a redo is applied here, before
/// its cells are rebuilt on the pool.
fn start_next(
    entity: Entity,
    terrain: &mut Terrain,
    world: Option<&TerrainWorld>,
    output: CellOutput,
    settings: &TerrainSettings,
    physics: &TerrainPhysicsBackend,
    pool: Option<Arc<rayon::ThreadPool>>,
    rejected: &mut MessageWriter<CarveRejected>,
) -> bool {
    let context = JobContext {
        quantization: terrain.quantization,
        smoothing_degrees: settings.smoothing_degrees,
        physics: physics.0.clone(),
        debris: terrain.debris.clone(),
        debris_density: settings.debris_density,
        max_debris_hulls: settings.max_debris_hulls,
        output,
        publish_border: terrain.runtime.publishes_border,
        measure_volumes: settings.measure_volumes,
    };
    terrain.runtime.builds_cells = context.builds_cells();
    if terrain.runtime.builds_cells
        && terrain
            .runtime
            .cells_output
            .is_some_and(|built| built != output)
    {
        // Cells built for another output (colliders only, before an
        // offstage chunk came into sight) are built again.
        terrain.runtime.needs_full_mesh = true;
    }
    if terrain.runtime.builds_cells {
        terrain.runtime.cells_output = Some(output);
    }
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
        // A first build starts the border vertices afresh, with the
        // outside points and wedges it was given.
        let mut mesher = if settings.shares_border_normals() {
            SeamedMesher::with_shading()
        } else {
            SeamedMesher::new()
        };
        mesher.set_outside_points(terrain.runtime.mesher.outside_points().to_vec());
        mesher.set_outside_wedges(terrain.runtime.mesher.outside_wedges());
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
        return false;
    }
    let order = world.map(|w| &w.pool_order);
    // Carves a world's save waiting for a consistent state holds back.
    let held = |request: Option<u64>| world.is_some_and(|w| w.holds_back(request));
    if let Some(Job::Carve { request, .. }) = terrain.runtime.queue.front()
        && held(*request)
    {
        return false;
    }
    match terrain.runtime.queue.pop_front() {
        None => {}
        Some(hold @ Job::HoldForWorldUndo { .. }) => {
            // The world carries it out and takes it away.
            terrain.runtime.queue.push_front(hold);
        }
        Some(Job::Undo {
            predicted: Some(prediction),
            ..
        }) if terrain.top_prediction() != Some(prediction) => {
            // The kernel refused that prediction: it left no step to undo.
        }
        Some(
            job @ (Job::Undo {
                requested, request, ..
            }
            | Job::Redo { requested, request }),
        ) => {
            let (redo, predicted) = match job {
                Job::Undo { predicted, .. } => (false, predicted),
                _ => (true, None),
            };
            let outcome = undo_or_redo(terrain, redo, predicted.is_some());
            if request.is_some() {
                // A replicated undo is in the octree now (or refused):
                // the terrain holds its terrain's order up to it.
                terrain.last_request = request;
            }
            match outcome {
                Ok((before, keys, redone)) => {
                    let octree = terrain.octree.clone();
                    let mesher = std::mem::take(&mut terrain.runtime.mesher);
                    // Ahead of the world's builds waiting on the pool, as a carve.
                    terrain.runtime.task = Some(spawn_in_order(order, async move {
                        on_pool(pool, || {
                            let step = undone_step(
                                &before, &octree, &keys, &context, requested, redone, request,
                                predicted,
                            );
                            remesh(
                                octree,
                                &context,
                                vec![step],
                                keys,
                                BTreeMap::new(),
                                mesher,
                                false,
                            )
                        })
                    }));
                    return true;
                }
                Err(error) => {
                    rejected.write(CarveRejected {
                        terrain: entity,
                        request,
                        predicted: None,
                        error,
                    });
                    return request.is_some();
                }
            }
        }
        Some(Job::Reseal { outside, wedges }) => {
            let octree = terrain.octree.clone();
            let mut mesher = std::mem::take(&mut terrain.runtime.mesher);
            mesher.set_outside_points(outside);
            mesher.set_outside_wedges(wedges);
            terrain.runtime.resealing = true;
            terrain.runtime.task = Some(AsyncComputeTaskPool::get().spawn(async move {
                on_pool(pool, || {
                    remesh(
                        octree,
                        &context,
                        Vec::new(),
                        Vec::new(),
                        BTreeMap::new(),
                        mesher,
                        false,
                    )
                })
            }));
        }
        Some(Job::Detached { keys, pieces }) => {
            let octree = terrain.octree.clone();
            let mesher = std::mem::take(&mut terrain.runtime.mesher);
            // Debris across chunk borders, floating until this job runs:
            // ahead of the chunk builds waiting on the pool.
            terrain.runtime.task = Some(spawn_in_order(order, async move {
                on_pool(pool, || {
                    detached_batch(octree, mesher, &context, keys, pieces)
                })
            }));
        }
        Some(Job::Carve {
            tool,
            edit,
            requested,
            request,
            predicted,
        }) => {
            let mut batch = vec![BatchCarve {
                tool,
                edit,
                requested,
                request,
                predicted,
            }];
            while batch.len() < settings.max_batch.max(1)
                && matches!(
                    terrain.runtime.queue.front(),
                    Some(Job::Carve { request, .. }) if !held(*request)
                )
            {
                if let Some(Job::Carve {
                    tool,
                    edit,
                    requested,
                    request,
                    predicted,
                }) = terrain.runtime.queue.pop_front()
                {
                    batch.push(BatchCarve {
                        tool,
                        edit,
                        requested,
                        request,
                        predicted,
                    });
                }
            }
            terrain.runtime.running_carves = batch.iter().map(|carve| carve.request).collect();
            let octree = terrain.octree.clone();
            let mesher = std::mem::take(&mut terrain.runtime.mesher);
            // The hole shows as soon as this job is done: ahead of the
            // world's builds waiting on the pool (`pool_order`).
            terrain.runtime.task = Some(spawn_in_order(order, async move {
                on_pool(pool, || carve_batch(octree, mesher, &context, batch))
            }));
        }
    }
    false
}

/// The octree before, the cells changed and (for a redo) the edit redone.
type UndoneNow = (Octree, Vec<CellKey>, Option<Option<Edit>>);

/// Applies an undo (or a redo) to `terrain` at once (an undo that rolls
/// a prediction back: `rollback`).
fn undo_or_redo(
    terrain: &mut Terrain,
    redo: bool,
    rollback: bool,
) -> Result<UndoneNow, TerrainError> {
    if redo {
        (terrain.redo_now_from()).map(|(before, keys, edit)| (before, keys, Some(edit)))
    } else {
        (terrain.undo_now_from(rollback)).map(|(before, keys)| (before, keys, None))
    }
}
