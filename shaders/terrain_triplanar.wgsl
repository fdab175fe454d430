// Triplanar PBR terrain: the fragment shader of `TriplanarMaterial`
// (`StandardMaterial` + `TriplanarExtension`, plugin/terrain/material/triplanar.rs).
//
// Notation: p world position × scale; n unit world normal; for each axis
// k ∈ {x, y, z} a projection with texture coordinates uv_k, tangent t_k
// (+u), bitangent b_k (up the image, −v) and axis a_k = sign(n_k) e_k,
// chosen so that t_k × b_k = a_k (right-handed, so normal maps are not
// mirrored on any face); weights w_k = |n_k|^sharpness / Σ.
//
// Only world position and world normal are used: no UVs, no tangents.
//
// Validated with Bevy's shader library (tests/it/shaders_validate.rs) under
// Defines: TONEMAP_IN_SHADER, DEBAND_DITHER, ENVIRONMENT_MAP.

#import bevy_pbr::{
    forward_io::{VertexOutput, FragmentOutput},
    pbr_fragment::pbr_input_from_standard_material,
    pbr_functions::{alpha_discard, apply_pbr_lighting, main_pass_post_lighting_processing},
}

// Mirrors the `#[uniform(100)]` fields of `TriplanarExtension`.
struct Triplanar {
    scale: f32,
    sharpness: f32,
    normal_strength: f32,
    macro_variation: f32,
}

@group(#{MATERIAL_BIND_GROUP}) @binding(100) var<uniform> triplanar: Triplanar;
@group(#{MATERIAL_BIND_GROUP}) @binding(101) var albedo_texture: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(102) var albedo_sampler: sampler;
@group(#{MATERIAL_BIND_GROUP}) @binding(103) var normal_texture: texture_2d<f32>;
@group(#{MATERIAL_BIND_GROUP}) @binding(104) var normal_sampler: sampler;

// One axis projection: where to sample and its tangent frame.
struct Projection {
    uv: vec2<f32>,
    t: vec3<f32>,
    b: vec3<f32>,
    a: vec3<f32>,
}

fn axis_sign(x: f32) -> f32 {
    return select(-1.0, 1.0, x >= 0.0);
}

// The projections along x, y and z for position p (scaled) and normal n.
fn projection_x(p: vec3<f32>, n: vec3<f32>) -> Projection {
    let s = axis_sign(n.x);
    let t = vec3(0.0, 0.0, -s);
    let b = vec3(0.0, 1.0, 0.0);
    return Projection(vec2(dot(p, t), -dot(p, b)), t, b, vec3(s, 0.0, 0.0));
}

fn projection_y(p: vec3<f32>, n: vec3<f32>) -> Projection {
    let s = axis_sign(n.y);
    let t = vec3(s, 0.0, 0.0);
    let b = vec3(0.0, 0.0, -1.0);
    return Projection(vec2(dot(p, t), -dot(p, b)), t, b, vec3(0.0, s, 0.0));
}

fn projection_z(p: vec3<f32>, n: vec3<f32>) -> Projection {
    let s = axis_sign(n.z);
    let t = vec3(s, 0.0, 0.0);
    let b = vec3(0.0, 1.0, 0.0);
    return Projection(vec2(dot(p, t), -dot(p, b)), t, b, vec3(0.0, 0.0, s));
}

// Blend weights |n|^sharpness, normalized to sum 1.
fn triplanar_weights(n: vec3<f32>, sharpness: f32) -> vec3<f32> {
    let w = pow(abs(n), vec3(max(sharpness, 1e-3)));
    return w / max(w.x + w.y + w.z, 1e-6);
}

// Whiteout blend of a tangent-space normal `tn` with the surface normal
// `n`, both in the projection's frame, returned in world space (unnormalized).
fn whiteout(tn: vec3<f32>, n: vec3<f32>, q: Projection) -> vec3<f32> {
    let local = vec3(dot(n, q.t), dot(n, q.b), dot(n, q.a));
    let blended = vec3(tn.xy + local.xy, abs(tn.z) * local.z);
    return blended.x * q.t + blended.y * q.b + blended.z * q.a;
}

// A normal-map texel as a tangent-space vector, its tilt scaled by `strength`.
fn tangent_normal(texel: vec4<f32>, strength: f32) -> vec3<f32> {
    let v = texel.xyz * 2.0 - 1.0;
    return vec3(v.xy * strength, v.z);
}

@fragment
fn fragment(
    in: VertexOutput,
    @builtin(front_facing) is_front: bool,
) -> FragmentOutput {
    var pbr_input = pbr_input_from_standard_material(in, is_front);

    let n = normalize(pbr_input.world_normal);
    let p = in.world_position.xyz * triplanar.scale;
    let w = triplanar_weights(n, triplanar.sharpness);
    let qx = projection_x(p, n);
    let qy = projection_y(p, n);
    let qz = projection_z(p, n);

    // All six samples unconditionally: derivatives stay in uniform control flow.
    let albedo = textureSample(albedo_texture, albedo_sampler, qx.uv) * w.x
        + textureSample(albedo_texture, albedo_sampler, qy.uv) * w.y
        + textureSample(albedo_texture, albedo_sampler, qz.uv) * w.z;
    let strength = triplanar.normal_strength;
    let nx = tangent_normal(textureSample(normal_texture, normal_sampler, qx.uv), strength);
    let ny = tangent_normal(textureSample(normal_texture, normal_sampler, qy.uv), strength);
    let nz = tangent_normal(textureSample(normal_texture, normal_sampler, qz.uv), strength);
    let mapped = whiteout(nx, n, qx) * w.x + whiteout(ny, n, qy) * w.y + whiteout(nz, n, qz) * w.z;

    // Macro variation against visible tiling: the albedo's brightness at an
    // eighth of the frequency (shifted), relative to its mean (the last mip).
    let pm = p * 0.125 + vec3(0.37, 0.11, 0.73);
    let coarse = textureSample(albedo_texture, albedo_sampler, projection_x(pm, n).uv) * w.x
        + textureSample(albedo_texture, albedo_sampler, projection_y(pm, n).uv) * w.y
        + textureSample(albedo_texture, albedo_sampler, projection_z(pm, n).uv) * w.z;
    let mean = textureSampleLevel(albedo_texture, albedo_sampler, vec2(0.5), 16.0);
    let luminance = vec3(0.2126, 0.7152, 0.0722);
    let ratio = dot(coarse.rgb, luminance) / max(dot(mean.rgb, luminance), 1e-3);
    let variation = clamp(mix(1.0, ratio, triplanar.macro_variation), 0.5, 1.5);

    pbr_input.material.base_color = vec4(
        pbr_input.material.base_color.rgb * albedo.rgb * variation,
        pbr_input.material.base_color.a,
    );
    pbr_input.N = normalize(mapped);
    pbr_input.material.base_color = alpha_discard(pbr_input.material, pbr_input.material.base_color);

    var out: FragmentOutput;
    out.color = apply_pbr_lighting(pbr_input);
    // Fog, exposure and (without a separate pass) tonemapping and dithering.
    out.color = main_pass_post_lighting_processing(pbr_input, out.color);
    return out;
}
