//! A world carved in every frame across chunk borders still saves
//! (`MinimalPlugins`): after its settle frames a [`SaveWorld`] takes the
//! first consistent state, each chunk before its carves in flight, every
//! world carve in all of its chunks or in none; [`WorldSaved::left_out`]
//! counts the carves left out, and the next save writes the chunks they
//! changed. With no settle frames a request saves at once; a bound below
//! the settle frames still gives up. With no hold frames no carve is held
//! back for a save, which still comes.

use std::collections::{BTreeMap, BTreeSet};

use bevy::prelude::*;
use bevy_chisel::terrain::{
    CarveApplied, CarveRejected, ChunkCoord, DEFAULT_SAVE_HOLD_FRAMES, DEFAULT_SAVE_SETTLE_FRAMES,
    TerrainError, TerrainSystems, TerrainWorld, WorldChunk, WorldSaved,
};

use super::terrain_world::{carve, dodecahedron, settle, the_world, world as new_world};
use super::world_save::{at, edited_bytes, heard, save, save_app, temp_folder, until_answered};
use super::world_save_wait::{hashes, loaded_bytes, request};

/// Every carve a chunk applied: its chunk, request id and state hash
/// right after, in the order applied; and the carves refused.
#[derive(Resource, Default)]
struct Landed {
    applied: Vec<(ChunkCoord, u64, u64)>,
    refused: usize,
}

fn note_landed(
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    chunks: Query<&WorldChunk>,
    mut landed: ResMut<Landed>,
) {
    for report in applied.read() {
        let (Ok(chunk), Some(request)) = (chunks.get(report.terrain), report.request) else {
            continue;
        };
        landed.applied.push((chunk.coord, request, report.hash));
    }
    landed.refused += rejected.read().count();
}

/// Cavities under the surface (heights 8..=20) on the borders and corners
/// of chunk (0, 0), none overlapping another: each world carve reaches two
/// chunks, or four around a corner (every sixth), and changes each.
fn cavities() -> Vec<Vec3> {
    let levels = [2.0, 5.5];
    let along: Vec<f32> = (0..8).map(|i| 3.5 + 3.5 * i as f32).collect();
    let mut borders = Vec::new();
    let mut corners = Vec::new();
    for y in levels {
        for &s in &along {
            for p in [[0.0, s], [32.0, s], [s, 0.0], [s, 32.0]] {
                borders.push(Vec3::new(p[0], y, p[1]));
            }
        }
        for p in [[0.0, 0.0], [32.0, 0.0], [0.0, 32.0], [32.0, 32.0]] {
            corners.push(Vec3::new(p[0], y, p[1]));
        }
    }
    let (mut borders, mut corners) = (borders.into_iter(), corners.into_iter());
    (0..)
        .map_while(|k| {
            if k % 6 == 0 {
                corners.next().or_else(|| borders.next())
            } else {
                borders.next().or_else(|| corners.next())
            }
        })
        .collect()
}

/// The cavities' circumradius.
const CAVITY: f32 = 1.5;

/// Which world carves each chunk's file holds: the request whose state
/// hash after it the file has (`None` for no file: nothing landed there),
/// from the chunk's applied carves.
fn requests_in_files(
    files: &BTreeMap<ChunkCoord, u64>,
    landed: &Landed,
) -> BTreeMap<ChunkCoord, Option<u64>> {
    let mut per_chunk: BTreeMap<ChunkCoord, Vec<(u64, u64)>> = BTreeMap::new();
    for &(coord, request, hash) in &landed.applied {
        per_chunk.entry(coord).or_default().push((request, hash));
    }
    let mut held = BTreeMap::new();
    for (coord, carves) in &per_chunk {
        let distinct: BTreeSet<u64> = carves.iter().map(|c| c.1).collect();
        assert_eq!(distinct.len(), carves.len(), "each carve changes {coord:?}");
        let r = files.get(coord).map(|hash| {
            let found = carves.iter().find(|c| c.1 == *hash);
            found
                .unwrap_or_else(|| panic!("{coord:?}: the file is no state it had"))
                .0
        });
        held.insert(*coord, r);
    }
    for coord in files.keys() {
        assert!(held.contains_key(coord), "{coord:?} has a file, no carve");
    }
    held
}

/// Checks that each file holds its chunk as it was after some carve, and
/// every world carve (`carving` of them, each over two or four chunks) is
/// in all of its chunks' files or in none; returns which carve each
/// chunk's file holds and the carves in the files.
fn carves_in_files(
    files: &BTreeMap<ChunkCoord, Vec<u8>>,
    landed: &Landed,
    carving: u32,
) -> (BTreeMap<ChunkCoord, Option<u64>>, BTreeSet<u64>) {
    let held = requests_in_files(&hashes(files), landed);
    let mut routed: BTreeMap<u64, BTreeSet<ChunkCoord>> = BTreeMap::new();
    for &(coord, request, _) in &landed.applied {
        routed.entry(request).or_default().insert(coord);
    }
    assert_eq!(routed.len(), carving as usize, "every carve landed");
    let mut in_files = BTreeSet::new();
    let mut corners = 0;
    for (&request, chunks) in &routed {
        assert!(chunks.len() >= 2, "carve {request} reached {chunks:?}");
        corners += usize::from(chunks.len() == 4);
        let holds: BTreeSet<bool> = (chunks.iter())
            .map(|c| held[c].is_some_and(|r| r >= request))
            .collect();
        assert_eq!(holds.len(), 1, "carve {request} split: {chunks:?} {held:?}");
        if holds.contains(&true) {
            in_files.insert(request);
        }
    }
    assert!(corners > 0);
    (held, in_files)
}

#[test]
fn a_world_carved_in_every_frame_across_borders_saves_a_consistent_cut() {
    const ASK: u32 = 3;
    const CARVING: u32 = 70;
    let (mut app, world, _focus) = save_app(new_world().with_max_save_wait(100));
    app.init_resource::<Landed>()
        .add_systems(Update, note_landed.after(TerrainSystems::Mesh));
    let settle_frames = the_world(&app, world).save_settle_frames();
    assert_eq!(settle_frames, DEFAULT_SAVE_SETTLE_FRAMES);
    assert_eq!(
        the_world(&app, world).save_hold_frames(),
        DEFAULT_SAVE_HOLD_FRAMES
    );
    let mut holding = 0;
    let craters = cavities();
    assert!(craters.len() >= CARVING as usize);
    let dir = temp_folder("cut-drill");

    // A crater in every frame; the request in frame `ASK`.
    let mut started = None;
    let mut first: Option<(WorldSaved, BTreeMap<ChunkCoord, Vec<u8>>)> = None;
    // Frames paced at 60 a second, as a game's.
    let pace = std::time::Duration::from_micros(16_667);
    for frame in 0..CARVING {
        let start = std::time::Instant::now();
        carve(
            &mut app,
            world,
            dodecahedron(CAVITY, craters[frame as usize]),
        );
        if frame == ASK {
            request(&mut app, world, &dir);
        }
        app.update();
        if frame >= ASK && started.is_none() && !the_world(&app, world).save_waiting() {
            started = Some(frame);
        }
        holding += u32::from(the_world(&app, world).save_holds_carves());
        if first.is_none()
            && let Some(done) = heard(&app).saved.first()
        {
            // Read before the next save can write the folder.
            first = Some((done.clone(), loaded_bytes(&dir)));
        }
        if let Some(rest) = pace.checked_sub(start.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    let started = started.expect("the save started while carving went on");
    let waited = started - ASK;
    println!(
        "save started {waited} frames after the request, carved in every frame, \
         carves held back in {holding} frames"
    );
    assert!(holding <= DEFAULT_SAVE_HOLD_FRAMES, "held {holding} frames");
    assert!(
        waited >= settle_frames && waited <= settle_frames + 12,
        "waited {waited} frames, settle {settle_frames}"
    );
    until_answered(&mut app, 1);
    let (done, files) = first.unwrap_or_else(|| {
        let done = heard(&app).saved.first().cloned().expect("saved");
        (done, loaded_bytes(&dir))
    });
    assert!(heard(&app).failed.is_empty(), "{:?}", heard(&app).failed);
    // The carve of the frame it started in, at least, was in flight.
    assert!(done.left_out >= 1, "{done:?}");
    settle(&mut app, world);
    let landed = app.world().resource::<Landed>();
    assert_eq!(landed.refused, 0);
    assert_eq!(the_world(&app, world).stats().detached_across, 0);

    let (held, in_files) = carves_in_files(&files, landed, CARVING);
    // The carves up to the save's frame are in the files but those left
    // out; none after it is.
    let started = u64::from(started);
    assert!(in_files.iter().all(|&r| r <= started), "{in_files:?}");
    let out = (0..=started).filter(|r| !in_files.contains(r)).count();
    assert_eq!(out, done.left_out, "left out: {in_files:?}");
    assert!(!in_files.is_empty(), "a cut, not nothing");

    // Settled, the next save writes the chunks that changed since the
    // cut (and those saved with seeds since searched), and the folder
    // then loads as the world is.
    let changed: BTreeSet<ChunkCoord> = (landed.applied.iter())
        .filter(|&&(coord, request, _)| held[&coord].is_none_or(|r| request > r))
        .map(|&(coord, _, _)| coord)
        .collect();
    assert!(!changed.is_empty());
    let again = save(&mut app, world, &dir).expect("saves");
    assert_eq!(again.left_out, 0, "a whole state");
    let written: BTreeSet<ChunkCoord> = again.written.iter().copied().collect();
    assert!(changed.is_subset(&written), "{changed:?} {written:?}");
    for coord in written.difference(&changed) {
        let file = bevy_chisel::terrain::Terrain::from_bytes(&files[coord]).expect("valid");
        assert!(!file.border_seeds().is_empty(), "{coord:?} written again");
    }
    assert_eq!(
        hashes(&loaded_bytes(&dir)),
        hashes(&edited_bytes(&app, world))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn with_no_settle_frames_a_save_takes_a_consistent_state_at_once() {
    let world = new_world().with_max_save_wait(0).with_save_settle_frames(0);
    let (mut app, world, _focus) = save_app(world);
    assert_eq!(the_world(&app, world).save_settle_frames(), 0);
    carve(
        &mut app,
        world,
        dodecahedron(CAVITY, Vec3::new(10.0, 5.5, 16.0)),
    );
    settle(&mut app, world);
    let before = hashes(&edited_bytes(&app, world));
    // A carve over the corner of four chunks and the request in one frame:
    // the carve is in flight in all four, and left out.
    carve(
        &mut app,
        world,
        dodecahedron(CAVITY, Vec3::new(32.0, 5.5, 32.0)),
    );
    let dir = temp_folder("cut-at-once");
    request(&mut app, world, &dir);
    app.update();
    assert!(!the_world(&app, world).save_waiting(), "started at once");
    until_answered(&mut app, 1);
    let done = heard(&app).saved.first().cloned().expect("saved");
    assert_eq!(
        (done.written.as_slice(), done.left_out),
        ([at(0, 0)].as_slice(), 1)
    );
    assert_eq!(hashes(&loaded_bytes(&dir)), before, "the state before it");
    settle(&mut app, world);
    let now = edited_bytes(&app, world);
    assert_eq!(now.len(), 4, "the carve reached four chunks");
    let again = save(&mut app, world, &dir).expect("saves");
    assert_eq!((again.written.len(), again.left_out), (4, 0));
    assert_eq!(hashes(&loaded_bytes(&dir)), hashes(&now));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bound_below_the_settle_frames_gives_up_on_a_busy_world() {
    let world = new_world().with_max_save_wait(0);
    let (mut app, world, _focus) = save_app(world);
    assert!(the_world(&app, world).save_settle_frames() > 0);
    carve(
        &mut app,
        world,
        dodecahedron(CAVITY, Vec3::new(32.0, 5.5, 16.0)),
    );
    let dir = temp_folder("cut-bound");
    request(&mut app, world, &dir);
    app.update();
    let h = heard(&app);
    assert!(h.saved.is_empty());
    assert_eq!(h.failed.len(), 1, "gave up in the request's frame");
    assert!(
        matches!(h.failed[0].error, TerrainError::WorldNotIdle { .. }),
        "{:?}",
        h.failed[0].error
    );
    assert!(!dir.exists(), "nothing written");
}

/// A world carved across chunk borders in every frame for `carving`
/// frames, a [`SaveWorld`] asked in frame `ask`; then settled. Returns the
/// frame the save started in (`None`: not while carving), the frames in
/// which carves were held back, the first answer with the files it wrote
/// (read before another save could write the folder) and what landed.
fn drill(
    world: TerrainWorld,
    ask: u32,
    carving: u32,
    dir: &std::path::Path,
) -> (
    Option<u32>,
    u32,
    WorldSaved,
    BTreeMap<ChunkCoord, Vec<u8>>,
    App,
    Entity,
) {
    let (mut app, world, _focus) = save_app(world);
    app.init_resource::<Landed>()
        .add_systems(Update, note_landed.after(TerrainSystems::Mesh));
    let craters = cavities();
    assert!(craters.len() >= carving as usize);
    let (mut started, mut holding, mut first) = (None, 0, None);
    let pace = std::time::Duration::from_micros(16_667);
    for frame in 0..carving {
        let start = std::time::Instant::now();
        carve(
            &mut app,
            world,
            dodecahedron(CAVITY, craters[frame as usize]),
        );
        if frame == ask {
            request(&mut app, world, dir);
        }
        app.update();
        if frame >= ask && started.is_none() && !the_world(&app, world).save_waiting() {
            started = Some(frame);
        }
        holding += u32::from(the_world(&app, world).save_holds_carves());
        if first.is_none()
            && let Some(done) = heard(&app).saved.first()
        {
            first = Some((done.clone(), loaded_bytes(dir)));
        }
        if let Some(rest) = pace.checked_sub(start.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    while the_world(&app, world).save_waiting() {
        app.update();
        holding += u32::from(the_world(&app, world).save_holds_carves());
    }
    until_answered(&mut app, 1);
    let (done, files) = first.unwrap_or_else(|| {
        let done = heard(&app).saved.first().cloned().expect("saved");
        (done, loaded_bytes(dir))
    });
    assert!(heard(&app).failed.is_empty(), "{:?}", heard(&app).failed);
    settle(&mut app, world);
    (started, holding, done, files, app, world)
}

#[test]
fn with_no_hold_frames_no_carve_is_held_back_and_the_save_still_comes() {
    const ASK: u32 = 3;
    const CARVING: u32 = 40;
    let dir = temp_folder("cut-no-hold");
    let world = new_world().with_max_save_wait(200).with_save_hold_frames(0);
    assert_eq!(world.save_hold_frames(), 0);
    let (started, holding, done, files, app, _) = drill(world, ASK, CARVING, &dir);
    println!(
        "no hold frames: save started in frame {started:?} (asked in {ASK}, carving \
         until {CARVING}), {} carves left out",
        done.left_out
    );
    assert_eq!(holding, 0, "no carve held back");
    let landed = app.world().resource::<Landed>();
    assert_eq!(landed.refused, 0);
    // Whether a consistent state came while carving or the whole one
    // after it, the files hold every world carve whole or not at all.
    let (_, in_files) = carves_in_files(&files, landed, CARVING);
    match started {
        Some(frame) => {
            let frame = u64::from(frame);
            assert!(frame >= u64::from(ASK + DEFAULT_SAVE_SETTLE_FRAMES) || done.left_out == 0);
            assert!(in_files.iter().all(|&r| r <= frame), "{in_files:?}");
            let out = (0..=frame).filter(|r| !in_files.contains(r)).count();
            assert_eq!(out, done.left_out, "left out: {in_files:?}");
        }
        None => {
            assert_eq!(done.left_out, 0, "a whole state after the carving");
            assert_eq!(in_files.len(), CARVING as usize);
        }
    }
    assert!(!in_files.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_hold_frames_default_and_bound_the_frames_carves_are_held_back() {
    const ASK: u32 = 3;
    const CARVING: u32 = 50;
    let dir = temp_folder("cut-hold-2");
    let world = new_world().with_max_save_wait(200).with_save_hold_frames(2);
    let (started, holding, done, files, app, _) = drill(world, ASK, CARVING, &dir);
    println!("hold 2: save started in frame {started:?}, carves held back {holding} frames");
    assert!(holding <= 2, "held {holding} frames");
    let landed = app.world().resource::<Landed>();
    let (_, in_files) = carves_in_files(&files, landed, CARVING);
    assert!(!in_files.is_empty());
    let _ = (done, std::fs::remove_dir_all(&dir));
    assert_eq!(
        new_world().save_hold_frames(),
        DEFAULT_SAVE_HOLD_FRAMES,
        "15 by default"
    );
    assert_eq!(DEFAULT_SAVE_HOLD_FRAMES, 15);
}
