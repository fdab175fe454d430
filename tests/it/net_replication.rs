//! One server and three clients over renet's netcode UDP transport on
//! 127.0.0.1: two clients send 1,000 random carves (many in the same frame
//! as the other's), a third joins halfway through from a snapshot, one
//! client's terrain is damaged locally and resyncs, and at the end all four
//! octrees are bit-identical with equal state hashes.

use crate::{ONE_APP_AT_A_TIME, net};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::StateHash;
use bevy_chisel::net::{NetClientStats, NetLimits, NetServerStats, Outcome};
use bevy_chisel::terrain::{Carve, CarveTool};
use net::{Rng, Seen, client, random_carve, request, run_until, server, slab, terrain_of};

const CARVES: usize = 1000;
/// Carves each of the two clients sends per frame.
const PER_FRAME: usize = 4;

/// The sequence number of the last carve in the app's terrain.
fn last_carve(app: &mut App) -> Option<u64> {
    terrain_of(app).and_then(|(_, t)| t.last_request())
}

fn idle(app: &mut App) -> bool {
    terrain_of(app).is_some_and(|(_, t)| t.is_idle())
}

fn snapshot_of(app: &mut App) -> (u64, Vec<u8>, u64) {
    let (_, terrain) = terrain_of(app).expect("terrain");
    let from_scratch = StateHash::of(terrain.octree()).value();
    (
        terrain.state_hash(),
        terrain.octree().to_bytes(),
        from_scratch,
    )
}

#[test]
fn four_peers_end_with_identical_octrees() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = net::unlimited();
    let (mut server, addr) = server(slab(), limits);
    // Different worker thread counts: the results must not depend on them.
    let mut a = client(addr, 1, 1);
    let mut b = client(addr, 2, 3);
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        apps[1..].iter_mut().all(|app| idle(app))
    });

    let mut rng = Rng(2026);
    let mut sent = 0usize;
    let mut c: Option<App> = None;
    let mut damaged = false;
    let mut frames = 0usize;
    while sent < CARVES {
        // Both clients send in the same frame: the server orders them.
        for (n, app) in [&mut a, &mut b].into_iter().enumerate() {
            for _ in 0..PER_FRAME.min(CARVES - sent) {
                let (tool, edit) = random_carve(&mut rng);
                request(app, (sent as u64) << 1 | n as u64, &tool, edit);
                sent += 1;
            }
        }
        if sent >= CARVES / 2 && c.is_none() {
            c = Some(client(addr, 3, 2));
        }
        if sent >= CARVES / 4 && !damaged {
            // A local edit the server never saw: b's next hash check fails.
            damaged = true;
            let (entity, _) = terrain_of(&mut b).expect("terrain");
            b.world_mut().write_message(Carve {
                terrain: entity,
                tool: CarveTool::dodecahedron(0.5, Vec3::new(5.0, 2.0, 5.0)),
                edit: bevy_chisel::bsp::octree::Edit::Subtract,
            });
        }
        let mut apps: Vec<&mut App> = vec![&mut server, &mut a, &mut b];
        if let Some(c) = c.as_mut() {
            apps.push(c);
        }
        for app in apps {
            app.update();
        }
        frames += 1;
    }
    let mut c = c.expect("the third client joined");
    let answered = |app: &App| app.world().resource::<Seen>().results.len();
    let settle = run_until(
        &mut [&mut server, &mut a, &mut b, &mut c],
        200_000,
        |apps| {
            let [server, a, b, c] = apps else {
                return false;
            };
            let want = last_carve(server);
            answered(a) + answered(b) == CARVES
                && [&mut **server, &mut **a, &mut **b, &mut **c]
                    .into_iter()
                    .all(|app| idle(app) && last_carve(app) == want)
        },
    );
    // A few more frames: hash checks of the last carves go through.
    for _ in 0..50 {
        for app in [&mut server, &mut a, &mut b, &mut c] {
            app.update();
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    println!("{frames} sending frames, {settle} frames to settle");

    let applied = [&a, &b]
        .iter()
        .flat_map(|app| app.world().resource::<Seen>().results.iter())
        .filter(|r| matches!(r.outcome, Outcome::Applied { .. }))
        .count();
    let (_, server_terrain) = terrain_of(&mut server).expect("server terrain");
    let journal = server_terrain.journal().len();
    println!("{applied} of {CARVES} carves applied; {journal} in the server's journal");
    assert_eq!(applied, journal, "every applied carve is in the journal");
    assert!(applied >= CARVES * 9 / 10, "most random carves apply");

    let reference = snapshot_of(&mut server);
    assert_eq!(
        reference.0, reference.2,
        "the updated hash is the hash from scratch"
    );
    for (name, app) in [("a", &mut a), ("b", &mut b), ("c", &mut c)] {
        let peer = snapshot_of(app);
        assert_eq!(
            peer.0, peer.2,
            "{name}: updated hash equals the hash from scratch"
        );
        assert_eq!(peer.0, reference.0, "{name}: state hash");
        assert!(peer.1 == reference.1, "{name}: octree bytes differ");
    }
    let stats = |app: &App| app.world().resource::<NetClientStats>().clone();
    let (sa, sb, sc) = (stats(&a), stats(&b), stats(&c));
    println!("client stats: a {sa:?}, b {sb:?}, c {sc:?}");
    assert_eq!(sa.desyncs, 0);
    assert!(sb.desyncs >= 1, "the damaged client noticed");
    assert!(sb.snapshots >= 2, "and resynced from a snapshot");
    assert!(sa.checks_passed > 0 && sc.checks_passed > 0);
    let server_stats = server.world().resource::<NetServerStats>().clone();
    println!("server stats: {server_stats:?}");
    assert_eq!(server_stats.accepted as usize, CARVES);
    let c_sync = &c.world().resource::<Seen>().synced;
    assert!(c_sync[0].seq > 0, "the late client joined after carves");
}

/// A joining client gets the rules a carve depends on, not only the
/// octree: the server's custom debris anchors and limits and its
/// materials. Without them the client's next carve could cut loose a
/// different piece than the server's.
#[test]
fn a_late_client_gets_the_debris_rules_and_materials() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    use bevy_chisel::bsp::octree::{Anchors, CellBox, CubeSide, DebrisConfig};
    let rules = DebrisConfig {
        anchors: Anchors {
            sides: vec![
                CubeSide::BOTTOM,
                CubeSide {
                    axis: 0,
                    upper: false,
                },
            ],
            boxes: vec![CellBox {
                min: [400, 150, 400],
                max: [600, 200, 600],
            }],
        },
        max_volume: Some(5_000_000_000),
        max_cells: Some(300),
    };
    let terrain = slab().with_labels([7]).with_debris(Some(rules.clone()));
    let (mut server, addr) = server(terrain, NetLimits::default());
    let mut a = client(addr, 1, 1);
    run_until(&mut [&mut server, &mut a], 20_000, |apps| idle(apps[1]));
    let mut rng = Rng(7);
    for request_id in 0..20 {
        let (tool, edit) = random_carve(&mut rng);
        request(&mut a, request_id, &tool, edit);
    }
    run_until(&mut [&mut server, &mut a], 100_000, |apps| {
        apps[1].world().resource::<Seen>().results.len() == 20 && idle(apps[1])
    });
    let want = last_carve(&mut server);
    assert!(
        want.is_some_and(|seq| seq > 0),
        "carves were applied before the join"
    );

    let mut late = client(addr, 2, 2);
    run_until(&mut [&mut server, &mut late], 100_000, |apps| {
        idle(apps[1]) && last_carve(apps[1]) == want
    });
    let (_, joined) = terrain_of(&mut late).expect("the late client has the terrain");
    assert_eq!(joined.debris(), Some(&rules));
    assert_eq!(
        joined.labels().iter().copied().collect::<Vec<_>>(),
        vec![1, 2, 7]
    );
    assert!(joined.journal().is_empty(), "a snapshot carries no journal");
    let (late_hash, late_bytes, _) = snapshot_of(&mut late);
    let (hash, bytes, _) = snapshot_of(&mut server);
    assert_eq!(late_hash, hash);
    assert!(late_bytes == bytes, "the joined octree is the server's");
}
