// The splat pass (paper 2, §6, §6.1): one instance per splat.
//
// Vertex stage: each splat becomes a surface-aligned box around its patch
// (axes `tangent`, `normal × tangent`, `normal`; half-extents from the
// surface over the sample's cell, `chisel_quadric::splats::cell_box`, each
// at most r; a singular point gets its sphere's box), drawn with
// back-face culling so every covered pixel runs one fragment; a box thinner
// than `flat_ratio · r` collapses to its front face, a quad lifted by e
// along the normal. With SPLAT_SCREEN_QUAD it is instead a camera-facing
// quad of half-size r placed at the front of the splat's sphere. A mirrored
// prop (negative determinant) gets its boxes wound the other way round in
// local space (`box_corner`), so they reach clip space counter-clockwise.
//
// Fragment stage: local ray tracing of the splat's quadric, keeping the
// root nearest the sample and only within its radius; local clipping
// against the splat's clip list; exact normal from the gradient, shaded
// by Bevy's PBR (`splat_shading.wgsl`); depth written (reverse-Z). Every proxy lies in front of the patch it bounds, so
// the written depth never exceeds the rasterized one:
// `@early_depth_test(less_equal)` where the device supports it.
//
//
// Shadow maps (SHADOW_DEPTH): the same boxes and the same per-fragment ray
// tracing and clipping, seen from a light's shadow view (the pass's view
// uniform holds the light's projection, a directional cascade being
// orthographic), writing depth only, so a prop's shadow has its exact
// silhouette. Bevy's mesh view bindings (groups 0 and 1) are not used. In
// an orthographic (directional) shadow view a caster between the light and
// the cascade's near plane is flattened onto that plane, as Bevy does for
// meshes ("unclipped depth"): proxy vertices and written depths are clamped
// to the near plane's depth 1 instead of being clipped.
//
// Multisampled targets: every covered sample shows the surface along its
// own ray. Tracing only the ray through the pixel's centre and applying the
// result to every sample the proxy covers is wrong: where a splat's proxy
// covers a sample but the centre's ray leaves its radius, the splat
// discards the whole fragment and that sample keeps whatever lies behind
// the surface (a speckle of another surface wherever splats abut, at a few
// pixels per splat). Two forms:
// - SAMPLE_RAYS (4 samples, at the standard positions): the fragment stage
//   runs once per pixel, traces the ray of each covered sample
//   (`@builtin(sample_mask)` in), writes the samples whose ray hits the
//   splat's patch (`sample_mask` out) and shades once, at the hit of the
//   first of them. The rays come from `ray_point`, affine in window
//   position, and its exact per-pixel differences (`dpdxFine`). One depth
//   for the written samples: the farthest of their hits, so it never lies
//   in front of any of their own hits or proxies (the early depth test's
//   promise). Against another surface within a pixel's depth span (a mesh
//   through the prop, two patches crossing) the samples are ordered per
//   pixel, not per sample.
// - PER_SAMPLE (2 or 8 samples): the fragment stage runs once per covered
//   sample, with the proxy point at that sample: a depth per sample, and
//   a shading per sample.
//
// Defines: SPLAT_SCREEN_QUAD, EARLY_DEPTH_TEST, SAMPLE_RAYS, PER_SAMPLE, OUTPUT_IDS, OUTPUT_NORMALS,
// OUTPUT_OVERDRAW (a constant per fragment, for additive blending),
// OUTPUT_BOUNDS (the proxies themselves, flat-coloured per splat),
// SPLAT_OPEN_BOX (30 vertices per box: the −n face left out), SHADOW_DEPTH
// (depth only, into a shadow map), CULL_FACING_AWAY (a splat whose every
// point faces away from the eye is dropped in the vertex stage; main views
// only, the shadow pass keeps every splat for the silhouette).
#import bevy_chisel::quadric::{
    INDEX_MASK, NO_ROOT, SurfaceOutput, box_corner, clip_depth, intersect_line,
    literal_holds, local_ray_direction, local_eye, prop, quadrics, clip_indices,
    splats, surface_depth, view, world_normal,
}
#ifndef SHADOW_DEPTH
#import bevy_chisel::shading::surface_color
#endif

struct SplatVarying {
    @builtin(position) clip: vec4<f32>,
    /// The proxy point in the prop's local coordinates (on the view ray).
    /// Multisampled, at each sample covered: the proxy of a neighbouring
    /// splat may cover a sample but not the pixel's centre, where the ray
    /// can leave the splat's radius and the surface would be lost there.
#ifdef PER_SAMPLE
    @location(0) @interpolate(perspective, sample) local: vec3<f32>,
#else
    @location(0) local: vec3<f32>,
#endif
    @location(1) @interpolate(flat) splat: u32,
};

/// Outside the depth range: the triangle is clipped away.
const DISCARDED_VERTEX: vec4<f32> = vec4<f32>(0.0, 0.0, -2.0, 1.0);

/// Quad corners in the order of two counter-clockwise triangles.
const QUAD_CORNERS: array<vec2<f32>, 6> = array<vec2<f32>, 6>(
    vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
    vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
);

/// The clip position of a world point; in an orthographic shadow view,
/// clamped to the near plane rather than clipped by it.
fn clip_position(world: vec4<f32>) -> vec4<f32> {
    var clip = view.clip_from_world * world;
#ifdef SHADOW_DEPTH
    if view.camera_position.w < 0.5 {
        clip.z = min(clip.z, clip.w);
    }
#endif
    return clip;
}

fn varying_at(local: vec3<f32>, splat: u32) -> SplatVarying {
    var out: SplatVarying;
    out.local = local;
    out.splat = splat;
    out.clip = clip_position(prop.world_from_local * vec4<f32>(local, 1.0));
    return out;
}

#ifdef CULL_FACING_AWAY
/// Whether the whole prop lies beyond the view's near plane: its bounding
/// sphere (which holds every splat's patch) is on the far side of the
/// plane `clip.w − clip.z = 0` (reverse-Z depth 1). Then every view ray
/// enters the solid from outside before it can leave it, so a surface
/// point facing away from the eye is hidden behind one facing it.
fn prop_beyond_near_plane() -> bool {
    let m = view.clip_from_world;
    let plane = vec4<f32>(
        m[0].w - m[0].z, m[1].w - m[1].z, m[2].w - m[2].z, m[3].w - m[3].z,
    );
    let centre = prop.world_from_local * vec4<f32>(prop.bounds.xyz, 1.0);
    let radius = abs(prop.bounds.w) * prop.max_scale * 1.01;
    return dot(plane, centre) > radius * length(plane.xyz);
}

/// Whether every surface point splat `s` can draw (those within `r` of its
/// sample) faces away from the eye: a conservative bound, never true for a
/// splat that holds a point facing the eye.
///
/// With n = g/|g| the outward unit normal at the sample s (g = σ(As − b),
/// σ = −1 for a complemented literal), κ = ‖A‖₂/|g| (`normal_turn`),
/// w = s − eye (perspective) or the view direction (orthographic) and
/// δ = p − s, |δ| ≤ r, a point p faces away where
/// f(p) = σ(Ap − b)·(p − eye) > 0, and exactly
/// f(p)/|g| = n·w + n·δ' + σ(Aδ)·w/|g| + σ(Aδ)·δ'/|g|, δ' = δ
/// (perspective) or 0. So f(p)/|g| ≥ n·w − r' − κ r (|w| + r'), r' = r or
/// 0: how far the splat faces away against how far its normal can turn.
/// The test is in local coordinates, where the sign of f is the world's
/// (n_world ∝ M⁻ᵀg, p − eye = M(p_l − eye_l)). A relative margin of 10⁻⁴
/// covers the `f32` rounding of n and w, and r is widened by 1 % beyond
/// the fragment stage's radius test.
fn faces_away(position: vec3<f32>, normal: vec3<f32>, normal_turn: f32, r: f32) -> bool {
    let rr = r * 1.01;
    var w = (prop.local_from_world * vec4<f32>(view.view_forward.xyz, 0.0)).xyz;
    var w_turn = 0.0;
    if view.camera_position.w > 0.5 {
        w = position - local_eye();
        w_turn = rr;
    }
    let w_len = length(w);
    let bound = w_turn + normal_turn * rr * (w_len + w_turn)
        + 1e-4 * (w_len + w_turn + 2.0 * length(position));
    return dot(normal, w) > bound && prop_beyond_near_plane();
}
#endif

@vertex
fn vertex(
    @builtin(vertex_index) vertex: u32,
    @builtin(instance_index) instance: u32,
) -> SplatVarying {
    let s = splats[instance];
    let r = s.radius * view.radius_tolerance;
#ifdef CULL_FACING_AWAY
    if faces_away(s.position, s.normal, s.normal_turn, r) {
        var culled: SplatVarying;
        culled.clip = DISCARDED_VERTEX;
        culled.local = s.position;
        culled.splat = instance;
        return culled;
    }
#endif
#ifdef SPLAT_SCREEN_QUAD
    var out: SplatVarying;
    out.splat = instance;
    if vertex >= 6u {
        out.clip = DISCARDED_VERTEX;
        out.local = s.position;
        return out;
    }
    let centre = (prop.world_from_local * vec4<f32>(s.position, 1.0)).xyz;
    let rw = r * prop.max_scale;
    var dir = view.view_forward.xyz;
    if view.camera_position.w > 0.5 {
        let to_centre = centre - view.camera_position.xyz;
        dir = to_centre / max(length(to_centre), 1e-30);
    }
    var helper = vec3<f32>(0.0, 1.0, 0.0);
    if abs(dir.y) > 0.9 {
        helper = vec3<f32>(1.0, 0.0, 0.0);
    }
    let right = normalize(cross(dir, helper));
    let up = cross(right, dir);
    var corners = QUAD_CORNERS;
    let c = corners[vertex];
    // A quad of half-size r at distance d − r covers the sphere's silhouette
    // (its angular radius asin(r/d) is below atan(r/(d − r))).
    let world = centre - dir * rw + (right * c.x + up * c.y) * rw;
    out.local = (prop.local_from_world * vec4<f32>(world, 1.0)).xyz;
    out.clip = clip_position(vec4<f32>(world, 1.0));
    return out;
#else
    var n = s.normal;
    var e = s.normal_extent * view.radius_tolerance;
    var t1 = s.tangent;
    var h = s.tangent_extent * view.radius_tolerance;
    if dot(n, n) < 0.25 {
        // A singular point (cone apex): no tangent plane, bound the sphere.
        n = vec3<f32>(0.0, 0.0, 1.0);
#ifdef SPLAT_OPEN_BOX
        // Its −n face, left out, must face away from the eye.
        n = -local_ray_direction(s.position);
#endif
        e = r;
        var helper = vec3<f32>(1.0, 0.0, 0.0);
        if abs(n.x) > 0.9 {
            helper = vec3<f32>(0.0, 1.0, 0.0);
        }
        t1 = normalize(cross(helper, n));
        h = vec2<f32>(r, r);
    }
    let t2 = cross(n, t1);
#ifdef SPLAT_OPEN_BOX
    // Vertices 6..12 of a closed box are its −n face: skip them.
    let c = box_corner(select(vertex, vertex + 6u, vertex >= 6u));
#else
    let c = box_corner(vertex);
#endif
    if e < view.flat_ratio * r {
        // Flat: only the +n face (the first six vertices), lifted to +e.
        if vertex >= 6u {
            var out: SplatVarying;
            out.clip = DISCARDED_VERTEX;
            out.local = s.position;
            out.splat = instance;
            return out;
        }
        return varying_at(s.position + t1 * (c.x * h.x) + t2 * (c.y * h.y) + n * e, instance);
    }
    return varying_at(s.position + t1 * (c.x * h.x) + t2 * (c.y * h.y) + n * (c.z * e), instance);
#endif
}

#ifdef OUTPUT_OVERDRAW
/// One unit per fragment invocation, summed by additive blending.
@fragment
fn fragment(in: SplatVarying) -> @location(0) vec4<f32> {
    return vec4<f32>(1.0 / 64.0, 1.0 / 64.0, 1.0 / 64.0, 1.0);
}
#else
#ifdef OUTPUT_BOUNDS
/// The splat bounds (§6.1, Fig. 12): each proxy in a colour of its own,
/// its faces told apart by their slope, at the rasterized depth.
@fragment
fn fragment(in: SplatVarying) -> @location(0) vec4<f32> {
    let face = normalize(cross(dpdx(in.local), dpdy(in.local)));
    let light = 0.55 + 0.45 * abs(dot(face, vec3<f32>(0.3, 0.5, 0.81)));
    return vec4<f32>(hash_color(in.splat) * light, 1.0);
}

/// A bright colour from a splat index.
fn hash_color(i: u32) -> vec3<f32> {
    var h = i * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = (h >> 22u) ^ h;
    let c = vec3<f32>(f32(h & 255u), f32((h >> 8u) & 255u), f32((h >> 16u) & 255u)) / 255.0;
    return 0.25 + 0.75 * c;
}
#else
/// The local point of splat `splat`'s surface patch seen through the
/// point `local` of a view ray: the root of the splat's quadric along the
/// ray nearest the sample, within its radius and inside its clip list
/// (`w` = 1), or `w` = 0 where there is none.
fn splat_trace(local: vec3<f32>, splat: u32) -> vec4<f32> {
    let s = splats[splat];
    let q = quadrics[s.quadric & INDEX_MASK];
    let dir = local_ray_direction(local);
    // Solve from the point of the ray closest to the sample: the root of
    // smallest |u| is then the hit nearest the sample.
    let p0 = local + dot(s.position - local, dir) * dir;
    let roots = intersect_line(q, p0, dir);
    var u = roots.x;
    if abs(roots.y) < abs(u) {
        u = roots.y;
    }
    if abs(u) >= NO_ROOT {
        return vec4<f32>(p0, 0.0);
    }
    let p = p0 + u * dir;
    let r = s.radius * view.radius_tolerance;
    let off = p - s.position;
    if dot(off, off) > r * r {
        return vec4<f32>(p, 0.0);
    }
    for (var i = 0u; i < s.clip_count; i += 1u) {
        if !literal_holds(clip_indices[s.clip_start + i], p) {
            return vec4<f32>(p, 0.0);
        }
    }
    return vec4<f32>(p, 1.0);
}

/// The hit of `splat_trace` through the proxy point `local`; the fragment
/// is discarded where there is none.
fn splat_hit(local: vec3<f32>, splat: u32) -> vec3<f32> {
    let hit = splat_trace(local, splat);
    if hit.w == 0.0 {
        discard;
    }
    return hit.xyz;
}

#ifdef SHADOW_DEPTH
/// Depth only, into a shadow map: the hit's depth in the light's view,
/// clamped to the near plane in an orthographic (directional) view.
@fragment
fn fragment(in: SplatVarying) -> @builtin(frag_depth) f32 {
    let p = splat_hit(in.local, in.splat);
    var depth = clip_depth(p);
    if view.camera_position.w < 0.5 {
        depth = min(depth, 1.0);
    }
    if depth < 0.0 || depth > 1.0 {
        discard;
    }
    return depth;
}
#else
#ifdef SAMPLE_RAYS
/// Offsets of the 4 standard sample positions from the pixel's centre, in
/// pixels, y down (Vulkan's standard locations, WebGPU's 4× pattern): bit
/// `i` of the sample mask is sample `i`.
const SAMPLE_OFFSETS: array<vec2<f32>, 4> = array<vec2<f32>, 4>(
    vec2<f32>(-0.125, -0.375), vec2<f32>(0.375, -0.125),
    vec2<f32>(-0.375, 0.125), vec2<f32>(0.125, 0.375),
);

/// A point of the view ray through the local point `x` that is an affine
/// function of window position, so that its value at a sample is its
/// value at the pixel's centre plus its per-pixel differences times the
/// sample's offset. Perspective: `eye + (x − eye) / w` (`w` the clip
/// coordinate, proportional to the depth along the view direction: the
/// ray's direction scaled to unit depth); orthographic: `x` itself (the
/// proxy plane's points are affine in window position, `w` = 1).
fn ray_point(x: vec3<f32>) -> vec3<f32> {
    if view.camera_position.w > 0.5 {
        let eye = local_eye();
        let w = (view.clip_from_world * (prop.world_from_local * vec4<f32>(x, 1.0))).w;
        return eye + (x - eye) / w;
    }
    return x;
}

/// The surface colour and depth, and the samples they are written to.
struct MaskedSurfaceOutput {
    @location(0) color: vec4<f32>,
    @builtin(frag_depth) depth: f32,
    @builtin(sample_mask) mask: u32,
};

#ifdef EARLY_DEPTH_TEST
@early_depth_test(less_equal)
#endif
@fragment
fn fragment(in: SplatVarying, @builtin(sample_mask) covered: u32) -> MaskedSurfaceOutput {
    // In uniform control flow: the differences come from the 2×2 quad.
    let centre = ray_point(in.local);
    let step_x = dpdxFine(centre);
    let step_y = dpdyFine(centre);
    var mask = 0u;
    var shaded = vec3<f32>(0.0);
    var depth = 1.0;
    for (var i = 0u; i < 4u; i += 1u) {
        if (covered & (1u << i)) == 0u {
            continue;
        }
        let offset = SAMPLE_OFFSETS[i];
        let hit = splat_trace(centre + step_x * offset.x + step_y * offset.y, in.splat);
        if hit.w == 0.0 {
            continue;
        }
        let d = surface_depth(hit.xyz);
        if d < 0.0 {
            continue;
        }
        if mask == 0u {
            shaded = hit.xyz;
        }
        mask |= 1u << i;
        // Reverse-Z: the smallest depth is the farthest hit.
        depth = min(depth, d);
    }
    if mask == 0u {
        discard;
    }
    let s = splats[in.splat];
    var out: MaskedSurfaceOutput;
    let frag_coord = vec4<f32>(in.clip.xy, depth, in.clip.w);
    out.color = surface_color(s.quadric, shaded, world_normal(s.quadric, shaded), frag_coord);
    out.depth = depth;
    out.mask = mask;
    return out;
}
#else
#ifdef EARLY_DEPTH_TEST
@early_depth_test(less_equal)
#endif
@fragment
fn fragment(in: SplatVarying) -> SurfaceOutput {
    let p = splat_hit(in.local, in.splat);
    let depth = surface_depth(p);
    if depth < 0.0 {
        discard;
    }
    let s = splats[in.splat];
    var out: SurfaceOutput;
    let frag_coord = vec4<f32>(in.clip.xy, depth, in.clip.w);
    out.color = surface_color(s.quadric, p, world_normal(s.quadric, p), frag_coord);
    out.depth = depth;
    return out;
}
#endif
#endif
#endif
#endif
