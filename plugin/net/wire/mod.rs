//! What travels between peers: carve requests in, integer carves, results,
//! hash checks and snapshots out. Every message is plain data with serde
//! derives, encoded with postcard.
//!
//! A client sends its tool as floats ([`WireTool::World`], a copy of the
//! [`CarveTool`]'s numbers: no trigonometry, no transform) or already on
//! the grid ([`WireTool::Grid`]); the server rounds a float tool to the
//! grid once ([`CarveTool::to_grid`]) and from then on only the integer
//! [`GridTool`] travels ([`NetCarve`]), so every peer builds the same
//! exact tool.
//!
//! Client packets are decoded by [`decode_client_packet`], which never
//! fails: bytes that are no valid request become
//! [`ClientPacket::Malformed`], which the server answers with a reason.

use bevy::prelude::*;
use bevy_replicon::bytes::Bytes;
use bevy_replicon::prelude::*;
use bevy_replicon::shared::message::ctx::{ClientSendCtx, ServerReceiveCtx};
use chisel_bsp::octree::Edit;
use serde::{Deserialize, Serialize};

#[cfg(doc)]
use crate::terrain::CarveTool;
use crate::terrain::GridTool;

mod tool;
pub use tool::{WirePiece, WirePose, WireShape, WireTool};

/// A terrain's name on the network: the same on every peer.
pub type TerrainId = u32;

/// A streamed world's name on the network: the same on every peer.
pub type WorldId = u32;

/// Marks a terrain entity as replicated under this id. Put it on a
/// server's terrain; clients get their terrains (with it) from snapshots.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[reflect(Component)]
pub struct NetTerrain(pub TerrainId);

/// Marks a [`crate::terrain::TerrainWorld`] entity as replicated under
/// this id. Every peer spawns the world itself, from the same layout and
/// source (a source is code, not data); put this on it on the server and
/// on every client (see [`super::world`]).
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[reflect(Component)]
pub struct NetWorld(pub WorldId);

/// What a client asks of the server.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ClientRequest {
    /// Carve a terrain; answered by [`ServerPacket::Result`] with the same
    /// request id.
    Carve {
        /// Chosen by the client.
        request: u64,
        /// The terrain.
        terrain: TerrainId,
        /// The tool.
        tool: WireTool,
        /// What to do inside it.
        edit: Edit,
    },
    /// The client's hash after carve `seq` differs from the server's:
    /// send a snapshot.
    Desync {
        /// The terrain.
        terrain: TerrainId,
        /// The carve after which the hashes were compared.
        seq: u64,
        /// The client's hash there.
        hash: u64,
    },
    /// Carve a streamed world (variants are only ever appended); answered
    /// by [`ServerPacket::Result`] with the same request id.
    CarveWorld {
        /// Chosen by the client.
        request: u64,
        /// The world.
        world: WorldId,
        /// The tool, in the world's local frame.
        tool: WireTool,
        /// What to do inside it.
        edit: Edit,
    },
    /// The client's hash of a chunk after world op `seq` differs from the
    /// server's ([`ServerPacket::WorldCheck`]): send the world's snapshot.
    WorldDesync {
        /// The world.
        world: WorldId,
        /// The op after which the hashes were compared.
        seq: u64,
        /// The client's hash of the chunk there.
        hash: u64,
    },
    /// Undo the terrain's last undoable carve (`redo: false`), or redo
    /// its last undone one (`redo: true`), if the server's
    /// [`super::UndoPolicy`] lets this client; answered by
    /// [`ServerPacket::UndoResult`] with the same request id.
    Undo {
        /// Chosen by the client.
        request: u64,
        /// The terrain.
        terrain: TerrainId,
        /// A redo rather than an undo.
        redo: bool,
    },
}

/// A client packet as the server received it.
#[derive(Message, Reflect, Clone, Debug, PartialEq)]
#[reflect(opaque)]
#[reflect(Debug, PartialEq, Clone)]
pub enum ClientPacket {
    /// A well-formed request.
    Request(ClientRequest),
    /// Bytes that are no request (the server answers with the reason).
    Malformed {
        /// What was wrong.
        reason: String,
    },
}

/// Largest client packet decoded (bigger ones are malformed).
pub const MAX_CLIENT_PACKET_BYTES: usize = 16 << 20;

/// Encodes a client packet (only requests are sent).
///
/// # Errors
/// Never for requests; a [`ClientPacket::Malformed`] is not sent.
pub fn encode_client_packet(
    _ctx: &mut ClientSendCtx,
    packet: &ClientPacket,
    out: &mut Vec<u8>,
) -> Result<()> {
    match packet {
        ClientPacket::Request(request) => {
            out.extend_from_slice(&postcard::to_allocvec(request)?);
            Ok(())
        }
        ClientPacket::Malformed { .. } => Err("a malformed packet is not sent".into()),
    }
}

/// Decodes a client packet; never fails (see [`ClientPacket::Malformed`]).
///
/// # Errors
/// None.
pub fn decode_client_packet(
    _ctx: &mut ServerReceiveCtx,
    bytes: &mut Bytes,
) -> Result<ClientPacket> {
    let data = bytes.split_to(bytes.len());
    Ok(client_packet_from_bytes(&data))
}

/// The request in `data`, or why there is none.
#[must_use]
pub fn client_packet_from_bytes(data: &[u8]) -> ClientPacket {
    if data.len() > MAX_CLIENT_PACKET_BYTES {
        return ClientPacket::Malformed {
            reason: format!(
                "packet of {} bytes is over the limit of {MAX_CLIENT_PACKET_BYTES}",
                data.len()
            ),
        };
    }
    match postcard::from_bytes::<ClientRequest>(data) {
        Ok(request) => ClientPacket::Request(request),
        Err(e) => ClientPacket::Malformed {
            reason: format!("undecodable request ({} bytes): {e}", data.len()),
        },
    }
}

/// An accepted carve, in the integer form every peer applies.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct NetCarve {
    /// The terrain.
    pub terrain: TerrainId,
    /// Its place in the terrain's order of carves, from 1 without gaps.
    pub seq: u64,
    /// The exact tool.
    pub tool: GridTool,
    /// What it does.
    pub edit: Edit,
}

/// An accepted undo (or redo) of a terrain, in its order of carves:
/// every peer undoes (or redoes) its last carve (or undo) there, exactly
/// as the server did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct NetUndo {
    /// The terrain.
    pub terrain: TerrainId,
    /// Its place in the terrain's order, shared with the carves.
    pub seq: u64,
    /// A redo rather than an undo.
    pub redo: bool,
}

/// Why the server refused a request.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
pub enum RejectReason {
    /// The packet was no request.
    #[error("malformed packet: {0}")]
    Malformed(String),
    /// The client sent more carves than its rate allows.
    #[error("too many carves; slow down")]
    RateLimited,
    /// No terrain has this id.
    #[error("no terrain has id {0}")]
    UnknownTerrain(TerrainId),
    /// Too many pieces in one tool.
    #[error("{pieces} tool pieces, at most {limit} allowed")]
    TooManyPieces {
        /// Pieces sent.
        pieces: usize,
        /// The limit.
        limit: usize,
    },
    /// Too many points in one piece.
    #[error("{points} points in a tool piece, at most {limit} allowed")]
    TooManyPoints {
        /// Points sent.
        points: usize,
        /// The limit.
        limit: usize,
    },
    /// The tool spans more of the grid than allowed.
    #[error("the tool spans {extent} grid units, at most {limit} allowed")]
    TooLarge {
        /// Its largest extent, in grid units.
        extent: i64,
        /// The limit.
        limit: i64,
    },
    /// The tool or edit is invalid: non-finite or out-of-budget
    /// coordinates, a degenerate hull, an unknown material, a miss.
    #[error("{0}")]
    Invalid(String),
    /// No streamed world has this id (variants are only ever appended).
    #[error("no world has id {0}")]
    UnknownWorld(WorldId),
    /// The tool reaches a world chunk beyond the range the server allows
    /// ([`super::NetLimits::max_world_chunk`]).
    #[error("the tool reaches chunk {chunk:?}, beyond the ±{limit} chunks allowed")]
    OutsideWorld {
        /// The chunk (x, z).
        chunk: [i64; 2],
        /// The limit on `|x|` and `|z|`.
        limit: i64,
    },
    /// The request had no server to go to (the client was connecting, or
    /// disconnected in an app without the server plugin) and was not sent;
    /// answered locally, never by a server.
    #[error("not connected yet; the request was not sent")]
    NotConnected,
    /// An undo with no carve left to undo on the terrain (variants are
    /// only ever appended).
    #[error("nothing to undo")]
    NothingToUndo,
    /// A redo with no undo left to redo on the terrain.
    #[error("nothing to redo")]
    NothingToRedo,
    /// The carve the undo (or redo) would take back (or put back) is not
    /// the client's own ([`super::UndoPolicy::OwnLatest`]).
    #[error("carve {seq} is not yours to undo or redo")]
    NotYourCarve {
        /// The carve's place in the terrain's order (0: one ordered
        /// before the server kept track).
        seq: u64,
    },
    /// The server lets no client undo ([`super::UndoPolicy::Nobody`]).
    #[error("the server lets no client undo or redo")]
    UndoForbidden,
}

/// What became of a request.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Outcome {
    /// Applied as carve `seq` of its terrain.
    Applied {
        /// Its sequence number.
        seq: u64,
    },
    /// Refused; nothing changed.
    Rejected(RejectReason),
}

/// One part of a terrain snapshot: the snapshot bytes
/// ([`crate::terrain::Terrain::to_snapshot_bytes`]: octree, grid, base,
/// materials and debris rules, no journal) after carve `seq`, cut into
/// parts so that no message is large.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SnapshotPart {
    /// The terrain.
    pub terrain: TerrainId,
    /// The last carve the snapshot holds (0: none).
    pub seq: u64,
    /// Bytes of the whole snapshot.
    pub total: u64,
    /// Where this part starts.
    pub offset: u64,
    /// The part's bytes.
    pub bytes: Vec<u8>,
    /// The terrain entity's transform.
    pub pose: WirePose,
}

/// An accepted world carve, in the integer form every peer applies to the
/// chunks the tool reaches.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct NetWorldCarve {
    /// The world.
    pub world: WorldId,
    /// Its place in the world's order of carves, from 1 without gaps.
    pub seq: u64,
    /// The exact tool, on the world's grid.
    pub tool: GridTool,
    /// What it does.
    pub edit: Edit,
}

/// A detach across chunk borders the server applied to its world
/// (`crate::terrain::world::debris_order`), numbered in the world's order
/// with its carves: every peer searches `chunks` (every other chunk
/// anchors) from `seeds` once every earlier op is applied there, and takes
/// out the same pieces. No geometry travels.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct NetWorldDetach {
    /// The world.
    pub world: WorldId,
    /// Its place in the world's order, shared with the carves.
    pub seq: u64,
    /// The chunks it depends on (x, z), in coordinate order, at most
    /// [`MAX_DETACH_CHUNKS`].
    pub chunks: Vec<[i64; 2]>,
    /// One cell per piece to search from, at most [`MAX_DETACH_SEEDS`].
    pub seeds: Vec<WireSeed>,
}

/// A cell of one chunk of a [`NetWorldDetach`]: an octree cell key.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct WireSeed {
    /// The chunk's index in the detach's `chunks`.
    pub chunk: u32,
    /// The cell's depth below the chunk's root.
    pub depth: u8,
    /// Its position in units of its edge, each below `2^depth`.
    pub pos: [u32; 3],
}

pub use crate::terrain::world::debris_order::{MAX_DETACH_CHUNKS, MAX_DETACH_SEEDS};

/// One part of a world snapshot: every edited chunk's terrain snapshot
/// ([`crate::terrain::Terrain::to_snapshot_bytes`]), chunk after chunk,
/// each cut into parts as a terrain snapshot is. A world without edited
/// chunks is one part without a chunk.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorldSnapshotPart {
    /// The world.
    pub world: WorldId,
    /// Every world carve up to this one is in the chunks (or reached none
    /// of them); the carves after it follow the snapshot.
    pub seq: u64,
    /// Edited chunks in the snapshot.
    pub chunks: u32,
    /// The part of one chunk (`None` only when `chunks` is 0).
    pub chunk: Option<ChunkSnapshotPart>,
}

/// Part of one chunk's terrain snapshot in a [`WorldSnapshotPart`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChunkSnapshotPart {
    /// The chunk's place among the snapshot's chunks, from 0.
    pub index: u32,
    /// The chunk (x, z).
    pub coord: [i64; 2],
    /// The last world op (carve or detach across chunk borders) the chunk
    /// holds (0: none): ops after the world's `seq` up to this one are not
    /// applied to it again.
    pub seq: u64,
    /// Bytes of the chunk's whole snapshot.
    pub total: u64,
    /// Where this part starts.
    pub offset: u64,
    /// The part's bytes.
    pub bytes: Vec<u8>,
}

/// Most chunks one [`ServerPacket::WorldCheck`] names.
pub const MAX_CHECK_CHUNKS: usize = 1024;

/// A chunk's state hash in a [`ServerPacket::WorldCheck`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChunkCheck {
    /// The chunk (x, z).
    pub coord: [i64; 2],
    /// The last op of the world's order applied to it.
    pub seq: u64,
    /// Its state hash after that op.
    pub hash: u64,
}

/// Decodes the chunks of a world check, refusing more than
/// [`MAX_CHECK_CHUNKS`] before reading them.
fn bounded_checks<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> std::result::Result<Vec<ChunkCheck>, D::Error> {
    struct Bounded;
    impl<'de> serde::de::Visitor<'de> for Bounded {
        type Value = Vec<ChunkCheck>;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "at most {MAX_CHECK_CHUNKS} chunk checks")
        }

        fn visit_seq<A: serde::de::SeqAccess<'de>>(
            self,
            mut seq: A,
        ) -> std::result::Result<Self::Value, A::Error> {
            let too_many = |n| serde::de::Error::invalid_length(n, &Bounded);
            if let Some(n) = seq.size_hint().filter(|&n| n > MAX_CHECK_CHUNKS) {
                return Err(too_many(n));
            }
            let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0));
            while let Some(check) = seq.next_element()? {
                if out.len() == MAX_CHECK_CHUNKS {
                    return Err(too_many(MAX_CHECK_CHUNKS + 1));
                }
                out.push(check);
            }
            Ok(out)
        }
    }
    deserializer.deserialize_seq(Bounded)
}

/// Snapshot `bytes` cut into parts of at most `part_bytes` each: the
/// offset of each part and its bytes.
pub(crate) fn snapshot_parts(
    bytes: &[u8],
    part_bytes: usize,
) -> impl Iterator<Item = (u64, &[u8])> {
    bytes.chunks(part_bytes.max(1)).scan(0u64, |offset, part| {
        let at = *offset;
        *offset += part.len() as u64;
        Some((at, part))
    })
}

/// What the server sends.
#[derive(Message, Reflect, Clone, Debug, PartialEq, Serialize, Deserialize)]
#[reflect(opaque)]
#[reflect(Debug, PartialEq, Clone)]
pub enum ServerPacket {
    /// An accepted carve, to every client.
    Carve(NetCarve),
    /// The answer to one client's request.
    Result {
        /// The client's request id (`None` for a packet that was no
        /// request).
        request: Option<u64>,
        /// What became of it.
        outcome: Outcome,
    },
    /// The server's hash after carve `seq` of a terrain.
    Check {
        /// The terrain.
        terrain: TerrainId,
        /// The carve.
        seq: u64,
        /// The state hash after it.
        hash: u64,
    },
    /// Part of a snapshot.
    Snapshot(SnapshotPart),
    /// An accepted world carve, to every client (variants are only ever
    /// appended).
    WorldCarve(NetWorldCarve),
    /// The server's state hashes of the world's chunks changed since its
    /// previous check, once every op up to `seq` is applied there (one
    /// check may come as several packets with the same `seq`, each naming
    /// at most [`MAX_CHECK_CHUNKS`] chunks).
    WorldCheck {
        /// The world.
        world: WorldId,
        /// Every op up to this one is in the hashes.
        seq: u64,
        /// Each chunk changed since the previous check, with the last op
        /// applied to it and its hash after that op; a client refuses a
        /// check naming more than [`MAX_CHECK_CHUNKS`].
        #[serde(deserialize_with = "bounded_checks")]
        chunks: Vec<ChunkCheck>,
    },
    /// Part of a world snapshot.
    WorldSnapshot(WorldSnapshotPart),
    /// A detach across chunk borders in a world's order, to every client.
    WorldDetach(NetWorldDetach),
    /// An accepted undo or redo in a terrain's order, to every client.
    Undo(NetUndo),
    /// The answer to one client's [`ClientRequest::Undo`].
    UndoResult {
        /// The client's request id.
        request: u64,
        /// What became of it: [`Outcome::Applied`] names the undo's place
        /// in its terrain's order.
        outcome: Outcome,
    },
}

/// Registers the messages, in the same order on every peer.
pub(crate) fn register(app: &mut App) {
    app.add_client_message_with(Channel::Ordered, encode_client_packet, decode_client_packet)
        .add_server_message::<ServerPacket>(Channel::Ordered)
        .make_message_independent::<ServerPacket>()
        .register_type::<ClientPacket>()
        .register_type::<ServerPacket>()
        .register_type::<NetWorld>();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::terrain::{CarveShape, CarveTool, MAX_ROUND_CORNERS};

    /// One tool of every shape, in the order of [`CarveShape`].
    fn every_shape() -> CarveTool {
        let pose = Transform::from_xyz(1.0, 2.0, 3.0).with_rotation(Quat::from_rotation_x(0.5));
        CarveTool::union([
            CarveTool::dodecahedron(1.5, Vec3::ONE),
            CarveTool::new(
                CarveShape::Cuboid {
                    half_size: Vec3::new(1.0, 2.0, 3.0),
                },
                pose,
            ),
            CarveTool::new(
                CarveShape::Prism {
                    sides: 7,
                    radius: 0.5,
                    length: 4.0,
                },
                pose,
            ),
            CarveTool::new(CarveShape::Hull(vec![Vec3::ZERO, Vec3::X, Vec3::Y]), pose),
            CarveTool::sphere(2.0, Vec3::NEG_ONE),
            CarveTool::new(
                CarveShape::Sphere {
                    radius: 2.0,
                    tolerance: Some(0.01),
                },
                pose,
            ),
            CarveTool::cylinder(0.5, 3.0, pose),
            CarveTool::swept(
                CarveShape::Capsule {
                    radius: 0.25,
                    half_height: 1.0,
                    tolerance: Some(0.005),
                },
                pose,
                Transform::from_xyz(4.0, 0.0, 0.0),
            ),
        ])
    }

    #[test]
    fn every_shape_survives_the_wire() {
        let tool = every_shape();
        let wire = WireTool::from(&tool);
        let bytes = postcard::to_allocvec(&wire).unwrap();
        let back: WireTool = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back, wire);
        assert_eq!(back.to_carve_tool(), Some(tool));
    }

    #[test]
    fn older_encodings_keep_their_meaning() {
        // The shapes that existed before the round ones keep their variant
        // index (postcard writes it as the first byte) and their fields.
        let radius = 1.5f32.to_le_bytes();
        let shape = WireShape::Dodecahedron { radius: 1.5 };
        let bytes = postcard::to_allocvec(&shape).unwrap();
        assert_eq!(bytes, [&[0u8][..], &radius].concat());
        assert_eq!(postcard::from_bytes::<WireShape>(&bytes).unwrap(), shape);
        let hull = postcard::to_allocvec(&WireShape::Hull(vec![[0.0; 3]])).unwrap();
        assert_eq!(hull[..2], [3, 1]);
        // The round shapes come after them.
        let sphere = WireShape::Sphere {
            radius: 1.5,
            tolerance: None,
        };
        let bytes = postcard::to_allocvec(&sphere).unwrap();
        assert_eq!(bytes, [&[4u8][..], &radius, &[0]].concat());
        let capsule = postcard::to_allocvec(&WireShape::Capsule {
            radius: 1.0,
            half_height: 1.0,
            tolerance: Some(0.1),
        })
        .unwrap();
        assert_eq!(capsule[0], 6);
    }

    /// A world check names at most [`MAX_CHECK_CHUNKS`] chunks: one more
    /// is refused when decoded, also when the length prefix lies.
    #[test]
    fn a_world_check_naming_too_many_chunks_is_refused() {
        let check = |n: usize| ServerPacket::WorldCheck {
            world: 3,
            seq: 77,
            chunks: (0..n)
                .map(|i| ChunkCheck {
                    coord: [i as i64, -(i as i64)],
                    seq: 70 + i as u64 % 7,
                    hash: i as u64 * 0x9E37_79B9,
                })
                .collect(),
        };
        let decode = |bytes: &[u8]| postcard::from_bytes::<ServerPacket>(bytes);
        for n in [0, 1, MAX_CHECK_CHUNKS] {
            let packet = check(n);
            let bytes = postcard::to_allocvec(&packet).unwrap();
            assert_eq!(decode(&bytes).unwrap(), packet, "{n} chunks");
        }
        let bytes = postcard::to_allocvec(&check(MAX_CHECK_CHUNKS + 1)).unwrap();
        assert!(decode(&bytes).is_err(), "one chunk too many");
        // A length prefix of u32::MAX and no chunks behind it.
        let mut lying = postcard::to_allocvec(&check(0)).unwrap();
        lying.pop();
        lying.extend_from_slice(&[0xFF, 0xFF, 0xFF, 0xFF, 0x0F]);
        assert!(decode(&lying).is_err(), "a lying length");
    }

    /// The undo messages come after the older variants (postcard writes
    /// the variant index first), so older encodings keep their meaning;
    /// a truncated or unknown request is malformed, not a panic.
    #[test]
    fn undo_messages_are_appended_and_hostile_bytes_refused() {
        let undo = ServerPacket::Undo(NetUndo {
            terrain: 1,
            seq: 2,
            redo: true,
        });
        let bytes = postcard::to_allocvec(&undo).unwrap();
        assert_eq!(bytes, [8, 1, 2, 1]);
        assert_eq!(postcard::from_bytes::<ServerPacket>(&bytes).unwrap(), undo);
        let answer = ServerPacket::UndoResult {
            request: 3,
            outcome: Outcome::Rejected(RejectReason::NotYourCarve { seq: 4 }),
        };
        let bytes = postcard::to_allocvec(&answer).unwrap();
        assert_eq!(bytes, [9, 3, 1, 12, 4]);
        assert_eq!(
            postcard::from_bytes::<ServerPacket>(&bytes).unwrap(),
            answer
        );
        let request = ClientRequest::Undo {
            request: 5,
            terrain: 6,
            redo: false,
        };
        let bytes = postcard::to_allocvec(&request).unwrap();
        assert_eq!(bytes, [4, 5, 6, 0]);
        assert_eq!(
            client_packet_from_bytes(&bytes),
            ClientPacket::Request(request)
        );
        for hostile in [&bytes[..3], &[4, 5, 6, 2], &[5, 0]] {
            assert!(
                matches!(
                    client_packet_from_bytes(hostile),
                    ClientPacket::Malformed { .. }
                ),
                "{hostile:?}"
            );
        }
    }

    #[test]
    fn a_round_shape_counts_its_most_corners() {
        let wire = WireTool::from(&CarveTool::capsule(1.0, 1.0, Transform::IDENTITY));
        assert_eq!(wire.size(), (1, MAX_ROUND_CORNERS));
    }
}
