//! Debris across chunk borders in a world whose chunks stream out while
//! the search runs (`MinimalPlugins`): a slab over the border x = 32 on a
//! pillar that a carve cuts through, with one of its chunks or both
//! streamed out in the frame after the search took the cut's seeds. The
//! search goes stale; the seeds it took are stored with the chunk that
//! left, and once the chunks are back the slab falls as one
//! [`TerrainDebris`] with its exact volume, leaving the chunks exactly as
//! in a world where nothing streamed out. Chunks that come back one at a
//! time still let it fall: the seeds wait for the neighbour streaming in.
//!
//! [`TerrainDebris`]: bevy_chisel::terrain::TerrainDebris

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, ExactVolume, StateHash};
use bevy_chisel::terrain::{ChunkCoord, StreamSettings, Terrain, TerrainWorld, WorldCarve};

use super::terrain_world::{app_with, settle, terrain, the_world, world};
use super::terrain_world_debris::{CUT, build_slab, cuboid, cut_until_searching, debris, falling};

/// The focus the slab is built around, on the border of its chunks.
const SLAB_FOCUS: Vec3 = Vec3::new(32.0, 30.0, 16.0);

const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// The slab's chunks: the pillar's and the neighbour's.
const SLAB_CHUNKS: [ChunkCoord; 2] = [at(0, 0), at(1, 0)];

/// Each chunk's kept state hash, the hash of its octree computed afresh
/// and its exact solid volume.
fn states(app: &App, world: Entity, coords: &[ChunkCoord]) -> Vec<(u64, u64, ExactVolume)> {
    coords
        .iter()
        .map(|&c| {
            let t = terrain(app, world, c);
            let octree = t.octree();
            let fresh = StateHash::of(octree).value();
            (t.state_hash(), fresh, octree.exact_solid_volume())
        })
        .collect()
}

/// Moves the focus to `to`, its global transform too: streaming sees it
/// in the next frame, not after the next frame's transform propagation.
pub(super) fn move_focus(app: &mut App, focus: Entity, to: Vec3) {
    let mut entity = app.world_mut().entity_mut(focus);
    entity.get_mut::<Transform>().expect("focus").translation = to;
    *entity.get_mut::<GlobalTransform>().expect("placed") = GlobalTransform::from_translation(to);
}

/// The slab's chunks after the same carves in a world where nothing
/// streamed out.
fn reference(new_world: &dyn Fn() -> TerrainWorld) -> Vec<(u64, u64, ExactVolume)> {
    let (mut app, world, _) = app_with(new_world(), SLAB_FOCUS);
    build_slab(&mut app, world, false);
    app.world_mut().write_message(WorldCarve {
        world,
        tool: cuboid(CUT.0, CUT.1),
        edit: Edit::Subtract,
    });
    settle(&mut app, world);
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1);
    assert_eq!(pieces[0].exact_volume, falling());
    states(&app, world, &SLAB_CHUNKS)
}

/// Builds the slab in `new_world()`, cuts its pillar, and in the frame
/// after the search took the cut's seeds moves the focus to `away`, where
/// chunks `out` stream out in the next frame (and the others of the
/// slab stay); then settles, brings the focus to `back` and settles.
/// Checks that the slab falls then, exactly as in [`reference`].
fn falls_after_streaming(
    new_world: &dyn Fn() -> TerrainWorld,
    away: Vec3,
    out: &[ChunkCoord],
    back: Vec3,
) {
    let (mut app, world, focus) = app_with(new_world(), SLAB_FOCUS);
    build_slab(&mut app, world, false);
    let dropped = the_world(&app, world).stats().debris_searches_dropped;
    cut_until_searching(&mut app, world);
    assert!(
        terrain(&app, world, at(0, 0)).border_seeds().is_empty(),
        "the search took the cut's seeds"
    );
    // The search is applied in a later frame at the earliest; the chunks
    // stream out first in the next one.
    move_focus(&mut app, focus, away);
    app.update();
    let w = the_world(&app, world);
    for c in SLAB_CHUNKS {
        let live = w.chunk_entity(c).is_some();
        assert_eq!(live, !out.contains(&c), "{c:?} streamed out or stayed");
    }
    let stored = w.stored_chunk(at(0, 0)).map(Terrain::from_bytes);
    if out.contains(&at(0, 0)) {
        let stored = stored.expect("stored").expect("valid bytes");
        assert!(
            !stored.border_seeds().is_empty(),
            "the seeds the search took are stored with the chunk"
        );
    }
    settle(&mut app, world);
    let w = the_world(&app, world);
    assert_eq!(
        w.stats().debris_searches_dropped,
        dropped + 1,
        "the search went stale"
    );
    assert!(debris(&mut app).is_empty(), "nothing fell while out");
    assert_eq!(the_world(&app, world).stats().detached_across, 0);

    move_focus(&mut app, focus, back);
    settle(&mut app, world);
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1, "the slab falls once the chunks are back");
    assert_eq!(pieces[0].exact_volume, falling());
    assert_eq!(the_world(&app, world).stats().detached_across, 1);
    assert_eq!(
        states(&app, world, &SLAB_CHUNKS),
        reference(new_world),
        "the chunks are as if nothing streamed out"
    );
}

/// The pillar's chunk (0, 0) streams out (the focus is 78 from it, 46
/// from the neighbour, which the hysteresis keeps), then comes back.
#[test]
fn the_slab_falls_after_its_cut_chunk_streams_out_during_the_search() {
    let away = Vec3::new(110.0, 30.0, 16.0);
    falls_after_streaming(&world, away, &[at(0, 0)], SLAB_FOCUS);
}

/// Both chunks stream out, and come back one at a time: with one build
/// at a time and the focus at x = 4, chunk (0, 0) is built first and its
/// neighbour (1, 0), 28 away, seventh. The seeds wait for it (searched
/// before, the neighbour's side would hold the slab for good).
#[test]
fn the_slab_falls_after_both_chunks_stream_out_and_back_one_at_a_time() {
    let one_build = || {
        world()
            .with_streaming(StreamSettings {
                load_radius: 40.0,
                unload_radius: 72.0,
                max_building: 1,
            })
            .expect("valid settings")
    };
    let away = Vec3::new(1000.0, 30.0, 16.0);
    let back = Vec3::new(4.0, 30.0, 16.0);
    falls_after_streaming(&one_build, away, &SLAB_CHUNKS, back);
}
