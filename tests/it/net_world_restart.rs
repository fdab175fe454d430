//! A networked world's server saved and restarted: the first server's
//! world is carved by a client, saved in the background ([`SaveWorld`])
//! and dropped with every connection; a second server starts from
//! `TerrainWorld::load_edits` of that folder, on another port, and a new
//! client joins it. The new client gets every saved chunk bit-identical
//! from the snapshot, later carves on the loaded chunks keep every peer
//! identical, and no chunk check fails: a game server can stop and come
//! back without losing what its players dug.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::net::{NetClientStats, Outcome};
use bevy_chisel::terrain::{CarveTool, ChunkCoord, SaveWorld};

use crate::net::world::build_deferred;
use crate::net_worlds::{edited_chunks, streamed_world as world, world_settled as settled};
use crate::world_save::{Heard, hear, temp_folder};
use crate::{ONE_APP_AT_A_TIME, net};
use net::{Rng, Seen, WorldsSeen, request_world, run_until, world_client, world_of, world_server};

/// Blasts and heaps around the chunk borders at x = 32 and z = 32, so
/// that most of them reach two or four chunks.
fn carve_near_borders(rng: &mut Rng) -> (CarveTool, Edit) {
    let centre = Vec3::new(
        32.0 + rng.range(-6.0, 6.0),
        rng.range(10.0, 18.0),
        32.0 + rng.range(-6.0, 6.0),
    );
    let tool = CarveTool::dodecahedron(rng.range(1.5, 4.0), centre);
    let edit = if rng.next().is_multiple_of(4) {
        Edit::Add(2)
    } else {
        Edit::Subtract
    };
    (tool, edit)
}

/// Sends `count` carves from `client`, a few per frame, and runs until
/// the server answered all of them and both are settled.
fn carve(server: &mut App, client: &mut App, rng: &mut Rng, first: u64, count: u64) {
    for request in first..first + count {
        let (tool, edit) = carve_near_borders(rng);
        request_world(client, request, &tool, edit);
        if request % 3 == 2 {
            net::update_all(&mut [&mut *server, &mut *client]);
        }
    }
    let answered = |app: &App| {
        let results = &app.world().resource::<Seen>().results;
        results
            .iter()
            .filter(|r| r.request.is_some_and(|q| q >= first))
            .count() as u64
    };
    run_until(&mut [server, client], 100_000, |apps| {
        build_deferred(apps[1]);
        answered(apps[1]) == count && settled(apps[0]) && settled(apps[1])
    });
}

/// Runs a few frames more, for the world checks to arrive and pass.
fn let_checks_run(apps: &mut [&mut App]) {
    for _ in 0..60 {
        net::update_all(apps);
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

#[test]
fn a_restarted_server_serves_its_saved_world_bit_identical() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let folder = temp_folder("net-restart");
    let mut rng = Rng(4242);

    // The first server, carved by one client.
    let (mut server, addr) = world_server(world(), net::unlimited());
    server.init_resource::<Heard>().add_systems(Last, hear);
    let mut a = world_client(addr, 1, world(), Vec3::new(32.0, 30.0, 32.0));
    run_until(&mut [&mut server, &mut a], 20_000, |apps| {
        !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
    });
    carve(&mut server, &mut a, &mut rng, 0, 24);
    let applied = (a.world().resource::<Seen>().results.iter())
        .filter(|r| matches!(r.outcome, Outcome::Applied { .. }))
        .count();
    assert!(applied >= 20, "{applied} of 24 carves applied");

    // Saved in the background, then everything is dropped.
    let (world_entity, _) = world_of(&mut server);
    server.world_mut().write_message(SaveWorld {
        world: world_entity,
        folder: folder.clone(),
    });
    run_until(&mut [&mut server, &mut a], 10_000, |apps| {
        let heard = apps[0].world().resource::<Heard>();
        !heard.saved.is_empty() || !heard.failed.is_empty()
    });
    let failed = &server.world().resource::<Heard>().failed;
    assert!(failed.is_empty(), "the save failed: {failed:?}");
    let saved_chunks = edited_chunks(&mut server);
    let written = server.world().resource::<Heard>().saved[0].written.clone();
    assert_eq!(
        written,
        saved_chunks.keys().copied().collect::<Vec<_>>(),
        "the save wrote every edited chunk"
    );
    assert!(
        saved_chunks.len() >= 4,
        "carves over the borders edited {} chunks",
        saved_chunks.len()
    );
    assert_eq!(edited_chunks(&mut a), saved_chunks, "a matched the server");
    drop(a);
    drop(server);

    // The second server, from the save, on another port; a new client.
    let loaded = world().load_edits(&folder).expect("the save loads");
    let (mut server, addr) = world_server(loaded, net::unlimited());
    assert_eq!(
        edited_chunks(&mut server),
        saved_chunks,
        "the restarted server holds the saved chunks"
    );
    let mut b = world_client(addr, 2, world(), Vec3::new(32.0, 30.0, 32.0));
    run_until(&mut [&mut server, &mut b], 20_000, |apps| {
        build_deferred(apps[1]);
        !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
    });
    let joined = &b.world().resource::<WorldsSeen>().synced[0];
    assert_eq!(joined.chunks, saved_chunks.len(), "the snapshot's chunks");
    assert_eq!(
        edited_chunks(&mut b),
        saved_chunks,
        "the new client got every saved chunk bit-identical"
    );

    // Carving goes on over the loaded chunks; every peer stays identical
    // and every chunk check passes.
    carve(&mut server, &mut b, &mut rng, 100, 24);
    let_checks_run(&mut [&mut server, &mut b]);
    let after: BTreeMap<ChunkCoord, _> = edited_chunks(&mut server);
    assert_ne!(after, saved_chunks, "the later carves changed chunks");
    assert_eq!(edited_chunks(&mut b), after, "b matches the server");
    let stats = b.world().resource::<NetClientStats>().clone();
    println!(
        "{} chunks saved, {} after; client b: {stats:?}",
        saved_chunks.len(),
        after.len()
    );
    assert_eq!(stats.desyncs, 0, "{stats:?}");
    assert!(stats.checks_passed > 0, "{stats:?}");
    let (_, server_world) = world_of(&mut server);
    assert!(
        server_world.stored_chunks().count() > 0,
        "the server keeps its edited chunks stored"
    );
    let _ = std::fs::remove_dir_all(&folder);
}
