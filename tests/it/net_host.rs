//! One game binary in every role: apps with both `NetServerPlugin` and
//! `NetClientPlugin`. A listen-server host (a player whose app runs the
//! server) and two clients carve a terrain and a streamed world over
//! 127.0.0.1 with the same messages; at the end every peer holds the
//! host's octrees bit-identical, which are their journals replayed, and
//! each accepted carve was applied once. The host is validated but not
//! rate limited; an app with neither a server nor a connection carves
//! alone through the same messages, and follows none of the packets its
//! own server addresses to it. A client that loses its connection carves
//! alone and rejoins identical; a request with no server to go to is
//! answered `NotConnected`.

use std::collections::{BTreeMap, BTreeSet};
use std::net::{Ipv4Addr, SocketAddr};

use crate::net::world::build_deferred;
use crate::net_worlds::{
    edited_chunks, edited_terrains, streamed_world as world, world_settled, world_tool,
};
use crate::{ONE_APP_AT_A_TIME, net};
use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::net::{
    NetCarve, NetCarveRequest, NetCarveResult, NetClientPlugin, NetClientStats, NetLimits,
    NetServerPlugin, NetServerStats, NetTerrain, NetWorld, Outcome, RejectReason, ServerPacket,
    SnapshotPart, WirePose, WireShape, WireTool, WorldSynced, start_client, start_server,
};
use bevy_chisel::terrain::{
    CarveTool, CellOutput, ChunkCoord, Terrain, TerrainFocus, TerrainPlugin, TerrainSettings,
};
use bevy_replicon::prelude::{ClientState, SendTargets, ServerState, ToClients};
use net::{Rng, random_carve, request, request_world, run_until, slab, terrain_of, world_of};

/// Rounds of carves; in each, every peer asks for one terrain carve and
/// one world carve.
const ROUNDS: usize = 40;

/// Results and world snapshots an app saw.
#[derive(Resource, Default)]
struct Answers {
    results: Vec<NetCarveResult>,
    worlds_synced: usize,
}

fn record(
    mut answers: ResMut<Answers>,
    mut results: MessageReader<NetCarveResult>,
    mut synced: MessageReader<WorldSynced>,
) {
    answers.results.extend(results.read().cloned());
    answers.worlds_synced += synced.read().count();
}

/// A game app in no role yet: both networking plugins, the world as
/// network world 1 with a focus at `focus`.
fn game_app(limits: NetLimits, focus: Vec3) -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin::default(),
        TransformPlugin,
        TerrainPlugin,
        NetServerPlugin,
        NetClientPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .insert_resource(TerrainSettings {
        worker_threads: 1,
        output: CellOutput::Nothing,
        ..TerrainSettings::default()
    })
    .insert_resource(limits)
    .init_resource::<Answers>()
    .add_systems(Last, record);
    app.world_mut().spawn((world(), NetWorld(1)));
    app.world_mut()
        .spawn((TerrainFocus, Transform::from_translation(focus)));
    app
}

/// The host: a game app with the slab as network terrain 1, listening.
fn host(limits: NetLimits) -> (App, SocketAddr) {
    let mut app = game_app(limits, Vec3::new(16.0, 30.0, 16.0));
    app.world_mut().spawn((slab(), NetTerrain(1)));
    app.finish();
    app.cleanup();
    let addr =
        start_server(app.world_mut(), (Ipv4Addr::LOCALHOST, 0).into(), 8).expect("host listens");
    (app, addr)
}

/// A game app connecting to the host as client `id`.
fn joining(addr: SocketAddr, id: u64, focus: Vec3) -> App {
    let mut app = game_app(NetLimits::default(), focus);
    app.finish();
    app.cleanup();
    start_client(app.world_mut(), addr, id).expect("client starts");
    app
}

fn answers(app: &App) -> &[NetCarveResult] {
    &app.world().resource::<Answers>().results
}

/// Whether the terrain (if any) is idle and the world settled; asks the
/// world to build the far chunks whose carves a client deferred, so that
/// a settled peer holds every edited chunk.
fn settled(app: &mut App) -> bool {
    build_deferred(app);
    terrain_of(app).is_none_or(|(_, t)| t.is_idle()) && world_settled(app)
}

/// A random blast or heap near the surface of chunks (0..3, 0..3).
fn random_world_carve(rng: &mut Rng) -> (CarveTool, Edit) {
    let centre = Vec3::new(
        rng.range(2.0, 94.0),
        rng.range(8.0, 20.0),
        rng.range(2.0, 94.0),
    );
    let tool = CarveTool::dodecahedron(rng.range(1.5, 4.0), centre);
    let edit = if rng.next().is_multiple_of(5) {
        Edit::Add(2)
    } else {
        Edit::Subtract
    };
    (tool, edit)
}

/// A request id: the peer, whether it is a world carve, and a counter.
fn request_id(peer: u64, world: bool, n: usize) -> u64 {
    (n as u64) << 3 | u64::from(world) << 2 | peer
}

fn is_world(request: u64) -> bool {
    request & 4 != 0
}

fn applied(results: &[NetCarveResult], world: bool) -> usize {
    results
        .iter()
        .filter(|r| r.request.is_some_and(|id| is_world(id) == world))
        .filter(|r| matches!(r.outcome, Outcome::Applied { .. }))
        .count()
}

#[test]
fn a_host_and_two_clients_end_identical_with_each_carve_applied_once() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = net::unlimited();
    let (mut host, addr) = host(limits);
    let mut a = joining(addr, 1, Vec3::new(80.0, 30.0, 48.0));
    let mut b = joining(addr, 2, Vec3::new(48.0, 30.0, 80.0));
    run_until(&mut [&mut host, &mut a, &mut b], 20_000, |apps| {
        apps[1..].iter_mut().all(|app| {
            terrain_of(app).is_some()
                && app.world().resource::<Answers>().worlds_synced > 0
                && settled(app)
        })
    });
    assert_eq!(
        *host.world().resource::<State<ServerState>>().get(),
        ServerState::Running
    );
    assert_eq!(
        *a.world().resource::<State<ClientState>>().get(),
        ClientState::Connected
    );

    // Every peer sends a terrain carve and a world carve each frame.
    let mut rng = Rng(4242);
    let mut sent: BTreeMap<u64, BTreeSet<u64>> = BTreeMap::new();
    for round in 0..ROUNDS {
        for (peer, app) in [&mut host, &mut a, &mut b].into_iter().enumerate() {
            let peer = peer as u64;
            let (tool, edit) = random_carve(&mut rng);
            let id = request_id(peer, false, round);
            request(app, id, &tool, edit);
            let (tool, edit) = random_world_carve(&mut rng);
            let world_id = request_id(peer, true, round);
            request_world(app, world_id, &tool, edit);
            sent.entry(peer).or_default().extend([id, world_id]);
        }
        for app in [&mut host, &mut a, &mut b] {
            app.update();
        }
        std::thread::sleep(std::time::Duration::from_micros(500));
    }
    let want = 2 * ROUNDS;
    run_until(&mut [&mut host, &mut a, &mut b], 200_000, |apps| {
        apps.iter().all(|app| answers(app).len() >= want)
            && apps.iter_mut().all(|app| settled(app))
            && {
                let reference = edited_chunks(apps[0]);
                apps[1..]
                    .iter_mut()
                    .all(|app| edited_chunks(app) == reference)
            }
    });
    for _ in 0..40 {
        for app in [&mut host, &mut a, &mut b] {
            app.update();
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }

    // Each peer got exactly one answer per request, the host included.
    for (peer, app) in [&host, &a, &b].into_iter().enumerate() {
        let ids: Vec<u64> = answers(app).iter().filter_map(|r| r.request).collect();
        let unique: BTreeSet<u64> = ids.iter().copied().collect();
        assert_eq!(ids.len(), unique.len(), "peer {peer}: one answer each");
        assert_eq!(unique, sent[&(peer as u64)], "peer {peer}: every request");
    }
    let all: Vec<NetCarveResult> = [&host, &a, &b]
        .iter()
        .flat_map(|app| answers(app).iter().cloned())
        .collect();
    let (terrain_carves, world_carves) = (applied(&all, false), applied(&all, true));
    println!(
        "{terrain_carves} terrain and {world_carves} world carves applied of {} each",
        3 * ROUNDS
    );
    assert!(terrain_carves >= 3 * ROUNDS * 9 / 10 && world_carves >= 3 * ROUNDS * 9 / 10);
    let host_applied = applied(answers(&host), false) + applied(answers(&host), true);
    assert!(host_applied > ROUNDS, "the host's own carves apply");

    // The host's terrain has one journal entry per applied terrain carve,
    // numbered in the server's order; each peer's octree is the host's,
    // which is the journal replayed on the slab.
    let (_, terrain) = terrain_of(&mut host).expect("host terrain");
    assert_eq!(terrain.journal().len(), terrain_carves, "one entry each");
    assert_eq!(terrain.last_request(), Some(3 * ROUNDS as u64));
    let reference = (terrain.octree().to_bytes(), terrain.state_hash());
    let mut replay = slab();
    for entry in terrain.journal() {
        replay.apply_now(&entry.tool, entry.edit).expect("replays");
    }
    assert!(
        replay.octree().to_bytes() == reference.0,
        "journal replayed"
    );
    for app in [&mut a, &mut b] {
        let (_, terrain) = terrain_of(app).expect("client terrain");
        assert_eq!(terrain.state_hash(), reference.1);
        assert!(terrain.octree().to_bytes() == reference.0, "octree differs");
    }

    // Every edited chunk is the same on every peer and is its journal
    // replayed on the source's chunk.
    let chunks = edited_chunks(&mut host);
    assert!(chunks.len() >= 4, "carves edited {} chunks", chunks.len());
    for app in [&mut a, &mut b] {
        assert!(edited_chunks(app) == chunks, "a client's chunks differ");
    }
    let (_, host_world) = world_of(&mut host);
    let mut generated: BTreeMap<ChunkCoord, Terrain> = chunks
        .keys()
        .map(|&c| (c, host_world.generate_chunk(c).expect("chunk builds")))
        .collect();
    for (coord, terrain) in edited_terrains(&mut host) {
        let mut replay = generated.remove(&coord).expect("generated");
        for entry in terrain.journal() {
            replay.apply_now(&entry.tool, entry.edit).expect("replays");
        }
        assert!(
            replay.octree().to_bytes() == chunks[&coord].0,
            "chunk {coord:?} is its journal replayed"
        );
    }

    // The host orders every carve and follows none; the clients order
    // none and follow every one, checked against the host's hashes.
    let host_stats = host.world().resource::<NetServerStats>().clone();
    assert_eq!(host_stats.accepted as usize, 6 * ROUNDS);
    let followed = host.world().resource::<NetClientStats>().clone();
    assert_eq!(followed.carves, 0, "the host follows nothing: {followed:?}");
    assert_eq!(followed.snapshots, 0);
    for app in [&a, &b] {
        assert_eq!(app.world().resource::<NetServerStats>().accepted, 0);
        let stats = app.world().resource::<NetClientStats>().clone();
        assert_eq!(stats.carves as usize, 6 * ROUNDS, "{stats:?}");
        assert_eq!(stats.desyncs, 0);
        assert!(stats.checks_passed > 0);
    }
}

fn nan_tool() -> WireTool {
    world_tool(
        WireShape::Dodecahedron { radius: 0.3 },
        [f32::NAN, 2.0, 5.0],
    )
}

#[test]
fn the_host_is_validated_but_not_rate_limited() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    // Default limits: 40 carves at once, then 20 a second.
    let (mut host, addr) = host(NetLimits::default());
    let mut a = joining(addr, 1, Vec3::new(80.0, 30.0, 48.0));
    // A request while connecting (the host does not answer yet) is
    // answered at once, and not sent.
    run_until(&mut [&mut a], 100, |apps| {
        *apps[0].world().resource::<State<ClientState>>().get() == ClientState::Connecting
    });
    let early = CarveTool::dodecahedron(2.0, Vec3::new(80.0, 14.0, 48.0));
    request_world(&mut a, 99, &early, Edit::Subtract);
    a.update();
    assert_eq!(
        answers(&a),
        [NetCarveResult {
            request: Some(99),
            outcome: Outcome::Rejected(RejectReason::NotConnected),
        }]
    );
    run_until(&mut [&mut host, &mut a], 20_000, |apps| {
        terrain_of(apps[1]).is_some() && settled(apps[1])
    });
    let before = terrain_of(&mut host).map(|(_, t)| t.state_hash());

    // Hostile requests from the host itself: refused with their reasons.
    let (terrain, _) = terrain_of(&mut host).expect("terrain");
    let (world, _) = world_of(&mut host);
    let unknown_material = WireTool::from(&CarveTool::dodecahedron(0.3, Vec3::new(5.0, 2.0, 5.0)));
    host.world_mut().write_message(NetCarveRequest {
        request: 1,
        terrain,
        tool: nan_tool(),
        edit: Edit::Subtract,
    });
    host.world_mut().write_message(NetCarveRequest {
        request: 2,
        terrain,
        tool: unknown_material,
        edit: Edit::Add(9),
    });
    host.world_mut()
        .write_message(bevy_chisel::net::NetWorldCarveRequest {
            request: 3,
            world,
            tool: nan_tool(),
            edit: Edit::Subtract,
        });
    run_until(&mut [&mut host, &mut a], 2_000, |apps| {
        answers(apps[0]).len() == 3
    });
    for result in answers(&host) {
        assert!(
            matches!(result.outcome, Outcome::Rejected(RejectReason::Invalid(_))),
            "{result:?}"
        );
    }
    assert_eq!(terrain_of(&mut host).map(|(_, t)| t.state_hash()), before);
    assert!(edited_chunks(&mut host).is_empty(), "no chunk was edited");
    assert_eq!(host.world().resource::<NetServerStats>().accepted, 0);

    // 60 carves in one frame from the host, and from a client.
    let mut rng = Rng(7);
    for n in 1..=60 {
        let (tool, _) = random_carve(&mut rng);
        request(&mut host, request_id(0, false, n), &tool, Edit::Subtract);
        request(&mut a, request_id(1, false, n), &tool, Edit::Subtract);
    }
    run_until(&mut [&mut host, &mut a], 20_000, |apps| {
        answers(apps[0]).len() == 63 && answers(apps[1]).len() == 61
    });
    let limited = |app: &App| {
        answers(app)
            .iter()
            .filter(|r| r.outcome == Outcome::Rejected(RejectReason::RateLimited))
            .count()
    };
    assert_eq!(limited(&host), 0, "the host is not rate limited");
    assert_eq!(applied(answers(&host), false), 60);
    assert!(limited(&a) >= 15, "a client is: {} limited", limited(&a));
}

#[test]
fn a_single_player_app_carves_through_the_same_messages() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = game_app(NetLimits::default(), Vec3::new(16.0, 30.0, 16.0));
    app.world_mut().spawn((slab(), NetTerrain(1)));
    app.finish();
    app.cleanup();
    run_until(&mut [&mut app], 2_000, |apps| settled(apps[0]));
    assert_eq!(
        *app.world().resource::<State<ServerState>>().get(),
        ServerState::Stopped
    );
    assert_eq!(
        *app.world().resource::<State<ClientState>>().get(),
        ClientState::Disconnected
    );
    let mut rng = Rng(11);
    for n in 0..50 {
        let (tool, edit) = random_carve(&mut rng);
        request(&mut app, request_id(0, false, n), &tool, edit);
        let (tool, edit) = random_world_carve(&mut rng);
        request_world(&mut app, request_id(0, true, n), &tool, edit);
    }
    let (terrain, _) = terrain_of(&mut app).expect("terrain");
    app.world_mut().write_message(NetCarveRequest {
        request: 1 << 40,
        terrain,
        tool: nan_tool(),
        edit: Edit::Subtract,
    });
    run_until(&mut [&mut app], 20_000, |apps| {
        answers(apps[0]).len() == 101 && settled(apps[0])
    });
    let results = answers(&app).to_vec();
    let refused = results
        .iter()
        .find(|r| r.request == Some(1 << 40))
        .expect("answered");
    assert!(matches!(
        refused.outcome,
        Outcome::Rejected(RejectReason::Invalid(_))
    ));
    let terrain_carves = applied(&results, false);
    let world_carves = applied(&results, true);
    assert!(terrain_carves >= 45 && world_carves >= 45, "{results:?}");
    let (_, terrain) = terrain_of(&mut app).expect("terrain");
    assert_eq!(terrain.journal().len(), terrain_carves, "one entry each");
    assert!(!edited_chunks(&mut app).is_empty());
    assert_eq!(app.world().resource::<NetClientStats>().carves, 0);
}

/// Server packets addressed to the app itself (bevy_replicon delivers
/// those locally while it is no connected client) are its own server
/// speaking: a host or single player neither applies, buffers nor installs
/// them, and answers still arrive.
#[test]
fn an_app_that_is_no_client_follows_none_of_its_own_packets() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = game_app(NetLimits::default(), Vec3::new(16.0, 30.0, 16.0));
    app.world_mut().spawn((slab(), NetTerrain(1)));
    app.finish();
    app.cleanup();
    run_until(&mut [&mut app], 2_000, |apps| settled(apps[0]));
    let (_, terrain) = terrain_of(&mut app).expect("terrain");
    let before = terrain.state_hash();
    let snapshot = terrain.to_snapshot_bytes();
    let tool = CarveTool::dodecahedron(0.4, Vec3::new(5.0, 2.0, 5.0))
        .to_grid(terrain.quantization())
        .expect("rounds");
    let to_all = |message| ToClients {
        targets: SendTargets::All,
        message,
    };
    app.world_mut()
        .write_message(to_all(ServerPacket::Carve(NetCarve {
            terrain: 1,
            seq: 1,
            tool,
            edit: Edit::Subtract,
        })));
    app.world_mut()
        .write_message(to_all(ServerPacket::Snapshot(SnapshotPart {
            terrain: 1,
            seq: 0,
            total: snapshot.len() as u64,
            offset: 0,
            bytes: snapshot,
            pose: WirePose::from(&Transform::default()),
        })));
    app.world_mut().write_message(to_all(ServerPacket::Check {
        terrain: 1,
        seq: 1,
        hash: 0,
    }));
    app.world_mut().write_message(to_all(ServerPacket::Result {
        request: Some(5),
        outcome: Outcome::Applied { seq: 9 },
    }));
    for _ in 0..20 {
        app.update();
    }
    let mut terrains = app
        .world_mut()
        .query_filtered::<&Terrain, With<NetTerrain>>();
    let terrains: Vec<&Terrain> = terrains.iter(app.world()).collect();
    assert_eq!(terrains.len(), 1, "no terrain installed from the snapshot");
    assert_eq!(terrains[0].state_hash(), before, "the carve is not applied");
    assert!(terrains[0].journal().is_empty());
    let stats = app.world().resource::<NetClientStats>().clone();
    assert_eq!((stats.carves, stats.snapshots, stats.desyncs), (0, 0, 0));
    assert_eq!(
        answers(&app),
        [NetCarveResult {
            request: Some(5),
            outcome: Outcome::Applied { seq: 9 },
        }]
    );
}

/// A client that loses its connection carves alone (as a single player),
/// then joins again: what it carved alone is replaced by the host's
/// snapshots, and it ends identical to the host.
#[test]
fn a_client_that_leaves_carves_alone_and_rejoins_identical() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = net::unlimited();
    let (mut host, addr) = host(limits);
    let mut a = joining(addr, 1, Vec3::new(48.0, 30.0, 48.0));
    let ready = |app: &mut App| {
        terrain_of(app).is_some() && app.world().resource::<Answers>().worlds_synced > 0
    };
    run_until(&mut [&mut host, &mut a], 20_000, |apps| {
        ready(apps[1]) && settled(apps[1])
    });
    let mut rng = Rng(99);
    let mut carve_both = |apps: [&mut App; 2], n: usize| {
        for app in apps {
            let (tool, edit) = random_carve(&mut rng);
            request(app, request_id(0, false, n), &tool, edit);
            let (tool, edit) = random_world_carve(&mut rng);
            request_world(app, request_id(0, true, n), &tool, edit);
        }
    };
    for n in 0..5 {
        carve_both([&mut host, &mut a], n);
        host.update();
        a.update();
    }
    let state = |app: &App| *app.world().resource::<State<ClientState>>().get();
    run_until(&mut [&mut host, &mut a], 20_000, |apps| {
        answers(apps[1]).len() == 10 && settled(apps[0]) && settled(apps[1])
    });

    // The connection ends; the client carves alone, the host goes on.
    a.world_mut()
        .resource_mut::<bevy_replicon_renet::RenetClient>()
        .disconnect();
    run_until(&mut [&mut host, &mut a], 200, |apps| {
        state(apps[1]) == ClientState::Disconnected
    });
    a.world_mut()
        .remove_resource::<bevy_replicon_renet::RenetClient>();
    a.world_mut()
        .remove_resource::<bevy_replicon_renet::netcode::NetcodeClientTransport>();
    for n in 5..10 {
        carve_both([&mut host, &mut a], n);
        host.update();
        a.update();
    }
    run_until(&mut [&mut host, &mut a], 20_000, |apps| {
        answers(apps[0]).len() == 20 && answers(apps[1]).len() == 20
    });
    let alone = applied(answers(&a), false) + applied(answers(&a), true);
    assert!(alone >= 15, "the client's carves apply alone too");
    run_until(&mut [&mut host, &mut a], 20_000, |apps| {
        settled(apps[0]) && settled(apps[1])
    });
    let hash = |app: &mut App| terrain_of(app).map(|(_, t)| t.state_hash());
    assert_ne!(hash(&mut a), hash(&mut host), "the terrains went apart");
    assert!(edited_chunks(&mut a) != edited_chunks(&mut host));

    // It joins again, and ends as the host.
    start_client(a.world_mut(), addr, 11).expect("client starts");
    run_until(&mut [&mut host, &mut a], 50_000, |apps| {
        state(apps[1]) == ClientState::Connected
            && settled(apps[0])
            && settled(apps[1])
            && terrain_of(apps[1]).map(|(_, t)| t.state_hash())
                == terrain_of(apps[0]).map(|(_, t)| t.state_hash())
            && edited_chunks(apps[1]) == edited_chunks(apps[0])
    });
    let (_, terrain) = terrain_of(&mut host).expect("host terrain");
    let bytes = terrain.octree().to_bytes();
    let (_, terrain) = terrain_of(&mut a).expect("client terrain");
    assert!(terrain.octree().to_bytes() == bytes, "octree differs");
    let stats = a.world().resource::<NetClientStats>().clone();
    assert!(
        stats.snapshots >= 4,
        "two of each on joining twice: {stats:?}"
    );
    assert_eq!(stats.desyncs, 0);
}

/// A client-only app (no server plugin) that is not connected has no server
/// to send to: its requests are answered at once, not lost.
#[test]
fn a_client_only_app_that_is_not_connected_answers_not_connected() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut app = net::client_app(1);
    app.world_mut().spawn((slab(), NetTerrain(1)));
    app.update();
    let tool = CarveTool::dodecahedron(0.3, Vec3::new(5.0, 2.0, 5.0));
    request(&mut app, 7, &tool, Edit::Subtract);
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(
        app.world().resource::<net::Seen>().results,
        [NetCarveResult {
            request: Some(7),
            outcome: Outcome::Rejected(RejectReason::NotConnected),
        }]
    );
    let (_, terrain) = terrain_of(&mut app).expect("terrain");
    assert!(terrain.journal().is_empty(), "nothing carved");
}
