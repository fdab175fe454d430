//! Ray casts against a terrain, for aiming.
//!
//! The ray is walked through the octree front to back (only leaf cells
//! whose box it crosses, nearest first), and through each leaf's BSP front
//! to back: at a split the near side is visited before the far side, so the
//! first non-empty region reached is the hit.
//!
//! Precision: the regions are exact, the walk is not. Distances along the
//! ray are computed in `f64` from the planes' correctly rounded
//! coefficients ([`chisel_bsp::exact::Plane::approx`]), in grid units: the
//! hit point is within about `1e-6` grid units of the exact surface for
//! planes of ordinary size, and a ray that grazes an edge or a plane within
//! that distance may report the neighbouring face. Good for aiming and
//! picking; exact decisions stay in the kernel.

use bevy::math::{DVec3, Ray3d};
use bevy::prelude::*;
use chisel_bsp::octree::{CellBox, CellKey, Leaf, Octree};
use chisel_bsp::tree::{Bsp, EMPTY, Label, Node};

use super::component::Terrain;

/// Where a ray first meets a terrain's material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainHit {
    /// The hit point in the terrain's local frame.
    pub point: Vec3,
    /// Distance from the ray's origin, in world units.
    pub distance: f32,
    /// Unit normal of the surface hit, facing the ray (`−direction` when
    /// the ray starts inside material).
    pub normal: Vec3,
    /// The material hit.
    pub label: Label,
    /// The leaf cell hit.
    pub cell: CellKey,
}

/// A ray in grid units: `origin + t · direction`, `t` in world units.
struct GridRay {
    origin: DVec3,
    direction: DVec3,
}

impl GridRay {
    /// The `t` interval where the ray is inside `cell`, with the normal of
    /// the face it enters through.
    fn clip(&self, cell: &CellBox, t0: f64, t1: f64) -> Option<(f64, f64, DVec3)> {
        let (mut lo, mut hi) = (t0, t1);
        let mut normal = DVec3::ZERO;
        for a in 0..3 {
            let (o, d) = (self.origin[a], self.direction[a]);
            let (min, max) = (cell.min[a] as f64, cell.max[a] as f64);
            if d == 0.0 {
                if o < min || o > max {
                    return None;
                }
                continue;
            }
            let (mut near, mut far) = ((min - o) / d, (max - o) / d);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            if near > lo {
                lo = near;
                normal = DVec3::ZERO;
                normal[a] = -d.signum();
            }
            hi = hi.min(far);
        }
        (lo <= hi).then_some((lo, hi, normal))
    }
}

impl Terrain {
    /// The first point where `ray` (in the terrain's local frame) meets
    /// material within `max_distance`. See the module docs for precision.
    #[must_use]
    pub fn ray_cast(&self, ray: Ray3d, max_distance: f32) -> Option<TerrainHit> {
        let q = &self.quantization;
        let origin = DVec3::from_array(q.origin());
        let unit = q.unit();
        let direction = ray.direction.as_dvec3();
        let grid = GridRay {
            origin: (ray.origin.as_dvec3() - origin) / unit,
            direction: direction / unit,
        };
        let octree = &self.octree;
        let (t0, t1, n) = grid.clip(&octree.root_box(), 0.0, f64::from(max_distance))?;
        let normal = if t0 <= 0.0 { -direction } else { n };
        let (t, normal, label, cell) = walk(octree, &grid, CellKey::ROOT, t0, t1, normal)?;
        let local = ray.origin.as_dvec3() + direction * t;
        Some(TerrainHit {
            point: local.as_vec3(),
            distance: t as f32,
            normal: normal.normalize_or_zero().as_vec3(),
            label,
            cell,
        })
    }
}

type Hit = (f64, DVec3, Label, CellKey);

fn walk(octree: &Octree, ray: &GridRay, key: CellKey, t0: f64, t1: f64, n: DVec3) -> Option<Hit> {
    if let Some(leaf) = octree.leaf(key) {
        return match leaf {
            Leaf::Uniform(EMPTY) => None,
            Leaf::Uniform(label) => Some((t0, n, *label, key)),
            Leaf::Bsp(bsp) => bsp_walk(bsp, 0, ray, t0, t1, n).map(|(t, n, l)| (t, n, l, key)),
        };
    }
    let mut children: Vec<(f64, f64, DVec3, CellKey)> = (0..8)
        .filter_map(|i| {
            let child = key.child(i);
            let (lo, hi, normal) = ray.clip(&octree.cell_box(child), t0, t1)?;
            let normal = if lo <= t0 { n } else { normal };
            Some((lo, hi, normal, child))
        })
        .collect();
    children.sort_by(|a, b| a.0.total_cmp(&b.0));
    children
        .into_iter()
        .find_map(|(lo, hi, normal, child)| walk(octree, ray, child, lo, hi, normal))
}

fn bsp_walk(
    bsp: &Bsp,
    node: u32,
    ray: &GridRay,
    t0: f64,
    t1: f64,
    n: DVec3,
) -> Option<(f64, DVec3, Label)> {
    match bsp.nodes().get(node as usize)? {
        Node::Leaf(EMPTY) => None,
        Node::Leaf(label) => Some((t0, n, *label)),
        &Node::Split {
            plane,
            below,
            above,
        } => {
            let [a, b, c, d] = bsp.planes().get(plane as usize)?.approx();
            let normal = DVec3::new(a, b, c);
            let at = |t: f64| normal.dot(ray.origin + ray.direction * t) + d;
            let slope = normal.dot(ray.direction);
            let start = at(t0);
            let near_is_below = start < 0.0 || (start == 0.0 && slope < 0.0);
            let (near, far) = if near_is_below {
                (below, above)
            } else {
                (above, below)
            };
            let crossing = if slope == 0.0 {
                f64::INFINITY
            } else {
                -(normal.dot(ray.origin) + d) / slope
            };
            if !(crossing > t0 && crossing < t1) {
                return bsp_walk(bsp, near, ray, t0, t1, n);
            }
            if let Some(hit) = bsp_walk(bsp, near, ray, t0, crossing, n) {
                return Some(hit);
            }
            // Entering the far side through the plane: its normal faces
            // back along the ray.
            let facing = if slope > 0.0 { -normal } else { normal };
            bsp_walk(bsp, far, ray, crossing, t1, facing)
        }
    }
}
