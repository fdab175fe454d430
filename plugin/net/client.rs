//! The client side: sends carve requests, applies the server's carves
//! strictly in sequence order per terrain, builds terrains from snapshots,
//! compares hashes and asks for a snapshot when its terrain differs.
//!
//! A client sends the request's floats ([`super::wire::WireTool::World`])
//! and keeps only the integer [`NetCarve`](super::NetCarve)s the server sends back: it
//! queues each on the terrain as a carve tracked by its sequence number
//! (what a [`GridCarve`](crate::terrain::GridCarve) with that request id
//! queues), directly, so that it keeps its place among the client's
//! predictions.
//!
//! With [`super::NetClientSettings::predict_own_carves`] a connected
//! client also rounds its own requests with the server's rounding and
//! applies them at once, ahead of the server, then reconciles them with
//! the server's order (module [`super::predict`]).
//!
//! Requests and answers work in every role; following the server (its
//! carves, checks and snapshots) only while connected
//! (`ClientState::Connected`). On a host or in single player the requests
//! go to the app's own [`super::NetServerPlugin`] (bevy_replicon writes them
//! locally) and its answers come back the same way; the carves are applied
//! by the server side, so nothing is followed here. A request written while
//! connecting, or while disconnected in an app without the server plugin,
//! is answered [`RejectReason::NotConnected`]. On leaving
//! `Connected`, what was being followed is dropped (the terrains stay);
//! the next connection starts again from snapshots.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use bevy::prelude::*;
use bevy_replicon::prelude::ClientState;
use chisel_bsp::octree::Edit;

use super::predict::{self, NetClientSettings, Op, Predictions};
use super::wire::{
    ClientPacket, ClientRequest, NetTerrain, Outcome, RejectReason, ServerPacket, TerrainId,
    WireTool,
};
use crate::terrain::{CarveApplied, CarveRejected, Terrain, TerrainCell, TerrainSystems};

/// Ask the server to carve a terrain, in any role: sent to the server by a
/// connected client, ordered by the app's own server on a host or in
/// single player; answered by a [`NetCarveResult`].
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct NetCarveRequest {
    /// Chosen by the sender; echoed in [`NetCarveResult`].
    pub request: u64,
    /// The local terrain entity (with a [`NetTerrain`]).
    pub terrain: Entity,
    /// The tool: `WireTool::from(&carve_tool)` for a
    /// [`crate::terrain::CarveTool`], or a grid tool.
    #[reflect(ignore)]
    pub tool: WireTool,
    /// What to do inside it.
    #[reflect(ignore)]
    pub edit: Edit,
}

/// The server's answer to a [`NetCarveRequest`] (or to a packet it could
/// not read: `request` is then `None`).
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
#[reflect(from_reflect = false)]
pub struct NetCarveResult {
    /// The request id.
    pub request: Option<u64>,
    /// What became of it.
    #[reflect(ignore)]
    pub outcome: Outcome,
}

/// Most bytes of one terrain snapshot a client assembles (a server that
/// announces more is not followed: the snapshot is refused and logged).
pub const MAX_SNAPSHOT_BYTES: u64 = 4 << 30;

/// A terrain arrived from a snapshot: at join, or after a desync.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct TerrainSynced {
    /// The local terrain entity.
    pub terrain: Entity,
    /// Its network id.
    pub id: TerrainId,
    /// The last carve the snapshot holds.
    pub seq: u64,
    /// Snapshot bytes.
    pub bytes: usize,
}

/// The terrain's hash after carve `seq` differs from the server's; the
/// client asked for a snapshot.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
pub struct Desynced {
    /// The local terrain entity.
    pub terrain: Entity,
    /// The carve after which the hashes differ.
    pub seq: u64,
    /// This client's hash.
    pub local: u64,
    /// The server's hash.
    pub server: u64,
}

/// Hashes kept per terrain for comparison with late checks.
const KEPT_HASHES: usize = 1024;

/// One terrain as this client follows it.
#[derive(Default)]
struct Follow {
    entity: Option<Entity>,
    /// The next carve to hand to the terrain.
    next_seq: u64,
    /// Carves (and undos) received but not handed over yet.
    waiting: BTreeMap<u64, Op>,
    /// Undos handed over whose jobs have not reported yet.
    undos: BTreeSet<u64>,
    /// A snapshot being received: its last carve and its bytes so far.
    assembling: Option<(u64, Vec<u8>)>,
    /// The hash after each recent carve (and after the snapshot).
    hashes: BTreeMap<u64, u64>,
    /// The server's latest check not yet compared: (seq, hash).
    check: Option<(u64, u64)>,
    /// Waiting for a snapshot after a desync.
    resyncing: bool,
    /// This client's own carves applied ahead of the server.
    predictions: Predictions,
}

#[derive(Resource, Default)]
struct ClientLedger {
    terrains: HashMap<TerrainId, Follow>,
    /// The number of the latest prediction applied.
    predicted: u64,
}

/// Counters of a client, for reports and tests.
#[derive(Resource, Reflect, Clone, Debug, Default)]
#[reflect(Resource, Default)]
pub struct NetClientStats {
    /// Server carves handed to the terrains (a confirmed prediction is
    /// not handed over again: [`NetClientStats::predictions_confirmed`]).
    pub carves: u64,
    /// Hash checks that matched (a world's: one per chunk checked).
    pub checks_passed: u64,
    /// Hash checks that did not (each led to a snapshot).
    pub desyncs: u64,
    /// Snapshots installed.
    pub snapshots: u64,
    /// Chunk checks of networked worlds kept now until their chunks
    /// report the op named (chunks whose carves wait deferred, far from
    /// every focus).
    pub world_checks_waiting: u64,
    /// Own carves applied ahead of the server
    /// ([`NetClientSettings::predict_own_carves`]).
    pub predictions: u64,
    /// Predictions the server's order confirmed: its carve was not
    /// applied again.
    pub predictions_confirmed: u64,
    /// Predictions the server refused, taken back.
    pub predictions_refused: u64,
    /// Roll backs: another carve came first, or a request was refused,
    /// and the pending predictions were taken back (and those still
    /// pending applied again on top).
    pub rollbacks: u64,
    /// Predictions taken back in those roll backs.
    pub predictions_rolled_back: u64,
    /// Times the undo history could not hold the predictions to take
    /// back, so that they were dropped and a snapshot asked for.
    pub prediction_resyncs: u64,
    /// The server's undos and redos handed to the terrains (module
    /// [`super::undo`]).
    pub undos: u64,
    /// Times a terrain could not apply the server's undo or redo (its
    /// history was shorter), so that a snapshot was asked for.
    pub undo_resyncs: u64,
}

/// The client side of networked carving; connect with
/// [`super::start_client`]. Terrains appear (with [`NetTerrain`]) when the
/// server's snapshots arrive.
///
/// Add it with [`super::NetServerPlugin`] to pick the role at run time
/// (module docs, "Roles"): its requests then also carve a host's or a
/// single player's own terrains.
pub struct NetClientPlugin;

impl Plugin for NetClientPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<super::NetProtocolPlugin>() {
            app.add_plugins(super::NetProtocolPlugin);
        }
        app.init_resource::<ClientLedger>()
            .init_resource::<super::undo::UndoRequests>()
            .init_resource::<NetClientStats>()
            .init_resource::<NetClientSettings>()
            .init_resource::<predict::PredictedDebris>()
            .register_type::<NetClientSettings>()
            .add_message::<NetCarveRequest>()
            .add_message::<NetCarveResult>()
            .add_message::<TerrainSynced>()
            .add_message::<Desynced>()
            .register_type::<NetClientStats>()
            .register_type::<NetCarveRequest>()
            .register_type::<NetCarveResult>()
            .register_type::<TerrainSynced>()
            .register_type::<Desynced>();
        super::world_client::build(app);
        let connected = in_state(ClientState::Connected);
        app.add_systems(
            Update,
            (
                (
                    (send_requests, super::undo::send_undo_requests),
                    (receive_packets, super::undo::receive_undo_results),
                    hand_over.run_if(connected.clone()),
                )
                    .chain()
                    .before(TerrainSystems::Carve),
                compare_hashes.after(TerrainSystems::Mesh).run_if(connected),
                predict::take_back_debris.after(TerrainSystems::Mesh),
            ),
        )
        .add_systems(
            OnExit(ClientState::Connected),
            (stop_following, super::undo::forget_undo_requests),
        );
    }
}

/// Forgets the carves, snapshots and checks being followed when the
/// connection ends; the terrains stay. Sequence 0 is no carve, so every
/// carve of the next connection waits for its snapshot.
fn stop_following(mut ledger: ResMut<ClientLedger>) {
    for follow in ledger.terrains.values_mut() {
        *follow = Follow {
            entity: follow.entity,
            ..Follow::default()
        };
    }
}

/// Whether a request written now has no server to go to: while
/// connecting, or while disconnected in an app without
/// [`super::NetServerPlugin`].
pub(super) fn nowhere_to_send(state: &ClientState, server_side: bool) -> bool {
    match state {
        ClientState::Connecting => true,
        ClientState::Disconnected => !server_side,
        ClientState::Connected => false,
    }
}

/// The networked id a request names, when it can be sent; otherwise its
/// refusal is answered at once: [`RejectReason::NotConnected`] when there is
/// no server to send it to (`unsent`), or no networked `what` behind its
/// entity (`target` is `None`).
pub(super) fn addressee<T>(
    request: u64,
    unsent: bool,
    target: Option<T>,
    what: &str,
    results: &mut MessageWriter<NetCarveResult>,
) -> Option<T> {
    let reason = match target {
        _ if unsent => RejectReason::NotConnected,
        Some(target) => return Some(target),
        None => RejectReason::Invalid(format!("the entity is no networked {what}")),
    };
    results.write(NetCarveResult {
        request: Some(request),
        outcome: Outcome::Rejected(reason),
    });
    None
}

/// Sends each request to the server: over the connection, or to the app's
/// own server side when not connected (bevy_replicon writes client
/// messages locally then). One with no server to go to
/// ([`nowhere_to_send`]) is answered [`RejectReason::NotConnected`]. A
/// connected client that predicts its carves also queues each one on its
/// terrain ([`super::predict`]).
#[allow(clippy::too_many_arguments)]
fn send_requests(
    mut requests: MessageReader<NetCarveRequest>,
    mut terrains: Query<(&NetTerrain, Option<&mut Terrain>)>,
    state: Res<State<ClientState>>,
    server_side: Option<Res<super::server::ServerLedger>>,
    settings: Res<NetClientSettings>,
    mut ledger: ResMut<ClientLedger>,
    mut stats: ResMut<NetClientStats>,
    mut packets: MessageWriter<ClientPacket>,
    mut results: MessageWriter<NetCarveResult>,
) {
    let unsent = nowhere_to_send(state.get(), server_side.is_some());
    let predicting = settings.predict_own_carves && *state.get() == ClientState::Connected;
    for request in requests.read() {
        let target = terrains.get(request.terrain).ok().map(|(id, _)| *id);
        let Some(id) = addressee(request.request, unsent, target, "terrain", &mut results) else {
            continue;
        };
        packets.write(ClientPacket::Request(ClientRequest::Carve {
            request: request.request,
            terrain: id.0,
            tool: request.tool.clone(),
            edit: request.edit,
        }));
        if !predicting {
            continue;
        }
        let ledger = &mut *ledger;
        let (Ok((_, Some(mut terrain))), Some(follow)) = (
            terrains.get_mut(request.terrain),
            ledger.terrains.get_mut(&id.0),
        ) else {
            continue;
        };
        if follow.entity != Some(request.terrain) || follow.resyncing {
            continue;
        }
        // The server's own rounding; a tool it would refuse to round, or
        // an edit the terrain refuses, is not predicted.
        let Ok(tool) = request.tool.to_grid(terrain.quantization()) else {
            continue;
        };
        if terrain.check_edit(request.edit).is_err() {
            continue;
        }
        ledger.predicted += 1;
        // A request, not a change of the terrain's content yet.
        predict::predict(
            terrain.bypass_change_detection(),
            &mut follow.predictions,
            ledger.predicted,
            request.request,
            tool,
            request.edit,
        );
        stats.predictions += 1;
    }
}

/// Turns the server's answers into [`NetCarveResult`]s in every role, and
/// keeps its carves, checks and snapshots while connected: a packet of
/// those that arrives otherwise is the app's own server speaking to
/// itself, and is dropped.
#[allow(clippy::too_many_arguments)]
fn receive_packets(
    mut packets: MessageReader<ServerPacket>,
    state: Res<State<ClientState>>,
    mut ledger: ResMut<ClientLedger>,
    mut stats: ResMut<NetClientStats>,
    cells: Query<(Entity, &TerrainCell)>,
    mut commands: Commands,
    mut results: MessageWriter<NetCarveResult>,
    mut synced: MessageWriter<TerrainSynced>,
) {
    let following = *state.get() == ClientState::Connected;
    for packet in packets.read() {
        if !following && !matches!(packet, ServerPacket::Result { .. }) {
            continue;
        }
        match packet {
            ServerPacket::Carve(carve) => {
                let follow = ledger.terrains.entry(carve.terrain).or_default();
                if carve.seq >= follow.next_seq {
                    follow
                        .waiting
                        .entry(carve.seq)
                        .or_insert_with(|| Op::Carve(carve.clone()));
                }
            }
            ServerPacket::Undo(undo) => {
                let follow = ledger.terrains.entry(undo.terrain).or_default();
                if undo.seq >= follow.next_seq {
                    follow.waiting.entry(undo.seq).or_insert(Op::Undo(*undo));
                }
            }
            ServerPacket::Result { request, outcome } => {
                if let (true, Some(request), Outcome::Rejected(_)) = (following, request, outcome) {
                    // A refused request whose prediction is pending: the
                    // hand over takes it back.
                    let predicted = ledger.terrains.values_mut().find(|follow| {
                        (follow.predictions.pending.iter()).any(|p| p.request == *request)
                    });
                    if let Some(follow) = predicted {
                        follow.predictions.refused.push(*request);
                    }
                }
                results.write(NetCarveResult {
                    request: *request,
                    outcome: outcome.clone(),
                });
            }
            ServerPacket::Check { terrain, seq, hash } => {
                let follow = ledger.terrains.entry(*terrain).or_default();
                follow.check = Some((*seq, *hash));
            }
            // World packets: `super::world_client`.
            ServerPacket::WorldCarve(_)
            | ServerPacket::WorldCheck { .. }
            | ServerPacket::WorldSnapshot(_)
            | ServerPacket::WorldDetach(_) => {}
            // Answers to undo requests: `super::undo`.
            ServerPacket::UndoResult { .. } => {}
            ServerPacket::Snapshot(part) => {
                let follow = ledger.terrains.entry(part.terrain).or_default();
                let (seq, bytes) = match assemble(
                    &mut follow.assembling,
                    part.seq,
                    part.total,
                    part.offset,
                    &part.bytes,
                ) {
                    Assembled::Partial => continue,
                    Assembled::Whole(seq, bytes) => (seq, bytes),
                    Assembled::Dropped(why) => {
                        warn!("snapshot of terrain {} dropped: {why}", part.terrain);
                        continue;
                    }
                };
                let mut terrain = match Terrain::from_snapshot_bytes(&bytes) {
                    Ok(terrain) => terrain,
                    Err(e) => {
                        error!("snapshot of terrain {} refused: {e}", part.terrain);
                        continue;
                    }
                };
                terrain.last_request = (seq > 0).then_some(seq);
                let hash = terrain.state_hash();
                let pose = Transform::from(&part.pose);
                let entity = match follow.entity {
                    Some(entity) => {
                        for (cell, of) in &cells {
                            if of.terrain == entity {
                                commands.entity(cell).despawn();
                            }
                        }
                        commands.entity(entity).insert((terrain, pose));
                        entity
                    }
                    None => commands
                        .spawn((terrain, NetTerrain(part.terrain), pose))
                        .id(),
                };
                follow.entity = Some(entity);
                follow.next_seq = seq + 1;
                follow.waiting.retain(|&s, _| s > seq);
                follow.hashes.clear();
                follow.undos.clear();
                follow.hashes.insert(seq, hash);
                follow.resyncing = false;
                // The snapshot replaces the terrain, predictions and all.
                follow.predictions = Predictions::default();
                stats.snapshots += 1;
                synced.write(TerrainSynced {
                    terrain: entity,
                    id: part.terrain,
                    seq,
                    bytes: bytes.len(),
                });
            }
        }
    }
}

/// What became of one snapshot part ([`assemble`]).
pub(super) enum Assembled {
    /// More parts to come (or a part without its start, ignored).
    Partial,
    /// The last part: the snapshot's `seq` and its bytes.
    Whole(u64, Vec<u8>),
    /// The snapshot is dropped: too large or a part out of order.
    Dropped(String),
}

/// Adds a part (`offset` into a snapshot of `total` bytes after carve
/// `seq`) to the snapshot being received in `slot`: a part at offset 0
/// starts a new one.
pub(super) fn assemble(
    slot: &mut Option<(u64, Vec<u8>)>,
    seq: u64,
    total: u64,
    offset: u64,
    bytes: &[u8],
) -> Assembled {
    if total > MAX_SNAPSHOT_BYTES {
        *slot = None;
        return Assembled::Dropped(format!(
            "{total} bytes, more than the {MAX_SNAPSHOT_BYTES} a client accepts"
        ));
    }
    if offset == 0 {
        *slot = Some((seq, Vec::new()));
    }
    let Some((at, have)) = slot.as_mut() else {
        return Assembled::Partial;
    };
    if *at != seq || have.len() as u64 != offset {
        *slot = None;
        return Assembled::Dropped("a part out of order".into());
    }
    have.extend_from_slice(bytes);
    if (have.len() as u64) < total {
        return Assembled::Partial;
    }
    match slot.take() {
        Some((seq, bytes)) => Assembled::Whole(seq, bytes),
        None => Assembled::Partial,
    }
}

/// Hands the waiting carves to their terrains, in sequence order and
/// without gaps, reconciled with the client's predictions
/// ([`predict::hand_over`]).
fn hand_over(
    mut ledger: ResMut<ClientLedger>,
    mut stats: ResMut<NetClientStats>,
    mut terrains: Query<&mut Terrain>,
    mut rejected: MessageWriter<CarveRejected>,
    mut packets: MessageWriter<ClientPacket>,
) {
    let ClientLedger {
        terrains: follows,
        predicted,
    } = &mut *ledger;
    for (&id, follow) in follows.iter_mut() {
        let Some(entity) = follow.entity else {
            continue;
        };
        if follow.resyncing {
            continue;
        }
        let Ok(mut terrain) = terrains.get_mut(entity) else {
            continue;
        };
        if follow.waiting.first_key_value().map(|(&s, _)| s) != Some(follow.next_seq)
            && follow.predictions.refused.is_empty()
        {
            continue;
        }
        // Queued carves are requests, not changes of the content yet.
        let done = predict::hand_over(
            entity,
            terrain.bypass_change_detection(),
            &mut follow.waiting,
            &mut follow.next_seq,
            &mut follow.hashes,
            &mut follow.predictions,
            predicted,
            &mut rejected,
        );
        stats.carves += done.carves;
        stats.undos += done.undos.len() as u64;
        follow.undos.extend(done.undos);
        stats.predictions_confirmed += done.confirmed;
        stats.predictions_refused += done.refused;
        stats.rollbacks += done.rollbacks;
        stats.predictions_rolled_back += done.rolled_back;
        if done.confirmed > 0 {
            // A confirmed prediction may move the last request on.
            terrain.set_changed();
        }
        if done.needs_snapshot {
            stats.prediction_resyncs += 1;
            follow.resyncing = true;
            let seq = follow.next_seq.saturating_sub(1);
            warn!(
                "terrain {id}: more predictions to take back than its undo history holds; \
                 asking for a snapshot"
            );
            packets.write(ClientPacket::Request(ClientRequest::Desync {
                terrain: id,
                seq,
                hash: terrain.state_hash(),
            }));
        }
    }
}

/// Keeps the hash after each applied carve and compares it with the
/// server's checks; a difference asks for a snapshot.
fn compare_hashes(
    mut applied: MessageReader<CarveApplied>,
    mut refused: MessageReader<CarveRejected>,
    mut ledger: ResMut<ClientLedger>,
    mut stats: ResMut<NetClientStats>,
    mut terrains: Query<(&NetTerrain, &mut Terrain)>,
    mut packets: MessageWriter<ClientPacket>,
    mut desynced: MessageWriter<Desynced>,
) {
    let refused: Vec<&CarveRejected> = refused.read().collect();
    let predicted = (refused.iter()).filter_map(|r| Some((r.terrain, r.predicted?, None)));
    let reports: Vec<(Entity, Option<u64>, Option<u64>, Option<u64>)> = applied
        .read()
        .filter(|r| r.edit.is_some() || r.predicted.is_none())
        .map(|r| (r.terrain, r.request, r.predicted, Some(r.hash)))
        .chain(predicted.map(|(e, n, h)| (e, None, Some(n), h)))
        .collect();
    for (entity, request, number, hash) in reports {
        let Ok((id, mut terrain)) = terrains.get_mut(entity) else {
            continue;
        };
        let Some(follow) = ledger.terrains.get_mut(&id.0) else {
            continue;
        };
        let seq_hash = match (request, number) {
            (Some(seq), _) => hash.map(|h| (seq, h)),
            (None, Some(number)) => {
                // A prediction's job: its hash is the server carve's once
                // confirmed.
                let confirmed = predict::reported(
                    terrain.bypass_change_detection(),
                    &mut follow.predictions,
                    number,
                    hash,
                );
                confirmed.and_then(|(seq, hash)| Some((seq, hash?)))
            }
            (None, None) => None,
        };
        if let Some((seq, hash)) = seq_hash {
            follow.undos.remove(&seq);
            follow.hashes.insert(seq, hash);
            while follow.hashes.len() > KEPT_HASHES {
                follow.hashes.pop_first();
            }
        }
    }
    for report in &refused {
        // The server's undo (or redo), which this terrain could not apply:
        // its history is shorter than the server's there.
        let (Some(seq), Ok((id, terrain))) = (report.request, terrains.get(report.terrain)) else {
            continue;
        };
        let Some(follow) = ledger.terrains.get_mut(&id.0) else {
            continue;
        };
        if follow.undos.remove(&seq) && !follow.resyncing {
            stats.undo_resyncs += 1;
            follow.resyncing = true;
            warn!(
                "terrain {}: undo {seq} of the server's order is not in this client's undo \
                 history ({}); asking for a snapshot",
                id.0, report.error
            );
            packets.write(ClientPacket::Request(ClientRequest::Desync {
                terrain: id.0,
                seq,
                hash: terrain.state_hash(),
            }));
        }
    }
    for (&id, follow) in &mut ledger.terrains {
        let (Some((seq, server)), Some(entity)) = (follow.check, follow.entity) else {
            continue;
        };
        if follow.resyncing {
            follow.check = None;
            continue;
        }
        let Some(&local) = follow.hashes.get(&seq) else {
            // Not applied yet (kept until a newer check replaces it), or
            // older than what is kept.
            if follow
                .hashes
                .first_key_value()
                .is_some_and(|(&s, _)| s > seq)
            {
                follow.check = None;
            }
            continue;
        };
        follow.check = None;
        if local == server {
            stats.checks_passed += 1;
            continue;
        }
        stats.desyncs += 1;
        follow.resyncing = true;
        warn!(
            "terrain {id}: hash {local:#018x} after carve {seq}, server has {server:#018x}; \
             asking for a snapshot"
        );
        desynced.write(Desynced {
            terrain: entity,
            seq,
            local,
            server,
        });
        packets.write(ClientPacket::Request(ClientRequest::Desync {
            terrain: id,
            seq,
            hash: local,
        }));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_assemble_in_order_and_a_stray_part_drops_the_snapshot() {
        let bytes: Vec<u8> = (0..=255).collect();
        let parts: Vec<(u64, &[u8])> = super::super::wire::snapshot_parts(&bytes, 100).collect();
        assert_eq!(
            parts.iter().map(|(o, p)| (*o, p.len())).collect::<Vec<_>>(),
            vec![(0, 100), (100, 100), (200, 56)]
        );
        let mut slot = None;
        for (i, (offset, part)) in parts.iter().enumerate() {
            match assemble(&mut slot, 7, 256, *offset, part) {
                Assembled::Partial => assert!(i < 2, "part {i}"),
                Assembled::Whole(seq, whole) => {
                    assert_eq!((i, seq), (2, 7));
                    assert_eq!(whole, bytes);
                }
                Assembled::Dropped(why) => panic!("part {i}: {why}"),
            }
        }
        assert!(slot.is_none());
        // A part of another snapshot, or at the wrong offset, drops it.
        assert!(matches!(
            assemble(&mut slot, 8, 256, 0, parts[0].1),
            Assembled::Partial
        ));
        assert!(matches!(
            assemble(&mut slot, 9, 256, 100, parts[1].1),
            Assembled::Dropped(_)
        ));
        assert!(slot.is_none());
        // A part without its start is ignored; an oversize one dropped.
        assert!(matches!(
            assemble(&mut slot, 8, 256, 100, parts[1].1),
            Assembled::Partial
        ));
        assert!(matches!(
            assemble(&mut slot, 8, MAX_SNAPSHOT_BYTES + 1, 0, &[]),
            Assembled::Dropped(_)
        ));
    }
}
