//! Seeded random inputs shared by the property tests.

use chisel_quadric::Quadric;
use glam::{DMat4, DQuat, DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::HashMap;

use chisel_quadric::SampleSet;

/// A deterministic generator for test `seed`.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A uniform point in the cube `[-h, h]³`.
pub fn point(rng: &mut ChaCha8Rng, h: f64) -> DVec3 {
    DVec3::new(
        rng.random_range(-h..h),
        rng.random_range(-h..h),
        rng.random_range(-h..h),
    )
}

/// A uniform unit vector.
pub fn unit(rng: &mut ChaCha8Rng) -> DVec3 {
    loop {
        let v = point(rng, 1.0);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// A uniform rotation.
pub fn rotation(rng: &mut ChaCha8Rng) -> DQuat {
    let axis = unit(rng);
    DQuat::from_axis_angle(axis, rng.random_range(0.0..std::f64::consts::TAU))
}

/// A random affine map: rotation, per-axis scale in `[0.3, 3]`, a shear and
/// a translation in `[-2, 2]³`.
pub fn affine(rng: &mut ChaCha8Rng) -> DMat4 {
    let scale = DVec3::new(
        rng.random_range(0.3..3.0),
        rng.random_range(0.3..3.0),
        rng.random_range(0.3..3.0),
    );
    let mut shear = DMat4::IDENTITY;
    shear.y_axis.x = rng.random_range(-0.5..0.5);
    let trs = DMat4::from_scale_rotation_translation(scale, rotation(rng), point(rng, 2.0));
    trs * shear
}

/// A rigid motion (rotation and translation).
pub fn rigid(rng: &mut ChaCha8Rng) -> DMat4 {
    DMat4::from_rotation_translation(rotation(rng), point(rng, 2.0))
}

/// The kinds of quadric the generators produce.
pub const KINDS: usize = 12;

/// A quadric of kind `kind % KINDS`, roughly of unit size near the origin,
/// randomly placed.
pub fn quadric_of_kind(rng: &mut ChaCha8Rng, kind: usize) -> Quadric {
    let r = |rng: &mut ChaCha8Rng| rng.random_range(0.4..1.5);
    let c = point(rng, 0.5);
    let base = match kind % KINDS {
        0 => Quadric::sphere(c, r(rng)),
        1 => Quadric::ellipsoid(c, DVec3::new(r(rng), r(rng), r(rng))),
        2 => Quadric::half_space(unit(rng), rng.random_range(-0.5..0.5)),
        3 => Quadric::cylinder(c, unit(rng), r(rng)),
        4 => Quadric::elliptic_cylinder(DVec2::new(r(rng), r(rng))),
        5 => Quadric::cone(c, unit(rng), rng.random_range(0.2..1.2)),
        6 => Quadric::elliptic_cone(DVec2::new(r(rng), r(rng))),
        7 => Quadric::elliptic_paraboloid(DVec2::new(r(rng), r(rng))),
        8 => Quadric::hyperbolic_paraboloid(DVec2::new(r(rng), r(rng))),
        9 => Quadric::hyperboloid_one_sheet(DVec3::new(r(rng), r(rng), r(rng))),
        10 => Quadric::hyperboloid_two_sheets(DVec3::new(r(rng), r(rng), r(rng))),
        _ => {
            let mut k = [0.0; 10];
            for x in &mut k {
                *x = rng.random_range(-1.0..1.0);
            }
            Quadric::from_coefficients(k)
        }
    }
    .expect("generated parameters are valid");
    base.transformed(&rigid(rng))
        .expect("rigid motions are invertible")
}

/// A random quadric of any kind.
pub fn quadric(rng: &mut ChaCha8Rng) -> Quadric {
    let kind = rng.random_range(0..KINDS);
    quadric_of_kind(rng, kind)
}

/// Loads a shipped scene from `assets/scenes/NAME.quadric.ron`.
pub fn scene(name: &str) -> chisel_quadric::Scene {
    let path = format!(
        "{}/../assets/scenes/{name}.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    chisel_quadric::Scene::load(&path).expect("shipped scenes parse")
}

/// Cameras on a ring and the two poles around `centre` at `distance`.
pub fn cameras(centre: DVec3, distance: f64, size: u32) -> Vec<chisel_quadric::Camera> {
    let mut dirs: Vec<DVec3> = (0..6)
        .map(|i| {
            let a = f64::from(i) * std::f64::consts::TAU / 6.0 + 0.3;
            DVec3::new(a.cos(), a.sin(), 0.45 * if i % 2 == 0 { 1.0 } else { -1.0 })
        })
        .collect();
    dirs.push(DVec3::new(0.1, 0.2, 1.0));
    dirs.push(DVec3::new(-0.2, 0.1, -1.0));
    dirs.into_iter()
        .map(|d| {
            chisel_quadric::Camera::new(centre + d.normalize() * distance, centre, 40.0, size, size)
                .expect("valid camera")
        })
        .collect()
}

/// Sample positions and radii per `(quadric, grid cell)`.
pub type Buckets = HashMap<(u32, [i64; 3]), Vec<(DVec3, f64)>>;

/// The largest distance between a point `p` and its nearest `f32`s, from
/// the stored `f32` point (`2⁻²⁴` of each coordinate's magnitude, twice
/// over: `p` is within that much of the stored point, whose coordinates
/// are within a factor `1 + 2⁻²⁴` of its own).
pub fn f32_rounding(stored: DVec3) -> f64 {
    2.0 * stored.abs().element_sum() * 2f64.powi(-24)
}

/// The largest stored radius a sample of `set` may have: the splat radius
/// plus the rounding of a position in the bounding sphere's box to `f32`
/// (`chisel_quadric::sampling::storage`), rounded up.
pub fn largest_radius(set: &SampleSet) -> f64 {
    let b = set.options.bounds;
    let corner = b.centre.abs() + b.radius;
    set.options.radius + f32_rounding(corner) + f64::from(f32::EPSILON) * set.options.radius
}

/// Samples bucketed by quadric and grid cell of size `cell`.
pub struct SampleGrid {
    cell: f64,
    buckets: Buckets,
}

impl SampleGrid {
    fn key(&self, p: DVec3) -> [i64; 3] {
        let k = (p / self.cell).floor();
        #[allow(clippy::cast_possible_truncation)]
        [k.x as i64, k.y as i64, k.z as i64]
    }

    /// Buckets the samples of `set` in cells of size `cell`.
    pub fn new(set: &SampleSet, cell: f64) -> Self {
        let mut grid = Self {
            cell,
            buckets: HashMap::new(),
        };
        for s in &set.samples {
            let key = grid.key(s.position.as_dvec3());
            grid.buckets
                .entry((set.patch_of(s).quadric, key))
                .or_default()
                .push((s.position.as_dvec3(), f64::from(s.radius)));
        }
        grid
    }

    /// Whether some sample of `quadric` covers `p` (within its own radius).
    pub fn covered(&self, quadric: u32, p: DVec3, slack: f64) -> bool {
        let k = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = (quadric, [k[0] + dx, k[1] + dy, k[2] + dz]);
                    let near = self
                        .buckets
                        .get(&key)
                        .is_some_and(|v| v.iter().any(|(s, r)| s.distance(p) <= r * (1.0 + slack)));
                    if near {
                        return true;
                    }
                }
            }
        }
        false
    }
}
