//! A streamed world carved over the network: one server (no focus: it
//! holds only the chunks carves reach and stores the edited ones) and
//! three clients with foci in different places, on 127.0.0.1. Two clients
//! send random world carves, many across chunk borders; a third joins
//! halfway through from the world's snapshot while carves go on; one client's chunk is
//! damaged locally and the world resyncs. At the end every chunk edited
//! anywhere is held by every peer, bit-identical (octree bytes and state
//! hashes), and the server's chunks are their journals replayed on the
//! source's chunks. Hostile world requests are refused with their reasons
//! while an honest client goes on.

use std::collections::{BTreeMap, BTreeSet};

use crate::net::world::build_deferred;
use crate::net_worlds::{
    edited_chunks, edited_terrains, streamed_world as world, world_settled as settled, world_tool,
};
use crate::{ONE_APP_AT_A_TIME, net};
use bevy::ecs::message::Messages;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::net::{
    ClientPacket, ClientRequest, NetClientStats, NetLimits, NetServerStats, Outcome, RejectReason,
    WireShape, world_state_hash,
};
use bevy_chisel::terrain::{Carve, CarveRejected, CarveTool, ChunkCoord, TerrainError, WorldCarve};
use net::world::world_hash;
use net::{Rng, Seen, WorldsSeen, request_world, run_until, world_client, world_of, world_server};

const CARVES: usize = 160;
/// Carves each of the two clients sends per frame.
const PER_FRAME: usize = 2;

/// A random blast or heap near the surface over chunks (0..3, 0..3); one in
/// three is centred on a chunk border.
fn random_world_carve(rng: &mut Rng) -> (CarveTool, Edit) {
    let mut centre = Vec3::new(
        rng.range(2.0, 94.0),
        rng.range(8.0, 20.0),
        rng.range(2.0, 94.0),
    );
    if rng.next().is_multiple_of(3) {
        centre.x = 32.0 * (1 + rng.next() % 2) as f32;
    }
    let tool = CarveTool::dodecahedron(rng.range(1.5, 5.0), centre);
    let edit = if rng.next().is_multiple_of(5) {
        Edit::Add(2)
    } else {
        Edit::Subtract
    };
    (tool, edit)
}

fn synced(app: &App) -> bool {
    !app.world().resource::<WorldsSeen>().synced.is_empty()
}

fn peer_hash(app: &mut App) -> u64 {
    world_state_hash(edited_chunks(app).into_iter().map(|(c, (_, h))| (c, h)))
}

fn live(app: &mut App) -> BTreeSet<ChunkCoord> {
    let (_, world) = world_of(app);
    world.live_chunks().map(|(c, _)| c).collect()
}

/// Runs until every peer is settled and holds the same edited chunks as
/// the first (by world hash), then a few frames more for the hash checks.
/// The clients build the far chunks whose carves they deferred.
fn converge(apps: &mut [&mut App], done: impl Fn(&mut [&mut App]) -> bool) -> usize {
    let frames = run_until(apps, 200_000, |apps| {
        apps.iter_mut().for_each(|app| build_deferred(app));
        if !done(apps) || !apps.iter_mut().all(|app| settled(app)) {
            return false;
        }
        let want = peer_hash(apps[0]);
        apps[1..].iter_mut().all(|app| peer_hash(app) == want)
    });
    for _ in 0..40 {
        for app in apps.iter_mut() {
            app.update();
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    frames
}

#[test]
fn world_carves_leave_every_held_chunk_identical_on_every_peer() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = net::unlimited();
    let (mut server, addr) = world_server(world(), limits);
    let mut a = world_client(addr, 1, world(), Vec3::new(16.0, 30.0, 16.0));
    let mut b = world_client(addr, 2, world(), Vec3::new(80.0, 30.0, 48.0));
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        apps[1..].iter_mut().all(|app| synced(app) && settled(app))
    });

    let answered = |app: &App| app.world().resource::<Seen>().results.len();
    let mut rng = Rng(2027);
    let mut sent = 0usize;
    let mut c: Option<App> = None;
    let mut damaged = false;
    while sent < CARVES {
        // Both clients send in the same frame: the server orders them.
        for (n, app) in [&mut a, &mut b].into_iter().enumerate() {
            for _ in 0..PER_FRAME {
                let (tool, edit) = random_world_carve(&mut rng);
                request_world(app, (sent as u64) << 1 | n as u64, &tool, edit);
                sent += 1;
            }
        }
        if sent >= CARVES / 2 && c.is_none() {
            // Once the server applied the first half, so that the late
            // client gets edited chunks; it connects while carves go on.
            run_until(&mut [&mut server, &mut a, &mut b], 100_000, |apps| {
                answered(&*apps[1]) + answered(&*apps[2]) == sent && settled(apps[0])
            });
            c = Some(world_client(addr, 3, world(), Vec3::new(48.0, 30.0, 80.0)));
        }
        if sent >= CARVES / 4 && !damaged {
            // A local edit the server never saw, in a chunk later carves
            // reach: b's world hash stops matching.
            let (_, world) = world_of(&mut b);
            if let Some(chunk) = world.chunk_entity(ChunkCoord { x: 2, z: 1 }) {
                b.world_mut().write_message(Carve {
                    terrain: chunk,
                    tool: CarveTool::dodecahedron(4.0, Vec3::new(80.0, 14.0, 48.0)),
                    edit: Edit::Subtract,
                });
                damaged = true;
            }
        }
        let mut apps: Vec<&mut App> = vec![&mut server, &mut a, &mut b];
        if let Some(c) = c.as_mut() {
            apps.push(c);
        }
        for app in apps {
            app.update();
        }
        std::thread::sleep(std::time::Duration::from_micros(500));
    }
    assert!(damaged, "b's chunk (2, 1) was live to damage");
    let mut c = c.expect("the third client joined");
    let frames = converge(&mut [&mut server, &mut a, &mut b, &mut c], |apps| {
        answered(&*apps[1]) + answered(&*apps[2]) == CARVES
    });
    println!("{frames} frames to converge");

    // Every chunk edited anywhere is on every peer, bit-identical.
    let reference = edited_chunks(&mut server);
    assert!(
        reference.len() >= 6,
        "carves edited {} chunks",
        reference.len()
    );
    for (name, app) in [("a", &mut a), ("b", &mut b), ("c", &mut c)] {
        let chunks = edited_chunks(app);
        assert_eq!(
            chunks.keys().collect::<Vec<_>>(),
            reference.keys().collect::<Vec<_>>(),
            "{name}: edited chunks"
        );
        for (coord, (bytes, hash)) in &reference {
            let (peer_bytes, peer_hash) = &chunks[coord];
            assert_eq!(peer_hash, hash, "{name}: state hash of chunk {coord:?}");
            assert!(
                peer_bytes == bytes,
                "{name}: octree of chunk {coord:?} differs"
            );
        }
    }
    // Peers held different live chunks around their own foci.
    assert_ne!(live(&mut a), live(&mut b));
    assert!(
        live(&mut server).is_empty(),
        "the server keeps no live chunk"
    );

    // The server's chunks are the source's chunks with their journals
    // replayed (an independent reference), and carves across borders
    // reached several chunks.
    let (_, server_world) = world_of(&mut server);
    // Debris across chunk borders is the server's to decide; a chunk that
    // lost a part of such a piece is no longer its journal alone.
    assert!(server_world.debris_across_borders());
    let detached_across = server_world.stats().detached_across;
    let generate = |coord| server_world.generate_chunk(coord).expect("chunk builds");
    let mut generated = BTreeMap::new();
    for coord in reference.keys() {
        generated.insert(*coord, generate(*coord));
    }
    let mut chunk_carves = 0;
    let mut not_replayed = Vec::new();
    for (coord, terrain) in edited_terrains(&mut server) {
        let mut replay = generated.remove(&coord).expect("generated");
        for entry in terrain.journal() {
            replay
                .apply_now(&entry.tool, entry.edit)
                .expect("the journal replays");
        }
        chunk_carves += terrain.journal().len();
        if replay.octree().to_bytes() != reference[&coord].0 {
            not_replayed.push(coord);
        }
    }
    println!("{detached_across} pieces across borders; chunks not replayed: {not_replayed:?}");
    assert!(
        not_replayed.is_empty() || detached_across > 0,
        "chunks {not_replayed:?} are not their journals replayed"
    );
    let applied = [&a, &b]
        .iter()
        .flat_map(|app| app.world().resource::<Seen>().results.iter())
        .filter(|r| matches!(r.outcome, Outcome::Applied { .. }))
        .count();
    println!("{applied} of {CARVES} world carves applied, {chunk_carves} chunk carves");
    assert!(applied >= CARVES * 9 / 10, "most random carves apply");
    assert!(chunk_carves > applied, "some carves reached several chunks");
    let server_stats = server.world().resource::<NetServerStats>().clone();
    assert_eq!(server_stats.accepted as usize, CARVES);

    let stats = |app: &App| app.world().resource::<NetClientStats>().clone();
    let (sa, sb, sc) = (stats(&a), stats(&b), stats(&c));
    println!("client stats: a {sa:?}, b {sb:?}, c {sc:?}");
    assert_eq!(sa.desyncs, 0);
    assert_eq!(sc.desyncs, 0);
    assert!(sb.desyncs >= 1, "the damaged client noticed");
    let noticed = &b.world().resource::<WorldsSeen>().desynced[0];
    assert_eq!(
        noticed.chunk,
        ChunkCoord { x: 2, z: 1 },
        "the check of the damaged chunk failed: {noticed:?}"
    );
    assert_ne!(noticed.local, Some(noticed.server));
    assert!(sb.snapshots >= 2, "and resynced from the world's snapshot");
    assert!(sa.checks_passed > 0 && sc.checks_passed > 0);
    let joined = &c.world().resource::<WorldsSeen>().synced[0];
    assert!(
        joined.seq > 0 && joined.chunks > 0,
        "the late client joined after carves: {joined:?}"
    );
}

#[test]
fn hostile_world_requests_are_refused_and_honest_carves_go_on() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = NetLimits {
        max_world_chunk: 4,
        ..NetLimits::default()
    };
    let (mut server, addr) = world_server(world(), limits);
    let mut honest = world_client(addr, 1, world(), Vec3::new(16.0, 30.0, 16.0));
    let mut hostile = world_client(addr, 2, world(), Vec3::new(48.0, 30.0, 48.0));
    run_until(
        &mut [&mut server, &mut honest, &mut hostile],
        20_000,
        |apps| apps[1..].iter_mut().all(|app| synced(app) && settled(app)),
    );
    let dodecahedron = |radius: f32| WireShape::Dodecahedron { radius };
    let hostile_requests = [
        (
            world_tool(dodecahedron(2.0), [f32::NAN, 12.0, 12.0]),
            1,
            Edit::Subtract,
        ),
        (
            world_tool(dodecahedron(2.0), [336.0, 12.0, 16.0]),
            1,
            Edit::Subtract,
        ),
        (
            world_tool(dodecahedron(2.0), [16.0, 12.0, 16.0]),
            99,
            Edit::Subtract,
        ),
        (
            world_tool(dodecahedron(100.0), [16.0, 12.0, 16.0]),
            1,
            Edit::Subtract,
        ),
        (
            world_tool(dodecahedron(2.0), [16.0, 500.0, 16.0]),
            1,
            Edit::Subtract,
        ),
        (
            world_tool(dodecahedron(2.0), [16.0, 12.0, 16.0]),
            1,
            Edit::Add(9),
        ),
    ];
    let mut rng = Rng(5);
    for (n, (tool, world, edit)) in hostile_requests.into_iter().enumerate() {
        hostile
            .world_mut()
            .write_message(ClientPacket::Request(ClientRequest::CarveWorld {
                request: n as u64,
                world,
                tool,
                edit,
            }));
        let (tool, edit) = random_world_carve(&mut rng);
        request_world(&mut honest, n as u64, &tool, edit);
        for app in [&mut server, &mut honest, &mut hostile] {
            app.update();
        }
    }
    let answered = |app: &App| app.world().resource::<Seen>().results.len();
    converge(&mut [&mut server, &mut honest, &mut hostile], |apps| {
        answered(&*apps[1]) == 6 && answered(&*apps[2]) == 6
    });

    let mut outcomes: Vec<(u64, Outcome)> = hostile
        .world()
        .resource::<Seen>()
        .results
        .iter()
        .map(|r| (r.request.expect("request id"), r.outcome.clone()))
        .collect();
    outcomes.sort_by_key(|(request, _)| *request);
    let reason = |n: usize| match &outcomes[n].1 {
        Outcome::Rejected(reason) => reason.clone(),
        other => panic!("request {n} was not refused: {other:?}"),
    };
    println!("{outcomes:?}");
    assert!(matches!(reason(0), RejectReason::Invalid(_)), "NaN");
    assert_eq!(
        reason(1),
        RejectReason::OutsideWorld {
            chunk: [10, 0],
            limit: 4
        }
    );
    assert_eq!(reason(2), RejectReason::UnknownWorld(99));
    assert!(matches!(reason(3), RejectReason::TooLarge { .. }));
    assert!(
        matches!(reason(4), RejectReason::Invalid(ref why) if why.contains("outside")),
        "a tool above every chunk: {:?}",
        reason(4)
    );
    assert!(
        matches!(reason(5), RejectReason::Invalid(ref why) if why.contains('9')),
        "an unknown material: {:?}",
        reason(5)
    );
    let honest_results = &honest.world().resource::<Seen>().results;
    let applied = honest_results
        .iter()
        .filter(|r| matches!(r.outcome, Outcome::Applied { .. }))
        .count();
    assert!(applied >= 5, "the honest carves apply: {honest_results:?}");
    let reference = edited_chunks(&mut server);
    assert!(!reference.is_empty());
    for app in [&mut honest, &mut hostile] {
        assert!(edited_chunks(app) == reference, "a client's chunks differ");
    }
}

#[test]
fn a_local_world_carve_on_a_networked_world_is_refused() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = world_server(world(), net::unlimited());
    let mut client = world_client(addr, 1, world(), Vec3::new(16.0, 30.0, 16.0));
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        synced(apps[1]) && settled(apps[1])
    });
    let before = [world_hash(&mut server), world_hash(&mut client)];
    // Outside the server's order on either side: refused, nothing carved.
    for app in [&mut server, &mut client] {
        let (world, _) = world_of(app);
        app.world_mut().write_message(WorldCarve {
            world,
            tool: CarveTool::dodecahedron(3.0, Vec3::new(16.0, 14.0, 16.0)),
            edit: Edit::Subtract,
        });
        app.update();
        let messages = app.world().resource::<Messages<CarveRejected>>();
        let refused = (messages.get_cursor().read(messages))
            .filter(|r| r.terrain == world && matches!(r.error, TerrainError::NetworkedWorld))
            .count();
        assert_eq!(refused, 1, "the local world carve is refused");
    }
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        apps.iter_mut().all(|app| settled(app))
    });
    assert_eq!([world_hash(&mut server), world_hash(&mut client)], before);
    let stats = client.world().resource::<NetClientStats>();
    assert_eq!(stats.desyncs, 0);
}
