//! Undo across a streamed world (`MinimalPlugins`): one [`WorldUndo`]
//! gives every chunk a world carve changed its state hash and exact volume
//! of before the carve (over a border, over a corner, with a slab cut
//! loose across a border, on a chunk streamed out), several undo in
//! reverse order, a carve asked for after an undo lands after it, and the
//! refusals change nothing.

use std::collections::BTreeMap;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, ExactVolume, StateHash};
use bevy_chisel::terrain::{
    CarveShape, CarveTool, ChunkCoord, Terrain, TerrainDebris, TerrainWorld, UndoCarve, WorldCarve,
    WorldUndo, WorldUndoRefusal, WorldUndoRejected, WorldUndone,
};

use super::terrain_world::{app_with, settle, the_world, world as new_world};

/// A box tool with grid corners `min` and `max` (grid unit 1).
pub(crate) fn cuboid(min: [i64; 3], max: [i64; 3]) -> CarveTool {
    let lo = Vec3::new(min[0] as f32, min[1] as f32, min[2] as f32);
    let hi = Vec3::new(max[0] as f32, max[1] as f32, max[2] as f32);
    CarveTool::new(
        CarveShape::Cuboid {
            half_size: (hi - lo) / 2.0,
        },
        Transform::from_translation((lo + hi) / 2.0),
    )
}

pub(crate) fn sphere(radius: f32, at: Vec3) -> CarveTool {
    CarveTool::new(
        CarveShape::Sphere {
            radius,
            tolerance: None,
        },
        Transform::from_translation(at),
    )
}

pub(crate) const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// What the undo messages said so far.
#[derive(Resource, Default)]
struct Heard {
    undone: Vec<WorldUndone>,
    rejected: Vec<WorldUndoRejected>,
}

fn hear(
    mut undone: MessageReader<WorldUndone>,
    mut rejected: MessageReader<WorldUndoRejected>,
    mut heard: ResMut<Heard>,
) {
    heard.undone.extend(undone.read().cloned());
    heard.rejected.extend(rejected.read().cloned());
}

/// A world app (focus at `focus`) that records the undo messages.
fn undo_app(world: TerrainWorld, focus: Vec3) -> (App, Entity, Entity) {
    let (mut app, world, focus) = app_with(world, focus);
    app.init_resource::<Heard>().add_systems(Update, hear);
    (app, world, focus)
}

fn heard(app: &App) -> &Heard {
    app.world().resource::<Heard>()
}

/// Carves the world and runs frames until it settles.
pub(super) fn carve(app: &mut App, world: Entity, tool: CarveTool, edit: Edit) {
    app.world_mut()
        .write_message(WorldCarve { world, tool, edit });
    settle(app, world);
}

/// Undoes the world's last carve and runs frames until it settles.
pub(super) fn undo(app: &mut App, world: Entity) {
    app.world_mut().write_message(WorldUndo { world });
    settle(app, world);
}

pub(crate) fn chunk(app: &App, world: Entity, coord: ChunkCoord) -> &Terrain {
    let entity = the_world(app, world)
        .chunk_entity(coord)
        .unwrap_or_else(|| panic!("chunk {coord:?} is not live"));
    app.world().get::<Terrain>(entity).expect("chunk terrain")
}

/// Every live chunk's state: its kept hash, the hash of its octree
/// computed afresh, its exact solid volume and its journal length.
pub(crate) type States = BTreeMap<ChunkCoord, (u64, u64, ExactVolume, usize)>;

pub(crate) fn states(app: &App, world: Entity) -> States {
    the_world(app, world)
        .live_chunks()
        .map(|(coord, entity)| {
            let t = app.world().get::<Terrain>(entity).expect("chunk terrain");
            let state = (
                t.state_hash(),
                StateHash::of(t.octree()).value(),
                t.octree().exact_solid_volume(),
                t.journal().len(),
            );
            (coord, state)
        })
        .collect()
}

/// The chunks whose state differs between `a` and `b`.
pub(crate) fn differ(a: &States, b: &States) -> Vec<ChunkCoord> {
    a.iter()
        .filter(|(c, s)| b.get(c) != Some(s))
        .map(|(c, _)| *c)
        .collect()
}

pub(crate) fn debris(app: &mut App) -> usize {
    let mut query = app.world_mut().query::<&TerrainDebris>();
    query.iter(app.world()).count()
}

/// The four chunks around the corner (32, 32).
const CORNER: [ChunkCoord; 4] = [at(0, 0), at(0, 1), at(1, 0), at(1, 1)];

#[test]
fn one_undo_gives_back_every_chunk_of_a_carve_over_a_border_and_a_corner() {
    let (mut app, world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 32.0));
    // Over the border x = 32 only.
    let before = states(&app, world);
    carve(
        &mut app,
        world,
        sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    let carved = states(&app, world);
    assert_eq!(differ(&before, &carved), vec![at(0, 0), at(1, 0)]);
    assert_eq!(the_world(&app, world).undo_depth(), 1);
    undo(&mut app, world);
    assert_eq!(states(&app, world), before, "every chunk as before");
    assert_eq!(heard(&app).undone.len(), 1);
    assert_eq!(heard(&app).undone[0].chunks, vec![at(0, 0), at(1, 0)]);
    assert_eq!(the_world(&app, world).undo_depth(), 0);

    // Over the corner: four chunks, with an added block too.
    carve(
        &mut app,
        world,
        cuboid([28, 10, 28], [36, 30, 36]),
        Edit::Add(1),
    );
    let corner = states(&app, world);
    assert_eq!(differ(&before, &corner), CORNER.to_vec());
    carve(
        &mut app,
        world,
        sphere(7.0, Vec3::new(32.0, 22.0, 32.0)),
        Edit::Subtract,
    );
    assert_eq!(differ(&corner, &states(&app, world)), CORNER.to_vec());
    assert!(
        debris(&mut app) > 0,
        "the block's top fell across the corner"
    );
    undo(&mut app, world);
    assert_eq!(states(&app, world), corner);
    undo(&mut app, world);
    assert_eq!(states(&app, world), before);
    for coord in CORNER {
        let t = chunk(&app, world, coord);
        assert_eq!(t.undo_depth(), 0);
        assert!(t.journal().is_empty());
    }
    assert!(heard(&app).rejected.is_empty());
}

#[test]
fn several_carves_undo_in_reverse_order_even_asked_for_at_once() {
    let (mut app, world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 32.0));
    let tools = [
        (sphere(6.0, Vec3::new(32.0, 16.0, 12.0)), Edit::Subtract),
        (cuboid([20, 12, 30], [44, 26, 34]), Edit::Add(1)),
        (sphere(5.0, Vec3::new(31.0, 18.0, 33.0)), Edit::Subtract),
        (cuboid([10, 0, 10], [14, 30, 14]), Edit::Subtract),
    ];
    let mut snapshots = vec![states(&app, world)];
    for (tool, edit) in &tools {
        carve(&mut app, world, tool.clone(), *edit);
        snapshots.push(states(&app, world));
    }
    assert_eq!(the_world(&app, world).undo_depth(), tools.len());
    // One by one, checking each state.
    undo(&mut app, world);
    assert_eq!(states(&app, world), snapshots[3]);
    undo(&mut app, world);
    assert_eq!(states(&app, world), snapshots[2]);
    // The last two asked for in one frame.
    app.world_mut().write_message(WorldUndo { world });
    app.world_mut().write_message(WorldUndo { world });
    settle(&mut app, world);
    assert_eq!(states(&app, world), snapshots[0]);
    assert_eq!(heard(&app).undone.len(), 4);
    // Nothing is left to undo.
    undo(&mut app, world);
    assert_eq!(
        heard(&app).rejected.last().map(|r| &r.reason),
        Some(&WorldUndoRefusal::NothingToUndo)
    );
    assert_eq!(states(&app, world), snapshots[0]);
}

/// An undo waits for the carve it takes back (asked for in the same
/// frame); a carve asked for after an undo lands after it: the chunks are
/// those of the second carve alone, as in a world that never had the
/// first.
#[test]
fn undos_and_carves_keep_their_order_however_long_the_jobs_take() {
    let first = (sphere(6.0, Vec3::new(32.0, 16.0, 12.0)), Edit::Subtract);
    let second = (cuboid([26, 10, 8], [38, 24, 16]), Edit::Add(1));
    let (mut app, world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 32.0));
    let before = states(&app, world);
    app.world_mut().write_message(WorldCarve {
        world,
        tool: first.0.clone(),
        edit: first.1,
    });
    app.world_mut().write_message(WorldUndo { world });
    settle(&mut app, world);
    assert_eq!(states(&app, world), before);

    app.world_mut().write_message(WorldCarve {
        world,
        tool: first.0.clone(),
        edit: first.1,
    });
    app.update();
    app.world_mut().write_message(WorldUndo { world });
    app.update();
    app.world_mut().write_message(WorldCarve {
        world,
        tool: second.0.clone(),
        edit: second.1,
    });
    settle(&mut app, world);

    let (mut only, only_world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 32.0));
    carve(&mut only, only_world, second.0, second.1);
    let hashes = |s: States| s.into_iter().map(|(c, s)| (c, s.0)).collect::<Vec<_>>();
    assert_eq!(
        hashes(states(&app, world)),
        hashes(states(&only, only_world))
    );
    assert_eq!(the_world(&app, world).undo_depth(), 1);
    assert!(heard(&app).rejected.is_empty());
}

/// The surface is at most 20 high: a pillar stands from 4 up to 25 in
/// chunk (0, 0), a slab lies on it at 24..28 over the border x = 32, and
/// the cut at 21..23 meets only the pillar.
pub(crate) const PILLAR: ([i64; 3], [i64; 3]) = ([26, 4, 10], [29, 25, 13]);
pub(crate) const SLAB: ([i64; 3], [i64; 3]) = ([26, 24, 10], [38, 28, 14]);
pub(crate) const CUT: ([i64; 3], [i64; 3]) = ([25, 21, 9], [30, 23, 14]);

/// Cutting the pillar drops the slab from both chunks as one body; one
/// undo gives both chunks back, the neighbour's part included, though the
/// carve never reached the neighbour. The body stays, as after a single
/// terrain's undo, and nothing falls again.
#[test]
fn a_slab_cut_loose_across_a_border_comes_back_whole() {
    let (mut app, world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    carve(&mut app, world, cuboid(PILLAR.0, PILLAR.1), Edit::Add(1));
    carve(&mut app, world, cuboid(SLAB.0, SLAB.1), Edit::Add(1));
    let before = states(&app, world);
    assert_eq!(debris(&mut app), 0);
    carve(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    assert_eq!(debris(&mut app), 1, "the slab fell");
    let cut = states(&app, world);
    assert_eq!(differ(&before, &cut), vec![at(0, 0), at(1, 0)]);
    let label = |app: &App, c, p| chunk(app, world, c).octree().label_at(p).expect("inside");
    assert_eq!(label(&app, at(1, 0), [35, 26, 12]), Some(0));

    undo(&mut app, world);
    assert_eq!(states(&app, world), before, "both chunks as before the cut");
    assert_eq!(label(&app, at(1, 0), [35, 26, 12]), Some(1));
    assert_eq!(label(&app, at(0, 0), [27, 22, 11]), Some(1));
    assert_eq!(debris(&mut app), 1, "the body stays; nothing falls again");
    assert_eq!(heard(&app).undone[0].chunks, vec![at(0, 0), at(1, 0)]);

    // And the two carves before, in reverse order.
    undo(&mut app, world);
    undo(&mut app, world);
    for coord in [at(0, 0), at(1, 0)] {
        let t = chunk(&app, world, coord);
        let source = the_world(&app, world)
            .generate_chunk(coord)
            .expect("builds");
        assert_eq!(t.state_hash(), source.state_hash());
        assert_eq!(StateHash::of(t.octree()).value(), source.state_hash());
    }
}

/// Undoing the cut in its own chunk only, with [`UndoCarve`], is
/// something else since the world carve: the world undo is then refused
/// for that chunk and changes nothing.
#[test]
fn a_later_chunk_edit_refuses_the_world_undo_and_changes_nothing() {
    let (mut app, world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    let first = states(&app, world);
    carve(
        &mut app,
        world,
        sphere(4.0, Vec3::new(12.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    let before = states(&app, world);
    carve(
        &mut app,
        world,
        sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
        Edit::Subtract,
    );
    let carved = states(&app, world);
    // A carve of chunk (1, 0) alone.
    let Some(entity) = the_world(&app, world).chunk_entity(at(1, 0)) else {
        panic!("chunk (1, 0) is live");
    };
    app.world_mut().write_message(bevy_chisel::terrain::Carve {
        terrain: entity,
        tool: sphere(3.0, Vec3::new(40.0, 18.0, 20.0)),
        edit: Edit::Subtract,
    });
    settle(&mut app, world);
    let later = states(&app, world);
    assert_eq!(differ(&carved, &later), vec![at(1, 0)]);
    // Two undos at once: the first is refused, and so is the second, which
    // would undo the older carve before the newer one.
    app.world_mut().write_message(WorldUndo { world });
    app.world_mut().write_message(WorldUndo { world });
    settle(&mut app, world);
    assert_eq!(states(&app, world), later, "nothing changed");
    assert_eq!(
        heard(&app)
            .rejected
            .iter()
            .map(|r| r.reason.clone())
            .collect::<Vec<_>>(),
        vec![
            WorldUndoRefusal::ChunkChanged { coord: at(1, 0) },
            WorldUndoRefusal::EarlierUndoRefused
        ]
    );
    assert_eq!(the_world(&app, world).undo_depth(), 2, "the steps are kept");
    // Once that chunk's own carve is undone, the world undos go through.
    app.world_mut().write_message(UndoCarve { terrain: entity });
    settle(&mut app, world);
    assert_eq!(states(&app, world), carved);
    undo(&mut app, world);
    assert_eq!(states(&app, world), before);
    undo(&mut app, world);
    assert_eq!(states(&app, world), first);
    assert!(heard(&app).undone.len() == 2);
}

#[test]
fn trimmed_histories_and_missing_worlds_are_refused() {
    let (mut app, world, _) = undo_app(new_world().with_max_undo(2), Vec3::new(32.0, 30.0, 16.0));
    let mut hashes = vec![states(&app, world)];
    for x in [12.0, 20.0, 28.0] {
        carve(
            &mut app,
            world,
            sphere(3.0, Vec3::new(x, 16.0, 12.0)),
            Edit::Subtract,
        );
        hashes.push(states(&app, world));
    }
    assert_eq!(the_world(&app, world).undo_depth(), 2, "the depth limit");
    assert_eq!(
        chunk(&app, world, at(0, 0)).undo_depth(),
        2,
        "chunks keep as many"
    );
    undo(&mut app, world);
    assert_eq!(states(&app, world), hashes[2]);
    // A chunk whose history was cleared no longer holds the step.
    let Some(entity) = the_world(&app, world).chunk_entity(at(0, 0)) else {
        panic!("chunk (0, 0) is live");
    };
    let mut t = app.world_mut().get_mut::<Terrain>(entity).expect("chunk");
    t.clear_undo();
    undo(&mut app, world);
    assert_eq!(states(&app, world), hashes[2], "nothing changed");
    undo(&mut app, world);
    let reasons: Vec<_> = heard(&app)
        .rejected
        .iter()
        .map(|r| r.reason.clone())
        .collect();
    assert_eq!(
        reasons,
        vec![
            WorldUndoRefusal::HistoryTrimmed { coord: at(0, 0) },
            WorldUndoRefusal::HistoryTrimmed { coord: at(0, 0) },
        ]
    );

    // Nothing to undo in a fresh world; no world at all.
    let (mut fresh, fresh_world, focus) = undo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    let before = states(&fresh, fresh_world);
    undo(&mut fresh, fresh_world);
    fresh.world_mut().write_message(WorldUndo { world: focus });
    settle(&mut fresh, fresh_world);
    let reasons: Vec<_> = heard(&fresh)
        .rejected
        .iter()
        .map(|r| r.reason.clone())
        .collect();
    assert_eq!(
        reasons,
        vec![
            WorldUndoRefusal::NothingToUndo,
            WorldUndoRefusal::NoSuchWorld
        ]
    );
    assert_eq!(states(&fresh, fresh_world), before);
}

/// A chunk far from the focus is built for the carve and streams out
/// again with its state stored; the undo restores it, undoes it there,
/// and it streams out unedited: nothing is stored any more and it comes
/// back as the source's.
#[test]
fn an_undo_restores_a_chunk_streamed_out() {
    let (mut app, world, focus) = undo_app(new_world(), Vec3::new(16.0, 30.0, 16.0));
    let far = at(6, 0);
    carve(
        &mut app,
        world,
        sphere(5.0, Vec3::new(6.0 * 32.0 + 12.0, 14.0, 16.0)),
        Edit::Subtract,
    );
    let w = the_world(&app, world);
    assert_eq!(w.stored_chunks().collect::<Vec<_>>(), vec![far]);
    assert!(w.chunk_entity(far).is_none());
    let before = states(&app, world);
    undo(&mut app, world);
    let w = the_world(&app, world);
    assert_eq!(heard(&app).undone[0].chunks, vec![far]);
    assert!(w.stored_chunks().next().is_none(), "unedited again");
    assert!(w.chunk_entity(far).is_none(), "streamed out again");
    assert_eq!(states(&app, world), before, "the near chunks untouched");
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(6.0 * 32.0 + 16.0, 30.0, 16.0);
    settle(&mut app, world);
    let source = the_world(&app, world).generate_chunk(far).expect("builds");
    assert_eq!(chunk(&app, world, far).state_hash(), source.state_hash());
}

/// The cut and a small carve elsewhere in the same chunk land in one
/// frame (one job), so the slab's fall is searched from both and belongs
/// to the later carve; undoing that carve gives every chunk exactly its
/// state after the cut and its fall, as if it had never been made.
#[test]
fn undoing_a_carve_that_landed_with_an_earlier_cut_keeps_the_cut_and_its_fall() {
    let (mut app, world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    carve(&mut app, world, cuboid(PILLAR.0, PILLAR.1), Edit::Add(1));
    carve(&mut app, world, cuboid(SLAB.0, SLAB.1), Edit::Add(1));
    let (mut reference, reference_world, _) = undo_app(new_world(), Vec3::new(32.0, 30.0, 16.0));
    carve(
        &mut reference,
        reference_world,
        cuboid(PILLAR.0, PILLAR.1),
        Edit::Add(1),
    );
    carve(
        &mut reference,
        reference_world,
        cuboid(SLAB.0, SLAB.1),
        Edit::Add(1),
    );
    carve(
        &mut reference,
        reference_world,
        cuboid(CUT.0, CUT.1),
        Edit::Subtract,
    );
    assert_eq!(debris(&mut reference), 1);

    for (tool, edit) in [
        (cuboid(CUT.0, CUT.1), Edit::Subtract),
        (sphere(3.0, Vec3::new(8.0, 16.0, 24.0)), Edit::Subtract),
    ] {
        app.world_mut()
            .write_message(WorldCarve { world, tool, edit });
    }
    settle(&mut app, world);
    assert_eq!(debris(&mut app), 1, "the slab fell");
    undo(&mut app, world);
    assert_eq!(states(&app, world), states(&reference, reference_world));
    // Both carves landed in one job, so the fall was searched from both
    // and belonged to the later one: its undo gave the slab back with the
    // seeds of the cut, and the slab fell again, a second body.
    assert_eq!(debris(&mut app), 2);
}

/// A networked world's server orders every change and its clients replay
/// them: a local undo is refused on both, and changes nothing.
#[cfg(feature = "net")]
#[test]
fn a_networked_world_refuses_undo_on_server_and_client() {
    use crate::net::{request_world, run_until, unlimited, world_client, world_of, world_server};
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
    let tool = sphere(5.0, Vec3::new(32.0, 16.0, 12.0));
    request_world(&mut client, 1, &tool, Edit::Subtract);
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        world_settled(apps[0])
            && world_settled(apps[1])
            && world_of(apps[1]).1.chunk_entity(at(1, 0)).is_some_and(|e| {
                apps[1]
                    .world()
                    .get::<Terrain>(e)
                    .is_some_and(|t| !t.journal().is_empty())
            })
    });
    // Every chunk either peer edited, live or stored (the server, with no
    // focus, streams chunks out once carved).
    let hashes = |app: &mut App| {
        let edited = crate::net_worlds::edited_chunks(app);
        edited
            .into_iter()
            .map(|(c, (_, h))| (c, h))
            .collect::<Vec<_>>()
    };
    let before = (hashes(&mut server), hashes(&mut client));
    assert!(
        !before.0.is_empty() && before.0 == before.1,
        "the carve is on both"
    );
    for app in [&mut server, &mut client] {
        let (entity, _) = world_of(app);
        app.world_mut().write_message(WorldUndo { world: entity });
    }
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        apps.iter().all(|app| !heard(app).rejected.is_empty())
    });
    for app in [&mut server, &mut client] {
        let reasons: Vec<_> = heard(app)
            .rejected
            .iter()
            .map(|r| r.reason.clone())
            .collect();
        assert_eq!(reasons, vec![WorldUndoRefusal::Networked]);
        assert!(heard(app).undone.is_empty());
    }
    assert_eq!((hashes(&mut server), hashes(&mut client)), before);
}

/// A chunk whose own undo took the world carve back answers a world undo
/// of that carve the same whether it is still live or streamed out since
/// (unedited again, so nothing of it is stored): the chunk changed since
/// the carve, not lost; nothing changes.
#[test]
fn a_chunk_undone_on_its_own_refuses_alike_live_or_streamed_out() {
    let mut reasons = Vec::new();
    for stream_out in [false, true] {
        let (mut app, world, focus) = undo_app(new_world(), Vec3::new(16.0, 30.0, 16.0));
        carve(
            &mut app,
            world,
            sphere(4.0, Vec3::new(12.0, 16.0, 12.0)),
            Edit::Subtract,
        );
        let Some(entity) = the_world(&app, world).chunk_entity(at(0, 0)) else {
            panic!("chunk (0, 0) is live");
        };
        app.world_mut().write_message(UndoCarve { terrain: entity });
        settle(&mut app, world);
        if stream_out {
            app.world_mut()
                .get_mut::<Transform>(focus)
                .expect("focus")
                .translation = Vec3::new(10.0 * 32.0, 30.0, 16.0);
            settle(&mut app, world);
            let w = the_world(&app, world);
            assert!(w.chunk_entity(at(0, 0)).is_none(), "streamed out");
            assert!(w.stored_chunks().next().is_none(), "unedited: not stored");
        }
        let before = states(&app, world);
        undo(&mut app, world);
        assert_eq!(states(&app, world), before, "nothing changed");
        assert!(heard(&app).undone.is_empty());
        let rejected = &heard(&app).rejected;
        assert_eq!(rejected.len(), 1, "{rejected:?}");
        reasons.push(rejected[0].reason.clone());
    }
    assert_eq!(reasons[1], reasons[0], "the same answer either way");
}

/// A world carve over chunks (1, 0) and (2, 0), with the focus near
/// (0, 0): chunk (2, 0), beyond the load radius, is built for the carve,
/// but the source fails inside it, so its build fails and its carve is
/// dropped. The world undo of that carve is refused naming the chunk, it
/// changes nothing, and the chunks it held are free again: a later carve
/// lands there.
#[test]
fn a_chunk_whose_build_failed_refuses_the_world_undo_and_changes_nothing() {
    use super::terrain_world::{height, layout};
    use bevy_chisel::terrain::StreamSettings;

    let lost = at(2, 0);
    // Samples 16..=24 along x and 0..=8 along z are chunk (2, 0)'s; only
    // it has those inside, and there the source gives the floor.
    let source = |i: i64, j: i64| {
        let inside = (17..=23).contains(&i) && (1..=7).contains(&j);
        if inside { 0 } else { height(i, j) }
    };
    let failing = TerrainWorld::new(layout(), source)
        .expect("valid layout")
        .with_streaming(StreamSettings {
            load_radius: 40.0,
            unload_radius: 72.0,
            max_building: 4,
        })
        .expect("valid settings");
    let (mut app, world, _) = undo_app(failing, Vec3::new(16.0, 30.0, 16.0));
    assert!(the_world(&app, world).chunk_entity(at(1, 0)).is_some());
    let first = states(&app, world);
    carve(
        &mut app,
        world,
        cuboid([50, 10, 10], [70, 22, 14]),
        Edit::Subtract,
    );
    let carved = states(&app, world);
    assert_eq!(differ(&first, &carved), vec![at(1, 0)]);
    let w = the_world(&app, world);
    assert_eq!(w.stats().failed, 1, "chunk (2, 0) did not build");
    assert!(w.chunk_entity(lost).is_none() && w.waiting_carves(lost) == 0);
    assert_eq!(w.undo_depth(), 1);

    undo(&mut app, world);
    assert_eq!(states(&app, world), carved, "nothing changed");
    assert!(heard(&app).undone.is_empty());
    let reasons: Vec<_> = (heard(&app).rejected.iter())
        .map(|r| r.reason.clone())
        .collect();
    assert_eq!(reasons, vec![WorldUndoRefusal::ChunkLost { coord: lost }]);
    assert_eq!(the_world(&app, world).undo_depth(), 1, "the step is kept");
    // No hold of the refused undo is left in chunk (1, 0): it carves on.
    carve(
        &mut app,
        world,
        sphere(3.0, Vec3::new(44.0, 16.0, 20.0)),
        Edit::Subtract,
    );
    assert_eq!(differ(&carved, &states(&app, world)), vec![at(1, 0)]);
}
