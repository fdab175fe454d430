//! Debris across chunk borders in a networked streamed world: one server
//! (no focus) and two clients on 127.0.0.1, one holding every chunk
//! involved, one holding only some of them. A slab over a chunk border,
//! then one over the corner of four chunks, each on a pillar that a carve
//! cuts through, falls on every peer as one piece of the same exact
//! volume; every edited chunk ends bit-identical on every peer; no world
//! hash ever differs; a client that joins afterwards gets the chunks with
//! the pieces taken out from the world's snapshot. A snapshot followed in
//! the log by a detach (taken before it, or holding it already) ends
//! identical too. Malformed detaches are refused and the client that
//! skipped them resyncs.

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, ExactVolume};
use bevy_chisel::net::wire::WorldSnapshotPart;
use bevy_chisel::net::wire::{NetWorldDetach, WireSeed};
use bevy_chisel::net::{NetClientStats, Outcome, ServerPacket};
use bevy_chisel::terrain::{CarveShape, CarveTool, ChunkCoord, DebrisDetached, Terrain};

use crate::net::world::{build_deferred, world_hash};
use crate::net::{
    Seen, WorldsSeen, request_world, run_until, unlimited, update_all, world_client, world_of,
    world_server,
};
use crate::net_worlds::{edited_chunks, streamed_world as world, world_settled as settled};
use crate::{ONE_APP_AT_A_TIME, net, net_worlds::edited_terrains};

/// The exact volumes of the pieces an app saw fall.
#[derive(Resource, Default)]
pub(crate) struct Fallen(Vec<ExactVolume>);

pub(crate) fn record_fallen(
    mut fallen: ResMut<Fallen>,
    mut detached: MessageReader<DebrisDetached>,
) {
    fallen
        .0
        .extend(detached.read().map(|d| d.exact_volume.clone()));
}

fn watch(mut app: App) -> App {
    app.init_resource::<Fallen>()
        .add_systems(Last, record_fallen);
    app
}

pub(crate) fn fallen(app: &App) -> Vec<ExactVolume> {
    app.world().resource::<Fallen>().0.clone()
}

/// A box tool with grid corners `min` and `max` (grid unit 1).
pub(crate) fn cuboid(min: [i64; 3], max: [i64; 3]) -> CarveTool {
    let lo = Vec3::new(min[0] as f32, min[1] as f32, min[2] as f32);
    let hi = Vec3::new(max[0] as f32, max[1] as f32, max[2] as f32);
    CarveTool::new(
        CarveShape::Cuboid {
            half_size: (hi - lo) / 2.0,
        },
        Transform::from_translation((lo + hi) / 2.0),
    )
}

pub(crate) fn box_volume(min: [i64; 3], max: [i64; 3]) -> ExactVolume {
    ExactVolume::from_integer((0..3).map(|a| i128::from(max[a] - min[a])).product())
}

const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// A slab from `lo` to `lo + (12, 4, depth)` at height 24..28 on a 3×3
/// pillar from the ground (4) up to 25 at its low corner, and the cut
/// through the pillar at 21..23 (above the ground, at most 20 high).
struct Slab {
    lo: [i64; 2],
    depth: i64,
}

impl Slab {
    fn pillar(&self) -> ([i64; 3], [i64; 3]) {
        let [x, z] = self.lo;
        ([x, 4, z], [x + 3, 25, z + 3])
    }

    fn slab(&self) -> ([i64; 3], [i64; 3]) {
        let [x, z] = self.lo;
        ([x, 24, z], [x + 12, 28, z + self.depth])
    }

    fn cut(&self) -> ([i64; 3], [i64; 3]) {
        let [x, z] = self.lo;
        ([x - 1, 21, z - 1], [x + 4, 23, z + 4])
    }

    /// What falls: the pillar above the cut and the slab.
    fn falling(&self) -> ExactVolume {
        let [x, z] = self.lo;
        let (slab_lo, slab_hi) = self.slab();
        box_volume([x, 23, z], [x + 3, 24, z + 3]) + box_volume(slab_lo, slab_hi)
    }
}

/// Sends the carves one after another from `app` (request ids from
/// `first`) and runs every app until each is answered and every peer is
/// settled with the same world hash.
fn carve_and_converge(
    apps: &mut [&mut App],
    first: u64,
    carves: &[(([i64; 3], [i64; 3]), Edit)],
) -> usize {
    for (n, &((min, max), edit)) in carves.iter().enumerate() {
        let request = first + n as u64;
        request_world(apps[1], request, &cuboid(min, max), edit);
        run_until(apps, 50_000, |apps| {
            let seen = &apps[1].world().resource::<Seen>().results;
            seen.iter().any(|r| r.request == Some(request))
        });
        let seen = &apps[1].world().resource::<Seen>().results;
        let outcome = seen.iter().find(|r| r.request == Some(request));
        assert!(
            outcome.is_some_and(|r| matches!(r.outcome, Outcome::Applied { .. })),
            "carve {request} applies: {outcome:?}"
        );
    }
    converge(apps)
}

/// Runs until every peer is settled with the first one's world hash,
/// then a few frames more for the world checks. The clients build the far
/// chunks whose carves they deferred.
fn converge(apps: &mut [&mut App]) -> usize {
    let frames = run_until(apps, 100_000, |apps| {
        apps.iter_mut().for_each(|app| build_deferred(app));
        if !apps.iter_mut().all(|app| settled(app)) {
            return false;
        }
        let want = edited_chunks(apps[0]);
        apps[1..].iter_mut().all(|app| edited_chunks(app) == want)
    });
    for _ in 0..40 {
        for app in apps.iter_mut() {
            app.update();
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    frames
}

/// The material at grid point `p` of chunk `coord`, as `app` holds it.
fn label_at(app: &mut App, coord: ChunkCoord, p: [i64; 3]) -> Option<u8> {
    let terrains = edited_terrains(app);
    let terrain: &Terrain = terrains.get(&coord).expect("an edited chunk");
    terrain.octree().label_at(p).expect("inside the chunk")
}

fn assert_same_chunks(server: &mut App, peers: &mut [(&str, &mut App)]) {
    let reference = edited_chunks(server);
    for (name, app) in peers.iter_mut() {
        let chunks = edited_chunks(app);
        assert_eq!(
            chunks.keys().collect::<Vec<_>>(),
            reference.keys().collect::<Vec<_>>(),
            "{name}: edited chunks"
        );
        for (coord, (bytes, hash)) in &reference {
            let (peer_bytes, peer_hash) = &chunks[coord];
            assert_eq!(peer_hash, hash, "{name}: state hash of chunk {coord:?}");
            assert!(peer_bytes == bytes, "{name}: octree of chunk {coord:?}");
        }
    }
}

fn no_desync(name: &str, app: &App) {
    let stats = app.world().resource::<NetClientStats>();
    assert_eq!(stats.desyncs, 0, "{name}: world hashes always matched");
    assert!(
        stats.checks_passed > 0,
        "{name}: world hashes were compared"
    );
    assert!(app.world().resource::<WorldsSeen>().desynced.is_empty());
}

#[test]
fn pieces_cut_loose_across_borders_fall_alike_on_every_peer() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = unlimited();
    let (server, addr) = world_server(world(), limits);
    let mut server = watch(server);
    // `a` holds chunks (0..=1, 0..=1); `b` holds (0, 0) and (0, 1) but
    // neither (1, 0) nor (1, 1).
    let mut a = watch(world_client(addr, 1, world(), Vec3::new(32.0, 30.0, 32.0)));
    let mut b = watch(world_client(addr, 2, world(), Vec3::new(-10.0, 30.0, 16.0)));
    let holds = |app: &mut App, coord| world_of(app).1.chunk_entity(coord).is_some();
    run_until(&mut [&mut server, &mut a, &mut b], 20_000, |apps| {
        let synced = apps[1..]
            .iter_mut()
            .all(|app| !app.world().resource::<WorldsSeen>().synced.is_empty() && settled(app));
        synced && holds(apps[1], at(1, 1)) && holds(apps[2], at(0, 0))
    });
    let (_, b_world) = world_of(&mut b);
    assert!(b_world.chunk_entity(at(0, 0)).is_some());
    assert!(b_world.chunk_entity(at(1, 0)).is_none());
    assert!(b_world.chunk_entity(at(1, 1)).is_none());

    // A slab over the border x = 32, on a pillar in chunk (0, 0).
    let border = Slab {
        lo: [26, 10],
        depth: 4,
    };
    let mut apps = [&mut server, &mut a, &mut b];
    carve_and_converge(
        &mut apps,
        1,
        &[
            (border.pillar(), Edit::Add(1)),
            (border.slab(), Edit::Add(1)),
        ],
    );
    for app in apps.iter() {
        assert!(fallen(app).is_empty(), "the slab rests on its pillar");
    }
    let frames = carve_and_converge(&mut apps, 3, &[(border.cut(), Edit::Subtract)]);
    println!("{frames} frames to converge after the cut over a border");
    for (name, app) in [("server", &*apps[0]), ("a", &*apps[1]), ("b", &*apps[2])] {
        assert_eq!(
            fallen(app),
            vec![border.falling()],
            "{name}: one piece fell"
        );
    }
    for app in apps.iter_mut() {
        assert_eq!(label_at(app, at(1, 0), [35, 26, 12]), Some(0), "slab out");
        assert_eq!(label_at(app, at(0, 0), [27, 26, 12]), Some(0), "slab out");
        assert_eq!(
            label_at(app, at(0, 0), [27, 10, 11]),
            Some(1),
            "pillar stays"
        );
    }

    // A slab over the corner of four chunks, on a pillar in chunk (0, 0).
    let corner = Slab {
        lo: [26, 26],
        depth: 12,
    };
    carve_and_converge(
        &mut apps,
        4,
        &[
            (corner.pillar(), Edit::Add(1)),
            (corner.slab(), Edit::Add(1)),
        ],
    );
    let frames = carve_and_converge(&mut apps, 6, &[(corner.cut(), Edit::Subtract)]);
    println!("{frames} frames to converge after the cut at a corner");
    for (name, app) in [("server", &*apps[0]), ("a", &*apps[1]), ("b", &*apps[2])] {
        assert_eq!(
            fallen(app),
            vec![border.falling(), corner.falling()],
            "{name}: the second piece fell, over four chunks"
        );
    }
    for app in apps.iter_mut() {
        for (coord, p) in [
            (at(1, 1), [35, 26, 35]),
            (at(0, 1), [27, 26, 35]),
            (at(1, 0), [35, 26, 27]),
        ] {
            assert_eq!(label_at(app, coord, p), Some(0), "{coord:?}: slab out");
        }
    }
    let [server, a, b] = apps;
    assert_same_chunks(server, &mut [("a", a), ("b", b)]);
    no_desync("a", a);
    no_desync("b", b);
    let (_, b_world) = world_of(b);
    assert!(
        b_world.chunk_entity(at(1, 1)).is_none(),
        "b does not keep the chunk it built for the detach"
    );

    // A client that joins now gets the chunks with the pieces out.
    let mut c = watch(world_client(addr, 3, world(), Vec3::new(48.0, 30.0, 48.0)));
    run_until(&mut [server, a, b, &mut c], 20_000, |apps| {
        !apps[3].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[3])
    });
    converge(&mut [server, a, b, &mut c]);
    assert!(fallen(&c).is_empty(), "c installs the chunks as they are");
    // One more carve, so that c compares a world hash too.
    carve_and_converge(
        &mut [server, a, b, &mut c],
        7,
        &[(([40, 12, 40], [43, 15, 43]), Edit::Subtract)],
    );
    assert_eq!(label_at(&mut c, at(1, 1), [35, 26, 35]), Some(0));
    assert_same_chunks(server, &mut [("a", a), ("b", b), ("c", &mut c)]);
    for (name, app) in [("a", &*a), ("b", &*b), ("c", &c)] {
        no_desync(name, app);
    }
}

/// Malformed detaches in a client's world order (a seed naming no chunk
/// of the detach, too many chunks, a cell outside its chunk, a world the
/// client does not have) are refused with a warning, never a panic; the
/// ones that took the place of the server's carves make the client's
/// world hash differ, and it resyncs to the server's chunks.
#[test]
fn a_malformed_detach_is_refused_and_the_client_resyncs() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limits = unlimited();
    let (mut server, addr) = world_server(world(), limits);
    let mut a = world_client(addr, 1, world(), Vec3::new(16.0, 30.0, 16.0));
    run_until(&mut [&mut server, &mut a], 20_000, |apps| {
        !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
    });
    let seed = WireSeed {
        chunk: 0,
        depth: 1,
        pos: [0, 0, 1],
    };
    let detach = |world, seq, chunks: Vec<[i64; 2]>, seeds| {
        ServerPacket::WorldDetach(NetWorldDetach {
            world,
            seq,
            chunks,
            seeds,
        })
    };
    let too_many = (0..100).map(|x| [x, 0]).collect();
    let outside = WireSeed { depth: 200, ..seed };
    for packet in [
        detach(1, 1, vec![[0, 0]], vec![WireSeed { chunk: 1, ..seed }]),
        detach(1, 2, too_many, vec![seed]),
        detach(1, 3, vec![[0, 0]], vec![outside]),
        detach(99, 1, vec![[0, 0]], vec![seed]),
    ] {
        a.world_mut().write_message(packet);
    }
    a.update();
    for n in 0..3u64 {
        let centre = Vec3::new(8.0 + 6.0 * n as f32, 14.0, 12.0);
        let tool = CarveTool::dodecahedron(2.5, centre);
        request_world(&mut a, n, &tool, Edit::Subtract);
    }
    converge(&mut [&mut server, &mut a]);
    let answered = &a.world().resource::<Seen>().results;
    assert_eq!(answered.len(), 3);
    assert!(
        answered
            .iter()
            .all(|r| matches!(r.outcome, Outcome::Applied { .. })),
        "the server applied the carves: {answered:?}"
    );
    assert_same_chunks(&mut server, &mut [("a", &mut a)]);
    let stats = a.world().resource::<NetClientStats>();
    assert!(stats.desyncs >= 1, "the skipped carves were noticed");
    assert!(stats.snapshots >= 2, "and the world resynced");
}

/// What the search costs a server that holds no chunk but those carves
/// reach: craters in the middle of chunks, whose searches stop on the
/// ground, build no chunk besides the carved ones (12 for 12 carves in
/// 12 places nobody holds, as with the search turned off); the chunks
/// across a side are built only where a search stops on that side (the
/// slabs of the test above).
#[test]
fn a_server_without_a_focus_builds_only_the_carved_chunks_for_craters() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    for across_borders in [true, false] {
        let limits = unlimited();
        let served = world().with_debris_across_borders(across_borders);
        let (mut server, addr) = world_server(served, limits);
        let mut a = world_client(addr, 1, world(), Vec3::new(-500.0, 30.0, -500.0));
        run_until(&mut [&mut server, &mut a], 20_000, |apps| {
            !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
        });
        let before = world_of(&mut server).1.stats().clone();
        // Three chunks apart along x, in the middle of chunk (3k, 0).
        let carves: Vec<_> = (0..12)
            .map(|k| {
                let x = 96 * k + 14;
                (([x, 14, 14], [x + 4, 22, 18]), Edit::Subtract)
            })
            .collect();
        carve_and_converge(&mut [&mut server, &mut a], 1, &carves);
        let after = world_of(&mut server).1.stats().clone();
        let built = after.generated + after.restored - before.generated - before.restored;
        println!(
            "debris across borders {across_borders}: the server built {built} chunks for 12 \
             carves in {:?}",
            after.build_time - before.build_time
        );
        assert_eq!(built, 12, "one chunk built per carve");
    }
}

/// Every server packet an app received, in order.
#[derive(Resource, Default)]
struct Received(Vec<ServerPacket>);

fn record_packets(mut received: ResMut<Received>, mut packets: MessageReader<ServerPacket>) {
    received.0.extend(packets.read().cloned());
}

/// A light client (the protocol only, no world) that records what the
/// server sends it.
fn recorder(addr: std::net::SocketAddr, id: u64) -> App {
    let mut app = net::light_client(addr, id);
    app.init_resource::<Received>()
        .add_systems(Update, record_packets);
    app
}

fn received(app: &App) -> Vec<ServerPacket> {
    app.world().resource::<Received>().0.clone()
}

/// The snapshot parts among `packets`.
fn snapshot_parts(packets: &[ServerPacket]) -> Vec<WorldSnapshotPart> {
    (packets.iter())
        .filter_map(|p| match p {
            ServerPacket::WorldSnapshot(part) => Some(part.clone()),
            _ => None,
        })
        .collect()
}

/// The exact volume of material 1 in chunks `coords` as `app` holds them.
fn rock_in(app: &mut App, coords: &[ChunkCoord]) -> ExactVolume {
    let terrains = edited_terrains(app);
    coords
        .iter()
        .filter_map(|coord| terrains.get(coord))
        .filter_map(|terrain| terrain.octree().exact_volumes().remove(&1))
        .fold(ExactVolume::default(), |sum, v| sum + v)
}

/// A client whose world snapshot lands while a detach across chunk
/// borders is in the server's order after the snapshot's `seq`, in the
/// two forms the server sends:
///
/// - **before**: the snapshot was taken before the cut that frees a slab
///   (its chunks do not hold the cut), and the cut and its detach follow
///   it in the log: the client must carry the detach out (skipping it
///   would leave the slab);
/// - **holding**: the server's *done* op was still before the cut (an
///   earlier carve not yet reported by every chunk) while the cut's
///   chunks already held the cut and the detach, so the snapshot's `seq`
///   is before the cut, its chunks' own `seq` at the detach, and the cut
///   and the detach follow: the client must skip both for those chunks.
///
/// The packets are the server's own, recorded by light clients that
/// joined before and after the cut (the second's snapshot `seq` set back
/// to before the cut, as a server whose done op lags sends it), and given
/// to a connected client as a resync. Each client ends bit-identical to
/// the server: same edited chunks, octrees, state hashes and world hash,
/// the rock of the slab's chunks less exactly the cut and the piece; the
/// piece falls on the first client only. A client that skipped the
/// detach in the first form keeps the slab and fails; one that carried it
/// out again in the second form searches cells already empty, finds
/// nothing and ends the same (checked by changing the client's routing).
#[test]
fn a_snapshot_landing_before_a_detach_in_the_log_ends_identical() {
    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (server, addr) = world_server(world(), unlimited());
    let mut server = watch(server);
    let mut a = watch(world_client(addr, 1, world(), Vec3::new(32.0, 30.0, 32.0)));
    run_until(&mut [&mut server, &mut a], 20_000, |apps| {
        !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
    });
    let border = Slab {
        lo: [26, 10],
        depth: 4,
    };
    carve_and_converge(
        &mut [&mut server, &mut a],
        1,
        &[
            (border.pillar(), Edit::Add(1)),
            (border.slab(), Edit::Add(1)),
        ],
    );
    let slab_chunks = [at(0, 0), at(1, 0)];
    let rock_before = rock_in(&mut server, &slab_chunks);
    // Joins before the cut, and records the cut and the detach after its
    // snapshot.
    let mut early = recorder(addr, 10);
    run_until(&mut [&mut server, &mut a, &mut early], 20_000, |apps| {
        !snapshot_parts(&received(apps[2])).is_empty()
    });
    carve_and_converge(
        &mut [&mut server, &mut a],
        3,
        &[(border.cut(), Edit::Subtract)],
    );
    run_until(&mut [&mut server, &mut a, &mut early], 20_000, |apps| {
        (received(apps[2]).iter()).any(|p| matches!(p, ServerPacket::WorldDetach(_)))
    });
    // Joins after the detach: its snapshot's chunks hold it.
    let mut late = recorder(addr, 11);
    run_until(&mut [&mut server, &mut a, &mut late], 20_000, |apps| {
        !snapshot_parts(&received(apps[2])).is_empty()
    });
    for _ in 0..20 {
        update_all(&mut [&mut server, &mut a, &mut late]);
    }

    let early_packets = received(&early);
    let before = snapshot_parts(&early_packets);
    let ops: Vec<ServerPacket> = (early_packets.iter())
        .filter(|p| {
            matches!(
                p,
                ServerPacket::WorldCarve(_) | ServerPacket::WorldDetach(_)
            )
        })
        .cloned()
        .collect();
    let cut = match &ops[..] {
        [
            ServerPacket::WorldCarve(cut),
            ServerPacket::WorldDetach(detach),
        ] => {
            assert_eq!(detach.seq, cut.seq + 1, "the detach follows the cut");
            cut.seq
        }
        other => panic!("the early recorder saw the cut and its detach: {other:?}"),
    };
    assert!(before.iter().all(|p| p.seq == cut - 1), "before the cut");
    let holding: Vec<WorldSnapshotPart> = snapshot_parts(&received(&late))
        .into_iter()
        .map(|mut part| {
            assert_eq!(part.seq, cut + 1, "the late snapshot holds the detach");
            part.seq = cut - 1;
            part
        })
        .collect();
    let held: Vec<u64> = (holding.iter())
        .filter_map(|p| p.chunk.as_ref())
        .filter(|c| slab_chunks.contains(&at(c.coord[0], c.coord[1])))
        .map(|c| c.seq)
        .collect();
    assert!(
        !held.is_empty() && held.iter().all(|&s| s == cut + 1),
        "the slab's chunks hold the detach: {held:?}"
    );

    let falling = border.falling();
    let cut_rock = box_volume([26, 21, 10], [29, 23, 13]);
    let variants = [
        (20, "before", before, true),
        (21, "holding", holding, false),
    ];
    for (id, name, parts, falls) in variants {
        let mut c = watch(world_client(addr, id, world(), Vec3::new(48.0, 30.0, 16.0)));
        run_until(&mut [&mut server, &mut c], 20_000, |apps| {
            !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && settled(apps[1])
        });
        for part in parts {
            c.world_mut()
                .write_message(ServerPacket::WorldSnapshot(part));
        }
        for op in &ops {
            c.world_mut().write_message(op.clone());
        }
        let want = edited_chunks(&mut server);
        run_until(&mut [&mut server, &mut c], 20_000, |apps| {
            apps[1].world().resource::<WorldsSeen>().synced.len() == 2
                && settled(apps[1])
                && edited_chunks(apps[1]) == want
        });
        let pieces = fallen(&c);
        if falls {
            assert_eq!(pieces, vec![falling.clone()], "{name}: the piece fell");
        } else {
            assert!(pieces.is_empty(), "{name}: the snapshot holds the detach");
        }
        assert_eq!(
            rock_in(&mut c, &slab_chunks) + cut_rock.clone() + falling.clone(),
            rock_before,
            "{name}: the slab's chunks lost exactly the cut and the piece"
        );
        assert_eq!(
            label_at(&mut c, at(1, 0), [35, 26, 12]),
            Some(0),
            "slab out"
        );
        assert_eq!(label_at(&mut c, at(0, 0), [27, 10, 11]), Some(1), "pillar");
        assert_same_chunks(&mut server, &mut [(name, &mut c)]);
        assert_eq!(world_hash(&mut c), world_hash(&mut server), "{name}");
    }
}
