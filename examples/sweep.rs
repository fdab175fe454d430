//! The volume swept by a gear moving along a Bézier curve while turning
//! (paper 1 §5, Fig. 12), built step by step as exact unions of convex
//! pieces on a 1 µm grid.
//!
//! From one sample of the path to the next, every triangle of the gear's
//! mesh sweeps a prism — the hull of the triangle at both poses — and the
//! union of those prisms (with the gear's convex wedges at the start) is
//! the swept volume of the sampled motion
//! ([`bevy_chisel::bsp::tools::sweep`], the same geometry as `chisel
//! sweep`): each union is exact, and the prisms follow the turning gear
//! to within each step's sagitta (corners move along chords, not arcs).
//! Each prism is one `Carve` of a block of stone: added as brass, the
//! swept solid grows out of the block; subtracted, the gear cuts its slot
//! through it. The panel shows the time of every step in the
//! kernel and in all (re-meshing included).
//!
//! Controls: `M` switch between adding and carving (restarts), `Space`
//! pause, `R` restart; arrow keys or a left/middle drag orbit, the wheel
//! zooms, WASD and Q/E move the camera's focus.
//!
//! Runs in a window when a display exists; otherwise (or with
//! `CHISEL_HEADLESS=1`) it sweeps a coarser sampling of the path headless
//! and writes `screenshots/sweep-0008.png` (part way) and
//! `screenshots/sweep-0016.png` (the whole sweep).
//!
//! `cargo run --release --all-features --example sweep`

use std::f32::consts::FRAC_PI_2;
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::sweep::{GearSweep, WedgeMesh, spans_volume};
use bevy_chisel::bsp::tools::{Pose, Quantization};
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveShape, CarveTool, CellMesh, Terrain, TerrainBase,
    TerrainMaterials, TerrainPlugin, TerrainSystems,
};
use bevy_chisel::viewer::{ORBIT_HELP, OrbitCamera, Overlay, ViewerPlugin, overlay_text};

/// World units are millimetres (the sweep's own units); the grid is 1 µm.
const GRID_UNIT: f64 = 0.001;
const STONE: u8 = 1;
const BRASS: u8 = 2;
/// The block the gear passes through, mm (the sweep's frame, `z` up).
const BLOCK_MIN: [f64; 3] = [10.0, 10.0, 0.0];
const BLOCK_MAX: [f64; 3] = [90.0, 90.0, 40.0];
/// The octree cube: lower corner (mm) and edge `2^17` µm ≈ 131 mm, room
/// for the whole sweep (inside `[−5, 105]² × [0, 80]`).
const CUBE_MIN: [f64; 3] = [-10.0, -10.0, -10.0];
const CUBE_LOG2: u8 = 17;
/// Samples along the path: in a window as in `chisel sweep`; headless
/// fewer, so that the whole sweep fits in a CI run.
const SAMPLES: usize = 100;
const HEADLESS_SAMPLES: usize = 9;
/// Headless: steps done at the first screenshot, and frames shown there.
const HEADLESS_PAUSE_AT: usize = 4;
const HEADLESS_PAUSE_FRAMES: u32 = 10;

fn main() -> AppExit {
    let presentation = match Presentation::detect("sweep") {
        Presentation::Headless(config) => Presentation::Headless(HeadlessConfig {
            capture_frames: vec![8, 16],
            max_frames: 3000,
            ..config
        }),
        window => window,
    };
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — sweep");
    app.add_plugins((TerrainPlugin, ViewerPlugin))
        .insert_resource(ClearColor(Color::srgb(0.16, 0.17, 0.20)))
        .insert_resource(SweepRun::new(
            Edit::Add(BRASS),
            if headless { HEADLESS_SAMPLES } else { SAMPLES },
        ))
        .add_systems(Startup, spawn_scene)
        .add_systems(
            Update,
            (
                (keys, sweep_steps).chain().before(TerrainSystems::Carve),
                (record_timings, update_panel)
                    .chain()
                    .after(TerrainSystems::Mesh),
                draw_path,
            ),
        );
    if headless {
        app.insert_resource(HoldCaptures(true))
            .insert_resource(HeadlessPause {
                at: HEADLESS_PAUSE_AT,
                frames: 0,
            })
            .add_systems(Update, hold_captures.after(TerrainSystems::Mesh));
    }
    app.run()
}

/// The sweep in progress.
#[derive(Resource)]
struct SweepRun {
    sweep: GearSweep,
    gear: WedgeMesh,
    edit: Edit,
    samples: usize,
    /// The next step sweeps from sample `next` to `next + 1`.
    next: usize,
    paused: bool,
    /// The step being applied.
    current: Option<StepTiming>,
    /// Finished steps.
    done: Vec<StepTiming>,
    /// Prisms left out as flat, over all steps.
    flat: usize,
    rejected: usize,
}

/// What one step (one sample to the next) cost.
#[derive(Clone, Debug)]
struct StepTiming {
    pieces: usize,
    /// Kernel time of all its carves (off the main thread).
    kernel: Duration,
    started: Instant,
    /// From sending the carves to the last mesh in place.
    total: Duration,
}

impl SweepRun {
    fn new(edit: Edit, samples: usize) -> Self {
        let sweep = GearSweep::FIG12_MM;
        Self {
            gear: sweep.gear.mesh(),
            sweep,
            edit,
            samples,
            next: 0,
            paused: false,
            current: None,
            done: Vec::new(),
            flat: 0,
            rejected: 0,
        }
    }

    fn finished(&self) -> bool {
        self.next + 1 >= self.samples && self.current.is_none()
    }

    fn restart(&mut self) {
        *self = Self {
            paused: self.paused,
            ..Self::new(self.edit, self.samples)
        };
    }

    /// The gear's vertices at sample `k`, in world units (the terrain's
    /// local frame).
    fn placed(&self, k: usize) -> Vec<Vec3> {
        let pose = self.sweep.pose(k, self.samples);
        self.gear
            .vertices
            .iter()
            .map(|&v| Vec3::from_array(pose.apply(v).map(|c| c as f32)))
            .collect()
    }

    /// The carves of step `k`: the gear's wedges at sample 0 (first step
    /// only) and every sweep prism from sample `k` to `k + 1` that spans a
    /// volume once on the grid.
    fn step_tools(&mut self, k: usize, grid: &Quantization) -> Vec<CarveTool> {
        let on_grid = |points: &[Vec3]| -> Option<Vec<[i64; 3]>> {
            points
                .iter()
                .map(|p| grid.to_grid_f32(p.to_array()).ok().map(|g| g.coords()))
                .collect()
        };
        let hull =
            |points: Vec<Vec3>| CarveTool::new(CarveShape::Hull(points), Transform::IDENTITY);
        let from = self.placed(k);
        let to = self.placed(k + 1);
        let mut tools = Vec::new();
        if k == 0 {
            tools.extend(self.gear.wedge_points(&from).into_iter().map(hull));
        }
        for t in 0..self.gear.triangles.len() {
            let prism = self.gear.prism_points(t, &from, &to);
            // The same rounding as the carve's: a prism that is flat on the
            // grid would be a degenerate tool. (One off the grid is sent, to
            // be rejected with its reason.)
            if on_grid(&prism).is_none_or(|points| spans_volume(&points)) {
                tools.push(hull(prism));
            } else {
                self.flat += 1;
            }
        }
        tools
    }
}

/// Headless: wait at step `at` for a few counted frames (the first
/// screenshot), then go on to the end (the second).
#[derive(Resource)]
struct HeadlessPause {
    at: usize,
    frames: u32,
}

#[derive(Component)]
struct GearModel;

/// The block's materials, for a fresh block on restart.
#[derive(Resource)]
struct Palette(TerrainMaterials);

fn block_terrain() -> Result<Terrain, BevyError> {
    let grid = Quantization::new(GRID_UNIT, [0.0; 3])?;
    let to_grid = |p: [f64; 3]| grid.to_grid(p).map(|g| g.coords());
    let base = TerrainBase::Box {
        origin: to_grid(CUBE_MIN)?,
        size_log2: CUBE_LOG2,
        solid: CellBox {
            min: to_grid(BLOCK_MIN)?,
            max: to_grid(BLOCK_MAX)?,
        },
        label: STONE,
    };
    // Thousands of carves: no undo snapshots.
    Ok(Terrain::from_base(grid, base, OctreeConfig::default())?
        .with_max_undo(0)
        .with_labels([BRASS]))
}

/// The sweep's frame (`z` up) in the world (`y` up), with the block's
/// centre at the origin.
fn sweep_frame() -> Transform {
    let centre = Vec3::new(50.0, 50.0, 20.0);
    let rotation = Quat::from_rotation_x(-FRAC_PI_2);
    Transform::from_rotation(rotation).with_translation(-(rotation * centre))
}

/// The gear as a flat-shaded mesh.
fn gear_mesh(gear: &WedgeMesh) -> Mesh {
    let mut cell = CellMesh::default();
    for t in &gear.triangles {
        let [a, b, c] = t.map(|v| Vec3::from_array(gear.vertices[v].map(|x| x as f32)));
        let normal = (b - a).cross(c - a).normalize_or_zero().to_array();
        let first = cell.positions.len() as u32;
        cell.positions.extend([a, b, c].map(|p| p.to_array()));
        cell.normals.extend([normal; 3]);
        cell.indices.extend(first..first + 3);
    }
    cell.to_mesh()
}

fn spawn_scene(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    run: Res<SweepRun>,
) -> Result {
    let stone = materials.add(StandardMaterial {
        base_color: Color::srgb(0.62, 0.60, 0.56),
        perceptual_roughness: 0.85,
        ..default()
    });
    let brass = materials.add(StandardMaterial {
        base_color: Color::srgb(0.85, 0.62, 0.25),
        metallic: 0.8,
        perceptual_roughness: 0.35,
        ..default()
    });
    let table = TerrainMaterials::new([(STONE, stone.clone()), (BRASS, brass)], stone);
    commands.spawn((block_terrain()?, table.clone(), sweep_frame()));
    commands.insert_resource(Palette(table));
    commands.spawn((
        Mesh3d(meshes.add(gear_mesh(&run.gear))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgba(0.3, 0.7, 0.95, 0.6),
            alpha_mode: AlphaMode::Blend,
            ..default()
        })),
        gear_transform(&run, 0),
        GearModel,
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
    commands.spawn(
        OrbitCamera::new(Vec3::new(0.0, 12.0, 0.0), 165.0)
            .with_angles(0.8, 0.6)
            .with_drag([MouseButton::Left, MouseButton::Middle]),
    );
    commands.spawn(overlay_text());
    Ok(())
}

fn keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut run: ResMut<SweepRun>,
    palette: Res<Palette>,
    terrains: Query<Entity, With<Terrain>>,
    mut commands: Commands,
) -> Result {
    if keys.just_pressed(KeyCode::Space) {
        run.paused = !run.paused;
    }
    let switch = keys.just_pressed(KeyCode::KeyM);
    if switch {
        run.edit = match run.edit {
            Edit::Subtract => Edit::Add(BRASS),
            _ => Edit::Subtract,
        };
    }
    if switch || keys.just_pressed(KeyCode::KeyR) {
        run.restart();
        // A fresh block: the old one, its cells and any carve still running
        // on it are dropped.
        for entity in &terrains {
            commands.entity(entity).despawn();
        }
        commands.spawn((block_terrain()?, palette.0.clone(), sweep_frame()));
    }
    Ok(())
}

/// Sends the next step's carves once the previous step is in place, and
/// moves the gear model to the step's end.
fn sweep_steps(
    mut run: ResMut<SweepRun>,
    pause: Option<ResMut<HeadlessPause>>,
    terrains: Query<(Entity, &Terrain)>,
    mut gears: Query<&mut Transform, With<GearModel>>,
    mut carves: MessageWriter<Carve>,
) {
    let Some((entity, terrain)) = terrains.iter().next() else {
        return;
    };
    if !terrain.is_idle() {
        return;
    }
    if let Some(mut step) = run.current.take() {
        step.total = step.started.elapsed();
        run.done.push(step);
    }
    if let Some(mut pause) = pause
        && run.next == pause.at
        && pause.frames < HEADLESS_PAUSE_FRAMES
    {
        pause.frames += 1;
        return;
    }
    if run.paused || run.finished() {
        return;
    }
    let k = run.next;
    let tools = run.step_tools(k, terrain.quantization());
    run.current = Some(StepTiming {
        pieces: tools.len(),
        kernel: Duration::ZERO,
        started: Instant::now(),
        total: Duration::ZERO,
    });
    let edit = run.edit;
    carves.write_batch(tools.into_iter().map(|tool| Carve {
        terrain: entity,
        tool,
        edit,
    }));
    run.next += 1;
    for mut transform in &mut gears {
        *transform = gear_transform(&run, run.next);
    }
}

/// The gear model at sample `k`, in the world.
fn gear_transform(run: &SweepRun, k: usize) -> Transform {
    let pose: Pose = run.sweep.pose(k, run.samples);
    let r = pose.rotation.map(|row| row.map(|x| x as f32));
    // `Pose` is row-major; `Mat3` takes columns.
    let rotation = Mat3::from_cols_array_2d(&r).transpose();
    let local = Transform::from_translation(Vec3::from_array(pose.translation.map(|x| x as f32)))
        .with_rotation(Quat::from_mat3(&rotation));
    sweep_frame().mul_transform(local)
}

/// Headless: captures count only while the sweep waits at its pause or is
/// finished, with every mesh in place.
fn hold_captures(
    run: Res<SweepRun>,
    pause: Res<HeadlessPause>,
    terrains: Query<&Terrain>,
    mut hold: ResMut<HoldCaptures>,
) {
    let idle = terrains.iter().all(Terrain::is_idle);
    let waiting = run.next == pause.at && pause.frames < HEADLESS_PAUSE_FRAMES;
    hold.0 = !(idle && run.current.is_none() && (waiting || run.finished()));
}

fn record_timings(
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    mut run: ResMut<SweepRun>,
) {
    let kernel: Duration = applied.read().map(|a| a.apply_time).sum();
    let refused = rejected.read().count();
    run.rejected += refused;
    if let Some(step) = run.current.as_mut() {
        step.kernel += kernel;
    }
}

fn draw_path(
    run: Res<SweepRun>,
    frames: Query<&GlobalTransform, With<Terrain>>,
    mut gizmos: Gizmos,
) {
    for frame in &frames {
        let points = (0..=64).map(|i| {
            let p = run.sweep.curve.point(f64::from(i) / 64.0);
            frame.transform_point(Vec3::from_array(p.map(|x| x as f32)))
        });
        gizmos.linestrip(points, Color::srgb(0.95, 0.85, 0.3));
    }
}

fn update_panel(
    run: Res<SweepRun>,
    terrains: Query<&Terrain>,
    mut panel: Query<&mut Text, With<Overlay>>,
) {
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mode = match run.edit {
        Edit::Subtract => "carving the sweep out of the block",
        _ => "adding the sweep to the block",
    };
    let mut lines = vec![
        "bevy_chisel sweep: a gear along a Bezier curve, exact unions of sweep prisms (1 um grid)"
            .to_owned(),
        format!("M add/carve | Space pause | R restart | {ORBIT_HELP} | WASD/QE move"),
        format!(
            "{mode}: step {} of {}{}",
            run.next,
            run.samples - 1,
            if run.paused { " (paused)" } else { "" }
        ),
    ];
    if let Some(last) = run.done.last() {
        let pieces: usize = run.done.iter().map(|s| s.pieces).sum();
        let kernel: Duration = run.done.iter().map(|s| s.kernel).sum();
        lines.push(format!(
            "last step: {} prisms, kernel {:.1} ms ({:.2} ms per prism), {:.0} ms in all with meshes",
            last.pieces,
            ms(last.kernel),
            ms(last.kernel) / last.pieces.max(1) as f64,
            ms(last.total),
        ));
        lines.push(format!(
            "so far: {pieces} unions, kernel {:.2} ms per union on average; {} flat prisms left out",
            ms(kernel) / pieces.max(1) as f64,
            run.flat
        ));
    }
    if run.rejected > 0 {
        lines.push(format!("{} carves rejected", run.rejected));
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
