//! The level-design workflow for quadric props, in an app without rendering
//! (`MinimalPlugins`): an edited scene file re-samples its props in the
//! background and swaps the new splats in (only the regions the edit can
//! change are sampled again), a malformed edit keeps the previous prop, and
//! moving or scaling a prop samples nothing.
//!
//! Edits reach the app through `AssetServer::reload`, the call Bevy's
//! `file_watcher` makes when a file changes on disk.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bevy::asset::{AssetPlugin, LoadState};
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::quadric::Scene;
use bevy_chisel::splat::{
    ChiselSplatPlugin, PropBounds, PropSampling, PropSplats, QuadricProp, QuadricScene, SplatRadius,
};

use crate::ONE_APP_AT_A_TIME;

/// The splat radius of the edited prop: machine80 at about 80,000 splats.
const RADIUS: SplatRadius = SplatRadius::Auto(100.0);

/// machine80 with one bolt head made wider: an edit of one quadric.
const BOLT: (&str, &str) = (
    "Cylinder(point: (-45, -25, 0), axis: (0, 0, 1), radius: 8)",
    "Cylinder(point: (-45, -25, 0), axis: (0, 0, 1), radius: 9)",
);

fn shipped(name: &str) -> String {
    let path = format!(
        "{}/assets/scenes/{name}.quadric.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(path).expect("shipped scene")
}

/// A directory of its own for this test's asset files.
fn asset_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chisel-props-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn app_in(dir: &Path) -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin {
            file_path: dir.to_string_lossy().into_owned(),
            ..default()
        },
        TransformPlugin,
        ChiselSplatPlugin,
    ));
    app
}

/// Runs frames until `done` holds (or fails after a generous limit).
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

fn generation(app: &App, prop: Entity) -> Option<u64> {
    app.world().get::<PropSplats>(prop).map(|s| s.0.generation)
}

fn runs(app: &App, prop: Entity) -> u64 {
    app.world()
        .get::<PropSampling>(prop)
        .map_or(0, PropSampling::sampling_runs)
}

/// Spawns a prop of the scene file `file` and waits for its first splats.
fn spawn_prop(app: &mut App, file: &str, radius: SplatRadius) -> (Entity, Handle<QuadricScene>) {
    let scene: Handle<QuadricScene> = app.world().resource::<AssetServer>().load(file.to_owned());
    let prop = app
        .world_mut()
        .spawn(QuadricProp {
            scene: scene.clone(),
            bounds: None,
            radius,
        })
        .id();
    run_until(app, "the first splats", |app| {
        generation(app, prop).is_some()
    });
    (prop, scene)
}

fn edit(app: &mut App, dir: &Path, file: &str, text: &str) {
    std::fs::write(dir.join(file), text).expect("write the scene file");
    app.world()
        .resource::<AssetServer>()
        .reload(file.to_owned());
}

#[test]
fn an_edited_scene_file_is_resampled_in_the_background() {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = asset_dir("edit");
    let text = shipped("machine80");
    std::fs::write(dir.join("part.quadric.ron"), &text).expect("write");
    let mut app = app_in(&dir);
    let (prop, _) = spawn_prop(&mut app, "part.quadric.ron", RADIUS);
    assert_eq!(runs(&app, prop), 1);

    // Five edits of one bolt head's radius, each saved once the previous
    // one is in.
    let edits: Vec<String> = ["9", "10", "8.5", "9.5", "7"]
        .iter()
        .map(|r| {
            text.replacen(
                BOLT.0,
                &BOLT.1.replace("radius: 9", &format!("radius: {r}")),
                1,
            )
        })
        .collect();
    let mut swaps = Vec::new();
    let mut waiting = Vec::new();
    for (k, edited) in edits.iter().enumerate() {
        assert_ne!(edited, &text);
        let previous = generation(&app, prop).expect("splats");
        edit(&mut app, &dir, "part.quadric.ron", edited);
        // Every frame until the new splats land draws the old ones; time
        // each frame on the main thread, and the one that swaps them in.
        let mut swapped = false;
        for _ in 0..20_000 {
            let start = Instant::now();
            app.update();
            let took = start.elapsed();
            match generation(&app, prop) {
                Some(g) if g == previous => waiting.push(took),
                Some(_) => {
                    swaps.push(took);
                    swapped = true;
                    break;
                }
                None => panic!("the prop lost its splats while re-sampling"),
            }
            std::thread::sleep(Duration::from_micros(300));
        }
        assert!(swapped, "edit {k} was not re-sampled");
        assert_eq!(runs(&app, prop), 2 + k as u64);
    }
    // No second sampling of an edit (a reload also sends
    // `LoadedWithDependencies`, maybe frames later).
    let last = generation(&app, prop);
    for _ in 0..50 {
        app.update();
        std::thread::sleep(Duration::from_micros(300));
    }
    assert_eq!(runs(&app, prop), 1 + edits.len() as u64);
    assert_eq!(generation(&app, prop), last);
    let splats = app
        .world()
        .get::<PropSplats>(prop)
        .expect("splats")
        .0
        .clone();
    let ms = |d: &Duration| d.as_secs_f64() * 1e3;
    // What a pass over the splats (their `Aabb`) would add to a swap frame
    // had it stayed on the main thread.
    let start = Instant::now();
    let aabb = splats.aabb();
    let aabb_time = start.elapsed();
    assert_eq!(Some(aabb), splats.cached_aabb);
    swaps.sort();
    waiting.sort();
    eprintln!(
        "machine80, {} edits, {} splats: main-thread frame time in the swap frames {:?} ms; \
         median {:.3} ms over the {} frames while sampling ran; the Aabb, now computed on \
         the task, takes {:.3} ms",
        edits.len(),
        splats.splat_count(),
        swaps
            .iter()
            .map(|d| (ms(d) * 1e3).round() / 1e3)
            .collect::<Vec<_>>(),
        ms(&waiting[waiting.len() / 2]),
        waiting.len(),
        ms(&aabb_time)
    );
    // A frame at 60 Hz: a swap must not be a hitch.
    let worst = swaps[swaps.len() - 1];
    assert!(
        worst < Duration::from_millis(16),
        "a swap frame took {worst:?}"
    );

    // The splats are the chain of partial re-samples of the edits, exactly.
    let scene = |text: &str| Scene::from_ron(text).expect("scene");
    let bounds = PropBounds::resolve(None, &scene(&text)).expect("bounds");
    let radius = bounds.splat_radius(RADIUS);
    let (mut expected, mut regions) =
        PropSplats::rebuild(&scene(&text), bounds, radius, None).expect("sampling");
    for edited in &edits {
        (expected, regions) = PropSplats::rebuild(&scene(edited), bounds, radius, Some(&regions))
            .expect("partial re-sample");
    }
    assert_eq!(splats.splats, expected.0.splats);
    assert_eq!(splats.quadrics, expected.0.quadrics);
}

#[test]
fn a_malformed_edit_keeps_the_previous_prop() {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = asset_dir("malformed");
    let text = shipped("three_spheres");
    std::fs::write(dir.join("spheres.quadric.ron"), &text).expect("write");
    let mut app = app_in(&dir);
    let (prop, scene) = spawn_prop(&mut app, "spheres.quadric.ron", SplatRadius::Auto(40.0));
    let first = generation(&app, prop).expect("splats");
    let count = app
        .world()
        .get::<PropSplats>(prop)
        .expect("splats")
        .0
        .splat_count();

    // A reference to a primitive that does not exist.
    edit(
        &mut app,
        &dir,
        "spheres.quadric.ron",
        &text.replacen("Ref(\"C\")", "Ref(\"D\")", 1),
    );
    run_until(&mut app, "the failed reload", |app| {
        matches!(
            app.world().resource::<AssetServer>().get_load_state(&scene),
            Some(LoadState::Failed(_))
        )
    });
    for _ in 0..20 {
        app.update();
    }
    assert_eq!(
        generation(&app, prop),
        Some(first),
        "the splats were replaced"
    );
    assert_eq!(
        app.world()
            .get::<PropSplats>(prop)
            .expect("splats")
            .0
            .splat_count(),
        count
    );
    assert_eq!(runs(&app, prop), 1, "a failed edit started a sampling");
    let kept = app
        .world()
        .resource::<Assets<QuadricScene>>()
        .get(&scene)
        .expect("the previous scene is kept");
    assert_eq!(kept.0.dag.primitives().len(), 3);

    // Fixing the file brings the edit in.
    edit(
        &mut app,
        &dir,
        "spheres.quadric.ron",
        &text.replacen("radius: 25", "radius: 20", 1),
    );
    run_until(&mut app, "the fixed edit", |app| {
        generation(app, prop).is_some_and(|g| g != first)
    });
    assert_eq!(runs(&app, prop), 2);
}

#[test]
fn a_scene_that_failed_to_load_is_sampled_once_fixed() {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = asset_dir("fixed");
    let text = shipped("three_spheres");
    std::fs::write(
        dir.join("late.quadric.ron"),
        text.replacen("Ref(\"C\")", "Ref(\"D\")", 1),
    )
    .expect("write");
    let mut app = app_in(&dir);
    let scene: Handle<QuadricScene> = app
        .world()
        .resource::<AssetServer>()
        .load("late.quadric.ron");
    let prop = app
        .world_mut()
        .spawn(QuadricProp {
            scene: scene.clone(),
            bounds: None,
            radius: SplatRadius::Auto(40.0),
        })
        .id();
    run_until(&mut app, "the failed load", |app| {
        matches!(
            app.world().resource::<AssetServer>().get_load_state(&scene),
            Some(LoadState::Failed(_))
        )
    });
    for _ in 0..20 {
        app.update();
    }
    assert_eq!(generation(&app, prop), None);
    assert_eq!(runs(&app, prop), 0);

    edit(&mut app, &dir, "late.quadric.ron", &text);
    run_until(&mut app, "the splats of the fixed file", |app| {
        generation(app, prop).is_some()
    });
    for _ in 0..50 {
        app.update();
        std::thread::sleep(Duration::from_micros(300));
    }
    assert_eq!(runs(&app, prop), 1);
}

/// Frames (counted in `Last`) in which a prop's sampling state or splats
/// were marked changed.
#[derive(Resource, Default)]
struct PropChanges(usize);

fn count_prop_changes(
    changed: Query<(), Or<(Changed<PropSampling>, Changed<PropSplats>)>>,
    mut count: ResMut<PropChanges>,
) {
    if !changed.is_empty() {
        count.0 += 1;
    }
}

#[test]
fn moving_or_scaling_a_prop_does_not_resample_it() {
    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = app_in(&asset_dir("move"));
    app.init_resource::<PropChanges>()
        .add_systems(Last, count_prop_changes);
    let scene = Scene::from_ron(&shipped("classic")).expect("scene");
    let handle = app
        .world_mut()
        .resource_mut::<Assets<QuadricScene>>()
        .add(QuadricScene(scene));
    let prop = app
        .world_mut()
        .spawn(QuadricProp {
            scene: handle,
            bounds: None,
            radius: SplatRadius::Auto(30.0),
        })
        .id();
    run_until(&mut app, "the first splats", |app| {
        generation(app, prop).is_some()
    });
    let first = generation(&app, prop);
    assert_eq!(runs(&app, prop), 1);
    app.world_mut().resource_mut::<PropChanges>().0 = 0;

    for i in 0..30 {
        let t = i as f32;
        let transform = Transform {
            translation: Vec3::new(t, -2.0 * t, 0.5 * t),
            rotation: Quat::from_rotation_y(0.1 * t),
            // Non-uniform, and mirrored on odd frames.
            scale: Vec3::new(1.0 + 0.1 * t, if i % 2 == 0 { 0.5 } else { -0.5 }, 2.0),
        };
        app.world_mut().entity_mut(prop).insert(transform);
        app.update();
        let global = app
            .world()
            .get::<GlobalTransform>(prop)
            .expect("global transform");
        assert!(
            global
                .translation()
                .abs_diff_eq(transform.translation, 1e-4)
        );
        assert_eq!(runs(&app, prop), 1, "frame {i}: the prop was re-sampled");
        assert_eq!(generation(&app, prop), first);
        let state = app.world().get::<PropSampling>(prop).expect("state");
        assert!(!state.is_busy());
    }
    // Nor does it mark its sampling state or splats changed.
    assert_eq!(app.world().resource::<PropChanges>().0, 0);

    // A change of the prop itself does re-sample it: the count can move.
    app.world_mut()
        .get_mut::<QuadricProp>(prop)
        .expect("prop")
        .radius = SplatRadius::Auto(20.0);
    run_until(&mut app, "the re-sampled prop", |app| {
        generation(app, prop) != first
    });
    assert_eq!(runs(&app, prop), 2);
}

/// The swap in an app that draws the prop (headless, on the machine's
/// Vulkan adapter, lavapipe in CI), with pipelined rendering off so that
/// each update also runs the render world, which uploads the new buffers:
/// the new splats are drawn in the frame they land, and that frame is
/// timed against the frames before it (on lavapipe, drawing the splats on
/// the CPU dominates every frame).
#[test]
fn the_swap_frame_of_a_drawn_prop() {
    use bevy::asset::RenderAssetUsages;
    use bevy::camera::RenderTarget;
    use bevy::render::RenderPlugin;
    use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
    use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
    use bevy::window::ExitCondition;
    use bevy::winit::WinitPlugin;

    let _one = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = App::new();
    app.add_plugins((
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(RenderPlugin {
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<WinitPlugin>()
            .disable::<PipelinedRenderingPlugin>(),
        ChiselSplatPlugin,
    ));
    let size = Extent3d {
        width: 64,
        height: 64,
        depth_or_array_layers: 1,
    };
    let mut image = Image::new_uninit(
        size,
        TextureDimension::D2,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage |= TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    let target = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    let text = shipped("machine80");
    let scene = |text: &str| QuadricScene(Scene::from_ron(text).expect("scene"));
    let handle = app
        .world_mut()
        .resource_mut::<Assets<QuadricScene>>()
        .add(scene(&text));
    let world = app.world_mut();
    let prop = world
        .spawn((
            QuadricProp {
                scene: handle.clone(),
                bounds: None,
                radius: SplatRadius::Auto(40.0),
            },
            Transform::from_scale(Vec3::splat(0.01)),
        ))
        .id();
    world.spawn((
        Camera3d::default(),
        RenderTarget::Image(target.into()),
        Transform::from_xyz(0.0, 0.5, 3.0).looking_at(Vec3::new(0.0, 0.0, 0.3), Vec3::Y),
    ));
    app.finish();
    app.cleanup();
    run_until(&mut app, "the first splats", |app| {
        generation(app, prop).is_some()
    });
    for _ in 0..10 {
        app.update();
    }

    let mut swaps = Vec::new();
    let mut waiting = Vec::new();
    for radius in ["9", "10", "8.5"] {
        let edited = text.replacen(
            BOLT.0,
            &BOLT.1.replace("radius: 9", &format!("radius: {radius}")),
            1,
        );
        let previous = generation(&app, prop).expect("splats");
        *app.world_mut()
            .resource_mut::<Assets<QuadricScene>>()
            .get_mut(&handle)
            .expect("scene") = scene(&edited);
        let mut swapped = false;
        for _ in 0..2_000 {
            let start = Instant::now();
            app.update();
            let took = start.elapsed();
            if generation(&app, prop) == Some(previous) {
                waiting.push(took);
                continue;
            }
            swaps.push(took);
            swapped = true;
            // The render world drew the new splats in the same frame.
            let extracted = app
                .sub_app(bevy::render::RenderApp)
                .world()
                .resource::<bevy_chisel::splat::render::ExtractedProps>()
                .0
                .iter()
                .find(|p| p.entity == prop)
                .map(|p| p.data.generation);
            assert_eq!(extracted, generation(&app, prop));
            break;
        }
        assert!(swapped, "the edit to radius {radius} was not re-sampled");
    }
    let ms = |d: &Duration| (d.as_secs_f64() * 1e6).round() / 1e3;
    waiting.sort();
    let splats = app
        .world()
        .get::<PropSplats>(prop)
        .expect("splats")
        .0
        .splat_count();
    eprintln!(
        "machine80 drawn, {splats} splats: frame time of the swap frames {:?} ms; median {} ms, \
         max {} ms over the {} frames while sampling ran",
        swaps.iter().map(ms).collect::<Vec<_>>(),
        ms(&waiting[waiting.len() / 2]),
        ms(&waiting[waiting.len() - 1]),
        waiting.len()
    );
    assert_eq!(runs(&app, prop), 4);
}
