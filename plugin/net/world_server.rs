//! The server side of networked worlds ([`super::world`]): validates world
//! carve requests, numbers them per world, routes them to its own chunks,
//! broadcasts them, answers each request once every chunk it reached
//! reported, sends the hashes of the chunks changed, and world snapshots to clients that join
//! or fall out of step. Like [`super::server`], it runs whenever the app
//! is no connected client, and a host's own world carves are ordered here
//! once and broadcast to the remote clients only.

use std::collections::{BTreeMap, HashMap};
use std::time::Instant;

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon::server::AuthorizedClient;

use super::server::{
    NetLimits, NetServerStats, RequestRejected, ServerLedger, allow, check_grid_tool, check_size,
    invalid, round_tool,
};
use super::wire::{
    ChunkSnapshotPart, ClientPacket, ClientRequest, MAX_CHECK_CHUNKS, NetWorld, NetWorldCarve,
    Outcome, RejectReason, ServerPacket, WireTool, WorldId, WorldSnapshotPart, snapshot_parts,
};
use super::world::{WorldBook, chunk_reports, claim_debris, wire_detach};
use crate::terrain::world::debris_order::DebrisRole;
use crate::terrain::{
    CarveApplied, CarveRejected, ChunkCoord, GridTool, Terrain, TerrainSystems, TerrainWorld,
    WorldChunk,
};

/// Who asked for an accepted carve, and what its chunks did so far.
struct Answer {
    client: ClientId,
    request: u64,
    /// Some chunk applied it.
    applied: bool,
    /// Why a chunk refused it (the first one).
    error: Option<String>,
}

/// One world's order of carves on the server.
#[derive(Default)]
struct ServedWorld {
    book: WorldBook,
    /// The ops (accepted carves, applied detaches) after the book's done
    /// carve, as sent.
    log: BTreeMap<u64, ServerPacket>,
    answers: HashMap<u64, Answer>,
    /// The op up to which the chunks' hashes were sent.
    checked: u64,
}

#[derive(Resource, Default)]
struct WorldLedger {
    worlds: HashMap<WorldId, ServedWorld>,
    /// Clients that need the snapshot of one world, or of every world.
    joining: Vec<(ClientId, Option<WorldId>)>,
    last_check: Option<Instant>,
}

/// A world's snapshot as sent: its parts, then the ops after it.
struct WorldSnapshot {
    parts: Vec<WorldSnapshotPart>,
    log: Vec<ServerPacket>,
    bytes: usize,
}

/// Adds the world systems to [`super::NetServerPlugin`].
pub(super) fn build(app: &mut App) {
    app.init_resource::<WorldLedger>()
        .add_observer(on_authorized)
        .add_observer(super::world::networked_debris)
        .add_systems(
            Update,
            (
                (seed_worlds, receive_world_requests, send_world_snapshots)
                    .chain()
                    .before(TerrainSystems::Carve),
                report_world_carves.after(TerrainSystems::Mesh),
            )
                .run_if(in_state(ClientState::Disconnected)),
        );
}

fn on_authorized(add: On<Add, AuthorizedClient>, mut ledger: ResMut<WorldLedger>) {
    ledger.joining.push((ClientId::Client(add.entity), None));
}

/// Starts the book of each networked world the first time it is seen,
/// with the chunks edited before (loaded with
/// [`TerrainWorld::load_edits`], or carved before the world was
/// networked) as edited at carve 0; the server's pass decides debris
/// across chunk borders in every networked world.
fn seed_worlds(
    mut worlds: Query<(&NetWorld, &mut TerrainWorld)>,
    terrains: Query<&Terrain>,
    mut ledger: ResMut<WorldLedger>,
) {
    for (_, mut world) in &mut worlds {
        claim_debris(world.bypass_change_detection(), DebrisRole::Serve);
    }
    for (id, world) in &worlds {
        if ledger.worlds.contains_key(&id.0) {
            continue;
        }
        let mut served = ServedWorld::default();
        let mut seed = |coord: ChunkCoord, hash: u64| {
            served.book.chunks.entry(coord).or_default().insert(0, hash);
        };
        for coord in world.stored_chunks() {
            match world.stored_chunk(coord).map(Terrain::from_bytes) {
                Some(Ok(terrain)) => seed(coord, terrain.state_hash()),
                Some(Err(e)) => error!("world {} chunk {coord:?}: {e}", id.0),
                None => {}
            }
        }
        for (coord, entity) in world.live_chunks() {
            if let Ok(terrain) = terrains.get(entity)
                && world.chunk_edited(coord, terrain)
            {
                seed(coord, terrain.state_hash());
            }
        }
        ledger.worlds.insert(id.0, served);
    }
}

/// Checks a world carve request against the limits and the world, rounds
/// a float tool to the world's grid (the one rounding of the carve) and
/// finds the chunks it reaches.
fn validate_world(
    tool: &WireTool,
    edit: chisel_bsp::octree::Edit,
    world: &TerrainWorld,
    limits: &NetLimits,
) -> Result<(GridTool, Vec<ChunkCoord>), RejectReason> {
    check_size(tool, limits)?;
    world.check_edit(edit).map_err(invalid)?;
    let grid = &world.layout().quantization;
    let tool = round_tool(tool, grid)?;
    check_grid_tool(&tool, grid.unit(), limits)?;
    let coords = world.chunks_reached(&tool).map_err(invalid)?;
    let limit = limits.max_world_chunk;
    let beyond = |c: &&ChunkCoord| {
        c.x.unsigned_abs() > limit.unsigned_abs() || c.z.unsigned_abs() > limit.unsigned_abs()
    };
    if let Some(far) = coords.iter().find(beyond) {
        return Err(RejectReason::OutsideWorld {
            chunk: [far.x, far.z],
            limit,
        });
    }
    Ok((tool, coords))
}

#[allow(clippy::too_many_arguments)]
fn receive_world_requests(
    mut packets: MessageReader<FromClient<ClientPacket>>,
    mut worlds: Query<(&NetWorld, &mut TerrainWorld)>,
    limits: Res<NetLimits>,
    mut allowance: ResMut<ServerLedger>,
    mut ledger: ResMut<WorldLedger>,
    mut stats: ResMut<NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
    mut rejected: MessageWriter<RequestRejected>,
) {
    for packet in packets.read() {
        let client = packet.client_id;
        let (request, id, tool, edit) = match &packet.message {
            ClientPacket::Request(ClientRequest::WorldDesync { world, seq, hash }) => {
                warn!(
                    "client {client} reports world {world} out of step after carve {seq} \
                     (its hash {hash:#018x}); sending the world's snapshot"
                );
                if !ledger.joining.contains(&(client, Some(*world))) {
                    ledger.joining.push((client, Some(*world)));
                }
                continue;
            }
            ClientPacket::Request(ClientRequest::CarveWorld {
                request,
                world,
                tool,
                edit,
            }) => (*request, *world, tool, *edit),
            _ => continue,
        };
        let accepted = if allow(&mut allowance, client, &limits) {
            match worlds.iter_mut().find(|(w, _)| w.0 == id) {
                None => Err(RejectReason::UnknownWorld(id)),
                Some((_, world)) => validate_world(tool, edit, &world, &limits)
                    .map(|(tool, coords)| (tool, coords, world)),
            }
        } else {
            Err(RejectReason::RateLimited)
        };
        let (tool, coords, mut world) = match accepted {
            Ok(accepted) => accepted,
            Err(reason) => {
                stats.rejected += 1;
                out.write(ToClients {
                    targets: SendTargets::Single(client),
                    message: ServerPacket::Result {
                        request: Some(request),
                        outcome: Outcome::Rejected(reason.clone()),
                    },
                });
                rejected.write(RequestRejected {
                    client,
                    request: Some(request),
                    reason,
                });
                continue;
            }
        };
        let served = ledger.worlds.entry(id).or_default();
        let seq = served.book.routed + 1;
        world.route(&tool, edit, seq, &coords);
        served.book.note_routed(seq, &coords);
        let carve = NetWorldCarve {
            world: id,
            seq,
            tool,
            edit,
        };
        served
            .log
            .insert(seq, ServerPacket::WorldCarve(carve.clone()));
        served.answers.insert(
            seq,
            Answer {
                client,
                request,
                applied: false,
                error: None,
            },
        );
        let packet = ServerPacket::WorldCarve(carve);
        stats.accepted += 1;
        stats.carve_bytes += postcard::to_allocvec(&packet).map_or(0, |b| b.len() as u64);
        out.write(ToClients {
            targets: SendTargets::CLIENTS_ONLY,
            message: packet,
        });
    }
}

/// Reads the chunks' reports of world carves: answers each request once
/// every chunk it reached reported, forgets the carves every chunk has,
/// and every check interval sends the hashes of each world's chunks
/// changed since the previous check.
#[allow(clippy::too_many_arguments)]
fn report_world_carves(
    mut applied: MessageReader<CarveApplied>,
    mut refused: MessageReader<CarveRejected>,
    chunks: Query<&WorldChunk>,
    ids: Query<&NetWorld>,
    mut worlds: Query<(&NetWorld, &mut TerrainWorld)>,
    limits: Res<NetLimits>,
    mut ledger: ResMut<WorldLedger>,
    mut stats: ResMut<NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
    mut rejected: MessageWriter<RequestRejected>,
) {
    let ledger = &mut *ledger;
    number_detaches(&mut worlds, ledger, &mut out);
    let mut finished: Vec<(WorldId, u64)> = Vec::new();
    for report in chunk_reports(&mut applied, &mut refused, &chunks, &ids) {
        let Some(served) = ledger.worlds.get_mut(&report.world) else {
            continue;
        };
        if let Some(answer) = served.answers.get_mut(&report.seq) {
            answer.applied |= report.hash.is_some();
            if answer.error.is_none() {
                answer.error = report.error;
            }
        }
        if served
            .book
            .note_report(report.coord, report.seq, report.hash)
        {
            finished.push((report.world, report.seq));
        }
    }
    for (id, world) in &worlds {
        if let Some(served) = ledger.worlds.get_mut(&id.0) {
            finished.extend(
                served
                    .book
                    .settle_failed(world)
                    .into_iter()
                    .map(|s| (id.0, s)),
            );
            let done = served.book.done();
            served.log = served.log.split_off(&(done + 1));
        }
    }
    for (id, seq) in finished {
        let Some(answer) = ledger
            .worlds
            .get_mut(&id)
            .and_then(|served| served.answers.remove(&seq))
        else {
            continue;
        };
        let outcome = if answer.applied {
            Outcome::Applied { seq }
        } else {
            stats.rejected += 1;
            let reason = RejectReason::Invalid(
                answer
                    .error
                    .unwrap_or_else(|| "no chunk the tool reaches could be built".into()),
            );
            rejected.write(RequestRejected {
                client: answer.client,
                request: Some(answer.request),
                reason: reason.clone(),
            });
            Outcome::Rejected(reason)
        };
        out.write(ToClients {
            targets: SendTargets::Single(answer.client),
            message: ServerPacket::Result {
                request: Some(answer.request),
                outcome,
            },
        });
    }
    let now = Instant::now();
    if ledger
        .last_check
        .is_some_and(|at| now.duration_since(at) < limits.check_interval)
    {
        return;
    }
    ledger.last_check = Some(now);
    for (&world, served) in &mut ledger.worlds {
        let done = served.book.done();
        if done <= served.checked {
            continue;
        }
        let changed = served.book.changed_chunks(served.checked, done);
        served.checked = done;
        served.book.prune(done);
        for chunks in changed.chunks(MAX_CHECK_CHUNKS) {
            out.write(ToClients {
                targets: SendTargets::CLIENTS_ONLY,
                message: ServerPacket::WorldCheck {
                    world,
                    seq: done,
                    chunks: chunks.to_vec(),
                },
            });
        }
    }
}

/// Numbers the detaches across chunk borders each world applied this
/// frame (after its carves were handed to its chunks, before any later
/// carve is numbered: see `crate::terrain::world::debris_order`) as the
/// next ops of its order, notes each chunk's hash after it and sends it
/// to every client.
fn number_detaches(
    worlds: &mut Query<(&NetWorld, &mut TerrainWorld)>,
    ledger: &mut WorldLedger,
    out: &mut MessageWriter<ToClients<ServerPacket>>,
) {
    for (id, mut world) in worlds.iter_mut() {
        if world.detaches_applied.is_empty() {
            continue;
        }
        // Numbering the world's detaches is the server's bookkeeping.
        let world = world.bypass_change_detection();
        let applied = std::mem::take(&mut world.detaches_applied);
        let served = ledger.worlds.entry(id.0).or_default();
        for detach in applied {
            let seq = served.book.routed + 1;
            served.book.note_routed(seq, &detach.chunks);
            for &(coord, hash) in &detach.hashes {
                served.book.note_report(coord, seq, hash);
            }
            world.next_request = world.next_request.max(seq + 1);
            debug!(
                "world {}: detach {seq} across chunk borders, {} pieces over {} chunks",
                id.0,
                detach.seeds.len(),
                detach.chunks.len()
            );
            let packet = ServerPacket::WorldDetach(wire_detach(id.0, seq, &detach));
            served.log.insert(seq, packet.clone());
            out.write(ToClients {
                targets: SendTargets::CLIENTS_ONLY,
                message: packet,
            });
        }
    }
}

/// The snapshot of `world` now, or `None` when an edited chunk's terrain
/// cannot be read this frame (it was just spawned): try again next frame.
fn world_snapshot(
    id: WorldId,
    world: &TerrainWorld,
    terrains: &Query<&Terrain>,
    served: &ServedWorld,
    limits: &NetLimits,
) -> Option<WorldSnapshot> {
    let done = served.book.done();
    let mut chunks: Vec<(ChunkCoord, u64, Vec<u8>)> = Vec::new();
    for (&coord, hashes) in &served.book.chunks {
        let last_applied = hashes.keys().next_back().copied().unwrap_or(0);
        if let Some(entity) = world.chunk_entity(coord) {
            let terrain = terrains.get(entity).ok()?;
            let seq = terrain.last_request().unwrap_or(0).max(last_applied);
            chunks.push((coord, seq, terrain.to_snapshot_bytes()));
        } else if let Some(bytes) = world.stored_chunk(coord) {
            match Terrain::from_bytes(bytes) {
                Ok(terrain) => chunks.push((coord, last_applied, terrain.to_snapshot_bytes())),
                Err(e) => error!("world {id} chunk {coord:?} is not sent: {e}"),
            }
        } else {
            warn!("world {id}: edited chunk {coord:?} is neither live nor stored; not sent");
        }
    }
    let count = u32::try_from(chunks.len()).unwrap_or(u32::MAX);
    let mut parts = Vec::new();
    let mut bytes = 0;
    for (index, (coord, seq, snapshot)) in chunks.iter().enumerate() {
        bytes += snapshot.len();
        for (offset, part) in snapshot_parts(snapshot, limits.snapshot_part_bytes) {
            parts.push(WorldSnapshotPart {
                world: id,
                seq: done,
                chunks: count,
                chunk: Some(ChunkSnapshotPart {
                    index: u32::try_from(index).unwrap_or(u32::MAX),
                    coord: [coord.x, coord.z],
                    seq: *seq,
                    total: snapshot.len() as u64,
                    offset,
                    bytes: part.to_vec(),
                }),
            });
        }
    }
    if parts.is_empty() {
        parts.push(WorldSnapshotPart {
            world: id,
            seq: done,
            chunks: 0,
            chunk: None,
        });
    }
    let log = served
        .log
        .range(done + 1..)
        .map(|(_, op)| op.clone())
        .collect();
    Some(WorldSnapshot { parts, log, bytes })
}

/// Sends each world's snapshot, then the carves after it, to the clients
/// that joined or asked for one.
fn send_world_snapshots(
    worlds: Query<(&NetWorld, &TerrainWorld)>,
    terrains: Query<&Terrain>,
    limits: Res<NetLimits>,
    mut ledger: ResMut<WorldLedger>,
    mut stats: ResMut<NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
) {
    if ledger.joining.is_empty() {
        return;
    }
    let joining = std::mem::take(&mut ledger.joining);
    let mut made: HashMap<WorldId, Option<WorldSnapshot>> = HashMap::new();
    for (id, world) in &worlds {
        if joining
            .iter()
            .any(|(_, only)| only.is_none_or(|w| w == id.0))
        {
            let snapshot = ledger
                .worlds
                .get(&id.0)
                .and_then(|served| world_snapshot(id.0, world, &terrains, served, &limits));
            made.insert(id.0, snapshot);
        }
    }
    for (client, only) in joining {
        let wanted: Vec<WorldId> = made
            .keys()
            .copied()
            .filter(|&w| only.is_none_or(|o| o == w))
            .collect();
        if wanted
            .iter()
            .any(|w| made.get(w).is_some_and(Option::is_none))
        {
            // A chunk could not be read yet: the whole join waits a frame.
            ledger.joining.push((client, only));
            continue;
        }
        for world in wanted {
            let Some(Some(snapshot)) = made.get(&world) else {
                continue;
            };
            stats.snapshots += 1;
            stats.snapshot_bytes += snapshot.bytes as u64;
            for part in &snapshot.parts {
                out.write(ToClients {
                    targets: SendTargets::Single(client),
                    message: ServerPacket::WorldSnapshot(part.clone()),
                });
            }
            for op in &snapshot.log {
                out.write(ToClients {
                    targets: SendTargets::Single(client),
                    message: op.clone(),
                });
            }
        }
    }
}
