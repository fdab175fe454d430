//! Splat output (§6): clip lists are exactly the nearby literals of the
//! sample's own product, deduplicated; box extents are bounded; local
//! clipping keeps every traced surface point under some covering splat.

use crate::common;

use std::collections::HashSet;

use chisel_quadric::{
    BoundingSphere, INDEX_MASK, NO_HIT, OUTSIDE_FLAG, QuadricDistance, SampleOptions, SplatSet,
    sample, trace_image,
};
use glam::DVec3;

const SCENES: [(&str, [f64; 3], f64); 4] = [
    ("three_spheres", [0.0, 0.0, 10.0], 75.0),
    ("classic", [0.0, 0.0, 0.0], 90.0),
    ("sharp8", [0.0, 0.0, 0.0], 60.0),
    ("machine80", [0.0, 0.0, 35.0], 110.0),
];

#[test]
fn splat_buffers_are_consistent_and_clip_correctly() {
    for (name, centre, bound) in SCENES {
        let scene = common::scene(name);
        let dnf = scene.dnf().unwrap();
        let sphere = BoundingSphere::new(DVec3::from(centre), bound).unwrap();
        let radius = bound / 15.0;
        let set = sample(&dnf, &SampleOptions::new(radius, sphere).unwrap()).unwrap();
        let splats = SplatSet::new(&dnf, &scene.dag, &set);
        assert_eq!(splats.splats.len(), set.samples.len());
        assert_eq!(splats.quadrics.len(), dnf.quadrics().len());
        let distances: Vec<_> = dnf
            .quadrics()
            .iter()
            .map(|q| QuadricDistance::new(&q.quadric))
            .collect();
        let mut lists = HashSet::new();
        for (splat, s) in splats.splats.iter().zip(&set.samples) {
            assert_eq!(splat.quadric & INDEX_MASK, set.patch_of(s).quadric);
            assert!(splat.normal_extent >= 0.0 && splat.normal_extent <= splat.radius);
            assert!(splat.tangent_extent.max_element() <= splat.radius);
            assert!(splat.tangent_extent.min_element() >= 0.0);
            assert!(splat.tangent.dot(splat.normal).abs() < 1e-9);
            assert!((splat.tangent.length() - 1.0).abs() < 1e-12);
            let start = splat.clip_start as usize;
            let list = &splats.clip_indices[start..start + splat.clip_count as usize];
            assert!(list.windows(2).all(|w| w[0] < w[1]));
            let product = &dnf.products()[set.patch_of(s).product as usize];
            let expect: Vec<u32> = product
                .iter()
                .enumerate()
                .filter(|(j, l)| {
                    *j != set.patch_of(s).literal as usize
                        && distances[l.quadric].distance(s.position.as_dvec3()).abs()
                            < f64::from(s.radius)
                })
                .map(|(_, l)| {
                    let q = l.quadric as u32;
                    if l.side == chisel_quadric::Side::Outside {
                        q | OUTSIDE_FLAG
                    } else {
                        q
                    }
                })
                .collect();
            let mut expect = expect;
            expect.sort_unstable();
            assert_eq!(list, &expect[..], "{name}");
            if !list.is_empty() {
                lists.insert((splat.clip_start, splat.clip_count));
            }
        }
        // Deduplicated: every stored list is distinct.
        let distinct: HashSet<&[u32]> = lists
            .iter()
            .map(|&(s, c)| &splats.clip_indices[s as usize..(s + c) as usize])
            .collect();
        assert_eq!(distinct.len(), lists.len(), "{name}");
        // The scaled f32 coefficients keep the sign of every quadric at the splats.
        for (splat, s) in splats.splats.iter().zip(&set.samples).take(200) {
            let k = splats.quadrics[set.patch_of(s).quadric as usize].scaled_coefficients();
            let p = splat.position + splat.normal * radius;
            let exact = dnf.quadrics()[set.patch_of(s).quadric as usize]
                .quadric
                .value(p);
            let h = p.as_vec3();
            let v = k[0] * h.x * h.x
                + 2.0 * k[1] * h.x * h.y
                + 2.0 * k[2] * h.x * h.z
                + 2.0 * k[3] * h.x
                + k[4] * h.y * h.y
                + 2.0 * k[5] * h.y * h.z
                + 2.0 * k[6] * h.y
                + k[7] * h.z * h.z
                + 2.0 * k[8] * h.z
                + k[9];
            assert!(exact == 0.0 || (v > 0.0) == (exact > 0.0) || v.abs() < 1e-3);
        }
        // Local clipping keeps traced surface points (pixel-perfect rendering).
        for camera in common::cameras(DVec3::from(centre), 2.5 * bound, 24) {
            let image = trace_image(&dnf, &camera);
            for (i, &q) in image.quadric.iter().enumerate() {
                if q == NO_HIT {
                    continue;
                }
                let ray = camera.ray(i as u32 % camera.width, i as u32 / camera.width);
                let p = ray.at(image.depth[i]);
                if sphere.signed_distance(p) > -1e-9 * bound {
                    continue;
                }
                // Nudge inside the solid by a hair: the point then satisfies
                // every literal strictly, except at edges it lies on.
                let inner = p - image.normal[i] * 1e-9 * bound;
                let kept = |boxed: bool| {
                    splats.splats.iter().any(|sp| {
                        sp.quadric & INDEX_MASK == q
                            && sp.position.distance(p) <= sp.radius
                            && (!boxed || sp.box_holds(p, 1.0 + 1e-9))
                            && splats.keeps(sp, inner)
                    })
                };
                assert!(
                    kept(false),
                    "{name}: traced point {p} clipped by every covering splat"
                );
                // The renderer rasterizes the boxes: one of them holds it.
                assert!(kept(true), "{name}: traced point {p} outside every box");
            }
        }
    }
}

/// Each splat's box holds the surface it covers: the lifted points of its
/// cell (a 9 × 9 grid over the plane box `uv ± cell`) within its radius,
/// at the renderer's default radius (bounds ÷ 40).
#[test]
fn every_splat_box_holds_the_surface_over_its_cell() {
    for (name, centre, bound) in SCENES {
        let scene = common::scene(name);
        let dnf = scene.dnf().unwrap();
        let sphere = BoundingSphere::new(DVec3::from(centre), bound).unwrap();
        let set = sample(&dnf, &SampleOptions::new(bound / 40.0, sphere).unwrap()).unwrap();
        let splats = SplatSet::new(&dnf, &scene.dag, &set);
        let (mut checked, mut tight) = (0_usize, 0_usize);
        for (splat, s) in splats.splats.iter().zip(&set.samples) {
            let hf = &set.patches[s.patch as usize].heightfield;
            let r = f64::from(s.radius);
            let half = s.cell.as_dvec2().min(glam::DVec2::splat(r));
            if !half.is_finite() {
                continue;
            }
            tight += usize::from(splat.tangent_extent.max_element() < splat.radius);
            for i in 0..=8 {
                for j in 0..=8 {
                    let f = glam::DVec2::new(f64::from(i) / 4.0 - 1.0, f64::from(j) / 4.0 - 1.0);
                    let Some(p) = hf.point(set.uv_of(s) + half * f) else {
                        continue;
                    };
                    if p.distance(s.position.as_dvec3()) > r {
                        continue;
                    }
                    checked += 1;
                    assert!(
                        splat.box_holds(p, 1.0 + 1e-9),
                        "{name}: {p} over the cell of the splat at {} outside its box {:?}",
                        splat.position,
                        (splat.tangent_extent, splat.normal_extent)
                    );
                }
            }
        }
        println!(
            "{name}: {checked} cell points in their boxes; {tight} of {} boxes narrower than the sphere's",
            splats.splats.len()
        );
        assert!(
            tight > splats.splats.len() / 2,
            "{name}: the cells bound most boxes"
        );
    }
}
