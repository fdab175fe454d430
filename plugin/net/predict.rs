//! Client-side prediction of a client's own carves
//! ([`NetClientSettings::predict_own_carves`]).
//!
//! A connected client that sends a [`super::NetCarveRequest`] for a
//! [`super::NetTerrain`] rounds the tool on the terrain's own grid, with
//! the server's rounding ([`super::WireTool::to_grid`]), and queues it on
//! its terrain at once as a *prediction*: the crater shows after the
//! client's own carve job, not after a round trip to the server. Exact
//! integer carving makes a confirmed prediction free: the client's
//! octree is bit-identical to the server's, so nothing is corrected.
//!
//! The client keeps one invariant per terrain: its octree is the server's
//! state after the last server carve it took (`base`), with the pending
//! predictions `P1..Pk` applied on top, in order. When the server's carve
//! `base + 1` arrives:
//!
//! - equal to `P1` (same grid tool and edit, whoever sent it): *confirmed*.
//!   It is not applied again; `P1`'s hash is the hash after that carve
//!   for the server's checks, and [`Terrain::last_request`] moves to it.
//! - otherwise: *rolled back*. The `k` predictions are taken back (those
//!   whose jobs have not started are taken off the queue, the others
//!   undone, newest first), the server's carve applied, and `P1..Pk`
//!   queued again on top of it. The terrain's undo history must hold them:
//!   with [`Terrain::max_undo`] under `k` the client drops its
//!   predictions and asks for a snapshot instead, as after a desync.
//!
//! The server's undo or redo (module [`super::undo`]) matches no
//! prediction: the predictions are rolled back the same way, the undo
//! applied, and they are queued again on top of it. A prediction's undo
//! step keeps the redo steps its carve cleared, so that a roll back leaves
//! them as they were for the server's redos; a confirmed prediction's
//! step is undone (and redone) by the server's order like any carve's.
//! The undo itself is never predicted.
//!
//! A [`RejectReason`](super::RejectReason) answer for a request whose
//! prediction is pending rolls the predictions back the same way, without
//! that one (the oldest pending prediction of that request id: a game
//! that predicts gives its requests distinct ids). A snapshot (join or resync) and leaving `Connected` drop
//! every prediction (a snapshot replaces the terrain).
//!
//! Debris: a prediction's carve may cut pieces loose, which spawn as
//! [`crate::terrain::TerrainDebris`] bodies like any carve's, their
//! [`DebrisDetached::predicted`] naming the prediction. An undo puts the
//! solid back in the octree but despawns nothing by itself, so when a roll
//! back undoes a prediction, the client despawns the bodies that
//! prediction cut loose; applied again, it cuts them loose anew. A body
//! that fell or moved meanwhile disappears where it is.
//! A confirmed prediction's bodies stay: they are the server's carve's.
//!
//! The game tells predictions apart through [`CarveApplied::predicted`]:
//! `Some` on a prediction's carve and on the undo of a roll back.
//!
//! [`CarveApplied::predicted`]: crate::terrain::CarveApplied::predicted

use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use bevy::prelude::*;
use chisel_bsp::octree::Edit;

use super::wire::{NetCarve, NetUndo};
use crate::terrain::jobs::Job;
use crate::terrain::{CarveApplied, CarveRejected, DebrisDetached, GridTool, Terrain};

/// How a client treats its own requests.
#[derive(Resource, Reflect, Clone, Debug, Default)]
#[reflect(Resource, Default)]
pub struct NetClientSettings {
    /// Whether a connected client applies its own carve requests on its
    /// terrains at once, ahead of the server, and reconciles them with the
    /// server's order when it arrives (module [`super::predict`]). Off by
    /// default: a game turns it on where the player should see their own
    /// craters without the round trip. A host and a single player never
    /// predict: their own server applies their carves at once.
    pub predict_own_carves: bool,
}

/// Most predictions whose debris bodies are remembered for a roll back.
const KEPT_DEBRIS: usize = 256;

/// The debris bodies each recent prediction cut loose.
#[derive(Resource, Default)]
pub(super) struct PredictedDebris(BTreeMap<u64, Vec<Entity>>);

/// Despawns the debris bodies of predictions a roll back undid.
pub(super) fn take_back_debris(
    mut detached: MessageReader<DebrisDetached>,
    mut applied: MessageReader<CarveApplied>,
    mut bodies: ResMut<PredictedDebris>,
    mut commands: Commands,
) {
    for piece in detached.read() {
        if let Some(number) = piece.predicted {
            bodies.0.entry(number).or_default().push(piece.entity);
        }
    }
    for report in applied.read() {
        if let (None, Some(number)) = (report.edit, report.predicted)
            && let Some(entities) = bodies.0.remove(&number)
        {
            for entity in entities {
                if let Ok(mut body) = commands.get_entity(entity) {
                    body.try_despawn();
                }
            }
        }
    }
    while bodies.0.len() > KEPT_DEBRIS {
        bodies.0.pop_first();
    }
}

/// A carve applied ahead of the server.
pub(super) struct Prediction {
    /// The request id the game chose.
    pub request: u64,
    /// The tool as the server will round it.
    pub tool: GridTool,
    /// The edit.
    pub edit: Edit,
    /// The number of its current application ([`Job::Carve`]).
    pub number: u64,
    /// `None` until its job reports: then the hash after it, or `None`
    /// when the kernel refused it.
    pub outcome: Option<Option<u64>>,
}

/// A terrain's predictions.
#[derive(Default)]
pub(super) struct Predictions {
    /// Applied (or queued) on top of the server's state, oldest first.
    pub pending: VecDeque<Prediction>,
    /// Confirmed predictions whose jobs have not reported yet: their
    /// number and the server carve they are.
    pub confirmed: BTreeMap<u64, u64>,
    /// Requests the server refused since the last hand over.
    pub refused: Vec<u64>,
}

/// An op of a terrain's order, received and waiting for its turn.
pub(super) enum Op {
    /// A carve.
    Carve(NetCarve),
    /// An undo or redo (module [`super::undo`]).
    Undo(NetUndo),
}

/// What [`hand_over`] did to one terrain.
#[derive(Default)]
pub(super) struct HandedOver {
    /// Server carves queued.
    pub carves: u64,
    /// Server undos and redos queued, by their place in the order.
    pub undos: Vec<u64>,
    /// Predictions confirmed.
    pub confirmed: u64,
    /// Predictions refused by the server and taken off.
    pub refused: u64,
    /// Roll backs (each takes back every pending prediction).
    pub rollbacks: u64,
    /// Predictions taken back in them.
    pub rolled_back: u64,
    /// The undo history cannot hold the predictions to take back: they
    /// are dropped, and the terrain needs a snapshot.
    pub needs_snapshot: bool,
}

/// Queues `tool` with `edit` on `terrain` as prediction `number` of
/// request `request`.
pub(super) fn predict(
    terrain: &mut Terrain,
    predictions: &mut Predictions,
    number: u64,
    request: u64,
    tool: GridTool,
    edit: Edit,
) {
    push_prediction(terrain, number, &tool, edit);
    predictions.pending.push_back(Prediction {
        request,
        tool,
        edit,
        number,
        outcome: None,
    });
}

fn push_prediction(terrain: &mut Terrain, number: u64, tool: &GridTool, edit: Edit) {
    terrain.runtime.queue.push_back(Job::Carve {
        tool: tool.clone(),
        edit,
        requested: Instant::now(),
        request: None,
        predicted: Some(number),
    });
}

/// Queues the server's carve on `terrain`, tracked by its sequence number
/// (as a [`crate::terrain::GridCarve`] would be): in place in the queue,
/// before any prediction queued after it.
fn push_carve(
    entity: Entity,
    terrain: &mut Terrain,
    carve: NetCarve,
    rejected: &mut MessageWriter<CarveRejected>,
) {
    if let Err(error) = terrain.check_label(carve.edit) {
        // As `read_requests` answers a grid carve: the server checked the
        // same labels, so only a damaged terrain gets here (its next hash
        // check asks for a snapshot).
        rejected.write(CarveRejected {
            terrain: entity,
            request: Some(carve.seq),
            predicted: None,
            error,
        });
        return;
    }
    terrain.runtime.queue.push_back(Job::Carve {
        tool: carve.tool,
        edit: carve.edit,
        requested: Instant::now(),
        request: Some(carve.seq),
        predicted: None,
    });
}

/// Takes every pending prediction off `terrain`: those whose jobs have
/// not started off the queue, the others by undo, newest first. Returns
/// `false` (and changes nothing) when the undo history may not hold them.
fn lift(terrain: &mut Terrain, predictions: &Predictions) -> bool {
    let pending = &predictions.pending;
    if pending.len() > terrain.max_undo() {
        return false;
    }
    let mut applied = pending.len();
    let queue = &mut terrain.runtime.queue;
    while applied > 0
        && matches!(
            queue.back(),
            Some(Job::Carve { predicted: Some(n), .. }) if *n == pending[applied - 1].number
        )
    {
        queue.pop_back();
        applied -= 1;
    }
    for prediction in pending.iter().take(applied).rev() {
        queue.push_back(Job::Undo {
            requested: Instant::now(),
            request: None,
            predicted: Some(prediction.number),
        });
    }
    true
}

/// Confirmed prediction `prediction` is server carve `seq`: its hash is
/// the hash after `seq`, and the terrain's last request moves on to it,
/// now when its job has reported, or when it does ([`reported`]).
fn settle(
    terrain: &mut Terrain,
    predictions: &mut Predictions,
    hashes: &mut BTreeMap<u64, u64>,
    prediction: &Prediction,
    seq: u64,
) {
    match prediction.outcome {
        Some(hash) => {
            if let Some(hash) = hash {
                hashes.insert(seq, hash);
            }
            if terrain.last_request < Some(seq) {
                terrain.last_request = Some(seq);
            }
        }
        None => {
            predictions.confirmed.insert(prediction.number, seq);
        }
    }
}

/// The job of prediction `number` reported: the hash after it (`None`:
/// the kernel refused it). Returns the server carve it is, with the hash,
/// when it was confirmed already (the caller keeps that hash).
pub(super) fn reported(
    terrain: &mut Terrain,
    predictions: &mut Predictions,
    number: u64,
    hash: Option<u64>,
) -> Option<(u64, Option<u64>)> {
    if let Some(p) = predictions.pending.iter_mut().find(|p| p.number == number) {
        p.outcome = Some(hash);
        return None;
    }
    let seq = predictions.confirmed.remove(&number)?;
    if terrain.last_request < Some(seq) {
        terrain.last_request = Some(seq);
    }
    Some((seq, hash))
}

/// Takes the pending predictions off once per hand over ([`lift`]),
/// counting the roll back.
struct Lifter {
    lifted: bool,
}

impl Lifter {
    fn lift(
        &mut self,
        terrain: &mut Terrain,
        predictions: &Predictions,
        done: &mut HandedOver,
    ) -> bool {
        if self.lifted {
            return true;
        }
        if !lift(terrain, predictions) {
            return false;
        }
        self.lifted = true;
        done.rollbacks += 1;
        done.rolled_back += predictions.pending.len() as u64;
        true
    }
}

/// Hands the waiting server carves, from `next_seq` on and without gaps,
/// to `terrain` (entity `entity`), reconciling them with its predictions
/// (module docs); then takes off the predictions the server refused.
#[allow(clippy::too_many_arguments)]
pub(super) fn hand_over(
    entity: Entity,
    terrain: &mut Terrain,
    waiting: &mut BTreeMap<u64, Op>,
    next_seq: &mut u64,
    hashes: &mut BTreeMap<u64, u64>,
    predictions: &mut Predictions,
    next_number: &mut u64,
    rejected: &mut MessageWriter<CarveRejected>,
) -> HandedOver {
    let mut done = HandedOver::default();
    let mut lifter = Lifter { lifted: false };
    let mut failed = false;
    while !failed && let Some(op) = waiting.get(next_seq) {
        // An undo matches no prediction: they are rolled back, the undo
        // applied, and they go on top again, as after another's carve.
        let matches = match op {
            Op::Carve(carve) => (predictions.pending.front())
                .is_some_and(|p| p.tool == carve.tool && p.edit == carve.edit),
            Op::Undo(_) => false,
        };
        if !matches
            && !predictions.pending.is_empty()
            && !lifter.lift(terrain, predictions, &mut done)
        {
            failed = true;
            break;
        }
        let carve = match waiting.remove(next_seq) {
            None => break,
            Some(Op::Undo(undo)) => {
                *next_seq += 1;
                super::undo::queue_undo(terrain, undo.seq, undo.redo);
                done.undos.push(undo.seq);
                continue;
            }
            Some(Op::Carve(carve)) => carve,
        };
        *next_seq += 1;
        if matches {
            let Some(prediction) = predictions.pending.pop_front() else {
                continue;
            };
            if !lifter.lifted {
                // Already in the octree (or on its way): not applied again.
                done.confirmed += 1;
                settle(terrain, predictions, hashes, &prediction, carve.seq);
                continue;
            }
            // Taken back already: the server's carve takes its place.
        }
        push_carve(entity, terrain, carve, rejected);
        done.carves += 1;
    }
    // Refusals after the carves: those carves may confirm the
    // predictions before a refused one, which then need no roll back.
    for request in std::mem::take(&mut predictions.refused) {
        if failed {
            break;
        }
        let Some(at) = (predictions.pending.iter()).position(|p| p.request == request) else {
            continue;
        };
        if !lifter.lift(terrain, predictions, &mut done) {
            failed = true;
            break;
        }
        predictions.pending.remove(at);
        done.refused += 1;
    }
    if failed {
        // Left as it was; the snapshot replaces the terrain and the
        // carves after it come again.
        predictions.pending.clear();
        predictions.confirmed.clear();
        done.needs_snapshot = true;
        return done;
    }
    if lifter.lifted {
        for prediction in &mut predictions.pending {
            *next_number += 1;
            prediction.number = *next_number;
            prediction.outcome = None;
            push_prediction(
                terrain,
                prediction.number,
                &prediction.tool,
                prediction.edit,
            );
        }
    }
    done
}
