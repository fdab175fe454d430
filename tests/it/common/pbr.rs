//! Comparison of a prop with a `StandardMaterial` mesh in one headless
//! image: the prop in the left half, the mesh mirrored in the right half
//! (the scene mirror symmetric about the image's centre column), over the
//! pixels both cover away from their silhouettes.

use bevy::core_pipeline::tonemapping::DebandDither;
use bevy::prelude::*;
use bevy_chisel::quadric::Scene;
use bevy_chisel::splat::{PropBounds, PropSplats};

/// One sphere of radius 50 scene units, in the comparison colour.
pub const SPHERE_SCENE: &str = "Scene(
    primitives: [
        (name: \"S\", shape: Sphere(center: (0, 0, 0), radius: 50), color: (0.8, 0.3, 0.2)),
    ],
    root: Ref(\"S\"),
    bounds: (0, 0, 0, 60),
)";

/// The splats of [`SPHERE_SCENE`] at radius 2 scene units.
pub fn sphere_splats() -> PropSplats {
    let scene = Scene::from_ron(SPHERE_SCENE).expect("sphere scene");
    let bounds = PropBounds {
        centre: Vec3::ZERO,
        radius: 60.0,
    };
    PropSplats::build(&scene, bounds, 2.0).expect("sampling")
}

/// The lights and camera of a mirrored comparison: a directional and a
/// point light without shadows, symmetric about the image's centre
/// column, and a camera on −y looking at the origin with +z up.
pub fn spawn_comparison_lights_and_camera(commands: &mut Commands) {
    commands.spawn((
        DirectionalLight {
            illuminance: 2000.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(0.0, -1.0, 1.5).looking_at(Vec3::ZERO, Vec3::Z),
    ));
    commands.spawn((
        PointLight {
            intensity: 200_000.0,
            range: 50.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(0.0, -3.0, -0.5),
    ));
    commands.spawn((
        Camera3d::default(),
        DebandDither::Disabled,
        Msaa::Off,
        Transform::from_xyz(0.0, -6.0, 0.0).looking_at(Vec3::ZERO, Vec3::Z),
    ));
}

/// sRGB byte to linear.
pub fn linear(c: u8) -> f64 {
    let c = f64::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Byte differences of one pair of spheres over the pixels both cover
/// away from their silhouettes.
#[derive(Debug)]
pub struct SphereDifference {
    /// Pixels compared.
    pub pixels: usize,
    /// Mean linear colour of the prop and of the mesh.
    pub means: [[f64; 3]; 2],
    /// Mean of the largest channel difference per pixel, in sRGB bytes.
    pub mean_bytes: f64,
    /// 99th percentile of the same, in sRGB bytes.
    pub p99_bytes: u8,
}

impl SphereDifference {
    /// Per channel, how far the prop's mean linear colour is from the
    /// mesh's, relative to the mesh's.
    pub fn mean_relative(&self) -> [f64; 3] {
        std::array::from_fn(|ch| {
            (self.means[0][ch] - self.means[1][ch]).abs() / self.means[1][ch].max(1e-3)
        })
    }
}

/// Compares the prop in rows `rows` of the left half of an image `width`
/// pixels wide with the mirror image of the mesh in the right half.
pub fn compare_mirrored(image: &Image, width: u32, rows: std::ops::Range<u32>) -> SphereDifference {
    let bytes = |x: u32, y: u32| {
        image
            .get_color_at(x, y)
            .expect("pixel inside the image")
            .to_srgba()
            .to_u8_array()
    };
    let covered = |x: u32, y: u32| bytes(x, y)[..3].iter().any(|&v| v > 3);
    // Covered with all eight neighbours: away from the silhouette, where
    // the mesh's polygon edge and the exact sphere differ by a pixel.
    let inside = |x: u32, y: u32| {
        (x.saturating_sub(1)..=x + 1).all(|i| {
            (y.saturating_sub(1)..=y + 1).all(|j| i < width && rows.contains(&j) && covered(i, j))
        })
    };
    let (mut pixels, mut sums, mut diffs) = (0, [[0.0_f64; 3]; 2], Vec::new());
    for y in rows.clone() {
        for x in 0..width / 2 {
            let mirrored = width - 1 - x;
            if !inside(x, y) || !inside(mirrored, y) {
                continue;
            }
            let (prop, mesh) = (bytes(x, y), bytes(mirrored, y));
            pixels += 1;
            for ch in 0..3 {
                sums[0][ch] += linear(prop[ch]);
                sums[1][ch] += linear(mesh[ch]);
            }
            diffs.push(
                (0..3)
                    .map(|ch| prop[ch].abs_diff(mesh[ch]))
                    .max()
                    .unwrap_or(0),
            );
        }
    }
    diffs.sort_unstable();
    let n = pixels.max(1) as f64;
    SphereDifference {
        pixels,
        means: sums.map(|s| s.map(|v| v / n)),
        mean_bytes: diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / n,
        p99_bytes: diffs
            .get(diffs.len() * 99 / 100)
            .copied()
            .unwrap_or(u8::MAX),
    }
}

// Tolerances of the PBR comparison. Measured with lavapipe (320×256,
// 8529 px per sphere): mean colours 0.44–0.65 % apart, per-pixel
// difference 0.6–0.7 B on average, 2 B at the 99th percentile; what is
// left is the mesh's interpolated vertex normals against the exact ones.

/// Largest relative difference of the two spheres' mean linear colours.
pub const MAX_MEAN_RELATIVE: f64 = 0.015;
/// Largest mean per-pixel difference (sRGB bytes, largest channel).
pub const MAX_MEAN_BYTES: f64 = 1.5;
/// Largest 99th percentile of the per-pixel difference (sRGB bytes).
pub const MAX_P99_BYTES: u8 = 4;
