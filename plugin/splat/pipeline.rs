//! The render pipelines of the splat and global passes: bind group layouts
//! and specialization on the view (format, MSAA, and the mesh pipeline's
//! view key) and the pass settings.
//!
//! Bind groups: 0 and 1 are Bevy's mesh view bind groups (the view's
//! `MeshViewBindGroup`: view uniform, lights, shadow maps, clusters, light
//! probes), laid out as `MeshPipeline::get_view_layout` lays them out for
//! the view's key, so the fragment shader can call Bevy's PBR functions;
//! 2 is the splat pass's own view uniform; 3 is the prop.
//!
//! The shadow pipeline (`SplatShadowPipeline`) draws the same splats
//! depth-only into Bevy's shadow maps: groups 2 and 3 as above (group 2
//! holding the light's shadow view), 0 and 1 empty.

use std::sync::Arc;

use bevy::asset::uuid_handle;
use bevy::core_pipeline::core_3d::CORE_3D_DEPTH_FORMAT;
use bevy::mesh::{MeshVertexBufferLayout, MeshVertexBufferLayoutRef, VertexBufferLayout};
use bevy::pbr::{MeshPipeline, MeshPipelineKey};
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{storage_buffer_read_only, uniform_buffer};
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, BindGroupLayoutEntries, BlendComponent, BlendFactor, BlendOperation,
    BlendState, CachedRenderPipelineId, ColorTargetState, ColorWrites, CompareFunction,
    DepthBiasState, DepthStencilState, Face, FragmentState, MultisampleState, PipelineCache,
    PrimitiveState, RenderPipelineDescriptor, ShaderStages, SpecializedMeshPipeline,
    SpecializedRenderPipeline, TextureFormat, VertexFormat, VertexState, VertexStepMode,
};
use bevy::shader::{Shader, ShaderDefVal};

use super::gpu::{PropUniform, QuadricRecord, SplatRecord, SplatViewUniform};
use super::{SplatMode, SplatOutput};

/// The shared quadric module (`shaders/quadric_common.wgsl`).
pub const QUADRIC_COMMON_SHADER: Handle<Shader> =
    uuid_handle!("5f0c7c4e-2b8e-4d61-9a57-0d6f0f5a1c11");
/// The shading module (`shaders/splat_shading.wgsl`): Bevy's PBR lighting.
pub const SPLAT_SHADING_SHADER: Handle<Shader> =
    uuid_handle!("2d8f6a3b-91c4-4e7d-a0b5-6c3e8f1d2a44");
/// The splat pass (`shaders/splat.wgsl`).
pub const SPLAT_SHADER: Handle<Shader> = uuid_handle!("7a3e9b1d-46c2-4f0e-8d5b-2c9a6e4f7b22");
/// The global ray-tracing pass (`shaders/global.wgsl`).
pub const GLOBAL_SHADER: Handle<Shader> = uuid_handle!("9c4d2e6f-8a1b-4c3d-b5e7-f1a2b3c4d533");

/// Adds the four shaders to `Assets<Shader>` (compiled into the crate).
pub(crate) fn add_shaders(app: &mut App) {
    let Some(mut shaders) = app.world_mut().get_resource_mut::<Assets<Shader>>() else {
        warn!("bevy_chisel: no shader assets (is the RenderPlugin added?); splats are not drawn");
        return;
    };
    let sources = [
        (
            &QUADRIC_COMMON_SHADER,
            include_str!("../../shaders/quadric_common.wgsl"),
            "shaders/quadric_common.wgsl",
        ),
        (
            &SPLAT_SHADING_SHADER,
            include_str!("../../shaders/splat_shading.wgsl"),
            "shaders/splat_shading.wgsl",
        ),
        (
            &SPLAT_SHADER,
            include_str!("../../shaders/splat.wgsl"),
            "shaders/splat.wgsl",
        ),
        (
            &GLOBAL_SHADER,
            include_str!("../../shaders/global.wgsl"),
            "shaders/global.wgsl",
        ),
    ];
    for (handle, source, path) in sources {
        if let Err(e) = shaders.insert(handle.id(), Shader::from_wgsl(source, path)) {
            error!("bevy_chisel: cannot add shader {path}: {e}");
        }
    }
}

/// Bind group of the splat pass's view uniform.
pub(crate) const SPLAT_VIEW_GROUP: u32 = 2;
/// Bind group of the prop; Bevy's PBR library declares its (unused)
/// material bindings at `MATERIAL_BIND_GROUP`, set to the same group, as the
/// material pipeline does.
pub(crate) const PROP_GROUP: u32 = 3;

/// Layouts and shaders of the splat and global pipelines.
#[derive(Resource)]
pub(crate) struct SplatPipeline {
    /// Group 2: the splat view uniform (dynamic offset).
    pub view_layout: BindGroupLayoutDescriptor,
    /// Group 3: the prop uniform and its four storage buffers.
    pub prop_layout: BindGroupLayoutDescriptor,
    /// Bevy's mesh pipeline: its view layouts (groups 0 and 1) and the
    /// shader defines it sets for a view.
    mesh_pipeline: MeshPipeline,
    /// Positions and normals: the vertex layout under which the mesh
    /// pipeline is asked for its defines.
    mesh_vertex_layout: MeshVertexBufferLayoutRef,
}

impl SplatPipeline {
    fn new(mesh_pipeline: MeshPipeline) -> Self {
        let mesh_vertex_layout = MeshVertexBufferLayoutRef(Arc::new(MeshVertexBufferLayout::new(
            vec![Mesh::ATTRIBUTE_POSITION.id, Mesh::ATTRIBUTE_NORMAL.id],
            VertexBufferLayout::from_vertex_formats(
                VertexStepMode::Vertex,
                [VertexFormat::Float32x3, VertexFormat::Float32x3],
            ),
        )));
        Self {
            view_layout: BindGroupLayoutDescriptor::new(
                "chisel_splat_view_layout",
                &BindGroupLayoutEntries::single(
                    ShaderStages::VERTEX_FRAGMENT,
                    uniform_buffer::<SplatViewUniform>(true),
                ),
            ),
            prop_layout: BindGroupLayoutDescriptor::new(
                "chisel_splat_prop_layout",
                &BindGroupLayoutEntries::sequential(
                    ShaderStages::VERTEX_FRAGMENT,
                    (
                        uniform_buffer::<PropUniform>(false),
                        storage_buffer_read_only::<QuadricRecord>(false),
                        storage_buffer_read_only::<u32>(false),
                        storage_buffer_read_only::<SplatRecord>(false),
                        storage_buffer_read_only::<u32>(false),
                    ),
                ),
            ),
            mesh_pipeline,
            mesh_vertex_layout,
        }
    }

    /// The mesh view layouts (groups 0 and 1) and the shader defines of
    /// Bevy's mesh pipeline for an opaque mesh with positions and normals
    /// in a view of key `view_key`: exactly what its PBR functions need.
    fn mesh_view_layouts_and_defs(
        &self,
        view_key: MeshPipelineKey,
    ) -> (Vec<BindGroupLayoutDescriptor>, Vec<ShaderDefVal>) {
        match self
            .mesh_pipeline
            .specialize(view_key, &self.mesh_vertex_layout)
        {
            Ok(mut mesh) => {
                mesh.layout.truncate(2);
                let defs = mesh.fragment.map(|f| f.shader_defs).unwrap_or_default();
                (mesh.layout, defs)
            }
            Err(e) => {
                // Not expected for positions and normals; the shader then
                // fails to compile and the pipeline cache reports it.
                error!("bevy_chisel: no mesh pipeline defines for the splat pass: {e}");
                let layout = self.mesh_pipeline.get_view_layout(view_key.into());
                (
                    vec![layout.main_layout, layout.binding_array_layout],
                    Vec::new(),
                )
            }
        }
    }
}

/// The depth-only pipeline of the splats in Bevy's shadow maps: surface
/// boxes (whatever the views' [`SplatMode`]: every mode gives the same
/// pixels), back faces culled as seen from the light, the fragment stage
/// ray tracing and clipping as the main pass does and writing the hit's
/// depth, compared and stored as Bevy's shadow passes do (reverse-Z,
/// `GreaterEqual`, no bias: Bevy applies the light's biases where shadows
/// are received).
#[derive(Resource)]
pub(crate) struct SplatShadowPipeline {
    /// The queued pipeline.
    pub id: CachedRenderPipelineId,
    /// Groups 0 and 1: empty.
    pub empty_layout: BindGroupLayoutDescriptor,
}

impl SplatShadowPipeline {
    fn descriptor(
        splat: &SplatPipeline,
        empty_layout: &BindGroupLayoutDescriptor,
    ) -> RenderPipelineDescriptor {
        let defs: Vec<ShaderDefVal> = vec!["SHADOW_DEPTH".into()];
        RenderPipelineDescriptor {
            label: Some("chisel_splat_shadow_pipeline".into()),
            layout: vec![
                empty_layout.clone(),
                empty_layout.clone(),
                splat.view_layout.clone(),
                splat.prop_layout.clone(),
            ],
            vertex: VertexState {
                shader: SPLAT_SHADER,
                shader_defs: defs.clone(),
                ..default()
            },
            primitive: PrimitiveState {
                cull_mode: Some(Face::Back),
                ..default()
            },
            depth_stencil: Some(DepthStencilState {
                format: CORE_3D_DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(CompareFunction::GreaterEqual),
                stencil: default(),
                bias: default(),
            }),
            multisample: MultisampleState::default(),
            fragment: Some(FragmentState {
                shader: SPLAT_SHADER,
                shader_defs: defs,
                targets: Vec::new(),
                ..default()
            }),
            ..default()
        }
    }
}

/// Creates the [`SplatPipeline`] once Bevy's mesh pipeline exists, and
/// queues the [`SplatShadowPipeline`].
pub(crate) fn init_splat_pipeline(
    mut commands: Commands,
    mesh_pipeline: Res<MeshPipeline>,
    pipeline_cache: Res<PipelineCache>,
) {
    let splat = SplatPipeline::new(mesh_pipeline.clone());
    let empty_layout = BindGroupLayoutDescriptor::new("chisel_splat_empty_layout", &[]);
    let id = pipeline_cache
        .queue_render_pipeline(SplatShadowPipeline::descriptor(&splat, &empty_layout));
    commands.insert_resource(SplatShadowPipeline { id, empty_layout });
    commands.insert_resource(splat);
}

/// Depth bias of the counting pass of [`SplatOutput::DepthTestedOverdraw`]
/// towards the eye (reverse-Z: positive), in units of depth rounding...
const COUNT_DEPTH_BIAS: i32 = 64;
/// ... and per unit of depth slope.
const COUNT_SLOPE_BIAS: f32 = 2.0;

/// What a pipeline variant depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SplatPipelineKey {
    /// The view's colour format.
    pub format: TextureFormat,
    /// MSAA sample count.
    pub samples: u32,
    /// Splat boxes, screen quads or global ray tracing.
    pub mode: SplatMode,
    /// Shaded, ids, normals or overdraw.
    pub output: SplatOutput,
    /// The device supports `@early_depth_test`.
    pub early_depth_test: bool,
    /// Surface-aligned boxes without their `−n` face.
    pub open_boxes: bool,
    /// Splats facing away from the eye are dropped in the vertex stage
    /// ([`SplatSettings::cull_facing_away`](super::SplatSettings)).
    pub cull_facing_away: bool,
    /// Depth only: the colour target is left unwritten (the prepass of
    /// [`SplatOutput::DepthTestedOverdraw`]).
    pub depth_only: bool,
    /// Bevy's mesh pipeline key of the view (MSAA, prepasses, tonemapping,
    /// fog, shadow filtering, projection…): the layout of its mesh view
    /// bind groups and the defines of its PBR shading.
    pub view_key: MeshPipelineKey,
}

impl SplatPipelineKey {
    /// Vertices per instance.
    #[must_use]
    pub fn vertex_count(&self) -> u32 {
        match self.mode {
            SplatMode::ScreenQuads => 6,
            SplatMode::SurfaceBoxes if self.open_boxes => 30,
            SplatMode::SurfaceBoxes | SplatMode::GlobalRayTrace => 36,
        }
    }
}

impl SpecializedRenderPipeline for SplatPipeline {
    type Key = SplatPipelineKey;

    fn specialize(&self, key: Self::Key) -> RenderPipelineDescriptor {
        let (mut layout, mut defs) = self.mesh_view_layouts_and_defs(key.view_key);
        defs.push(ShaderDefVal::UInt("MATERIAL_BIND_GROUP".into(), PROP_GROUP));
        layout.push(self.view_layout.clone());
        layout.push(self.prop_layout.clone());
        match key.output {
            SplatOutput::Shaded => {}
            SplatOutput::QuadricIds => defs.push("OUTPUT_IDS".into()),
            SplatOutput::Normals => defs.push("OUTPUT_NORMALS".into()),
            SplatOutput::Overdraw | SplatOutput::DepthTestedOverdraw => {
                defs.push("OUTPUT_OVERDRAW".into());
            }
            SplatOutput::Bounds => defs.push("OUTPUT_BOUNDS".into()),
        }
        // A surface output on a multisampled target traces the ray of every
        // covered sample (`shaders/splat.wgsl`): at 4 samples once per
        // pixel, shaded once (SAMPLE_RAYS), else once per sample
        // (PER_SAMPLE); the proxies and the overdraw counts stay per pixel.
        let surface = matches!(
            key.output,
            SplatOutput::Shaded | SplatOutput::QuadricIds | SplatOutput::Normals
        );
        if key.samples > 1 && surface && key.mode != SplatMode::GlobalRayTrace {
            defs.push(if key.samples == 4 {
                "SAMPLE_RAYS".into()
            } else {
                "PER_SAMPLE".into()
            });
        }
        let (shader, cull_mode) = match key.mode {
            SplatMode::SurfaceBoxes => {
                if key.open_boxes {
                    defs.push("SPLAT_OPEN_BOX".into());
                }
                (SPLAT_SHADER, Some(Face::Back))
            }
            SplatMode::ScreenQuads => {
                defs.push("SPLAT_SCREEN_QUAD".into());
                (SPLAT_SHADER, None)
            }
            // Back faces of the proxy cube: one fragment per pixel, eye inside or not.
            SplatMode::GlobalRayTrace => (GLOBAL_SHADER, Some(Face::Front)),
        };
        if key.cull_facing_away && key.mode != SplatMode::GlobalRayTrace {
            defs.push("CULL_FACING_AWAY".into());
        }
        if key.early_depth_test && key.mode != SplatMode::GlobalRayTrace {
            defs.push("EARLY_DEPTH_TEST".into());
        }
        let overdraw = matches!(
            key.output,
            SplatOutput::Overdraw | SplatOutput::DepthTestedOverdraw
        );
        // Counting at the proxies' rasterized depth against the prepass's.
        let depth_tested = key.output == SplatOutput::DepthTestedOverdraw;
        let additive = BlendComponent {
            src_factor: BlendFactor::One,
            dst_factor: BlendFactor::One,
            operation: BlendOperation::Add,
        };
        RenderPipelineDescriptor {
            label: Some("chisel_splat_pipeline".into()),
            layout,
            vertex: VertexState {
                shader: shader.clone(),
                shader_defs: defs.clone(),
                ..default()
            },
            primitive: PrimitiveState {
                cull_mode,
                ..default()
            },
            depth_stencil: Some(DepthStencilState {
                format: CORE_3D_DEPTH_FORMAT,
                depth_write_enabled: Some(!overdraw),
                depth_compare: Some(if overdraw && !depth_tested {
                    CompareFunction::Always
                } else {
                    CompareFunction::GreaterEqual
                }),
                stencil: default(),
                // A flat splat's quad lies on its surface (a plane's has no
                // lift): moved towards the eye by a few units of depth
                // rounding, it is counted where the prepass drew it.
                bias: if depth_tested {
                    DepthBiasState {
                        constant: COUNT_DEPTH_BIAS,
                        slope_scale: COUNT_SLOPE_BIAS,
                        clamp: 0.0,
                    }
                } else {
                    DepthBiasState::default()
                },
            }),
            multisample: MultisampleState {
                count: key.samples,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(FragmentState {
                shader,
                shader_defs: defs,
                targets: vec![Some(ColorTargetState {
                    format: key.format,
                    blend: overdraw.then_some(BlendState {
                        color: additive,
                        alpha: additive,
                    }),
                    write_mask: if key.depth_only {
                        ColorWrites::empty()
                    } else {
                        ColorWrites::ALL
                    },
                })],
                ..default()
            }),
            ..default()
        }
    }
}
