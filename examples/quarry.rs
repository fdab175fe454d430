//! A quarry of exact, destructible terrain.
//!
//! A heightfield (`assets/terrain/quarry_height.png`) becomes layered
//! terrain — grass and dirt following the surface, rock below, veins of
//! ore — stored as an octree of exact BSPs. Click to blast craters with
//! dodecahedra, right-click to heap up dirt, Z to undo, Y to redo, F5 to
//! save the terrain and F9 to load it back; only the cells a blast
//! reaches are re-meshed, on the async compute pool. The HUD shows each
//! carve's time in the kernel and in re-meshing, the triangle count, and
//! how much rock, dirt, grass and ore the carves have taken out (each
//! carve's exact `volume_change`, as a mining game would tally it).
//!
//! Camera: WASD and Q/E move the focus, the arrow keys or a middle-button
//! drag orbit, the wheel zooms.
//!
//! Runs in a window when a display exists; otherwise renders headless,
//! blasts a few scripted craters and writes PNG screenshots to
//! `screenshots/`.
//!
//! `cargo run --release --all-features --example quarry`

use std::collections::BTreeMap;
use std::time::Duration;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveShape, CarveTool, HeightLayer, Heightfield, Terrain,
    TerrainMaterials, TerrainPlugin, TerrainSettings, TerrainSurface, TerrainSystems,
    TriplanarMaterial, TriplanarMaterialPlugin, surface_table,
};
use bevy_chisel::viewer::{
    CARVING_HELP, ClickCarving, ORBIT_HELP, OrbitCamera, Overlay, ViewerPlugin, blast, overlay_text,
};

const ROCK: u8 = 1;
const DIRT: u8 = 2;
const GRASS: u8 = 3;
const ORE: u8 = 4;

/// Radius of a blast crater (m).
const BLAST_RADIUS: f32 = 2.0;
/// Radius of a heap of added dirt (m).
const HEAP_RADIUS: f32 = 1.0;

fn main() -> AppExit {
    let presentation = match Presentation::detect("quarry") {
        Presentation::Headless(config) => Presentation::Headless(HeadlessConfig {
            capture_frames: vec![10, 20],
            max_frames: 300,
            ..config
        }),
        window => window,
    };
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — quarry");
    app.add_plugins((TerrainPlugin, TriplanarMaterialPlugin, ViewerPlugin))
        .insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
        // Each carve reports the rock, dirt, grass and ore it took out.
        .insert_resource(TerrainSettings {
            measure_volumes: true,
            ..default()
        })
        .insert_resource(ClickCarving {
            blast_radius: BLAST_RADIUS,
            heap_radius: HEAP_RADIUS,
            heap_label: DIRT,
            reach: 500.0,
            undo_key: Some(KeyCode::KeyZ),
            redo_key: Some(KeyCode::KeyY),
        })
        .init_resource::<Stats>()
        .add_systems(Startup, spawn_scene)
        .add_systems(
            Update,
            (
                keys.before(TerrainSystems::Carve),
                update_hud.after(TerrainSystems::Mesh),
            ),
        );
    if headless {
        app.insert_resource(Script::default())
            .add_systems(Update, scripted_carves.before(TerrainSystems::Carve));
    }
    app.run()
}

/// The quarry's terrain, rounded to a 1 mm grid.
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
    let mut terrain = Terrain::from_heightfield(grid, &field)?.with_labels([ORE]);
    // Veins of ore in the rock, 2.3 m under the surface: painted, and not
    // undoable.
    for (k, (x, z)) in [
        (-6.0, 6.0),
        (-7.5, 4.0),
        (6.5, -5.5),
        (3.0, 9.0),
        (0.0, -2.0),
        (10.0, 8.0),
    ]
    .into_iter()
    .enumerate()
    {
        let down = Ray3d::new(Vec3::new(x, 20.0, z), Dir3::NEG_Y);
        let Some(hit) = terrain.ray_cast(down, 50.0) else {
            continue;
        };
        let centre = hit.point - Vec3::Y * 2.3;
        let tool = CarveTool::new(
            CarveShape::Dodecahedron { radius: 1.4 },
            Transform::from_translation(centre)
                .with_rotation(Quat::from_rotation_y(0.7 * k as f32))
                .with_scale(Vec3::new(1.8, 0.7, 1.0)),
        );
        let grid_tool = tool.to_grid(terrain.quantization())?;
        terrain.apply_now(&grid_tool, Edit::Paint(ORE))?;
    }
    terrain.clear_undo();
    Ok(terrain)
}

fn spawn_scene(mut commands: Commands, mut materials: ResMut<Assets<TriplanarMaterial>>) -> Result {
    // Textured, triplanar-mapped surfaces shipped with the plugin.
    let table = surface_table(
        &mut materials,
        [
            (ROCK, TerrainSurface::Rock),
            (DIRT, TerrainSurface::Dirt),
            (GRASS, TerrainSurface::Grass),
            (ORE, TerrainSurface::Ore),
        ],
        TerrainSurface::Rock,
    );
    let terrain = build_terrain()?;
    commands.spawn((terrain, table.clone(), Name::new("quarry")));
    commands.insert_resource(Palette(table));
    commands.spawn((
        DirectionalLight {
            illuminance: 11_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(12.0, 25.0, 8.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 400.0,
        ..default()
    });
    commands.spawn(OrbitCamera {
        min_distance: 3.0,
        max_distance: 120.0,
        ..OrbitCamera::new(Vec3::new(-1.0, 1.5, 1.0), 26.0)
    });
    commands.spawn(overlay_text());
    Ok(())
}

/// The materials, kept to give a loaded terrain the same look.
#[derive(Resource)]
struct Palette(TerrainMaterials<TriplanarMaterial>);

/// Carve timings and material taken out, for the HUD.
#[derive(Resource, Default)]
struct Stats {
    last: Option<CarveApplied>,
    /// Per material, what the carves took out less what they put in (m³).
    taken_out: BTreeMap<u8, f64>,
    error: Option<String>,
    message: Option<String>,
}

/// F5 saves the terrain, F9 loads it back.
fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    terrains: Query<(Entity, &Terrain)>,
    palette: Res<Palette>,
    mut stats: ResMut<Stats>,
    mut commands: Commands,
) {
    let path = std::env::temp_dir().join("quarry.chiselterrain");
    for (entity, terrain) in &terrains {
        if keys.just_pressed(KeyCode::F5) {
            stats.message = Some(match terrain.save(&path) {
                Ok(()) => format!("saved {}", path.display()),
                Err(e) => format!("save failed: {e}"),
            });
        }
        if keys.just_pressed(KeyCode::F9) {
            match Terrain::load(&path) {
                Ok(loaded) => {
                    commands.entity(entity).despawn();
                    commands.spawn((loaded, palette.0.clone(), Name::new("quarry")));
                    stats.message = Some(format!("loaded {}", path.display()));
                }
                Err(e) => stats.message = Some(format!("load failed: {e}")),
            }
        }
    }
}

/// Headless runs: once the terrain is meshed, blast a few craters and heap
/// up some dirt, so that the screenshots show carving.
#[derive(Resource, Default)]
struct Script {
    done: bool,
}

fn scripted_carves(
    mut script: ResMut<Script>,
    terrains: Query<(Entity, &Terrain)>,
    mut carves: MessageWriter<Carve>,
) {
    if script.done {
        return;
    }
    for (entity, terrain) in &terrains {
        if !terrain.is_idle() {
            return;
        }
        let down =
            |x: f32, z: f32| terrain.ray_cast(Ray3d::new(Vec3::new(x, 20.0, z), Dir3::NEG_Y), 50.0);
        let spots = [
            (-6.0, 6.0),
            (-5.0, 7.5),
            (-7.5, 4.8),
            (4.0, 4.0),
            (6.0, -5.0),
            (7.5, -6.5),
            (0.0, -2.0),
        ];
        for (k, (x, z)) in spots.into_iter().enumerate() {
            if let Some(hit) = down(x, z) {
                carves.write(Carve {
                    terrain: entity,
                    tool: blast(hit.point, BLAST_RADIUS, k),
                    edit: Edit::Subtract,
                });
            }
        }
        if let Some(hit) = down(-2.0, 9.0) {
            carves.write(Carve {
                terrain: entity,
                tool: CarveTool::sphere(HEAP_RADIUS, hit.point),
                edit: Edit::Add(DIRT),
            });
        }
        script.done = true;
    }
}

fn update_hud(
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    mut stats: ResMut<Stats>,
    terrains: Query<&Terrain>,
    mut hud: Query<&mut Text, With<Overlay>>,
) {
    for report in applied.read() {
        for (label, change) in report.volume_change.iter().flatten() {
            *stats.taken_out.entry(*label).or_default() -= change;
        }
        stats.last = Some(report.clone());
        stats.error = None;
    }
    if let Some(r) = rejected.read().last() {
        stats.error = Some(r.error.to_string());
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut lines = vec![
        "bevy_chisel quarry: exact destructible terrain".to_owned(),
        format!("{CARVING_HELP} | F5 save | F9 load"),
        format!("WASD/QE move | {ORBIT_HELP}"),
    ];
    for terrain in &terrains {
        let stats_line = terrain.octree().stats();
        lines.push(format!(
            "triangles {} | leaf cells {} | edits {} | undo {}",
            terrain.triangle_count(),
            stats_line.leaves,
            terrain.journal().len(),
            terrain.undo_depth()
        ));
    }
    match &stats.last {
        Some(last) => lines.push(format!(
            "last carve: kernel {:.2} ms, meshes {:.2} ms (off-thread), visible after {:.1} ms, {} cells",
            ms(last.apply_time),
            ms(last.mesh_time),
            ms(last.latency),
            last.cells
        )),
        None => lines.push("last carve: none yet".to_owned()),
    }
    if !stats.taken_out.is_empty() {
        let name = |label: u8| match label {
            ROCK => "rock",
            DIRT => "dirt",
            GRASS => "grass",
            ORE => "ore",
            _ => "other",
        };
        let parts: Vec<String> = (stats.taken_out.iter())
            .map(|(label, v)| format!("{} {v:.2}", name(*label)))
            .collect();
        lines.push(format!(
            "taken out, cubic metres (exact regions): {}",
            parts.join(" | ")
        ));
    }
    if let Some(e) = &stats.error {
        lines.push(format!("rejected: {e}"));
    }
    if let Some(m) = &stats.message {
        lines.push(m.clone());
    }
    for mut text in &mut hud {
        text.0 = lines.join("\n");
    }
}
