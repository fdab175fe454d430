//! Undo and redo of replicated terrains: an [`UndoCarve`] or [`RedoCarve`]
//! of a [`NetTerrain`] is an op in the terrain's order, like a carve.
//!
//! - **Server** (and host, and single player): the app's own undo is
//!   numbered in the terrain's order at once (the authority may undo any
//!   carve), queued on the terrain with its number and sent to every
//!   client as a [`NetUndo`]; the server's hash after it is checked like
//!   a carve's ([`ServerPacket::Check`]). With nothing to undo (or redo)
//!   the terrain is unchanged and a [`CarveRejected`] says so, as without
//!   the network.
//! - **Client**: the game's [`UndoCarve`] or [`RedoCarve`] becomes a
//!   request ([`ClientRequest::Undo`]), rate limited like a carve
//!   ([`super::NetLimits::carves_per_second`]) and allowed or refused by
//!   [`super::NetLimits::undo`] ([`UndoPolicy`]); the answer comes back as
//!   a [`NetUndoResult`]. The undo itself is not predicted: it shows once
//!   the server's [`NetUndo`] arrives, in order.
//!
//! A client applies each [`NetUndo`] exactly as the server did: its undo
//! history holds the same steps as the server's for every carve since its
//! snapshot (the snapshot carries [`Terrain::max_undo`], so a client keeps
//! as many steps as the server), and the redo steps of the undos since.
//! Pending predictions are rolled back first and applied again on top
//! (module [`super::predict`]). Where a client cannot apply it (the step
//! is older than its snapshot, or was pushed out by its predictions) the
//! terrain refuses it, and the client asks for a snapshot
//! ([`super::NetClientStats::undo_resyncs`]): it never goes on out of
//! step.
//!
//! So a client can take part in undos as deep as the carves since it
//! joined, up to the server's [`Terrain::max_undo`]; a game that lets its
//! players undo `n` steps, while each predicts up to `k` carves, gives the
//! server's terrain `n + k` steps or more.

use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use bevy::prelude::*;
use bevy_replicon::prelude::*;

use super::wire::{ClientPacket, ClientRequest, NetTerrain, NetUndo, Outcome, RejectReason};
use super::wire::{ServerPacket, TerrainId};
use crate::terrain::jobs::Job;
use crate::terrain::{CarveRejected, RedoCarve, Terrain, TerrainError, UndoCarve};

/// Who may undo and redo what on a server's replicated terrains
/// ([`super::NetLimits::undo`]). The server's own app (a dedicated
/// server's game, a listen-server host, a single player) is the authority
/// and may always undo; this decides for remote clients.
#[derive(Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Default)]
pub enum UndoPolicy {
    /// No client may undo or redo ([`RejectReason::UndoForbidden`]).
    Nobody,
    /// A client may undo the terrain's most recent undoable carve only if
    /// that carve was its own request, and redo the most recent undone
    /// carve only if it was its own; otherwise
    /// [`RejectReason::NotYourCarve`]. The default: in a shared sandbox no
    /// player takes back another's work.
    #[default]
    OwnLatest,
    /// Any client may undo the most recent undoable carve and redo the
    /// most recent undone one, whoever made it (a co-op editor).
    Anyone,
}

/// The answer to a client's [`UndoCarve`] or [`RedoCarve`] of a
/// replicated terrain (or to the server's own, when refused).
#[derive(Message, Reflect, Clone, Debug, PartialEq, Eq)]
#[reflect(from_reflect = false)]
pub struct NetUndoResult {
    /// The local terrain entity.
    pub terrain: Entity,
    /// A redo rather than an undo.
    pub redo: bool,
    /// [`Outcome::Applied`] with the undo's place in the terrain's order
    /// (it shows once the client has applied it), or why it was refused.
    #[reflect(ignore)]
    pub outcome: Outcome,
}

/// The server's account of a terrain's undo history, as it will be once
/// every op numbered so far is applied: who made each undoable carve and
/// each redoable one, most recent last.
#[derive(Default)]
pub(super) struct UndoModel {
    seeded: bool,
    undo: VecDeque<(u64, ClientId)>,
    redo: Vec<(u64, ClientId)>,
}

impl UndoModel {
    /// Takes the terrain's steps from before the server kept account
    /// (the server's own, numbered 0), once.
    pub(super) fn seed(&mut self, terrain: &Terrain) {
        if !self.seeded {
            self.seeded = true;
            self.undo = (0..terrain.undo_depth())
                .map(|_| (0, ClientId::Server))
                .collect();
            self.redo = (0..terrain.redo_depth())
                .map(|_| (0, ClientId::Server))
                .collect();
        }
    }

    /// Carve `seq` by `owner` was numbered.
    pub(super) fn carve(&mut self, seq: u64, owner: ClientId, max_undo: usize) {
        self.undo.push_back((seq, owner));
        while self.undo.len() > max_undo {
            self.undo.pop_front();
        }
        self.redo.clear();
    }

    /// Carve `seq` was refused by the kernel: it left no step.
    pub(super) fn refused(&mut self, seq: u64) {
        self.undo.retain(|&(s, _)| s != seq);
    }

    /// Whether `client` may undo (or redo) now under `policy`.
    pub(super) fn check(
        &self,
        client: ClientId,
        redo: bool,
        policy: UndoPolicy,
    ) -> Result<(), RejectReason> {
        let top = if redo {
            self.redo.last().ok_or(RejectReason::NothingToRedo)?
        } else {
            self.undo.back().ok_or(RejectReason::NothingToUndo)?
        };
        match policy {
            _ if client == ClientId::Server => Ok(()),
            UndoPolicy::Nobody => Err(RejectReason::UndoForbidden),
            UndoPolicy::OwnLatest if top.1 != client => {
                Err(RejectReason::NotYourCarve { seq: top.0 })
            }
            UndoPolicy::OwnLatest | UndoPolicy::Anyone => Ok(()),
        }
    }

    /// An undo (or redo) was numbered.
    fn apply(&mut self, redo: bool, max_undo: usize) {
        if redo {
            if let Some(step) = self.redo.pop() {
                self.undo.push_back(step);
                while self.undo.len() > max_undo {
                    self.undo.pop_front();
                }
            }
        } else if let Some(step) = self.undo.pop_back() {
            self.redo.push(step);
        }
    }
}

/// Numbers an undo (or redo) of terrain `id` as op `next_seq + 1` of its
/// order, and queues it on `terrain` with that number: an op is queued in
/// the order it is numbered.
pub(super) fn order_undo(
    terrain: &mut Terrain,
    next_seq: &mut u64,
    model: &mut UndoModel,
    id: TerrainId,
    redo: bool,
) -> NetUndo {
    *next_seq = (*next_seq).max(terrain.last_request().unwrap_or(0)) + 1;
    let seq = *next_seq;
    model.apply(redo, terrain.max_undo());
    queue_undo(terrain, seq, redo);
    NetUndo {
        terrain: id,
        seq,
        redo,
    }
}

/// Queues undo (or redo) `seq` of the terrain's order on `terrain`.
pub(super) fn queue_undo(terrain: &mut Terrain, seq: u64, redo: bool) {
    let requested = Instant::now();
    let request = Some(seq);
    terrain.runtime.queue.push_back(if redo {
        Job::Redo { requested, request }
    } else {
        Job::Undo {
            requested,
            request,
            predicted: None,
        }
    });
}

/// The app's own undos and redos of its replicated terrains, in authority
/// (not a connected client): numbered, queued and broadcast at once; an
/// undo with nothing to undo is refused here ([`CarveRejected`] and
/// [`NetUndoResult`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn order_own_undos(
    mut undos: MessageReader<UndoCarve>,
    mut redos: MessageReader<RedoCarve>,
    mut terrains: Query<(&NetTerrain, &mut Terrain)>,
    mut ledger: ResMut<super::server::ServerLedger>,
    mut stats: ResMut<super::NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
    mut results: MessageWriter<NetUndoResult>,
    mut rejected: MessageWriter<CarveRejected>,
) {
    let undos = undos.read().map(|u| (u.terrain, false));
    let asked: Vec<(Entity, bool)> = undos
        .chain(redos.read().map(|r| (r.terrain, true)))
        .collect();
    for (entity, redo) in asked {
        let Ok((id, mut terrain)) = terrains.get_mut(entity) else {
            continue;
        };
        let order = ledger.terrains.entry(id.0).or_default();
        order.undo.seed(&terrain);
        if let Err(reason) = order.undo.check(ClientId::Server, redo, UndoPolicy::Anyone) {
            let error = if redo {
                TerrainError::NothingToRedo
            } else {
                TerrainError::NothingToUndo
            };
            rejected.write(CarveRejected {
                terrain: entity,
                request: None,
                predicted: None,
                error,
            });
            results.write(NetUndoResult {
                terrain: entity,
                redo,
                outcome: Outcome::Rejected(reason),
            });
            continue;
        }
        // A request, not a change of the terrain's content yet.
        let terrain = terrain.bypass_change_detection();
        let undo = order_undo(terrain, &mut order.next_seq, &mut order.undo, id.0, redo);
        order.broadcast_undo(undo, &mut stats, &mut out);
        results.write(NetUndoResult {
            terrain: entity,
            redo,
            outcome: Outcome::Applied { seq: undo.seq },
        });
    }
}

/// Most undo requests a client keeps waiting for their answers.
const KEPT_REQUESTS: usize = 1024;

/// A client's undo requests waiting for their answers: request id →
/// (terrain entity, redo).
#[derive(Resource, Default)]
pub(super) struct UndoRequests {
    next: u64,
    waiting: BTreeMap<u64, (Entity, bool)>,
}

/// Sends a client's undos and redos of its replicated terrains to the
/// server; one with no server to go to is answered
/// [`RejectReason::NotConnected`]. In authority (host, single player)
/// [`order_own_undos`] takes them instead.
#[allow(clippy::too_many_arguments)]
pub(super) fn send_undo_requests(
    mut undos: MessageReader<UndoCarve>,
    mut redos: MessageReader<RedoCarve>,
    terrains: Query<&NetTerrain>,
    state: Res<State<ClientState>>,
    server_side: Option<Res<super::server::ServerLedger>>,
    mut asked: ResMut<UndoRequests>,
    mut packets: MessageWriter<ClientPacket>,
    mut results: MessageWriter<NetUndoResult>,
) {
    let undos = undos.read().map(|u| (u.terrain, false));
    let all: Vec<(Entity, bool)> = undos
        .chain(redos.read().map(|r| (r.terrain, true)))
        .collect();
    if *state.get() == ClientState::Disconnected && server_side.is_some() {
        return;
    }
    let unsent = super::client::nowhere_to_send(state.get(), server_side.is_some());
    for (entity, redo) in all {
        let Ok(id) = terrains.get(entity) else {
            continue;
        };
        if unsent {
            results.write(NetUndoResult {
                terrain: entity,
                redo,
                outcome: Outcome::Rejected(RejectReason::NotConnected),
            });
            continue;
        }
        asked.next += 1;
        let request = asked.next;
        asked.waiting.insert(request, (entity, redo));
        while asked.waiting.len() > KEPT_REQUESTS {
            asked.waiting.pop_first();
        }
        packets.write(ClientPacket::Request(ClientRequest::Undo {
            request,
            terrain: id.0,
            redo,
        }));
    }
}

/// Turns the server's answers to a client's undo requests into
/// [`NetUndoResult`]s.
pub(super) fn receive_undo_results(
    mut packets: MessageReader<ServerPacket>,
    mut asked: ResMut<UndoRequests>,
    mut results: MessageWriter<NetUndoResult>,
) {
    for packet in packets.read() {
        if let ServerPacket::UndoResult { request, outcome } = packet
            && let Some((terrain, redo)) = asked.waiting.remove(request)
        {
            results.write(NetUndoResult {
                terrain,
                redo,
                outcome: outcome.clone(),
            });
        }
    }
}

/// Forgets the undo requests of a connection that ended.
pub(super) fn forget_undo_requests(mut asked: ResMut<UndoRequests>) {
    asked.waiting.clear();
}

/// Marks every replicated terrain's undos as the network's to take in
/// (the terrain plugin leaves them alone).
pub(super) fn on_net_terrain(add: On<Add, NetTerrain>, mut commands: Commands) {
    if let Ok(mut entity) = commands.get_entity(add.entity) {
        entity.insert(crate::terrain::queue::UndoRouted);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_policy_allows_a_client_only_its_own_latest_carve() {
        let (a, b) = (
            ClientId::Client(Entity::from_raw_u32(1).expect("valid")),
            ClientId::Client(Entity::from_raw_u32(2).expect("valid")),
        );
        let mut model = UndoModel::default();
        assert_eq!(
            model.check(a, false, UndoPolicy::OwnLatest),
            Err(RejectReason::NothingToUndo)
        );
        model.carve(1, a, 8);
        model.carve(2, b, 8);
        assert_eq!(
            model.check(a, false, UndoPolicy::OwnLatest),
            Err(RejectReason::NotYourCarve { seq: 2 })
        );
        assert_eq!(model.check(a, false, UndoPolicy::Anyone), Ok(()));
        assert_eq!(
            model.check(a, false, UndoPolicy::Nobody),
            Err(RejectReason::UndoForbidden)
        );
        assert_eq!(
            model.check(ClientId::Server, false, UndoPolicy::Nobody),
            Ok(())
        );
        model.apply(false, 8);
        assert_eq!(model.check(a, false, UndoPolicy::OwnLatest), Ok(()));
        assert_eq!(
            model.check(a, true, UndoPolicy::OwnLatest),
            Err(RejectReason::NotYourCarve { seq: 2 })
        );
        assert_eq!(model.check(b, true, UndoPolicy::OwnLatest), Ok(()));
        // A carve forgets the redo steps; one the kernel refused leaves
        // no step; the depth is bounded.
        model.carve(3, b, 2);
        assert_eq!(
            model.check(b, true, UndoPolicy::OwnLatest),
            Err(RejectReason::NothingToRedo)
        );
        model.refused(3);
        assert_eq!(
            model.check(a, false, UndoPolicy::OwnLatest),
            Ok(()),
            "carve 1 is on top again"
        );
        model.carve(4, b, 1);
        model.apply(false, 1);
        assert_eq!(
            model.check(b, false, UndoPolicy::Anyone),
            Err(RejectReason::NothingToUndo)
        );
    }
}
