// The global ray-tracing pass (paper 2, §7.2): the baseline the splat pass
// is measured against. One cube around the prop's bounding sphere is
// rasterized (back faces, so the eye may be inside it); every fragment
// intersects its view ray with every literal of every product of the normal
// form and keeps the nearest root where the ray enters that literal while
// all other literals of the product hold — the first point of the solid
// along the ray when the eye is outside it. A mirrored prop's cube is wound
// the other way round in local space (`box_corner`), so the faces kept are
// the far ones whatever the prop's transform.
//
// Defines: OUTPUT_IDS, OUTPUT_NORMALS, OUTPUT_OVERDRAW, OUTPUT_BOUNDS (the
// proxy cube itself).
#import bevy_chisel::quadric::{
    INDEX_MASK, NO_ROOT, OUTSIDE_FLAG, SurfaceOutput, box_corner, intersect_line,
    literal_holds, local_eye, local_ray_direction, prop, quadric_half_gradient, quadrics,
    surface_depth, terms, view, world_normal,
}
#import bevy_chisel::shading::surface_color

struct ProxyVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec3<f32>,
};

@vertex
fn vertex(@builtin(vertex_index) vertex: u32) -> ProxyVarying {
    let local = prop.bounds.xyz + box_corner(vertex) * prop.bounds.w;
    var out: ProxyVarying;
    out.local = local;
    out.clip = view.clip_from_world * (prop.world_from_local * vec4<f32>(local, 1.0));
    return out;
}

/// Whether the root u of literal `lit` (product terms[start..start+count],
/// position j) is a point where the ray enters the product.
fn enters_product(
    lit: u32,
    j: u32,
    start: u32,
    count: u32,
    p: vec3<f32>,
    dir: vec3<f32>,
) -> bool {
    var slope = dot(dir, quadric_half_gradient(quadrics[lit & INDEX_MASK], p));
    if (lit & OUTSIDE_FLAG) != 0u {
        slope = -slope;
    }
    if slope > 0.0 {
        return false;
    }
    for (var m = 0u; m < count; m += 1u) {
        if m != j && !literal_holds(terms[start + m], p) {
            return false;
        }
    }
    return true;
}

#ifdef OUTPUT_OVERDRAW
@fragment
fn fragment(in: ProxyVarying) -> @location(0) vec4<f32> {
    return vec4<f32>(1.0 / 64.0, 1.0 / 64.0, 1.0 / 64.0, 1.0);
}
#else
#ifdef OUTPUT_BOUNDS
/// The proxy cube, its faces told apart by their slope.
@fragment
fn fragment(in: ProxyVarying) -> @location(0) vec4<f32> {
    let face = normalize(cross(dpdx(in.local), dpdy(in.local)));
    let light = 0.55 + 0.45 * abs(dot(face, vec3<f32>(0.3, 0.5, 0.81)));
    return vec4<f32>(vec3<f32>(0.35, 0.6, 0.9) * light, 1.0);
}
#else
@fragment
fn fragment(in: ProxyVarying) -> SurfaceOutput {
    let dir = local_ray_direction(in.local);
    var eye = in.local - dir * (4.0 * prop.bounds.w);
    if view.camera_position.w > 0.5 {
        eye = local_eye();
    }
    // Solve from the point of the ray closest to the bounding centre.
    let p0 = eye + dot(prop.bounds.xyz - eye, dir) * dir;
    let u_eye = dot(eye - p0, dir);
    var best_u = NO_ROOT;
    var best_lit = 0u;
    for (var a = 0u; a < prop.product_count; a += 1u) {
        let start = terms[2u * a];
        let count = terms[2u * a + 1u];
        for (var j = 0u; j < count; j += 1u) {
            let lit = terms[start + j];
            let roots = intersect_line(quadrics[lit & INDEX_MASK], p0, dir);
            let u1 = min(roots.x, roots.y);
            let u2 = max(roots.x, roots.y);
            if u1 > u_eye && u1 < best_u && enters_product(lit, j, start, count, p0 + u1 * dir, dir) {
                best_u = u1;
                best_lit = lit;
            } else if u2 > u_eye && u2 < best_u && u2 < NO_ROOT
                && enters_product(lit, j, start, count, p0 + u2 * dir, dir) {
                best_u = u2;
                best_lit = lit;
            }
        }
    }
    if best_u >= NO_ROOT {
        discard;
    }
    let p = p0 + best_u * dir;
    let depth = surface_depth(p);
    if depth < 0.0 {
        discard;
    }
    var out: SurfaceOutput;
    let frag_coord = vec4<f32>(in.clip.xy, depth, in.clip.w);
    out.color = surface_color(best_lit, p, world_normal(best_lit, p), frag_coord);
    out.depth = depth;
    return out;
}
#endif
#endif
