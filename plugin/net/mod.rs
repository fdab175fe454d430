//! Multiplayer carving (feature `net`): one authoritative server, any
//! number of clients, every peer with bit-identical terrain.
//!
//! Exact integer carving gives the same octree on every machine, so only
//! carves travel, never meshes: a client sends a request
//! ([`NetCarveRequest`]), the server validates it (size limits, the grid's
//! bit budget, a rate limit per client), rounds it to the grid once,
//! numbers it in its terrain's order and sends the integer carve
//! ([`NetCarve`]) to every client, which applies the carves strictly in
//! that order. A client that joins gets each terrain's file bytes
//! ([`crate::terrain::Terrain::to_bytes`]) and then the carves after them.
//! The server sends its state hash ([`crate::terrain::Terrain::state_hash`])
//! every [`NetLimits::check_interval`]; a client whose hash after the same
//! carve differs reports it and gets a fresh snapshot.
//!
//! Transport: `bevy_replicon` messages over `bevy_replicon_renet`'s netcode
//! UDP transport ([`start_server`], [`start_client`]), unsecured (for LAN
//! and tests; a public server should use netcode's secure tokens).
//!
//! - [`wire`] — the messages and their encoding.
//! - [`server`] — [`NetServerPlugin`]: validation, order, broadcast,
//!   checks, snapshots.
//! - [`client`] — [`NetClientPlugin`]: requests, ordered application,
//!   snapshots, hash comparison.

pub mod client;
pub mod server;
pub mod wire;

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
pub use server::{DesyncReported, NetLimits, NetServerPlugin, NetServerStats, RequestRejected};
pub use wire::{
    ClientPacket, ClientRequest, NetCarve, NetTerrain, Outcome, RejectReason, ServerPacket,
    SnapshotPart, TerrainId, WirePiece, WirePose, WireShape, WireTool,
};

/// The netcode protocol id of this wire format: peers with another id do
/// not connect.
pub const PROTOCOL_ID: u64 = 0xC415_E100_0000_0002;

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
    let local: SocketAddr = if server.is_ipv4() {
        (Ipv4Addr::UNSPECIFIED, 0).into()
    } else {
        (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
    };
    let local = if server.ip().is_loopback() && server.is_ipv4() {
        SocketAddr::from((Ipv4Addr::LOCALHOST, 0))
    } else {
        local
    };
    let socket = UdpSocket::bind(local)?;
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
