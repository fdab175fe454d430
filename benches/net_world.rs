//! Figures of networked streamed worlds (`net::world`), printed as one
//! JSON line:
//!
//! `cargo bench -p bevy_chisel --all-features --bench net_world`
//!
//! `cargo test` runs this binary without `--bench`: it then measures
//! nothing (see `support`). The server and clients are those of the
//! networked tests (`tests/it/net`, included by path): one process,
//! Bevy apps on 127.0.0.1 over renet's netcode UDP transport, a server
//! without a focus (it holds only the chunks carves reach) and clients
//! that stream the world around their own focus. The world has chunks of
//! 32 m on a 1 m grid, as in the networked world tests.
//!
//! - bytes on the wire of one world carve (the encoded
//!   [`ServerPacket::WorldCarve`]) and of one detach across chunk borders
//!   ([`ServerPacket::WorldDetach`]), against the mesh bytes of the chunk
//!   cells each changed on a client (what replicating meshes would send);
//! - what one remote carve costs a client (wall and process CPU time, the
//!   only app running being that client) when it lands in chunks the
//!   client holds, against far from its focus (beyond its unload radius),
//!   where the client defers it: the carve waits, unbuilt, until the chunk
//!   streams in or too many carves wait for it
//!   ([`TerrainWorld::with_max_deferred_carves`]); at the end the client
//!   builds every deferred chunk and holds the server's chunks;
//! - a client joining a world after 1,000 carves over 16 chunks: the
//!   snapshot's bytes and the time until it holds every edited chunk as
//!   the server does (world hash equal) and has meshed the live ones;
//! - world carves per second one server sustains with 8 clients sending
//!   at once (light clients that only send and read the answers).

#[path = "../tests/it/net/mod.rs"]
#[allow(dead_code, reason = "the tests' helpers, not all used here")]
mod net;
mod support;

use std::time::{Duration, Instant};

use bevy::mesh::{Indices, Mesh3d};
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::net::{
    ClientPacket, ClientRequest, NetClientStats, NetLimits, NetServerStats, Outcome, ServerPacket,
    WireTool,
};
use bevy_chisel::terrain::{
    CarveApplied, CarveShape, CarveTool, ChunkCoord, DebrisDetached, StreamSettings,
    TerrainCellChanged, TerrainWorld, WorldLayout,
};
use net::world::{world_hash, world_settled};
use net::{
    Answers, Rng, Seen, WorldsSeen, burst_rate, light_client, request_world, run_until,
    world_client, world_of, world_server,
};

/// Chunks of 32 grid units of 1 m, samples 4 apart, heights 8..=20.
fn layout() -> WorldLayout {
    WorldLayout {
        quantization: Quantization::new(1.0, [0.0; 3]).expect("valid unit"),
        chunk_log2: 5,
        spacing_log2: 2,
        floor: 0,
        label: 1,
        layers: Vec::new(),
    }
}

fn height(i: i64, j: i64) -> i64 {
    8 + (i * 7 + j * 13).rem_euclid(9) + (i * j).rem_euclid(5)
}

/// The world every peer spawns: streamed 24 m around each focus, with
/// material 2 to add.
fn world() -> TerrainWorld {
    TerrainWorld::new(layout(), height)
        .expect("valid layout")
        .with_streaming(StreamSettings {
            load_radius: 24.0,
            unload_radius: 40.0,
            max_building: 4,
        })
        .expect("valid settings")
        .with_labels([2])
}

/// Where the measuring client's focus is: it holds the 3×3 chunks
/// around chunk (0, 0), from -32 m to 64 m along x and z.
const FOCUS: Vec3 = Vec3::new(16.0, 30.0, 16.0);

/// Whether a client around [`FOCUS`] is synced, settled and holds its
/// 3×3 chunks.
fn ready(app: &mut App) -> bool {
    synced(app) && world_settled(app) && world_of(app).1.live_chunks().count() == 9
}

fn unlimited() -> NetLimits {
    NetLimits {
        carves_per_second: 1e9,
        burst: 1e9,
        ..NetLimits::default()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// What a measuring client saw, frame by frame: mesh bytes of the cells
/// changed (running total), the world ops it applied, their wire sizes.
#[derive(Resource, Default)]
struct Watch {
    /// Mesh bytes of every cell changed so far.
    mesh_bytes: u64,
    /// Per frame: the running mesh total after it and the requests (world
    /// ops) some chunk reported applied in it.
    frames: Vec<(u64, Vec<u64>)>,
    /// Encoded bytes of each world carve and detach received.
    carve_wire: Vec<usize>,
    detach_wire: Vec<usize>,
    /// Pieces that fell.
    fallen: usize,
}

#[allow(clippy::too_many_arguments)]
fn watch(
    mut changed: MessageReader<TerrainCellChanged>,
    mut applied: MessageReader<CarveApplied>,
    mut packets: MessageReader<ServerPacket>,
    mut fallen: MessageReader<DebrisDetached>,
    cells: Query<&Mesh3d>,
    meshes: Res<Assets<Mesh>>,
    mut watch: ResMut<Watch>,
) {
    for change in changed.read() {
        for entity in &change.entities {
            let Some(mesh) = cells.get(*entity).ok().and_then(|m| meshes.get(&m.0)) else {
                continue;
            };
            let attributes: usize = mesh.attributes().map(|(_, v)| v.get_bytes().len()).sum();
            let indices = match mesh.indices() {
                Some(Indices::U32(i)) => i.len() * 4,
                Some(Indices::U16(i)) => i.len() * 2,
                None => 0,
            };
            watch.mesh_bytes += (attributes + indices) as u64;
        }
    }
    let requests = applied.read().filter_map(|a| a.request).collect();
    let total = watch.mesh_bytes;
    watch.frames.push((total, requests));
    for packet in packets.read() {
        let size = || postcard::to_allocvec(packet).map_or(0, |b| b.len());
        match packet {
            ServerPacket::WorldCarve(_) => watch.carve_wire.push(size()),
            ServerPacket::WorldDetach(_) => watch.detach_wire.push(size()),
            _ => {}
        }
    }
    watch.fallen += fallen.read().count();
}

/// A world client that watches what it applies.
fn watching_client(addr: std::net::SocketAddr, id: u64, focus: Vec3) -> App {
    let mut app = world_client(addr, id, world(), focus);
    app.init_resource::<Watch>().add_systems(Last, watch);
    app
}

fn synced(app: &App) -> bool {
    !app.world().resource::<WorldsSeen>().synced.is_empty()
}

fn answered(app: &App, request: u64) -> Option<Outcome> {
    let results = &app.world().resource::<Seen>().results;
    (results.iter().rev())
        .find(|r| r.request == Some(request))
        .map(|r| r.outcome.clone())
}

/// A random blast or heap near the surface centred in `[lo, hi)` along x
/// and z (m), of radius 1.5–4 m.
fn random_carve(rng: &mut Rng, lo: f32, hi: f32) -> (CarveTool, Edit) {
    random_carve_in(rng, lo, hi, ChunkCoord { x: 0, z: 0 })
}

/// [`random_carve`] moved by a whole number of chunks, to chunk `chunk`.
fn random_carve_in(rng: &mut Rng, lo: f32, hi: f32, chunk: ChunkCoord) -> (CarveTool, Edit) {
    let shift = Vec3::new(32.0 * chunk.x as f32, 0.0, 32.0 * chunk.z as f32);
    let centre = shift + Vec3::new(rng.range(lo, hi), rng.range(10.0, 18.0), rng.range(lo, hi));
    let tool = CarveTool::dodecahedron(rng.range(1.5, 4.0), centre);
    let edit = if rng.next().is_multiple_of(5) {
        Edit::Add(2)
    } else {
        Edit::Subtract
    };
    (tool, edit)
}

/// A box tool with grid corners `min` and `max` (grid unit 1 m).
fn cuboid(min: [i64; 3], max: [i64; 3]) -> CarveTool {
    let lo = Vec3::new(min[0] as f32, min[1] as f32, min[2] as f32);
    let hi = Vec3::new(max[0] as f32, max[1] as f32, max[2] as f32);
    CarveTool::new(
        CarveShape::Cuboid {
            half_size: (hi - lo) / 2.0,
        },
        Transform::from_translation((lo + hi) / 2.0),
    )
}

/// Sends one world carve from `apps[1]` and runs every app until it is
/// answered and every world peer is settled; returns the carve's `seq`.
fn carve_settled(apps: &mut [&mut App], request: u64, tool: &CarveTool, edit: Edit) -> u64 {
    request_world(apps[1], request, tool, edit);
    run_until(apps, 200_000, |apps| {
        answered(apps[1], request).is_some() && apps.iter_mut().all(|app| world_settled(app))
    });
    match answered(apps[1], request) {
        Some(Outcome::Applied { seq }) => seq,
        other => panic!("carve {request} was not applied: {other:?}"),
    }
}

/// Wire bytes against mesh bytes, for world carves in chunks the client
/// holds and for detaches across a chunk border.
struct WireFigures {
    carves: usize,
    carve_wire: f64,
    carve_mesh: f64,
    detaches: usize,
    detach_wire: f64,
    detach_mesh: f64,
    cut_mesh: f64,
}

fn wire_against_meshes() -> WireFigures {
    let (mut server, addr) = world_server(world(), unlimited());
    let mut a = watching_client(addr, 1, FOCUS);
    run_until(&mut [&mut server, &mut a], 20_000, |apps| ready(apps[1]));
    let mut rng = Rng(31);
    const CARVES: usize = 60;
    let mut carve_mesh = Vec::new();
    for n in 0..CARVES {
        let before = a.world().resource::<Watch>().mesh_bytes;
        let (tool, edit) = random_carve(&mut rng, -20.0, 52.0);
        carve_settled(&mut [&mut server, &mut a], n as u64, &tool, edit);
        carve_mesh.push((a.world().resource::<Watch>().mesh_bytes - before) as f64);
    }
    // Slabs over the border x = 32 on a pillar in chunk (0, 0), each cut
    // loose by a cut through its pillar: a detach across the border.
    let (mut detach_mesh, mut detach_wire, mut cut_mesh) = (vec![], vec![], vec![]);
    let mut request = CARVES as u64;
    for z in [-24i64, -14, 40, 50] {
        let x = 26;
        let pillar = cuboid([x, 4, z], [x + 3, 25, z + 3]);
        let slab = cuboid([x, 24, z], [x + 12, 28, z + 4]);
        let cut = cuboid([x - 1, 21, z - 1], [x + 4, 23, z + 4]);
        for tool in [pillar, slab] {
            carve_settled(&mut [&mut server, &mut a], request, &tool, Edit::Add(1));
            request += 1;
        }
        let watched = a.world().resource::<Watch>();
        let (fallen, first_frame) = (watched.fallen, watched.frames.len());
        let (before, detaches) = (watched.mesh_bytes, watched.detach_wire.len());
        let seq = carve_settled(&mut [&mut server, &mut a], request, &cut, Edit::Subtract);
        request += 1;
        let watched = a.world().resource::<Watch>();
        assert!(watched.fallen > fallen, "the slab fell");
        let wire = &watched.detach_wire[detaches..];
        assert_eq!(
            wire.len(),
            1,
            "the slab fell in one detach across the border"
        );
        detach_wire.push(wire[0] as f64);
        // The cut's cells are in place once its last chunk reported it;
        // what changes after that is the detach's.
        let cut_done = (watched.frames[first_frame..].iter())
            .rposition(|(_, requests)| requests.contains(&seq))
            .map(|i| watched.frames[first_frame + i].0)
            .expect("the cut was reported");
        cut_mesh.push((cut_done - before) as f64);
        detach_mesh.push((watched.mesh_bytes - cut_done) as f64);
    }
    let stats = server.world().resource::<NetServerStats>().clone();
    let watched = a.world().resource::<Watch>();
    let wire = |v: &[usize]| mean(&v.iter().map(|&b| b as f64).collect::<Vec<_>>());
    let carve_wire = stats.carve_bytes as f64 / stats.accepted as f64;
    assert!(
        (carve_wire - wire(&watched.carve_wire)).abs() < 1e-9,
        "the client received the carves the server sent"
    );
    WireFigures {
        carves: CARVES,
        carve_wire: wire(&watched.carve_wire[..CARVES]),
        carve_mesh: mean(&carve_mesh),
        detaches: detach_mesh.len(),
        detach_wire: mean(&detach_wire),
        detach_mesh: mean(&detach_mesh),
        cut_mesh: mean(&cut_mesh),
    }
}

/// A client's cost of remote carves: per carve, wall and CPU (ms) and
/// the chunks it built.
struct RemoteCost {
    wall_ms: f64,
    cpu_ms: f64,
    frames: f64,
    builds: f64,
    /// Mesh bytes of the cells the client built for it.
    mesh_bytes: f64,
}

/// Remote carves sent by a light client; after the server answered each
/// one, only the measuring client `o` runs until it applied it, its world
/// is settled and it holds no chunk but those around its focus again.
fn remote_carves(
    server: &mut App,
    sender: &mut App,
    o: &mut App,
    first: u64,
    carves: &[(CarveTool, Edit)],
) -> RemoteCost {
    let (mut walls, mut cpus, mut frames) = (vec![], vec![], vec![]);
    let (mut builds, mut mesh_bytes) = (vec![], vec![]);
    let live = |o: &mut App| world_of(o).1.live_chunks().count();
    let held = live(o);
    for (n, (tool, edit)) in carves.iter().enumerate() {
        let asked = sender.world().resource::<Answers>().0;
        sender
            .world_mut()
            .write_message(ClientPacket::Request(ClientRequest::CarveWorld {
                request: first + n as u64,
                world: 1,
                tool: WireTool::from(tool),
                edit: *edit,
            }));
        run_until(&mut [&mut *server, &mut *sender], 200_000, |apps| {
            apps[1].world().resource::<Answers>().0 > asked && world_settled(apps[0])
        });
        let routed = o.world().resource::<NetClientStats>().carves;
        let built = |o: &mut App| {
            let stats = world_of(o).1.stats();
            stats.generated + stats.restored
        };
        let built_before = built(o);
        let meshed = o.world().resource::<Watch>().mesh_bytes;
        let (start, cpu) = (Instant::now(), support::process_cpu());
        let mut frame = 0;
        loop {
            o.update();
            frame += 1;
            let done = o.world().resource::<NetClientStats>().carves > routed
                && world_settled(o)
                && live(o) == held;
            if done {
                break;
            }
            if frame >= 20_000 {
                let stats = o.world().resource::<NetClientStats>().clone();
                let settled = world_settled(o);
                let (_, world) = world_of(o);
                panic!(
                    "carve {n}: the client did not apply it: {stats:?} (routed before \
                     {routed}), settled {settled}, {:?}, live {} (held {held})",
                    world.stats(),
                    world.live_chunks().count()
                );
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        walls.push(start.elapsed().as_secs_f64() * 1e3);
        cpus.push((support::process_cpu() - cpu).as_secs_f64() * 1e3);
        frames.push(f64::from(frame));
        builds.push((built(o) - built_before) as f64);
        mesh_bytes.push((o.world().resource::<Watch>().mesh_bytes - meshed) as f64);
    }
    RemoteCost {
        wall_ms: median(walls),
        cpu_ms: median(cpus),
        frames: median(frames),
        builds: mean(&builds),
        mesh_bytes: mean(&mesh_bytes),
    }
}

/// Near carves (in chunks the client holds) against far ones (chunks 4
/// to 12 away from its focus, whose carves it defers).
fn near_against_far() -> (RemoteCost, RemoteCost, usize, f64) {
    let (mut server, addr) = world_server(world(), unlimited());
    let mut o = watching_client(addr, 1, FOCUS);
    let mut sender = light_client(addr, 2);
    run_until(&mut [&mut server, &mut o, &mut sender], 20_000, |apps| {
        ready(apps[1])
    });
    const CARVES: usize = 30;
    let mut rng = Rng(47);
    let near: Vec<_> = (0..CARVES)
        .map(|_| random_carve(&mut rng, -20.0, 52.0))
        .collect();
    let far: Vec<_> = (0..CARVES)
        .map(|_| {
            // A chunk 4 to 12 away along x or z, either side.
            let offset = |rng: &mut Rng| {
                let k = 4 + (rng.next() % 9) as i64;
                if rng.next().is_multiple_of(2) { k } else { -k }
            };
            let any = |rng: &mut Rng| (rng.next() % 25) as i64 - 12;
            let (x, z) = match rng.next() % 3 {
                0 => (offset(&mut rng), any(&mut rng)),
                1 => (any(&mut rng), offset(&mut rng)),
                _ => (offset(&mut rng), offset(&mut rng)),
            };
            random_carve_in(&mut rng, 4.0, 28.0, ChunkCoord { x, z })
        })
        .collect();
    // What a frame of the client costs with nothing to do.
    let (cpu, frames) = (support::process_cpu(), 100);
    for _ in 0..frames {
        o.update();
        std::thread::sleep(Duration::from_micros(200));
    }
    let idle_ms = (support::process_cpu() - cpu).as_secs_f64() * 1e3 / f64::from(frames);
    let near_cost = remote_carves(&mut server, &mut sender, &mut o, 0, &near);
    let far_cost = remote_carves(&mut server, &mut sender, &mut o, 1_000, &far);
    // Once it builds its deferred chunks, the client holds every chunk
    // it was sent as the server does.
    run_until(&mut [&mut server, &mut o, &mut sender], 200_000, |apps| {
        net::world::build_deferred(apps[1]);
        world_settled(apps[0]) && world_settled(apps[1])
    });
    assert_eq!(world_hash(&mut o), world_hash(&mut server));
    let stored = world_of(&mut o).1.stored_chunks().count();
    (near_cost, far_cost, stored, idle_ms)
}

/// A server whose world holds `carves` carves over the 4×4 chunks
/// (0..4, 0..4), applied chunk by chunk beforehand (each inside its
/// chunk) and loaded as edited chunks, then clients joining one after
/// another: snapshot bytes, time until synced, time until the client's
/// world hash is the server's and its live chunks are meshed.
fn join_after(carves: usize) -> (usize, f64, f64, usize) {
    let source = world();
    let grid = source.layout().quantization;
    let folder = std::env::temp_dir().join(format!("chisel-net-world-{}", std::process::id()));
    std::fs::create_dir_all(&folder).expect("temporary folder");
    let coords: Vec<ChunkCoord> = (0..16).map(|i| ChunkCoord { x: i % 4, z: i / 4 }).collect();
    let mut rng = Rng(61);
    for (n, &coord) in coords.iter().enumerate() {
        let mut terrain = source.generate_chunk(coord).expect("chunk builds");
        let share = carves / coords.len() + usize::from(n < carves % coords.len());
        let mut done = 0;
        while done < share {
            let (tool, edit) = random_carve_in(&mut rng, 6.0, 26.0, coord);
            if let Ok(tool) = tool.to_grid(&grid)
                && terrain.apply_now(&tool, edit).is_ok()
            {
                done += 1;
            }
        }
        let path = folder.join(TerrainWorld::chunk_file_name(coord));
        std::fs::write(path, terrain.to_bytes()).expect("chunk written");
    }
    let served = world().load_edits(&folder).expect("edits load");
    std::fs::remove_dir_all(&folder).expect("temporary folder removed");
    let (mut server, addr) = world_server(served, unlimited());
    server.update();
    let want = world_hash(&mut server);
    let (mut synced_s, mut held_s, mut bytes) = (vec![], vec![], 0);
    for id in 0..3 {
        let start = Instant::now();
        let mut c = world_client(addr, 50 + id, world(), Vec3::new(64.0, 30.0, 64.0));
        run_until(&mut [&mut server, &mut c], 1_000_000, |apps| {
            synced(apps[1])
        });
        synced_s.push(start.elapsed().as_secs_f64());
        bytes = c.world().resource::<WorldsSeen>().synced[0].bytes;
        // Live: the 4 chunks around (64, 64), restored from the snapshot
        // and meshed; the other 12 stored.
        run_until(&mut [&mut server, &mut c], 1_000_000, |apps| {
            world_settled(apps[1]) && world_of(apps[1]).1.live_chunks().count() == 4
        });
        held_s.push(start.elapsed().as_secs_f64());
        assert_eq!(
            world_hash(&mut c),
            want,
            "the client holds the server's chunks"
        );
    }
    (bytes, median(synced_s), median(held_s), coords.len())
}

/// World carves per second with 8 light clients sending 50 each at once
/// over the 4×4 chunks (0..4, 0..4), the server building every chunk they
/// reach.
fn eight_clients() -> (f64, usize) {
    let (mut server, addr) = world_server(world(), unlimited());
    let mut clients: Vec<App> = (0..8).map(|i| light_client(addr, 10 + i)).collect();
    for _ in 0..400 {
        server.update();
        clients.iter_mut().for_each(App::update);
        std::thread::sleep(Duration::from_millis(1));
    }
    let mut rng = Rng(8);
    burst_rate(&mut server, &mut clients, 50, |n, i| {
        let (tool, edit) = random_carve(&mut rng, 2.0, 126.0);
        ClientRequest::CarveWorld {
            request: (n * 50 + i) as u64,
            world: 1,
            tool: WireTool::from(&tool),
            edit,
        }
    })
}

fn main() {
    let Some(args) = support::Args::parse("net_world") else {
        return;
    };
    if args.wants("net_world_figures") {
        net_world_figures();
    }
}

fn net_world_figures() {
    let wire = wire_against_meshes();
    let (near, far, stored, idle_ms) = near_against_far();
    let (snapshot, join_synced, join_held, chunks) = join_after(1_000);
    let (rate, applied) = eight_clients();
    support::json_line(
        "net_world::net_world_figures",
        serde_json::json!({
            "carves": wire.carves,
            "carve_wire_bytes": wire.carve_wire,
            "carve_mesh_bytes": wire.carve_mesh,
            "carve_ratio": wire.carve_mesh / wire.carve_wire,
            "detaches": wire.detaches,
            "detach_wire_bytes": wire.detach_wire,
            "detach_mesh_bytes": wire.detach_mesh,
            "detach_ratio": wire.detach_mesh / wire.detach_wire,
            "cut_mesh_bytes": wire.cut_mesh,
            "near_carve_wall_ms": near.wall_ms,
            "near_carve_cpu_ms": near.cpu_ms,
            "near_carve_frames": near.frames,
            "near_carve_builds": near.builds,
            "near_carve_mesh_bytes": near.mesh_bytes,
            "far_carve_wall_ms": far.wall_ms,
            "far_carve_cpu_ms": far.cpu_ms,
            "far_carve_frames": far.frames,
            "far_carve_builds": far.builds,
            "far_carve_mesh_bytes": far.mesh_bytes,
            "far_chunks_stored": stored,
            "idle_frame_cpu_ms": idle_ms,
            "join_carves": 1_000,
            "join_chunks": chunks,
            "join_snapshot_bytes": snapshot,
            "join_synced_s": join_synced,
            "join_held_s": join_held,
            "eight_clients_world_carves_per_s": rate,
            "eight_clients_applied": applied,
        }),
    );
}
