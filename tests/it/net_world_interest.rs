//! A client spends nothing on world carves far from its focus: one server
//! (no focus) and one client whose focus is far from where the carves
//! land. The client builds none of those chunks while they are far (their
//! carves wait, deferred, and their chunk checks wait too, no desync);
//! once its focus moves there the chunks stream in with every carve
//! applied in order, their octrees and state hashes exactly the
//! server's, and the waiting checks pass. A far chunk with as many
//! carves waiting as the world allows is built in the background, carved,
//! checked and stored again. A detach across chunk borders far away builds
//! the chunks it names, and the same piece falls as on the server.

use std::collections::BTreeSet;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::net::NetClientStats;
use bevy_chisel::terrain::{CarveTool, ChunkCoord, WorldChunk};

use crate::ONE_APP_AT_A_TIME;
use crate::net::world::{build_deferred, chunk_builds, edited_chunks, move_focus};
use crate::net::{
    Seen, WorldsSeen, request_world, run_until, unlimited, world_client, world_of, world_server,
};
use crate::net_world_debris::{Fallen, box_volume, cuboid, fallen, record_fallen};
use crate::net_worlds::{streamed_world as world, world_settled as settled};

/// The client's focus: over chunk (0, 0), 40 m (the unload radius) from
/// nothing the carves reach.
const HOME: Vec3 = Vec3::new(16.0, 30.0, 16.0);

const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// Carves around chunk (6, 0), 176 m from home: inside chunks (6, 0) and
/// (6, 1), and over the border of (6, 0) and (7, 0); each with the chunks
/// it reaches.
fn far_carves() -> Vec<(CarveTool, Edit, Vec<ChunkCoord>)> {
    let blast = |x: f32, z: f32, r: f32| CarveTool::dodecahedron(r, Vec3::new(x, 12.0, z));
    vec![
        (blast(200.0, 10.0, 3.0), Edit::Subtract, vec![at(6, 0)]),
        (blast(205.0, 12.0, 3.5), Edit::Subtract, vec![at(6, 0)]),
        (
            blast(224.0, 16.0, 4.0),
            Edit::Subtract,
            vec![at(6, 0), at(7, 0)],
        ),
        (blast(210.0, 48.0, 3.0), Edit::Subtract, vec![at(6, 1)]),
        (blast(203.0, 11.0, 2.0), Edit::Add(2), vec![at(6, 0)]),
        (
            blast(226.0, 20.0, 3.0),
            Edit::Subtract,
            vec![at(6, 0), at(7, 0)],
        ),
        (blast(212.0, 50.0, 2.5), Edit::Subtract, vec![at(6, 1)]),
    ]
}

fn stats(app: &App) -> NetClientStats {
    app.world().resource::<NetClientStats>().clone()
}

fn answered(app: &App) -> usize {
    app.world().resource::<Seen>().results.len()
}

/// The chunks of the app's world that have a terrain entity.
fn chunk_entities(app: &mut App) -> BTreeSet<ChunkCoord> {
    let ecs = app.world_mut();
    let mut chunks = ecs.query::<&WorldChunk>();
    chunks.iter(ecs).map(|c| c.coord).collect()
}

/// A server and a client at [`HOME`] (its world `client_world`), the
/// client synced and settled; its chunk builds so far.
fn start(client_world: bevy_chisel::terrain::TerrainWorld) -> (App, App, u64) {
    let (mut server, addr) = world_server(world(), unlimited());
    let mut client = world_client(addr, 1, client_world, HOME);
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        let synced = !apps[1].world().resource::<WorldsSeen>().synced.is_empty();
        synced && world_of(apps[1]).1.live_chunks().count() > 0 && settled(apps[1])
    });
    // The snapshot keeps the chunks already streamed in, so the world can
    // be settled before all around the focus are: a missing one starts
    // building within a frame, so settled for 20 frames in a row is done.
    let mut calm = 0;
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        calm = if settled(apps[1]) { calm + 1 } else { 0 };
        calm >= 20
    });
    let builds = chunk_builds(&mut client);
    assert!(builds > 0, "the client streamed in the chunks around it");
    (server, client, builds)
}

/// Sends `carves` from the client, one a frame, and runs until each is
/// answered, applied, and the server is settled.
fn send(server: &mut App, client: &mut App, first: u64, carves: &[(CarveTool, Edit)]) {
    let before = answered(client);
    for (n, (tool, edit)) in carves.iter().enumerate() {
        request_world(client, first + n as u64, tool, *edit);
        server.update();
        client.update();
    }
    run_until(&mut [server, client], 50_000, |apps| {
        answered(apps[1]) == before + carves.len() && settled(apps[0])
    });
    let seen = &client.world().resource::<Seen>().results[before..];
    assert!(
        (seen.iter()).all(|r| matches!(r.outcome, bevy_chisel::net::Outcome::Applied { .. })),
        "every far carve applies on the server: {seen:?}"
    );
}

/// The server's edited chunks `coords` against the client's: octree bytes
/// and state hashes identical.
fn assert_as_server(server: &mut App, client: &mut App, coords: &BTreeSet<ChunkCoord>) {
    let reference = edited_chunks(server);
    let mine = edited_chunks(client);
    for coord in coords {
        let (bytes, hash) = reference.get(coord).expect("the server edited the chunk");
        let (my_bytes, my_hash) = mine.get(coord).expect("the client holds the chunk");
        assert_eq!(my_hash, hash, "state hash of chunk {coord:?}");
        assert!(my_bytes == bytes, "octree of chunk {coord:?} differs");
    }
}

#[test]
fn far_carves_wait_unbuilt_and_land_identical_when_the_focus_comes() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, mut client, builds) = start(world());
    let carves = far_carves();
    let far: BTreeSet<ChunkCoord> = carves.iter().flat_map(|c| c.2.clone()).collect();
    let sent: Vec<(CarveTool, Edit)> = carves.iter().map(|c| (c.0.clone(), c.1)).collect();
    send(&mut server, &mut client, 1, &sent);
    // Until the server's checks name every far chunk.
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        stats(apps[1]).world_checks_waiting as usize >= far.len()
    });
    for _ in 0..20 {
        server.update();
        client.update();
        std::thread::sleep(std::time::Duration::from_millis(5));
    }

    // (i) Nothing built for them: their carves and checks wait.
    assert_eq!(
        chunk_builds(&mut client),
        builds,
        "no chunk built for far carves"
    );
    let (_, world) = world_of(&mut client);
    assert_eq!(world.deferred_chunks().collect::<BTreeSet<_>>(), far);
    for coord in &far {
        let routed = carves.iter().filter(|c| c.2.contains(coord)).count();
        assert_eq!(world.waiting_carves(*coord), routed, "chunk {coord:?}");
        assert_eq!(world.chunk_entity(*coord), None);
    }
    assert!(
        settled(&mut client),
        "deferred carves leave the world settled"
    );
    assert!(chunk_entities(&mut client).is_disjoint(&far));
    assert!(edited_chunks(&mut client).is_empty());
    let waiting = stats(&client);
    assert_eq!(
        waiting.world_checks_waiting as usize,
        far.len(),
        "{waiting:?}"
    );
    assert_eq!(waiting.desyncs, 0);
    assert!(client.world().resource::<WorldsSeen>().desynced.is_empty());

    // (ii) The focus comes: the chunks stream in with every carve.
    move_focus(&mut client, Vec3::new(208.0, 30.0, 16.0));
    run_until(&mut [&mut server, &mut client], 50_000, |apps| {
        let (_, world) = world_of(apps[1]);
        let live = far.iter().all(|c| world.chunk_entity(*c).is_some());
        live && settled(apps[1]) && stats(apps[1]).world_checks_waiting == 0
    });
    let (_, world) = world_of(&mut client);
    assert_eq!(world.deferred_chunks().count(), 0);
    assert_as_server(&mut server, &mut client, &far);
    let after = stats(&client);
    println!("checks before the focus came: {waiting:?}, after: {after:?}");
    assert!(
        after.checks_passed >= waiting.checks_passed + far.len() as u64,
        "each far chunk's waiting check passed: {after:?}"
    );
    assert_eq!(after.desyncs, 0);
    assert!(client.world().resource::<WorldsSeen>().desynced.is_empty());
}

#[test]
fn a_far_chunk_with_the_most_carves_waiting_is_built_and_checked() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    const MOST: usize = 4;
    let (mut server, mut client, builds) = start(world().with_max_deferred_carves(MOST));
    assert_eq!(world_of(&mut client).1.max_deferred_carves(), MOST);
    let inside: Vec<(CarveTool, Edit)> = (0..=MOST)
        .map(|k| {
            let centre = Vec3::new(198.0 + 4.0 * k as f32, 12.0, 12.0 + 2.0 * k as f32);
            (CarveTool::dodecahedron(2.5, centre), Edit::Subtract)
        })
        .collect();
    let chunk = at(6, 0);
    let only = BTreeSet::from([chunk]);

    // One carve fewer than the most: deferred.
    send(&mut server, &mut client, 1, &inside[..MOST - 1]);
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        stats(apps[1]).world_checks_waiting == 1
    });
    assert_eq!(chunk_builds(&mut client), builds);
    assert_eq!(world_of(&mut client).1.waiting_carves(chunk), MOST - 1);
    let before = stats(&client);

    // The most: built in the background, carved, checked, stored again.
    send(&mut server, &mut client, 10, &inside[MOST - 1..MOST]);
    run_until(&mut [&mut server, &mut client], 50_000, |apps| {
        let (_, world) = world_of(apps[1]);
        let stored = world.stored_chunks().any(|c| c == chunk);
        stored && settled(apps[1]) && stats(apps[1]).world_checks_waiting == 0
    });
    assert_eq!(chunk_builds(&mut client), builds + 1, "built once");
    let (_, world) = world_of(&mut client);
    assert_eq!(world.chunk_entity(chunk), None, "streamed out again");
    assert_eq!(world.waiting_carves(chunk), 0);
    assert_as_server(&mut server, &mut client, &only);
    let after = stats(&client);
    assert!(after.checks_passed > before.checks_passed, "{after:?}");
    assert_eq!(after.desyncs, 0);

    // Later carves wait again, from the chunk's stored state.
    send(&mut server, &mut client, 20, &inside[MOST..]);
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        stats(apps[1]).world_checks_waiting == 1
    });
    let (_, world) = world_of(&mut client);
    assert_eq!(world.waiting_carves(chunk), 1);
    assert_eq!(world.deferred_chunks().collect::<BTreeSet<_>>(), only);
    assert_eq!(chunk_builds(&mut client), builds + 1);

    // Asked to build its deferred chunks, the client holds them all.
    build_deferred(&mut client);
    assert!(!settled(&mut client), "it has chunks to build");
    assert_eq!(world_of(&mut client).1.deferred_chunks().count(), 0);
    run_until(&mut [&mut server, &mut client], 50_000, |apps| {
        settled(apps[1])
            && world_of(apps[1]).1.waiting_carves(chunk) == 0
            && stats(apps[1]).world_checks_waiting == 0
    });
    assert_as_server(&mut server, &mut client, &only);
    assert_eq!(chunk_builds(&mut client), builds + 2, "restored once more");
    assert_eq!(stats(&client).desyncs, 0);
}

#[test]
fn a_far_detach_builds_its_chunks_and_the_same_piece_falls() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, mut client, builds) = start(world());
    for app in [&mut server, &mut client] {
        app.init_resource::<Fallen>()
            .add_systems(Last, record_fallen);
    }
    // A slab over the border x = 224 of chunks (6, 0) and (7, 0), on a
    // pillar in (6, 0), 176 m from the client's focus.
    let pillar = ([218, 4, 10], [221, 25, 13]);
    let slab = ([218, 24, 10], [230, 28, 14]);
    let cut = ([217, 21, 9], [222, 23, 14]);
    let build = [
        (cuboid(pillar.0, pillar.1), Edit::Add(1)),
        (cuboid(slab.0, slab.1), Edit::Add(1)),
    ];
    send(&mut server, &mut client, 1, &build);
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        stats(apps[1]).world_checks_waiting == 2
    });
    let pair = BTreeSet::from([at(6, 0), at(7, 0)]);
    assert_eq!(chunk_builds(&mut client), builds, "nothing built yet");
    assert_eq!(
        world_of(&mut client)
            .1
            .deferred_chunks()
            .collect::<BTreeSet<_>>(),
        pair
    );

    // The cut: the server's detach across the border names the chunks,
    // and the client builds them for it, carves and searches them.
    send(
        &mut server,
        &mut client,
        3,
        &[(cuboid(cut.0, cut.1), Edit::Subtract)],
    );
    let falling = box_volume([218, 23, 10], [221, 24, 13]) + box_volume(slab.0, slab.1);
    run_until(&mut [&mut server, &mut client], 50_000, |apps| {
        !fallen(apps[0]).is_empty()
            && !fallen(apps[1]).is_empty()
            && settled(apps[0])
            && settled(apps[1])
            && stats(apps[1]).world_checks_waiting == 0
    });
    assert_eq!(fallen(&server), vec![falling.clone()], "server: one piece");
    assert_eq!(fallen(&client), vec![falling], "client: the same piece");
    let (_, world) = world_of(&mut client);
    assert_eq!(world.deferred_chunks().count(), 0, "the detach needed both");
    assert!(chunk_builds(&mut client) > builds);
    let reference = edited_chunks(&mut server);
    assert!(
        reference
            .keys()
            .copied()
            .collect::<BTreeSet<_>>()
            .is_superset(&pair)
    );
    assert!(
        edited_chunks(&mut client) == reference,
        "the client holds every edited chunk as the server does"
    );
    assert_eq!(stats(&client).desyncs, 0);
    assert!(client.world().resource::<WorldsSeen>().desynced.is_empty());
}
