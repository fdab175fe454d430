//! The client side of networked worlds ([`super::world`]): sends world
//! carve requests, installs world snapshots, routes the server's carves to
//! its chunks strictly in order, and compares its chunks' hashes with the
//! server's checks.
//! As in [`super::client`], requests work in every role and the rest only
//! while connected.

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use bevy::prelude::*;
use bevy_replicon::prelude::ClientState;
use chisel_bsp::octree::Edit;

use super::client::{
    Assembled, NetCarveResult, NetClientStats, addressee, assemble, nowhere_to_send,
};
use super::wire::{
    ClientPacket, ClientRequest, MAX_CHECK_CHUNKS, NetWorld, NetWorldCarve, NetWorldDetach,
    ServerPacket, WireTool, WorldId, WorldSnapshotPart,
};
use super::world::{WorldBook, chunk_reports, claim_debris, ordered_detach};
use crate::terrain::world::debris_order::DebrisRole;
use crate::terrain::{
    CarveApplied, CarveRejected, ChunkCoord, Terrain, TerrainSystems, TerrainWorld, WorldChunk,
};

/// Ask the server to carve a networked world, in any role (as a
/// [`super::NetCarveRequest`]); answered by a [`NetCarveResult`] with the
/// same request id.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct NetWorldCarveRequest {
    /// Chosen by the sender; echoed in [`NetCarveResult`].
    pub request: u64,
    /// The local world entity (with a [`NetWorld`]).
    pub world: Entity,
    /// The tool in the world's local frame: `WireTool::from(&carve_tool)`
    /// for a [`crate::terrain::CarveTool`], or a tool on the world's grid.
    #[reflect(ignore)]
    pub tool: WireTool,
    /// What to do inside it.
    #[reflect(ignore)]
    pub edit: Edit,
}

/// A world's chunks were replaced by the server's snapshot: at join, or
/// after a desync.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldSynced {
    /// The local world entity.
    pub world: Entity,
    /// Its network id.
    pub id: WorldId,
    /// Every world carve up to this one is in the installed chunks.
    pub seq: u64,
    /// Edited chunks installed.
    pub chunks: usize,
    /// Their snapshot bytes.
    pub bytes: usize,
    /// Live chunks kept as they were, since they already held their state
    /// in the snapshot (the rest stream in again from it or the source).
    pub kept: usize,
}

/// A chunk's state hash after world op `seq` differs from the server's
/// ([`ServerPacket::WorldCheck`]); the client asked for the world's
/// snapshot.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct WorldDesynced {
    /// The local world entity.
    pub world: Entity,
    /// The chunk whose hashes differ.
    pub chunk: ChunkCoord,
    /// The op after which they differ: the last one the server applied
    /// to the chunk.
    pub seq: u64,
    /// This client's hash of the chunk (`None`: not edited here).
    pub local: Option<u64>,
    /// The server's.
    pub server: u64,
}

/// An op of a world's order as received.
enum WorldOp {
    Carve(NetWorldCarve),
    Detach(NetWorldDetach),
}

/// A world snapshot being received.
struct Incoming {
    seq: u64,
    chunks: u32,
    /// Chunks complete so far: coordinates, last carve held, bytes.
    done: Vec<(ChunkCoord, u64, Vec<u8>)>,
    /// The chunk being received.
    slot: Option<(u64, Vec<u8>)>,
}

/// A complete world snapshot, not installed yet.
struct Received {
    seq: u64,
    chunks: Vec<(ChunkCoord, u64, Vec<u8>)>,
}

/// One world as this client follows it.
#[derive(Default)]
struct FollowWorld {
    book: WorldBook,
    /// A snapshot was installed: carves may be routed.
    synced: bool,
    /// The next carve to route.
    next_seq: u64,
    /// Ops (carves, detaches) received but not routed yet.
    waiting: BTreeMap<u64, WorldOp>,
    /// Chunks whose installed snapshot holds the carves up to this one.
    held: BTreeMap<ChunkCoord, u64>,
    incoming: Option<Incoming>,
    ready: Option<Received>,
    /// The server's latest hash of each chunk not yet compared: the last
    /// op applied to it and the hash after it.
    checks: BTreeMap<ChunkCoord, (u64, u64)>,
    /// Waiting for a snapshot after a desync.
    resyncing: bool,
}

#[derive(Resource, Default)]
struct WorldFollower {
    worlds: HashMap<WorldId, FollowWorld>,
}

/// Adds the world systems and messages to [`super::NetClientPlugin`].
pub(super) fn build(app: &mut App) {
    app.init_resource::<WorldFollower>()
        .add_observer(super::world::networked_debris)
        .add_message::<NetWorldCarveRequest>()
        .add_message::<WorldSynced>()
        .add_message::<WorldDesynced>()
        .register_type::<NetWorldCarveRequest>()
        .register_type::<WorldSynced>()
        .register_type::<WorldDesynced>()
        .add_systems(
            Update,
            (
                (
                    send_world_requests,
                    (receive_world_packets, install_and_route)
                        .chain()
                        .run_if(in_state(ClientState::Connected)),
                )
                    .chain()
                    .before(TerrainSystems::Carve),
                compare_world_hashes
                    .after(TerrainSystems::Mesh)
                    .run_if(in_state(ClientState::Connected)),
            ),
        )
        .add_systems(OnExit(ClientState::Connected), stop_following_worlds);
}

/// Forgets what was being followed of each world when the connection
/// ends; the worlds and their chunks stay, and the next connection starts
/// again from the world's snapshot.
fn stop_following_worlds(mut follower: ResMut<WorldFollower>) {
    follower.worlds.clear();
}

/// Sends each world request as `send_requests` in [`super::client`]
/// sends terrain requests.
fn send_world_requests(
    mut requests: MessageReader<NetWorldCarveRequest>,
    worlds: Query<&NetWorld>,
    state: Res<State<ClientState>>,
    server_side: Option<Res<super::server::ServerLedger>>,
    mut packets: MessageWriter<ClientPacket>,
    mut results: MessageWriter<NetCarveResult>,
) {
    let unsent = nowhere_to_send(state.get(), server_side.is_some());
    for request in requests.read() {
        let target = worlds.get(request.world).ok();
        let Some(id) = addressee(request.request, unsent, target, "world", &mut results) else {
            continue;
        };
        packets.write(ClientPacket::Request(ClientRequest::CarveWorld {
            request: request.request,
            world: id.0,
            tool: request.tool.clone(),
            edit: request.edit,
        }));
    }
}

fn receive_world_packets(
    mut packets: MessageReader<ServerPacket>,
    mut follower: ResMut<WorldFollower>,
) {
    for packet in packets.read() {
        match packet {
            ServerPacket::WorldCarve(carve) => {
                let follow = follower.worlds.entry(carve.world).or_default();
                // Behind a snapshot come the carves after it, some of which
                // may be routed here already: keep them for the snapshot.
                let snapshot = follow.incoming.is_some() || follow.ready.is_some();
                if carve.seq >= follow.next_seq || snapshot {
                    follow
                        .waiting
                        .entry(carve.seq)
                        .or_insert_with(|| WorldOp::Carve(carve.clone()));
                }
            }
            ServerPacket::WorldDetach(detach) => {
                let follow = follower.worlds.entry(detach.world).or_default();
                let snapshot = follow.incoming.is_some() || follow.ready.is_some();
                if detach.seq >= follow.next_seq || snapshot {
                    follow
                        .waiting
                        .entry(detach.seq)
                        .or_insert_with(|| WorldOp::Detach(detach.clone()));
                }
            }
            ServerPacket::WorldCheck { world, chunks, .. } => {
                let follow = follower.worlds.entry(*world).or_default();
                for check in chunks.iter().take(MAX_CHECK_CHUNKS) {
                    let coord = ChunkCoord {
                        x: check.coord[0],
                        z: check.coord[1],
                    };
                    // Only the latest of each chunk is kept.
                    let newer =
                        (follow.checks.get(&coord)).is_none_or(|&(seq, _)| seq <= check.seq);
                    if newer {
                        follow.checks.insert(coord, (check.seq, check.hash));
                    }
                }
            }
            ServerPacket::WorldSnapshot(part) => {
                let follow = follower.worlds.entry(part.world).or_default();
                receive_part(follow, part);
            }
            _ => {}
        }
    }
}

/// Adds one part to the world snapshot being received.
fn receive_part(follow: &mut FollowWorld, part: &WorldSnapshotPart) {
    let Some(chunk) = &part.chunk else {
        follow.incoming = None;
        follow.ready = Some(Received {
            seq: part.seq,
            chunks: Vec::new(),
        });
        return;
    };
    if chunk.index == 0 && chunk.offset == 0 {
        follow.incoming = Some(Incoming {
            seq: part.seq,
            chunks: part.chunks,
            done: Vec::new(),
            slot: None,
        });
    }
    let Some(incoming) = follow.incoming.as_mut() else {
        return;
    };
    if incoming.seq != part.seq
        || incoming.chunks != part.chunks
        || chunk.index as usize != incoming.done.len()
    {
        warn!(
            "world {} snapshot: a part out of order; dropped",
            part.world
        );
        follow.incoming = None;
        return;
    }
    let assembled = assemble(
        &mut incoming.slot,
        chunk.seq,
        chunk.total,
        chunk.offset,
        &chunk.bytes,
    );
    match assembled {
        Assembled::Partial => {}
        Assembled::Dropped(why) => {
            warn!("world {} snapshot dropped: {why}", part.world);
            follow.incoming = None;
        }
        Assembled::Whole(seq, bytes) => {
            let coord = ChunkCoord {
                x: chunk.coord[0],
                z: chunk.coord[1],
            };
            incoming.done.push((coord, seq, bytes));
            if incoming.done.len() >= incoming.chunks as usize {
                let incoming = follow.incoming.take();
                follow.ready = incoming.map(|i| Received {
                    seq: i.seq,
                    chunks: i.done,
                });
            }
        }
    }
}

/// Installs complete snapshots into their worlds, then routes the waiting
/// ops of each synced world to its chunks, in order and without gaps: a
/// detach across chunk borders goes to the world, and nothing after it is
/// routed until the world applied it.
fn install_and_route(
    mut commands: Commands,
    mut worlds: Query<(Entity, &NetWorld, &mut TerrainWorld)>,
    terrains: Query<&Terrain>,
    mut follower: ResMut<WorldFollower>,
    mut stats: ResMut<NetClientStats>,
    mut synced: MessageWriter<WorldSynced>,
) {
    for (entity, id, mut world) in &mut worlds {
        claim_debris(world.bypass_change_detection(), DebrisRole::Follow);
        let Some(follow) = follower.worlds.get_mut(&id.0) else {
            continue;
        };
        if let Some(received) = follow.ready.take() {
            let seq = received.seq;
            match install(&mut commands, &mut world, &terrains, follow, received) {
                Ok(installed) => {
                    stats.snapshots += 1;
                    synced.write(WorldSynced {
                        world: entity,
                        id: id.0,
                        seq,
                        chunks: installed.chunks,
                        bytes: installed.bytes,
                        kept: installed.kept,
                    });
                }
                Err(why) => error!("world {} snapshot refused: {why}", id.0),
            }
        }
        if !follow.synced || follow.resyncing {
            continue;
        }
        while world.detach_ordered.is_none() {
            let Some(op) = follow.waiting.remove(&follow.next_seq) else {
                break;
            };
            match op {
                WorldOp::Carve(carve) => {
                    // The server found chunks for it; none here means
                    // another world.
                    let coords: Vec<ChunkCoord> = world
                        .chunks_reached(&carve.tool)
                        .unwrap_or_default()
                        .into_iter()
                        .filter(|c| follow.held.get(c).is_none_or(|&held| held < carve.seq))
                        .collect();
                    world.route(&carve.tool, carve.edit, carve.seq, &coords);
                    follow.book.note_routed(carve.seq, &coords);
                    stats.carves += 1;
                }
                WorldOp::Detach(detach) => route_detach(&mut world, follow, &detach, id.0),
            }
            follow.next_seq += 1;
        }
        let next = follow.next_seq;
        follow.held.retain(|_, held| *held >= next);
    }
}

/// Hands a detach across chunk borders to the world, unless the installed
/// snapshot already holds it (a chunk of it holds an op at or after it:
/// the server applied it before the snapshot) or it is malformed.
fn route_detach(
    world: &mut TerrainWorld,
    follow: &mut FollowWorld,
    detach: &NetWorldDetach,
    id: WorldId,
) {
    // Routed to no chunk when skipped, so that the world hash after it is
    // known (and, after a refusal, found to differ from the server's).
    let seq = detach.seq;
    match ordered_detach(detach, world.layout().chunk_log2) {
        Ok(ordered) => {
            let held =
                (ordered.chunks.iter()).any(|c| follow.held.get(c).is_some_and(|&h| h >= seq));
            if held {
                follow.book.note_routed(seq, &[]);
            } else {
                follow.book.note_routed(seq, &ordered.chunks);
                world.detach_ordered = Some(ordered);
            }
        }
        Err(why) => {
            warn!("world {id}: detach {seq} from the server is refused: {why}");
            follow.book.note_routed(seq, &[]);
        }
    }
}

/// What installing a snapshot did.
struct Installed {
    /// Edited chunks in the snapshot.
    chunks: usize,
    /// Their snapshot bytes.
    bytes: usize,
    /// Live chunks kept as they were.
    kept: usize,
}

/// Replaces the world's chunks with a received snapshot's, keeping the
/// live chunks that already hold their state in it ([`unchanged_live`]).
fn install(
    commands: &mut Commands,
    world: &mut TerrainWorld,
    terrains: &Query<&Terrain>,
    follow: &mut FollowWorld,
    received: Received,
) -> Result<Installed, String> {
    let layout = world.layout().clone();
    let mut edited = BTreeMap::new();
    let mut hashes = BTreeMap::new();
    let mut held = BTreeMap::new();
    let mut snapshots = BTreeMap::new();
    let mut bytes = 0;
    for (coord, seq, snapshot) in &received.chunks {
        let terrain =
            Terrain::from_snapshot_bytes(snapshot).map_err(|e| format!("chunk {coord:?}: {e}"))?;
        let base = layout
            .chunk_base(&*world.source, *coord)
            .map_err(|e| format!("chunk {coord:?}: {e}"))?;
        if *terrain.quantization() != layout.quantization || *terrain.base() != base {
            return Err(format!(
                "chunk {coord:?} is not a chunk of this world (another grid or base)"
            ));
        }
        hashes.insert(*coord, BTreeMap::from([(*seq, terrain.state_hash())]));
        held.insert(*coord, *seq);
        edited.insert(*coord, Arc::new(terrain.to_bytes()));
        snapshots.insert(*coord, terrain);
        bytes += snapshot.len();
    }
    let keep = unchanged_live(world, terrains, &snapshots);
    world.reset_chunks(commands, edited, &keep);
    let floor = held.values().copied().fold(received.seq, u64::max);
    follow.book = WorldBook {
        chunks: hashes,
        outstanding: BTreeMap::new(),
        unreported: BTreeMap::new(),
        routed: received.seq,
        floor,
    };
    follow.next_seq = received.seq + 1;
    follow.waiting.retain(|&s, _| s > received.seq);
    follow.held = held;
    follow.synced = true;
    follow.resyncing = false;
    // Checks of states older than the snapshot's cannot be compared.
    follow.checks.retain(|_, &mut (seq, _)| seq >= floor);
    Ok(Installed {
        chunks: received.chunks.len(),
        bytes,
        kept: keep.len(),
    })
}

/// The live chunks that already hold exactly their state in the received
/// `snapshots`, so a snapshot need not despawn and build them again (at a
/// join, the chunks the client streamed in while it waited; at a resync,
/// all but the chunks that differ): an idle chunk the snapshot names
/// whose octree is the received one, byte for byte, or an idle chunk the
/// snapshot does not name that holds the source's state (not edited).
/// The chunk keeps its own settings (debris rules, undo depth), which are
/// this world's. Idle but
/// for sealing at its neighbours' points, which a kept chunk goes on with.
fn unchanged_live(
    world: &TerrainWorld,
    terrains: &Query<&Terrain>,
    snapshots: &BTreeMap<ChunkCoord, Terrain>,
) -> BTreeMap<ChunkCoord, Entity> {
    let unchanged = |coord: ChunkCoord, terrain: &Terrain| {
        terrain.is_idle_but_for_seams()
            && match snapshots.get(&coord) {
                Some(sent) => {
                    terrain.state_hash() == sent.state_hash()
                        && terrain.octree().to_bytes() == sent.octree().to_bytes()
                }
                None => !world.chunk_edited(coord, terrain),
            }
    };
    (world.live_chunks())
        .filter(|&(coord, entity)| terrains.get(entity).is_ok_and(|t| unchanged(coord, t)))
        .collect()
}

/// Reads the chunks' reports of world carves and detaches and compares
/// each chunk the server's checks name once it reported every op up to
/// the one named (checks of chunks not there yet wait, the latest of each
/// chunk kept); a difference asks for the world's snapshot.
#[allow(clippy::too_many_arguments)]
fn compare_world_hashes(
    mut applied: MessageReader<CarveApplied>,
    mut refused: MessageReader<CarveRejected>,
    chunks: Query<&WorldChunk>,
    ids: Query<&NetWorld>,
    mut worlds: Query<(Entity, &NetWorld, &mut TerrainWorld)>,
    mut follower: ResMut<WorldFollower>,
    mut stats: ResMut<NetClientStats>,
    mut packets: MessageWriter<ClientPacket>,
    mut desynced: MessageWriter<WorldDesynced>,
) {
    for report in chunk_reports(&mut applied, &mut refused, &chunks, &ids) {
        if let Some(follow) = follower.worlds.get_mut(&report.world) {
            follow
                .book
                .note_report(report.coord, report.seq, report.hash);
        }
    }
    for (entity, id, mut world) in &mut worlds {
        // Reading the detaches applied is bookkeeping.
        let applied = std::mem::take(&mut world.bypass_change_detection().detaches_applied);
        let Some(follow) = follower.worlds.get_mut(&id.0) else {
            continue;
        };
        // Each chunk of a detach the world carried out reports it.
        for detach in applied {
            let Some(seq) = detach.seq else {
                continue;
            };
            for (coord, hash) in detach.hashes {
                follow.book.note_report(coord, seq, hash);
            }
        }
        follow.book.settle_failed(&world);
        if !follow.synced || follow.resyncing {
            follow.checks.clear();
            continue;
        }
        let Some((chunk, seq, local, server)) = compare_chunks(follow, &mut stats) else {
            continue;
        };
        stats.desyncs += 1;
        follow.resyncing = true;
        follow.checks.clear();
        warn!(
            "world {}: chunk ({}, {}) has hash {local:#018x?} after op {seq}, the server \
             {server:#018x}; asking for the world's snapshot",
            id.0, chunk.x, chunk.z
        );
        desynced.write(WorldDesynced {
            world: entity,
            chunk,
            seq,
            local,
            server,
        });
        packets.write(ClientPacket::Request(ClientRequest::WorldDesync {
            world: id.0,
            seq,
            hash: local.unwrap_or(0),
        }));
    }
    let waiting = follower
        .worlds
        .values()
        .map(|f| f.checks.len())
        .sum::<usize>();
    stats.world_checks_waiting = waiting as u64;
}

/// Compares every waiting check whose chunk reported every op up to the
/// one named, and forgets them (and the hashes no later check needs);
/// checks older than the installed snapshot are dropped. Returns the
/// first chunk whose hash differs: its coordinates, the op, this
/// client's hash and the server's.
fn compare_chunks(
    follow: &mut FollowWorld,
    stats: &mut NetClientStats,
) -> Option<(ChunkCoord, u64, Option<u64>, u64)> {
    let mut decided = Vec::new();
    let mut differs = None;
    for (&coord, &(seq, server)) in &follow.checks {
        if seq < follow.book.floor {
            decided.push((coord, seq));
            continue;
        }
        // Not known yet: kept until known or replaced by a newer check.
        let Some(local) = follow.book.chunk_hash_at(coord, seq) else {
            continue;
        };
        decided.push((coord, seq));
        if local == Some(server) {
            stats.checks_passed += 1;
        } else if differs.is_none() {
            differs = Some((coord, seq, local, server));
        }
    }
    for (coord, seq) in decided {
        follow.checks.remove(&coord);
        follow.book.prune_chunk(coord, seq);
    }
    differs
}
