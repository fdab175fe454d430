//! Debris across chunk borders in a streamed world (`MinimalPlugins`): a
//! slab over one border, or over the corner of four chunks, on a pillar
//! that a carve cuts through falls as one [`TerrainDebris`] whose exact
//! volume is what the chunks lost besides the carve, summed over the
//! chunks exactly; a slab still held by a pillar in the neighbouring chunk
//! stays; over the world's limits nothing falls; undoing the cut in its
//! chunk brings that chunk's part back; the same carves give the same
//! chunks and debris twice.

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{Edit, ExactVolume, StateHash};
use bevy_chisel::terrain::{
    CarveShape, CarveTool, ChunkCoord, DebrisLimits, TerrainDebris, TerrainWorld, UndoCarve,
    WorldCarve,
};

use super::terrain_world::{app_with, settle, terrain, the_world, world};

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

fn edit(app: &mut App, world: Entity, tool: CarveTool, edit: Edit) {
    app.world_mut()
        .write_message(WorldCarve { world, tool, edit });
    settle(app, world);
}

pub(crate) fn box_volume(min: [i64; 3], max: [i64; 3]) -> ExactVolume {
    ExactVolume::from_integer((0..3).map(|a| i128::from(max[a] - min[a])).product())
}

/// The exact solid volume of each chunk.
fn volumes(app: &App, world: Entity, coords: &[ChunkCoord]) -> Vec<ExactVolume> {
    coords
        .iter()
        .map(|&c| terrain(app, world, c).octree().exact_solid_volume())
        .collect()
}

pub(crate) fn debris(app: &mut App) -> Vec<TerrainDebris> {
    let mut query = app.world_mut().query::<&TerrainDebris>();
    query.iter(app.world()).cloned().collect()
}

fn sum(v: &[ExactVolume]) -> ExactVolume {
    v.iter().cloned().sum()
}

const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// The surface is at most 20 high: pillars stand from 4 up to 25, the
/// slab lies at 24..28, and the cut at 21..23 meets only the pillar.
const PILLAR: ([i64; 3], [i64; 3]) = ([26, 4, 10], [29, 25, 13]);
pub(crate) const CUT: ([i64; 3], [i64; 3]) = ([25, 21, 9], [30, 23, 14]);

/// Sends the cut that frees the slab and runs until the search for
/// debris across borders it seeds is running.
pub(super) fn cut_until_searching(app: &mut App, world: Entity) {
    app.world_mut().write_message(WorldCarve {
        world,
        tool: cuboid(CUT.0, CUT.1),
        edit: Edit::Subtract,
    });
    let mut frames = 0;
    while !the_world(app, world).debris_searching() {
        app.update();
        frames += 1;
        assert!(frames < 20_000, "the cut starts a search");
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
}

/// A world with a slab from x = 26 to 38 over the border x = 32 on a
/// pillar in chunk (0, 0), and also one in chunk (1, 0) when `held`.
fn slab_world(held: bool) -> (App, Entity) {
    slab_in(world(), held)
}

/// [`slab_world`] in `world`.
fn slab_in(world: TerrainWorld, held: bool) -> (App, Entity) {
    let (mut app, world, _) = app_with(world, Vec3::new(32.0, 30.0, 16.0));
    build_slab(&mut app, world, held);
    (app, world)
}

/// Builds [`slab_world`]'s pillar (or pillars) and slab in `app`'s
/// `world`, whose focus is near (32, 16).
pub(crate) fn build_slab(app: &mut App, world: Entity, held: bool) {
    edit(app, world, cuboid(PILLAR.0, PILLAR.1), Edit::Add(1));
    if held {
        edit(app, world, cuboid([35, 4, 10], [38, 25, 13]), Edit::Add(1));
    }
    edit(app, world, cuboid([26, 24, 10], [38, 28, 14]), Edit::Add(1));
    assert!(debris(app).is_empty(), "the slab rests on its pillar");
}

/// What falls when the pillar is cut: the pillar above the cut, 3×1×3,
/// and the slab, 12×4×4.
pub(crate) fn falling() -> ExactVolume {
    box_volume([26, 23, 10], [29, 24, 13]) + box_volume([26, 24, 10], [38, 28, 14])
}

#[test]
fn a_slab_cut_loose_across_a_border_falls_as_one_piece() {
    let (mut app, world) = slab_world(false);
    let chunks = [at(0, 0), at(1, 0)];
    let before = volumes(&app, world, &chunks);
    edit(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    let after = volumes(&app, world, &chunks);
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1, "one body for both parts");
    let piece = &pieces[0];
    assert_eq!(piece.exact_volume, falling());
    assert_eq!(piece.volumes.get(&1), Some(&falling()));
    // The chunks lost the carve's share of the pillar and the piece, no
    // more and no less, summed exactly over the chunks.
    let cut = box_volume([26, 21, 10], [29, 23, 13]);
    assert_eq!(sum(&before), sum(&after) + cut + piece.exact_volume.clone());
    // The neighbour lost exactly its share of the slab.
    assert_eq!(
        before[1].clone(),
        after[1].clone() + box_volume([32, 24, 10], [38, 28, 14])
    );
    let octree = terrain(&app, world, at(1, 0)).octree();
    assert_eq!(octree.label_at([35, 26, 12]).unwrap(), Some(0));
    assert_eq!(the_world(&app, world).stats().detached_across, 1);
}

#[test]
fn a_slab_held_through_the_neighbouring_chunk_stays() {
    let (mut app, world) = slab_world(true);
    let chunks = [at(0, 0), at(1, 0)];
    let before = volumes(&app, world, &chunks);
    edit(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    assert!(debris(&mut app).is_empty(), "the second pillar holds it");
    let after = volumes(&app, world, &chunks);
    assert_eq!(before[1], after[1], "nothing left the neighbour");
    let octree = terrain(&app, world, at(1, 0)).octree();
    assert_eq!(octree.label_at([35, 26, 12]).unwrap(), Some(1));
    // Cut the second pillar too: now it falls, with both pillars' tops.
    edit(
        &mut app,
        world,
        cuboid([34, 21, 9], [39, 23, 14]),
        Edit::Subtract,
    );
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1);
    let tops = box_volume([26, 23, 10], [29, 24, 13]) + box_volume([35, 23, 10], [38, 24, 13]);
    assert_eq!(
        pieces[0].exact_volume,
        tops + box_volume([26, 24, 10], [38, 28, 14])
    );
}

#[test]
fn a_slab_over_a_corner_falls_from_four_chunks_as_one_piece() {
    let (mut app, world, _) = app_with(world(), Vec3::new(32.0, 30.0, 32.0));
    let chunks = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
    edit(
        &mut app,
        world,
        cuboid([26, 4, 26], [29, 25, 29]),
        Edit::Add(1),
    );
    let slab = ([26, 24, 26], [38, 28, 38]);
    edit(&mut app, world, cuboid(slab.0, slab.1), Edit::Add(1));
    assert!(debris(&mut app).is_empty());
    let before = volumes(&app, world, &chunks);
    edit(
        &mut app,
        world,
        cuboid([25, 21, 25], [30, 23, 30]),
        Edit::Subtract,
    );
    let after = volumes(&app, world, &chunks);
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1);
    let falling = box_volume([26, 23, 26], [29, 24, 29]) + box_volume(slab.0, slab.1);
    assert_eq!(pieces[0].exact_volume, falling);
    let cut = box_volume([26, 21, 26], [29, 23, 29]);
    assert_eq!(sum(&before), sum(&after) + cut + falling);
    for i in 1..4 {
        assert!(after[i] < before[i], "chunk {:?} lost its part", chunks[i]);
    }
}

#[test]
fn the_same_carves_give_the_same_chunks_and_debris() {
    let run = || {
        let (mut app, world) = slab_world(false);
        edit(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
        let hashes: Vec<(ChunkCoord, u64)> = the_world(&app, world)
            .live_chunks()
            .map(|(c, _)| (c, terrain(&app, world, c).state_hash()))
            .collect();
        let volumes: Vec<ExactVolume> = debris(&mut app)
            .into_iter()
            .map(|d| d.exact_volume)
            .collect();
        (hashes, volumes)
    };
    let first = run();
    assert_eq!(first.1, vec![falling()]);
    assert_eq!(first, run());
}

/// Over the world's limits the slab stays where it is, whole; at them
/// exactly it falls.
#[test]
fn over_the_world_limits_nothing_falls_across_borders() {
    let limited = |volume: u128| {
        world().with_debris_limits(DebrisLimits {
            max_volume: Some(volume),
            max_cells: None,
        })
    };
    let (mut app, world) = slab_in(limited(200), false);
    let before = volumes(&app, world, &[at(1, 0)]);
    edit(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    assert!(debris(&mut app).is_empty(), "201 is over 200");
    assert_eq!(volumes(&app, world, &[at(1, 0)]), before);
    assert_eq!(the_world(&app, world).stats().detached_across, 0);
    let (mut app, world) = slab_in(limited(201), false);
    edit(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1);
    assert_eq!(pieces[0].exact_volume, falling());
}

/// The detach joins the cut's undo step in the chunk that was cut: undo
/// there gives that chunk exactly its state before the cut (its part of
/// the slab back), with a hash that agrees with its octree; the
/// neighbour keeps its part out.
#[test]
fn undoing_the_cut_brings_back_the_part_in_its_chunk() {
    let (mut app, world) = slab_world(false);
    let hash = |app: &App, c| terrain(app, world, c).state_hash();
    let before = hash(&app, at(0, 0));
    edit(&mut app, world, cuboid(CUT.0, CUT.1), Edit::Subtract);
    let neighbour = hash(&app, at(1, 0));
    let Some(entity) = the_world(&app, world).chunk_entity(at(0, 0)) else {
        panic!("chunk (0, 0) is live");
    };
    app.world_mut().write_message(UndoCarve { terrain: entity });
    settle(&mut app, world);
    let chunk = terrain(&app, world, at(0, 0));
    assert_eq!(chunk.state_hash(), before);
    assert_eq!(StateHash::of(chunk.octree()).value(), before);
    assert_eq!(chunk.octree().label_at([30, 26, 12]).unwrap(), Some(1));
    assert_eq!(hash(&app, at(1, 0)), neighbour);
}

/// A notch out of the top of the slab's part in chunk (1, 0).
const NOTCH: ([i64; 3], [i64; 3]) = ([34, 26, 9], [36, 29, 15]);

/// The search runs off the frames: a carve that lands on a chunk the
/// search takes solid from while it runs (here it is asked for then and
/// applied after the search started) makes its result stale. It is
/// dropped, and the search run again finds exactly what one search over
/// the chunks with both carves finds: the same piece, the same chunks.
#[test]
fn a_carve_landing_during_the_search_makes_it_search_again() {
    let (mut app, world) = slab_world(false);
    let dropped = |app: &App| the_world(app, world).stats().debris_searches_dropped;
    let before = dropped(&app);
    cut_until_searching(&mut app, world);
    assert!(debris(&mut app).is_empty(), "nothing fell yet");
    edit(&mut app, world, cuboid(NOTCH.0, NOTCH.1), Edit::Subtract);
    assert_eq!(dropped(&app), before + 1, "the first search was dropped");
    let notched = &falling() - &box_volume([34, 26, 10], [36, 28, 14]);
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1);
    assert_eq!(pieces[0].exact_volume, notched);

    // One search over the same carves: the notch first, then the cut.
    let (mut single, single_world) = slab_world(false);
    edit(
        &mut single,
        single_world,
        cuboid(NOTCH.0, NOTCH.1),
        Edit::Subtract,
    );
    let before_cut = the_world(&single, single_world)
        .stats()
        .debris_searches_dropped;
    edit(
        &mut single,
        single_world,
        cuboid(CUT.0, CUT.1),
        Edit::Subtract,
    );
    assert_eq!(
        the_world(&single, single_world)
            .stats()
            .debris_searches_dropped,
        before_cut
    );
    let reference = debris(&mut single);
    assert_eq!(reference.len(), 1);
    assert_eq!(reference[0].exact_volume, pieces[0].exact_volume);
    assert_eq!(reference[0].volumes, pieces[0].volumes);
    let hashes = |app: &App, world: Entity| -> Vec<(ChunkCoord, u64)> {
        the_world(app, world)
            .live_chunks()
            .map(|(c, _)| (c, terrain(app, world, c).state_hash()))
            .collect()
    };
    assert_eq!(hashes(&app, world), hashes(&single, single_world));
    assert!(!the_world(&app, world).debris_searching());
}
