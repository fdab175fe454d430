//! Props in the main world: the [`QuadricProp`] component, the
//! [`QuadricScene`] asset (scene files, `quadric/SCENES.md`), and sampling on
//! the async compute pool with the result swapped in when ready.
//!
//! States of a prop entity: [`QuadricProp`] (what to draw) → a sampling task
//! ([`PropSampling`]) → [`PropSplats`] (what the render world draws). An edit
//! while a task runs re-samples when it ends; the old splats stay on screen
//! until the new ones are in, so an edit never causes a frame without the
//! prop nor a frame hitch. [`PropSampling`] keeps the samples per basic
//! region of the splats drawn: an edit of the scene's shapes re-samples only
//! the regions it can change ([`RegionSamples::resample`]). A scene file
//! that fails to load after an edit is reported, and Bevy keeps the
//! previous scene, so the prop keeps its splats.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoadFailedEvent, AssetLoader, LoadContext, LoadState};
use bevy::camera::primitives::Aabb;
use bevy::camera::visibility::{VisibilityClass, add_visibility_class};
use bevy::ecs::lifecycle::HookContext;
use bevy::ecs::world::DeferredWorld;
use bevy::math::{DVec3, Vec4};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};
use chisel_quadric::sampling::partial::RegionSamples;
use chisel_quadric::{BoundingSphere, SampleOptions, Scene, SplatSet, encode_normal_form};

use super::gpu::{QuadricRecord, SplatRecord};
use super::prop_carve::{CarveRefusal, PropCarveRefused, PropCarved, PropCarves};

/// A quadric CSG scene as an asset, loaded from a RON scene file
/// (`*.quadric.ron`, format in `quadric/SCENES.md`) or added in memory with
/// `Assets::<QuadricScene>::add`. With Bevy's `file_watcher` feature an
/// edited scene file is reloaded and its props are re-sampled.
#[derive(Asset, TypePath, Clone, Debug)]
pub struct QuadricScene(pub Scene);

/// Loads [`QuadricScene`]s from `.quadric.ron` files. A malformed file fails the
/// load with the line, column and problem (Bevy logs it with the path).
#[derive(Default, TypePath)]
pub struct QuadricSceneLoader;

/// Why a scene file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum QuadricSceneLoadError {
    /// The file could not be read.
    #[error("cannot read the scene file: {0}")]
    Io(std::io::Error),
    /// The text is not valid UTF-8.
    #[error("the scene file is not UTF-8 text")]
    NotUtf8,
    /// The scene is malformed (line, column and problem inside).
    #[error("malformed scene: {0}")]
    Scene(chisel_quadric::Error),
}

impl AssetLoader for QuadricSceneLoader {
    type Asset = QuadricScene;
    type Settings = ();
    type Error = QuadricSceneLoadError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        _load_context: &mut LoadContext<'_>,
    ) -> Result<QuadricScene, QuadricSceneLoadError> {
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(QuadricSceneLoadError::Io)?;
        let text = String::from_utf8(bytes).map_err(|_| QuadricSceneLoadError::NotUtf8)?;
        Scene::from_ron(&text)
            .map(QuadricScene)
            .map_err(QuadricSceneLoadError::Scene)
    }

    fn extensions(&self) -> &[&str] {
        &["quadric.ron"]
    }
}

/// The splat radius of a prop, in scene units.
#[derive(Clone, Copy, Debug, PartialEq, Reflect)]
#[reflect(Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SplatRadius {
    /// The bounding radius divided by this number (the default, 40, gives
    /// tens of thousands of splats for the shipped scenes).
    Auto(f32),
    /// A fixed radius.
    Fixed(f32),
}

impl Default for SplatRadius {
    fn default() -> Self {
        Self::Auto(40.0)
    }
}

/// A quadric CSG prop: a scene drawn pixel-exact by the splat pass, placed
/// by the entity's `Transform` (scene units are local units).
///
/// Changing the component (or the scene asset) re-samples it on the async
/// compute pool; the previous splats are drawn until the new ones are in.
/// Its [`PropCarves`] (carves of this instance, [`super::prop_carve`]) are
/// cut from the scene's solid.
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(Component)]
#[require(Transform, Visibility, PropCarves)]
pub struct QuadricProp {
    /// The scene.
    pub scene: Handle<QuadricScene>,
    /// Only the surface inside this sphere (local coordinates) is sampled
    /// and drawn; it must contain the solid. `None`: the scene file's
    /// `bounds` (a scene without them is reported and not drawn).
    pub bounds: Option<PropBounds>,
    /// Splat radius.
    pub radius: SplatRadius,
}

/// A bounding sphere in the prop's local coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PropBounds {
    /// Centre.
    pub centre: Vec3,
    /// Radius (positive).
    pub radius: f32,
}

impl From<BoundingSphere> for PropBounds {
    fn from(sphere: BoundingSphere) -> Self {
        Self {
            centre: sphere.centre.as_vec3(),
            radius: sphere.radius as f32,
        }
    }
}

impl PropBounds {
    /// The bounds of a prop: `given`, or else the scene's own (`bounds` in
    /// the scene file); `None` when neither is there.
    #[must_use]
    pub fn resolve(given: Option<PropBounds>, scene: &Scene) -> Option<PropBounds> {
        given.or_else(|| scene.bounds.map(PropBounds::from))
    }

    /// The radius `r` of splats for `radius`.
    #[must_use]
    pub fn splat_radius(&self, radius: SplatRadius) -> f32 {
        match radius {
            SplatRadius::Auto(divisor) => self.radius / divisor.max(1.0),
            SplatRadius::Fixed(r) => r,
        }
    }
}

/// Splats of a prop ready for the GPU, shared with the render world.
///
/// Spawn it directly (with a `Transform`) to draw splats sampled elsewhere,
/// e.g. synchronously with [`PropSplats::build`].
///
/// Props are frustum-culled like meshes: inserting `PropSplats` also
/// inserts an [`Aabb`] around every splat's proxy ([`PropGpuData::aabb`]),
/// the entity joins Bevy's visibility check as class `PropSplats`, and the
/// splat pass draws a prop only in the views whose frustum it meets.
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(Component, from_reflect = false)]
#[require(Transform, Visibility, VisibilityClass)]
#[component(on_add = add_visibility_class::<PropSplats>, on_insert = insert_prop_aabb)]
pub struct PropSplats(#[reflect(ignore)] pub Arc<PropGpuData>);

/// Keeps the prop's `Aabb` in step with its splats.
fn insert_prop_aabb(mut world: DeferredWorld<'_>, HookContext { entity, .. }: HookContext) {
    let Some(aabb) = world
        .get::<PropSplats>(entity)
        .map(|s| s.0.cached_aabb.unwrap_or_else(|| s.0.aabb()))
    else {
        return;
    };
    world.commands().entity(entity).insert(aabb);
}

/// The buffers of one prop in GPU form (empty by default: nothing to
/// draw).
#[derive(Clone, Debug, Default)]
pub struct PropGpuData {
    /// Unique per build: the render world re-uploads when it changes.
    pub generation: u64,
    /// The quadric buffer (one record per quadric of the normal form).
    pub quadrics: Vec<QuadricRecord>,
    /// The deduplicated clip lists.
    pub clip_indices: Vec<u32>,
    /// The instance buffer: one record per splat.
    pub splats: Vec<SplatRecord>,
    /// The normal form for the global pass ([`encode_normal_form`]):
    /// `(start, count)` per product, then each product's literal references.
    pub terms: Vec<u32>,
    /// Number of products.
    pub product_count: u32,
    /// Local bounding sphere (`xyz` centre, `w` radius).
    pub bounds: Vec4,
    /// Splat radius used.
    pub radius: f32,
    /// [`aabb`](Self::aabb), computed beside the splats on the sampling
    /// task so that swapping them in costs the main thread no pass over
    /// them; `None`: computed when the splats are inserted.
    pub cached_aabb: Option<Aabb>,
}

/// Why a prop could not be sampled ([`PropSplats::build`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PropSampleError {
    /// The scene has no valid disjunctive normal form.
    #[error("normal form: {0}")]
    NormalForm(#[source] chisel_quadric::Error),
    /// The bounding sphere is invalid (not finite, or not positive).
    #[error("bounds: {0}")]
    Bounds(#[source] chisel_quadric::Error),
    /// The splat radius is invalid for these bounds.
    #[error("radius: {0}")]
    Radius(#[source] chisel_quadric::Error),
    /// Adaptive sampling failed.
    #[error("sampling: {0}")]
    Sampling(#[source] chisel_quadric::Error),
}

static GENERATION: AtomicU64 = AtomicU64::new(1);

impl PropGpuData {
    /// Number of splats.
    #[must_use]
    pub fn splat_count(&self) -> usize {
        self.splats.len()
    }

    /// The local box around every splat's proxy: a splat's box reaches
    /// `r` along two tangents and `e` along the normal (`r` where the
    /// normal is undefined), so it lies within `√2·r + e` of the sample in
    /// every axis; 1% more covers the pass's radius tolerance. Empty
    /// splats give the bounding sphere's box.
    #[must_use]
    pub fn aabb(&self) -> Aabb {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for s in &self.splats {
            let e = if s.normal.length_squared() < 0.25 {
                s.radius
            } else {
                s.normal_extent.abs()
            };
            let reach = Vec3::splat(1.01 * (std::f32::consts::SQRT_2 * s.radius + e));
            lo = lo.min(s.position - reach);
            hi = hi.max(s.position + reach);
        }
        if lo.cmple(hi).all() && lo.is_finite() && hi.is_finite() {
            Aabb::from_min_max(lo, hi)
        } else {
            let c = self.bounds.truncate();
            let r = Vec3::splat(self.bounds.w.abs());
            Aabb::from_min_max(c - r, c + r)
        }
    }
}

impl PropSplats {
    /// Samples `scene` inside `bounds` with splat radius `radius` (blocking;
    /// the plugin runs this on the async compute pool).
    ///
    /// Errors: the scene's normal form or the sampling options are invalid
    /// (the message says which).
    pub fn build(scene: &Scene, bounds: PropBounds, radius: f32) -> Result<Self, PropSampleError> {
        Self::rebuild(scene, bounds, radius, None).map(|(splats, _)| splats)
    }

    /// As [`build`](Self::build), also returning the samples per basic
    /// region; where `previous` was sampled with the same bounds and radius
    /// (an earlier version of the scene), only the regions the edit can
    /// change are sampled again ([`RegionSamples::resample`]).
    ///
    /// Errors: as [`build`](Self::build).
    pub fn rebuild(
        scene: &Scene,
        bounds: PropBounds,
        radius: f32,
        previous: Option<&RegionSamples>,
    ) -> Result<(Self, RegionSamples), PropSampleError> {
        let dnf = scene.dnf().map_err(PropSampleError::NormalForm)?;
        let sphere = BoundingSphere::new(bounds.centre.as_dvec3(), f64::from(bounds.radius))
            .map_err(PropSampleError::Bounds)?;
        let options =
            SampleOptions::new(f64::from(radius), sphere).map_err(PropSampleError::Radius)?;
        let regions = match previous {
            Some(previous) if *previous.options() == options => {
                previous.resample(&dnf).map(|(regions, _)| regions)
            }
            _ => RegionSamples::sample(&dnf, &options),
        }
        .map_err(PropSampleError::Sampling)?;
        let samples = regions.to_sample_set();
        let set = SplatSet::new(&dnf, &scene.dag, &samples);
        let terms = encode_normal_form(&dnf);
        let centre: DVec3 = sphere.centre;
        let mut data = PropGpuData {
            generation: GENERATION.fetch_add(1, Ordering::Relaxed),
            quadrics: set.quadrics.iter().map(QuadricRecord::from).collect(),
            clip_indices: set.clip_indices,
            splats: set
                .splats
                .iter()
                .map(|s| SplatRecord::new(s, &set.quadrics))
                .collect(),
            terms,
            product_count: to_u32(dnf.products().len()),
            bounds: centre.as_vec3().extend(bounds.radius),
            radius,
            cached_aabb: None,
        };
        data.cached_aabb = Some(data.aabb());
        Ok((Self(Arc::new(data)), regions))
    }
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

/// The sampling state of a prop. `Changed<PropSampling>` marks the frames
/// in which a sampling was asked for, started or finished, not those in
/// which one only runs.
#[derive(Component, Reflect, Default)]
#[reflect(Component, from_reflect = false)]
pub struct PropSampling {
    /// A (re-)sample is wanted.
    pending: bool,
    /// The running task.
    #[reflect(ignore)]
    task: Option<Task<(SamplingResult, usize)>>,
    /// The scene failed to load, or has no bounds, and was reported.
    reported: bool,
    /// Sampling tasks started so far.
    runs: u64,
    /// The samples per basic region of the splats drawn now: an edit of
    /// the scene re-samples only the regions it can change. They cost
    /// about 90 bytes per sample beside the splats (7 MB for `machine80`
    /// at 80,000 splats).
    #[reflect(ignore)]
    regions: Option<Arc<RegionSamples>>,
}

type SamplingResult = Result<(PropSplats, RegionSamples), PropSampleError>;

impl PropSampling {
    /// The sampling tasks started for this prop so far: one when it
    /// appears, one per change of its [`QuadricProp`] or scene (moving,
    /// rotating or scaling the prop starts none).
    #[must_use]
    pub fn sampling_runs(&self) -> u64 {
        self.runs
    }

    /// Asks for a new sampling (a carve came in).
    pub(crate) fn request(&mut self) {
        self.pending = true;
    }

    /// Whether a sampling task is running or wanted.
    #[must_use]
    pub fn is_busy(&self) -> bool {
        self.pending || self.task.is_some()
    }
}

/// Marks props whose component or scene changed as wanting new splats.
pub(crate) fn request_sampling(
    mut commands: Commands,
    mut events: MessageReader<AssetEvent<QuadricScene>>,
    changed: Query<Entity, (With<QuadricProp>, Changed<QuadricProp>)>,
    mut props: Query<(Entity, &QuadricProp, Option<&mut PropSampling>)>,
) {
    // A reload sends `Modified` and then, maybe frames later,
    // `LoadedWithDependencies`: only the first re-samples, or a second task
    // would sample the same scene again. `LoadedWithDependencies` matters
    // to a prop whose scene had failed to load (it has no `Modified`).
    let (mut modified, mut loaded) = (Vec::new(), Vec::new());
    for event in events.read() {
        match event {
            AssetEvent::Modified { id } => modified.push(*id),
            AssetEvent::LoadedWithDependencies { id } => loaded.push(*id),
            _ => {}
        }
    }
    for (entity, prop, state) in &mut props {
        let id = prop.scene.id();
        let wanted = changed.contains(entity)
            || modified.contains(&id)
            || (loaded.contains(&id) && state.as_ref().is_some_and(|s| s.reported));
        match state {
            Some(mut state) if wanted => {
                state.pending = true;
                state.reported = false;
            }
            Some(_) => {}
            None => {
                commands.entity(entity).insert(PropSampling {
                    pending: true,
                    ..default()
                });
            }
        }
    }
}

/// Reports a scene file that failed to load again after it had loaded
/// (an edit with a mistake), once per prop using it: Bevy keeps the
/// previous scene, so the prop keeps its splats until the file is fixed.
/// A first load that fails is reported by [`start_sampling`].
pub(crate) fn report_failed_edits(
    mut failures: MessageReader<AssetLoadFailedEvent<QuadricScene>>,
    scenes: Res<Assets<QuadricScene>>,
    props: Query<(Entity, &QuadricProp)>,
) {
    for failure in failures.read() {
        if !scenes.contains(failure.id) {
            continue;
        }
        for (entity, prop) in &props {
            if prop.scene.id() == failure.id {
                error!(
                    "quadric prop {entity}: the edited scene file `{}` did not load; the prop \
                     keeps its previous scene and splats until the file is fixed: {}",
                    failure.path, failure.error
                );
            }
        }
    }
}

/// Starts sampling tasks for props that want one and have their scene.
pub(crate) fn start_sampling(
    scenes: Res<Assets<QuadricScene>>,
    asset_server: Res<AssetServer>,
    mut props: Query<(Entity, &QuadricProp, &mut PropSampling, Option<&PropCarves>)>,
) {
    for (entity, prop, mut state, carves) in &mut props {
        if !state.pending || state.task.is_some() {
            continue;
        }
        let Some(scene) = scenes.get(&prop.scene) else {
            if let Some(LoadState::Failed(e)) = asset_server.get_load_state(&prop.scene)
                && !state.reported
            {
                error!("quadric prop {entity}: its scene did not load: {e}");
                state.reported = true;
                state.pending = false;
            }
            continue;
        };
        let Some(bounds) = PropBounds::resolve(prop.bounds, &scene.0) else {
            if !state.reported {
                error!(
                    "quadric prop {entity}: no bounding sphere: give `bounds: (x, y, z, r)` in \
                     the scene file or `QuadricProp::bounds`"
                );
                state.reported = true;
            }
            state.pending = false;
            continue;
        };
        let scene = scene.0.clone();
        let radius = bounds.splat_radius(prop.radius);
        let previous = state.regions.clone();
        let carves = carves.map(PropCarves::snapshot).unwrap_or_default();
        state.pending = false;
        state.runs += 1;
        state.task = Some(AsyncComputeTaskPool::get().spawn(async move {
            let result = scene
                .carved(&carves)
                .map_err(PropSampleError::NormalForm)
                .and_then(|scene| PropSplats::rebuild(&scene, bounds, radius, previous.as_deref()));
            (result, carves.len())
        }));
    }
}

/// Swaps finished samplings in, and tells which carves came in or were
/// taken back.
pub(crate) fn finish_sampling(
    mut commands: Commands,
    mut props: Query<(Entity, &mut PropSampling, Option<&mut PropCarves>)>,
    mut carved: MessageWriter<PropCarved>,
    mut refused: MessageWriter<PropCarveRefused>,
) {
    for (entity, mut state, carves) in &mut props {
        // Polling is no change; a finished task is (`Changed<PropSampling>`).
        let Some(task) = state.bypass_change_detection().task.as_mut() else {
            continue;
        };
        let Some(result) = check_ready(task) else {
            continue;
        };
        state.task = None;
        let (result, carve_count) = result;
        match result {
            Ok((splats, regions)) => {
                debug!("quadric prop {entity}: {} splats", splats.0.splat_count());
                state.regions = Some(Arc::new(regions));
                commands.entity(entity).insert(splats);
                if let Some(carves) = carves.and_then(|mut c| c.sampled(carve_count)) {
                    carved.write(PropCarved {
                        prop: entity,
                        carves,
                    });
                }
            }
            Err(message) => {
                error!("quadric prop {entity}: {message}; the previous splats (if any) stay drawn");
                let taken_back = carves.map_or(0, |mut c| c.failed(carve_count));
                for _ in 0..taken_back {
                    refused.write(PropCarveRefused {
                        prop: entity,
                        reason: CarveRefusal::Sampling(message.clone()),
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPHERE: &str = r#"Scene(
        primitives: [(name: "A", shape: Sphere(center: (0, 0, 0), radius: 10))],
        root: Ref("A"),
    )"#;
    const SPHERE_WITH_BOUNDS: &str = r#"Scene(
        primitives: [(name: "A", shape: Sphere(center: (0, 0, 0), radius: 10))],
        root: Ref("A"),
        bounds: (1, 2, 3, 12),
    )"#;

    #[test]
    fn bounds_come_from_the_prop_then_from_the_scene_file() {
        let with = Scene::from_ron(SPHERE_WITH_BOUNDS).expect("valid scene");
        let without = Scene::from_ron(SPHERE).expect("valid scene");
        let given = PropBounds {
            centre: Vec3::ZERO,
            radius: 20.0,
        };
        assert_eq!(PropBounds::resolve(Some(given), &with), Some(given));
        assert_eq!(
            PropBounds::resolve(None, &with),
            Some(PropBounds {
                centre: Vec3::new(1.0, 2.0, 3.0),
                radius: 12.0,
            })
        );
        assert_eq!(PropBounds::resolve(None, &without), None);
    }
}
