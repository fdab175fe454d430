// Shading of the splat and global passes: a ray-traced surface point lit by
// Bevy's PBR functions exactly as a `StandardMaterial` mesh fragment is —
// every light of the view (directional, point, spot, ambient, light
// probes), received shadows from the view's shadow maps, the camera's
// exposure, then fog, tonemapping and debanding where the view asks for
// them. The view's bindings are Bevy's mesh view bind groups (groups 0 and
// 1), bound by the pass; the pipeline carries the mesh pipeline's shader
// defines for that view.
//
// The material: base colour from the quadric (linear RGB), metallic and
// perceptual roughness from the quadric where its primitive sets them
// (the scene file's `metallic`, `roughness`), else from the prop
// (`PropMaterial`), reflectance from the prop, the rest
// `StandardMaterial`'s defaults (no emission, opaque, fog enabled).
//
// Debug outputs (OUTPUT_IDS, OUTPUT_NORMALS) are unlit and skip the
// post-lighting step, so their bytes stay exact.
#define_import_path bevy_chisel::shading

#import bevy_pbr::{
    mesh_types::MESH_FLAGS_SHADOW_RECEIVER_BIT,
    mesh_view_bindings,
    pbr_functions,
    pbr_types,
}
#import bevy_chisel::quadric::{
    INDEX_MASK, id_color, prop, quadric_color, quadric_metallic, quadric_roughness, quadrics,
}

/// The colour of the surface point at local position `local` of literal
/// `lit`, with world-space unit `normal` (zero at a singular point), seen
/// at `frag_coord` (window position, `z` the point's depth).
fn surface_color(
    lit: u32,
    local: vec3<f32>,
    normal: vec3<f32>,
    frag_coord: vec4<f32>,
) -> vec4<f32> {
    let index = lit & INDEX_MASK;
#ifdef OUTPUT_IDS
    return id_color(index);
#else
#ifdef OUTPUT_NORMALS
    return vec4<f32>(normal * 0.5 + 0.5, 1.0);
#else
    var pbr_input = pbr_types::pbr_input_new();
    let q = quadrics[index];
    pbr_input.material.base_color = vec4<f32>(quadric_color(q), 1.0);
    pbr_input.material.metallic = quadric_metallic(q);
    pbr_input.material.perceptual_roughness = quadric_roughness(q);
    pbr_input.material.reflectance = vec3<f32>(prop.reflectance);
    pbr_input.material.flags |= pbr_types::STANDARD_MATERIAL_FLAGS_FOG_ENABLED_BIT;
    pbr_input.flags = MESH_FLAGS_SHADOW_RECEIVER_BIT;
    pbr_input.frag_coord = frag_coord;
    pbr_input.world_position = prop.world_from_local * vec4<f32>(local, 1.0);
    pbr_input.is_orthographic = mesh_view_bindings::view.clip_from_view[3].w == 1.0;
    pbr_input.V = pbr_functions::calculate_view(pbr_input.world_position, pbr_input.is_orthographic);
    // A singular point (a cone's apex) has no normal: light it as if it
    // faced the eye.
    var n = normal;
    if dot(n, n) == 0.0 {
        n = pbr_input.V;
    }
    pbr_input.world_normal = n;
    pbr_input.N = n;
    let lit_color = pbr_functions::apply_pbr_lighting(pbr_input);
    return pbr_functions::main_pass_post_lighting_processing(pbr_input, lit_color);
#endif
#endif
}
