//! Figures of networked carving, printed as one JSON line (BENCHMARKS.md
//! quotes it):
//!
//! `cargo bench -p bevy_chisel --all-features --bench net`
//!
//! `cargo test` runs this binary without `--bench`: it then measures
//! nothing (see `support`). The servers and clients are those of the
//! networked tests (`tests/it/net`, included by path).
//!
//! - bytes of one carve on the wire (the encoded [`ServerPacket::Carve`])
//!   against the bytes of the meshes of the cells it changed (vertex
//!   attributes and indices: what replicating meshes would send);
//! - carves per second one server sustains with 8 clients sending at once
//!   (light clients that send requests and read the broadcasts; the server
//!   validates, applies and meshes every carve);
//! - the time a client needs to join a terrain after 10,000 carves:
//!   snapshot received, terrain loaded and meshed.

#[path = "../tests/it/net/mod.rs"]
#[allow(dead_code, reason = "the tests' helpers, not all used here")]
mod net;
mod support;

use std::time::Instant;

use bevy::mesh::{Indices, Mesh3d};
use bevy::prelude::*;
use bevy_chisel::net::{ClientRequest, NetLimits, NetServerStats, WireTool};
use bevy_chisel::terrain::{CarveApplied, CellOutput, TerrainCellChanged};
use net::{
    Rng, Seen, burst_rate, client, light_client, random_carve, request, run_until, server,
    server_building, slab, terrain_of,
};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Mesh bytes of the cells changed this frame, per finished carve.
#[derive(Resource, Default)]
struct MeshBytes {
    pending: u64,
    per_carve: Vec<u64>,
}

fn count_mesh_bytes(
    mut changed: MessageReader<TerrainCellChanged>,
    mut applied: MessageReader<CarveApplied>,
    cells: Query<&Mesh3d>,
    meshes: Res<Assets<Mesh>>,
    mut bytes: ResMut<MeshBytes>,
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
            bytes.pending += (attributes + indices) as u64;
        }
    }
    let finished: Vec<_> = applied.read().collect();
    if !finished.is_empty() {
        let share = bytes.pending / finished.len() as u64;
        bytes.per_carve.extend(finished.iter().map(|_| share));
        bytes.pending = 0;
    }
}

fn unlimited() -> NetLimits {
    NetLimits {
        carves_per_second: 1e9,
        burst: 1e9,
        ..NetLimits::default()
    }
}

/// Bytes per carve: wire against meshes, one carve at a time.
fn wire_against_meshes() -> (f64, f64, usize) {
    let (mut server, addr) = server(net::slab(), unlimited());
    let mut a = client(addr, 1, 1);
    a.init_resource::<MeshBytes>()
        .add_systems(Last, count_mesh_bytes);
    run_until(&mut [&mut server, &mut a], 20_000, |apps| {
        terrain_of(&mut *apps[1]).is_some_and(|(_, t)| t.is_idle())
    });
    a.world_mut().resource_mut::<MeshBytes>().per_carve.clear();
    let mut rng = Rng(5);
    const N: usize = 200;
    for i in 0..N {
        let (tool, _) = random_carve(&mut rng);
        request(
            &mut a,
            i as u64,
            &tool,
            bevy_chisel::bsp::octree::Edit::Subtract,
        );
        run_until(&mut [&mut server, &mut a], 100_000, |apps| {
            apps[1].world().resource::<MeshBytes>().per_carve.len() > i
        });
    }
    let stats = server.world().resource::<NetServerStats>().clone();
    let wire = stats.carve_bytes as f64 / stats.accepted as f64;
    let meshes = a.world().resource::<MeshBytes>().per_carve.clone();
    let mesh = meshes.iter().sum::<u64>() as f64 / meshes.len() as f64;
    (wire, mesh, N)
}

/// Carves per second with 8 clients sending at once, the server building
/// `output` for its cells.
fn eight_clients(output: CellOutput) -> (f64, usize) {
    let (mut server, addr) = server_building(slab(), unlimited(), output);
    let mut clients: Vec<App> = (0..8).map(|i| light_client(addr, 10 + i)).collect();
    // Connect and let the server mesh its terrain.
    for _ in 0..400 {
        server.update();
        clients.iter_mut().for_each(App::update);
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let mut rng = Rng(8);
    burst_rate(&mut server, &mut clients, 50, |n, i| {
        let (tool, edit) = random_carve(&mut rng);
        ClientRequest::Carve {
            request: (n * 50 + i) as u64,
            terrain: 1,
            tool: WireTool::from(&tool),
            edit,
        }
    })
}

/// Join time after 10,000 carves.
fn join_after(carves: usize) -> (f64, f64, usize) {
    let mut terrain = slab().with_max_undo(0);
    let grid = *terrain.quantization();
    let mut rng = Rng(11);
    let mut done = 0;
    while done < carves {
        let (tool, edit) = random_carve(&mut rng);
        if let Ok(tool) = tool.to_grid(&grid)
            && terrain.apply_now(&tool, edit).is_ok()
        {
            done += 1;
        }
    }
    let (mut server, addr) = server(terrain, unlimited());
    run_until(&mut [&mut server], 100_000, |apps| {
        terrain_of(&mut *apps[0]).is_some_and(|(_, t)| t.is_idle())
    });
    let mut times = Vec::new();
    let mut meshed = Vec::new();
    let mut bytes = 0;
    for id in 0..3 {
        let start = Instant::now();
        let mut c = client(addr, 50 + id, 1);
        run_until(&mut [&mut server, &mut c], 1_000_000, |apps| {
            !apps[1].world().resource::<Seen>().synced.is_empty()
        });
        times.push(start.elapsed().as_secs_f64());
        bytes = c.world().resource::<Seen>().synced[0].bytes;
        run_until(&mut [&mut server, &mut c], 1_000_000, |apps| {
            terrain_of(&mut *apps[1]).is_some_and(|(_, t)| t.is_idle())
        });
        meshed.push(start.elapsed().as_secs_f64());
    }
    (median(times), median(meshed), bytes)
}

fn main() {
    let Some(args) = support::Args::parse("net") else {
        return;
    };
    if args.wants("net_figures") {
        net_figures();
    }
}

fn net_figures() {
    let (wire, mesh, carves) = wire_against_meshes();
    let (rate, applied) = eight_clients(CellOutput::Nothing);
    let (meshing_rate, _) = eight_clients(CellOutput::Meshes);
    let (join, join_meshed, snapshot) = join_after(10_000);
    support::json_line(
        "net::net_figures",
        serde_json::json!({
            "carves": carves,
            "wire_bytes_per_carve": wire,
            "mesh_bytes_per_carve": mesh,
            "ratio": mesh / wire,
            "eight_clients_carves_per_s": rate,
            "eight_clients_applied": applied,
            "eight_clients_meshing_server_carves_per_s": meshing_rate,
            "join_after_10000_s": join,
            "join_meshed_s": join_meshed,
            "snapshot_bytes": snapshot,
        }),
    );
    assert!(
        mesh / wire >= 100.0,
        "carves are at least 100x smaller than meshes"
    );
}
