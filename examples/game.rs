//! A playable demo: walk over exact destructible terrain, blast it, and
//! watch what you cut loose fall.
//!
//! - A capsule character with a physics controller walks on the terrain's
//!   colliders, which are rebuilt with the meshes of every cell a carve
//!   changes. The physics engine is avian3d, or bevy_rapier3d with
//!   `--physics rapier` (or `CHISEL_PHYSICS=rapier`): the game is written
//!   once over a [`Body`] component (`game/physics.rs`), and the engine's
//!   module (`game/avian.rs`, `game/rapier.rs`) adds its plugins and copies
//!   the body to and from the simulation.
//! - Left click blasts a crater where the cursor points. Rock that is no
//!   longer connected to the ground — the slab of the bridge once both its
//!   pillars are gone, a boulder whose stalk is cut — is found exactly,
//!   taken out of the terrain and falls as a rigid body with a compound of
//!   convex hulls of its exact cells.
//! - Two quadric CSG props, drawn pixel-exact by the splat pass, stand on
//!   the ground and are solid: each has a voxel collider computed from the
//!   exact inside test of its solid.
//! - The HUD shows the times of the last carve: the exact kernel, the
//!   meshes, the colliders (both off the main thread), and the time until
//!   everything was in place.
//!
//! Controls: WASD walk, Shift run, Space jump, right-drag or arrow keys
//! look, wheel zoom, left click blast, R back to the start.
//!
//! Runs in a window when a display exists; otherwise (or with
//! `CHISEL_HEADLESS=1`) it plays a script headless and checks what a player
//! would see: the character lands and stands on the ground, walking into a
//! prop is stopped by it, and blasting the bridge's pillars and the
//! boulders' stalks drops them onto the ground. It writes
//! `screenshots/game-*.png` (`game-rapier-*.png` with Rapier) and fails if
//! any check fails.
//!
//! `cargo run --release --all-features --example game [-- --physics rapier]`

use std::f32::consts::FRAC_PI_2;
use std::time::Duration;

use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy::transform::TransformSystems;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::splat::prop_collider::{PropCollider, PropColliderShape};
use bevy_chisel::splat::{ChiselSplatPlugin, PropSplats, QuadricProp, SplatRadius};
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveShape, CarveTool, DebrisDetached, HeightLayer,
    Heightfield, Terrain, TerrainDebris, TerrainPlugin, TerrainSurface, TerrainSystems,
    TriplanarMaterial, TriplanarMaterialPlugin, surface_table,
};
use bevy_chisel::viewer::{Overlay, blast, overlay_text};

#[path = "game/avian.rs"]
mod avian;
#[path = "game/physics.rs"]
mod physics;
#[path = "game/rapier.rs"]
mod rapier;

use physics::{AfterPhysics, Body, PhysicsEngine};

const ROCK: u8 = 1;
const DIRT: u8 = 2;
const GRASS: u8 = 3;

/// Circumradius of a clicked crater (m).
const BLAST_RADIUS: f32 = 1.5;
/// Where the player starts, in x and z.
const START: [f32; 2] = [-4.0, 6.0];
/// The capsule: radius and the length of its straight part (m).
const PLAYER_RADIUS: f32 = 0.35;
const PLAYER_LENGTH: f32 = 0.9;
/// Walking and running speeds (m/s) and the jump's initial speed.
const WALK: f32 = 4.0;
const RUN: f32 = 8.0;
const JUMP: f32 = 5.5;

/// `(scene file, lowest z of the solid in scene units, scale, place on the
/// ground (x, z))`. Scenes are in millimetres, `z` up.
const PROPS: [(&str, f32, f32, [f32; 2]); 2] = [
    ("scenes/classic.quadric.ron", -50.0, 0.02, [-4.0, 0.5]),
    ("scenes/three_spheres.quadric.ron", -34.6, 0.03, [2.5, 4.0]),
];

/// The bridge: two pillars at these `(x, z)` and a slab between them,
/// `BRIDGE_HEIGHT` above the higher foot.
const PILLARS: [[f32; 2]; 2] = [[-8.0, -4.0], [-2.0, -4.0]];
const BRIDGE_HEIGHT: f32 = 2.6;
/// Boulders balanced on thin stalks, `(x, z)`.
const BOULDERS: [[f32; 2]; 3] = [[1.0, -2.5], [3.5, -1.0], [-11.0, 1.0]];
const STALK: f32 = 1.1;

fn main() -> AppExit {
    let engine = match PhysicsEngine::from_args_or_env() {
        Ok(engine) => engine,
        Err(e) => {
            eprintln!("game: {e}");
            return AppExit::error();
        }
    };
    let stem = match engine {
        PhysicsEngine::Avian => "game",
        PhysicsEngine::Rapier => "game-rapier",
    };
    let presentation = match Presentation::detect(stem) {
        Presentation::Headless(config) => Presentation::Headless(HeadlessConfig {
            capture_frames: vec![25, 105, 140],
            width: 640,
            height: 360,
            max_frames: 2000,
            ..config
        }),
        window => window,
    };
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — game");
    app.add_plugins((TerrainPlugin, TriplanarMaterialPlugin, ChiselSplatPlugin));
    engine.add_to(&mut app, headless);
    app.configure_sets(PostUpdate, AfterPhysics.before(TransformSystems::Propagate))
        .insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
        .init_resource::<PlayerInput>()
        .init_resource::<Hud>()
        .add_systems(Startup, spawn_scene)
        .add_systems(
            Update,
            (
                move_player,
                record_carves.after(TerrainSystems::Mesh),
                update_hud.after(TerrainSystems::Mesh),
                tidy_debris,
            ),
        )
        .add_systems(PostUpdate, follow_player.in_set(AfterPhysics));
    if headless {
        // One frame is 1/20 s of game time and of physics (the engine's
        // module sets its steps), whatever a CPU renderer takes to draw
        // it: the script's timing does not depend on the machine.
        app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            1.0 / 20.0,
        )))
        // Smaller shadow maps.
        .insert_resource(bevy::light::DirectionalLightShadowMap { size: 1024 })
        // No multisampling: on the CPU renderer 4x MSAA more than doubles
        // the cost of a frame (the terrain's main pass), while the checks
        // (physics, debris, screenshot content) do not depend on it.
        .add_observer(|add: On<Add, Camera3d>, mut commands: Commands| {
            commands.entity(add.entity).insert(Msaa::Off);
        })
        .insert_resource(HoldCaptures(true))
        .init_resource::<Script>()
        .add_systems(
            Update,
            play_script
                .before(move_player)
                .before(TerrainSystems::Carve),
        );
    } else {
        app.add_systems(
            Update,
            (
                keyboard_input.before(move_player),
                look,
                click_blast.before(TerrainSystems::Carve),
            ),
        );
    }
    app.run()
}

/// Where the script blasts: the middle of each pillar and each stalk, as
/// `(centre, crater radius)`.
#[derive(Resource, Default)]
struct Supports(Vec<(Vec3, f32)>);

/// The terrain: the quarry heightfield on a 1 mm grid, with a rock bridge
/// and balanced boulders added by exact carves.
fn build_terrain() -> Result<(Terrain, Supports), BevyError> {
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
    let mut terrain = Terrain::from_heightfield(grid, &field)?;
    let mut supports = Supports::default();
    let add = |terrain: &mut Terrain, shape: CarveShape, pose: Transform| -> Result {
        let tool = CarveTool::new(shape, pose).to_grid(terrain.quantization())?;
        terrain.apply_now(&tool, Edit::Add(ROCK))?;
        Ok(())
    };
    // The bridge.
    let feet = PILLARS.map(|spot| ground(&terrain, spot).unwrap_or(Vec3::ZERO));
    let deck = feet[0].y.max(feet[1].y) + BRIDGE_HEIGHT;
    for foot in feet {
        supports.0.push((foot + Vec3::Y * 1.3, 1.2));
        let height = deck - foot.y + 0.6;
        add(
            &mut terrain,
            CarveShape::Cuboid {
                half_size: Vec3::new(0.45, height / 2.0, 0.45),
            },
            Transform::from_translation(Vec3::new(foot.x, foot.y - 0.6 + height / 2.0, foot.z)),
        )?;
    }
    let middle = (feet[0] + feet[1]) / 2.0;
    let span = (feet[1] - feet[0]).with_y(0.0);
    add(
        &mut terrain,
        CarveShape::Cuboid {
            half_size: Vec3::new(span.length() / 2.0 + 0.8, 0.3, 0.7),
        },
        Transform::from_translation(middle.with_y(deck + 0.3))
            .with_rotation(Quat::from_rotation_y(-span.z.atan2(span.x))),
    )?;
    // The boulders, each on a stalk.
    for (k, spot) in BOULDERS.into_iter().enumerate() {
        let Some(foot) = ground(&terrain, spot) else {
            continue;
        };
        supports.0.push((foot + Vec3::Y * 0.6, 0.55));
        add(
            &mut terrain,
            CarveShape::Prism {
                sides: 6,
                radius: 0.22,
                length: STALK + 0.5,
            },
            Transform::from_translation(foot - Vec3::Y * 0.3)
                .with_rotation(Quat::from_rotation_x(-FRAC_PI_2)),
        )?;
        add(
            &mut terrain,
            CarveShape::Dodecahedron { radius: 0.75 },
            Transform::from_translation(foot + Vec3::Y * (STALK + 0.55))
                .with_rotation(Quat::from_rotation_y(0.8 * k as f32)),
        )?;
    }
    terrain.clear_undo();
    Ok((terrain, supports))
}

/// The ground under `(x, z)`.
fn ground(terrain: &Terrain, [x, z]: [f32; 2]) -> Option<Vec3> {
    let down = Ray3d::new(Vec3::new(x, 50.0, z), Dir3::NEG_Y);
    terrain.ray_cast(down, 100.0).map(|hit| hit.point)
}

/// The player's character.
#[derive(Component)]
#[require(Body)]
struct Player;

/// What the player wants to do this frame: from the keyboard and the
/// camera, or from the headless script.
#[derive(Resource, Default)]
struct PlayerInput {
    /// Walking direction in world x and z (length at most 1).
    walk: Vec2,
    run: bool,
    jump: bool,
}

/// The third-person camera around the player.
#[derive(Component)]
struct ThirdPerson {
    yaw: f32,
    pitch: f32,
    distance: f32,
    /// How far from the target something blocks the view (`None`: the
    /// view is clear up to `distance`); found by the engine's ray cast
    /// after each physics step.
    blocked_at: Option<f32>,
}

impl ThirdPerson {
    /// The direction from the target to the camera.
    fn back(&self) -> Vec3 {
        Quat::from_euler(EulerRot::YXZ, self.yaw, -self.pitch, 0.0) * Vec3::Z
    }
}

/// What the camera looks at: the player's head.
fn camera_target(player: Vec3) -> Vec3 {
    player + Vec3::Y * 0.8
}

fn spawn_scene(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut materials: ResMut<Assets<TriplanarMaterial>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
) -> Result {
    let table = surface_table(
        &mut materials,
        [
            (ROCK, TerrainSurface::Rock),
            (DIRT, TerrainSurface::Dirt),
            (GRASS, TerrainSurface::Grass),
        ],
        TerrainSurface::Rock,
    );
    let (terrain, supports) = build_terrain()?;
    commands.insert_resource(supports);
    for (path, bottom, scale, spot) in PROPS {
        let Some(foot) = ground(&terrain, spot) else {
            continue;
        };
        commands.spawn((
            QuadricProp {
                scene: assets.load(path),
                bounds: None,
                radius: SplatRadius::Auto(40.0),
            },
            Transform::from_translation(foot + Vec3::Y * (-bottom * scale - 0.1))
                .with_rotation(Quat::from_rotation_x(-FRAC_PI_2))
                .with_scale(Vec3::splat(scale)),
        ));
    }
    let start = ground(&terrain, START).unwrap_or(Vec3::ZERO) + Vec3::Y * 2.5;
    commands.spawn((terrain, table, Name::new("terrain")));
    commands.spawn((
        Player,
        Name::new("player"),
        Mesh3d(meshes.add(Capsule3d::new(PLAYER_RADIUS, PLAYER_LENGTH))),
        MeshMaterial3d(standard.add(StandardMaterial {
            base_color: Color::srgb(0.85, 0.25, 0.15),
            perceptual_roughness: 0.6,
            ..default()
        })),
        Transform::from_translation(start),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 10_000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(12.0, 25.0, 8.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.insert_resource(GlobalAmbientLight {
        brightness: 300.0,
        ..default()
    });
    commands.spawn((
        Camera3d::default(),
        ThirdPerson {
            yaw: 0.0,
            pitch: 0.55,
            distance: 8.0,
            blocked_at: None,
        },
        Transform::from_translation(start + Vec3::new(0.0, 3.0, 7.0)),
    ));
    commands.spawn(overlay_text());
    Ok(())
}

/// Steers the capsule: horizontal velocity follows the input quickly (on
/// the ground) or slowly (in the air); gravity does the rest.
fn move_player(
    time: Res<Time>,
    mut input: ResMut<PlayerInput>,
    mut players: Query<&mut Body, With<Player>>,
) {
    let dt = time.delta_secs();
    for mut body in &mut players {
        let on_ground = body.grounded;
        let velocity = &mut body.velocity;
        let speed = if input.run { RUN } else { WALK };
        let wanted = input.walk.clamp_length_max(1.0) * speed;
        let current = Vec2::new(velocity.x, velocity.z);
        let rate = if on_ground { 12.0 } else { 2.0 };
        let next = current.lerp(wanted, (rate * dt).min(1.0));
        velocity.x = next.x;
        velocity.z = next.y;
        if input.jump && on_ground {
            velocity.y = JUMP;
        }
    }
    input.jump = false;
}

/// Keyboard input, relative to where the camera looks.
fn keyboard_input(
    keys: Res<ButtonInput<KeyCode>>,
    cameras: Query<&ThirdPerson>,
    mut input: ResMut<PlayerInput>,
    mut players: Query<(&mut Transform, &mut Body), With<Player>>,
    terrains: Query<&Terrain>,
) {
    let Ok(camera) = cameras.single() else {
        return;
    };
    let mut local = Vec2::ZERO;
    for (key, dir) in [
        (KeyCode::KeyW, Vec2::new(0.0, -1.0)),
        (KeyCode::KeyS, Vec2::new(0.0, 1.0)),
        (KeyCode::KeyA, Vec2::new(-1.0, 0.0)),
        (KeyCode::KeyD, Vec2::new(1.0, 0.0)),
    ] {
        if keys.pressed(key) {
            local += dir;
        }
    }
    input.walk = Vec2::from_angle(-camera.yaw).rotate(local.normalize_or_zero());
    input.run = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    input.jump |= keys.just_pressed(KeyCode::Space);
    if keys.just_pressed(KeyCode::KeyR) {
        let start = terrains
            .iter()
            .find_map(|t| ground(t, START))
            .unwrap_or(Vec3::ZERO);
        for (mut transform, mut body) in &mut players {
            transform.translation = start + Vec3::Y * 2.0;
            body.velocity = Vec3::ZERO;
        }
    }
}

/// Right-drag or the arrow keys turn the camera; the wheel zooms.
fn look(
    time: Res<Time>,
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    mut cameras: Query<&mut ThirdPerson>,
) {
    let dt = time.delta_secs();
    for mut camera in &mut cameras {
        let mut turn = Vec2::ZERO;
        if buttons.pressed(MouseButton::Right) {
            turn += motion.delta * 0.005;
        }
        for (key, dir) in [
            (KeyCode::ArrowLeft, Vec2::new(-1.0, 0.0)),
            (KeyCode::ArrowRight, Vec2::new(1.0, 0.0)),
            (KeyCode::ArrowUp, Vec2::new(0.0, -1.0)),
            (KeyCode::ArrowDown, Vec2::new(0.0, 1.0)),
        ] {
            if keys.pressed(key) {
                turn += dir * 1.8 * dt;
            }
        }
        camera.yaw -= turn.x;
        camera.pitch = (camera.pitch + turn.y).clamp(-0.3, 1.4);
        camera.distance = (camera.distance * (1.0 - 0.1 * scroll.delta.y)).clamp(2.5, 30.0);
    }
}

/// Puts the camera behind the player, pulled in where the view is
/// blocked.
fn follow_player(
    players: Query<&Transform, (With<Player>, Without<ThirdPerson>)>,
    mut cameras: Query<(&ThirdPerson, &mut Transform)>,
) {
    let Ok(body) = players.single() else {
        return;
    };
    let target = camera_target(body.translation);
    for (view, mut transform) in &mut cameras {
        let distance = view
            .blocked_at
            .map_or(view.distance, |blocked| (blocked - 0.3).max(0.5));
        transform.translation = target + view.back() * distance;
        transform.look_at(target, Vec3::Y);
    }
}

/// A left click blasts a crater where the cursor points.
fn click_blast(
    buttons: Res<ButtonInput<MouseButton>>,
    windows: Query<&Window>,
    cameras: Query<(&Camera, &GlobalTransform), With<ThirdPerson>>,
    terrains: Query<(Entity, &Terrain)>,
    mut carves: MessageWriter<Carve>,
) {
    if !buttons.just_pressed(MouseButton::Left) {
        return;
    }
    let Some(cursor) = windows.iter().find_map(Window::cursor_position) else {
        return;
    };
    let Ok((camera, transform)) = cameras.single() else {
        return;
    };
    let Ok(ray) = camera.viewport_to_world(transform, cursor) else {
        return;
    };
    for (entity, terrain) in &terrains {
        if let Some(hit) = terrain.ray_cast(ray, 200.0) {
            carves.write(Carve {
                terrain: entity,
                tool: blast(hit.point, BLAST_RADIUS, terrain.journal().len()),
                edit: Edit::Subtract,
            });
        }
    }
}

/// Debris that fell out of the world, or too much of it, is removed.
fn tidy_debris(
    debris: Query<(Entity, &GlobalTransform), With<TerrainDebris>>,
    mut commands: Commands,
) {
    const KEEP: usize = 64;
    let all: Vec<(Entity, &GlobalTransform)> = debris.iter().collect();
    let excess = all.len().saturating_sub(KEEP);
    for (k, (entity, transform)) in all.into_iter().enumerate() {
        if k < excess || transform.translation().y < -50.0 {
            commands.entity(entity).despawn();
        }
    }
}

/// What the HUD shows.
#[derive(Resource, Default)]
struct Hud {
    last: Option<CarveApplied>,
    rejected: Option<String>,
    pieces: usize,
    last_piece: Option<(f32, u8)>,
    frame_ms: f32,
}

fn record_carves(
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    mut detached: MessageReader<DebrisDetached>,
    mut hud: ResMut<Hud>,
) {
    if let Some(last) = applied.read().last() {
        hud.last = Some(last.clone());
        hud.rejected = None;
    }
    if let Some(r) = rejected.read().last() {
        hud.rejected = Some(r.error.to_string());
    }
    for piece in detached.read() {
        hud.pieces += 1;
        hud.last_piece = Some((piece.volume, piece.main_label));
    }
}

fn update_hud(
    real: Res<Time<Real>>,
    mut hud: ResMut<Hud>,
    terrains: Query<&Terrain>,
    players: Query<(&Transform, &Body), With<Player>>,
    props: Query<Option<&PropCollider>, With<QuadricProp>>,
    mut text: Query<&mut Text, With<Overlay>>,
) {
    let dt = real.delta_secs() * 1e3;
    hud.frame_ms = if hud.frame_ms == 0.0 {
        dt
    } else {
        0.9 * hud.frame_ms + 0.1 * dt
    };
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let mut lines = vec![
        "bevy_chisel game: exact destructible terrain".to_owned(),
        "WASD walk | Shift run | Space jump | R restart".to_owned(),
        "right-drag or arrows look | wheel zoom | LMB blast".to_owned(),
    ];
    for terrain in &terrains {
        lines.push(format!(
            "terrain: {} triangles, {} leaf cells, {} carves | frame {:.1} ms",
            terrain.triangle_count(),
            terrain.octree().stats().leaves,
            terrain.journal().len(),
            hud.frame_ms
        ));
    }
    match &hud.last {
        Some(a) => lines.push(format!(
            "last carve ({} cells): kernel {:.2}, meshes {:.2}, colliders {:.2} ms\n\
             in place after {:.1} ms",
            a.cells,
            ms(a.apply_time),
            ms(a.mesh_time),
            ms(a.collider_time),
            ms(a.latency),
        )),
        None => lines.push("last carve: none yet (left click to blast)".to_owned()),
    }
    let piece = hud.last_piece.map_or(String::new(), |(volume, label)| {
        let name = match label {
            GRASS => "grass",
            DIRT => "dirt",
            _ => "rock",
        };
        format!(", the last {volume:.2} cubic metres of {name}")
    });
    lines.push(format!("debris: {} pieces cut loose{piece}", hud.pieces));
    let solid = props.iter().filter(|c| c.is_some()).count();
    lines.push(format!("props: {solid} of {} solid", props.iter().count()));
    for (transform, body) in &players {
        let p = transform.translation;
        lines.push(format!(
            "player at ({:.1}, {:.1}, {:.1}), {:.1} m/s, {}",
            p.x,
            p.y,
            p.z,
            body.velocity.length(),
            if body.grounded {
                "on the ground"
            } else {
                "in the air"
            }
        ));
    }
    if let Some(r) = &hud.rejected {
        lines.push(format!("rejected: {r}"));
    }
    for mut t in &mut text {
        t.0 = lines.join("\n");
    }
}

/// The headless script and its checks. Frames count from the moment the
/// terrain, the props' splats and their colliders are all in.
#[derive(Resource, Default)]
struct Script {
    frame: u32,
    /// Where the player was when it started to walk.
    walk_from: Option<Vec3>,
    /// The player touched the prop it walks to.
    touched_prop: bool,
    /// Debris pieces: entity and the height it was cut loose at.
    debris: Vec<(Entity, f32)>,
    failures: Vec<String>,
}

/// Frames of the script.
const LANDED: u32 = 30;
const WALKED: u32 = 90;
const BLAST: u32 = 95;
const CHECK_DEBRIS: u32 = 135;

#[allow(clippy::too_many_arguments)]
fn play_script(
    mut script: ResMut<Script>,
    mut hold: ResMut<HoldCaptures>,
    mut input: ResMut<PlayerInput>,
    terrains: Query<(Entity, &Terrain)>,
    props: Query<(Entity, &Transform, Has<PropSplats>, Has<PropCollider>), With<QuadricProp>>,
    prop_shapes: Query<&ChildOf, With<PropColliderShape>>,
    players: Query<(&Transform, &Body), With<Player>>,
    debris: Query<&GlobalTransform, With<TerrainDebris>>,
    mut detached: MessageReader<DebrisDetached>,
    mut carves: MessageWriter<Carve>,
    mut exit: MessageWriter<AppExit>,
    supports: Res<Supports>,
) {
    let ready = terrains.iter().all(|(_, t)| t.is_idle())
        && props.iter().count() == PROPS.len()
        && props.iter().all(|(_, _, splats, solid)| splats && solid);
    if hold.0 && !ready {
        return;
    }
    hold.0 = false;
    script.frame += 1;
    let frame = script.frame;
    for piece in detached.read() {
        script.debris.push((piece.entity, piece.centre.y));
    }
    let Ok((player, body)) = players.single() else {
        return;
    };
    let at = player.translation;
    let Some((terrain_entity, terrain)) = terrains.iter().next() else {
        return;
    };
    let mut failures = Vec::new();
    let mut check = |ok: bool, what: String| {
        if ok {
            println!("game: ok: {what}");
        } else {
            eprintln!("game: FAILED: {what}");
            failures.push(what);
        }
    };
    match frame {
        LANDED => {
            let floor = ground(terrain, [at.x, at.z]).map_or(f32::NAN, |g| g.y);
            let standing = at.y - floor;
            check(
                body.grounded && (0.5..1.3).contains(&standing),
                format!(
                    "the player landed and stands on the ground (centre {standing:.2} m above it)"
                ),
            );
            script.walk_from = Some(at);
        }
        f if f > LANDED && f < WALKED => {
            // Straight at the first prop, for three seconds: far enough to
            // pass through it if it were not solid.
            input.walk = Vec2::new(0.0, -1.0);
            // A prop's collider is on a child of the prop (its shape).
            script.touched_prop |= body.touching.iter().any(|&touched| {
                prop_shapes
                    .get(touched)
                    .is_ok_and(|shape| props.contains(shape.parent()))
            });
        }
        WALKED => {
            input.walk = Vec2::ZERO;
            let (_, prop, _, _) = props
                .iter()
                .min_by(|a, b| {
                    let d = |t: &Transform| t.translation.distance(at);
                    d(a.1).total_cmp(&d(b.1))
                })
                .expect("the props are in");
            // Three seconds of walking would take the player 12 m, through
            // the cube and 6 m beyond it, if it were not solid. It touches
            // the cube and is stopped in its near half (it presses into
            // the bore facing it: the controller pushes hard).
            let from = script.walk_from.map_or(at.z, |p| p.z);
            let half = 50.0 * PROPS[0].2;
            let far_side = prop.translation.z - half;
            check(
                script.touched_prop && from - at.z > 2.0 && at.z - far_side > half,
                format!(
                    "walking into the prop was stopped by it (walked {:.1} m, {:.2} m before its \
                     far side, touched it: {})",
                    from - at.z,
                    at.z - far_side,
                    script.touched_prop
                ),
            );
        }
        BLAST => {
            for (k, &(centre, radius)) in supports.0.iter().enumerate() {
                carves.write(Carve {
                    terrain: terrain_entity,
                    tool: blast(centre, radius, k),
                    edit: Edit::Subtract,
                });
            }
        }
        CHECK_DEBRIS => {
            let fallen = script
                .debris
                .iter()
                .filter(|(entity, from)| {
                    debris
                        .get(*entity)
                        .is_ok_and(|t| t.translation().y < from - 0.5 && t.translation().y > -8.0)
                })
                .count();
            check(
                script.debris.len() >= 2 && fallen == script.debris.len(),
                format!(
                    "the blasts cut {} pieces loose, {fallen} fell onto the ground",
                    script.debris.len()
                ),
            );
        }
        _ => {}
    }
    script.failures.extend(failures);
    if frame >= CHECK_DEBRIS && !script.failures.is_empty() {
        exit.write(AppExit::error());
    }
}
