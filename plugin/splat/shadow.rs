//! Render world: props cast shadows. Their splats are drawn depth-only into
//! Bevy's shadow maps, ray traced and clipped per fragment exactly as the
//! main pass does, so a shadow has the prop's true silhouette.
//!
//! Bevy 0.19 renders shadow maps in the `Core3d` schedule: the directional
//! cascades of a camera in `per_view_shadow_pass` (one shadow view per
//! cascade, listed in the camera's `ViewLightEntities`), point-light faces
//! and spot lights in `shared_shadow_pass`, run once per shadow view (a
//! root view of its own). Each shadow view holds a `ShadowView` whose
//! depth attachment clears on its first use in a frame and loads after.
//! The splat shadow passes are two systems beside those, ordered after
//! Bevy's (early and late) ones and before the main pass: they open a
//! render pass on the same attachment (loading what Bevy's meshes wrote)
//! and draw every prop that casts a shadow into that view, one instanced
//! draw each, with `SplatShadowPipeline`.
//!
//! Per shadow view, `prepare_shadow_views` pushes the light's view into
//! the splat view uniforms (its projection, and the light's position, or
//! its direction for a directional cascade) and picks the props to draw:
//! those without `NotShadowCaster` whose box meets the view's frustum and
//! whose render layers the light shares, as Bevy picks meshes.

use bevy::camera::primitives::Frustum;
use bevy::camera::visibility::RenderLayers;
use bevy::math::Affine3A;
use bevy::pbr::{ShadowView, ViewLightEntities};
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{BindGroup, PipelineCache, RenderPassDescriptor, StoreOp};
use bevy::render::renderer::{RenderContext, RenderDevice, ViewQuery};
use bevy::render::view::ExtractedView;

use super::SplatSettings;
use super::gpu::SplatViewUniform;
use super::pipeline::{PROP_GROUP, SPLAT_VIEW_GROUP, SplatShadowPipeline};
use super::render::{ExtractedProps, PropBuffers, SplatViewUniforms};

/// Vertices of one surface box.
const BOX_VERTICES: u32 = 36;

/// On a light's shadow view: where its splat view uniform is and which
/// props cast a shadow into it this frame.
#[derive(Component, Reflect, Debug, Clone, Default)]
#[reflect(Component, Default)]
pub struct SplatShadowCasters {
    /// Dynamic offset of the view's [`SplatViewUniform`].
    pub offset: u32,
    /// The main-world props drawn into this shadow map.
    pub props: Vec<Entity>,
}

/// The empty bind group bound at groups 0 and 1 of the shadow pipeline.
#[derive(Resource, Default)]
pub(crate) struct EmptyBindGroup(Option<BindGroup>);

/// Pushes every shadow view's uniform (after the cameras' and before
/// [`write_view_uniforms`](super::render::write_view_uniforms)) and picks
/// the props that cast a shadow into it.
pub(crate) fn prepare_shadow_views(
    mut commands: Commands,
    mut uniforms: ResMut<SplatViewUniforms>,
    views: Query<(Entity, &ExtractedView, &Frustum, Option<&RenderLayers>), With<ShadowView>>,
    props: Res<ExtractedProps>,
    settings: Res<SplatSettings>,
    device: Res<RenderDevice>,
    pipeline: Res<SplatShadowPipeline>,
    pipeline_cache: Res<PipelineCache>,
    mut empty: ResMut<EmptyBindGroup>,
) {
    if empty.0.is_none() {
        let layout = pipeline_cache.get_bind_group_layout(&pipeline.empty_layout);
        empty.0 = Some(device.create_bind_group("chisel_splat_empty_bind_group", &layout, &[]));
    }
    let default_layers = RenderLayers::default();
    for (entity, view, frustum, layers) in &views {
        let uniform = SplatViewUniform::new(view, &settings);
        // A directional cascade's frustum has its near plane at infinity:
        // casters between the light and the cascade count (as for meshes).
        let test_near = !uniform.is_orthographic();
        let layers = layers.unwrap_or(&default_layers);
        let casters: Vec<Entity> = props
            .0
            .iter()
            .filter(|p| {
                p.casts_shadows
                    && p.render_layers.intersects(layers)
                    && frustum.intersects_obb(
                        &p.aabb,
                        &Affine3A::from_mat4(p.world_from_local),
                        test_near,
                        true,
                    )
            })
            .map(|p| p.entity)
            .collect();
        if casters.is_empty() {
            commands.entity(entity).remove::<SplatShadowCasters>();
            continue;
        }
        let offset = uniforms.buffer.push(&uniform);
        commands.entity(entity).insert(SplatShadowCasters {
            offset,
            props: casters,
        });
    }
}

/// The directional cascades of the current camera.
pub(crate) fn per_view_splat_shadow_pass(
    view: ViewQuery<&ViewLightEntities>,
    shadow_views: Query<(&ShadowView, &SplatShadowCasters)>,
    resources: ShadowPassResources,
    mut ctx: RenderContext,
) {
    for light_view in view.into_inner().lights.iter().copied() {
        if let Ok((shadow_view, casters)) = shadow_views.get(light_view) {
            draw_shadow_view(shadow_view, casters, &resources, &mut ctx);
        }
    }
}

/// The current point-light face or spot light (a root view of its own).
pub(crate) fn shared_splat_shadow_pass(
    view: ViewQuery<(&ShadowView, &SplatShadowCasters)>,
    resources: ShadowPassResources,
    mut ctx: RenderContext,
) {
    let (shadow_view, casters) = view.into_inner();
    draw_shadow_view(shadow_view, casters, &resources, &mut ctx);
}

/// What the shadow passes read.
#[derive(bevy::ecs::system::SystemParam)]
pub(crate) struct ShadowPassResources<'w> {
    buffers: Res<'w, PropBuffers>,
    uniforms: Res<'w, SplatViewUniforms>,
    pipeline: Res<'w, SplatShadowPipeline>,
    pipeline_cache: Res<'w, PipelineCache>,
    empty: Res<'w, EmptyBindGroup>,
}

/// Draws `casters` into the shadow map of `shadow_view`, loading its depth.
fn draw_shadow_view(
    shadow_view: &ShadowView,
    casters: &SplatShadowCasters,
    resources: &ShadowPassResources,
    ctx: &mut RenderContext,
) {
    let (Some(pipeline), Some(view_bind_group), Some(empty)) = (
        resources
            .pipeline_cache
            .get_render_pipeline(resources.pipeline.id),
        resources.uniforms.bind_group.as_ref(),
        resources.empty.0.as_ref(),
    ) else {
        return;
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("chisel_splat_shadow_pass"),
        color_attachments: &[],
        depth_stencil_attachment: Some(shadow_view.depth_attachment.get_attachment(StoreOp::Store)),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let span = diagnostics.pass_span(&mut pass, "chisel_splat_shadow_pass");
    pass.set_render_pipeline(pipeline);
    pass.set_bind_group(0, empty, &[]);
    pass.set_bind_group(1, empty, &[]);
    pass.set_bind_group(
        SPLAT_VIEW_GROUP as usize,
        view_bind_group,
        &[casters.offset],
    );
    for entity in &casters.props {
        let Some(gpu) = resources.buffers.get(entity) else {
            continue;
        };
        let Some(bind_group) = gpu.bind_group.as_ref() else {
            continue;
        };
        pass.set_bind_group(PROP_GROUP as usize, bind_group, &[]);
        pass.draw(0..BOX_VERTICES, 0..gpu.splat_count);
    }
    span.end(&mut pass);
}
