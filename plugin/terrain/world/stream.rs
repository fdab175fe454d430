//! The world's systems: carves routed to the chunks their tools overlap,
//! and chunks streamed in and out around the [`TerrainFocus`] entities.
//!
//! Distances are horizontal (x and z), in grid units, from a focus to the
//! nearest point of a chunk's square; a chunk is wanted when one focus is
//! within [`StreamSettings::load_radius`](super::StreamSettings) of it,
//! and released once every focus is beyond `unload_radius` and the chunk
//! is idle with no carve waiting for it (at the earliest the frame after
//! its build is collected, when its terrain can be read and stored).

use std::sync::Arc;
use std::time::Instant;

use bevy::prelude::*;
use bevy::tasks::AsyncComputeTaskPool;
use bevy::tasks::futures::check_ready;

use super::super::carve::{CarveRejected, GridCarve};
use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::debris_order::DebrisRole;
use super::{
    Built, Chunk, ChunkCoord, ChunkOffstage, TerrainFocus, TerrainWorld, WorldCarve, WorldChunk,
};
use super::{generate, restore};

/// Most carves a far chunk of a networked world's client keeps waiting
/// before it is built ([`TerrainWorld::with_max_deferred_carves`]).
pub const DEFAULT_MAX_DEFERRED_CARVES: usize = 64;

impl TerrainWorld {
    /// On a networked world's client (feature `net`), builds a chunk
    /// beyond every focus's unload radius once `carves` carves wait for it
    /// (at least 1; [`DEFAULT_MAX_DEFERRED_CARVES`] by default): it is
    /// built out of sight, carved in order and streamed out again, so that
    /// no far chunk keeps more than that many carves waiting. Elsewhere
    /// every chunk a carve reaches is built at once.
    #[must_use]
    pub fn with_max_deferred_carves(mut self, carves: usize) -> Self {
        self.max_deferred_carves = carves.max(1);
        self
    }

    /// Most carves a far chunk of a networked world's client keeps
    /// waiting ([`TerrainWorld::with_max_deferred_carves`]).
    #[must_use]
    pub fn max_deferred_carves(&self) -> usize {
        self.max_deferred_carves
    }

    /// The chunks whose carves wait, deferred, until they stream in (far
    /// chunks of a networked world's client), as of the last streaming
    /// pass, in coordinate order.
    pub fn deferred_chunks(&self) -> impl Iterator<Item = ChunkCoord> + '_ {
        self.deferred.iter().copied()
    }

    /// How many carves wait for chunk `coord` (it is not live yet, or its
    /// carves are deferred).
    #[must_use]
    pub fn waiting_carves(&self, coord: ChunkCoord) -> usize {
        self.pending.get(&coord).map_or(0, Vec::len)
    }

    /// Builds every chunk whose carves wait deferred (out of sight, in
    /// the background, as streaming builds others), carves it and streams
    /// it out again: afterwards the world holds every edited chunk, for
    /// [`TerrainWorld::save`] (which refuses while a carve waits) or to
    /// read every chunk. Carves that reach far chunks later are deferred
    /// again.
    pub fn build_deferred(&mut self) {
        self.deferred_wanted.extend(self.pending.keys().copied());
        self.deferred.clear();
    }
}

/// Splits every [`WorldCarve`] into grid carves of the chunks its tool
/// overlaps (the grid boxes of its pieces, open: a piece that only
/// touches a chunk's side does not reach it). Chunks that are not live
/// keep the carve until they are ([`stream_chunks`] builds them, but the
/// far ones of a networked world's client: `defer_far_chunks`).
pub fn route_world_carves(
    mut carves: MessageReader<WorldCarve>,
    mut worlds: Query<&mut TerrainWorld>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    for carve in carves.read() {
        let Ok(mut world) = worlds.get_mut(carve.world) else {
            rejected.write(CarveRejected {
                terrain: carve.world,
                request: None,
                predicted: None,
                error: TerrainError::NoSuchTerrain,
            });
            continue;
        };
        match chunks_of(&world, carve) {
            // After a waiting undo, the carve waits for it (`undo`).
            Ok((tool, coords)) if world.history.holds_carves() => {
                world.history.hold(tool, carve.edit, coords);
            }
            Ok((tool, coords)) => {
                let request = world.next_request;
                world.route(&tool, carve.edit, request, &coords);
            }
            Err(error) => {
                rejected.write(CarveRejected {
                    terrain: carve.world,
                    request: None,
                    predicted: None,
                    error,
                });
            }
        }
    }
}

/// The carve's grid tool and the chunks it reaches, in order.
fn chunks_of(
    world: &TerrainWorld,
    carve: &WorldCarve,
) -> Result<(super::super::tool::GridTool, Vec<ChunkCoord>), TerrainError> {
    if world.debris_role != DebrisRole::Local {
        return Err(TerrainError::NetworkedWorld);
    }
    world.check_edit(carve.edit)?;
    let tool = carve.tool.to_grid(&world.layout.quantization)?;
    let coords = world.chunks_reached(&tool)?;
    Ok((tool, coords))
}

/// Streams every world's chunks: collects finished builds as terrain
/// entities, hands waiting carves to live chunks, starts builds of the
/// wanted chunks nearest first (chunks with waiting carves that are not
/// deferred, and those kept for debris across borders in a networked
/// world, before all),
/// and releases chunks beyond the unload radius, keeping the state of
/// edited ones. A world is marked changed in the frames its chunks change
/// (a build starts or is collected, a chunk is handed its waiting carves
/// or released), not in those that only poll its builds.
pub fn stream_chunks(
    mut commands: Commands,
    mut worlds: Query<(Entity, &mut TerrainWorld, &GlobalTransform)>,
    foci: Query<&GlobalTransform, With<TerrainFocus>>,
    terrains: Query<&Terrain>,
    offstage: Query<(), With<ChunkOffstage>>,
    mut grid_carves: MessageWriter<GridCarve>,
) {
    for (world_entity, mut world_mut, world_transform) in &mut worlds {
        // Polling builds is the plugin's bookkeeping: the world is marked
        // changed only when its chunks change (below).
        let world = world_mut.bypass_change_detection();
        let unit = world.layout.quantization.unit();
        let focus = grid_foci(&world.layout, world_transform, foci.iter());
        let edge = world.layout.chunk_edge();
        let distance = |coord: ChunkCoord| nearest_distance(&focus, coord, edge);
        let load = f64::from(world.settings.load_radius) / unit;
        let unload = f64::from(world.settings.unload_radius) / unit;
        let out_of_sight = |coord: ChunkCoord| distance(coord) > unload;

        let span = bevy::log::info_span!("chisel::stream::collect_builds").entered();
        // Their terrains are spawned by this frame's commands: none can be
        // read (nor stored when it streams out) before the next frame.
        let just_built = collect_builds(&mut commands, world_entity, world, out_of_sight);
        drop(span);
        // Chunks built out of sight that a focus came near build meshes.
        for (coord, entity) in world.live_chunks() {
            if offstage.contains(entity) && !out_of_sight(coord) {
                commands.entity(entity).try_remove::<ChunkOffstage>();
            }
        }
        // Chunks that were just sent carves are not idle yet, though their
        // queues fill only when the terrain systems read the messages.
        let just_carved = send_pending(world, &terrains, &mut grid_carves);
        let mut chunks_changed = !just_built.is_empty() || !just_carved.is_empty();
        defer_far_chunks(world, out_of_sight);

        // Wanted chunks, nearest first; those with waiting carves first
        // (but deferred ones).
        let deferred = &world.deferred;
        let mut wanted: Vec<(f64, ChunkCoord)> = (world.pending.keys())
            .filter(|c| !deferred.contains(c))
            .copied()
            .chain(world.debris_keep.iter().copied())
            .chain(world.history.wanted())
            .map(|c| (f64::NEG_INFINITY, c))
            .collect();
        let undoing: Vec<ChunkCoord> = world.history.wanted().collect();
        chunks_within(&focus, edge, load, distance, &mut wanted);
        wanted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        wanted.dedup_by_key(|w| w.1);
        let mut building = world
            .chunks
            .values()
            .filter(|c| matches!(c, Chunk::Building(_)))
            .count();
        for &(_, coord) in &wanted {
            if building >= world.settings.max_building {
                break;
            }
            if world.chunks.contains_key(&coord) {
                continue;
            }
            start_build(world, coord);
            building += 1;
            chunks_changed = true;
        }
        // Seeds beside the wanted chunks not live yet wait for them
        // (`debris`): a piece over the border falls once both are in.
        world.loading = (wanted.iter().map(|&(_, c)| c))
            .filter(|c| !matches!(world.chunks.get(c), Some(Chunk::Live(_) | Chunk::Failed)))
            .collect();

        // Release chunks beyond the unload radius.
        let far: Vec<(ChunkCoord, Option<Entity>)> = world
            .chunks
            .iter()
            .filter(|(c, _)| {
                distance(**c) > unload
                    && !world.pending.contains_key(c)
                    && !world.debris_keep.contains(c)
                    && !just_carved.contains(c)
                    && !undoing.contains(c)
                    && !just_built.contains(c)
            })
            .filter_map(|(c, state)| match state {
                Chunk::Live(e) => Some((*c, Some(*e))),
                Chunk::Failed => Some((*c, None)),
                Chunk::Building(_) => None,
            })
            .collect();
        let _span = bevy::log::info_span!("chisel::stream::release").entered();
        for (coord, entity) in far {
            let Some(entity) = entity else {
                world.chunks.remove(&coord);
                chunks_changed = true;
                continue;
            };
            match terrains.get(entity) {
                // Sealing again at a neighbour's new points is dropped.
                Ok(terrain) if !terrain.is_idle_but_for_seams() => continue,
                Ok(terrain) if world.chunk_edited(coord, terrain) => {
                    let _span = bevy::log::info_span!("chisel::stream::to_bytes").entered();
                    // With the seeds the world's search took out of it and
                    // has not applied: a search that depends on the chunk
                    // goes stale and drops them, and the chunk searches
                    // them when it streams back in (`debris`).
                    let taken = world.seeds_taken(entity);
                    let bytes = terrain.to_bytes_with_seeds_taken(taken);
                    world.stored.insert(coord, Arc::new(bytes));
                }
                // An unedited chunk has no stored bytes to hold seeds (those
                // a world undo gave back): it stays until they are searched.
                Ok(terrain)
                    if !terrain.runtime.border_seeds.is_empty()
                        || !world.seeds_taken(entity).is_empty() =>
                {
                    continue;
                }
                _ => {}
            }
            // Its own redo steps are not in its bytes: the world keeps them.
            if let Ok(terrain) = terrains.get(entity) {
                world.keep_streamed_redo(coord, terrain);
            }
            commands.entity(entity).try_despawn();
            world.chunks.remove(&coord);
            world.stats.released += 1;
            chunks_changed = true;
        }
        update_counts(world);
        if chunks_changed {
            world_mut.set_changed();
        }
    }
}

/// Notes the chunks whose carves wait deferred: on a networked world's
/// client, a chunk that is not live nor building, beyond every focus's
/// unload radius (`out_of_sight`), that no detach across chunk borders
/// needs, with fewer than the world's most deferred carves waiting and
/// not asked for by [`TerrainWorld::build_deferred`]. Every other chunk
/// with carves waiting is built. Elsewhere nothing is deferred.
fn defer_far_chunks(world: &mut TerrainWorld, out_of_sight: impl Fn(ChunkCoord) -> bool) {
    let pending = &world.pending;
    world.deferred_wanted.retain(|c| pending.contains_key(c));
    if world.debris_role != DebrisRole::Follow {
        world.deferred.clear();
        return;
    }
    let deferred = pending
        .iter()
        .filter(|&(c, carves)| {
            carves.len() < world.max_deferred_carves
                && !world.chunks.contains_key(c)
                && !world.debris_keep.contains(c)
                && !world.deferred_wanted.contains(c)
                && out_of_sight(*c)
        })
        .map(|(c, _)| *c)
        .collect();
    world.deferred = deferred;
}

/// The foci's positions in the world's grid units, horizontally (x, z):
/// their translations taken into the world entity's frame, less the grid's
/// origin, over its unit.
pub(super) fn grid_foci<'a>(
    layout: &super::WorldLayout,
    world_transform: &GlobalTransform,
    foci: impl Iterator<Item = &'a GlobalTransform>,
) -> Vec<[f64; 2]> {
    let unit = layout.quantization.unit();
    let origin = layout.quantization.origin();
    let to_local = world_transform.affine().inverse();
    foci.map(|f| {
        let p = to_local.transform_point3(f.translation()).as_dvec3();
        [(p.x - origin[0]) / unit, (p.z - origin[2]) / unit]
    })
    .collect()
}

/// Horizontal distance (grid units) from the nearest of `focus` to chunk
/// `coord`'s square; `+∞` without a focus.
pub(super) fn nearest_distance(focus: &[[f64; 2]], coord: ChunkCoord, edge: i64) -> f64 {
    focus
        .iter()
        .map(|f| square_distance(*f, coord, edge))
        .fold(f64::INFINITY, f64::min)
}

/// Horizontal distance from `f` (grid units) to chunk `coord`'s square.
pub(super) fn square_distance(f: [f64; 2], coord: ChunkCoord, edge: i64) -> f64 {
    let gap = |p: f64, c: i64| {
        let (lo, hi) = ((c * edge) as f64, ((c + 1) * edge) as f64);
        (lo - p).max(p - hi).max(0.0)
    };
    gap(f[0], coord.x).hypot(gap(f[1], coord.z))
}

/// Appends every chunk within `radius` (grid units) of a focus `f`
/// (grid units), with its `distance`: the chunks overlapping each focus's
/// square of half side `radius`, kept where `distance ≤ radius`. A chunk
/// near several foci is appended once for each.
pub(super) fn chunks_within(
    focus: &[[f64; 2]],
    edge: i64,
    radius: f64,
    distance: impl Fn(ChunkCoord) -> f64,
    out: &mut Vec<(f64, ChunkCoord)>,
) {
    let span = radius.ceil() as i64 + 1;
    for f in focus {
        let (fx, fz) = (f[0].floor() as i64, f[1].floor() as i64);
        let (x0, x1) = ((fx - span).div_euclid(edge), (fx + span).div_euclid(edge));
        let (z0, z1) = ((fz - span).div_euclid(edge), (fz + span).div_euclid(edge));
        for x in x0..=x1 {
            for z in z0..=z1 {
                let coord = ChunkCoord { x, z };
                let d = distance(coord);
                if d <= radius {
                    out.push((d, coord));
                }
            }
        }
    }
}

fn start_build(world: &mut TerrainWorld, coord: ChunkCoord) {
    let labels = world.labels.clone();
    // Behind the world's carves and debris work waiting (`pool_order`).
    let order = world.pool_order.clone();
    let task = if let Some(bytes) = world.stored.get(&coord).cloned() {
        AsyncComputeTaskPool::get().spawn(async move {
            order.after_first().await;
            let start = Instant::now();
            let terrain = restore(&bytes, &labels);
            Built {
                terrain,
                time: start.elapsed(),
                restored: true,
            }
        })
    } else {
        let (layout, source) = (world.layout.clone(), world.source.clone());
        AsyncComputeTaskPool::get().spawn(async move {
            order.after_first().await;
            let start = Instant::now();
            let terrain = generate(&layout, &*source, &labels, coord);
            Built {
                terrain,
                time: start.elapsed(),
                restored: false,
            }
        })
    };
    world.chunks.insert(coord, Chunk::Building(task));
}

/// Turns the finished builds into terrain entities (spawned by `commands`;
/// [`ChunkOffstage`] where `out_of_sight`) or failed chunks; returns the
/// chunks collected.
fn collect_builds(
    commands: &mut Commands,
    world_entity: Entity,
    world: &mut TerrainWorld,
    out_of_sight: impl Fn(ChunkCoord) -> bool,
) -> Vec<ChunkCoord> {
    let mut done = Vec::new();
    for (coord, state) in &mut world.chunks {
        if let Chunk::Building(task) = state
            && let Some(built) = check_ready(task)
        {
            done.push((*coord, built));
        }
    }
    let collected = done.iter().map(|(coord, _)| *coord).collect();
    for (coord, built) in done {
        world.stats.build_time += built.time;
        match built.terrain {
            Ok(terrain) => {
                let mut terrain = terrain.with_max_undo(world.history.max);
                // Seeds a world undo gave back while it was not live.
                if let Some(seeds) = world.seeds_back.remove(&coord) {
                    terrain.runtime.border_seeds.extend(seeds);
                }
                if built.restored {
                    // Stored with no carve of its own: it lost solid to a
                    // detach across chunk borders (`debris`).
                    let own_edits = terrain.is_edited();
                    terrain.detached_across |= !own_edits;
                    world.stats.restored += 1;
                    world.stored.remove(&coord);
                } else {
                    world.stats.generated += 1;
                }
                world.give_streamed_redo(coord, &mut terrain);
                let entity = commands
                    .spawn((
                        terrain,
                        WorldChunk {
                            world: world_entity,
                            coord,
                        },
                        ChildOf(world_entity),
                        Name::new(format!("chunk {} {}", coord.x, coord.z)),
                    ))
                    .id();
                if out_of_sight(coord) {
                    commands.entity(entity).insert(ChunkOffstage);
                }
                world.chunks.insert(coord, Chunk::Live(entity));
            }
            Err(error) => {
                warn!("terrain world chunk ({}, {}): {error}", coord.x, coord.z);
                world.stats.failed += 1;
                world.chunks.insert(coord, Chunk::Failed);
                world.seeds_back.remove(&coord);
                world.drop_streamed_redo(coord);
                if let Some(dropped) = world.pending.remove(&coord) {
                    warn!("{} carves of that chunk are dropped", dropped.len());
                }
            }
        }
    }
    collected
}

/// Sends the waiting carves of chunks whose terrain entity exists;
/// returns those chunks.
fn send_pending(
    world: &mut TerrainWorld,
    terrains: &Query<&Terrain>,
    grid_carves: &mut MessageWriter<GridCarve>,
) -> Vec<ChunkCoord> {
    let ready: Vec<(ChunkCoord, Entity)> = world
        .pending
        .keys()
        .filter_map(|c| match world.chunks.get(c) {
            Some(Chunk::Live(e)) if terrains.contains(*e) => Some((*c, *e)),
            _ => None,
        })
        .collect();
    for &(coord, entity) in &ready {
        for (tool, edit, request) in world.pending.remove(&coord).unwrap_or_default() {
            grid_carves.write(GridCarve {
                terrain: entity,
                tool,
                edit,
                request,
            });
        }
    }
    ready.into_iter().map(|(c, _)| c).collect()
}

fn update_counts(world: &mut TerrainWorld) {
    let stats = &mut world.stats;
    stats.live = 0;
    stats.building = 0;
    for state in world.chunks.values() {
        match state {
            Chunk::Live(_) => stats.live += 1,
            Chunk::Building(_) => stats.building += 1,
            Chunk::Failed => {}
        }
    }
    stats.stored = world.stored.len();
    stats.stored_bytes = world.stored.values().map(|b| b.len()).sum();
}
