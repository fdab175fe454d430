//! CNC milling (paper 1 §5): a spinning drill bit cuts a pocket and a
//! circular groove into a block, one subtraction per step.
//!
//! Each step subtracts the convex hull of the bit, a hexagonal prism, at
//! two consecutive poses from an exact octree-BSP block on a 10 µm grid.
//! The subtraction is exact, and so would the tool be if the bit only
//! moved: a convex solid moved without turning sweeps exactly the hull of
//! its start and end poses. But the bit also turns by `SPIN_PER_STEP`
//! about its axis each step, and a turning prism sweeps curved surfaces,
//! which no union of convex polyhedra is. The hull of the two poses
//! stands in for that sweep, neither inside it nor around it: it misses
//! thin slivers outside the chords of the arcs the corners travel (up to
//! `BIT_RADIUS · (1 − cos(SPIN_PER_STEP / 2))`, 0.05 mm here) and takes in
//! material between the corners that the turning prism never reaches (up
//! to about 0.18 mm here). The on-screen panel shows the time per step
//! in the kernel and in re-meshing.
//!
//! Controls: `Space` pause, `R` take the bit back to the start of its
//! path (the block stays as cut); arrow keys or a left/middle drag orbit,
//! the wheel zooms.
//!
//! Runs in a window when a display exists; otherwise mills headless and
//! writes PNG screenshots to `screenshots/`.
//!
//! `cargo run --release --all-features --example milling`

use std::f32::consts::{FRAC_PI_2, TAU};
use std::time::Duration;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, Presentation};
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveShape, CarveTool, Terrain, TerrainMaterials, TerrainPlugin,
    TerrainSystems,
};
use bevy_chisel::viewer::{ORBIT_HELP, OrbitCamera, Overlay, ViewerPlugin, overlay_text};

/// World units are millimetres; the grid step is 0.01 mm.
const GRID_UNIT: f64 = 0.01;
/// Drill bit: hexagonal prism, circumradius and length (mm).
const BIT_RADIUS: f32 = 3.0;
const BIT_LENGTH: f32 = 30.0;
/// Turn of the bit about its axis per step (rad).
const SPIN_PER_STEP: f32 = 0.35;

fn main() -> AppExit {
    let presentation = match Presentation::detect("milling") {
        Presentation::Headless(config) => Presentation::Headless(HeadlessConfig {
            capture_frames: vec![8, 16],
            max_frames: 200,
            ..config
        }),
        window => window,
    };
    let steps_per_frame = match presentation {
        Presentation::Headless(_) => 20,
        Presentation::Window => 1,
    };
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — milling");
    app.add_plugins((TerrainPlugin, ViewerPlugin))
        .insert_resource(ClearColor(Color::srgb(0.16, 0.17, 0.20)))
        .insert_resource(Mill {
            path: tool_path(),
            next: 0,
            steps_per_frame,
            times: Vec::new(),
            paused: false,
        })
        .add_systems(Startup, spawn_scene)
        .add_systems(
            Update,
            (
                mill_steps.before(TerrainSystems::Carve),
                update_panel.after(TerrainSystems::Mesh),
            ),
        )
        .run()
}

/// Tip positions of the bit, in order: a zig-zag pocket 2 mm deep, then a
/// circular groove 5 mm deep around it.
fn tool_path() -> Vec<Vec3> {
    let mut path = Vec::new();
    let (x0, x1, step) = (-30.0f32, 30.0f32, 3.0f32);
    let mut forward = true;
    let mut z = -12.0f32;
    while z <= 12.0 {
        let n = ((x1 - x0) / step) as i32;
        for k in 0..=n {
            let t = k as f32 * step;
            let x = if forward { x0 + t } else { x1 - t };
            path.push(Vec3::new(x, -2.0, z));
        }
        forward = !forward;
        z += 4.0;
    }
    let segments = 72;
    for k in 0..=segments {
        let a = k as f32 / segments as f32 * TAU;
        path.push(Vec3::new(40.0 * a.cos(), -5.0, 20.0 * a.sin()));
    }
    path
}

/// Pose of the bit with its tip at `tip`, axis up, turned by `spin`.
fn bit_pose(tip: Vec3, spin: f32) -> Transform {
    Transform::from_translation(tip)
        .with_rotation(Quat::from_rotation_y(spin) * Quat::from_rotation_x(-FRAC_PI_2))
}

#[derive(Resource)]
struct Mill {
    path: Vec<Vec3>,
    next: usize,
    steps_per_frame: usize,
    /// Kernel and mesh time of every applied step.
    times: Vec<(Duration, Duration)>,
    paused: bool,
}

#[derive(Component)]
struct Bit;

fn spawn_scene(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) -> Result {
    let grid = Quantization::new(GRID_UNIT, [0.0; 3])?;
    let block = Terrain::from_box(
        grid,
        Vec3::new(-50.0, -25.0, -30.0),
        Vec3::new(50.0, 0.0, 30.0),
        1,
    )?;
    let aluminium = materials.add(StandardMaterial {
        base_color: Color::srgb(0.75, 0.77, 0.80),
        metallic: 0.8,
        perceptual_roughness: 0.35,
        ..default()
    });
    commands.spawn((
        block,
        TerrainMaterials::new([(1, aluminium.clone())], aluminium),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Cylinder::new(BIT_RADIUS, BIT_LENGTH))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.85, 0.55, 0.15),
            metallic: 0.9,
            perceptual_roughness: 0.3,
            ..default()
        })),
        Transform::from_xyz(0.0, 40.0, 0.0),
        Bit,
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 9_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(60.0, 120.0, 40.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 500.0,
        ..default()
    });
    commands.spawn(OrbitCamera {
        min_distance: 20.0,
        max_distance: 600.0,
        move_keys: false,
        ..OrbitCamera::new(Vec3::new(0.0, -8.0, 0.0), 150.0)
            .with_angles(0.9, 0.75)
            .with_drag([MouseButton::Left, MouseButton::Middle])
    });
    commands.spawn(overlay_text());
    Ok(())
}

/// Sends the next steps of the path once the previous ones are applied.
fn mill_steps(
    keys: Res<ButtonInput<KeyCode>>,
    mut mill: ResMut<Mill>,
    terrains: Query<(Entity, &Terrain)>,
    mut bits: Query<&mut Transform, With<Bit>>,
    mut carves: MessageWriter<Carve>,
) {
    if keys.just_pressed(KeyCode::Space) {
        mill.paused = !mill.paused;
    }
    if keys.just_pressed(KeyCode::KeyR) {
        mill.next = 0;
    }
    let Some((entity, terrain)) = terrains.iter().next() else {
        return;
    };
    if mill.paused || !terrain.is_idle() || mill.next + 1 >= mill.path.len() {
        return;
    }
    let shape = CarveShape::Prism {
        sides: 6,
        radius: BIT_RADIUS,
        length: BIT_LENGTH,
    };
    for _ in 0..mill.steps_per_frame {
        let k = mill.next;
        if k + 1 >= mill.path.len() {
            break;
        }
        let (a, b) = (mill.path[k], mill.path[k + 1]);
        let spin = SPIN_PER_STEP * k as f32;
        carves.write(Carve {
            terrain: entity,
            tool: CarveTool::swept(
                shape.clone(),
                bit_pose(a, spin),
                bit_pose(b, spin + SPIN_PER_STEP),
            ),
            edit: Edit::Subtract,
        });
        mill.next += 1;
        for mut transform in &mut bits {
            *transform = Transform::from_translation(b + Vec3::Y * (BIT_LENGTH / 2.0))
                .with_rotation(Quat::from_rotation_y(spin));
        }
    }
}

fn update_panel(
    mut applied: MessageReader<CarveApplied>,
    mut mill: ResMut<Mill>,
    terrains: Query<&Terrain>,
    mut panel: Query<&mut Text, With<Overlay>>,
) {
    for a in applied.read() {
        mill.times.push((a.apply_time, a.mesh_time));
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut lines = vec![
        "bevy_chisel milling: exact subtractions of the hull of two bit poses (10 um grid)"
            .to_owned(),
        format!("{ORBIT_HELP} | Space pause | R restart path"),
        format!(
            "step {} of {}",
            mill.next,
            mill.path.len().saturating_sub(1)
        ),
    ];
    if let Some(&(apply, mesh)) = mill.times.last() {
        let mut kernel: Vec<f64> = mill.times.iter().map(|t| ms(t.0)).collect();
        kernel.sort_by(f64::total_cmp);
        let median = kernel[kernel.len() / 2];
        lines.push(format!(
            "last step: kernel {:.2} ms, meshes {:.2} ms (per batch, off-thread) | median kernel {median:.2} ms over {} steps",
            ms(apply),
            ms(mesh),
            kernel.len()
        ));
    }
    for terrain in &terrains {
        let stats = terrain.octree().stats();
        lines.push(format!(
            "triangles {} | leaf cells {} | BSP nodes {}",
            terrain.triangle_count(),
            stats.leaves,
            stats.bsp_nodes
        ));
    }
    for mut text in &mut panel {
        text.0 = lines.join("\n");
    }
}
