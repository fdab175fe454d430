//! Carving with a convex quadric prop's shape: [`CarveTool::from_prop`].
//!
//! Notation: `K` — the prop's solid placed in the terrain's frame; `c` — a
//! point inside `K`; `uᵢ` — the directions of a geodesic sphere; `sᵢ`,
//! `nᵢ` — where the ray from `c` along `uᵢ` leaves `K`, and `K`'s outward
//! unit normal there; `δ` — how far rounding moves a corner
//! ([`GRID_ROUNDING`] steps); `P` — the tool, the hull of integer corners.
//!
//! Convexity. `K` is convex when its normal form (paper 2, §5) is one
//! product of literals whose quadrics, with the side applied, have a
//! positive semi-definite quadratic part: each literal is then a sublevel
//! set of a convex function. That is sufficient, not necessary (one nappe
//! of a cone cut by a plane is convex, and refused).
//!
//! Containment. Each plane `nᵢ·(x − sᵢ) = 0` touches `K` and has it on one
//! side. Cutting a box by those planes, each moved out by `δ` and by what
//! rounding its normal to integers may turn it, leaves an exact polyhedron
//! containing `K` grown by `δ`; its corners rounded to the grid span a hull
//! `P ⊇ K` (the support function moves by at most `δ`). `K` lies in the box
//! when the polyhedron stays clear of the box's faces.
//!
//! Tolerance. The Hausdorff distance of nested convex bodies is the
//! largest distance from a corner of the outer one to the inner one; at
//! each corner a point of `K` on a ray towards `c`, or against the normal
//! of the nearest `sᵢ`, bounds it from above. The directions are refined
//! until that bound meets the tolerance.

use bevy::math::DVec3;
use bevy::prelude::*;
use chisel_bsp::convex::{ConvexArena, KeptOutcome, NO_TAG, Part};
use chisel_bsp::exact::{IntPoint, Plane};
use chisel_bsp::tools::{GRID_ROUNDING, Quantization, geodesic_point_count, geodesic_sphere};
use chisel_quadric::{Dnf, Ray, Scene, SymmetricEigen, TraceHit, trace_ray};

use super::error::TerrainError;
use super::tool::{CarveShape, CarveTool, MAX_ROUND_CORNERS};

/// Tangent-plane normals are rounded to integers at this scale: `2^20`
/// keeps `|a|, |b|, |c| ≤ 2^20` and `|d| ≤ 2^48` for coordinates within
/// `2^26`, far inside the plane budget, and turns a plane by at most
/// `2^-20` radians.
const NORMAL_SCALE: f64 = (1u64 << 20) as f64;

/// A quadratic part counts as positive semi-definite when its least
/// eigenvalue is above `−EIGEN_SLACK` times the largest coefficient (the
/// noise of transforming a plane, whose quadratic part is zero).
const EIGEN_SLACK: f64 = 1e-9;

impl CarveTool {
    /// A tool of the shape of a convex quadric prop: `scene` (for a
    /// `QuadricProp`, its `QuadricScene`'s scene) placed by `pose` in the
    /// terrain's frame, on the terrain's grid `quantization`. The tool is a
    /// hull of grid points that contains the prop's solid and lies within
    /// `tolerance` (world units) of its surface, with at most
    /// [`MAX_ROUND_CORNERS`] corners (module docs).
    ///
    /// # Errors
    /// [`TerrainError::PropNotConvex`] when the solid is not one
    /// intersection of convex quadric solids; [`TerrainError::InvalidProp`]
    /// for a scene that does not normalize, an empty or unbounded solid, or
    /// one with no point inside near its origin or its quadrics' centres;
    /// [`TerrainError::InvalidTool`] for a tolerance that is not positive
    /// and finite; [`TerrainError::Kernel`] with
    /// [`chisel_bsp::Error::ToleranceUnreachable`] when the corners allowed
    /// do not meet the tolerance, or with a range error for a prop outside
    /// the grid's range.
    pub fn from_prop(
        scene: &Scene,
        pose: &Transform,
        tolerance: f32,
        quantization: &Quantization,
    ) -> Result<Self, TerrainError> {
        let tolerance = f64::from(tolerance);
        if !(tolerance.is_finite() && tolerance > 0.0) {
            return Err(TerrainError::InvalidTool {
                reason: "a prop tool's tolerance must be positive and finite",
            });
        }
        let dnf = placed_dnf(scene, pose)?;
        check_convex(scene, &dnf)?;
        let centre = interior_point(&dnf, pose)?;
        let corners = fit_corners(&dnf, centre, tolerance, quantization)?;
        // World points that round back to exactly these grid points.
        let mut points = Vec::with_capacity(corners.len());
        for g in &corners {
            let world = quantization.to_world(g.map(|v| v as f64));
            let point = Vec3::from_array(world.map(|v| v as f32));
            if quantization.to_grid_f32(point.to_array())?.coords() != *g {
                return Err(TerrainError::InvalidProp {
                    reason: "the prop lies too far from the terrain's origin for its corners \
                             to be written as f32 world points"
                        .into(),
                });
            }
            points.push(point);
        }
        Ok(CarveTool::new(
            CarveShape::Hull(points),
            Transform::IDENTITY,
        ))
    }
}

fn invalid(reason: impl ToString) -> TerrainError {
    TerrainError::InvalidProp {
        reason: reason.to_string(),
    }
}

/// The scene's solid in normal form, placed by `pose`.
fn placed_dnf(scene: &Scene, pose: &Transform) -> Result<Dnf, TerrainError> {
    let mut dag = scene.dag.clone();
    let root = dag
        .transform(pose.to_matrix().as_dmat4(), scene.root)
        .map_err(invalid)?;
    Dnf::from_dag(&dag, root).map_err(invalid)
}

/// Refuses solids that are not one intersection of convex literals.
fn check_convex(scene: &Scene, dnf: &Dnf) -> Result<(), TerrainError> {
    let product = match dnf.products() {
        [] => return Err(invalid("its solid is empty")),
        [product] => product,
        products => {
            return Err(TerrainError::PropNotConvex {
                reason: format!(
                    "its solid is a union of {} intersections, which need not be convex",
                    products.len()
                ),
            });
        }
    };
    for &literal in product {
        let quadric = dnf.literal_quadric(literal);
        let least = SymmetricEigen::new(quadric.a()).min_value();
        if least < -EIGEN_SLACK * quadric.max_abs_coefficient() {
            let primitive = dnf.quadrics()[literal.quadric].primitive;
            let name = scene.names.get(primitive).map_or("?", String::as_str);
            return Err(TerrainError::PropNotConvex {
                reason: format!(
                    "the solid keeps the {} of primitive `{name}`, which is not convex \
                     (a cone, a hyperboloid, or the outside of a curved surface)",
                    match literal.side {
                        chisel_quadric::Side::Inside => "inside",
                        chisel_quadric::Side::Outside => "outside",
                    }
                ),
            });
        }
    }
    Ok(())
}

/// Where the ray from `from` (inside `K`) along `direction` leaves `K`.
fn exit(dnf: &Dnf, from: DVec3, direction: DVec3) -> Result<TraceHit, TerrainError> {
    let ray = Ray::new(from, direction).map_err(invalid)?;
    trace_ray(dnf, &ray, 0.0).ok_or_else(|| invalid("its solid is unbounded"))
}

/// A point inside `K`, about central: the mean of the midpoints of the
/// chords along the axes through the prop's origin or a quadric's centre,
/// whichever is inside.
fn interior_point(dnf: &Dnf, pose: &Transform) -> Result<DVec3, TerrainError> {
    let mut candidates = vec![pose.translation.as_dvec3()];
    for q in dnf.quadrics() {
        let a = q.quadric.a();
        let scale = q.quadric.max_abs_coefficient();
        if a.determinant().abs() > 1e-12 * scale * scale * scale {
            candidates.push(a.inverse() * -q.quadric.half_gradient(DVec3::ZERO));
        }
    }
    let start = candidates
        .into_iter()
        .find(|c| c.is_finite() && dnf.contains(*c))
        .ok_or_else(|| {
            invalid(
                "no point inside its solid was found at its origin or its quadrics' centres; \
                 model the prop around its origin",
            )
        })?;
    let mut sum = DVec3::ZERO;
    for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
        sum += (exit(dnf, start, axis)?.point + exit(dnf, start, -axis)?.point) * 0.5;
    }
    Ok(sum / 3.0)
}

/// The integer corners of the finest tangent-plane polyhedron needed to
/// meet `tolerance`.
fn fit_corners(
    dnf: &Dnf,
    centre: DVec3,
    tolerance: f64,
    quantization: &Quantization,
) -> Result<Vec<[i64; 3]>, TerrainError> {
    let mut best = f64::INFINITY;
    // A polyhedron of `F` tangent planes has about `2F` corners.
    let mut frequency = 1;
    while 2 * geodesic_point_count(frequency) <= MAX_ROUND_CORNERS {
        let mut samples = Vec::new();
        for u in geodesic_sphere(frequency).points {
            let hit = exit(dnf, centre, DVec3::from_array(u))?;
            if hit.normal != DVec3::ZERO {
                samples.push(hit);
            }
        }
        frequency += 1;
        let Some(corners) = tangent_polyhedron(&samples, quantization)? else {
            continue;
        };
        if corners.len() > MAX_ROUND_CORNERS {
            break;
        }
        let deviation = corners
            .iter()
            .map(|g| {
                let world = DVec3::from_array(quantization.to_world(g.map(|v| v as f64)));
                distance_bound(dnf, world, centre, &samples)
            })
            .fold(0.0, f64::max);
        if deviation <= tolerance {
            return Ok(corners);
        }
        best = deviation;
    }
    if best.is_infinite() {
        return Err(invalid(
            "its tangent planes close no bounded polyhedron (is the solid unbounded?)",
        ));
    }
    Err(chisel_bsp::Error::ToleranceUnreachable {
        tolerance,
        best,
        max_points: MAX_ROUND_CORNERS,
    }
    .into())
}

/// The rounded corners of the box cut by the tangent planes at `samples`,
/// each moved out to leave room for rounding; `None` when the result
/// reaches the box (the planes close nothing smaller).
fn tangent_polyhedron(
    samples: &[TraceHit],
    quantization: &Quantization,
) -> Result<Option<Vec<[i64; 3]>>, TerrainError> {
    let unit = quantization.unit();
    let origin = DVec3::from_array(quantization.origin());
    let on_grid = |w: DVec3| (w - origin) / unit;
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for s in samples {
        lo = lo.min(on_grid(s.point));
        hi = hi.max(on_grid(s.point));
    }
    let grow = (hi - lo).max_element() + 8.0;
    let (min, max) = ((lo - grow).floor(), (hi + grow).ceil());
    let to_int = |v: DVec3| IntPoint::from_array(v.to_array().map(|x| x as i64));
    let mut arena = ConvexArena::new();
    let mut poly = arena.add_box(to_int(min)?, to_int(max)?)?;
    // Rounding the normal to `N = S·n + e` (`|e| ≤ √3/2`) adds `e·(x − s)`,
    // at most `√3/2` times the box's diagonal, to `N·x` inside the box;
    // moving out by `δ` takes `|S·n|·δ ≤ (|N| + 1)·δ`; one more step
    // covers the `f64` error of `N·s` (below `2^-5` here).
    let turn = 0.5 * 3f64.sqrt() * (max - min).length();
    for s in samples {
        let normal = (s.normal * NORMAL_SCALE).round();
        let n = normal.to_array().map(|v| v as i64);
        let offset =
            normal.dot(on_grid(s.point)) + turn + (normal.length() + 1.0) * GRID_ROUNDING + 1.0;
        let plane = Plane::new(n[0], n[1], n[2], -(offset.ceil() as i128))?;
        match arena.cut_keeping(poly, &plane, Part::Below, NO_TAG) {
            KeptOutcome::Cut(kept) => poly = kept,
            KeptOutcome::Below => {}
            // The plane is moved out past a point of the solid, so the
            // solid's point is below it; nothing can lie wholly above.
            KeptOutcome::Above => return Ok(None),
        }
    }
    let mut corners: Vec<[i64; 3]> = arena
        .vertices_of(poly)
        .into_iter()
        .map(|v| arena.position(v).map(|x| x.round() as i64))
        .collect();
    corners.sort_unstable();
    corners.dedup();
    let (min, max) = (min.to_array(), max.to_array());
    let touches_box = corners
        .iter()
        .any(|g| (0..3).any(|a| g[a] as f64 <= min[a] + 1.0 || g[a] as f64 >= max[a] - 1.0));
    Ok((!touches_box).then_some(corners))
}

/// An upper bound on the distance from `point` to `K`: the nearest of a
/// few points of `K` — where rays from `point` towards `centre` and
/// against the normal of the nearest sample enter it, and that sample.
fn distance_bound(dnf: &Dnf, point: DVec3, centre: DVec3, samples: &[TraceHit]) -> f64 {
    if dnf.contains(point) {
        return 0.0;
    }
    let entry = |direction: DVec3| {
        Ray::new(point, direction)
            .ok()
            .and_then(|ray| trace_ray(dnf, &ray, 0.0))
            .map_or(f64::INFINITY, |hit| hit.t)
    };
    let mut bound = entry((centre - point).normalize_or_zero());
    if let Some(nearest) = samples.iter().min_by(|a, b| {
        a.point
            .distance_squared(point)
            .total_cmp(&b.point.distance_squared(point))
    }) {
        bound = bound
            .min(nearest.point.distance(point))
            .min(entry(-nearest.normal));
    }
    bound
}
