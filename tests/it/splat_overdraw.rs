//! The overdraw outputs of the splat pass, headless on the machine's
//! Vulkan adapter (lavapipe in CI): `Overdraw` counts every proxy fragment,
//! `DepthTestedOverdraw` those that pass the depth test after a depth
//! prepass of the splats. Three cameras see one prop: quadric ids (which
//! pixels show the solid), then the two counts, 1/64 per fragment added
//! up in the capture's linear colour (8-bit sRGB: exact for no fragment
//! and for one, within a fraction of a count for a few; the splat bench
//! reads exact counts from a float target).

use crate::common;

use bevy::prelude::*;
use bevy_chisel::splat::{SplatOutput, SplatSettings, SplatViewSettings};
use common::{
    Pixel, SCALE, View, classify, eye, load_scene, render_views, scene_entry, scene_splats,
};

const SIZE: u32 = 256;

/// The fragment count at a pixel of an overdraw view (`1/64` each, in
/// the red channel), and how far its decoded value lies from a whole count.
fn count(image: &Image, x: u32, y: u32) -> (u32, f32) {
    let c = image
        .get_color_at(x, y)
        .expect("pixel inside the image")
        .to_linear();
    let k = c.red * 64.0;
    (k.round() as u32, (k - k.round()).abs())
}

/// Every pixel that shows the solid counts at least one depth-tested
/// fragment (the visible surface's own proxy lies at or in front of it),
/// never more than the untested count, and the depth test rejects the
/// proxies behind the front surface: fewer fragments in all.
#[test]
fn depth_tested_overdraw_keeps_the_front_and_rejects_hidden_proxies() {
    for name in ["three_spheres", "machine80"] {
        let (name, centre, radius) = scene_entry(name);
        let scene = load_scene(name);
        let splats = scene_splats(&scene, centre, radius);
        let view = |output| View {
            eye: eye(centre, radius).as_vec3() * SCALE,
            centre: centre.as_vec3() * SCALE,
            settings: Some(SplatViewSettings(SplatSettings {
                output,
                ..default()
            })),
            msaa: Msaa::Off,
        };
        let image = render_views(
            splats,
            Transform::from_scale(Vec3::splat(SCALE)),
            SplatSettings::default(),
            &[
                view(SplatOutput::QuadricIds),
                view(SplatOutput::Overdraw),
                view(SplatOutput::DepthTestedOverdraw),
            ],
            SIZE,
        );
        let (mut covered, mut untested, mut tested, mut worst) = (0_u64, 0_u64, 0_u64, 0.0_f32);
        let mut uncounted = 0_u64;
        for y in 0..SIZE {
            for x in 0..SIZE {
                let (all, off_all) = count(&image, x + SIZE, y);
                let (front, off_front) = count(&image, x + 2 * SIZE, y);
                worst = worst.max(off_all).max(off_front);
                assert!(
                    front <= all + 1,
                    "{name} ({x}, {y}): {front} depth-tested fragments, {all} in all"
                );
                untested += u64::from(all);
                tested += u64::from(front);
                if matches!(classify(&image, x, y), Pixel::Quadric(_)) {
                    covered += 1;
                    uncounted += u64::from(front == 0);
                }
            }
        }
        println!(
            "{name}: {covered} covered px, {:.2} fragments per covered px, {:.2} depth-tested",
            untested as f64 / covered as f64,
            tested as f64 / covered as f64
        );
        // The capture is 8-bit sRGB: each blend rounds the running sum,
        // so counts decode to whole numbers only roughly.
        println!("{name}: decoded counts within {worst:.2} of whole numbers");
        assert_eq!(
            uncounted, 0,
            "{name}: covered pixels without a depth-tested fragment"
        );
        assert!(covered > 1000, "{name}: the prop is in view");
        assert!(
            tested < untested,
            "{name}: the depth test rejects hidden proxies"
        );
    }
}
