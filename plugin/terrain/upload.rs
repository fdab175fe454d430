//! Results out: finished jobs swapped in, their cells shown.
//!
//! The last step of a carve (see [`super::carve`] for the whole path):
//! [`finish_jobs`] takes a finished job's octree, records its undo steps
//! and queues its cells; [`upload_meshes`] adds the cells as assets and
//! entities with their colliders, spawns the debris the carves cut loose,
//! and writes [`TerrainCellChanged`], [`DebrisDetached`] and
//! [`CarveApplied`].

use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::tasks::futures::check_ready;
use chisel_bsp::octree::{CellKey, Octree};

use super::carve::{CarveApplied, CarveRejected, TerrainCellChanged, TerrainSettings};
use super::component::{Terrain, TerrainCell};
use super::debris::{BuiltDebris, DebrisDetached, DebrisPart, TerrainDebris};
use super::jobs::{BuiltMesh, CellCollider, CellUpdate, Runtime, StepOutcome, Upload};
use super::physics::TerrainPhysicsBackend;

/// Collects finished jobs: swaps the new octree in, records undo steps and
/// queues the cells.
pub fn finish_jobs(
    mut terrains: Query<(Entity, &mut Terrain)>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    let _span = bevy::log::info_span!("chisel::upload::finish_jobs").entered();
    for (entity, mut terrain) in &mut terrains {
        // Polling is the plugin's bookkeeping: the terrain is marked
        // changed only when a finished job changed its content.
        if finish_job(entity, terrain.bypass_change_detection(), &mut rejected) {
            terrain.set_changed();
        }
    }
}

/// Collects `terrain`'s job when it is done; returns whether its content
/// changed: a carve applied, or a tracked carve refused (its
/// [`Terrain::last_request`] moves on).
fn finish_job(
    entity: Entity,
    terrain: &mut Terrain,
    rejected: &mut MessageWriter<CarveRejected>,
) -> bool {
    let Some(task) = terrain.runtime.task.as_mut() else {
        return false;
    };
    let Some(output) = check_ready(task) else {
        return false;
    };
    let mut content_changed = false;
    terrain.runtime.task = None;
    terrain.runtime.resealing = false;
    terrain.runtime.running_carves.clear();
    let mut reports = Vec::new();
    let mut debris = Vec::new();
    let report =
        |edit, redo, request, predicted, hash, cells, volume_change, apply_time| CarveApplied {
            terrain: entity,
            edit,
            redo,
            request,
            predicted,
            hash,
            cells,
            volume_change,
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
                StepOutcome::Applied { before, .. } => std::mem::replace(&mut next, before.clone()),
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
                volume_change,
                apply_time,
                requested,
                request,
                predicted,
                debris: pieces,
            } => {
                content_changed = true;
                debris.extend(pieces.into_iter().map(|piece| (piece, predicted)));
                if terrain.runtime.publishes_border && terrain.debris.is_some() {
                    // A chunk's carve: seeds of the detach across
                    // chunk borders (`world::debris`).
                    let seeds = &mut terrain.runtime.border_seeds;
                    seeds.extend(changes.changed.iter().copied());
                }
                let cells = changes.changed.len() + changes.removed.len();
                terrain
                    .hash
                    .update(&after, changes.changed.iter().chain(&changes.removed));
                if request.is_some() {
                    terrain.last_request = request;
                }
                let hash = terrain.hash.value();
                reports.push((
                    report(
                        Some(edit),
                        false,
                        request,
                        predicted,
                        hash,
                        cells,
                        volume_change,
                        apply_time,
                    ),
                    requested,
                ));
                terrain.record(before, changes, tool, edit, predicted);
                if let (Some(request), true) = (request, terrain.runtime.records_landed) {
                    let journal = terrain.journal.len();
                    terrain
                        .runtime
                        .landed
                        .push((request, Some((hash, journal))));
                }
            }
            StepOutcome::Detached { debris: pieces } => {
                debris.extend(pieces.into_iter().map(|piece| (piece, None)));
            }
            StepOutcome::Undone {
                redone,
                cells,
                volume_change,
                requested,
                request,
                predicted,
            } => {
                let hash = terrain.hash.value();
                let (edit, redo) = (redone.flatten(), redone.is_some());
                let undone = report(
                    edit,
                    redo,
                    request,
                    predicted,
                    hash,
                    cells,
                    volume_change,
                    Duration::ZERO,
                );
                reports.push((undone, requested));
            }
            StepOutcome::Rejected {
                error,
                request,
                predicted,
            } => {
                if request.is_some() {
                    content_changed |= terrain.last_request != request;
                    terrain.last_request = request;
                }
                if let (Some(request), true) = (request, terrain.runtime.records_landed) {
                    terrain.runtime.landed.push((request, None));
                }
                rejected.write(CarveRejected {
                    terrain: entity,
                    request,
                    predicted,
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
    // For an undo, a redo or a full build this is the octree already in
    // place.
    terrain.octree = output.octree;
    terrain.runtime.mesher = output.mesher;
    if output.border.is_some() {
        terrain.runtime.border = output.border;
    }
    content_changed
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
    let _span = bevy::log::info_span!("chisel::upload::upload_meshes").entered();
    let start = Instant::now();
    let over_budget = |added: usize| added > 0 && start.elapsed() >= settings.mesh_budget;
    for (entity, mut terrain, placed) in &mut terrains {
        let placed = placed.copied().unwrap_or_default();
        // Cells shown are not a change of the terrain's content.
        let runtime = &mut terrain.bypass_change_detection().runtime;
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
            for (piece, predicted) in upload.debris {
                detached.write(spawn_debris(
                    &mut commands,
                    &mut meshes,
                    entity,
                    &placed,
                    piece,
                    predicted,
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
    predicted: Option<u64>,
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
        predicted,
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
                        CellCollider::Built(Some(collider)) => collider.apply(&mut cell),
                        CellCollider::Built(None) => {
                            if let Some(physics) = &self.physics.0 {
                                physics.remove_cell_collider(&mut cell);
                            }
                        }
                        CellCollider::Unchanged(_) => {}
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
            let collider = match mesh.collider {
                CellCollider::Built(collider) => collider,
                // Rare: the same surface under a new entity (its old one
                // was despawned), so built here, on the main thread.
                CellCollider::Unchanged(triangles) => self
                    .physics
                    .0
                    .as_ref()
                    .and_then(|physics| physics.cell_collider(&triangles)),
            };
            if let Some(collider) = collider {
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
