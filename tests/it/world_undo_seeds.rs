//! A [`WorldUndo`] gives the seeds its step's search took back to their
//! chunk when that chunk streamed out meanwhile (`MinimalPlugins`). A slab
//! over the border x = 32 rests on a pillar in chunk (0, 0); in one frame
//! a cut through that pillar and a second pillar added under the slab in
//! chunk (1, 0): nothing falls, and the search that found so took the
//! cut's seeds into the step of the later carve, the new pillar. With the
//! cut's chunk streamed out, undoing the new pillar stores the cut's seeds
//! with (0, 0) (the slab, leaning on the side of a chunk that is not live,
//! stays meanwhile): once it streams back, the slab falls, one
//! [`TerrainDebris`] of its exact volume, and both chunks are exactly as in
//! a world where nothing streamed out. Before, the seeds were dropped and
//! the slab stayed in the air for good.

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, ExactVolume, StateHash};
use bevy_chisel::terrain::{
    ChunkCoord, Terrain, TerrainDebris, WorldCarve, WorldUndo, WorldUndone,
};

use super::terrain_world::{app_with, settle, terrain, the_world};
use super::terrain_world_debris::{CUT, build_slab, cuboid, falling};
use super::terrain_world_debris_stream::move_focus;

const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// The focus the slab is built around, on the border of its chunks.
const SLAB_FOCUS: Vec3 = Vec3::new(32.0, 30.0, 16.0);
/// The cut's chunk and the slab's other chunk.
const CUT_CHUNK: ChunkCoord = at(0, 0);
const SLAB_CHUNK: ChunkCoord = at(1, 0);
/// The second pillar, under the slab in chunk (1, 0) only.
const PROP: ([i64; 3], [i64; 3]) = ([35, 4, 10], [38, 25, 13]);

/// Each body of debris, by entity.
fn bodies(app: &mut App) -> Vec<(Entity, TerrainDebris)> {
    let mut query = app.world_mut().query::<(Entity, &TerrainDebris)>();
    query
        .iter(app.world())
        .map(|(e, d)| (e, d.clone()))
        .collect()
}

/// Both chunks' kept state hash, fresh hash and exact solid volume.
fn states(app: &App, world: Entity) -> Vec<(u64, u64, ExactVolume)> {
    [CUT_CHUNK, SLAB_CHUNK]
        .iter()
        .map(|&c| {
            let t = terrain(app, world, c);
            let fresh = StateHash::of(t.octree()).value();
            (t.state_hash(), fresh, t.octree().exact_solid_volume())
        })
        .collect()
}

#[derive(Resource, Default)]
struct Undone(Vec<WorldUndone>);

fn hear(mut undone: MessageReader<WorldUndone>, mut heard: ResMut<Undone>) {
    heard.0.extend(undone.read().cloned());
}

/// The slab, then the cut and the second pillar in one frame, settled:
/// nothing fell. Returns the app, the world and the focus.
fn propped_slab() -> (App, Entity, Entity) {
    let (mut app, world, focus) = app_with(super::terrain_world::world(), SLAB_FOCUS);
    app.init_resource::<Undone>().add_systems(Update, hear);
    build_slab(&mut app, world, false);
    for (tool, edit) in [
        (cuboid(CUT.0, CUT.1), Edit::Subtract),
        (cuboid(PROP.0, PROP.1), Edit::Add(1)),
    ] {
        app.world_mut()
            .write_message(WorldCarve { world, tool, edit });
    }
    settle(&mut app, world);
    assert!(
        bodies(&mut app).is_empty(),
        "the second pillar holds the slab"
    );
    (app, world, focus)
}

fn undo(app: &mut App, world: Entity) {
    app.world_mut().write_message(WorldUndo { world });
    settle(app, world);
    let undone = &app.world().resource::<Undone>().0;
    assert_eq!(undone.len(), 1);
    assert_eq!(undone[0].chunks, vec![SLAB_CHUNK], "the second pillar");
    let pillar = terrain(app, world, SLAB_CHUNK)
        .octree()
        .label_at([36, 15, 11]);
    assert_eq!(
        pillar.expect("inside"),
        Some(0),
        "the second pillar is gone"
    );
}

/// The same in a world where nothing streams out: the undo gives the
/// cut's seeds back to its live chunk and the slab falls.
fn reference() -> Vec<(u64, u64, ExactVolume)> {
    let (mut app, world, _) = propped_slab();
    undo(&mut app, world);
    let fell = bodies(&mut app);
    assert_eq!(fell.len(), 1, "the slab fell");
    assert_eq!(fell[0].1.exact_volume, falling());
    states(&app, world)
}

#[test]
fn an_undo_gives_seeds_back_to_a_chunk_streamed_out_and_the_slab_falls() {
    let (mut app, world, focus) = propped_slab();
    // The cut's chunk streams out (the focus is 78 from it, 46 from the
    // slab's chunk, which the hysteresis keeps).
    move_focus(&mut app, focus, Vec3::new(110.0, 30.0, 16.0));
    settle(&mut app, world);
    let w = the_world(&app, world);
    assert!(w.chunk_entity(CUT_CHUNK).is_none(), "streamed out");
    assert!(w.chunk_entity(SLAB_CHUNK).is_some(), "kept");
    let stored = |app: &App| {
        let bytes = the_world(app, world).stored_chunk(CUT_CHUNK);
        Terrain::from_bytes(bytes.expect("stored")).expect("valid bytes")
    };
    assert!(stored(&app).border_seeds().is_empty(), "searched before");

    undo(&mut app, world);
    assert!(
        bodies(&mut app).is_empty(),
        "held by the side of a chunk not live"
    );
    assert!(
        !stored(&app).border_seeds().is_empty(),
        "the cut's seeds are stored with its chunk"
    );

    move_focus(&mut app, focus, SLAB_FOCUS);
    settle(&mut app, world);
    let fell = bodies(&mut app);
    assert_eq!(fell.len(), 1, "the slab falls once the chunk is back");
    assert_eq!(fell[0].1.exact_volume, falling());
    assert_eq!(fell[0].1.volumes.get(&1), Some(&falling()));
    assert_eq!(
        states(&app, world),
        reference(),
        "the chunks are as if nothing streamed out"
    );
}

/// The undo asked in the frame the cut's chunk starts to stream back in:
/// the chunk is being restored from its stored bytes when the undo gives
/// its seeds back, and gets them when its build is collected. Here the
/// seeds given back to the slab's chunk wait for it too (streaming wants
/// it) and would find the slab alone: this checks that the path gives
/// the same chunks and the one fall, not that it is needed.
#[test]
fn an_undo_while_the_chunk_streams_back_in_lets_the_slab_fall() {
    let (mut app, world, focus) = propped_slab();
    move_focus(&mut app, focus, Vec3::new(110.0, 30.0, 16.0));
    settle(&mut app, world);
    assert!(the_world(&app, world).chunk_entity(CUT_CHUNK).is_none());

    move_focus(&mut app, focus, SLAB_FOCUS);
    app.world_mut().write_message(WorldUndo { world });
    app.update();
    let w = the_world(&app, world);
    assert!(w.chunk_entity(CUT_CHUNK).is_none(), "not live yet");
    assert!(w.stats().building > 0, "streaming back in");
    settle(&mut app, world);
    let undone = &app.world().resource::<Undone>().0;
    assert_eq!(undone.len(), 1);
    assert_eq!(undone[0].chunks, vec![SLAB_CHUNK]);
    let fell = bodies(&mut app);
    assert_eq!(fell.len(), 1, "the slab falls once the chunk is back");
    assert_eq!(fell[0].1.exact_volume, falling());
    assert_eq!(states(&app, world), reference());
}
