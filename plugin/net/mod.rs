//! Multiplayer carving (feature `net`): one authoritative server, any
//! number of clients, every peer with bit-identical terrain.
//!
//! Exact integer carving gives the same octree on every machine, so only
//! carves travel, never meshes: a client sends a request
//! ([`NetCarveRequest`]), the server validates it (size limits, the
//! terrain's materials, the grid's bit budget, a rate limit per client),
//! rounds it to the grid once, numbers it in its terrain's order and sends
//! the integer carve ([`NetCarve`]) to every client, which applies the
//! carves strictly in that order. A client that joins gets each terrain's
//! snapshot ([`crate::terrain::Terrain::to_snapshot_bytes`]: the exact
//! octree and the rules a carve depends on, without the journal) and then
//! the carves after it. The server sends its state hash ([`crate::terrain::Terrain::state_hash`])
//! every [`NetLimits::check_interval`]; a client whose hash after the same
//! carve differs reports it and gets a fresh snapshot. Undos and redos
//! ([`crate::terrain::UndoCarve`], [`crate::terrain::RedoCarve`]) of a
//! networked terrain are ops of the same order ([`undo`]): the server's
//! reach every client, a client's are requests the server's
//! [`UndoPolicy`] allows or refuses.
//!
//! ## Roles
//!
//! A game adds both [`NetServerPlugin`] and [`NetClientPlugin`] to one
//! binary and picks its role at run time, as bevy_replicon recommends; it
//! writes the same [`NetCarveRequest`]s and [`NetWorldCarveRequest`]s and
//! reads the same [`NetCarveResult`]s in every role:
//!
//! - **Client** ([`start_client`]): requests go to the server; the server's
//!   carves are applied in its order, its hashes compared, its snapshots
//!   installed.
//! - **Listen-server host** ([`start_server`], the app's own player carves
//!   too): the host's requests come to its own server side as those of
//!   `ClientId::Server` (bevy_replicon writes a client's messages locally
//!   while it is not connected), are validated, rounded once, ordered and
//!   broadcast to the remote clients like any client's, and its terrains
//!   apply each carve once; its answers come back the same way. The host
//!   is not rate limited (it is the authority; [`NetLimits`]), every other
//!   limit applies.
//! - **Single player** (neither): the same, with nobody to broadcast to.
//!
//! The server side runs while the app is no connected client
//! (`ClientState::Disconnected`, replicon's condition for authority); the
//! following of a server only while connected (`ClientState::Connected`),
//! so a host never follows its own carves. A request with no server to go
//! to (written while connecting, or while disconnected in an app without
//! [`NetServerPlugin`]) is answered [`RejectReason::NotConnected`]. A dedicated
//! server adds [`NetServerPlugin`] alone, a client-only build
//! [`NetClientPlugin`] alone. A single player may start hosting at any
//! time: its order of carves goes on and joining clients get snapshots. A
//! peer that was a client and then hosts should spawn its terrains and
//! worlds anew, since theirs hold another server's order.
//!
//! Transport: `bevy_replicon` messages over `bevy_replicon_renet`'s netcode
//! UDP transport: unsecured ([`start_server`], [`start_client`]) for a LAN,
//! development and tests, or with signed connect tokens and encrypted
//! traffic ([`start_secure_server`], [`connect_token`],
//! [`start_secure_client`]) for a public server.
//!
//! - [`wire`] — the messages and their encoding.
//! - [`server`] — [`NetServerPlugin`]: validation, order, broadcast,
//!   checks, snapshots.
//! - [`client`] — [`NetClientPlugin`]: requests, ordered application,
//!   snapshots, hash comparison.
//! - [`predict`] — [`NetClientSettings`]: a client's own carves applied
//!   ahead of the server, confirmed or rolled back when its order comes.
//! - [`undo`] — [`UndoPolicy`]: undos and redos of replicated terrains
//!   in their order of carves; a client's are requests.
//! - [`secure`] — connect tokens and the secure transport.
//! - [`world`] — streamed worlds ([`crate::terrain::TerrainWorld`]) with a
//!   [`NetWorld`]: world carves in order, edited chunks in snapshots,
//!   each chunk's hash checked; [`world_server`] and
//!   [`world_client`] are its two sides.

pub mod client;
pub mod predict;
pub mod secure;
pub mod server;
pub mod undo;
pub mod wire;
pub mod world;
pub mod world_client;
pub mod world_server;

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::time::SystemTime;

use bevy::prelude::*;
use bevy::state::app::StatesPlugin;
use bevy_replicon::prelude::*;
use bevy_replicon_renet::netcode::{
    ClientAuthentication, NetcodeClientTransport, NetcodeServerTransport, ServerAuthentication,
    ServerConfig,
};
use bevy_replicon_renet::renet::ConnectionConfig;
use bevy_replicon_renet::{RenetChannelsExt, RenetClient, RenetServer, RepliconRenetPlugins};

pub use client::{
    Desynced, NetCarveRequest, NetCarveResult, NetClientPlugin, NetClientStats, TerrainSynced,
};
pub use predict::NetClientSettings;
pub use secure::{
    ConnectTokenError, NetKey, connect_token, read_connect_token, start_secure_client,
    start_secure_server,
};
pub use server::{DesyncReported, NetLimits, NetServerPlugin, NetServerStats, RequestRejected};
pub use undo::{NetUndoResult, UndoPolicy};
pub use wire::{
    ChunkCheck, ChunkSnapshotPart, ClientPacket, ClientRequest, NetCarve, NetTerrain, NetUndo,
    NetWorld, NetWorldCarve, Outcome, RejectReason, ServerPacket, SnapshotPart, TerrainId,
    WirePiece, WirePose, WireShape, WireTool, WorldId, WorldSnapshotPart,
};
pub use world::world_state_hash;
pub use world_client::{NetWorldCarveRequest, WorldDesynced, WorldSynced};

/// The netcode protocol id of this wire format: peers with another id do
/// not connect.
pub const PROTOCOL_ID: u64 = 0xC415_E100_0000_0004;

/// Most bytes a peer keeps in flight on one channel (snapshots and large
/// hull requests are single messages of a few megabytes at most).
pub const CHANNEL_MEMORY_BYTES: usize = 64 << 20;

/// Bytes a peer may send per update: 96 KiB, under what a default Linux
/// UDP receive buffer holds, so that a burst (a snapshot, a large request)
/// is not dropped by the receiving socket and resent; at 60 updates a
/// second, 5.9 MB/s.
pub const BYTES_PER_UPDATE: u64 = 96 << 10;

/// Replicon and its renet backend (added once), `StatesPlugin` when
/// missing, and the messages, registered in the same order on every peer.
pub struct NetProtocolPlugin;

impl Plugin for NetProtocolPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<StatesPlugin>() {
            app.add_plugins(StatesPlugin);
        }
        if !app.is_plugin_added::<RepliconSharedPlugin>() {
            app.add_plugins((RepliconPlugins, RepliconRenetPlugins));
        }
        wire::register(app);
        app.register_type::<NetTerrain>()
            .add_message::<NetUndoResult>()
            .register_type::<NetUndoResult>()
            .register_type::<UndoPolicy>()
            .add_observer(undo::on_net_terrain);
    }
}

/// Renet's connection settings for this protocol: replicon's channels with
/// room for snapshots and large requests.
#[must_use]
pub fn connection_config(channels: &RepliconChannels) -> ConnectionConfig {
    let mut server_channels_config = channels.server_configs();
    let mut client_channels_config = channels.client_configs();
    for channel in server_channels_config
        .iter_mut()
        .chain(client_channels_config.iter_mut())
    {
        channel.max_memory_usage_bytes = CHANNEL_MEMORY_BYTES;
    }
    ConnectionConfig {
        available_bytes_per_tick: BYTES_PER_UPDATE,
        server_channels_config,
        client_channels_config,
    }
}

/// Starts listening on `addr` (port 0 picks a free one) for up to
/// `max_clients`; returns the address bound. Call after adding
/// [`NetServerPlugin`] (and every other networked message).
///
/// # Errors
/// The socket cannot be bound or the transport not created.
pub fn start_server(
    world: &mut World,
    addr: SocketAddr,
    max_clients: usize,
) -> Result<SocketAddr, BevyError> {
    let config = connection_config(world.resource::<RepliconChannels>());
    let socket = UdpSocket::bind(addr)?;
    let bound = socket.local_addr()?;
    let transport = NetcodeServerTransport::new(
        ServerConfig {
            current_time: SystemTime::now().duration_since(SystemTime::UNIX_EPOCH)?,
            max_clients,
            protocol_id: PROTOCOL_ID,
            public_addresses: vec![bound],
            authentication: ServerAuthentication::Unsecure,
        },
        socket,
    )?;
    world.insert_resource(RenetServer::new(config));
    world.insert_resource(transport);
    Ok(bound)
}

/// Connects to the server at `server` as `client_id` (unique per client).
/// Call after adding [`NetClientPlugin`].
///
/// # Errors
/// The socket cannot be bound or the transport not created.
pub fn start_client(
    world: &mut World,
    server: SocketAddr,
    client_id: u64,
) -> Result<(), BevyError> {
    let config = connection_config(world.resource::<RepliconChannels>());
    let socket = bind_client_socket(server)?;
    let transport = NetcodeClientTransport::new(
        SystemTime::now().duration_since(SystemTime::UNIX_EPOCH)?,
        ClientAuthentication::Unsecure {
            client_id,
            protocol_id: PROTOCOL_ID,
            server_addr: server,
            user_data: None,
        },
        socket,
    )?;
    world.insert_resource(RenetClient::new(config));
    world.insert_resource(transport);
    Ok(())
}

/// A client's UDP socket on a free port, of the server address's family
/// (loopback for a loopback server).
fn bind_client_socket(server: SocketAddr) -> std::io::Result<UdpSocket> {
    let local: SocketAddr = match server {
        SocketAddr::V4(v4) if v4.ip().is_loopback() => (Ipv4Addr::LOCALHOST, 0).into(),
        SocketAddr::V4(_) => (Ipv4Addr::UNSPECIFIED, 0).into(),
        SocketAddr::V6(_) => (std::net::Ipv6Addr::UNSPECIFIED, 0).into(),
    };
    UdpSocket::bind(local)
}

#[cfg(test)]
mod tests {
    use std::any::TypeId;

    use bevy::asset::AssetPlugin;

    use super::*;
    use crate::terrain::TerrainPlugin;

    /// Every public component, resource and message of the module is in the
    /// type registry of an app with both plugins (for inspectors and scene
    /// files).
    #[test]
    fn the_public_types_are_reflected_and_registered() {
        let mut app = App::new();
        app.add_plugins((
            MinimalPlugins,
            AssetPlugin::default(),
            TerrainPlugin,
            NetServerPlugin,
            NetClientPlugin,
        ));
        let registry = app.world().resource::<AppTypeRegistry>().read();
        let types = [
            (TypeId::of::<NetTerrain>(), "NetTerrain"),
            (TypeId::of::<NetLimits>(), "NetLimits"),
            (TypeId::of::<NetServerStats>(), "NetServerStats"),
            (TypeId::of::<NetClientStats>(), "NetClientStats"),
            (TypeId::of::<NetClientSettings>(), "NetClientSettings"),
            (TypeId::of::<NetCarveRequest>(), "NetCarveRequest"),
            (TypeId::of::<NetCarveResult>(), "NetCarveResult"),
            (TypeId::of::<TerrainSynced>(), "TerrainSynced"),
            (TypeId::of::<Desynced>(), "Desynced"),
            (TypeId::of::<RequestRejected>(), "RequestRejected"),
            (TypeId::of::<DesyncReported>(), "DesyncReported"),
            (TypeId::of::<crate::terrain::GridCarve>(), "GridCarve"),
            (TypeId::of::<ClientPacket>(), "ClientPacket"),
            (TypeId::of::<ServerPacket>(), "ServerPacket"),
            (TypeId::of::<NetWorld>(), "NetWorld"),
            (TypeId::of::<NetWorldCarveRequest>(), "NetWorldCarveRequest"),
            (TypeId::of::<WorldSynced>(), "WorldSynced"),
            (TypeId::of::<WorldDesynced>(), "WorldDesynced"),
            (TypeId::of::<NetUndoResult>(), "NetUndoResult"),
            (TypeId::of::<UndoPolicy>(), "UndoPolicy"),
        ];
        let missing: Vec<&str> = types
            .iter()
            .filter(|(id, _)| registry.get(*id).is_none())
            .map(|(_, name)| *name)
            .collect();
        assert!(missing.is_empty(), "not registered: {missing:?}");
        let limits = registry
            .get(TypeId::of::<NetLimits>())
            .and_then(|r| r.data::<ReflectResource>());
        assert!(limits.is_some(), "NetLimits reflects as a resource");
    }
}
