//! The render world of the splat pass: extraction, buffer upload, bind
//! groups, and the pass itself — a `Core3d` system after the opaque pass
//! (Bevy 0.19 has no render-graph nodes: this system is the node).
//!
//! Per prop: a quadric buffer, a clip-index buffer, an instance buffer (one
//! record per splat) and the normal form for the global pass, uploaded when
//! the prop's splats change; a uniform with its transform, every frame. Per
//! view: a uniform (view-projection, eye, settings) at a dynamic offset and
//! the pipeline specialized for the view's settings (its camera's
//! [`SplatViewSettings`], else the [`SplatSettings`] resource) and for
//! Bevy's mesh pipeline key of the view. The pass binds the view's Bevy
//! mesh view bind groups (lights, shadow maps, exposure: the fragment
//! shader lights with Bevy's PBR functions) and draws each prop with one
//! instanced draw.

use std::any::TypeId;
use std::collections::HashMap;
use std::sync::Arc;

use bevy::camera::primitives::Aabb;
use bevy::camera::visibility::{RenderLayers, VisibleEntities};
use bevy::light::NotShadowCaster;
use bevy::math::{DMat3, Mat3};
use bevy::pbr::{MeshPipelineKey, MeshViewBindGroup, ViewKeyCache};
use bevy::prelude::*;
use bevy::render::Extract;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, CachedRenderPipelineId, DynamicUniformBuffer, PipelineCache,
    RenderPassDescriptor, SpecializedRenderPipelines, StorageBuffer, StoreOp, UniformBuffer,
    WgpuFeatures,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::sync_world::RenderEntity;
use bevy::render::view::{ExtractedView, Msaa, ViewDepthTexture, ViewTarget};

use super::gpu::{PropUniform, QuadricRecord, SplatRecord, SplatViewUniform};
use super::material::PropMaterial;
use super::pipeline::{PROP_GROUP, SPLAT_VIEW_GROUP, SplatPipeline, SplatPipelineKey};
use super::prop::{PropGpuData, PropSplats};
use super::{SplatMode, SplatOutput, SplatSettings, SplatViewSettings};

/// One prop as seen by the render world this frame.
#[derive(Reflect, Clone, Debug)]
pub struct ExtractedProp {
    /// The main-world entity.
    pub entity: Entity,
    /// Its splats.
    #[reflect(ignore)]
    pub data: Arc<PropGpuData>,
    /// Its local-to-world transform (invertible: props with a singular
    /// transform are not extracted).
    pub world_from_local: Mat4,
    /// Its PBR material (validated; the default where it has none or an
    /// invalid one).
    pub material: PropMaterial,
    /// Its local box around every splat proxy (the prop's `Aabb`).
    #[reflect(ignore)]
    pub aabb: Aabb,
    /// It casts shadows (it has no `NotShadowCaster`).
    pub casts_shadows: bool,
    /// Its render layers (the default layer where it has none).
    #[reflect(ignore)]
    pub render_layers: RenderLayers,
}

/// The props to draw this frame: those a camera sees, and those in the
/// shadow frusta of a light that casts shadows (their `ViewVisibility`,
/// Bevy's and `mark_props_seen_by_lights`'s).
#[derive(Resource, Reflect, Default, Debug)]
#[reflect(Resource, Default)]
pub struct ExtractedProps(pub Vec<ExtractedProp>);

/// On a view: the main-world props inside its frustum this frame (Bevy's
/// visibility check with each prop's `Aabb`, class [`PropSplats`]). The
/// splat pass draws only these.
#[derive(Component, Reflect, Default, Debug, Clone)]
#[reflect(Component, Default)]
pub struct VisibleProps(pub Vec<Entity>);

pub(crate) fn extract_visible_props(
    mut commands: Commands,
    cameras: Extract<Query<(RenderEntity, &VisibleEntities), With<Camera>>>,
) {
    for (entity, visible) in &cameras {
        let mut props: Vec<Entity> = visible.iter(TypeId::of::<PropSplats>()).copied().collect();
        props.sort_unstable();
        commands.entity(entity).insert(VisibleProps(props));
    }
}

pub(crate) fn extract_props(
    mut extracted: ResMut<ExtractedProps>,
    props: Extract<
        Query<(
            Entity,
            &PropSplats,
            &GlobalTransform,
            &ViewVisibility,
            Option<&PropMaterial>,
            Option<&Aabb>,
            Has<NotShadowCaster>,
            Option<&RenderLayers>,
        )>,
    >,
) {
    extracted.0.clear();
    for (entity, splats, transform, visibility, material, aabb, not_caster, layers) in &props {
        // A transform without an inverse (a zero scale) has no local rays
        // to trace: the prop is flat or a point, and is not drawn.
        let det = transform.affine().matrix3.determinant();
        if visibility.get() && !splats.0.splats.is_empty() && det.is_finite() && det != 0.0 {
            extracted.0.push(ExtractedProp {
                entity,
                data: splats.0.clone(),
                world_from_local: transform.to_matrix(),
                material: material
                    .and_then(PropMaterial::validated)
                    .unwrap_or_default(),
                // Inserted with the splats, by command: the bounding
                // sphere's box until then.
                aabb: aabb.copied().unwrap_or_else(|| {
                    let c = splats.0.bounds.truncate();
                    let r = Vec3::splat(splats.0.bounds.w.abs());
                    Aabb::from_min_max(c - r, c + r)
                }),
                casts_shadows: !not_caster,
                render_layers: layers.cloned().unwrap_or_default(),
            });
        }
    }
}

/// GPU buffers of one prop.
pub(crate) struct PropGpu {
    generation: u64,
    quadrics: StorageBuffer<Vec<QuadricRecord>>,
    clip_indices: StorageBuffer<Vec<u32>>,
    splats: StorageBuffer<Vec<SplatRecord>>,
    terms: StorageBuffer<Vec<u32>>,
    uniform: UniformBuffer<PropUniform>,
    pub(crate) bind_group: Option<BindGroup>,
    pub(crate) splat_count: u32,
}

/// GPU buffers of all props, by main-world entity.
#[derive(Resource, Default)]
pub(crate) struct PropBuffers(HashMap<Entity, PropGpu>);

impl PropBuffers {
    /// The buffers of the prop `entity` (main world).
    pub(crate) fn get(&self, entity: &Entity) -> Option<&PropGpu> {
        self.0.get(entity)
    }
}

fn non_empty<T: Copy + Default>(v: &[T]) -> Vec<T> {
    if v.is_empty() {
        vec![T::default()]
    } else {
        v.to_vec()
    }
}

/// The largest singular value of `m`: the most it stretches a vector,
/// so a sphere of radius `r` maps into one of radius `r · stretch(m)`
/// whatever the shear or non-uniform scale (the largest column length falls
/// short of it under shear).
fn largest_stretch(m: Mat3) -> f32 {
    let m = DMat3::from_cols(
        m.x_axis.as_dvec3(),
        m.y_axis.as_dvec3(),
        m.z_axis.as_dvec3(),
    );
    let gram = chisel_quadric::SymmetricEigen::new(m.transpose() * m);
    gram.max_value().max(0.0).sqrt() as f32
}

fn prop_uniform(prop: &ExtractedProp) -> PropUniform {
    let m = prop.world_from_local;
    let linear = Mat3::from_mat4(m);
    let normal = Mat4::from_mat3(linear.inverse().transpose());
    PropUniform {
        world_from_local: m,
        local_from_world: m.inverse(),
        normal_from_local: normal,
        bounds: prop.data.bounds,
        product_count: prop.data.product_count,
        max_scale: largest_stretch(linear),
        mirror_sign: if linear.determinant() < 0.0 {
            -1.0
        } else {
            1.0
        },
        metallic: prop.material.metallic,
        perceptual_roughness: prop.material.perceptual_roughness,
        reflectance: prop.material.reflectance,
        pad: UVec2::ZERO,
    }
}

pub(crate) fn prepare_props(
    mut buffers: ResMut<PropBuffers>,
    props: Res<ExtractedProps>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    pipeline: Res<SplatPipeline>,
    pipeline_cache: Res<PipelineCache>,
) {
    buffers
        .0
        .retain(|entity, _| props.0.iter().any(|p| p.entity == *entity));
    let layout = pipeline_cache.get_bind_group_layout(&pipeline.prop_layout);
    for prop in &props.0 {
        let data = &prop.data;
        let stale = buffers
            .0
            .get(&prop.entity)
            .is_none_or(|b| b.generation != data.generation);
        if stale {
            let mut gpu = PropGpu {
                generation: data.generation,
                quadrics: StorageBuffer::from(non_empty(&data.quadrics)),
                clip_indices: StorageBuffer::from(non_empty(&data.clip_indices)),
                splats: StorageBuffer::from(non_empty(&data.splats)),
                terms: StorageBuffer::from(non_empty(&data.terms)),
                uniform: UniformBuffer::default(),
                bind_group: None,
                splat_count: u32::try_from(data.splats.len()).unwrap_or(u32::MAX),
            };
            gpu.quadrics.write_buffer(&device, &queue);
            gpu.clip_indices.write_buffer(&device, &queue);
            gpu.splats.write_buffer(&device, &queue);
            gpu.terms.write_buffer(&device, &queue);
            buffers.0.insert(prop.entity, gpu);
        }
        let Some(gpu) = buffers.0.get_mut(&prop.entity) else {
            continue;
        };
        gpu.uniform.set(prop_uniform(prop));
        gpu.uniform.write_buffer(&device, &queue);
        if gpu.bind_group.is_none()
            && let (Some(uniform), Some(quadrics), Some(clips), Some(splats), Some(terms)) = (
                gpu.uniform.binding(),
                gpu.quadrics.binding(),
                gpu.clip_indices.binding(),
                gpu.splats.binding(),
                gpu.terms.binding(),
            )
        {
            let bind_group = device.create_bind_group(
                "chisel_splat_prop_bind_group",
                &layout,
                &BindGroupEntries::sequential((uniform, quadrics, clips, splats, terms)),
            );
            gpu.bind_group = Some(bind_group);
        }
    }
}

/// The per-view uniforms of all views: cameras, then shadow views.
#[derive(Resource, Default)]
pub(crate) struct SplatViewUniforms {
    pub(crate) buffer: DynamicUniformBuffer<SplatViewUniform>,
    pub(crate) bind_group: Option<BindGroup>,
}

/// What the pass needs per view.
#[derive(Component)]
pub(crate) struct SplatViewState {
    offset: u32,
    pipeline: CachedRenderPipelineId,
    /// The depth prepass drawn first ([`SplatOutput::DepthTestedOverdraw`]).
    prepass: Option<CachedRenderPipelineId>,
    vertex_count: u32,
    global: bool,
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare_views(
    mut commands: Commands,
    mut uniforms: ResMut<SplatViewUniforms>,
    views: Query<(Entity, &ExtractedView, &Msaa, Option<&SplatViewSettings>)>,
    view_keys: Res<ViewKeyCache>,
    settings: Res<SplatSettings>,
    device: Res<RenderDevice>,
    pipeline: Res<SplatPipeline>,
    pipeline_cache: Res<PipelineCache>,
    mut pipelines: ResMut<SpecializedRenderPipelines<SplatPipeline>>,
) {
    uniforms.buffer.clear();
    let early_depth_test = device
        .features()
        .contains(WgpuFeatures::SHADER_EARLY_DEPTH_TEST);
    for (entity, view, msaa, view_settings) in &views {
        let settings = view_settings.map_or(*settings, |s| s.0);
        let offset = uniforms
            .buffer
            .push(&SplatViewUniform::new(view, &settings));
        let key = SplatPipelineKey {
            format: view.target_format,
            samples: msaa.samples(),
            mode: settings.mode,
            output: settings.output,
            early_depth_test,
            open_boxes: settings.open_boxes,
            cull_facing_away: settings.cull_facing_away,
            depth_only: false,
            // Bevy fills the cache for every view before this system runs
            // (`RenderSystems::PrepareAssets`); the fallback is its key for
            // a plain view.
            view_key: view_keys
                .get(&view.retained_view_entity)
                .copied()
                .unwrap_or_else(|| {
                    MeshPipelineKey::from_msaa_samples(msaa.samples())
                        | MeshPipelineKey::from_target_format(view.target_format)
                }),
        };
        let id = pipelines.specialize(&pipeline_cache, &pipeline, key);
        let prepass = (key.output == SplatOutput::DepthTestedOverdraw
            && key.mode != SplatMode::GlobalRayTrace)
            .then(|| {
                let depth_only = SplatPipelineKey {
                    output: SplatOutput::QuadricIds,
                    depth_only: true,
                    ..key
                };
                pipelines.specialize(&pipeline_cache, &pipeline, depth_only)
            });
        commands.entity(entity).insert(SplatViewState {
            offset,
            pipeline: id,
            prepass,
            vertex_count: key.vertex_count(),
            global: settings.mode == SplatMode::GlobalRayTrace,
        });
    }
}

/// Uploads the view uniforms of the cameras and the shadow views (after
/// [`prepare_views`] and [`prepare_shadow_views`](super::shadow::prepare_shadow_views)
/// pushed them) and binds the buffer.
pub(crate) fn write_view_uniforms(
    mut uniforms: ResMut<SplatViewUniforms>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    pipeline: Res<SplatPipeline>,
    pipeline_cache: Res<PipelineCache>,
) {
    uniforms.buffer.write_buffer(&device, &queue);
    let layout = pipeline_cache.get_bind_group_layout(&pipeline.view_layout);
    uniforms.bind_group = uniforms.buffer.binding().map(|binding| {
        device.create_bind_group(
            "chisel_splat_view_bind_group",
            &layout,
            &BindGroupEntries::single(binding),
        )
    });
}

/// The splat pass of one view: every prop, one instanced draw each (one
/// proxy cube each in global ray-tracing mode).
pub(crate) fn splat_pass(
    view: ViewQuery<(
        &ExtractedCamera,
        &ViewTarget,
        &ViewDepthTexture,
        &SplatViewState,
        &MeshViewBindGroup,
        Option<&VisibleProps>,
    )>,
    props: Res<ExtractedProps>,
    buffers: Res<PropBuffers>,
    uniforms: Res<SplatViewUniforms>,
    pipeline_cache: Res<PipelineCache>,
    mut ctx: RenderContext,
) {
    let (camera, target, depth, state, mesh_view, visible) = view.into_inner();

    if props.0.is_empty() {
        return;
    }
    let (Some(pipeline), Some(view_bind_group)) = (
        pipeline_cache.get_render_pipeline(state.pipeline),
        uniforms.bind_group.as_ref(),
    ) else {
        return;
    };
    let prepass = match state.prepass {
        Some(id) => match pipeline_cache.get_render_pipeline(id) {
            Some(prepass) => Some(prepass),
            None => return,
        },
        None => None,
    };
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let mut pass = ctx.begin_tracked_render_pass(RenderPassDescriptor {
        label: Some("chisel_splat_pass"),
        color_attachments: &[Some(target.get_color_attachment())],
        depth_stencil_attachment: Some(depth.get_attachment(StoreOp::Store)),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let span = diagnostics.pass_span(&mut pass, "chisel_splat_pass");
    if let Some(viewport) = camera.viewport.as_ref() {
        pass.set_camera_viewport(viewport);
    }
    // The prepass (if any) writes the splats' depth; the pass proper then
    // draws against it.
    for pipeline in prepass.into_iter().chain([pipeline]) {
        pass.set_render_pipeline(pipeline);
        pass.set_bind_group(0, &mesh_view.main, &mesh_view.main_offsets);
        pass.set_bind_group(1, &mesh_view.binding_array, &[]);
        pass.set_bind_group(SPLAT_VIEW_GROUP as usize, view_bind_group, &[state.offset]);
        for prop in &props.0 {
            if visible.is_some_and(|v| v.0.binary_search(&prop.entity).is_err()) {
                continue;
            }
            let Some(gpu) = buffers.0.get(&prop.entity) else {
                continue;
            };
            let Some(bind_group) = gpu.bind_group.as_ref() else {
                continue;
            };
            pass.set_bind_group(PROP_GROUP as usize, bind_group, &[]);
            let instances = if state.global { 1 } else { gpu.splat_count };
            pass.draw(0..state.vertex_count, 0..instances);
        }
    }
    span.end(&mut pass);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn largest_stretch_is_the_largest_singular_value() {
        let rotation = Quat::from_euler(EulerRot::XYZ, 0.3, -1.1, 0.7);
        let scaled = Mat3::from_quat(rotation) * Mat3::from_diagonal(Vec3::new(2.0, -3.0, 0.5));
        assert!((largest_stretch(scaled) - 3.0).abs() < 1e-5);
        // A shear stretches (1, 1, 0)/√2 by more than any column's length:
        // the largest singular value of [[1, 1], [0, 1]] is the golden ratio.
        let shear = Mat3::from_cols(Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Z);
        let golden = (1.0 + 5.0_f32.sqrt()) / 2.0;
        assert!((largest_stretch(shear) - golden).abs() < 1e-5);
        assert!(largest_stretch(shear) > shear.y_axis.length());
    }
}
