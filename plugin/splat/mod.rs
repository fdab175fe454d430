//! Quadric CSG props drawn pixel-exact by splat ray tracing (paper 2, §6).
//!
//! ## Map
//!
//! - [`prop`] — main world: the [`QuadricProp`] component, the
//!   [`QuadricScene`] asset and its `.quadric.ron` loader, sampling on the async
//!   compute pool into [`PropSplats`]; an edited scene re-samples only the
//!   regions the edit can change (`chisel_quadric::sampling::partial`).
//! - [`prop_carve`] — main world: [`CarveProp`] cuts a world-space sphere
//!   from one prop instance (an ellipsoid in its local frame), re-sampled
//!   near the bite only; [`PropCarved`] / [`PropCarveRefused`] report it.
//! - [`material`] — [`PropMaterial`], a prop's metallic, roughness and
//!   reflectance for Bevy's PBR lighting (base colours are the quadrics').
//! - [`gpu`] — the GPU data layouts, declared once (`#[repr(C)]`,
//!   `ShaderType`) and converted from the kernel's plain records; their
//!   WGSL mirror is `shaders/quadric_common.wgsl`.
//! - [`pipeline`] — bind group layouts and the pipeline specialized on the
//!   view's format and MSAA and on its splat settings.
//! - [`render`] — render world: extraction, buffer upload, and the pass, a
//!   `Core3d` system between the opaque and transparent passes.
//! - [`shadow`] — render world: props cast shadows, their splats drawn
//!   depth-only into Bevy's shadow maps (directional cascades, point and
//!   spot lights) by two `Core3d` systems after Bevy's shadow passes.
//!   `NotShadowCaster` on a prop turns its shadow off.
//! - `light_visibility` — main world: props in a shadow-casting light's
//!   frusta are visible (extracted) even outside every camera, as meshes are.
//! - `prop_collider` (feature `avian` or `rapier`) — the voxels of a
//!   prop's solid from the exact inside test, computed off the main
//!   thread; `avian` (feature `avian`) and `rapier` (feature `rapier`) make
//!   them each engine's static voxel collider.
//!
//! Settings: the [`SplatSettings`] resource applies to every camera; a
//! camera with a [`SplatViewSettings`] component is drawn with those
//! instead (one view in global ray tracing or showing quadric ids beside
//! the shaded one, say).
//!
//! Multisampling: on a camera with `Msaa` (Bevy's default is 4 samples)
//! the splat pass traces the ray of each covered sample, so a prop's
//! silhouette is anti-aliased like a mesh's and every sample shows the
//! surface along its own ray (a splat's proxy can cover a sample of a pixel
//! whose centre lies beyond the splat's radius). At 4 samples that is one
//! fragment invocation per pixel tracing up to four rays and shading once,
//! with one depth for the samples it writes (the farthest of their hits):
//! where a mesh or another patch crosses the prop, samples are ordered per
//! pixel. At 2 or 8 samples it is one invocation per sample. What it
//! costs: `benches/splat.rs` with `CHISEL_BENCH_MSAA=4`, on lavapipe at
//! 1920×1080, puts the splat pass at 1.9–3.7× its time with `Msaa::Off`
//! on the four SCENARIOS scenes (3.2–6.6× with one invocation per sample;
//! BENCHMARKS.md, "Splat rendering"); `Msaa::Off` on the camera keeps one
//! ray per pixel.
//!
//! Transforms: a prop follows its entity's `GlobalTransform`, any
//! invertible affine map — non-uniform scale, shear, and mirroring (a
//! negative determinant: the prop is drawn as the mirror image of its
//! scene, boxes wound the other way round so that culling keeps the faces
//! towards the eye). A prop whose transform has no inverse (a zero scale)
//! is not drawn. A transform never re-samples a prop: the splats are in
//! its local frame and every fragment ray traces in local coordinates, so
//! any invertible map is drawn exactly (the splats stretch with it).
//!
//! Shaders: `shaders/splat.wgsl` (surface-aligned boxes with back-face
//! culling, §6.1, or screen-aligned quads; local ray tracing, clipping and
//! depth writes), `shaders/global.wgsl` (the global ray-tracing baseline),
//! and `shaders/splat_shading.wgsl`, which both import: a ray-traced point
//! lit by Bevy's PBR functions.
//!
//! ```no_run
//! use bevy::prelude::*;
//! use bevy_chisel::splat::{ChiselSplatPlugin, PropBounds, QuadricProp, SplatRadius};
//!
//! fn setup(mut commands: Commands, assets: Res<AssetServer>) {
//!     commands.spawn((
//!         QuadricProp {
//!             scene: assets.load("scenes/classic.quadric.ron"),
//!             // `None` takes the scene file's `bounds`.
//!             bounds: Some(PropBounds { centre: Vec3::ZERO, radius: 90.0 }),
//!             radius: SplatRadius::Auto(40.0),
//!         },
//!         // Scene units are millimetres: a 10 cm prop at the origin.
//!         Transform::from_scale(Vec3::splat(0.001)),
//!     ));
//! }
//!
//! App::new()
//!     .add_plugins((DefaultPlugins, ChiselSplatPlugin))
//!     .add_systems(Startup, setup)
//!     .run();
//! ```

#[cfg(feature = "avian")]
pub mod avian;
pub mod gpu;
mod light_visibility;
pub mod material;
pub mod pipeline;
pub mod prop;
pub mod prop_carve;
#[cfg(any(feature = "avian", feature = "rapier"))]
pub mod prop_collider;
#[cfg(feature = "rapier")]
pub mod rapier;
pub mod render;
pub mod shadow;

use bevy::camera::visibility::VisibilitySystems;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::light::SimulationLightSystems;
use bevy::pbr::{LATE_SHADOW_PASS, MeshPipelineSystems, per_view_shadow_pass, shared_shadow_pass};
use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::render_resource::SpecializedRenderPipelines;
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderStartup, RenderSystems};

pub use material::PropMaterial;
pub use prop::{
    PropBounds, PropGpuData, PropSampleError, PropSampling, PropSplats, QuadricProp, QuadricScene,
    SplatRadius,
};
pub use prop_carve::{
    CarveProp, CarveRefusal, DEFAULT_CARVE_COLOR, PropCarveRefused, PropCarved, PropCarves,
};

/// How props are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SplatMode {
    /// Splats as surface-aligned boxes (or quads where flat) with back-face
    /// culling (§6.1): the fast path.
    #[default]
    SurfaceBoxes,
    /// Splats as camera-facing quads covering each splat's sphere (§6).
    ScreenQuads,
    /// No splats: every pixel of a cube around each prop ray traces the
    /// whole normal form (the baseline of §7.2).
    GlobalRayTrace,
}

/// What the pass writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SplatOutput {
    /// Lit by Bevy's PBR functions as a `StandardMaterial` mesh is: every
    /// light, received shadows, the camera's exposure, fog and tonemapping.
    #[default]
    Shaded,
    /// The quadric index, unlit (tests): in an 8-bit sRGB target the bytes
    /// are `r = 16·(i mod 16) + 8`, `g = 16·(i div 16 mod 16) + 8`, `b = 200`.
    QuadricIds,
    /// The world normal as `n · 0.5 + 0.5`.
    Normals,
    /// `1/64` per fragment invocation, added up (no depth test): overdraw.
    Overdraw,
    /// `1/64` per fragment whose proxy passes the depth test against the
    /// splats' own surface, added up: the pass first draws every splat
    /// depth only (a depth prepass), then counts the proxy fragments at or
    /// in front of that depth, without writing it. These are the fragment
    /// shader invocations a GPU with early depth tests runs after a depth
    /// prepass (paper 2, §7 counts invocations with the depth test), and
    /// the fewest it runs in any drawing order. The counted proxies are
    /// moved towards the eye by a few units of depth rounding, so that a
    /// flat splat's quad, which lies on its surface, is counted there.
    DepthTestedOverdraw,
    /// The proxies themselves, each splat's in a colour of its own, at
    /// their rasterized depth: the splat bounds of §6.1 (the proxy cube in
    /// global ray-tracing mode).
    Bounds,
}

/// Settings of the splat pass, for all props, in every view whose camera
/// has no [`SplatViewSettings`] of its own.
#[derive(Resource, Clone, Copy, Debug, PartialEq, ExtractResource, Reflect)]
#[reflect(Resource, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SplatSettings {
    /// Splats or global ray tracing.
    pub mode: SplatMode,
    /// Shading or a debug output.
    pub output: SplatOutput,
    /// Splats with a normal extent below `flat_ratio · radius` are drawn as
    /// one quad instead of a box.
    pub flat_ratio: f32,
    /// Hits are kept within `radius · radius_tolerance` of their sample
    /// (slightly above 1 absorbs `f32` rounding at splat borders).
    pub radius_tolerance: f32,
    /// Surface-aligned boxes without their `−n` face (§6.1: "if we are only
    /// interested in the outer appearance, we can omit the box side in
    /// negative normal direction"): up to a third fewer fragments, from the
    /// splats facing away. Off by default: near a silhouette a splat whose
    /// sample normal faces slightly away from the eye can hold a visible
    /// hit whose ray enters the splat's box only through the `−n` face, so
    /// open boxes can miss silhouette pixels. `benches/splat.rs`
    /// compares both pixel for pixel: on an NVIDIA H100 at 1920×1080 open
    /// boxes left 1–2 silhouette pixels uncovered on three of the four
    /// scenes of `assets/scenes/` (none with lavapipe). Turn it on where a few
    /// missing silhouette pixels are acceptable; never with the camera or
    /// near plane inside a prop (open boxes leave out its inner surfaces).
    pub open_boxes: bool,
    /// Drop, in the vertex stage, every splat whose surface points all face
    /// away from the eye (a conservative bound from the quadric's gradient
    /// at the sample and how far its normal can turn over the splat's
    /// radius): they are hidden behind the front of the solid. Only where the whole
    /// prop (its bounding sphere) lies beyond the near plane, so with the
    /// eye or the near plane inside a prop every splat is still drawn. It
    /// assumes the prop is a closed solid inside its bounds, as sampling
    /// does. Shadow maps always draw every splat. On by default.
    pub cull_facing_away: bool,
}

impl Default for SplatSettings {
    fn default() -> Self {
        Self {
            mode: SplatMode::default(),
            output: SplatOutput::default(),
            flat_ratio: 1e-3,
            radius_tolerance: 1.001,
            open_boxes: false,
            cull_facing_away: true,
        }
    }
}

/// On a camera: the splat settings of that view, in place of the
/// [`SplatSettings`] resource (which the cameras without one keep using).
/// Every field applies per view — mode, output, flat ratio, radius
/// tolerance, open boxes, culling — and the pipeline is specialized per view, so
/// two cameras may draw the same props in different modes in one frame.
/// Removing the component returns the camera to the resource.
///
/// ```no_run
/// use bevy::prelude::*;
/// use bevy_chisel::splat::{SplatMode, SplatSettings, SplatViewSettings};
///
/// fn spawn_baseline_camera(mut commands: Commands) {
///     commands.spawn((
///         Camera3d::default(),
///         SplatViewSettings(SplatSettings {
///             mode: SplatMode::GlobalRayTrace,
///             ..default()
///         }),
///     ));
/// }
/// ```
#[derive(Component, Clone, Copy, Debug, PartialEq, ExtractComponent, Reflect)]
#[reflect(Component)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SplatViewSettings(pub SplatSettings);

/// The system sets of the main-world part, in order.
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub enum SplatSystems {
    /// Props whose component or scene changed are marked for re-sampling,
    /// and [`CarveProp`] messages are taken (send them before this set, or
    /// in an earlier schedule, to have them taken in the same frame).
    Request,
    /// Sampling tasks start and finished ones are swapped in
    /// ([`PropCarved`] and [`PropCarveRefused`] for a sampling's carves are
    /// sent here).
    Sample,
}

/// Quadric CSG props: the main-world component and sampling, and the
/// render-world splat pass. Needs Bevy's render and 3D core pipeline
/// plugins (`DefaultPlugins`).
pub struct ChiselSplatPlugin;

impl Plugin for ChiselSplatPlugin {
    fn build(&self, app: &mut App) {
        app.init_asset::<QuadricScene>()
            .init_asset_loader::<prop::QuadricSceneLoader>()
            .init_resource::<SplatSettings>()
            .register_type::<SplatSettings>()
            .register_type::<SplatViewSettings>()
            .register_type::<QuadricProp>()
            .register_type::<PropMaterial>()
            .register_type::<PropSplats>()
            .register_type::<prop::PropSampling>()
            .add_message::<CarveProp>()
            .add_message::<PropCarved>()
            .add_message::<PropCarveRefused>()
            .configure_sets(
                Update,
                (SplatSystems::Request, SplatSystems::Sample).chain(),
            )
            .add_systems(
                Update,
                (
                    (
                        prop::report_failed_edits,
                        prop::request_sampling,
                        prop_carve::apply_carves,
                    )
                        .chain()
                        .in_set(SplatSystems::Request),
                    (prop::start_sampling, prop::finish_sampling)
                        .chain()
                        .in_set(SplatSystems::Sample),
                    material::warn_on_unusable_materials,
                ),
            )
            .add_systems(
                PostUpdate,
                light_visibility::mark_props_seen_by_lights
                    .in_set(SimulationLightSystems::CheckLightVisibility)
                    .after(VisibilitySystems::CalculateBounds)
                    .after(SimulationLightSystems::UpdateLightFrusta)
                    .after(VisibilitySystems::CheckVisibility)
                    .before(VisibilitySystems::MarkNewlyHiddenEntitiesInvisible),
            )
            .add_plugins((
                ExtractResourcePlugin::<SplatSettings>::default(),
                ExtractComponentPlugin::<SplatViewSettings>::default(),
            ));
        pipeline::add_shaders(app);

        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<SpecializedRenderPipelines<pipeline::SplatPipeline>>()
            .init_resource::<render::ExtractedProps>()
            .init_resource::<render::PropBuffers>()
            .init_resource::<render::SplatViewUniforms>()
            .init_resource::<shadow::EmptyBindGroup>()
            // The render world's own type registry: its public data.
            .register_type::<render::ExtractedProps>()
            .register_type::<render::VisibleProps>()
            .register_type::<shadow::SplatShadowCasters>()
            .add_systems(
                ExtractSchedule,
                (render::extract_props, render::extract_visible_props),
            )
            .add_systems(
                RenderStartup,
                pipeline::init_splat_pipeline.after(MeshPipelineSystems),
            )
            .add_systems(
                Render,
                (
                    render::prepare_props,
                    (
                        render::prepare_views,
                        shadow::prepare_shadow_views,
                        render::write_view_uniforms,
                    )
                        .chain(),
                )
                    .in_set(RenderSystems::Prepare)
                    .run_if(resource_exists::<pipeline::SplatPipeline>),
            )
            .add_systems(
                Core3d,
                (
                    render::splat_pass
                        .after(main_opaque_pass_3d)
                        .before(main_transparent_pass_3d)
                        .in_set(Core3dSystems::MainPass),
                    shadow::per_view_splat_shadow_pass
                        .after(per_view_shadow_pass::<LATE_SHADOW_PASS>)
                        .before(Core3dSystems::MainPass),
                    shadow::shared_splat_shadow_pass
                        .after(shared_shadow_pass::<LATE_SHADOW_PASS>)
                        .before(Core3dSystems::MainPass),
                ),
            );
    }
}
