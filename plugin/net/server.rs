//! The authoritative side: validates carve requests, orders them per
//! terrain, applies them through the terrain plugin, broadcasts accepted
//! carves with their sequence numbers, answers every request, sends hash
//! checks, and snapshots to clients that join or fall out of step.
//!
//! Per terrain, accepted carves and undos (module [`super::undo`]) are
//! numbered 1, 2, … and queued on the terrain as they are numbered, which
//! is the order the terrain applies them in. A carve is queued as a
//! [`GridCarve`](crate::terrain::GridCarve) whose request id is its
//! sequence number would be, an undo with its number likewise, so the
//! terrain's [`Terrain::last_request`] names the last op in its octree:
//! a snapshot taken at any moment holds exactly ops `1..=last_request`,
//! and the ops after it are kept in a log until the terrain has them.
//!
//! These systems hold the authority: they run while the app is no
//! connected client (`ClientState::Disconnected`), on a dedicated server,
//! on a listen-server host and in single player alike. The host's own
//! requests arrive from `ClientId::Server` (bevy_replicon writes a
//! client's messages locally while it is not connected); they are
//! validated and ordered like any client's, but not rate limited
//! ([`NetLimits`]). Accepted carves are broadcast to the remote clients
//! only: the host's terrain applies each carve once, here, and its
//! answers come back through bevy_replicon's local delivery.

use std::collections::{BTreeMap, HashMap};
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy_replicon::prelude::*;
use bevy_replicon::server::AuthorizedClient;

use super::undo::{UndoModel, UndoPolicy};
use super::wire::{
    ClientPacket, ClientRequest, NetCarve, NetTerrain, NetUndo, Outcome, RejectReason,
    ServerPacket, SnapshotPart, TerrainId, WirePose, WireTool,
};
use crate::terrain::jobs::Job;
use crate::terrain::{CarveApplied, CarveRejected, GridTool, Terrain, TerrainSystems};

/// What the server accepts from one client.
///
/// Every limit applies to every request, the host's own
/// (`ClientId::Server`: a listen-server host or single player) included,
/// but the rate ([`NetLimits::carves_per_second`], [`NetLimits::burst`]):
/// the host is the authority, and its game decides how fast its own player
/// carves.
#[derive(Resource, Reflect, Clone, Debug)]
#[reflect(Resource, Default)]
pub struct NetLimits {
    /// Most convex pieces in one tool.
    pub max_pieces: usize,
    /// Most points in one piece.
    pub max_points: usize,
    /// Largest extent of a tool along any axis, in world units.
    pub max_tool_extent: f64,
    /// Carves per second a remote client may keep up.
    pub carves_per_second: f64,
    /// Carves a remote client may send at once after a pause.
    pub burst: f64,
    /// How often the server sends its hashes for comparison.
    pub check_interval: Duration,
    /// Bytes of one snapshot part.
    pub snapshot_part_bytes: usize,
    /// Chunks of a networked world a carve may reach: those with
    /// `|x|` and `|z|` at most this ([`RejectReason::OutsideWorld`]
    /// beyond), so that no client makes the server build and keep chunks
    /// without bound.
    pub max_world_chunk: i64,
    /// Who may undo and redo what on the replicated terrains (module
    /// [`super::undo`]); a client's undo requests count against its rate
    /// of carves.
    pub undo: UndoPolicy,
}

impl Default for NetLimits {
    fn default() -> Self {
        Self {
            max_pieces: 16,
            max_points: 1024,
            max_tool_extent: 64.0,
            carves_per_second: 20.0,
            burst: 40.0,
            check_interval: Duration::from_millis(250),
            snapshot_part_bytes: 256 << 10,
            max_world_chunk: 1 << 16,
            undo: UndoPolicy::OwnLatest,
        }
    }
}

/// A request the server refused (also sent to the client).
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct RequestRejected {
    /// Who sent it.
    #[reflect(ignore)]
    pub client: ClientId,
    /// Its request id (`None` for a malformed packet).
    pub request: Option<u64>,
    /// Why.
    #[reflect(ignore)]
    pub reason: RejectReason,
}

/// A client reported that its terrain differs from the server's; it gets a
/// fresh snapshot.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct DesyncReported {
    /// The client.
    #[reflect(ignore)]
    pub client: ClientId,
    /// The terrain.
    pub terrain: TerrainId,
    /// The carve after which the hashes differ.
    pub seq: u64,
}

/// Counters of the server, for reports and benchmarks.
#[derive(Resource, Reflect, Clone, Debug, Default)]
#[reflect(Resource, Default)]
pub struct NetServerStats {
    /// Carves accepted and broadcast.
    pub accepted: u64,
    /// Requests refused, by validation or by the kernel.
    pub rejected: u64,
    /// Encoded bytes of every carve broadcast (one copy each).
    pub carve_bytes: u64,
    /// Snapshots sent.
    pub snapshots: u64,
    /// Encoded bytes of every snapshot sent.
    pub snapshot_bytes: u64,
    /// Undos and redos of replicated terrains ordered and broadcast
    /// (module [`super::undo`]).
    pub undos: u64,
}

/// One terrain's order of carves (and undos) on the server.
#[derive(Default)]
pub(super) struct Ledger {
    pub(super) next_seq: u64,
    /// Accepted carves and undos the terrain may not have applied yet.
    log: BTreeMap<u64, ServerPacket>,
    /// Who asked for which accepted carve.
    pending: HashMap<u64, (ClientId, u64)>,
    /// The latest applied carve and the hash after it.
    latest: Option<(u64, u64)>,
    /// The last carve whose hash was sent.
    checked: Option<u64>,
    /// Who made the carves its undos and redos would take back.
    pub(super) undo: UndoModel,
}

impl Ledger {
    /// Keeps an ordered undo until the terrain has it, and sends it to
    /// every client.
    pub(super) fn broadcast_undo(
        &mut self,
        undo: NetUndo,
        stats: &mut NetServerStats,
        out: &mut MessageWriter<ToClients<ServerPacket>>,
    ) {
        let packet = ServerPacket::Undo(undo);
        self.log.insert(undo.seq, packet.clone());
        stats.undos += 1;
        out.write(ToClients {
            targets: SendTargets::CLIENTS_ONLY,
            message: packet,
        });
    }
}

/// A client's allowance of carves (a token bucket).
struct Allowance {
    tokens: f64,
    at: Instant,
}

#[derive(Resource, Default)]
pub(super) struct ServerLedger {
    pub(super) terrains: HashMap<TerrainId, Ledger>,
    allowance: HashMap<ClientId, Allowance>,
    /// Clients that need a snapshot of every terrain.
    joining: Vec<ClientId>,
    last_check: Option<Instant>,
}

/// The server side of networked carving: add it with `RepliconPlugins`
/// and `RepliconRenetPlugins` (see [`super::NetProtocolPlugin`]) and put a
/// [`NetTerrain`] on each terrain to replicate; start listening with
/// [`super::start_server`].
///
/// Add it with [`super::NetClientPlugin`] to pick the role at run time
/// (module docs, "Roles"): its systems run whenever the app is not a
/// connected client.
///
/// A dedicated server draws nothing: set [`TerrainSettings::output`] to
/// [`CellOutput::Nothing`] (or [`CellOutput::Colliders`] where it runs
/// physics) so that its terrains build no cell meshes. Its octrees and
/// state hashes stay those of the clients that mesh, and it sustains about
/// twice the carves (BENCHMARKS.md, "Multiplayer carving").
///
/// [`TerrainSettings::output`]: crate::terrain::TerrainSettings::output
/// [`CellOutput::Nothing`]: crate::terrain::CellOutput::Nothing
/// [`CellOutput::Colliders`]: crate::terrain::CellOutput::Colliders
pub struct NetServerPlugin;

impl Plugin for NetServerPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<super::NetProtocolPlugin>() {
            app.add_plugins(super::NetProtocolPlugin);
        }
        app.init_resource::<NetLimits>()
            .init_resource::<NetServerStats>()
            .init_resource::<ServerLedger>()
            .add_message::<RequestRejected>()
            .add_message::<DesyncReported>()
            .register_type::<NetLimits>()
            .register_type::<NetServerStats>()
            .register_type::<RequestRejected>()
            .register_type::<DesyncReported>()
            .add_observer(on_authorized);
        super::world_server::build(app);
        app.add_systems(
            Update,
            (
                (
                    receive_requests,
                    super::undo::order_own_undos,
                    send_snapshots,
                )
                    .chain()
                    .before(TerrainSystems::Carve),
                report_results.after(TerrainSystems::Mesh),
            )
                .run_if(in_state(ClientState::Disconnected)),
        );
    }
}

fn on_authorized(add: On<Add, AuthorizedClient>, mut ledger: ResMut<ServerLedger>) {
    ledger.joining.push(ClientId::Client(add.entity));
}

/// Checks a request against the limits and the terrain, and rounds a
/// float tool to the grid: the one rounding of a carve.
fn validate(
    tool: &WireTool,
    edit: chisel_bsp::octree::Edit,
    terrain: &Terrain,
    limits: &NetLimits,
) -> Result<GridTool, RejectReason> {
    check_size(tool, limits)?;
    terrain.check_edit(edit).map_err(invalid)?;
    let grid = round_tool(tool, terrain.quantization())?;
    let built = check_grid_tool(&grid, terrain.quantization().unit(), limits)?;
    if !built.bounds().overlaps(&terrain.octree().root_box()) {
        return Err(RejectReason::Invalid(
            "the tool lies entirely outside the terrain's cube".into(),
        ));
    }
    Ok(grid)
}

/// A terrain error as the reason for refusing a request.
pub(super) fn invalid(e: crate::terrain::TerrainError) -> RejectReason {
    RejectReason::Invalid(e.to_string())
}

/// Checks a tool's pieces and points against the limits, before any
/// geometry is built.
pub(super) fn check_size(tool: &WireTool, limits: &NetLimits) -> Result<(), RejectReason> {
    let (pieces, points) = tool.size();
    if pieces > limits.max_pieces {
        return Err(RejectReason::TooManyPieces {
            pieces,
            limit: limits.max_pieces,
        });
    }
    if points > limits.max_points {
        return Err(RejectReason::TooManyPoints {
            points,
            limit: limits.max_points,
        });
    }
    Ok(())
}

/// The request's tool on `grid` ([`WireTool::to_grid`]: the one rounding
/// of a carve, shared with a predicting client).
pub(super) fn round_tool(
    tool: &WireTool,
    grid: &chisel_bsp::tools::Quantization,
) -> Result<GridTool, RejectReason> {
    tool.to_grid(grid)
}

/// Checks a grid tool's extent against the limit (`unit`: world units per
/// grid unit) and builds it (a degenerate or out-of-budget tool fails).
pub(super) fn check_grid_tool(
    grid: &GridTool,
    unit: f64,
    limits: &NetLimits,
) -> Result<chisel_bsp::octree::Tool, RejectReason> {
    let limit = (limits.max_tool_extent / unit).min(1e15) as i64;
    let extent = grid
        .pieces
        .iter()
        .filter_map(|piece| chisel_bsp::octree::CellBox::enclosing(piece.iter().copied()))
        .map(|b| {
            (0..3)
                .map(|a| b.max[a].saturating_sub(b.min[a]))
                .max()
                .unwrap_or(0)
        })
        .max()
        .unwrap_or(0);
    if extent > limit {
        return Err(RejectReason::TooLarge { extent, limit });
    }
    grid.build().map_err(invalid)
}

/// Whether `client` may send one more carve now: always for the host
/// (`ClientId::Server`), within its allowance for a remote client.
pub(super) fn allow(ledger: &mut ServerLedger, client: ClientId, limits: &NetLimits) -> bool {
    if client == ClientId::Server {
        return true;
    }
    let now = Instant::now();
    let allowance = ledger.allowance.entry(client).or_insert(Allowance {
        tokens: limits.burst,
        at: now,
    });
    let refill = now.duration_since(allowance.at).as_secs_f64() * limits.carves_per_second;
    allowance.tokens = (allowance.tokens + refill).min(limits.burst);
    allowance.at = now;
    if allowance.tokens >= 1.0 {
        allowance.tokens -= 1.0;
        true
    } else {
        false
    }
}

#[allow(clippy::too_many_arguments)]
fn receive_requests(
    mut packets: MessageReader<FromClient<ClientPacket>>,
    mut terrains: Query<(Entity, &NetTerrain, &mut Terrain)>,
    limits: Res<NetLimits>,
    mut ledger: ResMut<ServerLedger>,
    mut stats: ResMut<NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
    mut rejected: MessageWriter<RequestRejected>,
    mut desyncs: MessageWriter<DesyncReported>,
) {
    let ids: HashMap<TerrainId, Entity> = terrains.iter().map(|(e, id, _)| (id.0, e)).collect();
    for packet in packets.read() {
        let client = packet.client_id;
        let mut reject = |request: Option<u64>, reason: RejectReason, undo: bool| {
            let outcome = Outcome::Rejected(reason.clone());
            let message = match (undo, request) {
                (true, Some(request)) => ServerPacket::UndoResult { request, outcome },
                _ => ServerPacket::Result { request, outcome },
            };
            out.write(ToClients {
                targets: SendTargets::Single(client),
                message,
            });
            rejected.write(RequestRejected {
                client,
                request,
                reason,
            });
        };
        match &packet.message {
            ClientPacket::Malformed { reason } => {
                stats.rejected += 1;
                reject(None, RejectReason::Malformed(reason.clone()), false);
            }
            ClientPacket::Request(ClientRequest::Desync { terrain, seq, hash }) => {
                warn!(
                    "client {client} reports terrain {terrain} out of step after carve {seq} \
                     (its hash {hash:#018x}); sending a snapshot"
                );
                desyncs.write(DesyncReported {
                    client,
                    terrain: *terrain,
                    seq: *seq,
                });
                if !ledger.joining.contains(&client) {
                    ledger.joining.push(client);
                }
            }
            // World carves and checks: `super::world_server`.
            ClientPacket::Request(
                ClientRequest::CarveWorld { .. } | ClientRequest::WorldDesync { .. },
            ) => {}
            ClientPacket::Request(ClientRequest::Undo {
                request,
                terrain,
                redo,
            }) => {
                let (id, request) = (*request, Some(*request));
                if !allow(&mut ledger, client, &limits) {
                    stats.rejected += 1;
                    reject(request, RejectReason::RateLimited, true);
                    continue;
                }
                let Some(Ok((_, _, mut target))) = ids.get(terrain).map(|&e| terrains.get_mut(e))
                else {
                    stats.rejected += 1;
                    reject(request, RejectReason::UnknownTerrain(*terrain), true);
                    continue;
                };
                let order = ledger.terrains.entry(*terrain).or_default();
                order.undo.seed(&target);
                if let Err(reason) = order.undo.check(client, *redo, limits.undo) {
                    stats.rejected += 1;
                    reject(request, reason, true);
                    continue;
                }
                // A request, not a change of the terrain's content yet.
                let target = target.bypass_change_detection();
                let undo = super::undo::order_undo(
                    target,
                    &mut order.next_seq,
                    &mut order.undo,
                    *terrain,
                    *redo,
                );
                order.broadcast_undo(undo, &mut stats, &mut out);
                out.write(ToClients {
                    targets: SendTargets::Single(client),
                    message: ServerPacket::UndoResult {
                        request: id,
                        outcome: Outcome::Applied { seq: undo.seq },
                    },
                });
            }
            ClientPacket::Request(ClientRequest::Carve {
                request,
                terrain,
                tool,
                edit,
            }) => {
                let request = Some(*request);
                if !allow(&mut ledger, client, &limits) {
                    stats.rejected += 1;
                    reject(request, RejectReason::RateLimited, false);
                    continue;
                }
                let Some(Ok((_, _, mut target))) = ids.get(terrain).map(|&e| terrains.get_mut(e))
                else {
                    stats.rejected += 1;
                    reject(request, RejectReason::UnknownTerrain(*terrain), false);
                    continue;
                };
                let tool = match validate(tool, *edit, &target, &limits) {
                    Ok(tool) => tool,
                    Err(reason) => {
                        stats.rejected += 1;
                        reject(request, reason, false);
                        continue;
                    }
                };
                let order = ledger.terrains.entry(*terrain).or_default();
                order.undo.seed(&target);
                let base = target.last_request().unwrap_or(0);
                order.next_seq = order.next_seq.max(base) + 1;
                let seq = order.next_seq;
                order.undo.carve(seq, client, target.max_undo());
                let carve = NetCarve {
                    terrain: *terrain,
                    seq,
                    tool: tool.clone(),
                    edit: *edit,
                };
                let packet = ServerPacket::Carve(carve);
                order.log.insert(seq, packet.clone());
                if let Some(request) = request {
                    order.pending.insert(seq, (client, request));
                }
                // Queued at once, as a grid carve with its number would be
                // (its labels are checked): in the order it is numbered,
                // among the undos (module `super::undo`). A request, not a
                // change of the terrain's content yet.
                let queue = &mut target.bypass_change_detection().runtime.queue;
                queue.push_back(Job::Carve {
                    tool,
                    edit: *edit,
                    requested: Instant::now(),
                    request: Some(seq),
                    predicted: None,
                });
                stats.accepted += 1;
                stats.carve_bytes += postcard::to_allocvec(&packet).map_or(0, |b| b.len() as u64);
                out.write(ToClients {
                    targets: SendTargets::CLIENTS_ONLY,
                    message: packet,
                });
            }
        }
    }
}

/// Answers requests once the terrain applied or refused them, keeps the
/// latest hash per terrain and sends hash checks.
#[allow(clippy::too_many_arguments)]
fn report_results(
    mut applied: MessageReader<CarveApplied>,
    mut refused: MessageReader<CarveRejected>,
    terrains: Query<(&NetTerrain, &Terrain)>,
    limits: Res<NetLimits>,
    mut ledger: ResMut<ServerLedger>,
    mut stats: ResMut<NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
    mut rejected: MessageWriter<RequestRejected>,
) {
    for report in applied.read() {
        let (Some(seq), Ok((id, _))) = (report.request, terrains.get(report.terrain)) else {
            continue;
        };
        let order = ledger.terrains.entry(id.0).or_default();
        order.latest = Some((seq, report.hash));
        if let Some((client, request)) = order.pending.remove(&seq) {
            out.write(ToClients {
                targets: SendTargets::Single(client),
                message: ServerPacket::Result {
                    request: Some(request),
                    outcome: Outcome::Applied { seq },
                },
            });
        }
    }
    for report in refused.read() {
        let (Some(seq), Ok((id, _))) = (report.request, terrains.get(report.terrain)) else {
            continue;
        };
        let order = ledger.terrains.entry(id.0).or_default();
        order.undo.refused(seq);
        if let Some((client, request)) = order.pending.remove(&seq) {
            stats.rejected += 1;
            let reason = RejectReason::Invalid(report.error.to_string());
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
        }
    }
    for (id, terrain) in &terrains {
        if let Some(order) = ledger.terrains.get_mut(&id.0) {
            let done = terrain.last_request().unwrap_or(0);
            order.log.retain(|&seq, _| seq > done);
        }
    }
    let now = Instant::now();
    if ledger
        .last_check
        .is_some_and(|at| now.duration_since(at) < limits.check_interval)
    {
        return;
    }
    ledger.last_check = Some(now);
    for (&terrain, order) in &mut ledger.terrains {
        if let Some((seq, hash)) = order.latest
            && order.checked != Some(seq)
        {
            order.checked = Some(seq);
            out.write(ToClients {
                targets: SendTargets::CLIENTS_ONLY,
                message: ServerPacket::Check { terrain, seq, hash },
            });
        }
    }
}

/// Sends every terrain's snapshot, then the carves it does not hold yet,
/// to the clients that joined or asked for one.
fn send_snapshots(
    terrains: Query<(&NetTerrain, &Terrain, Option<&Transform>)>,
    limits: Res<NetLimits>,
    mut ledger: ResMut<ServerLedger>,
    mut stats: ResMut<NetServerStats>,
    mut out: MessageWriter<ToClients<ServerPacket>>,
) {
    if ledger.joining.is_empty() {
        return;
    }
    let joining = std::mem::take(&mut ledger.joining);
    let mut snapshots = Vec::new();
    for (id, terrain, placed) in &terrains {
        let bytes = terrain.to_snapshot_bytes();
        let seq = terrain.last_request().unwrap_or(0);
        let pose = WirePose::from(&placed.copied().unwrap_or_default());
        let parts: Vec<SnapshotPart> =
            super::wire::snapshot_parts(&bytes, limits.snapshot_part_bytes)
                .map(|(offset, part)| SnapshotPart {
                    terrain: id.0,
                    seq,
                    total: bytes.len() as u64,
                    offset,
                    bytes: part.to_vec(),
                    pose,
                })
                .collect();
        let log: Vec<ServerPacket> = ledger
            .terrains
            .get(&id.0)
            .map(|order| order.log.range(seq + 1..).map(|(_, c)| c.clone()).collect())
            .unwrap_or_default();
        snapshots.push((bytes.len(), parts, log));
    }
    for client in joining {
        for (size, parts, log) in &snapshots {
            stats.snapshots += 1;
            stats.snapshot_bytes += *size as u64;
            for part in parts {
                out.write(ToClients {
                    targets: SendTargets::Single(client),
                    message: ServerPacket::Snapshot(part.clone()),
                });
            }
            for op in log {
                out.write(ToClients {
                    targets: SendTargets::Single(client),
                    message: op.clone(),
                });
            }
        }
    }
}
