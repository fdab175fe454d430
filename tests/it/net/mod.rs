//! What the networked tests share: a server and clients as Bevy apps in
//! one process, talking over renet's netcode UDP transport on 127.0.0.1.
//! [`world`] has what a peer holds of a networked world.

pub mod world;

use std::net::{Ipv4Addr, SocketAddr};

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::bsp::octree::{CellBox, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::net::{
    ClientPacket, ClientRequest, NetCarveRequest, NetCarveResult, NetClientPlugin, NetKey,
    NetLimits, NetProtocolPlugin, NetServerPlugin, NetTerrain, NetWorld, NetWorldCarveRequest,
    Outcome, ServerPacket, TerrainSynced, WireTool, WorldDesynced, WorldSynced, start_client,
    start_secure_server, start_server,
};
use bevy_chisel::terrain::{
    CarveTool, CellOutput, Terrain, TerrainBase, TerrainFocus, TerrainPlugin, TerrainSettings,
    TerrainWorld,
};

/// A 10 m × 2 m × 10 m slab of rock on a 1 cm grid, in a cube of 10.24 m.
pub fn slab() -> Terrain {
    let grid = Quantization::new(0.01, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 10,
        solid: CellBox {
            min: [0; 3],
            max: [1000, 200, 1000],
        },
        label: 1,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 40,
        max_depth: 8,
    };
    Terrain::from_base(grid, base, config)
        .expect("valid slab")
        .with_labels([2])
        .with_max_undo(8)
}

/// Messages a client saw.
#[derive(Resource, Default)]
pub struct Seen {
    pub results: Vec<NetCarveResult>,
    pub synced: Vec<TerrainSynced>,
}

fn record(
    mut seen: ResMut<Seen>,
    mut results: MessageReader<NetCarveResult>,
    mut synced: MessageReader<TerrainSynced>,
) {
    seen.results.extend(results.read().cloned());
    seen.synced.extend(synced.read().cloned());
}

fn base_app(threads: usize, output: CellOutput) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>()
        .insert_resource(TerrainSettings {
            worker_threads: threads,
            output,
            ..TerrainSettings::default()
        });
    app
}

/// A server with `terrain` as network terrain 1; returns the app and the
/// address it listens on.
pub fn server(terrain: Terrain, limits: NetLimits) -> (App, SocketAddr) {
    server_building(terrain, limits, CellOutput::Nothing)
}

/// [`server`], building `output` for its terrain's cells (a dedicated
/// server builds nothing).
pub fn server_building(
    terrain: Terrain,
    limits: NetLimits,
    output: CellOutput,
) -> (App, SocketAddr) {
    let mut app = server_app(terrain, limits, output);
    let addr =
        start_server(app.world_mut(), (Ipv4Addr::LOCALHOST, 0).into(), 16).expect("server listens");
    (app, addr)
}

/// A server that admits only clients with a connect token signed by `key`.
pub fn secure_server(terrain: Terrain, key: &NetKey) -> (App, SocketAddr) {
    let mut app = server_app(terrain, NetLimits::default(), CellOutput::Nothing);
    let addr = start_secure_server(
        app.world_mut(),
        (Ipv4Addr::LOCALHOST, 0).into(),
        Vec::new(),
        16,
        key,
    )
    .expect("secure server listens");
    (app, addr)
}

fn server_app(terrain: Terrain, limits: NetLimits, output: CellOutput) -> App {
    let mut app = base_app(1, output);
    app.add_plugins(NetServerPlugin).insert_resource(limits);
    app.world_mut().spawn((terrain, NetTerrain(1)));
    app.finish();
    app.cleanup();
    app
}

/// A client app with `threads` worker threads, not connected yet.
pub fn client_app(threads: usize) -> App {
    let mut app = base_app(threads, CellOutput::Meshes);
    app.add_plugins(NetClientPlugin)
        .init_resource::<Seen>()
        .add_systems(Last, record);
    app.finish();
    app.cleanup();
    app
}

/// A client connecting to `addr` with `threads` worker threads.
pub fn client(addr: SocketAddr, id: u64, threads: usize) -> App {
    let mut app = client_app(threads);
    start_client(app.world_mut(), addr, id).expect("client starts");
    app
}

/// Requests a light client answered: all of them, and those applied.
#[derive(Resource, Default)]
pub struct Answers(pub usize, pub usize);

/// A light client connecting to `addr`: the protocol only, no terrain or
/// world; it counts the answers to its requests in [`Answers`].
pub fn light_client(addr: SocketAddr, id: u64) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, NetProtocolPlugin))
        .init_resource::<Answers>()
        .add_systems(
            Update,
            |mut packets: MessageReader<ServerPacket>, mut answers: ResMut<Answers>| {
                for packet in packets.read() {
                    if let ServerPacket::Result { outcome, .. } = packet {
                        answers.0 += 1;
                        if matches!(outcome, Outcome::Applied { .. }) {
                            answers.1 += 1;
                        }
                    }
                }
            },
        );
    app.finish();
    app.cleanup();
    start_client(app.world_mut(), addr, id).expect("client starts");
    app
}

/// Light clients ([`light_client`]) each send `per_client` requests
/// (`request(client, i)`) in the same frame; runs the server and them
/// until every request is answered. Returns the requests applied per
/// second and how many were applied.
#[allow(dead_code, reason = "a figure of the net benches")]
pub fn burst_rate(
    server: &mut App,
    clients: &mut [App],
    per_client: usize,
    mut request: impl FnMut(usize, usize) -> ClientRequest,
) -> (f64, usize) {
    let start = std::time::Instant::now();
    for (n, app) in clients.iter_mut().enumerate() {
        for i in 0..per_client {
            let packet = ClientPacket::Request(request(n, i));
            app.world_mut().write_message(packet);
        }
    }
    let asked = clients.len() * per_client;
    loop {
        server.update();
        clients.iter_mut().for_each(App::update);
        let answered: usize = (clients.iter())
            .map(|app| app.world().resource::<Answers>().0)
            .sum();
        if answered >= asked {
            break;
        }
    }
    let applied: usize = (clients.iter())
        .map(|app| app.world().resource::<Answers>().1)
        .sum();
    (applied as f64 / start.elapsed().as_secs_f64(), applied)
}

/// Updates every app once.
pub fn update_all(apps: &mut [&mut App]) {
    for app in apps.iter_mut() {
        app.update();
    }
}

/// The app's network terrain: entity and component.
pub fn terrain_of(app: &mut App) -> Option<(Entity, &Terrain)> {
    let world = app.world_mut();
    let mut query = world.query_filtered::<(Entity, &Terrain), With<NetTerrain>>();
    let world = app.world();
    query.iter(world).next()
}

/// A random small blast or heap near the slab's top, as a float tool.
pub fn random_carve(rng: &mut Rng) -> (CarveTool, Edit) {
    let centre = Vec3::new(
        rng.range(0.5, 9.5),
        rng.range(1.7, 2.1),
        rng.range(0.5, 9.5),
    );
    let tool = CarveTool::dodecahedron(rng.range(0.15, 0.45), centre);
    let edit = if rng.next().is_multiple_of(5) {
        Edit::Add(2)
    } else {
        Edit::Subtract
    };
    (tool, edit)
}

/// Sends one carve request from a client app.
pub fn request(app: &mut App, request: u64, tool: &CarveTool, edit: Edit) {
    let (entity, _) = terrain_of(app).expect("the client has the terrain");
    app.world_mut().write_message(NetCarveRequest {
        request,
        terrain: entity,
        tool: WireTool::from(tool),
        edit,
    });
}

/// Updates the apps until `done` holds for all clients, at most `frames`
/// frames; returns the frames used.
pub fn run_until(
    apps: &mut [&mut App],
    frames: usize,
    mut done: impl FnMut(&mut [&mut App]) -> bool,
) -> usize {
    for frame in 0..frames {
        update_all(apps);
        if done(apps) {
            return frame;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    panic!("not done after {frames} frames");
}

/// The server's limits with no rate limit: the tests send carves as fast
/// as their frames run.
pub fn unlimited() -> NetLimits {
    NetLimits {
        carves_per_second: 1e6,
        burst: 1e6,
        ..NetLimits::default()
    }
}

/// A server with `world` as network world 1 (no focus: it holds only the
/// chunks carves reach, and stores the edited ones once idle).
pub fn world_server(world: TerrainWorld, limits: NetLimits) -> (App, SocketAddr) {
    let mut app = base_app(1, CellOutput::Nothing);
    app.add_plugins((TransformPlugin, NetServerPlugin))
        .insert_resource(limits);
    app.world_mut().spawn((world, NetWorld(1)));
    app.finish();
    app.cleanup();
    let addr =
        start_server(app.world_mut(), (Ipv4Addr::LOCALHOST, 0).into(), 16).expect("server listens");
    (app, addr)
}

/// A client with `world` as network world 1 and a focus at `focus`,
/// connecting to `addr`.
pub fn world_client(addr: SocketAddr, id: u64, world: TerrainWorld, focus: Vec3) -> App {
    let mut app = base_app(1, CellOutput::Meshes);
    app.add_plugins((TransformPlugin, NetClientPlugin))
        .init_resource::<Seen>()
        .init_resource::<WorldsSeen>()
        .add_systems(Last, (record, record_worlds));
    app.world_mut().spawn((world, NetWorld(1)));
    app.world_mut()
        .spawn((TerrainFocus, Transform::from_translation(focus)));
    app.finish();
    app.cleanup();
    start_client(app.world_mut(), addr, id).expect("client starts");
    app
}

/// World messages a client saw.
#[derive(Resource, Default)]
pub struct WorldsSeen {
    pub synced: Vec<WorldSynced>,
    pub desynced: Vec<WorldDesynced>,
}

fn record_worlds(
    mut seen: ResMut<WorldsSeen>,
    mut synced: MessageReader<WorldSynced>,
    mut desynced: MessageReader<WorldDesynced>,
) {
    seen.synced.extend(synced.read().cloned());
    seen.desynced.extend(desynced.read().cloned());
}

/// The app's network world: entity and component.
pub fn world_of(app: &mut App) -> (Entity, &TerrainWorld) {
    let world = app.world_mut();
    let mut query = world.query_filtered::<(Entity, &TerrainWorld), With<NetWorld>>();
    query
        .iter(app.world())
        .next()
        .expect("the app has its world")
}

/// Sends one world carve request from a client app.
pub fn request_world(app: &mut App, request: u64, tool: &CarveTool, edit: Edit) {
    let (world, _) = world_of(app);
    app.world_mut().write_message(NetWorldCarveRequest {
        request,
        world,
        tool: WireTool::from(tool),
        edit,
    });
}

/// A small seeded generator (SplitMix64), so that runs repeat exactly.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
}
