// Shared declarations of the splat pass (splat.wgsl) and the global
// ray-tracing pass (global.wgsl): bindings, quadric evaluation and the
// stable line–quadric intersection. Shading is `splat_shading.wgsl`'s.
//
// Notation (paper 2, §3, §6): a quadric Q is the symmetric 4×4
// [[A, -b], [-bᵀ, c]]; Q(x) = xᵀAx − 2xᵀb + c, inside where Q(x) < 0; the
// half gradient is Ax − b. Quadric coefficients are packed
// [q00 q01 q02 q03 | q11 q12 q13 q22 | q23 q33 r g | b m ρ 0] (so −b is
// (q03, q13, q23)), scaled to a largest magnitude of 1 on the CPU; m and
// ρ are the primitive's metallic and perceptual roughness, negative where
// it takes the prop's.
//
// Rust mirror (the single source of truth for every layout here):
// plugin/splat/gpu.rs.
#define_import_path bevy_chisel::quadric

/// Set in a literal reference when the literal is the complement (Q ≥ 0)
/// (mirror: `chisel_quadric::OUTSIDE_FLAG`).
const OUTSIDE_FLAG: u32 = 0x80000000u;
/// The quadric index bits of a literal reference (mirror:
/// `chisel_quadric::INDEX_MASK`).
const INDEX_MASK: u32 = 0x7fffffffu;
/// Marks a missing root of the line–quadric equation.
const NO_ROOT: f32 = 3.0e38;

/// One view (mirror: `SplatViewUniform`).
struct SplatView {
    clip_from_world: mat4x4<f32>,
    /// xyz: eye position; w: 1 for a perspective view, 0 for orthographic.
    camera_position: vec4<f32>,
    /// xyz: unit view direction (for orthographic views).
    view_forward: vec4<f32>,
    /// Splats whose normal extent is below `flat_ratio · radius` are drawn
    /// as a single surface-aligned quad.
    flat_ratio: f32,
    /// A hit is kept within `radius · radius_tolerance` of its sample.
    radius_tolerance: f32,
    pad: vec2<u32>,
};

/// One prop (mirror: `PropUniform`).
struct Prop {
    world_from_local: mat4x4<f32>,
    local_from_world: mat4x4<f32>,
    /// Inverse transpose of the linear part of `world_from_local`.
    normal_from_local: mat4x4<f32>,
    /// Local bounding sphere: centre, radius.
    bounds: vec4<f32>,
    /// Number of products of the normal form (global pass).
    product_count: u32,
    /// Largest stretch (singular value) of `world_from_local`.
    max_scale: f32,
    /// −1 when `world_from_local` mirrors (negative determinant), +1
    /// otherwise: see `box_corner`.
    mirror_sign: f32,
    /// PBR material of the whole prop (`PropMaterial`).
    metallic: f32,
    perceptual_roughness: f32,
    reflectance: f32,
    pad: vec2<u32>,
};

/// One quadric record (mirror: `QuadricRecord`).
struct Quadric {
    c: array<vec4<f32>, 4>,
};

/// One splat (mirror: `SplatRecord`).
struct Splat {
    position: vec3<f32>,
    radius: f32,
    normal: vec3<f32>,
    normal_extent: f32,
    /// The box's first tangent axis; the second is `cross(normal, tangent)`.
    tangent: vec3<f32>,
    /// ‖A‖₂ / |As − b| at the sample: how fast the normal can turn.
    normal_turn: f32,
    /// The box's half-extents along the two tangent axes (≤ radius).
    tangent_extent: vec2<f32>,
    quadric: u32,
    clip_start: u32,
    clip_count: u32,
    pad: array<u32, 3>,
};

// Groups 0 and 1 are Bevy's mesh view bindings (lights, shadow maps,
// clusters, exposure), which the shading reads.
@group(2) @binding(0) var<uniform> view: SplatView;
@group(3) @binding(0) var<uniform> prop: Prop;
@group(3) @binding(1) var<storage, read> quadrics: array<Quadric>;
@group(3) @binding(2) var<storage, read> clip_indices: array<u32>;
@group(3) @binding(3) var<storage, read> splats: array<Splat>;
/// Normal form for the global pass (`chisel_quadric::encode_normal_form`):
/// `(start, count)` per product, then the literal references of every product.
@group(3) @binding(4) var<storage, read> terms: array<u32>;

fn quadric_a(q: Quadric, x: vec3<f32>) -> vec3<f32> {
    let k0 = q.c[0];
    let k1 = q.c[1];
    return vec3<f32>(
        k0.x * x.x + k0.y * x.y + k0.z * x.z,
        k0.y * x.x + k1.x * x.y + k1.y * x.z,
        k0.z * x.x + k1.y * x.y + k1.w * x.z,
    );
}

fn quadric_linear(q: Quadric) -> vec3<f32> {
    return vec3<f32>(q.c[0].w, q.c[1].z, q.c[2].x);
}

/// Ax − b: half the gradient of Q at x.
fn quadric_half_gradient(q: Quadric, x: vec3<f32>) -> vec3<f32> {
    return quadric_a(q, x) + quadric_linear(q);
}

/// Q(x).
fn quadric_value(q: Quadric, x: vec3<f32>) -> f32 {
    return dot(x, quadric_a(q, x)) + 2.0 * dot(quadric_linear(q), x) + q.c[2].y;
}

fn quadric_color(q: Quadric) -> vec3<f32> {
    return vec3<f32>(q.c[2].z, q.c[2].w, q.c[3].x);
}

/// The primitive's metallic, or the prop's where it sets none.
fn quadric_metallic(q: Quadric) -> f32 {
    return select(prop.metallic, q.c[3].y, q.c[3].y >= 0.0);
}

/// The primitive's perceptual roughness, or the prop's where it sets none.
fn quadric_roughness(q: Quadric) -> f32 {
    return select(prop.perceptual_roughness, q.c[3].z, q.c[3].z >= 0.0);
}

/// Whether the literal `lit` (a flagged quadric index) holds at x.
fn literal_holds(lit: u32, x: vec3<f32>) -> bool {
    let v = quadric_value(quadrics[lit & INDEX_MASK], x);
    if (lit & OUTSIDE_FLAG) != 0u {
        return v >= 0.0;
    }
    return v <= 0.0;
}

/// Roots u of Q(p + u·v) = 0 for a unit v, as (u1, u2), NO_ROOT where
/// missing. Written a·u² + 2·h·u + c = 0 and solved without cancellation
/// (q = −(h + sign(h)·√(h² − ac)), u = q/a and c/q), which also covers the
/// linear case a = 0 (paper 2, eqs. 5–6). Place p near the expected hit.
fn intersect_line(q: Quadric, p: vec3<f32>, v: vec3<f32>) -> vec2<f32> {
    let a = dot(v, quadric_a(q, v));
    let h = dot(v, quadric_half_gradient(q, p));
    let c = quadric_value(q, p);
    let disc = h * h - a * c;
    if disc < 0.0 {
        return vec2<f32>(NO_ROOT, NO_ROOT);
    }
    var s = sqrt(disc);
    if h < 0.0 {
        s = -s;
    }
    let qq = -(h + s);
    var u1 = NO_ROOT;
    var u2 = NO_ROOT;
    if a != 0.0 {
        u1 = qq / a;
    }
    if qq != 0.0 {
        u2 = c / qq;
    } else if a != 0.0 {
        // h = 0 and disc = 0: the double root at 0.
        u2 = 0.0;
    }
    return vec2<f32>(u1, u2);
}

/// The eye in local coordinates, or the origin for an orthographic view.
fn local_eye() -> vec3<f32> {
    return (prop.local_from_world * vec4<f32>(view.camera_position.xyz, 1.0)).xyz;
}

/// The unit view ray direction through the local point x.
fn local_ray_direction(x: vec3<f32>) -> vec3<f32> {
    if view.camera_position.w > 0.5 {
        return normalize(x - local_eye());
    }
    return normalize((prop.local_from_world * vec4<f32>(view.view_forward.xyz, 0.0)).xyz);
}

/// World-space outward unit normal of literal `lit` at local point x.
fn world_normal(lit: u32, x: vec3<f32>) -> vec3<f32> {
    var g = quadric_half_gradient(quadrics[lit & INDEX_MASK], x);
    if (lit & OUTSIDE_FLAG) != 0u {
        g = -g;
    }
    let n = (prop.normal_from_local * vec4<f32>(g, 0.0)).xyz;
    let len = length(n);
    if len > 0.0 {
        return n / len;
    }
    return vec3<f32>(0.0, 0.0, 0.0);
}

struct SurfaceOutput {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
};

/// sRGB-encoded value back to linear, so that a debug colour lands on exact
/// bytes in an 8-bit sRGB target.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

/// The debug colour of quadric `index` (OUTPUT_IDS): bytes
/// r = 16·(i mod 16) + 8, g = 16·(i div 16 mod 16) + 8, b = 200 in an sRGB
/// target.
fn id_color(index: u32) -> vec4<f32> {
    let r = f32((index % 16u) * 16u + 8u) / 255.0;
    let g = f32(((index / 16u) % 16u) * 16u + 8u) / 255.0;
    return vec4<f32>(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(200.0 / 255.0), 1.0);
}

/// Depth (reverse-Z) of the local point x, above 1 in front of the near
/// plane, or −1 where the point is not in front of a perspective eye.
fn clip_depth(x: vec3<f32>) -> f32 {
    let world = prop.world_from_local * vec4<f32>(x, 1.0);
    let clip = view.clip_from_world * world;
    if clip.w <= 0.0 {
        return -1.0;
    }
    return clip.z / clip.w;
}

/// Depth (reverse-Z) of the local point x, or a negative value when it lies
/// outside the depth range.
fn surface_depth(x: vec3<f32>) -> f32 {
    let depth = clip_depth(x);
    if depth > 1.0 {
        return -1.0;
    }
    return depth;
}

/// The 36 corner indices of a box's 12 triangles, counter-clockwise seen
/// from outside; corner i has signs (bit 0, bit 1, bit 2) along the box axes
/// (t1, t2, n). The first two triangles are the +n face.
const BOX_CORNERS: array<u32, 36> = array<u32, 36>(
    4u, 5u, 7u, 4u, 7u, 6u,
    0u, 2u, 3u, 0u, 3u, 1u,
    1u, 3u, 7u, 1u, 7u, 5u,
    0u, 4u, 6u, 0u, 6u, 2u,
    2u, 6u, 7u, 2u, 7u, 3u,
    0u, 1u, 5u, 0u, 5u, 4u,
);

/// Corner `vertex` (0..36) of the box as signs (±1, ±1, ±1), the first
/// sign multiplied by `prop.mirror_sign`. The box is symmetric, so a
/// mirrored prop gets the same box with every triangle wound the other way
/// in local space: counter-clockwise from outside again once its
/// `world_from_local` has mirrored it, so back-face culling keeps the
/// faces towards the eye, and the face list keeps its order (the +n face
/// stays the first two triangles).
fn box_corner(vertex: u32) -> vec3<f32> {
    var corners = BOX_CORNERS;
    let i = corners[vertex % 36u];
    return vec3<f32>(
        select(-1.0, 1.0, (i & 1u) != 0u) * prop.mirror_sign,
        select(-1.0, 1.0, (i & 2u) != 0u),
        select(-1.0, 1.0, (i & 4u) != 0u),
    );
}
