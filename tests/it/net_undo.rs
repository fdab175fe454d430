//! Undo and redo of replicated terrains (`bevy_chisel::net::undo`): the
//! server's undos and redos reach every client in the terrain's order and
//! leave it bit-identical without a snapshot; a client's are requests the
//! server's `UndoPolicy` allows or refuses; a client whose history is too
//! short falls back to a snapshot; predicting clients stay exact.

use crate::{ONE_APP_AT_A_TIME, net};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, StateHash};
use bevy_chisel::net::{
    ClientPacket, ClientRequest, NetClientSettings, NetClientStats, NetLimits, NetServerStats,
    NetUndoResult, Outcome, RejectReason, ServerPacket, UndoPolicy,
};
use bevy_chisel::terrain::{CarveTool, RedoCarve, Terrain, UndoCarve};
use net::{Rng, client, random_carve, request, run_until, server, slab, terrain_of};

/// The undo answers an app saw.
#[derive(Resource, Default)]
struct UndoAnswers(Vec<NetUndoResult>);

fn record_answers(mut seen: ResMut<UndoAnswers>, mut results: MessageReader<NetUndoResult>) {
    seen.0.extend(results.read().cloned());
}

/// The answers to undo requests as they came over the wire.
#[derive(Resource, Default)]
struct WireAnswers(Vec<(u64, Outcome)>);

fn record_wire(mut seen: ResMut<WireAnswers>, mut packets: MessageReader<ServerPacket>) {
    for packet in packets.read() {
        if let ServerPacket::UndoResult { request, outcome } = packet {
            seen.0.push((*request, outcome.clone()));
        }
    }
}

/// A client connecting to `addr` that records its undo answers (and
/// predicts its own carves, or not).
fn player(addr: std::net::SocketAddr, id: u64, predict: bool) -> App {
    let mut app = client(addr, id, 1);
    app.insert_resource(NetClientSettings {
        predict_own_carves: predict,
    })
    .init_resource::<UndoAnswers>()
    .init_resource::<WireAnswers>()
    .add_systems(Last, (record_answers, record_wire));
    app
}

fn answers(app: &App) -> Vec<Outcome> {
    let seen = &app.world().resource::<UndoAnswers>().0;
    seen.iter().map(|a| a.outcome.clone()).collect()
}

fn idle(app: &mut App) -> bool {
    terrain_of(app).is_some_and(|(_, t)| t.is_idle())
}

fn last_op(app: &mut App) -> Option<u64> {
    terrain_of(app).and_then(|(_, t)| t.last_request())
}

/// The octree bytes and state hash of the app's terrain (the hash checked
/// against one from scratch).
fn state(app: &mut App) -> (Vec<u8>, u64) {
    let (_, terrain) = terrain_of(app).expect("terrain");
    let hash = terrain.state_hash();
    assert_eq!(hash, StateHash::of(terrain.octree()).value(), "hash kept");
    (terrain.octree().to_bytes(), hash)
}

fn stats(app: &App) -> NetClientStats {
    app.world().resource::<NetClientStats>().clone()
}

fn server_stats(app: &App) -> NetServerStats {
    app.world().resource::<NetServerStats>().clone()
}

/// Updates every app (the server first) until each is idle with the
/// server's last op and, where `ops` is given, that op is `ops`; then a
/// few more frames for the hash checks.
fn settle(apps: &mut [&mut App], ops: Option<u64>) {
    run_until(apps, 200_000, |apps| {
        let want = last_op(apps[0]);
        (ops.is_none() || want == ops)
            && apps.iter_mut().all(|app| idle(app) && last_op(app) == want)
    });
    for _ in 0..40 {
        net::update_all(apps);
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// Connects the clients and waits for their snapshots.
fn join(apps: &mut [&mut App]) {
    run_until(apps, 20_000, |apps| {
        apps[1..].iter_mut().all(|app| idle(app))
    });
}

/// Every client's terrain bit-identical to the server's, with no desync.
fn assert_identical(server: &mut App, clients: &mut [(&str, &mut App)]) {
    let reference = state(server);
    for (name, app) in clients.iter_mut() {
        let peer = state(app);
        assert_eq!(peer.1, reference.1, "{name}: state hash");
        assert!(peer.0 == reference.0, "{name}: octree bytes differ");
        assert_eq!(stats(app).desyncs, 0, "{name}: no desync");
    }
}

fn blast(x: f32, z: f32) -> CarveTool {
    CarveTool::dodecahedron(0.4, Vec3::new(x, 2.0, z))
}

fn undo(app: &mut App) {
    let (terrain, _) = terrain_of(app).expect("terrain");
    app.world_mut().write_message(UndoCarve { terrain });
}

fn redo(app: &mut App) {
    let (terrain, _) = terrain_of(app).expect("terrain");
    app.world_mut().write_message(RedoCarve { terrain });
}

/// The app's terrain's undo and redo depths.
fn depths(app: &mut App) -> (usize, usize) {
    let terrain: &Terrain = terrain_of(app).expect("terrain").1;
    (terrain.undo_depth(), terrain.redo_depth())
}

#[test]
fn server_undo_and_redo_reach_every_client_without_a_snapshot() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab(), net::unlimited());
    server
        .init_resource::<UndoAnswers>()
        .add_systems(Last, record_answers);
    let mut a = player(addr, 1, false);
    let mut b = player(addr, 2, true);
    join(&mut [&mut server, &mut a, &mut b]);
    let mut after = Vec::new();
    for (i, x) in [2.0, 5.0, 8.0].into_iter().enumerate() {
        request(&mut a, i as u64, &blast(x, 5.0), Edit::Subtract);
        settle(&mut [&mut server, &mut a, &mut b], Some(i as u64 + 1));
        after.push(state(&mut server));
    }
    let snapshots = server_stats(&server).snapshots;
    assert_eq!(snapshots, 2, "one per client at join");

    // Two undos and a redo from the server, then a carve and an undo.
    undo(&mut server);
    undo(&mut server);
    settle(&mut [&mut server, &mut a, &mut b], Some(5));
    assert!(state(&mut server) == after[0], "two carves undone");
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    redo(&mut server);
    settle(&mut [&mut server, &mut a, &mut b], Some(6));
    assert!(state(&mut server) == after[1], "one redone exactly");
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    assert_eq!(depths(&mut a).1, 1, "the client can redo too");
    redo(&mut server);
    settle(&mut [&mut server, &mut a, &mut b], Some(7));
    assert!(state(&mut server) == after[2], "both redone exactly");
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);

    for app in [&a, &b] {
        let s = stats(app);
        assert_eq!(s.undos, 4, "{s:?}");
        assert_eq!(s.snapshots, 1, "no snapshot after the join: {s:?}");
        assert_eq!(s.undo_resyncs, 0);
        assert!(
            s.checks_passed > 0,
            "the hashes after the undos were checked"
        );
    }
    let s = server_stats(&server);
    assert_eq!((s.snapshots, s.undos), (snapshots, 4), "{s:?}");
    // The server's own undos are answered in its app.
    let own = answers(&server);
    assert_eq!(own.len(), 4, "{own:?}");
    assert_eq!(own[3], Outcome::Applied { seq: 7 });
    // With nothing to redo, the server's redo is refused and no op sent.
    redo(&mut server);
    settle(&mut [&mut server, &mut a, &mut b], Some(7));
    assert_eq!(
        answers(&server)[4],
        Outcome::Rejected(RejectReason::NothingToRedo)
    );
    assert_eq!(server_stats(&server).undos, 4);
}

#[test]
fn a_client_undoes_and_redoes_its_own_carve_but_not_anothers() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab(), net::unlimited());
    let mut a = player(addr, 1, true);
    let mut b = player(addr, 2, false);
    join(&mut [&mut server, &mut a, &mut b]);
    let before = state(&mut server);
    request(&mut a, 1, &blast(3.0, 3.0), Edit::Subtract);
    settle(&mut [&mut server, &mut a, &mut b], Some(1));
    let carved = state(&mut server);

    // B may not undo A's carve.
    undo(&mut b);
    settle(&mut [&mut server, &mut a, &mut b], Some(1));
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        !answers(apps[2]).is_empty()
    });
    assert_eq!(
        answers(&b),
        [Outcome::Rejected(RejectReason::NotYourCarve { seq: 1 })]
    );
    assert!(state(&mut server) == carved, "nothing changed");

    // A may.
    undo(&mut a);
    settle(&mut [&mut server, &mut a, &mut b], Some(2));
    assert_eq!(answers(&a), [Outcome::Applied { seq: 2 }]);
    assert!(state(&mut server) == before, "the carve is undone");
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    // B may not redo it; A may.
    redo(&mut b);
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        answers(apps[2]).len() == 2
    });
    assert_eq!(
        answers(&b)[1],
        Outcome::Rejected(RejectReason::NotYourCarve { seq: 1 })
    );
    redo(&mut a);
    settle(&mut [&mut server, &mut a, &mut b], Some(3));
    assert_eq!(answers(&a)[1], Outcome::Applied { seq: 3 });
    assert!(state(&mut server) == carved, "the carve is back exactly");
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    // Nothing left to redo.
    redo(&mut a);
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        answers(apps[1]).len() == 3
    });
    assert_eq!(
        answers(&a)[2],
        Outcome::Rejected(RejectReason::NothingToRedo)
    );
    for (name, app) in [("a", &a), ("b", &b)] {
        assert_eq!(
            stats(app).snapshots,
            1,
            "{name}: no snapshot after the join"
        );
    }
    // A request naming no terrain gets a typed refusal.
    b.world_mut()
        .write_message(ClientPacket::Request(ClientRequest::Undo {
            request: 99,
            terrain: 42,
            redo: false,
        }));
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        (apps[2].world().resource::<WireAnswers>().0)
            .iter()
            .any(|(request, _)| *request == 99)
    });
    let wire = &b.world().resource::<WireAnswers>().0;
    assert_eq!(
        wire.last(),
        Some(&(99, Outcome::Rejected(RejectReason::UnknownTerrain(42))))
    );
    assert!(state(&mut server) == carved, "nothing changed");
}

#[test]
fn an_undo_older_than_a_clients_snapshot_falls_back_to_a_snapshot() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab(), net::unlimited());
    let mut a = player(addr, 1, false);
    join(&mut [&mut server, &mut a]);
    request(&mut a, 1, &blast(3.0, 3.0), Edit::Subtract);
    request(&mut a, 2, &blast(6.0, 3.0), Edit::Subtract);
    settle(&mut [&mut server, &mut a], Some(2));
    // C joins after both carves: its history holds neither.
    let mut c = player(addr, 3, false);
    join(&mut [&mut server, &mut a, &mut c]);
    assert_eq!(depths(&mut c).0, 0);
    // C carves once: it can follow one undo, not two.
    request(&mut c, 1, &blast(6.0, 7.0), Edit::Subtract);
    settle(&mut [&mut server, &mut a, &mut c], Some(3));
    undo(&mut server);
    settle(&mut [&mut server, &mut a, &mut c], Some(4));
    assert_eq!(stats(&c).undo_resyncs, 0, "C's own carve is in its history");
    undo(&mut server);
    settle(&mut [&mut server, &mut a, &mut c], Some(5));
    assert_identical(&mut server, &mut [("a", &mut a), ("c", &mut c)]);
    let (sa, sc) = (stats(&a), stats(&c));
    assert_eq!(
        (sa.undos, sa.snapshots, sa.undo_resyncs),
        (2, 1, 0),
        "{sa:?}"
    );
    assert_eq!((sc.undo_resyncs, sc.snapshots), (1, 2), "{sc:?}");
    // After its snapshot, C follows the next carve and undo again.
    request(&mut a, 3, &blast(8.0, 8.0), Edit::Subtract);
    settle(&mut [&mut server, &mut a, &mut c], Some(6));
    undo(&mut server);
    settle(&mut [&mut server, &mut a, &mut c], Some(7));
    assert_identical(&mut server, &mut [("a", &mut a), ("c", &mut c)]);
    assert_eq!(stats(&c).snapshots, 2, "no second snapshot");
}

#[test]
fn undos_among_predicting_clients_keep_every_terrain_identical() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let mut terrain = slab();
    terrain = terrain.with_max_undo(32);
    // Any client may undo the latest carve: the clients' undos meet
    // their own and each other's predictions.
    let limits = NetLimits {
        undo: UndoPolicy::Anyone,
        ..net::unlimited()
    };
    let (mut server, addr) = server(terrain, limits);
    let mut a = player(addr, 1, true);
    let mut b = player(addr, 2, true);
    let mut c = player(addr, 3, false);
    join(&mut [&mut server, &mut a, &mut b, &mut c]);
    let mut rng = Rng(0x5EED_00D0);
    let mut next = 0u64;
    for round in 0..24 {
        for _ in 0..(1 + rng.next() % 3) {
            for app in [&mut a, &mut b] {
                let (tool, edit) = random_carve(&mut rng);
                next += 1;
                request(app, next, &tool, edit);
            }
            a.update();
            b.update();
        }
        match rng.next() % 4 {
            0 => undo(&mut server),
            1 => redo(&mut server),
            2 => undo(&mut a),
            _ => {
                undo(&mut server);
                undo(&mut b);
            }
        }
        // Frames without settling, so that the undos meet predictions.
        for _ in 0..(rng.next() % 6) {
            net::update_all(&mut [&mut server, &mut a, &mut b, &mut c]);
        }
        if round % 4 == 3 {
            redo(&mut a);
        }
    }
    settle(&mut [&mut server, &mut a, &mut b, &mut c], None);
    assert_identical(
        &mut server,
        &mut [("a", &mut a), ("b", &mut b), ("c", &mut c)],
    );
    let s = server_stats(&server);
    println!("server: {s:?}");
    assert!(s.undos >= 12, "undos were ordered: {s:?}");
    for (name, app) in [("a", &a), ("b", &b), ("c", &c)] {
        let s = stats(app);
        println!("{name}: {s:?}");
        assert_eq!(s.undos, server_stats(&server).undos, "{name}: every undo");
    }
    let rolled: u64 = [&a, &b].iter().map(|app| stats(app).rollbacks).sum();
    assert!(rolled > 0, "undos met pending predictions");
    for app in [&a, &b] {
        let outcomes = answers(app);
        let applied = outcomes
            .iter()
            .filter(|o| matches!(o, Outcome::Applied { .. }));
        assert!(applied.count() > 0, "the clients' undos were ordered");
    }
}
