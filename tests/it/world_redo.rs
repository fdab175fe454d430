//! Redo across a streamed world (`MinimalPlugins`): one [`WorldRedo`]
//! gives every chunk a world undo changed its octree (bit for bit), state
//! hash, journal and undo depth of before the undo (over a border, over a
//! corner, with a slab cut loose across a border, with the chunks
//! streamed out and in), several redo in reverse order of their undos, a
//! new carve forgets them, a chunk changed since refuses the redo and
//! nothing changes; a chunk's own redo step survives streaming out and in;
//! a networked world refuses it.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, StateHash};
use bevy_chisel::terrain::{
    Carve, CarveTool, ChunkCoord, RedoCarve, TerrainWorld, UndoCarve, WorldRedo, WorldRedoRefusal,
    WorldRedoRejected, WorldRedone, WorldUndo, WorldUndone,
};

use super::terrain_world::{app_with, settle, the_world, world as new_world};
use super::world_undo::{CUT, PILLAR, SLAB, at, carve, chunk, cuboid, debris, sphere, undo};

/// What the undo and redo messages said so far.
#[derive(Resource, Default)]
struct Heard {
    undone: Vec<WorldUndone>,
    redone: Vec<WorldRedone>,
    rejected: Vec<WorldRedoRejected>,
}

fn hear(
    mut undone: MessageReader<WorldUndone>,
    mut redone: MessageReader<WorldRedone>,
    mut rejected: MessageReader<WorldRedoRejected>,
    mut heard: ResMut<Heard>,
) {
    heard.undone.extend(undone.read().cloned());
    heard.redone.extend(redone.read().cloned());
    heard.rejected.extend(rejected.read().cloned());
}

/// A world app (focus at `focus`) that records the undo and redo
/// messages.
fn redo_app(world: TerrainWorld, focus: Vec3) -> (App, Entity, Entity) {
    let (mut app, world, focus) = app_with(world, focus);
    app.init_resource::<Heard>().add_systems(Update, hear);
    (app, world, focus)
}

fn heard(app: &App) -> &Heard {
    app.world().resource::<Heard>()
}

fn redo(app: &mut App, world: Entity) {
    app.world_mut().write_message(WorldRedo { world });
    settle(app, world);
}

fn move_focus(app: &mut App, world: Entity, focus: Entity, to: Vec3) {
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = to;
    settle(app, world);
}

/// One chunk exactly: its octree's bytes, its kept state hash, the hash
/// of its octree computed afresh, its journal length and undo depth.
type Exact = (Vec<u8>, u64, u64, usize, usize);

/// Every live chunk, exactly.
fn exact(app: &App, world: Entity) -> BTreeMap<ChunkCoord, Exact> {
    the_world(app, world)
        .live_chunks()
        .map(|(coord, _)| {
            let t = chunk(app, world, coord);
            let state = (
                t.octree().to_bytes(),
                t.state_hash(),
                StateHash::of(t.octree()).value(),
                t.journal().len(),
                t.undo_depth(),
            );
            (coord, state)
        })
        .collect()
}

/// The chunks whose exact state differs between `a` and `b`.
fn differ(a: &BTreeMap<ChunkCoord, Exact>, b: &BTreeMap<ChunkCoord, Exact>) -> Vec<ChunkCoord> {
    a.iter()
        .filter(|(c, s)| b.get(c) != Some(s))
        .map(|(c, _)| *c)
        .collect()
}

fn last_refusal(app: &App) -> Option<&WorldRedoRefusal> {
    heard(app).rejected.last().map(|r| &r.reason)
}

const CORNER: [ChunkCoord; 4] = [at(0, 0), at(0, 1), at(1, 0), at(1, 1)];

#[test]
fn a_redo_gives_back_every_chunk_of_a_carve_over_a_border_bit_for_bit() {
    let (mut app, world, _) = redo_app(new_world(), Vec3::new(32.0, 30.0, 32.0));
    let before = exact(&app, world);
    carve(
        &mut app,
        world,
        sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    let carved = exact(&app, world);
    assert_eq!(differ(&before, &carved), vec![at(0, 0), at(1, 0)]);
    undo(&mut app, world);
    assert_eq!(exact(&app, world), before);
    assert_eq!(the_world(&app, world).redo_depth(), 1);
    redo(&mut app, world);
    assert_eq!(exact(&app, world), carved, "every chunk as after the carve");
    assert_eq!(heard(&app).redone.len(), 1);
    assert_eq!(heard(&app).redone[0].chunks, vec![at(0, 0), at(1, 0)]);
    assert_eq!(heard(&app).redone[0].request, heard(&app).undone[0].request);
    let w = the_world(&app, world);
    assert_eq!((w.undo_depth(), w.redo_depth()), (1, 0));
    // Nothing is left to redo; the redone carve undoes again.
    redo(&mut app, world);
    assert_eq!(last_refusal(&app), Some(&WorldRedoRefusal::NothingToRedo));
    assert_eq!(exact(&app, world), carved);
    undo(&mut app, world);
    assert_eq!(exact(&app, world), before);

    // Over the corner, with the block's top falling across it: two
    // carves undone and redone in reverse order, asked for in one frame.
    redo(&mut app, world);
    assert_eq!(exact(&app, world), carved);
    carve(
        &mut app,
        world,
        cuboid([28, 10, 28], [36, 30, 36]),
        Edit::Add(1),
    );
    let block = exact(&app, world);
    carve(
        &mut app,
        world,
        sphere(7.0, Vec3::new(32.0, 22.0, 32.0)),
        Edit::Subtract,
    );
    let fell = exact(&app, world);
    assert_eq!(differ(&block, &fell), CORNER.to_vec());
    let bodies = debris(&mut app);
    assert!(bodies > 0, "the block's top fell across the corner");
    for _ in 0..2 {
        app.world_mut().write_message(WorldUndo { world });
    }
    settle(&mut app, world);
    assert_eq!(exact(&app, world), carved);
    for _ in 0..2 {
        app.world_mut().write_message(WorldRedo { world });
    }
    settle(&mut app, world);
    assert_eq!(exact(&app, world), fell, "both carves and the fall again");
    assert_eq!(debris(&mut app), bodies, "no new body");
    // An undo and a redo in one frame leave the chunks as they were.
    app.world_mut().write_message(WorldUndo { world });
    app.world_mut().write_message(WorldRedo { world });
    settle(&mut app, world);
    assert_eq!(exact(&app, world), fell);
    assert!(heard(&app).rejected.len() == 1, "only the redo of nothing");
}

#[test]
fn a_new_carve_forgets_the_redo() {
    let (mut app, world, _) = redo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    carve(
        &mut app,
        world,
        sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    undo(&mut app, world);
    carve(
        &mut app,
        world,
        sphere(4.0, Vec3::new(12.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    let other = exact(&app, world);
    assert_eq!(the_world(&app, world).redo_depth(), 0);
    redo(&mut app, world);
    assert_eq!(last_refusal(&app), Some(&WorldRedoRefusal::NothingToRedo));
    assert!(heard(&app).redone.is_empty());
    assert_eq!(exact(&app, world), other, "nothing changed");
}

/// A carve of chunk (1, 0)'s own after the undo refuses the redo for that
/// chunk and changes nothing, not even chunk (0, 0); once that carve is
/// undone the chunk is as the world undo left it, and the redo lands.
#[test]
fn a_chunk_changed_since_the_undo_refuses_the_redo_and_changes_nothing() {
    let (mut app, world, _) = redo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    carve(
        &mut app,
        world,
        sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    let carved = exact(&app, world);
    undo(&mut app, world);
    let own = the_world(&app, world)
        .chunk_entity(at(1, 0))
        .expect("chunk (1, 0) is live");
    app.world_mut().write_message(Carve {
        terrain: own,
        tool: sphere(3.0, Vec3::new(44.0, 16.0, 20.0)),
        edit: Edit::Subtract,
    });
    settle(&mut app, world);
    let changed = exact(&app, world);
    redo(&mut app, world);
    assert_eq!(
        last_refusal(&app),
        Some(&WorldRedoRefusal::ChunkChanged { coord: at(1, 0) })
    );
    assert_eq!(exact(&app, world), changed, "no chunk changed");
    assert_eq!(the_world(&app, world).redo_depth(), 1, "the step stays");
    app.world_mut().write_message(UndoCarve { terrain: own });
    settle(&mut app, world);
    redo(&mut app, world);
    assert_eq!(exact(&app, world), carved);
    assert_eq!(heard(&app).rejected.len(), 1);
}

/// The undo takes both chunks back to the source's state, so they stream
/// out with nothing stored; the redo, asked for while they are out,
/// builds them again, redoes the carve there, and they stream out stored.
/// Asked for after they streamed back in, it lands alike.
#[test]
fn a_redo_survives_its_chunks_streaming_out_and_in() {
    for while_out in [true, false] {
        let near = Vec3::new(32.0, 30.0, 16.0);
        let (mut app, world, focus) = redo_app(new_world(), near);
        carve(
            &mut app,
            world,
            sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
            Edit::Subtract,
        );
        let carved = exact(&app, world);
        undo(&mut app, world);
        move_focus(&mut app, world, focus, Vec3::new(8.0 * 32.0, 30.0, 16.0));
        let w = the_world(&app, world);
        assert!(w.chunk_entity(at(0, 0)).is_none() && w.chunk_entity(at(1, 0)).is_none());
        assert!(w.stored_chunks().next().is_none(), "unedited, not stored");
        if while_out {
            redo(&mut app, world);
            let w = the_world(&app, world);
            let stored: Vec<_> = w.stored_chunks().collect();
            assert_eq!(stored, vec![at(0, 0), at(1, 0)], "redone and stored");
            move_focus(&mut app, world, focus, near);
        } else {
            move_focus(&mut app, world, focus, near);
            redo(&mut app, world);
        }
        assert_eq!(heard(&app).redone[0].chunks, vec![at(0, 0), at(1, 0)]);
        assert_eq!(exact(&app, world), carved, "redone while out: {while_out}");
        undo(&mut app, world);
        assert_eq!(heard(&app).undone.len(), 2, "the redone carve undoes");
    }
}

/// A chunk's own undo takes it back to the source's state: it streams out
/// with no file, and the world keeps its redo step, handed back when it
/// streams in, so its [`RedoCarve`] redoes the carve exactly.
#[test]
fn a_chunk_keeps_its_own_redo_step_through_streaming() {
    let near = Vec3::new(16.0, 30.0, 16.0);
    let (mut app, world, focus) = redo_app(new_world(), near);
    carve(
        &mut app,
        world,
        CarveTool::dodecahedron(5.0, Vec3::new(12.0, 12.0, 12.0)),
        Edit::Subtract,
    );
    let carved = exact(&app, world);
    let entity = |app: &App| {
        the_world(app, world)
            .chunk_entity(at(0, 0))
            .expect("chunk (0, 0) is live")
    };
    let first = entity(&app);
    app.world_mut().write_message(UndoCarve { terrain: first });
    settle(&mut app, world);
    assert_eq!(chunk(&app, world, at(0, 0)).redo_depth(), 1);
    move_focus(&mut app, world, focus, Vec3::new(8.0 * 32.0, 30.0, 16.0));
    let w = the_world(&app, world);
    assert!(w.chunk_entity(at(0, 0)).is_none(), "streamed out");
    assert!(w.stored_chunks().next().is_none(), "unedited, not stored");
    move_focus(&mut app, world, focus, near);
    let second = entity(&app);
    assert_ne!(first, second, "built again");
    assert_eq!(chunk(&app, world, at(0, 0)).redo_depth(), 1, "handed back");
    app.world_mut().write_message(RedoCarve { terrain: second });
    settle(&mut app, world);
    assert_eq!(exact(&app, world), carved);
    // The world's undo still takes the carve back.
    undo(&mut app, world);
    assert_eq!(heard(&app).undone.len(), 1);
}

/// Cutting the pillar drops the slab from both chunks as one body; the
/// undo gives it back to both chunks, the redo takes it out of both
/// again, exactly as after the cut and its fall, and spawns no body.
#[test]
fn a_redo_takes_a_slab_cut_loose_across_a_border_out_again() {
    let (mut app, world, _) = redo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    carve(&mut app, world, cuboid(PILLAR.0, PILLAR.1), Edit::Add(1));
    carve(&mut app, world, cuboid(SLAB.0, SLAB.1), Edit::Add(1));
    let before = exact(&app, world);
    carve(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    assert_eq!(debris(&mut app), 1, "the slab fell");
    let cut = exact(&app, world);
    assert_eq!(differ(&before, &cut), vec![at(0, 0), at(1, 0)]);
    let label = |app: &App, c, p| chunk(app, world, c).octree().label_at(p).expect("inside");
    undo(&mut app, world);
    assert_eq!(exact(&app, world), before);
    assert_eq!(label(&app, at(1, 0), [35, 26, 12]), Some(1));
    redo(&mut app, world);
    assert_eq!(exact(&app, world), cut, "both chunks as after the fall");
    assert_eq!(label(&app, at(1, 0), [35, 26, 12]), Some(0));
    assert_eq!(debris(&mut app), 1, "no new body");
    assert_eq!(heard(&app).redone[0].chunks, vec![at(0, 0), at(1, 0)]);
    // And back again.
    undo(&mut app, world);
    assert_eq!(exact(&app, world), before);
    assert!(heard(&app).rejected.is_empty());
}

#[test]
fn a_networked_world_refuses_redo_on_server_and_client() {
    use crate::net::{run_until, unlimited, world_client, world_of, world_server};
    use crate::net_worlds::{streamed_world, world_settled};

    let _guard = crate::ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = world_server(streamed_world(), unlimited());
    let mut client = world_client(addr, 1, streamed_world(), Vec3::new(32.0, 30.0, 16.0));
    for app in [&mut server, &mut client] {
        app.init_resource::<Heard>().add_systems(Update, hear);
    }
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        !apps[1]
            .world()
            .resource::<crate::net::WorldsSeen>()
            .synced
            .is_empty()
            && world_settled(apps[1])
    });
    for app in [&mut server, &mut client] {
        let (entity, _) = world_of(app);
        app.world_mut().write_message(WorldRedo { world: entity });
    }
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        apps.iter().all(|app| !heard(app).rejected.is_empty())
    });
    for app in [&server, &client] {
        let reasons: Vec<_> = heard(app).rejected.iter().map(|r| &r.reason).collect();
        assert_eq!(reasons, vec![&WorldRedoRefusal::Networked]);
        assert!(heard(app).redone.is_empty());
    }
}
