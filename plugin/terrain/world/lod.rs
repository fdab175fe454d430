//! Level of detail for a [`TerrainWorld`]: chunks beyond the full-detail
//! ones, out to [`LodSettings::far_radius`], drawn from coarse meshes
//! ([`lod_mesh`](super::lod_mesh)), each at the coarsest level whose error
//! looks small enough from the nearest focus.
//!
//! Notation: `e_k` — the geometric error of level `k` of a chunk (world
//! units; see [`lod_mesh`](super::lod_mesh) for what it bounds), `d` — the
//! horizontal distance from the nearest focus to the chunk's square, `H`
//! — the viewport height in pixels, `φ` — the vertical field of view, `τ`
//! — [`LodSettings::pixel_tolerance`]. Level `k` looks like
//! `p_k(d) = e_k · H / (2 d tan(φ/2))` pixels (an error of `e_k` seen
//! face-on at distance `d`; the chunk is at least `d` away, so it looks no
//! larger). A chunk is drawn at the coarsest level `k` with `p_j(d) ≤ τ`
//! for every `j ≤ k` (level 1 when none fits). Hysteresis: a drawn
//! level is kept while it still fits `τ` and no coarser level fits
//! `τ·(1 − h)`, `h` = [`LodSettings::hysteresis`].
//!
//! A chunk whose full-detail terrain is live and meshed is drawn by it;
//! its coarse meshes stay built (hidden) so that it can swap back at once
//! when it streams out. An edited chunk's coarse meshes are rebuilt from
//! its exact octree once it idles beyond the load radius (or from its
//! stored bytes once it streamed out); until they are ready its previous
//! coarse meshes are drawn.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::tasks::futures::check_ready;
use bevy::tasks::{AsyncComputeTaskPool, Task};
use chisel_bsp::tree::Label;

use super::super::component::Terrain;
use super::super::error::TerrainError;
use super::lod_mesh::{LodBasis, LodPyramid, edited_pyramid, source_pyramid};
use super::{ChunkCoord, TerrainFocus, TerrainWorld, restore};

/// How far coarse chunks reach and how coarse they may look.
#[derive(Clone, Debug, PartialEq)]
pub struct LodSettings {
    /// Chunks whose square comes this close (world units, horizontally)
    /// to a focus are drawn, coarse where they are not full detail.
    pub far_radius: f32,
    /// Largest error on screen, in pixels, of a chunk's level.
    pub pixel_tolerance: f32,
    /// The hysteresis fraction `h` (0..1): a coarser level is taken only
    /// when it fits `τ·(1 − h)`; chunks are dropped beyond
    /// `far_radius·(1 + h)`.
    pub hysteresis: f32,
    /// Vertical field of view (radians) when no focus is a camera with a
    /// perspective projection.
    pub fov_y: f32,
    /// Viewport height (pixels) when no focus is a camera with a viewport.
    pub viewport_height: f32,
    /// Most coarse builds on the async compute pool at once.
    pub max_building: usize,
}

impl Default for LodSettings {
    fn default() -> Self {
        Self {
            far_radius: 400.0,
            pixel_tolerance: 2.0,
            hysteresis: 0.25,
            fov_y: std::f32::consts::FRAC_PI_4,
            viewport_height: 1080.0,
            max_building: 8,
        }
    }
}

/// What the view makes of a geometric error: pixels per world unit at
/// unit distance, `H / (2 tan(φ/2))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodView {
    /// `H / (2 tan(φ/2))`.
    pub pixels_per_radian: f32,
}

impl LodView {
    /// The view of a vertical field of view (radians) over `height`
    /// pixels.
    #[must_use]
    pub fn new(fov_y: f32, height: f32) -> Self {
        Self {
            pixels_per_radian: height / (2.0 * (0.5 * fov_y).tan()),
        }
    }

    /// Pixels an error of `error` world units covers at `distance`.
    #[must_use]
    pub fn pixels(&self, error: f32, distance: f32) -> f32 {
        error * self.pixels_per_radian / distance.max(f32::MIN_POSITIVE)
    }
}

/// The level to draw (1-based) for a chunk with level errors `errors`
/// (world units, finest first) at `distance`, drawn now at `current`
/// (see the module docs).
#[must_use]
pub fn choose_level(
    errors: &[f32],
    distance: f32,
    current: Option<u8>,
    view: LodView,
    tolerance: f32,
    hysteresis: f32,
) -> u8 {
    let fits = |limit: f32| {
        errors
            .iter()
            .take_while(|&&e| view.pixels(e, distance) <= limit)
            .count()
            .max(1) as u8
    };
    let fine = fits(tolerance);
    let Some(current) = current else {
        return fine;
    };
    let loose = fits(tolerance * (1.0 - hysteresis.clamp(0.0, 1.0)));
    if current > fine {
        fine
    } else if current < loose {
        loose
    } else {
        current
    }
}

/// One entity drawing one material of a chunk's coarse level; a child of
/// the world.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component)]
pub struct LodMesh {
    /// The world entity.
    pub world: Entity,
    /// The chunk.
    pub coord: ChunkCoord,
    /// The level drawn (1 is the finest coarse level).
    pub level: u8,
    /// The material shown.
    pub label: Label,
}

/// Counts of a world's coarse chunks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LodStats {
    /// Chunks with coarse meshes built (drawn or hidden).
    pub chunks: usize,
    /// Chunks drawn coarse now, per level (index `k − 1`).
    pub drawn_per_level: Vec<usize>,
    /// Triangles drawn coarse now (skirts included).
    pub triangles: usize,
    /// Bytes of vertex and index data of the coarse meshes drawn now.
    pub mesh_bytes: usize,
    /// Coarse builds so far, from the source and from edited chunks.
    pub built_from_source: u64,
    /// Coarse builds of edited chunks so far.
    pub built_edited: u64,
    /// Time spent on coarse builds (on the pool).
    pub build_time: Duration,
    /// Coarse builds being run now.
    pub building: usize,
    /// Frames that looked at every coarse chunk (see [`update_lod`]); the
    /// other frames looked only at live chunks and finished builds.
    pub full_passes: u64,
}

struct Built {
    pyramid: Result<LodPyramid, TerrainError>,
    time: Duration,
}

#[derive(Default)]
struct LodChunk {
    pyramid: Option<Arc<LodPyramid>>,
    task: Option<Task<Built>>,
    /// The level drawn and its entities (none while full detail draws).
    drawn: Option<(u8, Vec<Entity>)>,
    /// The state hash of the chunk when last seen live and edited.
    seen_edited: Option<u64>,
    /// The chunk's full-detail terrain entity, once it was meshed.
    full: Option<Entity>,
    /// New coarse meshes, not drawn yet.
    stale: bool,
    /// A failed build: not retried.
    failed: bool,
}

/// Level of detail for the [`TerrainWorld`] on the same entity: coarse
/// chunks out to the far radius. Insert it beside the world.
///
/// # Change detection
///
/// `Changed<WorldLod>` marks the frames in which a coarse chunk was drawn
/// at another level (or taken away), a coarse build started or finished,
/// or its [`LodStats`] moved otherwise; frames that only look at still
/// chunks mark nothing.
#[derive(Component, Default)]
pub struct WorldLod {
    settings: LodSettings,
    chunks: BTreeMap<ChunkCoord, LodChunk>,
    stats: LodStats,
    /// Coarse builds of chunks that are not live, due but not started (the
    /// build limit), as the last full pass found them.
    waiting: usize,
    /// What the last full pass saw (see [`update_lod`]).
    last_pass: Option<PassInputs>,
}

/// The inputs of a full pass over a world's coarse chunks besides the
/// chunks' own state: while none of them changes, only live chunks and
/// finished builds need a look.
#[derive(Clone, Debug, PartialEq)]
struct PassInputs {
    /// The foci, in grid units (x, z).
    focus: Vec<[f64; 2]>,
    view: LodView,
    /// The world's live chunks.
    live: Vec<(ChunkCoord, Entity)>,
    /// How many chunks the world stores.
    stored: usize,
}

impl PassInputs {
    /// Whether a full pass is due: a focus moved `step` grid units or
    /// more, or anything else differs.
    fn differ(&self, other: &Self, step: f64) -> bool {
        self.view != other.view
            || self.stored != other.stored
            || self.live != other.live
            || self.focus.len() != other.focus.len()
            || self
                .focus
                .iter()
                .zip(&other.focus)
                .any(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]) >= step)
    }
}

impl WorldLod {
    /// Level of detail with these settings.
    ///
    /// # Errors
    /// [`TerrainError::InvalidWorld`] for a non-finite or negative radius
    /// or tolerance, a hysteresis outside `0..1`, a bad view, or no builds
    /// allowed.
    pub fn new(settings: LodSettings) -> Result<Self, TerrainError> {
        let s = &settings;
        let ok = s.far_radius.is_finite()
            && s.far_radius >= 0.0
            && s.pixel_tolerance.is_finite()
            && s.pixel_tolerance > 0.0
            && (0.0..1.0).contains(&s.hysteresis)
            && s.fov_y > 0.0
            && s.fov_y < std::f32::consts::PI
            && s.viewport_height.is_finite()
            && s.viewport_height > 0.0
            && s.max_building > 0;
        if !ok {
            return Err(TerrainError::InvalidWorld {
                reason: format!(
                    "level of detail needs a finite far radius >= 0, a positive tolerance, \
                     hysteresis in 0..1, a field of view in (0, π), a positive viewport height \
                     and max_building > 0; got {settings:?}"
                ),
            });
        }
        Ok(Self {
            settings,
            ..Self::default()
        })
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &LodSettings {
        &self.settings
    }

    /// Counts of coarse chunks.
    #[must_use]
    pub fn stats(&self) -> &LodStats {
        &self.stats
    }

    /// The level chunk `coord` is drawn at and its error (world units),
    /// when it is drawn coarse.
    #[must_use]
    pub fn drawn_level(&self, coord: ChunkCoord) -> Option<(u8, f32)> {
        let chunk = self.chunks.get(&coord)?;
        let (level, _) = chunk.drawn.as_ref()?;
        let error = chunk.pyramid.as_ref()?.levels[usize::from(*level) - 1].error;
        Some((*level, error))
    }

    /// The coarse meshes built for chunk `coord`.
    #[must_use]
    pub fn pyramid(&self, coord: ChunkCoord) -> Option<&LodPyramid> {
        self.chunks.get(&coord)?.pyramid.as_deref()
    }

    /// Whether no coarse build runs or waits: every chunk within the far
    /// radius that full detail does not draw is drawn coarse, from its
    /// latest state (after the next update).
    #[must_use]
    pub fn is_settled(&self) -> bool {
        self.stats.building == 0 && self.waiting == 0
    }
}

/// A focus moving less than this fraction of a chunk's edge since the last
/// full pass does not start another (see [`update_lod`]).
const REFRESH_STEP: f64 = 0.25;

/// Builds, swaps and drops the coarse chunks of every world with a
/// [`WorldLod`]. Runs after the terrain's meshes are shown
/// ([`TerrainSystems::Mesh`](super::super::TerrainSystems)).
///
/// A full pass looks at every coarse chunk: it drops those beyond the far
/// radius, adds those within it, starts builds nearest first and chooses
/// every chunk's level. It runs when a build finished, a focus moved a
/// quarter of a chunk's edge, the view changed, or the world's live or
/// stored chunks changed. Other frames look only at the live chunks (an
/// edit, or full detail becoming ready, changes what they need), so a
/// still or slow focus costs little however many coarse chunks there are.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn update_lod(
    mut commands: Commands,
    mut worlds: Query<(Entity, &TerrainWorld, &mut WorldLod, &GlobalTransform)>,
    foci: Query<(Entity, &GlobalTransform), With<TerrainFocus>>,
    terrains: Query<&Terrain>,
    offstage: Query<(), With<super::ChunkOffstage>>,
    mut meshes: ResMut<Assets<Mesh>>,
    #[cfg(feature = "render")] cameras: Query<(&Camera, &Projection)>,
) {
    let _span = bevy::log::info_span!("chisel::lod::update").entered();
    for (world_entity, world, mut lod_mut, world_transform) in &mut worlds {
        // Bookkeeping bypasses change detection: the component is marked
        // changed only when what it shows or reports changed.
        let lod = lod_mut.bypass_change_detection();
        let stats_before = lod.stats.clone();
        let mut redrawn = false;
        let settings = lod.settings.clone();
        #[allow(unused_mut)]
        let mut view = LodView::new(settings.fov_y, settings.viewport_height);
        #[cfg(feature = "render")]
        if let Some(v) = foci
            .iter()
            .find_map(|(e, _)| cameras.get(e).ok().and_then(camera_view))
        {
            view = v;
        }
        let layout = &world.layout;
        let unit = layout.quantization.unit();
        let focus = super::stream::grid_foci(layout, world_transform, foci.iter().map(|(_, f)| f));
        let edge = layout.chunk_edge();
        // Distance in grid units, and in world units.
        let grid_distance =
            |coord: ChunkCoord| super::stream::nearest_distance(&focus, coord, edge);
        let distance = |coord: ChunkCoord| grid_distance(coord) * unit;
        let far = f64::from(settings.far_radius);
        let keep = far * (1.0 + f64::from(settings.hysteresis));
        let load = f64::from(world.settings.load_radius);

        // Collect finished builds.
        let mut finished = 0usize;
        for (coord, chunk) in &mut lod.chunks {
            let Some(task) = chunk.task.as_mut() else {
                continue;
            };
            let Some(built) = check_ready(task) else {
                continue;
            };
            chunk.task = None;
            finished += 1;
            lod.stats.build_time += built.time;
            match built.pyramid {
                Ok(pyramid) => {
                    match pyramid.basis {
                        LodBasis::Source => lod.stats.built_from_source += 1,
                        LodBasis::Edited(_) => lod.stats.built_edited += 1,
                    }
                    chunk.pyramid = Some(Arc::new(pyramid));
                    // Redrawn below from the new meshes.
                    chunk.stale = true;
                }
                Err(error) => {
                    warn!(
                        "terrain world coarse chunk ({}, {}): {error}",
                        coord.x, coord.z
                    );
                    chunk.failed = true;
                }
            }
        }

        let inputs = PassInputs {
            focus: focus.clone(),
            view,
            live: world.live_chunks().collect(),
            stored: world.stored.len(),
        };
        let full_pass = finished > 0
            || lod
                .last_pass
                .as_ref()
                .is_none_or(|last| last.differ(&inputs, REFRESH_STEP * edge as f64));

        let visit: Vec<ChunkCoord> = if full_pass {
            // Drop chunks beyond the far radius (with hysteresis).
            let gone: Vec<ChunkCoord> = lod
                .chunks
                .keys()
                .copied()
                .filter(|&c| distance(c) > keep)
                .collect();
            for coord in gone {
                if let Some(chunk) = lod.chunks.remove(&coord)
                    && let Some((_, entities)) = chunk.drawn
                {
                    despawn_all(&mut commands, &entities);
                }
            }
            // Chunks within the far radius.
            let mut wanted = Vec::new();
            super::stream::chunks_within(&focus, edge, far / unit, grid_distance, &mut wanted);
            for (_, coord) in wanted {
                lod.chunks.entry(coord).or_default();
            }
            lod.chunks.keys().copied().collect()
        } else {
            inputs
                .live
                .iter()
                .map(|&(coord, _)| coord)
                .filter(|c| lod.chunks.contains_key(c))
                .collect()
        };
        // Builds start nearest first.
        let mut order: Vec<(f64, ChunkCoord)> = visit.iter().map(|&c| (distance(c), c)).collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));

        // Start builds whose basis is out of date.
        let mut building = lod.chunks.values().filter(|c| c.task.is_some()).count();
        let mut waiting = if full_pass { 0 } else { lod.waiting };
        for &(d, coord) in &order {
            let Some(chunk) = lod.chunks.get_mut(&coord) else {
                continue;
            };
            let entity = world.chunk_entity(coord);
            let live = entity.and_then(|e| terrains.get(e).ok());
            // What the coarse meshes should be made from now, and whether
            // they can be built now.
            let job = match live {
                Some(t) if world.chunk_edited(coord, t) => {
                    chunk.seen_edited = Some(t.state_hash());
                    let ready = t.is_idle() && d > load;
                    Job::Octree(t.state_hash(), ready.then(|| t.octree().clone()))
                }
                Some(_) => {
                    chunk.seen_edited = None;
                    Job::Source
                }
                None => match world.stored.get(&coord) {
                    Some(bytes) => Job::Bytes(chunk.seen_edited, bytes.clone()),
                    None => Job::Source,
                },
            };
            let current = chunk.pyramid.as_ref().map(|p| p.basis);
            let up_to_date = match (&job, current) {
                (Job::Source, Some(LodBasis::Source)) => true,
                (Job::Octree(h, _), Some(LodBasis::Edited(b))) => *h == b,
                (Job::Bytes(Some(h), _), Some(LodBasis::Edited(b))) => *h == b,
                (Job::Bytes(None, _), Some(LodBasis::Edited(_))) => true,
                _ => false,
            };
            if up_to_date || chunk.task.is_some() || chunk.failed {
                continue;
            }
            if matches!(job, Job::Octree(_, None)) {
                // Full detail draws it; rebuilt once it idles farther out.
                continue;
            }
            if building >= settings.max_building {
                // Live chunks are looked at every frame; the others wait
                // for the next full pass, which a finished build starts.
                if entity.is_none() {
                    waiting += 1;
                }
                continue;
            }
            let layout = layout.clone();
            let labels = world.labels.clone();
            let pool = AsyncComputeTaskPool::get();
            // Behind the world's carves and debris work (`pool_order`).
            let order = world.pool_order.clone();
            let task = match job {
                Job::Source => {
                    let source = world.source.clone();
                    pool.spawn(async move {
                        order.after_first().await;
                        let start = Instant::now();
                        let pyramid = source_pyramid(&layout, &*source, coord);
                        Built {
                            pyramid,
                            time: start.elapsed(),
                        }
                    })
                }
                Job::Octree(hash, Some(octree)) => {
                    let source = world.source.clone();
                    pool.spawn(async move {
                        order.after_first().await;
                        let start = Instant::now();
                        let pyramid = edited_pyramid(&layout, &*source, coord, &octree, hash);
                        Built {
                            pyramid,
                            time: start.elapsed(),
                        }
                    })
                }
                Job::Octree(_, None) => continue,
                Job::Bytes(_, bytes) => {
                    let source = world.source.clone();
                    pool.spawn(async move {
                        order.after_first().await;
                        let start = Instant::now();
                        let pyramid = restore(&bytes, &labels).and_then(|t| {
                            edited_pyramid(&layout, &*source, coord, t.octree(), t.state_hash())
                        });
                        Built {
                            pyramid,
                            time: start.elapsed(),
                        }
                    })
                }
            };
            chunk.task = Some(task);
            building += 1;
        }

        // Draw: full detail where it is meshed, else the chosen level.
        for &(d, coord) in &order {
            let Some(chunk) = lod.chunks.get_mut(&coord) else {
                continue;
            };
            let full = match world.chunk_entity(coord) {
                // A chunk out of sight builds no meshes: coarse draws it.
                Some(e) if offstage.contains(e) => {
                    chunk.full = None;
                    false
                }
                Some(e) => {
                    // Full detail draws once it was idle (meshed) once.
                    if chunk.full != Some(e) && terrains.get(e).is_ok_and(Terrain::is_idle) {
                        chunk.full = Some(e);
                    }
                    chunk.full == Some(e)
                }
                None => {
                    chunk.full = None;
                    false
                }
            };
            let d = d as f32;
            let current = chunk.drawn.as_ref().map(|(l, _)| *l);
            let target = match &chunk.pyramid {
                _ if full => None,
                // Between the far radius and the drop distance: as it was.
                _ if d > settings.far_radius => current,
                Some(p) => Some(choose_level(
                    &p.errors(),
                    d,
                    current,
                    view,
                    settings.pixel_tolerance,
                    settings.hysteresis,
                )),
                None => None,
            };
            if current != target || chunk.stale {
                chunk.stale = false;
                redrawn = true;
                if let Some((_, entities)) = chunk.drawn.take() {
                    despawn_all(&mut commands, &entities);
                }
                if let (Some(level), Some(pyramid)) = (target, &chunk.pyramid) {
                    let level_mesh = &pyramid.levels[usize::from(level) - 1];
                    let entities = level_mesh
                        .meshes
                        .iter()
                        .map(|(label, mesh)| {
                            commands
                                .spawn((
                                    LodMesh {
                                        world: world_entity,
                                        coord,
                                        level,
                                        label: *label,
                                    },
                                    Mesh3d(meshes.add(mesh.clone())),
                                    Transform::IDENTITY,
                                    ChildOf(world_entity),
                                ))
                                .id()
                        })
                        .collect();
                    chunk.drawn = Some((level, entities));
                }
            }
        }

        let levels = usize::from(super::lod_mesh::coarsest_level(layout));
        let mut stats_drawn = vec![0usize; levels];
        let (mut triangles, mut bytes, mut built) = (0usize, 0usize, 0usize);
        for chunk in lod.chunks.values() {
            let Some(pyramid) = &chunk.pyramid else {
                continue;
            };
            built += 1;
            if let Some((level, _)) = &chunk.drawn {
                let l = &pyramid.levels[usize::from(*level) - 1];
                stats_drawn[usize::from(*level) - 1] += 1;
                triangles += l.triangles;
                bytes += l.bytes;
            }
        }
        lod.stats.chunks = built;
        lod.stats.drawn_per_level = stats_drawn;
        lod.stats.triangles = triangles;
        lod.stats.mesh_bytes = bytes;
        lod.stats.building = building;
        lod.waiting = waiting;
        if full_pass {
            lod.stats.full_passes += 1;
            lod.last_pass = Some(inputs);
        }
        if redrawn || lod.stats != stats_before {
            lod_mut.set_changed();
        }
    }
}

/// What a chunk's coarse meshes are to be made from.
enum Job {
    Source,
    /// A live edited chunk with this state hash, and its octree when it
    /// may be built now.
    Octree(u64, Option<chisel_bsp::octree::Octree>),
    /// A stored chunk (the hash it had when last seen live, if seen).
    Bytes(Option<u64>, Arc<Vec<u8>>),
}

fn despawn_all(commands: &mut Commands, entities: &[Entity]) {
    for &e in entities {
        commands.entity(e).try_despawn();
    }
}

/// The view of a camera with a perspective projection and a viewport.
#[cfg(feature = "render")]
fn camera_view((camera, projection): (&Camera, &Projection)) -> Option<LodView> {
    let Projection::Perspective(p) = projection else {
        return None;
    };
    let height = camera.physical_viewport_size()?.y as f32;
    (height > 0.0).then(|| LodView::new(p.fov, height))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> LodView {
        LodView::new(std::f32::consts::FRAC_PI_4, 1080.0)
    }

    #[test]
    fn the_level_is_the_coarsest_within_the_tolerance() {
        let errors = [0.05, 0.2, 0.8, 3.2];
        let v = view();
        for d in [1.0f32, 10.0, 40.0, 100.0, 300.0, 1000.0, 1e5] {
            let k = choose_level(&errors, d, None, v, 2.0, 0.25);
            // Every level up to k fits (unless k is the finest), and the
            // next does not.
            if v.pixels(errors[0], d) <= 2.0 {
                for e in &errors[..usize::from(k)] {
                    assert!(v.pixels(*e, d) <= 2.0, "d {d}: level {k}");
                }
            } else {
                assert_eq!(k, 1);
            }
            if usize::from(k) < errors.len() {
                assert!(v.pixels(errors[usize::from(k)], d) > 2.0, "d {d}: {k}");
            }
        }
        // Farther is never finer.
        let mut last = 1;
        for step in 0..3000 {
            let k = choose_level(&errors, step as f32, None, v, 2.0, 0.25);
            assert!(k >= last);
            last = k;
        }
        assert_eq!(last, 4);
        // pixels_per_radian = 1080 / (2 tan 22.5°) = 1303.6.
        assert!((v.pixels_per_radian - 1303.6).abs() < 0.1);
    }

    #[test]
    fn hysteresis_keeps_the_level_near_a_switch() {
        let errors = [0.05, 0.2, 0.8, 3.2];
        let v = view();
        // Level 2 fits 2 px beyond d2 = 0.2 · 1303.6 / 2.
        let d2 = 0.2 * v.pixels_per_radian / 2.0;
        assert_eq!(choose_level(&errors, d2 * 0.99, None, v, 2.0, 0.25), 1);
        assert_eq!(choose_level(&errors, d2 * 1.01, None, v, 2.0, 0.25), 2);
        // Drawn at 1, moving out just past d2: kept at 1 until level 2
        // fits 1.5 px (d2 / 0.75).
        assert_eq!(choose_level(&errors, d2 * 1.1, Some(1), v, 2.0, 0.25), 1);
        assert_eq!(choose_level(&errors, d2 * 1.3, Some(1), v, 2.0, 0.25), 1);
        assert_eq!(choose_level(&errors, d2 * 1.34, Some(1), v, 2.0, 0.25), 2);
        // Drawn at 2, moving back in: kept until level 2 no longer fits.
        assert_eq!(choose_level(&errors, d2 * 1.01, Some(2), v, 2.0, 0.25), 2);
        assert_eq!(choose_level(&errors, d2 * 0.99, Some(2), v, 2.0, 0.25), 1);
        // A jump far out skips levels; a drawn level too coarse for the
        // distance is refined at once.
        assert_eq!(choose_level(&errors, 1e4, Some(1), v, 2.0, 0.25), 4);
        assert_eq!(choose_level(&errors, 1.0, Some(4), v, 2.0, 0.25), 1);
        // Back and forth across d2 within the band: never a change.
        let mut level = 2;
        for k in 0..100 {
            let d = d2 * if k % 2 == 0 { 1.02 } else { 1.3 };
            level = choose_level(&errors, d, Some(level), v, 2.0, 0.25);
            assert_eq!(level, 2);
        }
    }

    #[test]
    fn a_camera_view_follows_fov_and_height() {
        let narrow = LodView::new(0.2, 1000.0);
        let wide = LodView::new(1.2, 1000.0);
        assert!(narrow.pixels(1.0, 100.0) > 4.0 * wide.pixels(1.0, 100.0));
        let tall = LodView::new(1.2, 2000.0);
        assert!((tall.pixels(1.0, 100.0) - 2.0 * wide.pixels(1.0, 100.0)).abs() < 1e-4);
        assert!(
            WorldLod::new(LodSettings {
                hysteresis: 1.5,
                ..LodSettings::default()
            })
            .is_err()
        );
        assert!(WorldLod::new(LodSettings::default()).is_ok());
    }
}
