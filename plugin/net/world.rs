//! Multiplayer for streamed worlds: carves of a [`TerrainWorld`] replicated
//! so that every chunk any peer holds is bit-identical to the server's.
//!
//! ## Design
//!
//! A world's source is code (a closure, a noise function), not data, so a
//! world is not sent: every peer spawns the same [`TerrainWorld`] (same
//! [`WorldLayout`](crate::terrain::WorldLayout), source and labels) with a
//! [`NetWorld`] id, and streams its chunks around its own
//! [`TerrainFocus`](crate::terrain::TerrainFocus) as usual. Peers hold
//! different live chunks; what is replicated is the world's carves.
//!
//! 1. **Requests.** A client sends a [`NetWorldCarveRequest`] (a float or
//!    grid tool in the world's local frame). The server checks it as a
//!    terrain carve (rate limit per client shared with terrain carves,
//!    pieces, points, extent, the world's materials; NaN or out-of-budget
//!    coordinates fail the rounding), rounds it to the world's grid once,
//!    and refuses a tool that reaches no chunk or a chunk beyond
//!    [`NetLimits::max_world_chunk`](super::NetLimits::max_world_chunk)
//!    ([`RejectReason::OutsideWorld`](super::RejectReason::OutsideWorld));
//!    an unknown world is [`RejectReason::UnknownWorld`](super::RejectReason::UnknownWorld).
//! 2. **Order.** Accepted carves are numbered 1, 2, … per world and sent
//!    to every client as [`NetWorldCarve`]s. Every peer routes carve `seq`
//!    to the chunks its grid tool reaches ([`TerrainWorld::chunks_reached`],
//!    a function of the integer tool only), in `seq` order, with `seq` as
//!    the chunks' request id. A chunk that is not live keeps the carve
//!    waiting, in order. On the server it is built (restored when edited)
//!    at once, as for a local [`WorldCarve`](crate::terrain::WorldCarve),
//!    since the server answers every carve. On a client a chunk beyond
//!    every focus's unload radius is *deferred*: its carves wait
//!    ([`TerrainWorld::deferred_chunks`]) until it streams in, a detach
//!    names it (see **Debris**), more than
//!    [`TerrainWorld::with_max_deferred_carves`] wait (it is then built out
//!    of sight, carved and stored again) or
//!    [`TerrainWorld::build_deferred`] asks; a resync drops them with the
//!    chunks. Then it is built and handed them in order, as it would have
//!    been at once, so a client's CPU follows the carving near its foci,
//!    not the whole server's. So each chunk receives the same carves in
//!    the same order on every peer whatever is streamed in, whenever it
//!    receives them, and exact carving makes its octree the same.
//! 3. **Edited chunks and checks.** A chunk is *edited* once a world
//!    carve applied to it (its [`CarveApplied`] report) or a detach
//!    across chunk borders took solid out of it (see **Debris**); the
//!    reports give each edited chunk's state hash after each op. Every
//!    [`NetLimits::check_interval`](super::NetLimits::check_interval) the
//!    server sends a [`ServerPacket::WorldCheck`]: once every op up to its
//!    *done* op `s` is reported by every chunk it reached, each chunk
//!    changed since the previous check with the last op `t ≤ s` applied to
//!    it and its hash after `t` (at most
//!    [`MAX_CHECK_CHUNKS`](super::wire::MAX_CHECK_CHUNKS) a packet, more in
//!    several). A client keeps the latest check of each chunk until that
//!    chunk has reported every op up to `t` that reached it, then compares
//!    its hash after `t` (none if it never changed here); a difference
//!    is a [`WorldDesynced`](super::WorldDesynced) naming the chunk, and
//!    the client gets the world's snapshot again. So each chunk is checked
//!    on its own, whenever this client holds it, whatever the others do.
//!    The *world hash* ([`world_state_hash`]) is the wrapping sum over the
//!    edited chunks of XXH64 of `(x, z, chunk hash)`, independent of order
//!    and of which chunks are live: tests compare peers with it. The check
//!    of a deferred chunk waits until the chunk is built, and passes then.
//! 4. **Joining.** A client that joins (or resyncs) gets the world's
//!    snapshot: every edited chunk's exact terrain snapshot
//!    ([`Terrain::to_snapshot_bytes`]) with the last carve it holds, cut
//!    into parts as terrain snapshots are, with `seq` the server's *done*
//!    carve (every carve up to it reported by every chunk), then the
//!    carves after `seq`. The client replaces all its chunks with these,
//!    keeps them as edited whatever their empty journals say, and routes
//!    each later carve to every chunk it reaches but those whose snapshot
//!    already holds it. A live chunk that already holds its state stays
//!    as it is (an idle chunk whose snapshot bytes are the received ones,
//!    or an unedited one the snapshot does not name:
//!    [`WorldSynced::kept`](super::WorldSynced::kept)); the others are
//!    despawned and stream in again from the snapshot or the source. So a
//!    client that streamed chunks in while it joined builds again only
//!    those the server edited, and a resync only the chunks that differ.
//!
//! A chunk whose build fails (a bad source sample, the same on every peer)
//! drops its carves as in a local world; it counts as reported.
//!
//! **Debris.** Each chunk detaches what a carve cuts loose within it, the
//! same on every peer; in a deferred chunk it falls when the chunk is
//! built and carved. A piece over a chunk border is detached by a pass
//! over live chunks together ([`crate::terrain::world::debris`]), whose
//! result depends on which chunks are live: so only the server's pass
//! runs ([`crate::terrain::world::debris_order`]). When it applies a
//! result it numbers it as the next op of the world's order and sends it
//! to every client as a [`NetWorldDetach`]: the chunks the result depends
//! on and one cell per piece, no geometry. The server's book notes the
//! changed chunks' hashes at that `seq` at once. A client processes the
//! op at its place like a carve: it routes nothing after it until it is
//! applied, builds every chunk of the op it does not hold, waits until
//! they hold every op before it, runs the same exact search over exactly
//! those chunks from those cells, takes out the same pieces (spawning the
//! same debris) and reports every chunk of the op at that `seq`, so the
//! world hash matches. A chunk that lost a part is edited (stored with the
//! part out, in snapshots, in the world hash); a snapshot chunk that
//! already holds the op skips it. A malformed op (too many chunks or
//! seeds, a seed naming no chunk of the op or no cell of a chunk) is
//! skipped with a warning; the next world check then resyncs the client.
//! Spawn the world and its [`NetWorld`] together.
//!
//! Limits: the checks compare the hashes the chunks report after
//! networked ops, so a local change to a chunk shows only once a later
//! world op reaches that chunk. A resync sends every edited chunk again,
//! though the client builds again only those that differ. A networked world is
//! carved only through the server: a local [`WorldCarve`] on any peer's
//! networked world would be outside its order, so it is refused
//! ([`TerrainError::NetworkedWorld`](crate::terrain::TerrainError::NetworkedWorld));
//! every peer sends [`NetWorldCarveRequest`]s, a listen-server host's own
//! ordered as any client's ([`super`], "Roles").
//!
//! [`WorldCarve`]: crate::terrain::WorldCarve
//!
//! - [`super::world_server`]: validation, order, broadcast, hashes and
//!   snapshots on the server.
//! - [`super::world_client`]: [`NetWorldCarveRequest`], ordered routing,
//!   snapshots and the comparison of chunk hashes on a client.

use std::collections::{BTreeMap, BTreeSet};

use bevy::prelude::*;

use super::wire::WorldId;
use crate::terrain::{CarveApplied, CarveRejected, ChunkCoord, TerrainWorld, WorldChunk};

use super::wire::{
    ChunkCheck, MAX_DETACH_CHUNKS, MAX_DETACH_SEEDS, NetWorld, NetWorldDetach, WireSeed,
};
#[cfg(doc)]
use super::wire::{NetWorldCarve, ServerPacket};
#[cfg(doc)]
use super::world_client::NetWorldCarveRequest;
use crate::terrain::Terrain;
use crate::terrain::world::debris::drop_search;
use crate::terrain::world::debris_order::{AppliedDetach, DebrisRole, OrderedDetach};
use chisel_bsp::octree::CellKey;

/// A world that becomes networked follows its server's detaches across
/// chunk borders until the server side claims it ([`claim_debris`]). The
/// search of its own pass, if one runs, is dropped and gives its seeds
/// back to their chunks: a server searches them again.
pub(super) fn networked_debris(
    add: On<Add, NetWorld>,
    mut worlds: Query<&mut TerrainWorld>,
    mut terrains: Query<&mut Terrain>,
) {
    if let Ok(mut world) = worlds.get_mut(add.entity) {
        // Who decides debris is bookkeeping, not a change of the world.
        let world = world.bypass_change_detection();
        if world.debris_role == DebrisRole::Local {
            drop_search(world, &mut terrains);
        }
        world.debris_role = DebrisRole::Follow;
    }
}

/// Gives a networked world its debris role (the server side's systems
/// claim `Serve`, a connected client's `Follow`); a change drops what the
/// world had under the other role. Bookkeeping: callers pass the world
/// past change detection (`Mut::bypass_change_detection`).
pub(super) fn claim_debris(world: &mut TerrainWorld, role: DebrisRole) {
    if world.debris_role != role {
        world.debris_role = role;
        world.debris_search = None;
        world.detach_ordered = None;
        world.detaches_applied.clear();
    }
}

/// The wire form of a detach the server applied, numbered `seq`.
pub(crate) fn wire_detach(world: WorldId, seq: u64, applied: &AppliedDetach) -> NetWorldDetach {
    let index = |c: ChunkCoord| applied.chunks.iter().position(|&d| d == c);
    NetWorldDetach {
        world,
        seq,
        chunks: applied.chunks.iter().map(|c| [c.x, c.z]).collect(),
        seeds: (applied.seeds.iter())
            .filter_map(|&(coord, key)| {
                Some(WireSeed {
                    chunk: u32::try_from(index(coord)?).ok()?,
                    depth: key.depth,
                    pos: key.pos,
                })
            })
            .collect(),
    }
}

/// Checks a detach from the wire against the bounds and the world's chunk
/// size (`chunk_log2`: no cell is deeper) and gives it as the world
/// carries it out.
///
/// # Errors
/// Why it is refused: no chunk, too many chunks or seeds, chunks not in
/// strictly increasing order, a seed naming no chunk of it or a cell
/// outside its chunk.
pub(crate) fn ordered_detach(
    detach: &NetWorldDetach,
    chunk_log2: u8,
) -> Result<OrderedDetach, String> {
    let (chunks, seeds) = (&detach.chunks, &detach.seeds);
    if chunks.is_empty() || chunks.len() > MAX_DETACH_CHUNKS {
        return Err(format!(
            "{} chunks (1..={MAX_DETACH_CHUNKS} allowed)",
            chunks.len()
        ));
    }
    if seeds.len() > MAX_DETACH_SEEDS {
        return Err(format!(
            "{} seeds (at most {MAX_DETACH_SEEDS})",
            seeds.len()
        ));
    }
    let coords: Vec<ChunkCoord> = chunks.iter().map(|&[x, z]| ChunkCoord { x, z }).collect();
    if coords.windows(2).any(|w| w[0] >= w[1]) {
        return Err("chunks not in strictly increasing order".into());
    }
    let mut out = Vec::with_capacity(seeds.len());
    for seed in seeds {
        let Some(&coord) = usize::try_from(seed.chunk).ok().and_then(|i| coords.get(i)) else {
            return Err(format!(
                "a seed names chunk {} of {}",
                seed.chunk,
                coords.len()
            ));
        };
        let cells = 1u64.checked_shl(u32::from(seed.depth)).unwrap_or(0);
        let inside = seed.depth <= chunk_log2 && seed.pos.iter().all(|&p| u64::from(p) < cells);
        if !inside {
            return Err(format!(
                "a seed's cell (depth {}, {:?}) is outside its chunk",
                seed.depth, seed.pos
            ));
        }
        let key = CellKey {
            depth: seed.depth,
            pos: seed.pos,
        };
        out.push((coord, key));
    }
    Ok(OrderedDetach {
        seq: detach.seq,
        chunks: coords,
        seeds: out,
    })
}

/// The world hash of edited chunks given as `(chunk, chunk state hash)`:
/// the wrapping sum of XXH64 over each chunk's `x`, `z` and hash (little
/// endian), so independent of the order they are given in.
#[must_use]
pub fn world_state_hash(chunks: impl IntoIterator<Item = (ChunkCoord, u64)>) -> u64 {
    chunks.into_iter().fold(0u64, |sum, (coord, hash)| {
        let mut bytes = [0u8; 24];
        bytes[..8].copy_from_slice(&coord.x.to_le_bytes());
        bytes[8..16].copy_from_slice(&coord.z.to_le_bytes());
        bytes[16..].copy_from_slice(&hash.to_le_bytes());
        sum.wrapping_add(chisel_bsp::octree::store::checksum(&bytes))
    })
}

/// One world's carves as a peer applies them: which are still to be
/// reported by which chunks, and each edited chunk's recent hashes.
#[derive(Default)]
pub(crate) struct WorldBook {
    /// Per edited chunk, its state hash after each recent carve that
    /// applied to it (`seq → hash`); at least the latest is kept.
    pub(crate) chunks: BTreeMap<ChunkCoord, BTreeMap<u64, u64>>,
    /// Carves routed but not yet reported by every chunk they reach.
    pub(crate) outstanding: BTreeMap<u64, BTreeSet<ChunkCoord>>,
    /// The same by chunk: the ops each chunk has still to report.
    pub(crate) unreported: BTreeMap<ChunkCoord, BTreeSet<u64>>,
    /// The last carve routed.
    pub(crate) routed: u64,
    /// The world hash is not known after carves before this one (pruned,
    /// or before a snapshot).
    pub(crate) floor: u64,
}

impl WorldBook {
    /// Carve `seq` was routed to `coords`.
    pub(crate) fn note_routed(&mut self, seq: u64, coords: &[ChunkCoord]) {
        if !coords.is_empty() {
            self.outstanding
                .entry(seq)
                .or_default()
                .extend(coords.iter().copied());
            for &coord in coords {
                self.unreported.entry(coord).or_default().insert(seq);
            }
        }
        self.routed = self.routed.max(seq);
    }

    /// Chunk `coord` reported carve `seq`: applied with the chunk's new
    /// `hash`, or refused (`None`). Returns whether every chunk has now
    /// reported the carve.
    pub(crate) fn note_report(&mut self, coord: ChunkCoord, seq: u64, hash: Option<u64>) -> bool {
        let Some(waiting) = self.outstanding.get_mut(&seq) else {
            return false;
        };
        if !waiting.remove(&coord) {
            return false;
        }
        if let Some(seqs) = self.unreported.get_mut(&coord) {
            seqs.remove(&seq);
            if seqs.is_empty() {
                self.unreported.remove(&coord);
            }
        }
        if let Some(hash) = hash {
            self.chunks.entry(coord).or_default().insert(seq, hash);
        }
        if waiting.is_empty() {
            self.outstanding.remove(&seq);
            return true;
        }
        false
    }

    /// The last carve such that it and every carve before it are reported
    /// by every chunk they reach.
    pub(crate) fn done(&self) -> u64 {
        self.outstanding
            .keys()
            .next()
            .map_or(self.routed, |&first| first - 1)
    }

    /// The world hash after carve `seq`, when known.
    #[cfg(test)]
    pub(crate) fn hash_at(&self, seq: u64) -> Option<u64> {
        if seq < self.floor || seq > self.done() {
            return None;
        }
        Some(world_state_hash(self.chunks.iter().filter_map(
            |(&coord, hashes)| hashes.range(..=seq).next_back().map(|(_, &h)| (coord, h)),
        )))
    }

    /// Each chunk changed by an op after `after` up to `upto`, with the
    /// last such op and its hash after it, in coordinate order.
    pub(crate) fn changed_chunks(&self, after: u64, upto: u64) -> Vec<ChunkCheck> {
        let Some(range) = after.checked_add(1).filter(|&from| from <= upto) else {
            return Vec::new();
        };
        (self.chunks.iter())
            .filter_map(|(coord, hashes)| {
                let (&seq, &hash) = hashes.range(range..=upto).next_back()?;
                Some(ChunkCheck {
                    coord: [coord.x, coord.z],
                    seq,
                    hash,
                })
            })
            .collect()
    }

    /// Chunk `coord`'s state hash after op `seq`, once known: every op up
    /// to `seq` is routed and every one that reached the chunk reported.
    /// `Some(None)`: the chunk was not edited by then (or not since a
    /// snapshot older than `seq`); `None`: not known yet.
    pub(crate) fn chunk_hash_at(&self, coord: ChunkCoord, seq: u64) -> Option<Option<u64>> {
        let waits = (self.unreported.get(&coord))
            .and_then(|seqs| seqs.first())
            .is_some_and(|&first| first <= seq);
        if seq > self.routed || waits {
            return None;
        }
        let hashes = self.chunks.get(&coord);
        Some(hashes.and_then(|h| h.range(..=seq).next_back().map(|(_, &hash)| hash)))
    }

    /// Forgets the hashes that no world hash after `seq` or later needs.
    pub(crate) fn prune(&mut self, seq: u64) {
        for hashes in self.chunks.values_mut() {
            if let Some(&last) = hashes.range(..=seq).next_back().map(|(s, _)| s) {
                *hashes = hashes.split_off(&last);
            }
        }
        self.floor = self.floor.max(seq);
    }

    /// Forgets chunk `coord`'s hashes that no check at `seq` or later
    /// needs.
    pub(crate) fn prune_chunk(&mut self, coord: ChunkCoord, seq: u64) {
        if let Some(hashes) = self.chunks.get_mut(&coord)
            && let Some(&last) = hashes.range(..=seq).next_back().map(|(s, _)| s)
        {
            *hashes = hashes.split_off(&last);
        }
    }

    /// Counts chunks that failed to build as having reported (refused) the
    /// carves they were routed; returns the carves that became complete.
    pub(crate) fn settle_failed(&mut self, world: &TerrainWorld) -> Vec<u64> {
        let mut failed: Vec<(u64, ChunkCoord)> = (self.unreported.iter())
            .filter(|&(&c, _)| world.chunk_failed(c))
            .flat_map(|(&c, seqs)| seqs.iter().map(move |&seq| (seq, c)))
            .collect();
        failed.sort_unstable();
        failed
            .into_iter()
            .filter(|&(seq, coord)| self.note_report(coord, seq, None))
            .map(|(seq, _)| seq)
            .collect()
    }
}

/// A chunk's report of one world carve: the world, the chunk, the carve
/// and the chunk's hash after it (`None`: refused).
pub(crate) struct ChunkReport {
    pub(crate) world: WorldId,
    pub(crate) coord: ChunkCoord,
    pub(crate) seq: u64,
    pub(crate) hash: Option<u64>,
    /// Why it was refused.
    pub(crate) error: Option<String>,
}

/// The reports of this frame's carves in chunks of networked worlds.
pub(crate) fn chunk_reports(
    applied: &mut MessageReader<CarveApplied>,
    refused: &mut MessageReader<CarveRejected>,
    chunks: &Query<&WorldChunk>,
    worlds: &Query<&NetWorld>,
) -> Vec<ChunkReport> {
    let locate = |terrain: Entity| {
        let chunk = chunks.get(terrain).ok()?;
        let id = worlds.get(chunk.world).ok()?;
        Some((id.0, chunk.coord))
    };
    let mut reports = Vec::new();
    for report in applied.read() {
        if let (Some(seq), Some((world, coord))) = (report.request, locate(report.terrain)) {
            reports.push(ChunkReport {
                world,
                coord,
                seq,
                hash: Some(report.hash),
                error: None,
            });
        }
    }
    for report in refused.read() {
        if let (Some(seq), Some((world, coord))) = (report.request, locate(report.terrain)) {
            reports.push(ChunkReport {
                world,
                coord,
                seq,
                hash: None,
                error: Some(report.error.to_string()),
            });
        }
    }
    reports
}

#[cfg(test)]
mod tests {
    use super::super::wire::ServerPacket;
    use super::*;

    fn c(x: i64, z: i64) -> ChunkCoord {
        ChunkCoord { x, z }
    }

    #[test]
    fn the_world_hash_ignores_order_but_not_place_or_state() {
        let a = [(c(0, 0), 11), (c(1, -2), 22), (c(-5, 3), 33)];
        let mut b = a;
        b.reverse();
        assert_eq!(world_state_hash(a), world_state_hash(b));
        assert_ne!(
            world_state_hash(a),
            world_state_hash([(c(0, 0), 11), (c(-2, 1), 22), (c(-5, 3), 33)])
        );
        assert_ne!(
            world_state_hash(a),
            world_state_hash([(c(0, 0), 11), (c(1, -2), 23), (c(-5, 3), 33)])
        );
        assert_eq!(world_state_hash([]), 0);
    }

    /// Reports in any order give the hash after each carve once every
    /// carve up to it is reported, from each chunk's latest state by then.
    #[test]
    fn the_book_knows_a_hash_once_every_carve_before_is_reported() {
        let mut book = WorldBook::default();
        book.note_routed(1, &[c(0, 0), c(1, 0)]);
        book.note_routed(2, &[c(1, 0)]);
        book.note_routed(3, &[c(0, 0)]);
        assert!(!book.note_report(c(1, 0), 1, Some(10)));
        assert!(book.note_report(c(1, 0), 2, Some(20)));
        assert_eq!(book.done(), 0, "carve 1 still waits for chunk (0, 0)");
        assert_eq!(book.hash_at(2), None);
        assert!(book.note_report(c(0, 0), 1, None));
        assert_eq!(book.done(), 2);
        assert_eq!(book.hash_at(1), Some(world_state_hash([(c(1, 0), 10)])));
        assert_eq!(book.hash_at(2), Some(world_state_hash([(c(1, 0), 20)])));
        assert!(book.note_report(c(0, 0), 3, Some(30)));
        let after_3 = world_state_hash([(c(0, 0), 30), (c(1, 0), 20)]);
        assert_eq!(book.hash_at(3), Some(after_3));
        assert!(!book.note_report(c(0, 0), 3, Some(31)), "one report each");
        book.prune(3);
        assert_eq!(book.hash_at(2), None, "pruned");
        assert_eq!(book.hash_at(3), Some(after_3));
        assert_eq!(book.chunks[&c(1, 0)].len(), 1, "only the latest kept");
    }

    /// A chunk's hash after an op is known once the chunk reported every
    /// op up to it, whatever other chunks still owe; the server names each
    /// chunk changed since its previous check with its last op.
    #[test]
    fn each_chunk_is_checked_on_its_own() {
        let mut book = WorldBook::default();
        book.note_routed(1, &[c(0, 0), c(9, 9)]);
        book.note_routed(2, &[c(0, 0)]);
        book.note_routed(3, &[c(9, 9), c(0, 1)]);
        assert!(!book.note_report(c(0, 0), 1, Some(10)));
        assert!(book.note_report(c(0, 0), 2, Some(20)));
        assert_eq!(book.chunk_hash_at(c(0, 0), 1), Some(Some(10)));
        assert_eq!(book.chunk_hash_at(c(0, 0), 2), Some(Some(20)));
        assert_eq!(
            book.chunk_hash_at(c(0, 0), 3),
            Some(Some(20)),
            "not reached"
        );
        assert_eq!(book.chunk_hash_at(c(0, 0), 4), None, "not routed yet");
        assert_eq!(book.chunk_hash_at(c(9, 9), 1), None, "(9, 9) owes op 1");
        assert_eq!(
            book.chunk_hash_at(c(0, 1), 2),
            Some(None),
            "unedited by op 2"
        );
        assert_eq!(book.chunk_hash_at(c(0, 1), 3), None, "(0, 1) owes op 3");
        assert_eq!(book.done(), 0, "no world hash after op 1 yet");
        assert!(!book.note_report(c(0, 1), 3, None));
        assert_eq!(book.chunk_hash_at(c(0, 1), 3), Some(None), "refused");
        assert!(book.note_report(c(9, 9), 1, Some(91)));
        assert!(book.note_report(c(9, 9), 3, Some(93)));
        assert!(book.unreported.is_empty());
        assert_eq!(book.chunk_hash_at(c(9, 9), 3), Some(Some(93)));
        let check = |coord: ChunkCoord, seq, hash| ChunkCheck {
            coord: [coord.x, coord.z],
            seq,
            hash,
        };
        assert_eq!(
            book.changed_chunks(0, 3),
            [check(c(0, 0), 2, 20), check(c(9, 9), 3, 93)]
        );
        assert_eq!(book.changed_chunks(2, 3), [check(c(9, 9), 3, 93)]);
        assert_eq!(book.changed_chunks(0, 1).len(), 2);
        assert!(book.changed_chunks(3, 3).is_empty());
        book.prune_chunk(c(9, 9), 3);
        assert_eq!(book.chunks[&c(9, 9)].len(), 1);
        assert_eq!(book.chunks[&c(0, 0)].len(), 2, "other chunks keep theirs");
    }

    fn applied() -> AppliedDetach {
        let key = |depth, pos| CellKey { depth, pos };
        AppliedDetach {
            seq: None,
            chunks: vec![c(-1, 0), c(0, 0), c(0, 1)],
            seeds: vec![(c(0, 0), key(3, [7, 0, 2])), (c(0, 1), key(5, [31, 1, 0]))],
            hashes: Vec::new(),
        }
    }

    /// A detach survives the wire and comes back as the world carries it
    /// out: the same chunks and seeds.
    #[test]
    fn a_detach_survives_the_wire() {
        let wire = wire_detach(7, 42, &applied());
        assert_eq!(wire.seeds[0].chunk, 1);
        let packet = ServerPacket::WorldDetach(wire.clone());
        let bytes = postcard::to_allocvec(&packet).unwrap();
        let back: ServerPacket = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back, packet);
        let ordered = ordered_detach(&wire, 5).expect("well formed");
        assert_eq!(ordered.seq, 42);
        assert_eq!(ordered.chunks, applied().chunks);
        assert_eq!(ordered.seeds, applied().seeds);
    }

    /// Every way a detach can be malformed is a refusal with its reason,
    /// never a panic.
    #[test]
    fn a_malformed_detach_is_refused() {
        let good = wire_detach(1, 3, &applied());
        let refused = |change: &dyn Fn(&mut NetWorldDetach), why: &str| {
            let mut bad = good.clone();
            change(&mut bad);
            let error = ordered_detach(&bad, 5).expect_err(why);
            assert!(error.contains(why), "{error} (expected {why})");
        };
        refused(&|d| d.chunks.clear(), "0 chunks");
        refused(
            &|d| d.chunks = (0..=MAX_DETACH_CHUNKS as i64).map(|x| [x, 0]).collect(),
            "65 chunks",
        );
        refused(
            &|d| d.seeds = vec![d.seeds[0]; MAX_DETACH_SEEDS + 1],
            "1025 seeds",
        );
        refused(&|d| d.chunks.swap(0, 1), "increasing");
        refused(&|d| d.chunks[1] = d.chunks[0], "increasing");
        refused(&|d| d.seeds[0].chunk = 3, "names chunk 3 of 3");
        refused(&|d| d.seeds[0].chunk = u32::MAX, "names chunk");
        refused(&|d| d.seeds[0].pos[2] = 8, "outside");
        refused(&|d| d.seeds[1].depth = 6, "outside");
        refused(&|d| d.seeds[1].depth = 255, "outside");
        // At the bounds it is taken.
        let mut full = good.clone();
        full.chunks = (0..MAX_DETACH_CHUNKS as i64).map(|x| [x, 0]).collect();
        full.seeds = vec![full.seeds[0]; MAX_DETACH_SEEDS];
        assert!(ordered_detach(&full, 5).is_ok());
        // The largest cell index at the deepest level is inside.
        let mut deep = good;
        deep.seeds[1] = WireSeed {
            chunk: 2,
            depth: 5,
            pos: [31; 3],
        };
        assert!(ordered_detach(&deep, 5).is_ok());
    }
}
