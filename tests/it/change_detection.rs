//! Bevy's change detection on terrains and worlds (`MinimalPlugins`): a
//! settled terrain or world shows no change frame after frame, and a
//! carve, undo or redo marks `Changed<Terrain>` in exactly the frames a
//! terrain's content changed (its state hash, journal, undo depth or last
//! request, read frame by frame as the reference), only on the chunks the
//! carve reached; streaming marks the world and none of the chunks that
//! stay live; a networked world at rest shows no change on its server nor
//! on its client.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Carve, CarveTool, ChunkCoord, RedoCarve, Terrain, TerrainBase, TerrainPlugin, TerrainWorld,
    UndoCarve, WorldCarve, WorldUndo,
};

use super::terrain_world::{app_with as world_app, settle as settle_world, the_world, world};

/// What a terrain shows of its content: state hash, journal length, undo
/// depth and last tracked request.
type Content = (u64, usize, usize, Option<u64>);

fn content(terrain: &Terrain) -> Content {
    (
        terrain.state_hash(),
        terrain.journal().len(),
        terrain.undo_depth(),
        terrain.last_request(),
    )
}

/// One frame as seen from `Last`.
#[derive(Default, Debug)]
struct Frame {
    /// Terrains `Changed<Terrain>` matched.
    changed: BTreeSet<Entity>,
    /// Worlds `Changed<TerrainWorld>` matched.
    worlds: usize,
    /// Every terrain's content at the end of the frame.
    content: BTreeMap<Entity, Content>,
}

#[derive(Resource, Default)]
struct Frames(Vec<Frame>);

fn watch_changes(
    changed: Query<Entity, Changed<Terrain>>,
    worlds: Query<(), Changed<TerrainWorld>>,
    all: Query<(Entity, &Terrain)>,
    mut frames: ResMut<Frames>,
) {
    frames.0.push(Frame {
        changed: changed.iter().collect(),
        worlds: worlds.iter().count(),
        content: all.iter().map(|(e, t)| (e, content(t))).collect(),
    });
}

/// Adds the watcher to a running app; its first frame (which sees every
/// component as changed) is dropped.
fn watch(app: &mut App) {
    app.init_resource::<Frames>()
        .add_systems(Last, watch_changes);
    app.update();
    app.world_mut().resource_mut::<Frames>().0.clear();
}

/// The frames watched since the last call, taken.
fn take_frames(app: &mut App) -> Vec<Frame> {
    std::mem::take(&mut app.world_mut().resource_mut::<Frames>().0)
}

/// Runs `frames` frames and checks that no terrain and no world shows a
/// change in any of them.
fn assert_quiet(app: &mut App, frames: usize, what: &str) {
    take_frames(app);
    for _ in 0..frames {
        app.update();
        std::thread::sleep(Duration::from_micros(200));
    }
    let seen = take_frames(app);
    assert_eq!(seen.len(), frames);
    for (i, frame) in seen.iter().enumerate() {
        assert!(
            frame.changed.is_empty() && frame.worlds == 0,
            "{what}: idle frame {i} shows {} changed terrains and {} changed worlds",
            frame.changed.len(),
            frame.worlds
        );
    }
}

/// Per frame, the terrains whose content differs from the frame before
/// (`before`: the content before the first frame).
fn content_changes(before: &BTreeMap<Entity, Content>, frames: &[Frame]) -> Vec<BTreeSet<Entity>> {
    let mut last = before.clone();
    frames
        .iter()
        .map(|frame| {
            let moved = (frame.content.iter())
                .filter(|(e, c)| last.get(e).is_some_and(|l| l != *c))
                .map(|(e, _)| *e)
                .collect();
            last.clone_from(&frame.content);
            moved
        })
        .collect()
}

/// Checks that the frames mark as changed exactly the terrains whose
/// content changed in them; returns every terrain marked.
fn assert_marks_follow_content(
    before: &BTreeMap<Entity, Content>,
    frames: &[Frame],
) -> BTreeSet<Entity> {
    let moved = content_changes(before, frames);
    for (i, (frame, moved)) in frames.iter().zip(&moved).enumerate() {
        assert_eq!(
            &frame.changed, moved,
            "frame {i}: terrains marked changed vs terrains whose content changed"
        );
    }
    frames
        .iter()
        .flat_map(|f| f.changed.iter().copied())
        .collect()
}

/// A 32³ block (grid unit 1) in a 64³ cube, split into many cells.
fn block() -> Terrain {
    let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 6,
        solid: CellBox {
            min: [0; 3],
            max: [32; 3],
        },
        label: 1,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 12,
        max_depth: 20,
    };
    Terrain::from_base(grid, base, config).expect("valid block")
}

fn settle_terrain(app: &mut App, entity: Entity) {
    for _ in 0..20_000 {
        app.update();
        let idle = app
            .world()
            .get::<Terrain>(entity)
            .is_some_and(Terrain::is_idle);
        if idle {
            for _ in 0..5 {
                app.update();
            }
            return;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("terrain did not settle");
}

fn contents(app: &mut App) -> BTreeMap<Entity, Content> {
    let mut query = app.world_mut().query::<(Entity, &Terrain)>();
    query
        .iter(app.world())
        .map(|(e, t)| (e, content(t)))
        .collect()
}

#[test]
fn a_terrain_is_changed_only_in_the_frames_its_carve_undo_and_redo_land() {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>();
    let entity = app.world_mut().spawn(block()).id();
    settle_terrain(&mut app, entity);
    watch(&mut app);
    assert_quiet(&mut app, 30, "settled terrain");

    let before = contents(&mut app);
    app.world_mut().write_message(Carve {
        terrain: entity,
        tool: CarveTool::dodecahedron(5.0, Vec3::new(16.0, 32.0, 16.0)),
        edit: Edit::Subtract,
    });
    settle_terrain(&mut app, entity);
    let frames = take_frames(&mut app);
    let marked = assert_marks_follow_content(&before, &frames);
    assert_eq!(marked, BTreeSet::from([entity]));
    let landed = frames.iter().filter(|f| !f.changed.is_empty()).count();
    assert_eq!(landed, 1, "one carve lands in one frame");
    let terrain = app.world().get::<Terrain>(entity).expect("terrain");
    assert_eq!((terrain.journal().len(), terrain.undo_depth()), (1, 1));
    assert_quiet(&mut app, 30, "carved terrain");

    let before = contents(&mut app);
    app.world_mut().write_message(UndoCarve { terrain: entity });
    settle_terrain(&mut app, entity);
    let frames = take_frames(&mut app);
    let marked = assert_marks_follow_content(&before, &frames);
    assert_eq!(marked, BTreeSet::from([entity]));
    let landed = frames.iter().filter(|f| !f.changed.is_empty()).count();
    assert_eq!(landed, 1, "one undo lands in one frame");
    let terrain = app.world().get::<Terrain>(entity).expect("terrain");
    assert_eq!((terrain.journal().len(), terrain.undo_depth()), (0, 0));
    assert_quiet(&mut app, 30, "terrain after undo");

    // A redo lands in one frame, as the undo did.
    let before = contents(&mut app);
    app.world_mut().write_message(RedoCarve { terrain: entity });
    settle_terrain(&mut app, entity);
    let frames = take_frames(&mut app);
    let marked = assert_marks_follow_content(&before, &frames);
    assert_eq!(marked, BTreeSet::from([entity]));
    let landed = frames.iter().filter(|f| !f.changed.is_empty()).count();
    assert_eq!(landed, 1, "one redo lands in one frame");
    let terrain = app.world().get::<Terrain>(entity).expect("terrain");
    assert_eq!((terrain.journal().len(), terrain.undo_depth()), (1, 1));
    assert_quiet(&mut app, 30, "terrain after redo");
    // A redo with nothing to redo is refused and marks nothing.
    app.world_mut().write_message(RedoCarve { terrain: entity });
    assert_quiet(&mut app, 30, "terrain after a refused redo");

    // A write through `&mut Terrain` by the game is a change, as Bevy has it.
    take_frames(&mut app);
    app.world_mut()
        .get_mut::<Terrain>(entity)
        .expect("terrain")
        .clear_undo();
    app.update();
    let frames = take_frames(&mut app);
    assert_eq!(frames[0].changed, BTreeSet::from([entity]));
}

fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

fn chunk_entities(app: &App, world: Entity, coords: &[ChunkCoord]) -> BTreeSet<Entity> {
    let w = the_world(app, world);
    coords
        .iter()
        .map(|&c| {
            w.chunk_entity(c)
                .unwrap_or_else(|| panic!("chunk {c:?} is live"))
        })
        .collect()
}

#[test]
fn a_world_carve_and_undo_mark_exactly_the_chunks_they_reach() {
    let (mut app, world_entity, focus) = world_app(world(), Vec3::new(32.0, 30.0, 32.0));
    watch(&mut app);
    let live = the_world(&app, world_entity).live_chunks().count();
    assert!(live >= 9, "{live} live chunks");
    assert_quiet(&mut app, 30, "settled world");

    // A sphere over the border x = 32, within chunks (0, 0) and (1, 0).
    let reached = chunk_entities(&app, world_entity, &[at(0, 0), at(1, 0)]);
    let before = contents(&mut app);
    app.world_mut().write_message(WorldCarve {
        world: world_entity,
        tool: CarveTool::sphere(6.0, Vec3::new(32.0, 16.0, 12.0)),
        edit: Edit::Subtract,
    });
    settle_world(&mut app, world_entity);
    let frames = take_frames(&mut app);
    let marked = assert_marks_follow_content(&before, &frames);
    assert_eq!(marked, reached, "the chunks the carve reached");
    assert!(
        frames.iter().any(|f| f.worlds == 1),
        "the world routed a carve"
    );
    assert_eq!(the_world(&app, world_entity).undo_depth(), 1);
    assert_quiet(&mut app, 30, "carved world");

    let before = contents(&mut app);
    app.world_mut().write_message(WorldUndo {
        world: world_entity,
    });
    settle_world(&mut app, world_entity);
    let frames = take_frames(&mut app);
    let marked = assert_marks_follow_content(&before, &frames);
    assert_eq!(marked, reached, "the chunks the undo gave back");
    assert!(
        frames.iter().any(|f| f.worlds == 1),
        "the world carried out an undo"
    );
    assert_eq!(the_world(&app, world_entity).undo_depth(), 0);
    assert_quiet(&mut app, 30, "world after undo");

    // Streaming marks the world; the chunks live before and after are
    // not marked (new chunks are added, which `Changed` also matches).
    let live_before: BTreeSet<Entity> = (the_world(&app, world_entity).live_chunks())
        .map(|(_, e)| e)
        .collect();
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(96.0, 30.0, 32.0);
    settle_world(&mut app, world_entity);
    let frames = take_frames(&mut app);
    let live_after: BTreeSet<Entity> = (the_world(&app, world_entity).live_chunks())
        .map(|(_, e)| e)
        .collect();
    let stayed: BTreeSet<Entity> = live_before.intersection(&live_after).copied().collect();
    assert!(
        !stayed.is_empty() && live_after != live_before,
        "chunks streamed"
    );
    assert!(frames.iter().any(|f| f.worlds == 1), "the world streamed");
    for (i, frame) in frames.iter().enumerate() {
        assert!(
            frame.changed.is_disjoint(&stayed),
            "frame {i}: a chunk that stayed live is marked changed"
        );
    }
    assert_quiet(&mut app, 30, "world after streaming");
}

#[cfg(feature = "net")]
#[test]
fn a_networked_world_at_rest_shows_no_change_on_server_nor_client() {
    use crate::ONE_APP_AT_A_TIME;
    use crate::net::{
        Seen, WorldsSeen, request_world, run_until, unlimited, world_client, world_server,
    };
    use crate::net_worlds::{streamed_world, world_settled};

    let _guard = ONE_APP_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (mut server, addr) = world_server(streamed_world(), unlimited());
    let mut client = world_client(addr, 1, streamed_world(), Vec3::new(16.0, 30.0, 16.0));
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        !apps[1].world().resource::<WorldsSeen>().synced.is_empty() && world_settled(apps[1])
    });
    // One carve over a border, answered and settled everywhere.
    let tool = CarveTool::dodecahedron(4.0, Vec3::new(32.0, 14.0, 16.0));
    request_world(&mut client, 1, &tool, Edit::Subtract);
    run_until(&mut [&mut server, &mut client], 20_000, |apps| {
        apps[1].world().resource::<Seen>().results.len() == 1
            && world_settled(apps[0])
            && world_settled(apps[1])
    });
    for _ in 0..10 {
        server.update();
        client.update();
    }
    watch(&mut server);
    watch(&mut client);
    take_frames(&mut server);
    take_frames(&mut client);
    for _ in 0..30 {
        server.update();
        client.update();
        std::thread::sleep(Duration::from_micros(200));
    }
    for (name, app) in [("server", &mut server), ("client", &mut client)] {
        let frames = take_frames(app);
        assert_eq!(frames.len(), 30);
        for (i, frame) in frames.iter().enumerate() {
            assert!(
                frame.changed.is_empty() && frame.worlds == 0,
                "{name}: idle frame {i} shows {} changed terrains and {} changed worlds",
                frame.changed.len(),
                frame.worlds
            );
        }
    }
}
