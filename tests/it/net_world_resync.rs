//! A snapshot keeps the live chunks that already hold their state: a
//! client's chunk damaged by a local carve fails its check, the client
//! gets the world's snapshot again, and only that chunk is despawned and
//! built again; every other live chunk, edited by world carves or not,
//! keeps its entity, and the client ends with the server's world.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::terrain::{Carve, CarveTool, ChunkCoord, Terrain, TerrainWorld};

use crate::net_worlds::{streamed_world as world, world_settled as settled};
use crate::{ONE_APP_AT_A_TIME, net};
use net::world::world_hash;
use net::{Rng, Seen, WorldsSeen, request_world, run_until, unlimited, world_client, world_of};

/// The client's live chunks and their entities.
fn live(app: &mut App) -> BTreeMap<ChunkCoord, Entity> {
    world_of(app).1.live_chunks().collect()
}

/// Runs until the client answered `answered` requests, both peers are
/// settled and hold the same edited chunks.
fn converge(server: &mut App, client: &mut App, answered: usize) {
    run_until(&mut [server, client], 100_000, |apps| {
        apps[1].world().resource::<Seen>().results.len() == answered
            && apps.iter_mut().all(|app| settled(app))
            && world_hash(apps[0]) == world_hash(apps[1])
    });
}

#[test]
fn a_resync_builds_again_only_the_chunk_that_differs() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = net::world_server(world(), unlimited());
    let mut client = world_client(addr, 1, world(), Vec3::new(48.0, 30.0, 48.0));
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
    });

    // Blasts on the chunk corners at z = 32: they edit chunks (0..3, 0..2)
    // and leave the live chunks at z = 2 as the source built them.
    let mut rng = Rng(41);
    let carves = 12;
    for request in 0..carves {
        let x = 32.0 * (1 + rng.next() % 2) as f32;
        let centre = Vec3::new(x, rng.range(12.0, 18.0), 32.0);
        let tool = CarveTool::dodecahedron(rng.range(2.0, 4.0), centre);
        request_world(&mut client, request, &tool, Edit::Subtract);
    }
    converge(&mut server, &mut client, carves as usize);
    let before = live(&mut client);
    let (world_entity, _) = world_of(&mut client);
    let ecs = client.world();
    let client_world = ecs.get::<TerrainWorld>(world_entity).expect("world");
    let edited_live = (before.iter())
        .filter(|&(&coord, &entity)| {
            (ecs.get::<Terrain>(entity)).is_some_and(|t| client_world.chunk_edited(coord, t))
        })
        .count();
    assert!(
        edited_live >= 4 && before.len() > edited_live,
        "{edited_live} of {} live chunks edited",
        before.len()
    );

    // A local carve the server never sees, then a world carve into the
    // same chunk, whose check fails.
    let damaged = ChunkCoord { x: 1, z: 1 };
    client.world_mut().write_message(Carve {
        terrain: before[&damaged],
        tool: CarveTool::dodecahedron(3.0, Vec3::new(48.0, 16.0, 48.0)),
        edit: Edit::Subtract,
    });
    let tool = CarveTool::dodecahedron(2.0, Vec3::new(44.0, 14.0, 50.0));
    request_world(&mut client, carves, &tool, Edit::Subtract);
    run_until(&mut [&mut server, &mut client], 100_000, |apps| {
        apps[1].world().resource::<WorldsSeen>().synced.len() >= 2
    });
    converge(&mut server, &mut client, carves as usize + 1);

    let seen = client.world().resource::<WorldsSeen>();
    assert_eq!(seen.desynced.len(), 1, "{:?}", seen.desynced);
    assert_eq!(seen.desynced[0].chunk, damaged);
    let resync = seen.synced[1].clone();
    println!(
        "resync: {} edited chunks sent ({} bytes), {} of {} live chunks kept",
        resync.chunks,
        resync.bytes,
        resync.kept,
        before.len()
    );
    let after = live(&mut client);
    assert_ne!(after.get(&damaged), Some(&before[&damaged]), "rebuilt");
    for (coord, entity) in &before {
        if *coord != damaged {
            assert_eq!(after.get(coord), Some(entity), "chunk {coord:?} kept");
        }
    }
    assert_eq!(resync.kept, before.len() - 1);
    assert_eq!(world_hash(&mut client), world_hash(&mut server));
}
