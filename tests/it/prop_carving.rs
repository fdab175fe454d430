//! Carving quadric props at runtime, in an app without rendering
//! (`MinimalPlugins`): a world-space sphere cut from one prop becomes the
//! ellipsoid of its transform, only that instance changes (another prop
//! of the same scene asset keeps its splats), the splats are those of a
//! partial re-sample of the carved scene, and bad carves are refused with
//! their reason and change nothing.

use std::time::Duration;

use bevy::asset::AssetPlugin;
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::quadric::Scene;
use bevy_chisel::quadric::scene::carve::MAX_CARVES;
use bevy_chisel::splat::{
    CarveProp, CarveRefusal, ChiselSplatPlugin, PropBounds, PropCarveRefused, PropCarved,
    PropCarves, PropSplats, QuadricProp, QuadricScene, SplatRadius, SplatSystems,
};

use crate::ONE_APP_AT_A_TIME;

const RADIUS: SplatRadius = SplatRadius::Auto(40.0);

/// The carve messages seen so far.
#[derive(Resource, Default)]
struct Seen {
    carved: Vec<PropCarved>,
    refused: Vec<PropCarveRefused>,
}

fn collect(
    mut seen: ResMut<Seen>,
    mut carved: MessageReader<PropCarved>,
    mut refused: MessageReader<PropCarveRefused>,
) {
    seen.carved.extend(carved.read().copied());
    seen.refused.extend(refused.read().cloned());
}

fn app() -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin {
            file_path: format!("{}/assets", env!("CARGO_MANIFEST_DIR")),
            ..default()
        },
        TransformPlugin,
        ChiselSplatPlugin,
    ))
    .init_resource::<Seen>()
    .add_systems(Update, collect.after(SplatSystems::Sample));
    app
}

fn run_until(app: &mut App, what: &str, mut done: impl FnMut(&mut App) -> bool) {
    for _ in 0..20_000 {
        app.update();
        if done(app) {
            return;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    panic!("timed out waiting for {what}");
}

fn splats(app: &App, prop: Entity) -> Option<PropSplats> {
    app.world().get::<PropSplats>(prop).cloned()
}

fn spawn(app: &mut App, scene: &Handle<QuadricScene>, transform: Transform) -> Entity {
    app.world_mut()
        .spawn((
            QuadricProp {
                scene: scene.clone(),
                bounds: None,
                radius: RADIUS,
            },
            transform,
        ))
        .id()
}

fn matrix(app: &App, prop: Entity) -> bevy::math::DMat4 {
    app.world()
        .get::<GlobalTransform>(prop)
        .expect("transform")
        .to_matrix()
        .as_dmat4()
}

/// A world-space point on the prop's drawn surface: its middle splat.
fn surface_point(app: &App, prop: Entity) -> Vec3 {
    let s = splats(app, prop).expect("splats");
    let p = s.0.splats[s.0.splats.len() / 2].position.as_dvec3();
    matrix(app, prop).transform_point3(p).as_vec3()
}

fn refusals(app: &App, prop: Entity) -> Vec<CarveRefusal> {
    let seen = app.world().resource::<Seen>();
    seen.refused
        .iter()
        .filter(|r| r.prop == prop)
        .map(|r| r.reason.clone())
        .collect()
}

#[test]
fn a_carve_bites_into_one_prop_instance() {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = app();
    let scene: Handle<QuadricScene> = app
        .world()
        .resource::<AssetServer>()
        .load("scenes/machine80.quadric.ron");
    // Rotated, scaled non-uniformly and mirrored: the world sphere is an
    // ellipsoid in its frame.
    let carved = spawn(
        &mut app,
        &scene,
        Transform::from_xyz(300.0, 0.0, 0.0)
            .with_rotation(Quat::from_euler(EulerRot::XYZ, 0.3, -0.5, 0.8))
            .with_scale(Vec3::new(1.3, 0.8, -1.1)),
    );
    let other = spawn(&mut app, &scene, Transform::IDENTITY);
    run_until(&mut app, "the first splats", |app| {
        splats(app, carved).is_some() && splats(app, other).is_some()
    });
    let before = splats(&app, carved).expect("splats");
    let other_before = splats(&app, other).expect("splats");

    let centre = surface_point(&app, carved);
    let radius = 7.0;
    app.world_mut()
        .write_message(CarveProp::sphere(carved, centre, radius));
    // Frames until the carve is drawn: the old splats stay until then.
    let start = std::time::Instant::now();
    let mut frames = 0;
    let mut slowest = Duration::ZERO;
    run_until(&mut app, "the carved splats", |app| {
        frames += 1;
        let done = !app.world().resource::<Seen>().carved.is_empty();
        if !done {
            assert_eq!(
                splats(app, carved).expect("splats").0.generation,
                before.0.generation
            );
        }
        done
    });
    // The frame times, without the test's sleeps.
    let latency = start.elapsed();
    for _ in 0..3 {
        let t = std::time::Instant::now();
        app.update();
        slowest = slowest.max(t.elapsed());
    }
    eprintln!(
        "machine80, {} splats: carve drawn after {frames} frames, {:.1} ms (with the \
         test's 0.3 ms sleeps); later frames up to {:.2} ms",
        before.0.splat_count(),
        latency.as_secs_f64() * 1e3,
        slowest.as_secs_f64() * 1e3
    );
    assert_eq!(
        app.world().resource::<Seen>().carved,
        [PropCarved {
            prop: carved,
            carves: 1
        }]
    );
    assert!(refusals(&app, carved).is_empty());
    let after = splats(&app, carved).expect("splats");
    assert_ne!(after.0.generation, before.0.generation);
    assert_eq!(after.0.quadrics.len(), before.0.quadrics.len() + 1);
    // The other instance of the same asset is untouched.
    assert_eq!(
        splats(&app, other).expect("splats").0.generation,
        other_before.0.generation
    );
    assert!(
        app.world()
            .get::<PropCarves>(other)
            .expect("carves")
            .carves()
            .is_empty()
    );

    // No splat lies inside the world sphere, and the bite has splats on it.
    let m = matrix(&app, carved);
    let (c, r) = (centre.as_dvec3(), f64::from(radius));
    let mut on_sphere = 0;
    for s in &after.0.splats {
        let d = (m.transform_point3(s.position.as_dvec3()) - c).length();
        assert!(d > r * (1.0 - 1e-5), "a splat {d} from the centre");
        if (d - r).abs() < r * 1e-5 {
            on_sphere += 1;
        }
    }
    assert!(on_sphere > 10, "{on_sphere} splats on the bite");

    // The tool is the world sphere in the prop's frame, and the splats
    // are a partial re-sample of the scene carved by it, exactly.
    let carves = app
        .world()
        .get::<PropCarves>(carved)
        .expect("carves")
        .clone();
    assert_eq!((carves.carves().len(), carves.drawn()), (1, 1));
    let tool = carves.carves()[0].tool;
    let inverse = m.inverse();
    for k in 0..40 {
        let t = f64::from(k) * 0.41;
        let dir = DVec3::new(
            t.cos() * (1.7 * t).sin(),
            t.sin() * (1.7 * t).sin(),
            (1.7 * t).cos(),
        );
        let local = inverse.transform_point3(c + r * dir);
        // Q_local(x) = Q_world(M x) = |M x − c|² − r², zero up to rounding.
        let scale = c.length_squared() + r * r;
        assert!(tool.value(local).abs() < 1e-9 * scale, "{k}");
    }
    let text = std::fs::read_to_string(format!(
        "{}/assets/scenes/machine80.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("scene");
    let plain = Scene::from_ron(&text).expect("scene");
    let bounds = PropBounds::resolve(None, &plain).expect("bounds");
    let splat_radius = bounds.splat_radius(RADIUS);
    let (_, regions) = PropSplats::rebuild(&plain, bounds, splat_radius, None).expect("sampling");
    let (expected, _) = PropSplats::rebuild(
        &plain.carved(carves.carves()).expect("carved"),
        bounds,
        splat_radius,
        Some(&regions),
    )
    .expect("re-sampling");
    assert_eq!(after.0.splats, expected.0.splats);
    assert_eq!(after.0.quadrics, expected.0.quadrics);
}

#[test]
fn bad_carves_are_refused_and_change_nothing() {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = app();
    let scene: Handle<QuadricScene> = app
        .world()
        .resource::<AssetServer>()
        .load("scenes/three_spheres.quadric.ron");
    let prop = spawn(&mut app, &scene, Transform::from_xyz(0.0, 10.0, 0.0));
    // Not drawn yet.
    app.world_mut()
        .write_message(CarveProp::sphere(prop, Vec3::ZERO, 5.0));
    app.update();
    assert_eq!(refusals(&app, prop), [CarveRefusal::NotSampled]);
    run_until(&mut app, "the first splats", |app| {
        splats(app, prop).is_some()
    });
    let drawn = splats(&app, prop).expect("splats").0.generation;
    let on_surface = surface_point(&app, prop);
    let not_a_prop = app.world_mut().spawn(Transform::IDENTITY).id();
    for carve in [
        CarveProp::sphere(not_a_prop, on_surface, 5.0),
        CarveProp::sphere(prop, Vec3::new(f32::NAN, 0.0, 0.0), 5.0),
        CarveProp::sphere(prop, on_surface, f32::INFINITY),
        CarveProp::sphere(prop, on_surface, 0.0),
        CarveProp::sphere(prop, on_surface, -2.0),
        CarveProp::sphere(prop, on_surface + Vec3::new(1000.0, 0.0, 0.0), 5.0),
    ] {
        app.world_mut().write_message(carve);
    }
    app.update();
    assert_eq!(refusals(&app, not_a_prop), [CarveRefusal::NotAProp]);
    assert_eq!(
        refusals(&app, prop),
        [
            CarveRefusal::NotSampled,
            CarveRefusal::NonFinite,
            CarveRefusal::NonFinite,
            CarveRefusal::DegenerateRadius { radius: 0.0 },
            CarveRefusal::DegenerateRadius { radius: -2.0 },
            CarveRefusal::Misses,
        ]
    );
    for _ in 0..20 {
        app.update();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(splats(&app, prop).expect("splats").0.generation, drawn);
    assert!(
        app.world()
            .get::<PropCarves>(prop)
            .expect("carves")
            .carves()
            .is_empty()
    );
    assert!(app.world().resource::<Seen>().carved.is_empty());

    // The limit: one more carve than it allows, in one frame.
    let s = splats(&app, prop).expect("splats");
    let m = matrix(&app, prop);
    let step = s.0.splats.len() / (MAX_CARVES + 2);
    for k in 0..=MAX_CARVES {
        let p = m
            .transform_point3(s.0.splats[k * step].position.as_dvec3())
            .as_vec3();
        app.world_mut()
            .write_message(CarveProp::sphere(prop, p, 2.0));
    }
    run_until(&mut app, "the carved splats", |app| {
        !app.world().resource::<Seen>().carved.is_empty()
    });
    assert_eq!(
        refusals(&app, prop).last(),
        Some(&CarveRefusal::LimitReached { limit: MAX_CARVES })
    );
    assert_eq!(
        app.world().resource::<Seen>().carved,
        [PropCarved {
            prop,
            carves: MAX_CARVES
        }]
    );
    let carves = app.world().get::<PropCarves>(prop).expect("carves");
    assert_eq!(
        (carves.carves().len(), carves.drawn()),
        (MAX_CARVES, MAX_CARVES)
    );
}

/// A carved prop, re-sampled partially from the uncarved one as the
/// plugin does, drawn by the splat pass (quadric ids, headless) agrees
/// with the CPU reference tracer of the carved solid, and the bite's
/// faces are seen in both.
#[cfg(feature = "viewer")]
#[test]
fn a_carved_prop_matches_the_reference_tracer() {
    use crate::common::{
        FOV_DEGREES, Pixel, Placement, SCALE, View, classify, compare_ids, eye, id_settings,
        load_scene, reference, render_views_with, scene_entry,
    };
    use bevy_chisel::quadric::scene::carve::Carve;
    use bevy_chisel::quadric::{Camera as RefCamera, NO_HIT, Quadric};
    use bevy_chisel::splat::SplatMode;

    const SIZE: u32 = 256;
    let mut failures = Vec::new();
    for name in ["classic", "machine80"] {
        let (_, centre, radius) = scene_entry(name);
        let scene = load_scene(name);
        let eye = eye(centre, radius);
        // A bite where the view ray through the middle pixel meets the
        // solid.
        let plain = reference(&scene, eye, centre, SIZE);
        let middle = (SIZE / 2 * SIZE + SIZE / 2) as usize;
        assert_ne!(
            plain.quadric[middle], NO_HIT,
            "{name}: the middle pixel sees the prop"
        );
        let camera = RefCamera::new(eye, centre, FOV_DEGREES, SIZE, SIZE).expect("camera");
        let hit = camera.ray(SIZE / 2, SIZE / 2).at(plain.depth[middle]);
        let tool = Quadric::sphere(hit, radius / 5.0).expect("tool");
        let carved = scene.carved(&[Carve::new(tool, [0.2; 3])]).expect("carve");
        let tool_id = u32::try_from(scene.dnf().expect("dnf").quadrics().len()).expect("id");
        let expected = reference(&carved, eye, centre, SIZE);
        let view = View {
            eye: eye.as_vec3() * SCALE,
            centre: centre.as_vec3() * SCALE,
            settings: None,
            msaa: Msaa::Off,
        };
        let bounds = PropBounds {
            centre: centre.as_vec3(),
            radius: radius as f32,
        };
        let splat_radius = (radius / 30.0) as f32;
        let (_, regions) =
            PropSplats::rebuild(&scene, bounds, splat_radius, None).expect("sampling");
        let (splats, _) = PropSplats::rebuild(&carved, bounds, splat_radius, Some(&regions))
            .expect("partial re-sampling");
        let image = render_views_with(
            splats,
            Transform::from_scale(Vec3::splat(SCALE)),
            id_settings(SplatMode::SurfaceBoxes),
            &[view],
            SIZE,
            None,
        );
        let placement = Placement {
            x_offset: 0,
            mirrored: false,
        };
        let a = compare_ids(&expected, &image, placement);
        let bite_reference = expected.quadric.iter().filter(|&&q| q == tool_id).count();
        let mut bite_drawn = 0;
        for y in 0..SIZE {
            for x in 0..SIZE {
                bite_drawn += usize::from(classify(&image, x, y) == Pixel::Quadric(tool_id));
            }
        }
        println!(
            "{name} carved: {:.3} % agree, {:.3} % holes; bite {bite_drawn} px drawn, \
             {bite_reference} px in the reference",
            100.0 * a.agree_fraction(),
            100.0 * a.hole_fraction()
        );
        if !a.passes() || bite_reference < 200 || bite_drawn < bite_reference * 9 / 10 {
            failures.push(format!(
                "{name}: {a:?}, bite {bite_drawn} of {bite_reference}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
