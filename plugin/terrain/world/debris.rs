//! Debris across chunk borders: a piece a carve cuts loose that reaches
//! over one or more chunk borders falls as one body.
//!
//! Each chunk's carve job detaches, on its own, the pieces that lie within
//! the chunk ([`super::chunk_debris`] anchors the chunk's four sides, so a
//! job never detaches what may rest on a neighbour). Solid that touches a
//! side is left for this pass, which sees all live chunks of the world
//! together ([`chisel_bsp::octree::detach_across_chunks`]):
//!
//! 1. Every carve a chunk's job applies leaves the leaves it changed as
//!    *seeds* in the chunk's runtime ([`crate::terrain::upload::finish_jobs`]).
//! 2. [`detach_across_borders`] runs between collecting finished jobs and
//!    starting new ones. When a live chunk has seeds, it joins the octrees
//!    of all live chunks of the world (cheap persistent clones): cells
//!    connect across a shared side where their faces there overlap with
//!    positive area, exactly, and the chunks' own anchors hold (the bottom
//!    and the base's floor). A side towards a chunk that is not live
//!    anchors, so nothing falls that leans on solid the world cannot see.
//!    Each piece no anchor holds, over two chunks across a side or four
//!    around a corner, is found as one and taken out of every chunk
//!    exactly.
//! 3. Each chunk that lost a part swaps in its octree with the part taken
//!    out, updates its state hash, and queues a job at the head of its
//!    queue that rebuilds the changed cells; the chunk of the piece's
//!    first part also builds the piece there, as one [`TerrainDebris`]
//!    (one body and collider of all parts, a mesh per part and material)
//!    that it spawns and reports ([`DebrisDetached`]) when its cells are
//!    shown. Both name that chunk's terrain entity.
//!
//! Rules across chunks:
//! - **Busy chunks.** A chunk whose job is running would overwrite a
//!   detach when its job finishes. When a piece has a part in such a
//!   chunk, nothing is taken out and the seeds wait for the next frame;
//!   the pass is exact and deterministic, so it finds the same pieces
//!   again (or fewer, when a later carve added support).
//! - **Limits.** [`TerrainWorld::with_debris_limits`] bounds what one pass
//!   takes out across borders, all pieces in all chunks together. The
//!   carves that cut them loose are already applied, each in its own
//!   chunk (a chunk's job refuses a carve over the chunk's own
//!   [`DebrisConfig`](crate::terrain::DebrisConfig) limits as a single
//!   terrain does). Over the world's limits the pass takes out nothing:
//!   the pieces stay in place, held, and a warning is logged; a later
//!   carve next to them looks again.
//! - **Undo.** The removal joins the chunk's last undo step: undoing that
//!   carve brings the chunk's part back, as undo does for debris within a
//!   terrain; other chunks keep their parts out. A chunk with no undo
//!   step of its own keeps its part out.
//! - **Streaming and files.** A chunk that lost a part counts as edited
//!   even with no carve of its own: it is kept while streamed out and
//!   saved with the world.
//! - **Determinism.** The chunks' octrees, the seeds and the kernel's
//!   search are exact, so the same carves give the same pieces and the
//!   same chunks, bit for bit. Journals record carves only: replaying one
//!   chunk's journal alone gives its state before any detach across
//!   borders.
//!
//! [`TerrainDebris`]: crate::terrain::TerrainDebris
//! [`DebrisDetached`]: crate::terrain::DebrisDetached

use std::collections::BTreeMap;

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, ChunkOctree, ChunkedPiece, Octree, detach_across_chunks};

use super::TerrainWorld;
use crate::terrain::component::Terrain;
use crate::terrain::jobs::Job;

/// Finds the pieces cut loose across chunk borders since the last pass,
/// takes them out of their chunks and queues their rebuild and spawn.
pub fn detach_across_borders(
    mut worlds: Query<&mut TerrainWorld>,
    mut terrains: Query<&mut Terrain>,
) {
    for mut world in &mut worlds {
        let live: Vec<Entity> = world.live_chunks().map(|(_, e)| e).collect();
        let seeded = live.iter().any(|&e| {
            terrains
                .get(e)
                .is_ok_and(|t| !t.runtime.border_seeds.is_empty())
        });
        if !seeded {
            continue;
        }
        let _span = bevy::log::info_span!("chisel::world::detach_across_borders").entered();
        let mut chunks = Vec::new();
        let mut entities = Vec::new();
        let mut near: Vec<(usize, CellKey)> = Vec::new();
        for &entity in &live {
            let Ok(terrain) = terrains.get(entity) else {
                continue;
            };
            // A chunk without debris detection is left out: it anchors
            // what touches it, as a chunk not loaded does.
            let Some(config) = &terrain.debris else {
                continue;
            };
            let i = chunks.len();
            let mut seeds = terrain.runtime.border_seeds.clone();
            seeds.sort_unstable();
            seeds.dedup();
            near.extend(seeds.into_iter().map(|key| (i, key)));
            chunks.push(ChunkOctree {
                octree: terrain.octree.clone(),
                anchors: config.anchors.clone(),
            });
            entities.push(entity);
        }
        let clear_seeds = |terrains: &mut Query<&mut Terrain>| {
            for &entity in &live {
                if let Ok(mut terrain) = terrains.get_mut(entity) {
                    terrain.runtime.border_seeds.clear();
                }
            }
        };
        let detached = match detach_across_chunks(&mut chunks, &near, world.debris_limits) {
            Ok(detached) => detached,
            Err(error) => {
                warn!("terrain world: no debris detached across chunk borders: {error}");
                clear_seeds(&mut terrains);
                continue;
            }
        };
        let touched = |i: usize| {
            let c = &detached.changes[i];
            !(c.changed.is_empty() && c.removed.is_empty())
        };
        let busy = (0..entities.len()).any(|i| {
            touched(i)
                && terrains
                    .get(entities[i])
                    .is_ok_and(|t| t.runtime.task.is_some())
        });
        if busy {
            continue;
        }
        clear_seeds(&mut terrains);
        world.stats.detached_across += detached.pieces.len() as u64;
        // Each piece is built and spawned by the chunk of its first part.
        let mut spawned_by: BTreeMap<usize, Vec<ChunkedPiece>> = BTreeMap::new();
        for piece in detached.pieces {
            if let Some(first) = piece.parts.first() {
                spawned_by.entry(first.chunk).or_default().push(piece);
            }
        }
        let octrees: Vec<Octree> = chunks.into_iter().map(|c| c.octree).collect();
        for (i, (octree, changes)) in octrees.into_iter().zip(detached.changes).enumerate() {
            let pieces = spawned_by.remove(&i).unwrap_or_default();
            if changes.changed.is_empty() && changes.removed.is_empty() && pieces.is_empty() {
                continue;
            }
            let Ok(mut terrain) = terrains.get_mut(entities[i]) else {
                continue;
            };
            let terrain = &mut *terrain;
            terrain.octree = octree;
            terrain.hash.update(
                &terrain.octree,
                changes.changed.iter().chain(&changes.removed),
            );
            if let Some(step) = terrain.history.back_mut() {
                step.changes = step.changes.then(&changes);
            }
            terrain.detached_across = true;
            let mut keys: Vec<CellKey> =
                changes.changed.into_iter().chain(changes.removed).collect();
            keys.sort_unstable();
            keys.dedup();
            terrain
                .runtime
                .queue
                .push_front(Job::Detached { keys, pieces });
        }
    }
}
