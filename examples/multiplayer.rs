//! Multiplayer carving: one authoritative server, clients that see each
//! other's craters live, every peer with a bit-identical terrain.
//!
//! ```text
//! cargo run --release --all-features --example multiplayer -- --host            # terminal 1: plays and serves
//! cargo run --release --all-features --example multiplayer -- --client 127.0.0.1:5000   # terminal 2, 3, …
//! cargo run --release --all-features --example multiplayer -- --server          # or a dedicated server
//! ```
//!
//! `--host [ADDR]` opens a window and listens (default `0.0.0.0:5000`): a
//! listen server whose own player carves through the server's order like
//! everyone else. `--server [ADDR]` listens without a window (a dedicated
//! server). `--client ADDR` opens a window and joins. In a window, left
//! click blasts a crater and right click heaps up dirt, and the server
//! sends every player's carve to everyone. Z undoes your latest carve and
//! Y redoes it (the host may undo anyone's): undos go through the
//! server's order too. The HUD shows the carves in the
//! terrain, its state hash, and the hash checks passed (a client) or the
//! carves ordered (the host).
//!
//! A player's app adds both `NetServerPlugin` and `NetClientPlugin` and
//! picks its role at run time; it writes the same `NetCarveRequest`s as a
//! host or a client (`bevy_chisel::net`, "Roles"). A client predicts its
//! own carves (`NetClientSettings::predict_own_carves`): its craters show
//! without waiting for the server, and are rolled back and applied again
//! in the server's order when another player's carve came first.
//!
//! With no arguments and no display (or `CHISEL_HEADLESS=1`), one process
//! runs a host and two scripted players on 127.0.0.1 (each in its own
//! thread, each its own Bevy app talking UDP), plus a third player that
//! renders offscreen; the host, a player too, blasts one crater. Once the
//! offscreen player has applied every crater it writes
//! `screenshots/multiplayer-*.png` and checks that its octree is the
//! host's, bit for bit.

use std::net::{Ipv4Addr, SocketAddr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::net::{
    NetCarveRequest, NetCarveResult, NetClientPlugin, NetClientSettings, NetClientStats,
    NetServerPlugin, NetServerStats, NetTerrain, NetUndoResult, Outcome, WireTool, start_client,
    start_server,
};
use bevy_chisel::presentation::{HeadlessConfig, HoldCaptures, Presentation};
use bevy_chisel::terrain::{
    CarveShape, CarveTool, CellOutput, RedoCarve, Terrain, TerrainBase, TerrainPlugin,
    TerrainSettings, TerrainSurface, TerrainSystems, TriplanarMaterial, TriplanarMaterialPlugin,
    UndoCarve, surface_table,
};
use bevy_chisel::viewer::{
    CursorPick, ORBIT_HELP, OrbitCamera, Overlay, ViewerPlugin, blast, overlay_text,
};

const ROCK: u8 = 1;
const DIRT: u8 = 2;
const GRASS: u8 = 3;
const BLAST_RADIUS: f32 = 1.2;
const HEAP_RADIUS: f32 = 0.8;
/// Undo steps a terrain keeps: more than the predictions a client has
/// pending at once, with room for the players' undos (Z).
const PREDICTION_UNDO: usize = 16;
/// Craters each scripted player blasts in the headless run.
const SCRIPTED: usize = 6;
/// Craters the host blasts in the headless run.
const HOST_CRATERS: usize = 1;

fn main() -> AppExit {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("--server") => match listen_addr(args.get(1)) {
            Ok(addr) => run_server(addr),
            Err(e) => fail(&format!("bad server address: {e}")),
        },
        Some("--host") => match listen_addr(args.get(1)) {
            Ok(addr) => run_host(addr, Presentation::detect("multiplayer")),
            Err(e) => fail(&format!("bad host address: {e}")),
        },
        Some("--client") => match args.get(1).map(|a| a.parse::<SocketAddr>()) {
            Some(Ok(addr)) => run_player(addr, Presentation::detect("multiplayer"), None),
            _ => fail("--client needs the server's address, e.g. --client 127.0.0.1:5000"),
        },
        Some(other) => fail(&format!(
            "unknown argument {other}; use --host, --server or --client ADDR"
        )),
        None => match Presentation::detect("multiplayer") {
            Presentation::Window => fail(
                "host a game with --host (or start a server with --server) and join with \
                 --client ADDR (or set CHISEL_HEADLESS=1 for the one-process demo)",
            ),
            Presentation::Headless(config) => run_headless(config),
        },
    }
}

/// The address to listen on: the argument, or `0.0.0.0:5000`.
fn listen_addr(arg: Option<&String>) -> Result<SocketAddr, std::net::AddrParseError> {
    arg.map_or(Ok(SocketAddr::from((Ipv4Addr::UNSPECIFIED, 5000))), |a| {
        a.parse()
    })
}

fn fail(message: &str) -> AppExit {
    eprintln!("multiplayer: {message}");
    AppExit::from_code(2)
}

/// The shared world: a 24 m × 4 m × 24 m slab of rock on a 1 cm grid,
/// under 80 cm of dirt and 15 cm of grass.
fn slab() -> Result<Terrain, BevyError> {
    let grid = Quantization::new(0.01, [-12.0, -4.0, -12.0])?;
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 12,
        solid: CellBox {
            min: [0; 3],
            max: [2400, 400, 2400],
        },
        label: ROCK,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 40,
        max_depth: 10,
    };
    let mut terrain = Terrain::from_base(grid, base, config)?
        .with_labels([DIRT, GRASS])
        .with_max_undo(0);
    for (depth, label) in [(0.95, DIRT), (0.15, GRASS)] {
        let layer = CarveTool::new(
            CarveShape::Cuboid {
                half_size: Vec3::new(12.0, depth / 2.0, 12.0),
            },
            Transform::from_xyz(0.0, -depth / 2.0, 0.0),
        );
        terrain.apply_now(&layer.to_grid(terrain.quantization())?, Edit::Paint(label))?;
    }
    // The layers are no undo steps; carves keep a few, which the snapshot
    // hands to the clients: a client takes back the predictions another
    // player's carve overtook by undo (with too few steps it would ask for
    // a snapshot instead), and follows the undos of carves made since it
    // joined.
    Ok(terrain.with_max_undo(PREDICTION_UNDO))
}

/// A server app (no window, no renderer): the terrain and the plugins.
/// One that `plays` also has the client plugin, and blasts one crater of
/// its own through the same request as every player (the headless run's
/// host).
fn server_app(plays: bool) -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(
            1.0 / 120.0,
        ))),
        AssetPlugin::default(),
        TerrainPlugin,
        NetServerPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    // Nothing is drawn here: the server keeps the octree and its hash, and
    // builds no cell meshes.
    .insert_resource(TerrainSettings {
        output: CellOutput::Nothing,
        ..TerrainSettings::default()
    })
    .add_systems(Startup, |mut commands: Commands| -> Result {
        commands.spawn((slab()?, NetTerrain(1)));
        Ok(())
    });
    if plays {
        app.add_plugins(NetClientPlugin).add_systems(
            Update,
            (host_crater.before(TerrainSystems::Carve), host_results),
        );
    }
    app.finish();
    app.cleanup();
    app
}

/// The headless host blasts [`HOST_CRATERS`] crater once its terrain is
/// idle: a request like a client's, ordered by its own server.
fn host_crater(
    terrains: Query<(Entity, &Terrain), With<NetTerrain>>,
    mut requests: MessageWriter<NetCarveRequest>,
    mut sent: Local<bool>,
) {
    let Ok((entity, terrain)) = terrains.single() else {
        return;
    };
    if *sent || !terrain.is_idle() {
        return;
    }
    requests.write(NetCarveRequest {
        request: 1,
        terrain: entity,
        tool: WireTool::from(&blast(Vec3::new(9.5, 0.0, -9.5), BLAST_RADIUS, 9)),
        edit: Edit::Subtract,
    });
    *sent = true;
}

/// Prints what became of the host's own requests.
fn host_results(mut results: MessageReader<NetCarveResult>) {
    for result in results.read() {
        match &result.outcome {
            Outcome::Applied { seq } => println!("the host's crater is carve {seq}"),
            Outcome::Rejected(why) => eprintln!("the host's crater was refused: {why}"),
        }
    }
}

fn run_server(addr: SocketAddr) -> AppExit {
    let mut app = server_app(false);
    match start_server(app.world_mut(), addr, 32) {
        Ok(bound) => println!("multiplayer server listening on {bound}"),
        Err(e) => return fail(&format!("cannot listen on {addr}: {e}")),
    }
    app.add_systems(Update, log_server);
    app.run()
}

fn log_server(stats: Res<NetServerStats>, mut last: Local<u64>) {
    if stats.accepted != *last {
        *last = stats.accepted;
        println!(
            "{} carves accepted, {} refused, {} snapshots sent",
            stats.accepted, stats.rejected, stats.snapshots
        );
    }
}

/// What a player's HUD shows, and what the headless run waits for.
#[derive(Resource, Clone)]
struct Player {
    /// Scripted players send their craters; `None` for a mouse player.
    script: Option<usize>,
    sent: usize,
    /// The player hosts the game (its app runs the server).
    hosting: bool,
    /// In the headless run: what the server holds when it is idle.
    check: Option<Arc<Mutex<Option<ServerState>>>>,
}

/// The server's terrain as the headless run's checking player sees it.
struct ServerState {
    /// Carves the server has accepted so far.
    accepted: u64,
    /// The terrain's state hash after them.
    hash: u64,
    /// The octree's bytes after them.
    bytes: Vec<u8>,
}

/// A player's app: a window (or offscreen target), the terrain, both
/// networking plugins (the role is picked by what is started: a server or
/// a connection).
fn player_app(presentation: Presentation, player: Player) -> App {
    let headless = matches!(presentation, Presentation::Headless(_));
    let mut app = App::new();
    presentation.add_default_plugins(&mut app, "bevy_chisel — multiplayer");
    app.add_plugins((
        TerrainPlugin,
        TriplanarMaterialPlugin,
        ViewerPlugin,
        NetServerPlugin,
        NetClientPlugin,
    ))
    .insert_resource(ClearColor(Color::srgb(0.53, 0.68, 0.84)))
    // A client shows its own craters at once (a host applies them at once
    // anyway).
    .insert_resource(NetClientSettings {
        predict_own_carves: true,
    })
    .insert_resource(player)
    .add_observer(dress_terrain)
    .add_systems(Startup, spawn_view)
    .add_systems(
        Update,
        (
            (click, undo_keys, scripted).before(TerrainSystems::Carve),
            hud.after(TerrainSystems::Mesh),
        ),
    );
    if headless {
        app.insert_resource(HoldCaptures(true))
            .add_systems(Update, release_captures.after(TerrainSystems::Mesh));
    }
    app
}

/// A player joining the game at `addr`: the terrain arrives from the
/// server.
fn run_player(
    addr: SocketAddr,
    presentation: Presentation,
    check: Option<Arc<Mutex<Option<ServerState>>>>,
) -> AppExit {
    let headless = matches!(presentation, Presentation::Headless(_));
    let player = Player {
        // The offscreen player of the one-process run blasts too.
        script: check.is_some().then_some(2),
        sent: 0,
        hosting: false,
        check,
    };
    let mut app = player_app(presentation, player);
    app.finish();
    app.cleanup();
    let id = std::process::id() as u64 * 1000 + u64::from(headless);
    if let Err(e) = start_client(app.world_mut(), addr, id) {
        return fail(&format!("cannot connect to {addr}: {e}"));
    }
    app.run()
}

/// A player hosting the game: the terrain is its own, and it listens on
/// `addr` for the others. Its clicks are requests like everyone's, ordered
/// by its own server.
fn run_host(addr: SocketAddr, presentation: Presentation) -> AppExit {
    let player = Player {
        script: None,
        sent: 0,
        hosting: true,
        check: None,
    };
    let mut app = player_app(presentation, player);
    app.add_systems(Startup, |mut commands: Commands| -> Result {
        commands.spawn((slab()?, NetTerrain(1)));
        Ok(())
    })
    .add_systems(Update, log_server);
    app.finish();
    app.cleanup();
    match start_server(app.world_mut(), addr, 32) {
        Ok(bound) => println!("hosting on {bound}; others join with --client {bound}"),
        Err(e) => return fail(&format!("cannot listen on {addr}: {e}")),
    }
    app.run()
}

/// Gives a terrain from the server its textures.
fn dress_terrain(
    add: On<Add, NetTerrain>,
    mut commands: Commands,
    mut materials: ResMut<Assets<TriplanarMaterial>>,
) {
    let table = surface_table(
        &mut materials,
        [
            (ROCK, TerrainSurface::Rock),
            (DIRT, TerrainSurface::Dirt),
            (GRASS, TerrainSurface::Grass),
        ],
        TerrainSurface::Rock,
    );
    commands.entity(add.entity).insert(table);
}

fn spawn_view(mut commands: Commands) {
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
        max_distance: 80.0,
        ..OrbitCamera::new(Vec3::new(0.0, 0.0, 0.0), 24.0).with_angles(0.6, 0.75)
    });
    commands.spawn(overlay_text());
}

/// Left click: a crater; right click: a heap of dirt; both as requests to
/// the server, which sends them back to everyone.
fn click(
    buttons: Res<ButtonInput<MouseButton>>,
    pick: CursorPick,
    mut player: ResMut<Player>,
    mut requests: MessageWriter<NetCarveRequest>,
) {
    let left = buttons.just_pressed(MouseButton::Left);
    if !(left || buttons.just_pressed(MouseButton::Right)) {
        return;
    }
    let Some((terrain, hit)) = pick.terrain_hit(200.0) else {
        return;
    };
    let (tool, edit) = if left {
        (blast(hit.point, BLAST_RADIUS, player.sent), Edit::Subtract)
    } else {
        let centre = hit.point + hit.normal * (0.6 * HEAP_RADIUS);
        (
            CarveTool::dodecahedron(HEAP_RADIUS, centre),
            Edit::Add(DIRT),
        )
    };
    player.sent += 1;
    requests.write(NetCarveRequest {
        request: player.sent as u64,
        terrain,
        tool: WireTool::from(&tool),
        edit,
    });
}

/// Z undoes a carve, Y redoes it, for every player: the server orders the
/// undo among the carves and every player applies it. A client may undo
/// only its own latest carve and redo only its own latest undone one (the
/// server's default `UndoPolicy::OwnLatest`); the host may undo any.
fn undo_keys(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    terrains: Query<Entity, With<NetTerrain>>,
    mut undos: MessageWriter<UndoCarve>,
    mut redos: MessageWriter<RedoCarve>,
    mut answers: MessageReader<NetUndoResult>,
) {
    for answer in answers.read() {
        if let Outcome::Rejected(reason) = &answer.outcome {
            let what = if answer.redo { "redo" } else { "undo" };
            info!("{what} refused: {reason}");
        }
    }
    let (Some(keys), Ok(terrain)) = (keys, terrains.single()) else {
        return;
    };
    if keys.just_pressed(KeyCode::KeyZ) {
        undos.write(UndoCarve { terrain });
    }
    if keys.just_pressed(KeyCode::KeyY) {
        redos.write(RedoCarve { terrain });
    }
}

/// A scripted player blasts its craters along a line of its own, all at
/// once, a few frames after its terrain has arrived.
fn scripted(
    mut player: ResMut<Player>,
    terrains: Query<(Entity, &Terrain), With<NetTerrain>>,
    mut requests: MessageWriter<NetCarveRequest>,
    mut frame: Local<u32>,
) {
    let Some(lane) = player.script else {
        return;
    };
    let Ok((entity, terrain)) = terrains.single() else {
        return;
    };
    *frame += 1;
    if player.sent >= SCRIPTED || !terrain.is_idle() || *frame < 3 {
        return;
    }
    for k in 0..SCRIPTED {
        let x = -7.5 + 3.0 * k as f32;
        let z = -6.0 + 6.0 * lane as f32;
        requests.write(NetCarveRequest {
            request: k as u64,
            terrain: entity,
            tool: WireTool::from(&blast(Vec3::new(x, 0.0, z), BLAST_RADIUS, k + 3 * lane)),
            edit: Edit::Subtract,
        });
    }
    player.sent = SCRIPTED;
}

fn hud(
    player: Res<Player>,
    stats: Res<NetClientStats>,
    served: Res<NetServerStats>,
    terrains: Query<&Terrain, With<NetTerrain>>,
    mut text: Query<&mut Text, With<Overlay>>,
) {
    let Ok(mut text) = text.single_mut() else {
        return;
    };
    let state = terrains.single().map_or_else(
        |_| "waiting for the server's terrain".to_owned(),
        |t| {
            format!(
                "{} carves since joining | state hash {:016x} | {} triangles",
                t.journal().len(),
                t.state_hash(),
                t.triangle_count()
            )
        },
    );
    let role = if player.hosting {
        format!(
            "hosting: {} carves ordered, {} refused, {} snapshots sent",
            served.accepted, served.rejected, served.snapshots
        )
    } else {
        format!(
            "{} hash checks passed | {} own carves predicted, {} confirmed, {} roll backs",
            stats.checks_passed, stats.predictions, stats.predictions_confirmed, stats.rollbacks
        )
    };
    text.0 = format!(
        "multiplayer | {state}\n{role}\n\
         LMB blast crater | RMB heap dirt | {ORBIT_HELP}"
    );
}

/// Headless: capture once every player's craters are in and meshed, and
/// the octree is the server's.
fn release_captures(
    player: Res<Player>,
    terrains: Query<&Terrain, With<NetTerrain>>,
    mut hold: ResMut<HoldCaptures>,
) {
    if !hold.0 {
        return;
    }
    let Ok(terrain) = terrains.single() else {
        return;
    };
    let Some(check) = &player.check else {
        // A lone player run offscreen: capture what the server has.
        hold.0 = !terrain.is_idle();
        return;
    };
    // Carves before this player joined came in its snapshot, which has no
    // journal: count them on the server, and compare the terrains.
    let expected = (3 * SCRIPTED + HOST_CRATERS) as u64;
    if !terrain.is_idle() {
        return;
    }
    let Ok(server) = check.lock() else {
        return;
    };
    if let Some(state) = server.as_ref()
        && state.accepted >= expected
        && state.hash == terrain.state_hash()
    {
        let hash = state.hash;
        assert!(
            state.bytes == terrain.octree().to_bytes(),
            "equal hashes but different octrees"
        );
        println!(
            "all {expected} carves applied; octree identical to the host's (hash {hash:016x})"
        );
        hold.0 = false;
    }
}

/// One process: a host (a server that blasts a crater of its own) and two
/// scripted players in threads, and a third scripted player rendering
/// offscreen in the main thread.
fn run_headless(config: HeadlessConfig) -> AppExit {
    let stop = Arc::new(AtomicBool::new(false));
    let server_state: Arc<Mutex<Option<ServerState>>> = Arc::default();
    let (tx, rx) = mpsc::channel();
    let mut threads = Vec::new();
    {
        let (stop, state) = (stop.clone(), server_state.clone());
        threads.push(std::thread::spawn(move || {
            let mut app = server_app(true);
            let bound = start_server(app.world_mut(), (Ipv4Addr::LOCALHOST, 0).into(), 8);
            let _ = tx.send(bound.map_err(|e| e.to_string()));
            while !stop.load(Ordering::Relaxed) {
                app.update();
                let world = app.world_mut();
                let accepted = world.resource::<NetServerStats>().accepted;
                let mut q = world.query_filtered::<&Terrain, With<NetTerrain>>();
                if let Ok(t) = q.single(world)
                    && t.is_idle()
                    && let Ok(mut s) = state.lock()
                    && s.as_ref().is_none_or(|s| s.accepted != accepted)
                {
                    *s = Some(ServerState {
                        accepted,
                        hash: t.state_hash(),
                        bytes: t.octree().to_bytes(),
                    });
                }
                std::thread::sleep(Duration::from_millis(2));
            }
        }));
    }
    let addr = match rx.recv() {
        Ok(Ok(addr)) => addr,
        Ok(Err(e)) => return fail(&format!("server: {e}")),
        Err(e) => return fail(&format!("server thread: {e}")),
    };
    for lane in 0..2 {
        let stop = stop.clone();
        threads.push(std::thread::spawn(move || {
            let mut app = App::new();
            app.add_plugins((
                MinimalPlugins,
                AssetPlugin::default(),
                TerrainPlugin,
                NetClientPlugin,
            ))
            .init_asset::<Mesh>()
            .init_asset::<StandardMaterial>()
            .insert_resource(Player {
                script: Some(lane),
                sent: 0,
                hosting: false,
                check: None,
            })
            .add_systems(Update, scripted.before(TerrainSystems::Carve));
            app.finish();
            app.cleanup();
            if start_client(app.world_mut(), addr, 100 + lane as u64).is_ok() {
                while !stop.load(Ordering::Relaxed) {
                    app.update();
                    std::thread::sleep(Duration::from_millis(2));
                }
            }
        }));
    }
    let exit = run_player(
        addr,
        Presentation::Headless(HeadlessConfig {
            capture_frames: vec![6],
            max_frames: 3000,
            ..config
        }),
        Some(server_state),
    );
    stop.store(true, Ordering::Relaxed);
    for thread in threads {
        let _ = thread.join();
    }
    exit
}
