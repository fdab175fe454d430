//! Crack-free seams, seen: a heavily carved terrain rendered through Bevy's
//! real pipeline (headless, on the machine's Vulkan adapter: the CPU driver
//! lavapipe in CI) at grazing angles, where a crack between two cells'
//! meshes would let the background through.
//!
//! The terrain is drawn in one unlit colour it shares with nothing else,
//! against a background colour it never has. The *silhouette* is where an
//! exact ray cast of the same octree ([`Terrain::ray_cast`]) from the pixel
//! centre meets the terrain; a pixel counts as inside it when its ray and
//! the rays of its eight neighbours all hit (so that rasterization and the
//! ray cast may disagree by a pixel along the outline). Inside, not one
//! pixel may show the background.
//!
//! The check is shown to catch a hole: the last capture is taken after the
//! cell seen near the bottom of the last view is hidden, and it does show
//! background inside the silhouette.

use bevy::camera::Viewport;
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::math::Ray3d;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellKey, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::terrain::{CarveTool, Terrain, TerrainMaterials, TerrainPlugin};

use crate::ONE_APP_AT_A_TIME;

const TERRAIN: [u8; 3] = [255, 0, 0];
const BACKGROUND: [u8; 3] = [0, 0, 255];
/// Edge of each view's square viewport, in pixels.
const SIZE: u32 = 160;
const FOV_DEGREES: f32 = 50.0;
/// Non-held frames at which the captures are taken, and the one at which
/// a cell is hidden between them.
const CAPTURES: [u32; 2] = [4, 12];
const HIDE_AT: u32 = 7;

/// xorshift64*: a fixed stream of numbers in `[0, 1)`.
fn uniform(mut state: u64) -> impl FnMut() -> f32 {
    move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A 12 m × 2 m × 12 m slab on a 1 cm grid in small cells (many seams),
/// blasted by 250 craters of 0.3–1.2 m on its top and its sides.
fn carved_slab() -> Terrain {
    let grid = Quantization::new(0.01, [0.0; 3]).expect("valid unit");
    let slab = Terrain::from_box(
        grid,
        Vec3::new(-6.0, -2.0, -6.0),
        Vec3::new(6.0, 0.0, 6.0),
        1,
    )
    .expect("valid slab");
    let config = OctreeConfig {
        max_bsp_nodes: 12,
        max_depth: 20,
    };
    let mut terrain = Terrain::from_base(grid, slab.base().clone(), config)
        .expect("same base")
        .with_max_undo(0);
    let mut next = uniform(0x9E37_79B9_7F4A_7C15);
    for k in 0..250 {
        let (u, v, r) = (next() * 12.0 - 6.0, next() * 12.0 - 6.0, 0.3 + 0.9 * next());
        // Mostly the top; every fifth on one of the four sides.
        let centre = match k % 5 {
            0 => match k % 4 {
                0 => Vec3::new(-6.0, -next(), u),
                1 => Vec3::new(6.0, -next(), u),
                2 => Vec3::new(u, -next(), -6.0),
                _ => Vec3::new(u, -next(), 6.0),
            },
            _ => Vec3::new(u, 0.1 - 0.4 * next(), v),
        };
        let tool = CarveTool::dodecahedron(r, centre)
            .to_grid(terrain.quantization())
            .expect("on the grid");
        terrain
            .apply_now(&tool, Edit::Subtract)
            .expect("valid crater");
    }
    terrain
}

/// Grazing views: eyes a little above the ground or beside its sides,
/// looking across it; and one looking down into the craters at about 25°.
fn views() -> [(Vec3, Vec3); 4] {
    [
        (Vec3::new(-9.0, 0.35, -8.0), Vec3::new(3.0, -0.2, 2.0)),
        (Vec3::new(9.5, 0.5, 1.0), Vec3::new(-4.0, -0.3, -1.0)),
        (Vec3::new(2.0, -0.9, 9.5), Vec3::new(-1.0, -1.0, 0.0)),
        (Vec3::new(-4.0, 2.5, 0.5), Vec3::new(3.0, -1.0, 0.0)),
    ]
}

fn camera_transform(eye: Vec3, centre: Vec3) -> Transform {
    Transform::from_translation(eye).looking_at(centre, Vec3::Y)
}

/// The ray through the centre of pixel `(x, y)` of a `SIZE`² view.
fn pixel_ray(camera: &Transform, x: u32, y: u32) -> Ray3d {
    let half = (FOV_DEGREES.to_radians() / 2.0).tan();
    let ndc_x = (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0;
    let local = Vec3::new(ndc_x * half, ndc_y * half, -1.0);
    let direction = Dir3::new(camera.rotation * local).expect("a finite direction");
    Ray3d::new(camera.translation, direction)
}

#[derive(Resource)]
struct Cameras(Vec<Transform>);

/// The cell hidden before the last capture.
#[derive(Resource, Clone, Copy)]
struct Hide(CellKey);

/// Holds the captures until the terrain is meshed, then hides [`Hide`]'s
/// cell at frame [`HIDE_AT`].
fn hold_and_hide(
    terrains: Query<&Terrain>,
    mut hold: ResMut<HoldCaptures>,
    hide: Res<Hide>,
    mut frames: Local<u32>,
    mut commands: Commands,
) {
    let Ok(terrain) = terrains.single() else {
        return;
    };
    hold.0 = !terrain.is_idle();
    if hold.0 {
        return;
    }
    *frames += 1;
    if *frames == HIDE_AT {
        for entity in terrain.cell_entities(hide.0) {
            commands.entity(entity).insert(Visibility::Hidden);
        }
    }
}

fn rgb(image: &Image, x: u32, y: u32) -> [u8; 3] {
    let c = image
        .get_color_at(x, y)
        .expect("pixel inside the image")
        .to_srgba()
        .to_u8_array();
    [c[0], c[1], c[2]]
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    a.iter().zip(b).all(|(&x, y)| x.abs_diff(y) <= 8)
}

/// Per view, which pixels' rays meet the terrain.
fn silhouettes(terrain: &Terrain, cameras: &[Transform]) -> Vec<Vec<bool>> {
    cameras
        .iter()
        .map(|camera| {
            (0..SIZE * SIZE)
                .map(|i| {
                    let ray = pixel_ray(camera, i % SIZE, i / SIZE);
                    terrain.ray_cast(ray, 100.0).is_some()
                })
                .collect()
        })
        .collect()
}

/// What one capture shows against the silhouettes.
#[derive(Debug, Default)]
struct Count {
    /// Pixels inside the silhouette (their ray and its 8 neighbours hit).
    inside: usize,
    /// Of those, pixels showing the background.
    holes: usize,
    /// Pixels where the capture and the ray cast disagree on terrain or
    /// background.
    disagree: usize,
    /// Pixels showing neither colour.
    other: usize,
}

fn count(image: &Image, hits: &[Vec<bool>]) -> Count {
    let mut c = Count::default();
    for (view, hit) in (0_u32..).zip(hits) {
        let at = |x: u32, y: u32| hit[(y * SIZE + x) as usize];
        for y in 0..SIZE {
            for x in 0..SIZE {
                let colour = rgb(image, view * SIZE + x, y);
                let (terrain, background) = (close(colour, TERRAIN), close(colour, BACKGROUND));
                if !terrain && !background {
                    c.other += 1;
                }
                if terrain != at(x, y) {
                    c.disagree += 1;
                }
                let interior = (x > 0 && y > 0 && x + 1 < SIZE && y + 1 < SIZE)
                    && (y - 1..=y + 1).all(|v| (x - 1..=x + 1).all(|u| at(u, v)));
                if interior {
                    c.inside += 1;
                    c.holes += usize::from(background);
                }
            }
        }
    }
    c
}

#[test]
fn a_carved_terrain_at_grazing_angles_shows_no_background_through_its_seams() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let terrain = carved_slab();
    let cameras: Vec<Transform> = views()
        .iter()
        .map(|&(eye, centre)| camera_transform(eye, centre))
        .collect();
    let hits = silhouettes(&terrain, &cameras);
    let near_ray = pixel_ray(&cameras[3], SIZE / 2, SIZE - 20);
    let hidden = terrain
        .ray_cast(near_ray, 100.0)
        .expect("the last view sees the terrain near its bottom edge")
        .cell;

    let count_views = u32::try_from(cameras.len()).expect("a few views");
    let config = HeadlessConfig {
        width: SIZE * count_views,
        height: SIZE,
        capture_frames: CAPTURES.to_vec(),
        // CHISEL_TEST_SCREENSHOTS=dir keeps the images for inspection.
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: "terrain_seams_render".into(),
        max_frames: 400,
        min_foreground: 0.0,
    };
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "seams test");
    let background = Color::srgb_u8(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2]);
    app.add_plugins(TerrainPlugin)
        .insert_resource(ClearColor(background))
        .insert_resource(HoldCaptures(true))
        .insert_resource(Hide(hidden))
        .insert_resource(Cameras(cameras))
        .add_systems(Update, hold_and_hide)
        .add_systems(
            Startup,
            move |mut commands: Commands,
                  cameras: Res<Cameras>,
                  mut materials: ResMut<Assets<StandardMaterial>>| {
                let flat = materials.add(StandardMaterial {
                    base_color: Color::srgb_u8(TERRAIN[0], TERRAIN[1], TERRAIN[2]),
                    unlit: true,
                    ..default()
                });
                commands.spawn((
                    carved_slab(),
                    TerrainMaterials::new([], flat),
                    Transform::IDENTITY,
                ));
                for (i, camera) in (0_u32..).zip(&cameras.0) {
                    commands.spawn((
                        Camera3d::default(),
                        Camera {
                            clear_color: ClearColorConfig::Custom(background),
                            order: i as isize,
                            viewport: Some(Viewport {
                                physical_position: UVec2::new(i * SIZE, 0),
                                physical_size: UVec2::splat(SIZE),
                                ..default()
                            }),
                            ..default()
                        },
                        Projection::Perspective(PerspectiveProjection {
                            fov: FOV_DEGREES.to_radians(),
                            near: 0.01,
                            ..default()
                        }),
                        Tonemapping::None,
                        DebandDither::Disabled,
                        Msaa::Off,
                        *camera,
                    ));
                }
            },
        );
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    let images = frames.images();
    assert_eq!(images.len(), 2, "two captures");

    let whole = count(&images[0], &hits);
    println!("carved terrain: {whole:?}");
    let total = (SIZE * SIZE) as usize * hits.len();
    assert!(
        whole.inside * 3 > total,
        "the terrain should fill much of the views: {whole:?} of {total}"
    );
    assert!(
        whole.other * 200 < total && whole.disagree * 50 < total,
        "the capture should match the ray-cast silhouette but for its outline: {whole:?} of \
         {total}"
    );
    assert_eq!(
        whole.holes, 0,
        "background shows through the terrain: {whole:?}"
    );

    let holed = count(&images[1], &hits);
    println!("one cell hidden: {holed:?}");
    assert!(
        holed.holes > 0,
        "with cell {hidden:?} hidden, the check should see background inside the silhouette: \
         {holed:?}"
    );
}
