//! Debris across chunk borders in a networked world (feature `net`,
//! `net::world`): the server's pass ([`super::debris`]) decides, and every
//! peer takes the same pieces out of the same chunks at the same place in
//! the world's order of carves, without any geometry on the wire.
//!
//! A world has a `DebrisRole`: `Local` (not networked: the pass as
//! [`super::debris`] describes it), `Serve` (the server, a host, a single
//! player of a networked world) or `Follow` (a connected client).
//!
//! **Server.** The pass runs over the server's own live chunks, with three
//! rules more:
//! - A search looks past *open* sides, those towards a chunk that is not
//!   live ([`chisel_bsp::octree::detach_across_chunks_with_open_sides`]):
//!   it stops only at the ground, and a component that nothing but open
//!   sides holds stays and names them. When such a side faces a chunk
//!   among the 3×3 around a chunk the search started from, the server
//!   drops the result, builds that chunk and searches again. A dedicated
//!   server holds no chunk but those carves reach, so without this a
//!   piece over a border would always be held by a neighbour it did not
//!   load; with it, a crater whose search reaches the ground builds
//!   nothing more (`net_world_debris` tests: 12 craters in 12 places
//!   nobody holds build 12 chunks, as with the search off). A piece
//!   reaching beyond those chunks is held by the first chunk that is not
//!   live, on every peer alike.
//! - Whatever the foci, the server keeps (builds, and does not stream
//!   out) the chunks with seeds, the chunks its search saw while it runs
//!   or waits, and the chunks a dropped result wants built until a result
//!   is applied. The pass notes them again after it starts a search, so
//!   that the next frame's streaming, which runs before it, does not
//!   release a chunk the new search just saw (the search would be dropped
//!   and run again over the chunk restored).
//! - A result is applied only when every chunk it *depends on* (those it
//!   takes solid from and their live neighbours across a side) is idle —
//!   no job running, no carve or undo queued — and no carve waits for it
//!   in the world (a carve routed to it before it was live), besides
//!   having the state hash the search saw.
//!
//! Each applied result is recorded (`AppliedDetach`: the chunks it
//! depends on, one seed per piece, the new state hash of each chunk) and
//! the server numbers it in the world's order as the next op, in the same
//! frame, before any later carve is numbered.
//!
//! *Why the op is well placed.* Carves reach a chunk in `seq` order: a
//! world carve waits in the world for a chunk that is not live, is handed
//! to the chunk's queue once it is, then runs as the chunk's job. At the
//! apply, for every chunk `c` the result depends on: nothing waits for
//! `c` in the world, nothing waits in its queue and no job runs, so every
//! carve numbered so far that reaches `c` is applied to `c`; and the op
//! is numbered after all of them and before any later one. So the state
//! the search saw is, in every chunk it depends on, "every op before the
//! detach applied" — the same on every peer, whatever it streams.
//!
//! **Followers.** A client's own pass is off (its seeds are dropped). It
//! processes the op at its place in the order, as a carve: it routes no
//! later op until the detach is applied, builds or restores every chunk
//! of the op it does not hold live (and keeps them while the op waits),
//! waits until none has a carve waiting or a job running — then each is
//! in its state after every op before the detach — and runs the same
//! exact search over exactly those chunks (every other side anchors, as a
//! chunk that is not live does) from the seeds sent, with no limits. It
//! applies the result as the server's pass applies one (the same octree
//! swaps, jobs, [`TerrainDebris`](crate::terrain::TerrainDebris) and
//! [`DebrisDetached`](crate::terrain::DebrisDetached)), and every chunk of
//! the op reports its state hash at the op's `seq` (changed or not).
//!
//! *Why the follower finds the same pieces.* Let `L` be the server's live
//! chunks when it searched, `P` one of its pieces and `D` the chunks sent.
//! `P`'s cells lie in chunks it takes solid from, and every live side
//! neighbour of those is in `D`, so in the graph over `D` `P` has the same
//! neighbours as over `L` (none outside `P`: it was a whole component)
//! and touches no side towards a chunk that is not in `D` (such a chunk is
//! not in `L` either, so that side anchored on the server, and `P` is
//! unanchored): `P` is a whole unanchored component over `D`. Conversely a
//! component unanchored over `D` touches no side towards a chunk outside
//! `D`, so it is a component over `L` too, unanchored: fewer chunks can
//! only anchor more. The seeds sent are seeds the server searched from
//! (for each piece the first of them that meets it), so every component
//! they reach over `D` was reached on the server: the follower finds
//! exactly the server's pieces, cell for cell. Their total is the
//! server's, within the server's limits; the follower searches with none,
//! so it never explores less than the server did.
//!
//! A chunk that lost a part counts as edited on every peer (stored when
//! streamed out with its part taken out, in world snapshots, in the world
//! hash). A snapshot chunk that holds the op (its last op at or after the
//! op's `seq`) is not searched again.

use std::collections::BTreeSet;

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, ChunkOctree, ChunkedDetached, DebrisLimits};

use super::debris::{DebrisSearch, SeenChunk, busy, launch};
use super::{Chunk, ChunkCoord, TerrainWorld};
use crate::terrain::component::Terrain;

/// Most chunks one ordered detach depends on; a server's result over more
/// is not applied (its pieces stay, held).
pub const MAX_DETACH_CHUNKS: usize = 64;

/// Most pieces (one seed each) of one ordered detach; a server's result
/// with more is not applied.
pub const MAX_DETACH_SEEDS: usize = 1024;

/// Who decides what falls across chunk borders in a world.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum DebrisRole {
    /// Not networked: the world's own pass.
    #[default]
    Local,
    /// A networked world's server: its own pass, each applied result
    /// recorded to be ordered.
    Serve,
    /// A networked world's client: no pass of its own; the detaches the
    /// server ordered are carried out.
    Follow,
}

/// A detach the server ordered, for a follower to carry out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct OrderedDetach {
    /// Its place in the world's order.
    pub(crate) seq: u64,
    /// The chunks it searches, in coordinate order.
    pub(crate) chunks: Vec<ChunkCoord>,
    /// Where it searches from: a chunk of `chunks` and a cell there.
    pub(crate) seeds: Vec<(ChunkCoord, CellKey)>,
}

/// A detach across chunk borders applied in a networked world.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct AppliedDetach {
    /// Its place in the order (a follower's), or `None` on the server,
    /// which numbers it.
    pub(crate) seq: Option<u64>,
    /// The chunks it depends on, in coordinate order.
    pub(crate) chunks: Vec<ChunkCoord>,
    /// One seed per piece (on the server).
    pub(crate) seeds: Vec<(ChunkCoord, CellKey)>,
    /// Each chunk of `chunks` with its new state hash, `None` when
    /// unchanged.
    pub(crate) hashes: Vec<(ChunkCoord, Option<u64>)>,
}

/// Whether cell keys `a` and `b` are the same cell or one holds the other.
#[must_use]
pub(crate) fn nested(a: CellKey, b: CellKey) -> bool {
    let (outer, inner) = if a.depth <= b.depth { (a, b) } else { (b, a) };
    let shift = u32::from(inner.depth - outer.depth);
    (0..3).all(|i| inner.pos[i].checked_shr(shift).unwrap_or(0) == outer.pos[i])
}

/// The 3×3 chunks centred on `coord`.
fn around(coord: ChunkCoord) -> impl Iterator<Item = ChunkCoord> {
    (-1..=1).flat_map(move |dx| {
        (-1..=1).map(move |dz| ChunkCoord {
            x: coord.x + dx,
            z: coord.z + dz,
        })
    })
}

/// Whether every chunk a server's search wants built first is live or
/// failed.
pub(super) fn wanted_built(world: &TerrainWorld) -> bool {
    (world.debris_wanted.iter())
        .all(|c| matches!(world.chunks.get(c), Some(Chunk::Live(_) | Chunk::Failed)))
}

/// A server's finished search: the chunks across the open sides where it
/// stopped (a side listed as an anchor only because the chunk across was
/// not live) that lie around a chunk it searched from and are neither
/// live nor failed. Empty on other roles, and when the search failed.
pub(super) fn chunks_across_open_sides(
    world: &TerrainWorld,
    search: &DebrisSearch,
) -> BTreeSet<ChunkCoord> {
    let mut wanted = BTreeSet::new();
    let Some(detached) = search
        .detached()
        .filter(|_| world.debris_role == DebrisRole::Serve)
    else {
        return wanted;
    };
    let seen: Vec<ChunkCoord> = search.chunks().collect();
    let seeded: BTreeSet<ChunkCoord> = search.seeded().map(|i| seen[i]).collect();
    for &(chunk, side) in &detached.held_at_open_sides {
        if side.axis == 1 {
            continue;
        }
        let step = if side.upper { 1 } else { -1 };
        let coord = seen[chunk];
        let across = if side.axis == 0 {
            ChunkCoord {
                x: coord.x + step,
                z: coord.z,
            }
        } else {
            ChunkCoord {
                x: coord.x,
                z: coord.z + step,
            }
        };
        let near_seeds = seeded.iter().any(|&s| around(s).any(|c| c == across));
        let built = matches!(
            world.chunks.get(&across),
            Some(Chunk::Live(_) | Chunk::Failed)
        );
        if near_seeds && !built {
            wanted.insert(across);
        }
    }
    wanted
}

/// Notes the chunks the world must build and keep for debris across
/// borders: on a server those around seeded chunks and those its search
/// saw, on a follower those of the ordered detach.
pub(super) fn keep_chunks(world: &mut TerrainWorld, terrains: &Query<&mut Terrain>) {
    let mut keep = BTreeSet::new();
    match world.debris_role {
        DebrisRole::Local => {}
        DebrisRole::Serve => {
            for (coord, entity) in world.live_chunks() {
                if terrains
                    .get(entity)
                    .is_ok_and(|t| !t.runtime.border_seeds.is_empty())
                {
                    keep.insert(coord);
                }
            }
            if let Some(search) = &world.debris_search {
                keep.extend(search.chunks());
            }
            keep.extend(world.debris_wanted.iter().copied());
        }
        DebrisRole::Follow => {
            if let Some(ordered) = &world.detach_ordered {
                keep.extend(ordered.chunks.iter().copied());
            }
        }
    }
    world.debris_keep = keep;
}

/// Starts the search of a follower's ordered detach once every chunk of
/// it is live (or failed to build), idle and with no carve waiting.
pub(super) fn start_ordered(world: &mut TerrainWorld, terrains: &Query<&mut Terrain>) {
    if world.debris_search.is_some() {
        return;
    }
    let Some(ordered) = world.detach_ordered.clone() else {
        return;
    };
    let (mut chunks, mut seen) = (Vec::new(), Vec::new());
    for &coord in &ordered.chunks {
        if world.pending.contains_key(&coord) {
            return;
        }
        match world.chunks.get(&coord) {
            Some(Chunk::Live(entity)) => {
                let Ok(terrain) = terrains.get(*entity) else {
                    return;
                };
                if busy(terrain) {
                    return;
                }
                let Some(config) = &terrain.debris else {
                    continue;
                };
                chunks.push(ChunkOctree {
                    octree: terrain.octree.clone(),
                    anchors: config.anchors.clone(),
                });
                seen.push(SeenChunk {
                    coord,
                    entity: *entity,
                    hash: terrain.hash.value(),
                });
            }
            Some(Chunk::Failed) => {}
            _ => return,
        }
    }
    let mut near: Vec<(usize, CellKey)> = (ordered.seeds.iter())
        .filter_map(|(coord, key)| {
            let i = seen.iter().position(|s| s.coord == *coord)?;
            Some((i, *key))
        })
        .collect();
    near.sort_unstable();
    near.dedup();
    let _span = bevy::log::info_span!("chisel::world::detach_ordered").entered();
    launch(
        world,
        chunks,
        seen,
        Vec::new(),
        near,
        DebrisLimits::default(),
        Some(ordered.seq),
    );
}

/// The record of a server's result before it is applied: the chunks it
/// depends on (`depends`, by the search's chunk index into `seen`) and,
/// for each piece, the first seed of `near` that meets it.
///
/// # Errors
/// When it is over [`MAX_DETACH_CHUNKS`] or [`MAX_DETACH_SEEDS`], or (never
/// expected) a piece no seed meets: it is then not applied.
pub(super) fn record(
    detached: &ChunkedDetached,
    near: &[(usize, CellKey)],
    seen: &[ChunkCoord],
    depends: &[usize],
) -> Result<AppliedDetach, String> {
    if depends.len() > MAX_DETACH_CHUNKS || detached.pieces.len() > MAX_DETACH_SEEDS {
        return Err(format!(
            "{} pieces over {} chunks, more than a networked world orders \
             ({MAX_DETACH_SEEDS} pieces, {MAX_DETACH_CHUNKS} chunks)",
            detached.pieces.len(),
            depends.len()
        ));
    }
    let mut seeds = Vec::new();
    for piece in &detached.pieces {
        let meets = |&&(chunk, key): &&(usize, CellKey)| {
            (piece.parts.iter())
                .filter(|part| part.chunk == chunk)
                .any(|part| part.piece.leaves.iter().any(|&leaf| nested(key, leaf)))
        };
        match near.iter().find(meets) {
            Some(&(chunk, key)) if depends.contains(&chunk) => seeds.push((seen[chunk], key)),
            _ => return Err("a piece that no seed meets".into()),
        }
    }
    seeds.sort_unstable();
    seeds.dedup();
    Ok(AppliedDetach {
        seq: None,
        chunks: depends.iter().map(|&j| seen[j]).collect(),
        seeds,
        hashes: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(depth: u8, pos: [u32; 3]) -> CellKey {
        CellKey { depth, pos }
    }

    #[test]
    fn cells_nest_only_in_their_ancestors() {
        let leaf = key(3, [5, 2, 7]);
        assert!(nested(leaf, leaf));
        assert!(nested(CellKey::ROOT, leaf));
        assert!(nested(key(1, [1, 0, 1]), leaf));
        assert!(nested(leaf, key(2, [2, 1, 3])), "either order");
        assert!(!nested(key(1, [0, 0, 1]), leaf));
        assert!(!nested(key(3, [5, 2, 6]), leaf), "a sibling");
        assert!(nested(leaf, key(5, [21, 8, 31])));
        assert!(!nested(leaf, key(5, [24, 8, 31])));
    }

    /// A server's result over four chunks in a row, recorded, and searched
    /// again as a follower does — over only the chunks it depends on, from
    /// the recorded seeds — gives the same pieces and the same chunks, bit
    /// for bit, one seed per piece.
    #[test]
    fn a_follower_finds_the_servers_pieces_over_the_chunks_sent() {
        use chisel_bsp::octree::{
            Anchors, CellBox, CubeSide, Edit, ExactVolume, Octree, OctreeConfig, Tool,
            detach_across_chunks,
        };
        let cube = |min, max| Tool::cuboid(CellBox { min, max }).expect("a box");
        let side = |axis, upper| CubeSide { axis, upper };
        let anchors = Anchors {
            sides: vec![
                CubeSide::BOTTOM,
                side(0, false),
                side(0, true),
                side(2, false),
                side(2, true),
            ],
            boxes: Vec::new(),
        };
        let mut chunks: Vec<ChunkOctree> = (0..4)
            .map(|i| ChunkOctree {
                octree: Octree::new([1024 * i, 0, 0], 10, 0, OctreeConfig::default())
                    .expect("an octree"),
                anchors: anchors.clone(),
            })
            .collect();
        let solids = [
            ([900, 0, 100], [1000, 300, 200]),   // pillar in chunk 0
            ([900, 300, 100], [1100, 400, 200]), // slab over 0 | 1
            ([100, 500, 100], [200, 600, 200]),  // floating, far from the cut
            ([2000, 0, 100], [3100, 50, 200]),   // ground bar over 2 | 3
        ];
        for chunk in &mut chunks {
            for (min, max) in solids {
                let b = CellBox { min, max };
                if b.overlaps(&chunk.octree.root_box()) {
                    chunk
                        .octree
                        .apply(&cube(min, max), Edit::Add(1))
                        .expect("adds");
                }
            }
        }
        let cut = cube([890, 100, 90], [1010, 150, 210]);
        let changes = chunks[0].octree.apply(&cut, Edit::Subtract).expect("cuts");
        let near: Vec<(usize, CellKey)> = changes.changed.iter().map(|&k| (0, k)).collect();
        let before = chunks.clone();
        let server =
            detach_across_chunks(&mut chunks, &near, DebrisLimits::default()).expect("searched");
        assert!(!server.pieces.is_empty());
        let seen: Vec<ChunkCoord> = (0..4).map(|x| ChunkCoord { x, z: 0 }).collect();
        let depends = [0, 1, 2];
        let recorded = record(&server, &near, &seen, &depends).expect("recorded");
        assert_eq!(recorded.chunks, seen[..3]);
        // One seed may meet several pieces (a coarse changed cell holds
        // the floating block too): it finds them all again.
        assert!((1..=server.pieces.len()).contains(&recorded.seeds.len()));
        for (_, key) in &recorded.seeds {
            assert!(near.iter().any(|(_, k)| k == key), "a server seed");
        }

        let mut follower: Vec<ChunkOctree> = before[..3].to_vec();
        let from: Vec<(usize, CellKey)> = (recorded.seeds.iter())
            .map(|&(c, k)| (usize::try_from(c.x).expect("index"), k))
            .collect();
        let found =
            detach_across_chunks(&mut follower, &from, DebrisLimits::default()).expect("searched");
        assert_eq!(found.pieces.len(), server.pieces.len());
        for (a, b) in found.pieces.iter().zip(&server.pieces) {
            assert_eq!(a.volume(), b.volume());
        }
        // The slab and the pillar above the cut fell over two chunks.
        let slab = ExactVolume::from_integer(100 * 150 * 100 + 200 * 100 * 100);
        assert!(
            server
                .pieces
                .iter()
                .any(|p| p.parts.len() == 2 && p.volume() == slab)
        );
        for (i, chunk) in follower.iter().enumerate() {
            assert!(
                chunk.octree.to_bytes() == chunks[i].octree.to_bytes(),
                "chunk {i} as on the server"
            );
        }

        let too_many: Vec<usize> = (0..=MAX_DETACH_CHUNKS).collect();
        assert!(record(&server, &near, &seen, &too_many).is_err());
    }

    #[test]
    fn around_is_the_three_by_three_block() {
        let all: BTreeSet<ChunkCoord> = around(ChunkCoord { x: 4, z: -2 }).collect();
        assert_eq!(all.len(), 9);
        assert!(all.contains(&ChunkCoord { x: 3, z: -3 }));
        assert!(all.contains(&ChunkCoord { x: 5, z: -1 }));
        assert!(!all.contains(&ChunkCoord { x: 6, z: -2 }));
    }
}
