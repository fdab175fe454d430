//! Both halves of bevy_chisel in one scene: exact destructible terrain with
//! quadric CSG props standing on it.
//!
//! The terrain is a heightfield (`assets/terrain/quarry_height.png`) with
//! grass and dirt following the surface and rock below, stored as an octree
//! of exact BSPs; a few craters are blasted into it at startup. Three props
//! from `assets/scenes/` (the machine part `machine80`, the `classic` CSG
//! cube and `three_spheres`) stand on it, drawn pixel-exact by the splat
//! pass and sharing the depth buffer with the terrain's meshes.
//!
//! Controls: left click blasts a crater, right click heaps up dirt, `Z`
//! undoes, `Y` redoes; `1` splats on surface-aligned boxes, `2` screen-aligned splats,
//! `3` global per-fragment ray tracing; arrow keys or a middle-button drag
//! orbit, the wheel zooms, WASD and Q/E move the camera's focus.
//!
//! The props cast shadows on the terrain (and on each other) from the
//! directional light, drawn into its shadow maps by the splat pass.
//!
//! Runs in a window when a display exists; otherwise (or with
//! `CHISEL_HEADLESS=1`) it renders headless: `screenshots/showcase-0008.png`
//! once the craters and props are in, then `showcase-0017.png` after one
//! more crater beside a prop, drawn by global ray tracing. Frames 9 and
//! 10 are checks: frame 9 with the props hidden, frame 10 with the props
//! shown but casting no shadows (`NotShadowCaster`). The run fails unless
//! the props themselves (the pixels where frames 9 and 10 differ) cover at
//! least [`MIN_PROP_FRACTION`] of the frame, and their shadows on the
//! terrain (pixels outside the props darker in frame 8 than in frame 10)
//! at least [`MIN_SHADOW_FRACTION`].
//!
//! `cargo run --release --all-features --example showcase`

use std::f32::consts::FRAC_PI_2;
use std::time::Duration;

use bevy::light::NotShadowCaster;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::splat::{
    ChiselSplatPlugin, PropSplats, QuadricProp, SplatMode, SplatRadius, SplatSettings,
};
use bevy_chisel::terrain::{
    Carve, CarveApplied, HeightLayer, Heightfield, Terrain, TerrainPlugin, TerrainSurface,
    TerrainSystems, TriplanarMaterial, TriplanarMaterialPlugin, surface_table,
};
use bevy_chisel::viewer::{
    CARVING_HELP, ClickCarving, ORBIT_HELP, OrbitCamera, Overlay, ViewerPlugin, blast, overlay_text,
};

const ROCK: u8 = 1;
const DIRT: u8 = 2;
const GRASS: u8 = 3;

/// World units (m) per scene unit (mm): a 10 cm part becomes 3 m.
const PROP_SCALE: f32 = 0.03;

/// `(scene file, lowest z of the solid in scene units, place on the
/// ground (x, z), turn about the vertical)`.
const PROPS: [(&str, f32, [f32; 2], f32); 3] = [
    ("scenes/machine80.quadric.ron", 0.0, [-5.0, 3.0], 0.4),
    ("scenes/classic.quadric.ron", -50.0, [5.0, -3.0], 0.8),
    ("scenes/three_spheres.quadric.ron", -34.6, [3.5, 6.5], 0.0),
];

/// Craters blasted at startup, `(x, z)`.
const CRATERS: [[f32; 2]; 5] = [
    [-1.0, -1.0],
    [0.5, 0.2],
    [-6.0, -5.0],
    [7.5, 3.0],
    [-1.5, 8.0],
];

/// Headless: the smallest fraction of the frame that the props must cover.
const MIN_PROP_FRACTION: f32 = 0.01;

/// Headless: the smallest fraction of the frame that the props' shadows on
/// the terrain must cover (measured: 0.84 % with lavapipe).
const MIN_SHADOW_FRACTION: f32 = 0.004;

/// Headless: a channel that changes by more than this many sRGB steps
/// between two captures counts as changed.
const CHANGED: u8 = 24;

fn main() -> AppExit {
    let presentation = match Presentation::detect("showcase") {
        Presentation::Headless(config) => Presentation::Headless(HeadlessConfig {
            capture_frames: vec![8, 9, 10, 17],
            max_frames: 1500,
            ..config
        }),
        window => window,
    };
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    let frames = presentation.add_default_plugins(&mut app, "bevy_chisel — showcase");
    app.add_plugins((TerrainPlugin, ChiselSplatPlugin, ViewerPlugin))
        .add_plugins(TriplanarMaterialPlugin)
        .insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
        .insert_resource(ClickCarving {
            blast_radius: 2.0,
            heap_radius: 1.0,
            heap_label: DIRT,
            reach: 500.0,
            undo_key: Some(KeyCode::KeyZ),
            redo_key: Some(KeyCode::KeyY),
        })
        .init_resource::<LastCarve>()
        .add_systems(Startup, spawn_scene)
        .add_systems(
            Update,
            (
                (opening_craters, splat_keys).before(TerrainSystems::Carve),
                update_hud.after(TerrainSystems::Mesh),
            ),
        );
    if headless {
        app.insert_resource(HoldCaptures(true))
            .add_systems(Update, headless_tour.after(TerrainSystems::Mesh));
    }
    let exit = app.run();
    if !headless || exit != AppExit::Success {
        return exit;
    }
    props_in_view(&frames.images())
}

/// The props are in frame 8 and cast shadows on the terrain: the pixels
/// where frame 9 (no props) and frame 10 (props casting no shadow) differ
/// are the props' and must reach [`MIN_PROP_FRACTION`]; the other pixels
/// darker in frame 8 (props casting) than in frame 10 are their shadows
/// and must reach [`MIN_SHADOW_FRACTION`].
fn props_in_view(images: &[Image]) -> AppExit {
    let rgb = |i: usize| {
        images
            .get(i)
            .and_then(|image| image.clone().try_into_dynamic().ok())
            .map(|d| d.to_rgb8())
    };
    let (Some(casting), Some(without), Some(no_shadows)) = (rgb(0), rgb(1), rgb(2)) else {
        eprintln!("showcase: FAILED: frames 8, 9 and 10 were not captured");
        return AppExit::error();
    };
    let changed = |a: &image::Rgb<u8>, b: &image::Rgb<u8>| {
        a.0.iter().zip(b.0).any(|(&x, y)| x.abs_diff(y) > CHANGED)
    };
    let luma = |p: &image::Rgb<u8>| p.0.iter().map(|&c| u32::from(c)).sum::<u32>();
    let (mut prop_pixels, mut shadow_pixels) = (0, 0);
    for ((lit, bare), unshadowed) in casting
        .pixels()
        .zip(without.pixels())
        .zip(no_shadows.pixels())
    {
        if changed(bare, unshadowed) {
            prop_pixels += 1;
        } else if changed(lit, unshadowed) && luma(lit) < luma(unshadowed) {
            shadow_pixels += 1;
        }
    }
    let total = (casting.width() * casting.height()).max(1) as f32;
    let (props, shadows) = (prop_pixels as f32 / total, shadow_pixels as f32 / total);
    println!(
        "showcase: the props cover {:.2}% of the frame, their shadows on the terrain {:.2}%",
        100.0 * props,
        100.0 * shadows
    );
    if props >= MIN_PROP_FRACTION && shadows >= MIN_SHADOW_FRACTION {
        println!("showcase: ok");
        AppExit::Success
    } else {
        eprintln!(
            "showcase: FAILED: at least {:.1}% props and {:.1}% shadows expected",
            100.0 * MIN_PROP_FRACTION,
            100.0 * MIN_SHADOW_FRACTION
        );
        AppExit::error()
    }
}

/// The terrain, rounded to a 1 mm grid.
fn build_terrain() -> Result<Terrain, BevyError> {
    let grid = Quantization::new(0.001, [0.0; 3])?;
    let field =
        Heightfield::load_image("assets/terrain/quarry_height.png", 1.0, 0.0, 5.0, 8.0, ROCK)?
            .with_layers([
                HeightLayer {
                    depth: 1.2,
                    label: DIRT,
                },
                HeightLayer {
                    depth: 0.25,
                    label: GRASS,
                },
            ]);
    Ok(Terrain::from_heightfield(grid, &field)?)
}

/// The ground height under `(x, z)`.
fn ground(terrain: &Terrain, [x, z]: [f32; 2]) -> Option<Vec3> {
    let down = Ray3d::new(Vec3::new(x, 50.0, z), Dir3::NEG_Y);
    terrain.ray_cast(down, 100.0).map(|hit| hit.point)
}

fn spawn_scene(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut materials: ResMut<Assets<TriplanarMaterial>>,
) -> Result {
    // Textured, triplanar-mapped surfaces shipped with the plugin.
    let table = surface_table(
        &mut materials,
        [
            (ROCK, TerrainSurface::Rock),
            (DIRT, TerrainSurface::Dirt),
            (GRASS, TerrainSurface::Grass),
        ],
        TerrainSurface::Rock,
    );
    let terrain = build_terrain()?;
    for (path, bottom, spot, turn) in PROPS {
        // Seated on the ground, sunk a little where the ground slopes.
        let Some(foot) = ground(&terrain, spot) else {
            continue;
        };
        let lift = -bottom * PROP_SCALE - 0.15;
        commands.spawn((
            QuadricProp {
                scene: assets.load(path),
                bounds: None,
                radius: SplatRadius::Auto(40.0),
            },
            // Scenes are `z` up, the world `y` up.
            Transform::from_translation(foot + Vec3::Y * lift)
                .with_rotation(Quat::from_rotation_y(turn) * Quat::from_rotation_x(-FRAC_PI_2))
                .with_scale(Vec3::splat(PROP_SCALE)),
        ));
    }
    commands.spawn((terrain, table, Name::new("terrain")));
    commands.spawn((
        DirectionalLight {
            illuminance: 8_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        // Low enough (30° up) for the props' shadows to reach past their feet.
        Transform::from_xyz(14.0, 10.0, 9.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 150.0,
        ..default()
    });
    commands.spawn(OrbitCamera::new(Vec3::new(0.0, 2.0, 1.0), 22.0).with_angles(0.9, 0.5));
    commands.spawn(overlay_text());
    Ok(())
}

/// Blasts the opening craters once the terrain is meshed.
fn opening_craters(
    mut done: Local<bool>,
    terrains: Query<(Entity, &Terrain)>,
    mut carves: MessageWriter<Carve>,
) {
    if *done {
        return;
    }
    for (entity, terrain) in &terrains {
        if !terrain.is_idle() {
            return;
        }
        for (k, spot) in CRATERS.into_iter().enumerate() {
            if let Some(point) = ground(terrain, spot) {
                carves.write(Carve {
                    terrain: entity,
                    tool: blast(point, 2.0, k),
                    edit: Edit::Subtract,
                });
            }
        }
        *done = true;
    }
}

fn splat_keys(keys: Res<ButtonInput<KeyCode>>, mut settings: ResMut<SplatSettings>) {
    for (key, mode) in [
        (KeyCode::Digit1, SplatMode::SurfaceBoxes),
        (KeyCode::Digit2, SplatMode::ScreenQuads),
        (KeyCode::Digit3, SplatMode::GlobalRayTrace),
    ] {
        if keys.just_pressed(key) {
            settings.mode = mode;
        }
    }
}

/// Headless: hold the captures until the terrain is meshed, the craters
/// are in and every prop is sampled; hide the props for capture 9, take
/// their shadows away for capture 10; after that blast one more crater
/// beside the machine part and switch to global ray tracing.
fn headless_tour(
    mut commands: Commands,
    mut counted: Local<u32>,
    mut hold: ResMut<HoldCaptures>,
    mut settings: ResMut<SplatSettings>,
    terrains: Query<(Entity, &Terrain)>,
    mut props: Query<(Entity, Has<PropSplats>, &mut Visibility), With<QuadricProp>>,
    mut carves: MessageWriter<Carve>,
) {
    let carved = terrains
        .iter()
        .all(|(_, t)| t.is_idle() && !t.journal().is_empty());
    let sampled = !props.is_empty() && props.iter().all(|(_, ready, _)| ready);
    hold.0 = !(carved && sampled);
    if hold.0 {
        return;
    }
    *counted += 1;
    // Counted frames are capture frames (the capture system counts in
    // `Last`, after this).
    for (entity, _, mut visibility) in &mut props {
        *visibility = if *counted == 9 {
            Visibility::Hidden
        } else {
            Visibility::Inherited
        };
        match *counted {
            10 => {
                commands.entity(entity).insert(NotShadowCaster);
            }
            11 => {
                commands.entity(entity).remove::<NotShadowCaster>();
            }
            _ => {}
        }
    }
    if *counted == 11 {
        settings.mode = SplatMode::GlobalRayTrace;
        for (entity, terrain) in &terrains {
            let [x, z] = PROPS[0].2;
            if let Some(point) = ground(terrain, [x + 3.0, z - 1.5]) {
                carves.write(Carve {
                    terrain: entity,
                    tool: blast(point, 1.5, 7),
                    edit: Edit::Subtract,
                });
            }
        }
    }
}

/// The latest carve, for the HUD.
#[derive(Resource, Default)]
struct LastCarve(Option<CarveApplied>);

fn update_hud(
    mut applied: MessageReader<CarveApplied>,
    mut last: ResMut<LastCarve>,
    settings: Res<SplatSettings>,
    terrains: Query<&Terrain>,
    props: Query<&PropSplats>,
    mut hud: Query<&mut Text, With<Overlay>>,
) {
    if let Some(a) = applied.read().last() {
        last.0 = Some(a.clone());
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut lines = vec![
        "bevy_chisel showcase: exact destructible terrain and quadric CSG props".to_owned(),
        format!("{CARVING_HELP} | 1/2/3 splat boxes / splat quads / ray tracing"),
        format!("{ORBIT_HELP} | WASD/QE move"),
    ];
    for terrain in &terrains {
        lines.push(format!(
            "terrain: {} triangles, {} leaf cells, {} carves",
            terrain.triangle_count(),
            terrain.octree().stats().leaves,
            terrain.journal().len()
        ));
    }
    let splats: usize = props.iter().map(|p| p.0.splat_count()).sum();
    lines.push(format!(
        "props: {} of {} sampled, {splats} splats, drawn by {:?}",
        props.iter().count(),
        PROPS.len(),
        settings.mode
    ));
    if let Some(a) = &last.0 {
        lines.push(format!(
            "last carve: kernel {:.2} ms, meshes {:.2} ms, visible after {:.1} ms",
            ms(a.apply_time),
            ms(a.mesh_time),
            ms(a.latency)
        ));
    }
    for mut text in &mut hud {
        text.0 = lines.join("\n");
    }
}
