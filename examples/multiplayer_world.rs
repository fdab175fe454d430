//! Multiplayer in a streamed world: one authoritative server orders every
//! player's carves, each peer streams the chunks around its own camera,
//! and every chunk any peer holds is bit-identical to the server's. A
//! bridge knocked down over a chunk border falls as one piece on every
//! peer.
//!
//! ```text
//! cargo run --release --all-features --example multiplayer_world -- --host        # plays and serves
//! cargo run --release --all-features --example multiplayer_world -- --client 127.0.0.1:5000
//! cargo run --release --all-features --example multiplayer_world -- --server      # dedicated server
//! cargo run --release --all-features --example multiplayer_world -- --server 0.0.0.0:5000 --save saves/world
//! ```
//!
//! `--host [ADDR]` opens a window and listens (default `0.0.0.0:5000`),
//! `--server [ADDR]` listens without a window, `--client ADDR` joins. With
//! `--save DIR` a dedicated server starts from the world saved in `DIR`
//! (when there is one) and saves it there in the background every 10 s
//! after carves (`SaveWorld`: only the chunks changed since the last save
//! are written), so it can be stopped and started again without losing
//! what the players dug; players joining get the saved chunks in the
//! world's snapshot. Every
//! peer spawns the same world (the landscape is code, not data) with the
//! same [`NetWorld`] id; only the carves travel. In a window, left click
//! blasts a crater, right click heaps up dirt, and `B` builds a stone
//! bridge where the cursor points and cuts its pillar: the deck falls
//! (avian3d), on every peer's screen. The HUD shows the edited chunks,
//! live and stored, and the world hash checks passed.
//!
//! With no display (or `CHISEL_HEADLESS=1`) one process runs a dedicated
//! server (no camera: it builds only the chunks carves reach), two
//! scripted players in threads and a third rendering offscreen. One
//! player blasts craters across the border between chunks `(0, 0)` and
//! `(1, 0)`; the other, whose camera is 80 m away and holds none of those
//! chunks, builds the bridge over that border and cuts its pillar. When
//! the server is settled, the offscreen player checks that it holds every
//! edited chunk bit for bit as the server does and that the deck fell,
//! then writes `screenshots/multiplayer_world-*.png`.

use std::collections::BTreeMap;
use std::net::{Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::net::{NetServerPlugin, NetServerStats, NetWorld, start_client, start_server};
use bevy_chisel::presentation::Presentation;
use bevy_chisel::terrain::{
    CarveShape, CarveTool, CellOutput, ChunkCoord, NoiseOctave, SaveWorld, StreamSettings, Terrain,
    TerrainPlugin, TerrainSettings, TerrainWorld, ValueNoise, WorldLayout, WorldSaveFailed,
    WorldSaved, WorldSource,
};

#[path = "multiplayer_world/headless.rs"]
mod headless;
#[path = "multiplayer_world/player.rs"]
mod player;

use player::{Player, player_app};

const ROCK: u8 = 1;
const DIRT: u8 = 2;
const GRASS: u8 = 3;
/// Grid unit (m); chunks 2^11 units = 20.48 m, height samples 1.28 m apart.
const UNIT: f64 = 0.01;
const CHUNK_LOG2: u8 = 11;
const SPACING_LOG2: u8 = 7;
const BLAST_RADIUS: f32 = 1.6;
const HEAP_RADIUS: f32 = 0.9;
/// The headless site: the bridge's pillar, west of the border between
/// chunks (0, 0) and (1, 0) at x = 20.48 m; its deck reaches over it.
const SITE: Vec2 = Vec2::new(17.5, 10.0);
/// Craters the headless blasting player sends, along z = 4 m across the
/// border; with the bridge's three carves, what the server accepts.
const CRATERS: usize = 6;
const CARVES: u64 = CRATERS as u64 + 3;
/// The camera: this far from the point it looks at, this high above the
/// horizon (rad). (Lower views of the world render far more slowly on a
/// software renderer.)
const CAMERA_DISTANCE: f32 = 20.0;
const CAMERA_PITCH: f32 = 0.9;
/// Frames the headless run waits for the deck to fall once every chunk
/// matches the server's.
const FALL_FRAMES: u32 = 1500;
/// Where the headless players' cameras are: at the site, and 80 m away.
const FAR: Vec2 = Vec2::new(90.0, 50.0);
/// A dedicated server with `--save` saves this long after the first carve
/// since its last save.
const SAVE_EVERY: Duration = Duration::from_secs(10);

fn main() -> AppExit {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let save = match args.iter().position(|a| a == "--save") {
        Some(at) if at + 1 < args.len() => {
            let dir = PathBuf::from(args.remove(at + 1));
            args.remove(at);
            Some(dir)
        }
        Some(_) => return fail("--save needs a folder, e.g. --save saves/world"),
        None => None,
    };
    if save.is_some() && args.first().map(String::as_str) != Some("--server") {
        return fail("--save is for a dedicated server (--server)");
    }
    match args.first().map(String::as_str) {
        Some("--server") => match listen_addr(args.get(1)) {
            Ok(addr) => run_server(addr, save),
            Err(e) => fail(&format!("bad server address: {e}")),
        },
        Some("--host") => match listen_addr(args.get(1)) {
            Ok(addr) => run_window(Some(addr), None),
            Err(e) => fail(&format!("bad host address: {e}")),
        },
        Some("--client") => match args.get(1).map(|a| a.parse::<SocketAddr>()) {
            Some(Ok(addr)) => run_window(None, Some(addr)),
            _ => fail("--client needs the server's address, e.g. --client 127.0.0.1:5000"),
        },
        Some(other) => fail(&format!(
            "unknown argument {other}; use --host, --server or --client ADDR"
        )),
        None => match Presentation::detect("multiplayer_world") {
            Presentation::Window => fail(
                "host a game with --host (or start a server with --server) and join with \
                 --client ADDR (or set CHISEL_HEADLESS=1 for the one-process demo)",
            ),
            Presentation::Headless(config) => headless::run_headless(config),
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
    eprintln!("multiplayer_world: {message}");
    AppExit::from_code(2)
}

// ---------------------------------------------------------------------------
// The world every peer spawns

/// Rolling hills of integer value noise, 1 m to about 9 m high.
fn landscape() -> ValueNoise {
    ValueNoise {
        base: 100,
        octaves: vec![
            NoiseOctave {
                cell: 24,
                amplitude: 650,
                seed: 1,
            },
            NoiseOctave {
                cell: 6,
                amplitude: 180,
                seed: 2,
            },
        ],
    }
}

/// The world, streamed within `load_radius` of each peer's camera.
fn new_world(load_radius: f32) -> Result<TerrainWorld, BevyError> {
    let layout = WorldLayout {
        quantization: Quantization::new(UNIT, [0.0; 3])?,
        chunk_log2: CHUNK_LOG2,
        spacing_log2: SPACING_LOG2,
        floor: 0,
        label: ROCK,
        // Grass 25 cm deep over 1.2 m of dirt, in grid units.
        layers: vec![(120, DIRT), (25, GRASS)],
    };
    Ok(TerrainWorld::new(layout, landscape())?
        .with_streaming(StreamSettings {
            load_radius,
            unload_radius: load_radius * 1.5,
            max_building: 4,
        })?
        .with_labels([DIRT]))
}

/// The height (m) of the highest sample within `reach` metres of `(x, z)`.
fn highest_ground(x: f32, z: f32, reach: f32) -> f32 {
    let spacing = (1i64 << SPACING_LOG2) as f32 * UNIT as f32;
    let index = |v: f32| (v / spacing).floor() as i64;
    let noise = landscape();
    let mut top = i64::MIN;
    for i in index(x - reach)..=index(x + reach) + 1 {
        for j in index(z - reach)..=index(z + reach) + 1 {
            top = top.max(noise.height(i, j));
        }
    }
    top as f32 * UNIT as f32
}

fn cuboid(min: Vec3, max: Vec3) -> CarveTool {
    CarveTool::new(
        CarveShape::Cuboid {
            half_size: (max - min) / 2.0,
        },
        Transform::from_translation((min + max) / 2.0),
    )
}

/// A bridge with its pillar at `(x, z)`: the pillar of rock, a deck 8 m
/// long towards +x resting on it, 2.5 m above the highest ground under
/// it, then the cut through the pillar that leaves the deck hanging. In
/// the world's order the three carves follow each other, so the deck is
/// held until the cut.
fn bridge(x: f32, z: f32) -> [(CarveTool, Edit); 3] {
    let pillar_ground = highest_ground(x, z, 0.6);
    let deck_bottom = highest_ground(x + 3.0, z, 4.5) + 2.5;
    let pillar = cuboid(
        Vec3::new(x - 0.6, pillar_ground - 1.5, z - 0.6),
        Vec3::new(x + 0.6, deck_bottom + 0.1, z + 0.6),
    );
    let deck = cuboid(
        Vec3::new(x - 1.0, deck_bottom, z - 1.5),
        Vec3::new(x + 7.0, deck_bottom + 0.6, z + 1.5),
    );
    let cut = cuboid(
        Vec3::new(x - 1.0, pillar_ground + 0.5, z - 1.0),
        Vec3::new(x + 1.0, pillar_ground + 1.5, z + 1.0),
    );
    [
        (pillar, Edit::Add(ROCK)),
        (deck, Edit::Add(ROCK)),
        (cut, Edit::Subtract),
    ]
}

/// A point `(x, z)` on the ground, `above` metres up.
fn on_ground(at: Vec2, above: f32) -> Vec3 {
    Vec3::new(at.x, highest_ground(at.x, at.y, 0.0) + above, at.y)
}

/// Every edited chunk a peer holds, live (`terrain` gives a chunk
/// entity's terrain) or stored: its octree's bytes and state hash.
fn edited_chunks<'a>(
    world: &TerrainWorld,
    terrain: impl Fn(Entity) -> Option<&'a Terrain>,
) -> BTreeMap<ChunkCoord, (Vec<u8>, u64)> {
    let record = |t: &Terrain| (t.octree().to_bytes(), t.state_hash());
    let mut out = BTreeMap::new();
    for (coord, entity) in world.live_chunks() {
        if let Some(t) = terrain(entity)
            && world.chunk_edited(coord, t)
        {
            out.insert(coord, record(t));
        }
    }
    for coord in world.stored_chunks() {
        if let Some(t) = (world.stored_chunk(coord)).and_then(|b| Terrain::from_bytes(b).ok()) {
            out.insert(coord, record(&t));
        }
    }
    out
}

/// Whether the world builds nothing, searches no debris and every live
/// chunk is idle.
fn settled(world: &TerrainWorld, idle: impl Fn(Entity) -> bool) -> bool {
    world.is_settled()
        && !world.debris_searching()
        && world.live_chunks().all(|(_, entity)| idle(entity))
}

// ---------------------------------------------------------------------------
// The dedicated server

/// A server app (no window, no renderer, no camera): it holds the chunks
/// carves reach while they work and stores the edited ones; its world
/// starts from the chunks saved in `save` when that folder exists.
fn server_app(save: Option<&PathBuf>) -> Result<App, BevyError> {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(ScheduleRunnerPlugin::run_loop(Duration::from_secs_f64(
            1.0 / 120.0,
        ))),
        AssetPlugin::default(),
        TransformPlugin,
        TerrainPlugin,
        NetServerPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .insert_resource(TerrainSettings {
        output: CellOutput::Nothing,
        ..TerrainSettings::default()
    });
    let mut world = new_world(0.0)?;
    if let Some(dir) = save.filter(|dir| dir.exists()) {
        world = world.load_edits(dir)?;
        println!(
            "loaded {} edited chunks from {}",
            world.stored_chunks().count(),
            dir.display()
        );
    }
    app.world_mut().spawn((world, NetWorld(1)));
    app.finish();
    app.cleanup();
    Ok(app)
}

fn run_server(addr: SocketAddr, save: Option<PathBuf>) -> AppExit {
    let mut app = match server_app(save.as_ref()) {
        Ok(app) => app,
        Err(e) => return fail(&format!("world: {e}")),
    };
    match start_server(app.world_mut(), addr, 32) {
        Ok(bound) => println!("multiplayer_world server listening on {bound}"),
        Err(e) => return fail(&format!("cannot listen on {addr}: {e}")),
    }
    app.add_systems(Update, log_server);
    if let Some(folder) = save {
        app.insert_resource(Autosave {
            folder,
            saved_at: 0,
            since: None,
            pending: false,
        })
        .add_systems(Update, autosave);
    }
    app.run()
}

/// A dedicated server's saves (`--save`).
#[derive(Resource)]
struct Autosave {
    folder: PathBuf,
    /// Carves accepted when the last save was asked for.
    saved_at: u64,
    /// When the first carve since then was seen.
    since: Option<Duration>,
    /// A save was asked for and is not answered yet.
    pending: bool,
}

/// Saves the world [`SAVE_EVERY`] after the first carve since the last
/// save, in the background (the save itself waits for a frame between
/// carves); a failed save is tried again [`SAVE_EVERY`] later.
fn autosave(
    time: Res<Time>,
    stats: Res<NetServerStats>,
    worlds: Query<Entity, With<TerrainWorld>>,
    mut save: ResMut<Autosave>,
    mut requests: MessageWriter<SaveWorld>,
    mut saved: MessageReader<WorldSaved>,
    mut failed: MessageReader<WorldSaveFailed>,
) {
    for answer in saved.read() {
        save.pending = false;
        println!(
            "saved {} changed chunks ({} kB; {} unchanged) to {}",
            answer.written.len(),
            answer.bytes / 1024,
            answer.unchanged,
            answer.folder.display()
        );
    }
    for failure in failed.read() {
        save.pending = false;
        // Tried again after another SAVE_EVERY (a world that held no
        // consistent state for `max_save_wait` frames reports
        // WorldNotIdle).
        eprintln!("save failed: {}", failure.error);
        save.since = Some(time.elapsed());
    }
    if stats.accepted > save.saved_at && save.since.is_none() {
        save.since = Some(time.elapsed());
    }
    let due = save.since.is_some_and(|t| time.elapsed() >= t + SAVE_EVERY);
    if let Ok(world) = worlds.single()
        && due
        && !save.pending
    {
        requests.write(SaveWorld {
            world,
            folder: save.folder.clone(),
        });
        save.pending = true;
        save.saved_at = stats.accepted;
        save.since = None;
    }
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

/// A window: hosting (`listen`) or joining (`join`).
fn run_window(listen: Option<SocketAddr>, join: Option<SocketAddr>) -> AppExit {
    let look_at = on_ground(SITE, 0.0);
    let mut app = match player_app(Presentation::Window, Player::new(None, None), look_at) {
        Ok(app) => app,
        Err(e) => return fail(&format!("world: {e}")),
    };
    app.finish();
    app.cleanup();
    if let Some(addr) = listen {
        match start_server(app.world_mut(), addr, 32) {
            Ok(bound) => println!("hosting on {bound}; others join with --client {bound}"),
            Err(e) => return fail(&format!("cannot listen on {addr}: {e}")),
        }
        app.add_systems(Update, log_server);
    }
    if let Some(addr) = join
        && let Err(e) = start_client(app.world_mut(), addr, u64::from(std::process::id()))
    {
        return fail(&format!("cannot connect to {addr}: {e}"));
    }
    app.run()
}
