//! Secure connections: netcode connect tokens and encrypted traffic.
//!
//! [`super::start_server`] admits any client that speaks the protocol,
//! which suits a LAN, development and tests. A public server starts with
//! [`start_secure_server`] instead: it admits only clients that present a
//! connect token signed with its private [`NetKey`], and every packet is
//! encrypted and authenticated. The key never leaves the places a game
//! trusts (the server, and the login or matchmaking service that hands
//! out tokens with [`connect_token`]); a client receives its token over
//! the game's own authenticated channel (HTTPS, say) and connects with
//! [`start_secure_client`]. A token names the client id, the server
//! addresses it is good for and how long it stays valid.

use std::fmt;
use std::net::SocketAddr;
use std::time::{Duration, SystemTime};

use bevy::prelude::*;
use bevy_replicon::prelude::RepliconChannels;
use bevy_replicon_renet::netcode::{
    ClientAuthentication, ConnectToken, NETCODE_KEY_BYTES, NetcodeClientTransport, NetcodeError,
    NetcodeServerTransport, ServerAuthentication, ServerConfig, TokenGenerationError,
    generate_random_bytes,
};
use bevy_replicon_renet::{RenetClient, RenetServer};

use super::{PROTOCOL_ID, bind_client_socket, connection_config};

/// Most server addresses one connect token can name.
pub const MAX_TOKEN_ADDRESSES: usize = 32;

/// Seconds without a packet after which a secure connection is dropped.
pub const CONNECTION_TIMEOUT_SECONDS: i32 = 15;

/// A secure server's private key: 32 bytes that sign connect tokens and
/// derive the connection keys. Keep it secret; `Debug` does not show it.
#[derive(Clone, PartialEq, Eq)]
pub struct NetKey([u8; NETCODE_KEY_BYTES]);

impl NetKey {
    /// A fresh key from the operating system's random source.
    #[must_use]
    pub fn generate() -> Self {
        Self(generate_random_bytes())
    }

    /// A key stored earlier (from a secrets file or the environment).
    #[must_use]
    pub fn from_bytes(bytes: [u8; NETCODE_KEY_BYTES]) -> Self {
        Self(bytes)
    }

    /// The key's bytes, to store it.
    #[must_use]
    pub fn as_bytes(&self) -> &[u8; NETCODE_KEY_BYTES] {
        &self.0
    }
}

impl fmt::Debug for NetKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("NetKey(..)")
    }
}

/// Why a connect token could not be made or read.
#[derive(Debug, thiserror::Error)]
pub enum ConnectTokenError {
    /// A token must name at least one server address.
    #[error("a connect token needs a server address")]
    NoServerAddress,
    /// A token names at most [`MAX_TOKEN_ADDRESSES`] server addresses.
    #[error("a connect token names at most {MAX_TOKEN_ADDRESSES} server addresses, not {0}")]
    TooManyServerAddresses(usize),
    /// The validity is zero or longer than the clock can count.
    #[error("a connect token must be valid for 1 s to 100 years, not {0:?}")]
    BadValidity(Duration),
    /// The system clock is before 1970.
    #[error("the system clock is before 1970")]
    Clock,
    /// Encryption failed while signing the token.
    #[error("cannot sign the connect token: {0}")]
    Generate(TokenGenerationError),
    /// The bytes are no connect token of this netcode version.
    #[error("not a connect token: {0}")]
    Malformed(NetcodeError),
    /// The token was made for another protocol (another wire format).
    #[error(
        "the connect token is for protocol {found:#018x}, this build speaks \
         {PROTOCOL_ID:#018x}"
    )]
    WrongProtocol {
        /// The token's protocol id.
        found: u64,
    },
}

fn now() -> Result<Duration, ConnectTokenError> {
    SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .map_err(|_| ConnectTokenError::Clock)
}

/// A connect token for client `client_id`, signed with `key`, good for
/// connecting to any of `server_addresses` (as the clients reach them)
/// within `valid_for` from now. Returns the token's bytes, for the client's
/// [`start_secure_client`]. Make tokens where the key is kept, never on a
/// client.
///
/// # Errors
/// No address or too many, a validity of zero or over 100 years, or a
/// clock before 1970.
pub fn connect_token(
    key: &NetKey,
    client_id: u64,
    server_addresses: &[SocketAddr],
    valid_for: Duration,
) -> Result<Vec<u8>, ConnectTokenError> {
    if server_addresses.is_empty() {
        return Err(ConnectTokenError::NoServerAddress);
    }
    if server_addresses.len() > MAX_TOKEN_ADDRESSES {
        return Err(ConnectTokenError::TooManyServerAddresses(
            server_addresses.len(),
        ));
    }
    const HUNDRED_YEARS: u64 = 100 * 365 * 24 * 3600;
    if valid_for.as_secs() == 0 || valid_for.as_secs() > HUNDRED_YEARS {
        return Err(ConnectTokenError::BadValidity(valid_for));
    }
    let token = ConnectToken::generate(
        now()?,
        PROTOCOL_ID,
        valid_for.as_secs(),
        client_id,
        CONNECTION_TIMEOUT_SECONDS,
        server_addresses.to_vec(),
        None,
        key.as_bytes(),
    )
    .map_err(ConnectTokenError::Generate)?;
    let mut bytes = Vec::new();
    token
        .write(&mut bytes)
        .map_err(|e| ConnectTokenError::Generate(TokenGenerationError::IoError(e)))?;
    Ok(bytes)
}

/// Reads a connect token made by [`connect_token`].
///
/// # Errors
/// The bytes are no token of this netcode version, or the token is for
/// another protocol.
pub fn read_connect_token(bytes: &[u8]) -> Result<ConnectToken, ConnectTokenError> {
    let token = ConnectToken::read(&mut &bytes[..]).map_err(ConnectTokenError::Malformed)?;
    if token.protocol_id != PROTOCOL_ID {
        return Err(ConnectTokenError::WrongProtocol {
            found: token.protocol_id,
        });
    }
    Ok(token)
}

/// Starts a secure server listening on `bind` (port 0 picks a free one)
/// for up to `max_clients`, admitting only clients with a token signed by
/// `key` that names one of `public_addresses` (the addresses clients reach
/// the server at; empty: the address bound, which suits a server reached
/// at that address, such as 127.0.0.1 in tests). Returns the address
/// bound. Call after adding [`super::NetServerPlugin`].
///
/// # Errors
/// The socket cannot be bound or the transport not created.
pub fn start_secure_server(
    world: &mut World,
    bind: SocketAddr,
    public_addresses: Vec<SocketAddr>,
    max_clients: usize,
    key: &NetKey,
) -> Result<SocketAddr, BevyError> {
    let config = connection_config(world.resource::<RepliconChannels>());
    let socket = std::net::UdpSocket::bind(bind)?;
    let bound = socket.local_addr()?;
    let public_addresses = if public_addresses.is_empty() {
        vec![bound]
    } else {
        public_addresses
    };
    let transport = NetcodeServerTransport::new(
        ServerConfig {
            current_time: now()?,
            max_clients,
            protocol_id: PROTOCOL_ID,
            public_addresses,
            authentication: ServerAuthentication::Secure {
                private_key: *key.as_bytes(),
            },
        },
        socket,
    )?;
    world.insert_resource(RenetServer::new(config));
    world.insert_resource(transport);
    Ok(bound)
}

/// Connects to a secure server with the connect token `token` (bytes from
/// [`connect_token`]); the client id is the token's. Call after adding
/// [`super::NetClientPlugin`].
///
/// # Errors
/// The token cannot be read, the socket cannot be bound or the transport
/// not created.
pub fn start_secure_client(world: &mut World, token: &[u8]) -> Result<(), BevyError> {
    let token = read_connect_token(token)?;
    let server = token
        .server_addresses
        .iter()
        .flatten()
        .next()
        .copied()
        .ok_or(ConnectTokenError::NoServerAddress)?;
    let config = connection_config(world.resource::<RepliconChannels>());
    let socket = bind_client_socket(server)?;
    let transport = NetcodeClientTransport::new(
        now()?,
        ClientAuthentication::Secure {
            connect_token: token,
        },
        socket,
    )?;
    world.insert_resource(RenetClient::new(config));
    world.insert_resource(transport);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn local() -> Vec<SocketAddr> {
        vec![SocketAddr::from(([127, 0, 0, 1], 5000))]
    }

    #[test]
    fn a_token_round_trips_and_names_its_client() {
        let key = NetKey::generate();
        let bytes = connect_token(&key, 42, &local(), Duration::from_secs(60)).expect("token");
        let token = read_connect_token(&bytes).expect("reads back");
        assert_eq!(token.client_id, 42);
        assert_eq!(token.server_addresses[0], Some(local()[0]));
        assert!(token.server_addresses[1..].iter().all(Option::is_none));
        assert_eq!(token.expire_timestamp - token.create_timestamp, 60);
    }

    #[test]
    fn bad_requests_and_bytes_get_typed_errors() {
        let key = NetKey::generate();
        let hour = Duration::from_secs(3600);
        assert!(matches!(
            connect_token(&key, 1, &[], hour),
            Err(ConnectTokenError::NoServerAddress)
        ));
        let many = vec![local()[0]; MAX_TOKEN_ADDRESSES + 1];
        assert!(matches!(
            connect_token(&key, 1, &many, hour),
            Err(ConnectTokenError::TooManyServerAddresses(33))
        ));
        assert!(matches!(
            connect_token(&key, 1, &local(), Duration::ZERO),
            Err(ConnectTokenError::BadValidity(_))
        ));
        assert!(matches!(
            connect_token(&key, 1, &local(), Duration::MAX),
            Err(ConnectTokenError::BadValidity(_))
        ));
        let bytes = connect_token(&key, 1, &local(), hour).expect("token");
        for cut in [0, 1, 20, bytes.len() / 2] {
            assert!(matches!(
                read_connect_token(&bytes[..cut]),
                Err(ConnectTokenError::Malformed(_))
            ));
        }
        // The protocol id follows the client id (8 bytes) and the version
        // string (13 bytes).
        let mut other = bytes.clone();
        other[21] ^= 1;
        assert!(matches!(
            read_connect_token(&other),
            Err(ConnectTokenError::WrongProtocol { .. })
        ));
        assert_eq!(format!("{key:?}"), "NetKey(..)");
    }
}
