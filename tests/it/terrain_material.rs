//! Terrain materials: every cell gets the material of its label in the
//! frame it is spawned, for any material type, and again when the table
//! changes; and the triplanar material renders textured and lit through
//! Bevy's real pipeline (headless, on the machine's Vulkan adapter: the CPU
//! driver lavapipe in CI).

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bevy::asset::AssetPlugin;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::terrain::{
    Carve, CarveTool, Terrain, TerrainCell, TerrainMaterialPlugin, TerrainMaterials, TerrainPlugin,
    TerrainSurface, TerrainSystems, TriplanarMaterial, TriplanarMaterialPlugin, surface_table,
};

use crate::ONE_APP_AT_A_TIME;

const ROCK: u8 = 1;
const ORE: u8 = 4;

/// Cells seen by [`check_new_cells`]: how many arrived, and which arrived
/// without the material of their label (shared, to be read after
/// `App::run`).
#[derive(Resource, Clone, Default)]
struct CellCheck(Arc<Mutex<Seen>>);

#[derive(Clone, Default)]
struct Seen {
    seen: usize,
    wrong: Vec<String>,
}

impl CellCheck {
    fn get(&self) -> Seen {
        self.0.lock().map(|s| s.clone()).unwrap_or_default()
    }
}

/// A cell and its material of type `M`, if any.
type NewCell<'a, M> = (Entity, &'a TerrainCell, Option<&'a MeshMaterial3d<M>>);

/// Runs after [`TerrainSystems::Material`]: every cell spawned this frame
/// already has `MeshMaterial3d<M>` with its label's material.
fn check_new_cells<M: Material>(
    cells: Query<NewCell<M>, Added<TerrainCell>>,
    tables: Query<&TerrainMaterials<M>>,
    check: Res<CellCheck>,
) {
    let Ok(mut check) = check.0.lock() else {
        return;
    };
    for (entity, cell, material) in &cells {
        check.seen += 1;
        let expected = tables.get(cell.terrain).map(|t| t.get(cell.label).id());
        if material.map(|m| m.id()) != expected.ok() {
            check.wrong.push(format!(
                "{entity} label {}: {:?}",
                cell.label,
                material.map(|m| m.id())
            ));
        }
    }
}

/// A 4 m cube of rock centred on the origin, on a 1 mm grid.
fn block() -> Terrain {
    let grid = Quantization::new(0.001, [0.0; 3]).expect("valid grid");
    Terrain::from_box(grid, Vec3::splat(-2.0), Vec3::splat(2.0), ROCK)
        .expect("valid block")
        .with_labels([ORE])
}

fn ore_vein() -> Carve {
    Carve {
        terrain: Entity::PLACEHOLDER,
        tool: CarveTool::dodecahedron(1.2, Vec3::new(2.0, 2.0, 2.0)),
        edit: Edit::Add(ORE),
    }
}

fn settle(app: &mut App, entity: Entity) {
    for _ in 0..20_000 {
        app.update();
        if app
            .world()
            .get::<Terrain>(entity)
            .is_some_and(Terrain::is_idle)
        {
            return;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("terrain did not settle");
}

#[test]
fn carved_cells_get_their_label_material_in_the_frame_they_appear() {
    let _guard = ONE_APP_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut app = App::new();
    // The triplanar table without its renderer: assigning materials is
    // plain ECS work for any material type.
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin::default(),
        TerrainPlugin,
        TerrainMaterialPlugin::<TriplanarMaterial>::default(),
        // Added twice: still one assignment.
        TerrainMaterialPlugin::<TriplanarMaterial>::default(),
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .init_asset::<Image>()
    .init_asset::<TriplanarMaterial>()
    .init_resource::<CellCheck>()
    .add_systems(
        Update,
        check_new_cells::<TriplanarMaterial>.after(TerrainSystems::Material),
    );
    let table = {
        let mut materials = app.world_mut().resource_mut::<Assets<TriplanarMaterial>>();
        surface_table(
            &mut materials,
            [(ROCK, TerrainSurface::Rock), (ORE, TerrainSurface::Ore)],
            TerrainSurface::Rock,
        )
    };
    let entity = app.world_mut().spawn((block(), table.clone())).id();
    settle(&mut app, entity);
    let initial = app.world().resource::<CellCheck>().get().seen;
    assert!(initial > 0, "the block was meshed");

    app.world_mut().write_message(Carve {
        terrain: entity,
        ..ore_vein()
    });
    settle(&mut app, entity);
    let check = app.world().resource::<CellCheck>().get();
    assert!(check.seen > initial, "the carve spawned cells");
    assert!(
        check.wrong.is_empty(),
        "cells without their material: {:?}",
        check.wrong
    );

    // The ore label's cells show the ore material; no cell is left with
    // Bevy's default material.
    let mut query = app
        .world_mut()
        .query::<(&TerrainCell, Option<&MeshMaterial3d<TriplanarMaterial>>)>();
    let mut ore_cells = 0;
    for (cell, material) in query.iter(app.world()) {
        assert_eq!(material.map(|m| m.id()), Some(table.get(cell.label).id()));
        ore_cells += usize::from(cell.label == ORE);
    }
    assert!(ore_cells > 0, "the vein is shown");
    let mut defaults = app
        .world_mut()
        .query_filtered::<(), (With<TerrainCell>, With<MeshMaterial3d<StandardMaterial>>)>();
    assert_eq!(defaults.iter(app.world()).count(), 0);

    // A new table re-assigns every cell.
    let swapped = {
        let mut materials = app.world_mut().resource_mut::<Assets<TriplanarMaterial>>();
        surface_table(&mut materials, [], TerrainSurface::Dirt)
    };
    let dirt = swapped.get(ROCK).id();
    app.world_mut().entity_mut(entity).insert(swapped);
    app.update();
    let mut query = app
        .world_mut()
        .query::<(&TerrainCell, &MeshMaterial3d<TriplanarMaterial>)>();
    assert!(query.iter(app.world()).all(|(_, m)| m.id() == dirt));
}

#[test]
fn terrain_without_a_table_shows_the_default_material() {
    let _guard = ONE_APP_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>();
    let entity = app.world_mut().spawn(block()).id();
    settle(&mut app, entity);
    let mut query = app
        .world_mut()
        .query::<(&TerrainCell, Option<&MeshMaterial3d<StandardMaterial>>)>();
    let cells: Vec<_> = query.iter(app.world()).map(|(_, m)| m.cloned()).collect();
    assert!(!cells.is_empty());
    assert!(
        cells
            .iter()
            .all(|m| m.as_ref().map(|m| m.id()) == Some(AssetId::default()))
    );
}

// ---------------------------------------------------------------- rendering

const WIDTH: u32 = 192;
const HEIGHT: u32 = 144;
const FOV: f32 = std::f32::consts::FRAC_PI_4;
const EYE: Vec3 = Vec3::new(6.0, 5.0, 7.0);

/// How the block is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Look {
    /// The shipped rock surface, triplanar textured.
    Textured,
    /// A flat grey `StandardMaterial`: the control.
    Plain,
}

/// Renders the block lit from `+x +y` (the `+z` face turned away from the
/// light), seen from [`EYE`]; returns the capture and what the check
/// system saw.
fn render_block(look: Look) -> (Image, usize, Vec<String>) {
    let _guard = ONE_APP_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let config = HeadlessConfig {
        width: WIDTH,
        height: HEIGHT,
        capture_frames: vec![6, 8],
        output_dir: std::env::var_os("CHISEL_TEST_SCREENSHOTS").map(Into::into),
        stem: format!("terrain_material-{look:?}"),
        max_frames: 600,
        min_foreground: 0.2,
    };
    let check = CellCheck::default();
    let mut app = App::new();
    let frames = Presentation::Headless(config).add_default_plugins(&mut app, "material test");
    app.add_plugins((TerrainPlugin, TriplanarMaterialPlugin))
        .insert_resource(ClearColor(Color::BLACK))
        .insert_resource(HoldCaptures(true))
        .insert_resource(GlobalAmbientLight {
            brightness: 60.0,
            ..default()
        })
        .insert_resource(check.clone())
        .add_systems(
            Update,
            (
                check_new_cells::<TriplanarMaterial>,
                check_new_cells::<StandardMaterial>,
            )
                .after(TerrainSystems::Material),
        )
        .add_systems(
            Update,
            |terrains: Query<&Terrain>, mut hold: ResMut<HoldCaptures>| {
                hold.0 = !terrains.iter().all(Terrain::is_idle);
            },
        );
    app.add_systems(
        Startup,
        move |mut commands: Commands,
              mut textured: ResMut<Assets<TriplanarMaterial>>,
              mut plain: ResMut<Assets<StandardMaterial>>| {
            let mut terrain = commands.spawn(block());
            match look {
                Look::Textured => {
                    let table = surface_table(&mut textured, [], TerrainSurface::Rock);
                    if let Some(mut m) = textured.get_mut(&table.fallback) {
                        m.extension.scale = 0.75;
                    }
                    terrain.insert(table);
                }
                Look::Plain => {
                    let grey = plain.add(StandardMaterial {
                        base_color: Color::srgb(0.45, 0.45, 0.45),
                        perceptual_roughness: 0.85,
                        ..default()
                    });
                    terrain.insert(TerrainMaterials::new([], grey));
                }
            }
            commands.spawn((
                DirectionalLight {
                    illuminance: 8_000.0,
                    shadow_maps_enabled: true,
                    ..default()
                },
                Transform::default().looking_to(Vec3::new(-0.6, -1.0, 0.5), Vec3::Y),
            ));
            commands.spawn((
                Camera3d::default(),
                Projection::Perspective(PerspectiveProjection {
                    fov: FOV,
                    ..default()
                }),
                Tonemapping::None,
                Msaa::Off,
                Transform::from_translation(EYE).looking_at(Vec3::ZERO, Vec3::Y),
            ));
        },
    );
    assert_eq!(app.run(), AppExit::Success, "headless run failed");
    let images = frames.images();
    assert_eq!(images.len(), 2, "two captured frames");
    assert!(
        images[0].data == images[1].data,
        "the picture has not settled"
    );
    let check = check.get();
    let image = images.into_iter().next_back().expect("two frames");
    (image, check.seen, check.wrong)
}

/// The pixel showing world point `p` through the test camera.
fn pixel(p: Vec3) -> (u32, u32) {
    let view = Mat4::look_at_rh(EYE, Vec3::ZERO, Vec3::Y);
    let clip = Mat4::perspective_rh(FOV, WIDTH as f32 / HEIGHT as f32, 0.1, 100.0);
    let ndc = clip.project_point3(view.transform_point3(p));
    let x = (ndc.x * 0.5 + 0.5) * WIDTH as f32;
    let y = (0.5 - ndc.y * 0.5) * HEIGHT as f32;
    (x as u32, y as u32)
}

/// Mean and standard deviation of the luminance (0–255) of the 15×15
/// pixels around the pixel showing `p`.
fn patch(image: &Image, p: Vec3) -> (f32, f32) {
    let (cx, cy) = pixel(p);
    let values: Vec<f32> = (cy - 7..=cy + 7)
        .flat_map(|y| (cx - 7..=cx + 7).map(move |x| (x, y)))
        .map(|(x, y)| {
            let c = image.get_color_at(x, y).expect("inside").to_srgba();
            255.0 * (0.2126 * c.red + 0.7152 * c.green + 0.0722 * c.blue)
        })
        .collect();
    let n = values.len() as f32;
    let mean = values.iter().sum::<f32>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / n;
    (mean, var.sqrt())
}

#[test]
fn triplanar_terrain_renders_textured_and_lit() {
    let faces = [
        ("top", Vec3::new(0.0, 2.0, 0.0)),
        ("+x", Vec3::new(2.0, 0.0, 0.0)),
        ("+z (away from the light)", Vec3::new(0.0, 0.0, 2.0)),
    ];
    let mut spread = Vec::new();
    for look in [Look::Textured, Look::Plain] {
        let (image, seen, wrong) = render_block(look);
        assert!(seen > 0, "{look:?}: no cells drawn");
        assert!(
            wrong.is_empty(),
            "{look:?}: cells without their material: {wrong:?}"
        );
        let stats = faces.map(|(_, p)| patch(&image, p));
        let [top, lit, away] = stats;
        // Lit faces are brighter than the face turned away from the light.
        assert!(
            lit.0 > 1.8 * away.0 && top.0 > 1.8 * away.0,
            "{look:?}: face brightness {stats:?} ({faces:?})"
        );
        spread.push((look, top.1.min(lit.1)));
    }
    // The texture is visible: lit faces vary from pixel to pixel, the
    // plain control does not.
    let [(_, textured), (_, plain)] = spread[..] else {
        unreachable!()
    };
    assert!(
        textured > 6.0 && plain < 2.0,
        "luminance deviation on lit faces: textured {textured:.2}, plain {plain:.2}"
    );
}
