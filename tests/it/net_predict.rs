//! Client-side prediction of a client's own carves
//! (`NetClientSettings::predict_own_carves`): a predicting client shows
//! its crater before the server has run, runs no second carve job when
//! the server confirms it, rolls back when another carve comes first or
//! the server refuses its request, and always ends bit-identical to the
//! server.

use crate::{ONE_APP_AT_A_TIME, net};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, StateHash};
use bevy_chisel::net::{
    NetClientSettings, NetClientStats, NetLimits, NetServerStats, Outcome, RejectReason,
};
use bevy_chisel::terrain::{CarveApplied, CarveTool};
use net::{Rng, Seen, client, random_carve, request, run_until, server, slab, terrain_of};

/// The carve reports a client saw.
#[derive(Resource, Default)]
struct Reports(Vec<CarveApplied>);

fn record_reports(mut reports: ResMut<Reports>, mut applied: MessageReader<CarveApplied>) {
    reports.0.extend(applied.read().cloned());
}

/// A client connecting to `addr` that predicts its own carves (or not).
fn predicting(addr: std::net::SocketAddr, id: u64, threads: usize, predict: bool) -> App {
    let mut app = client(addr, id, threads);
    app.insert_resource(NetClientSettings {
        predict_own_carves: predict,
    })
    .init_resource::<Reports>()
    .add_systems(Last, record_reports);
    app
}

fn idle(app: &mut App) -> bool {
    terrain_of(app).is_some_and(|(_, t)| t.is_idle())
}

fn last_carve(app: &mut App) -> Option<u64> {
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

fn reports(app: &App) -> &[CarveApplied] {
    &app.world().resource::<Reports>().0
}

/// Updates `app` alone until its terrain is idle.
fn settle_alone(app: &mut App) {
    run_until(&mut [app], 20_000, |apps| idle(apps[0]));
}

/// Updates every app until each is idle with the server's last carve and
/// every client's requests are answered, then a few more frames for the
/// hash checks.
fn settle(apps: &mut [&mut App], answers: usize) {
    run_until(apps, 200_000, |apps| {
        let want = last_carve(apps[0]);
        let answered: usize = apps[1..]
            .iter()
            .map(|app| app.world().resource::<Seen>().results.len())
            .sum();
        answered == answers
            && apps
                .iter_mut()
                .all(|app| idle(app) && last_carve(app) == want)
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

fn assert_identical(server: &mut App, clients: &mut [(&str, &mut App)]) {
    let reference = state(server);
    for (name, app) in clients.iter_mut() {
        let peer = state(app);
        assert_eq!(peer.1, reference.1, "{name}: state hash");
        assert!(peer.0 == reference.0, "{name}: octree bytes differ");
        assert_eq!(stats(app).desyncs, 0, "{name}: no desync");
    }
}

/// Runs `app`'s `Update` alone (no packets in or out) until its terrain
/// is idle: its predictions are applied before anything from the server
/// arrives, and its requests leave at its next full update.
fn predict_offline(app: &mut App) {
    for _ in 0..20_000 {
        app.world_mut().run_schedule(Update);
        if idle(app) {
            return;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    panic!("the prediction was not applied");
}

fn blast(at: Vec3, radius: f32) -> CarveTool {
    CarveTool::dodecahedron(radius, at)
}

#[test]
fn a_predicted_carve_shows_before_the_server_runs_and_is_not_applied_again() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab(), net::unlimited());
    let mut a = predicting(addr, 1, 1, true);
    join(&mut [&mut server, &mut a]);
    let (before, _) = state(&mut a);
    let volume_before = terrain_of(&mut a).expect("terrain").1.volumes()[&1];

    request(
        &mut a,
        7,
        &blast(Vec3::new(5.0, 2.0, 5.0), 0.4),
        Edit::Subtract,
    );
    // The server is not updated: the crater shows from the prediction.
    settle_alone(&mut a);
    let (predicted, _) = state(&mut a);
    assert!(
        predicted != before,
        "the crater shows before the server runs"
    );
    let volume_after = terrain_of(&mut a).expect("terrain").1.volumes()[&1];
    assert!(volume_after < volume_before - 0.01, "rock was taken out");
    let shown = reports(&a);
    assert_eq!(shown.len(), 1, "one carve job: {shown:?}");
    assert!(shown[0].predicted.is_some() && shown[0].request.is_none());
    assert!(shown[0].cells > 0, "cell meshes were rebuilt");
    assert_eq!(last_carve(&mut a), None, "no server carve yet");

    settle(&mut [&mut server, &mut a], 1);
    assert_identical(&mut server, &mut [("a", &mut a)]);
    assert!(state(&mut a).0 == predicted, "the prediction was the carve");
    assert_eq!(last_carve(&mut a), Some(1), "the confirmed carve is seq 1");
    let s = stats(&a);
    println!("a: {s:?}");
    assert_eq!(s.predictions, 1);
    assert_eq!(s.predictions_confirmed, 1);
    assert_eq!(s.carves, 0, "the server's carve was not handed over again");
    assert_eq!((s.rollbacks, s.predictions_rolled_back), (0, 0));
    assert_eq!(reports(&a).len(), 1, "no second carve job");
    assert!(
        s.checks_passed > 0,
        "the prediction's hash passed the check"
    );
    let results = &a.world().resource::<Seen>().results;
    assert_eq!(results[0].outcome, Outcome::Applied { seq: 1 });
}

#[test]
fn another_carve_ordered_first_rolls_the_prediction_back() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab(), net::unlimited());
    let mut a = predicting(addr, 1, 1, true);
    let mut b = predicting(addr, 2, 2, false);
    join(&mut [&mut server, &mut a, &mut b]);
    // A heaps material where B blasts: the two orders differ.
    let heap = blast(Vec3::new(5.0, 2.1, 5.0), 0.4);
    let crater = blast(Vec3::new(5.2, 2.0, 5.0), 0.4);

    // B's request reaches the server first; A's prediction is in A's
    // octree before B's carve reaches A, and A's request reaches the
    // server after B's: A runs its `Update` alone (no packets in or out)
    // until the prediction is applied.
    let (before, _) = state(&mut a);
    request(&mut b, 1, &crater, Edit::Subtract);
    b.update();
    request(&mut a, 2, &heap, Edit::Add(2));
    predict_offline(&mut a);
    let (predicted, _) = state(&mut a);
    assert!(predicted != before, "the prediction is applied");
    run_until(&mut [&mut server], 20_000, |apps| {
        apps[0].world().resource::<NetServerStats>().accepted == 1
    });

    settle(&mut [&mut server, &mut a, &mut b], 2);
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    let results = &a.world().resource::<Seen>().results;
    assert_eq!(
        results[0].outcome,
        Outcome::Applied { seq: 2 },
        "B's came first"
    );
    let (end, _) = state(&mut a);
    assert!(end != predicted, "the server's carve changed the result");
    // The other order would have ended elsewhere: the roll back mattered.
    let mut other = slab();
    let grid = *other.quantization();
    for (tool, edit) in [(&heap, Edit::Add(2)), (&crater, Edit::Subtract)] {
        let tool = tool.to_grid(&grid).expect("on the grid");
        other.apply_now(&tool, edit).expect("applies");
    }
    assert!(
        other.octree().to_bytes() != end,
        "the carves do not commute"
    );

    let s = stats(&a);
    println!("a: {s:?}");
    assert_eq!(s.predictions, 1);
    assert_eq!((s.rollbacks, s.predictions_rolled_back), (1, 1));
    assert_eq!(s.predictions_confirmed, 1, "re-applied, then confirmed");
    assert_eq!(s.carves, 1, "B's carve was handed over");
    let undone = reports(&a)
        .iter()
        .filter(|r| r.edit.is_none() && r.predicted.is_some())
        .count();
    assert_eq!(undone, 1, "the prediction was undone once");
    assert_eq!(reports(&a).len(), 4, "predict, undo, B's carve, predict");
}

#[test]
fn a_refused_request_is_rolled_back() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    // One carve, then none: the client does not know the server's rate.
    let limits = NetLimits {
        carves_per_second: 1e-3,
        burst: 1.0,
        ..NetLimits::default()
    };
    let (mut server, addr) = server(slab(), limits);
    let mut a = predicting(addr, 1, 1, true);
    join(&mut [&mut server, &mut a]);
    let (before, _) = state(&mut a);
    request(
        &mut a,
        1,
        &blast(Vec3::new(3.0, 2.0, 3.0), 0.4),
        Edit::Subtract,
    );
    request(
        &mut a,
        2,
        &blast(Vec3::new(7.0, 2.0, 7.0), 0.4),
        Edit::Subtract,
    );
    settle_alone(&mut a);
    assert_eq!(reports(&a).len(), 2, "both predicted");

    settle(&mut [&mut server, &mut a], 2);
    assert_identical(&mut server, &mut [("a", &mut a)]);
    assert!(state(&mut a).0 != before, "the first carve stays");
    let results = &a.world().resource::<Seen>().results;
    assert!(
        results
            .iter()
            .any(|r| r.request == Some(2)
                && r.outcome == Outcome::Rejected(RejectReason::RateLimited)),
        "{results:?}"
    );
    let s = stats(&a);
    println!("a: {s:?}");
    assert_eq!((s.predictions, s.predictions_confirmed), (2, 1));
    assert_eq!(s.predictions_refused, 1);
    assert_eq!((s.rollbacks, s.predictions_rolled_back), (1, 1));
    assert_eq!(reports(&a).len(), 3, "two predictions and one undo");
}

#[test]
fn more_predictions_than_undo_steps_resync_from_a_snapshot() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab().with_max_undo(1), net::unlimited());
    let mut a = predicting(addr, 1, 1, true);
    let mut b = predicting(addr, 2, 1, false);
    join(&mut [&mut server, &mut a, &mut b]);
    request(
        &mut b,
        1,
        &blast(Vec3::new(5.0, 2.0, 5.0), 0.4),
        Edit::Subtract,
    );
    run_until(&mut [&mut server, &mut b], 20_000, |apps| {
        apps[0].world().resource::<NetServerStats>().accepted == 1
    });
    request(
        &mut a,
        2,
        &blast(Vec3::new(5.3, 2.0, 5.0), 0.4),
        Edit::Subtract,
    );
    request(
        &mut a,
        3,
        &blast(Vec3::new(4.7, 2.0, 5.0), 0.4),
        Edit::Add(2),
    );
    settle_alone(&mut a);
    settle(&mut [&mut server, &mut a, &mut b], 3);
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    let s = stats(&a);
    println!("a: {s:?}");
    assert_eq!(s.prediction_resyncs, 1);
    assert!(s.snapshots >= 2, "the snapshot came");
}

/// Two predicting clients send random carves, often in the same frames,
/// while the server runs only every few frames: every peer ends
/// bit-identical, no hash check fails.
#[test]
fn two_predicting_clients_end_identical() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    const CARVES: usize = 150;
    let (mut server, addr) = server(slab().with_max_undo(64), net::unlimited());
    let mut a = predicting(addr, 1, 1, true);
    let mut b = predicting(addr, 2, 3, true);
    join(&mut [&mut server, &mut a, &mut b]);
    let mut rng = Rng(4242);
    let mut sent = 0usize;
    let mut frame = 0u64;
    while sent < CARVES {
        for (n, app) in [&mut a, &mut b].into_iter().enumerate() {
            for _ in 0..rng.next() % 3 {
                if sent < CARVES {
                    let (tool, edit) = random_carve(&mut rng);
                    request(app, (sent as u64) << 1 | n as u64, &tool, edit);
                    sent += 1;
                }
            }
        }
        if frame.is_multiple_of(1 + rng.next() % 3) {
            server.update();
        }
        a.update();
        b.update();
        frame += 1;
    }
    settle(&mut [&mut server, &mut a, &mut b], CARVES);
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    let (sa, sb) = (stats(&a), stats(&b));
    println!("a: {sa:?}\nb: {sb:?}");
    let accepted = server.world().resource::<NetServerStats>().accepted;
    assert_eq!(accepted as usize, CARVES);
    assert_eq!(sa.predictions + sb.predictions, CARVES as u64);
    for s in [&sa, &sb] {
        assert_eq!(s.prediction_resyncs, 0);
        assert!(s.predictions_confirmed > 0 && s.rollbacks > 0);
        assert!(s.checks_passed > 0);
    }
    assert_eq!(last_carve(&mut server), Some(CARVES as u64));
}

/// A prediction that cuts a piece loose, rolled back: the undo puts the
/// solid back in the octree and the client despawns the body; applied
/// again, the prediction cuts it loose anew: one body, as on B.
#[test]
fn a_rolled_back_prediction_takes_its_debris_body_back() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = server(slab(), net::unlimited());
    let mut a = predicting(addr, 1, 1, true);
    let mut b = predicting(addr, 2, 1, false);
    join(&mut [&mut server, &mut a, &mut b]);
    // A lump of dirt in the air above the slab: loose at once.
    let lump = blast(Vec3::new(5.0, 3.0, 5.0), 0.3);
    request(
        &mut b,
        1,
        &blast(Vec3::new(2.0, 2.0, 2.0), 0.4),
        Edit::Subtract,
    );
    b.update();
    request(&mut a, 2, &lump, Edit::Add(2));
    predict_offline(&mut a);
    let bodies = |app: &mut App| {
        let world = app.world_mut();
        world
            .query::<&bevy_chisel::terrain::TerrainDebris>()
            .iter(world)
            .count()
    };
    assert_eq!(bodies(&mut a), 1, "the prediction cut the lump loose");
    settle(&mut [&mut server, &mut a, &mut b], 2);
    assert_identical(&mut server, &mut [("a", &mut a), ("b", &mut b)]);
    let s = stats(&a);
    assert_eq!((s.rollbacks, s.predictions_confirmed), (1, 1));
    assert_eq!(bodies(&mut a), 1, "the first body went with the undo");
    assert_eq!(bodies(&mut b), 1, "B cut it loose once");
}

/// Frames and wall time from a request to its crater being in place on
/// the requesting client (its first carve report), with and without
/// prediction, frames paced at 60 Hz, with the server updated every
/// frame, every 4th and every 8th frame (a stand-in for network latency:
/// about 0, 50 and 117 ms). Prints the figures:
/// `cargo test --release -p bevy_chisel --all-features --test it -- \
/// net_predict::latency --nocapture`.
#[test]
fn latency_with_and_without_prediction() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    const CARVES: usize = 8;
    const FRAME: std::time::Duration = std::time::Duration::from_micros(16_667);
    let mut figures = Vec::new();
    for server_every in [1usize, 4, 8] {
        for predict in [false, true] {
            let (mut server, addr) = server(slab(), net::unlimited());
            let mut a = predicting(addr, 1, 1, predict);
            join(&mut [&mut server, &mut a]);
            let (mut frames, mut wall) = (0usize, 0.0f64);
            for i in 0..CARVES {
                let shown = reports(&a).len();
                let at = Vec3::new(1.0 + i as f32, 2.0, 5.0);
                request(&mut a, i as u64, &blast(at, 0.4), Edit::Subtract);
                let start = std::time::Instant::now();
                let mut frame = 0usize;
                while reports(&a).len() == shown {
                    // Frames paced at 60 Hz, as a game's.
                    let frame_start = std::time::Instant::now();
                    frame += 1;
                    a.update();
                    if frame.is_multiple_of(server_every) {
                        server.update();
                    }
                    assert!(frame < 10_000, "the carve never showed");
                    let left = FRAME.saturating_sub(frame_start.elapsed());
                    std::thread::sleep(left);
                }
                frames += frame;
                wall += start.elapsed().as_secs_f64() * 1e3;
                settle(&mut [&mut server, &mut a], i + 1);
            }
            let (mean_frames, mean_ms) = (frames as f64 / CARVES as f64, wall / CARVES as f64);
            println!(
                "server every {server_every} frame(s), prediction {}: {mean_frames:.1} frames, \
                 {mean_ms:.2} ms from request to crater",
                if predict { "on " } else { "off" }
            );
            assert_identical(&mut server, &mut [("a", &mut a)]);
            figures.push((server_every, predict, mean_frames));
        }
    }
    for pair in figures.chunks(2) {
        assert!(
            pair[1].2 < pair[0].2,
            "prediction shows the crater in fewer frames: {pair:?}"
        );
    }
}
