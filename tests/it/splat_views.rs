//! The splat pass under mirroring transforms and with per-camera settings,
//! headless on the machine's Vulkan adapter (lavapipe in CI), against the
//! CPU reference tracer with the thresholds of `tests/it/splat_render.rs`
//! (≥ 99.5 % of the pixels agree, ≤ 0.1 % holes).
//!
//! A prop scaled by `(−1, 1, 1)` seen from the mirror image `M·eye` of the
//! comparison eye must be the reference image of the unmirrored scene from
//! `eye`, left and right swapped (the reference camera's rays through the
//! pixel columns `x` and `width − 1 − x` are mirror images): same quadric
//! ids, normals mirrored by `x → −x`. A prop stretched unevenly and
//! rotated is compared with the reference tracer of its scene under the
//! same affine map.

use crate::common;

use bevy::math::DQuat;
use bevy::math::{DMat4, DVec3};
use bevy::prelude::*;
use bevy_chisel::splat::{SplatMode, SplatOutput, SplatSettings, SplatViewSettings};
use common::{
    Agreement, Placement, SCALE, View, compare_ids, compare_normals, eye, id_settings, load_scene,
    reference, render_views, scene_entry, scene_splats,
};

const SIZE: u32 = 256;

/// `x → −x`.
const MIRROR: DVec3 = DVec3::new(-1.0, 1.0, 1.0);

fn own(settings: SplatSettings) -> Option<SplatViewSettings> {
    Some(SplatViewSettings(settings))
}

fn check(failures: &mut Vec<String>, what: String, a: &Agreement) {
    println!(
        "{what}: {:.3} % agree, {:.3} % holes, {} covered px",
        100.0 * a.agree_fraction(),
        100.0 * a.hole_fraction(),
        a.covered
    );
    if !a.passes() {
        failures.push(format!("{what}: {a:?}"));
    }
}

#[test]
fn a_mirrored_prop_is_drawn_as_the_mirror_image_of_its_scene() {
    // Open boxes (the default) from the resource; closed boxes, global ray
    // tracing and normals from the cameras' own settings; and global ray
    // tracing again from an eye inside the proxy cube (which draws the
    // cube's far faces: the ones culling keeps).
    let views = [
        None,
        own(SplatSettings {
            open_boxes: false,
            ..id_settings(SplatMode::SurfaceBoxes)
        }),
        own(id_settings(SplatMode::GlobalRayTrace)),
        own(SplatSettings {
            output: SplatOutput::Normals,
            ..default()
        }),
        own(id_settings(SplatMode::GlobalRayTrace)),
    ];
    let mut failures = Vec::new();
    for name in ["sharp8", "three_spheres"] {
        let (name, centre, radius) = scene_entry(name);
        let scene = load_scene(name);
        let eye = eye(centre, radius);
        let expected = reference(&scene, eye, centre, SIZE);
        let near_eye = centre + DVec3::new(0.75, -0.6, 0.55) * radius;
        assert!(
            (near_eye - centre).abs().max_element() < radius
                && !scene.dnf().expect("normal form").contains(near_eye),
            "{name}: the near eye is inside the proxy cube and outside the solid"
        );
        let expected_near = reference(&scene, near_eye, centre, SIZE);
        let cameras: Vec<View> = (0..views.len())
            .map(|i| View {
                eye: (MIRROR * if i == 4 { near_eye } else { eye }).as_vec3() * SCALE,
                centre: (MIRROR * centre).as_vec3() * SCALE,
                settings: views[i],
                msaa: Msaa::Off,
            })
            .collect();
        let image = render_views(
            scene_splats(&scene, centre, radius),
            Transform::from_scale(MIRROR.as_vec3() * SCALE),
            id_settings(SplatMode::SurfaceBoxes),
            &cameras,
            SIZE,
        );
        let at = |i: u32| Placement {
            x_offset: i * SIZE,
            mirrored: true,
        };
        check(
            &mut failures,
            format!("{name} mirrored, open boxes"),
            &compare_ids(&expected, &image, at(0)),
        );
        check(
            &mut failures,
            format!("{name} mirrored, closed boxes"),
            &compare_ids(&expected, &image, at(1)),
        );
        check(
            &mut failures,
            format!("{name} mirrored, global ray tracing"),
            &compare_ids(&expected, &image, at(2)),
        );
        check(
            &mut failures,
            format!("{name} mirrored, normals"),
            &compare_normals(&expected, &image, at(3)),
        );
        check(
            &mut failures,
            format!("{name} mirrored, global ray tracing, eye inside the proxy"),
            &compare_ids(&expected_near, &image, at(4)),
        );
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn each_camera_draws_with_its_own_settings() {
    // Left: no settings of its own, so the resource's ids. Middle: normals
    // from screen quads. Right: the global pass's proxy cube.
    let (name, centre, radius) = scene_entry("classic");
    let scene = load_scene(name);
    let eye = eye(centre, radius);
    let expected = reference(&scene, eye, centre, SIZE);
    let view = |settings| View {
        eye: eye.as_vec3() * SCALE,
        centre: centre.as_vec3() * SCALE,
        settings,
        msaa: Msaa::Off,
    };
    let cameras = [
        view(None),
        view(own(SplatSettings {
            mode: SplatMode::ScreenQuads,
            output: SplatOutput::Normals,
            ..default()
        })),
        view(own(SplatSettings {
            mode: SplatMode::GlobalRayTrace,
            output: SplatOutput::Bounds,
            ..default()
        })),
    ];
    let image = render_views(
        scene_splats(&scene, centre, radius),
        Transform::from_scale(Vec3::splat(SCALE)),
        id_settings(SplatMode::SurfaceBoxes),
        &cameras,
        SIZE,
    );
    let at = |i: u32| Placement {
        x_offset: i * SIZE,
        mirrored: false,
    };
    let mut failures = Vec::new();
    check(
        &mut failures,
        "left: the resource's ids".into(),
        &compare_ids(&expected, &image, at(0)),
    );
    check(
        &mut failures,
        "middle: its own normals".into(),
        &compare_normals(&expected, &image, at(1)),
    );
    assert!(failures.is_empty(), "{failures:#?}");

    // The proxy cube: one flat blue, shaded per face, over every pixel the
    // prop covers and well beyond its silhouette.
    let (mut cube, mut cube_over_prop, mut covered) = (0, 0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let c = image
                .get_color_at(2 * SIZE + x, y)
                .expect("pixel inside the image")
                .to_srgba()
                .to_u8_array();
            let blue = c[2] > c[1] && c[1] > c[0] && c[0] > 40;
            let prop = expected.quadric[(y * SIZE + x) as usize] != bevy_chisel::quadric::NO_HIT;
            cube += usize::from(blue);
            covered += usize::from(prop);
            cube_over_prop += usize::from(blue && prop);
        }
    }
    println!("right: {cube} px of proxy cube, {cube_over_prop} of {covered} prop px under it");
    assert_eq!(cube_over_prop, covered, "the proxy cube covers the prop");
    assert!(
        cube as f64 > 1.2 * covered as f64,
        "the proxy cube reaches beyond the prop: {cube} px against {covered}"
    );
}

#[test]
fn a_stretched_and_rotated_prop_matches_the_reference_tracer() {
    // Non-uniform scale under a rotation: the normals need the inverse
    // transpose, and the screen quads the map's largest stretch (1.4).
    let (name, centre, radius) = scene_entry("classic");
    let mut scene = load_scene(name);
    let splats = scene_splats(&scene, centre, radius);
    let rotation = DQuat::from_euler(EulerRot::ZXY, 0.5, 0.25, -0.3);
    let stretch = DVec3::new(1.4, 0.6, 1.0);
    let affine = DMat4::from_scale_rotation_translation(stretch, rotation, DVec3::ZERO);
    scene.root = scene
        .dag
        .transform(affine, scene.root)
        .expect("an invertible map");
    let moved_centre = affine.transform_point3(centre);
    let eye = eye(moved_centre, radius * stretch.max_element());
    let expected = reference(&scene, eye, moved_centre, SIZE);
    let view = |settings| View {
        eye: eye.as_vec3() * SCALE,
        centre: moved_centre.as_vec3() * SCALE,
        settings,
        msaa: Msaa::Off,
    };
    let cameras = [
        view(None),
        view(own(id_settings(SplatMode::ScreenQuads))),
        view(own(id_settings(SplatMode::GlobalRayTrace))),
        view(own(SplatSettings {
            output: SplatOutput::Normals,
            ..default()
        })),
    ];
    let image = render_views(
        splats,
        Transform {
            rotation: rotation.as_quat(),
            scale: stretch.as_vec3() * SCALE,
            ..default()
        },
        id_settings(SplatMode::SurfaceBoxes),
        &cameras,
        SIZE,
    );
    let at = |i: u32| Placement {
        x_offset: i * SIZE,
        mirrored: false,
    };
    let mut failures = Vec::new();
    for (i, what) in ["surface boxes", "screen quads", "global ray tracing"]
        .into_iter()
        .enumerate()
    {
        check(
            &mut failures,
            format!("{name} stretched, {what}"),
            &compare_ids(&expected, &image, at(i as u32)),
        );
    }
    check(
        &mut failures,
        format!("{name} stretched, normals"),
        &compare_normals(&expected, &image, at(3)),
    );
    assert!(failures.is_empty(), "{failures:#?}");
}
