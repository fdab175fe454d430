//! A streamed world saves the falls across chunk borders still on their
//! way (`MinimalPlugins`): a chunk's seeds, in it or taken by a search not
//! applied yet, are written with the chunk, so a save no longer waits for
//! them. A world cratered every other frame saves within a few frames; a
//! save taken while a slab cut loose over a border has not fallen yet,
//! loaded into a fresh world, makes the slab fall there, leaving the
//! chunks exactly as the original world's fall left them; a chunk saved
//! with seeds is written again once they are searched, though its
//! terrain did not change; chunk files of the format before seeds
//! (version 2) still load, with none; bad seeds are an error naming the
//! file.

use std::path::Path;

use bevy::prelude::*;
use bevy_chisel::bsp::octree::store::checksum;
use bevy_chisel::terrain::file::FORMAT_VERSION;
use bevy_chisel::terrain::{ChunkCoord, Terrain, TerrainError, TerrainWorld};

use super::terrain_world::{carve, dodecahedron, settle, terrain, the_world, world as new_world};
use super::terrain_world_debris::{CUT, build_slab, cuboid, debris, falling};
use super::world_save::{
    at, edited_bytes, heard, inside, save, save_app, save_app_at, temp_folder, until_answered,
};
use super::world_save_wait::{frames_waited, hashes, loaded_bytes, print_waits, request};

/// The focus of the slab's worlds, near the border of chunks (0, 0) and
/// (1, 0).
const SLAB_FOCUS: Vec3 = Vec3::new(32.0, 30.0, 16.0);

#[test]
fn a_world_cratered_every_other_frame_saves_within_a_few_frames() {
    const RUNS: u32 = 12;
    const BOUND: u32 = 8;
    let (mut app, world, _focus) = save_app(new_world().with_max_save_wait(BOUND));
    let chunks = [at(0, 0), at(1, 0), at(0, 1), at(-1, 0), at(0, -1)];
    let crater = |k: u32| dodecahedron(2.0, inside(chunks[k as usize % chunks.len()], k));
    for period in [2, 4] {
        let waited = frames_waited(&mut app, world, &crater, period, RUNS);
        let gave_up = print_waits("seeds saved", period, &waited, BOUND);
        // Each carve leaves seeds and starts a search; before seeds were
        // saved no request started while craters came every 2 frames.
        assert_eq!(gave_up, 0, "every save starts: {waited:?}");
    }
    assert!(heard(&app).failed.is_empty(), "{:?}", heard(&app).failed);
    assert!(the_world(&app, world).stats().debris_searches > 0);
}

#[test]
fn a_save_taken_before_a_slab_cut_loose_falls_makes_it_fall_after_loading() {
    // Waiting for a whole state however long the cut's jobs take (after
    // the settle frames a save could leave the cut out).
    let whole = new_world().with_save_settle_frames(u32::MAX);
    let (mut app, world, _focus) = save_app_at(whole, SLAB_FOCUS);
    build_slab(&mut app, world, false);
    let standing = hashes(&edited_bytes(&app, world));
    // The cut and the request in the same frame: the first whole frame is
    // the one whose search takes the cut's seeds; the slab falls later.
    carve(&mut app, world, cuboid(CUT.0, CUT.1));
    let dir = temp_folder("seeds-slab");
    request(&mut app, world, &dir);
    until_answered(&mut app, 1);
    assert!(heard(&app).failed.is_empty(), "{:?}", heard(&app).failed);
    settle(&mut app, world);
    assert_eq!(the_world(&app, world).stats().detached_across, 1, "it fell");
    let fallen = hashes(&edited_bytes(&app, world));
    let saved = hashes(&loaded_bytes(&dir));
    assert_ne!(saved, fallen, "saved before the fall");
    assert_ne!(saved, standing, "saved after the cut");
    let cut_chunk = &loaded_bytes(&dir)[&at(0, 0)];
    let seeds = Terrain::from_bytes(cut_chunk).expect("valid");
    assert!(
        !seeds.border_seeds().is_empty(),
        "the cut's seeds are saved"
    );
    let pieces = debris(&mut app);
    assert_eq!(pieces.len(), 1);
    assert_eq!(pieces[0].exact_volume, falling());

    // A fresh world from the files: the seeds search again, the slab
    // falls there as one piece, and the chunks end as the original's.
    let loaded = new_world().load_edits(&dir).expect("loads");
    let (mut again, reloaded, _focus) = save_app_at(loaded, SLAB_FOCUS);
    settle(&mut again, reloaded);
    let w = the_world(&again, reloaded);
    assert_eq!(w.stats().detached_across, 1, "it falls after loading");
    let pieces = debris(&mut again);
    assert_eq!(pieces.len(), 1, "one body");
    assert_eq!(pieces[0].exact_volume, falling());
    assert_eq!(hashes(&edited_bytes(&again, reloaded)), fallen);
    for c in [at(0, 0), at(1, 0)] {
        let volume = |app: &App, world| terrain(app, world, c).octree().exact_solid_volume();
        assert_eq!(volume(&again, reloaded), volume(&app, world), "{c:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_chunk_saved_with_seeds_is_written_again_once_they_are_searched() {
    let (mut app, world, _focus) = save_app(new_world());
    let c = at(0, 0);
    // The crater and the request in the same frame: the save starts in
    // the frame whose search takes the crater's seeds.
    carve(&mut app, world, dodecahedron(3.0, inside(c, 0)));
    let dir = temp_folder("seeds-again");
    request(&mut app, world, &dir);
    until_answered(&mut app, 1);
    assert!(heard(&app).failed.is_empty(), "{:?}", heard(&app).failed);
    let file = loaded_bytes(&dir)[&c].clone();
    let saved = Terrain::from_bytes(&file).expect("valid");
    assert!(!saved.border_seeds().is_empty(), "saved with the seeds");
    settle(&mut app, world);
    let now = edited_bytes(&app, world);
    assert_eq!(now.keys().copied().collect::<Vec<_>>(), [c]);
    assert!(without_seeds(&file) == now[&c], "nothing fell");
    // Its terrain did not change since, but its seeds went: written
    // again, then left alone.
    let again = save(&mut app, world, &dir).expect("saves");
    assert_eq!((again.written.as_slice(), again.unchanged), (&[c][..], 0));
    assert!(loaded_bytes(&dir) == now, "the file is the chunk now");
    let third = save(&mut app, world, &dir).expect("saves");
    assert_eq!((third.written.len(), third.unchanged), (0, 1));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Terrain file `bytes` without their seeds (as a settled world's chunk
/// serializes after its search).
pub(super) fn without_seeds(bytes: &[u8]) -> Vec<u8> {
    let seeds = Terrain::from_bytes(bytes)
        .expect("valid")
        .border_seeds()
        .len();
    let body = bytes.len() - 8 - 4 - 13 * seeds;
    let mut out = bytes[..body].to_vec();
    out.extend_from_slice(&0u32.to_le_bytes());
    let sum = checksum(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// `bytes` (a terrain file of the current format whose seeds are
/// `seeds`' count and keys) with the seeds replaced by `seeds`, checksum
/// updated.
fn with_seeds(bytes: &[u8], seeds: &[u8]) -> Vec<u8> {
    let body = bytes.len() - 8 - 4;
    assert_eq!(bytes[body..body + 4], [0; 4], "a file without seeds");
    let mut out = bytes[..body].to_vec();
    out.extend_from_slice(seeds);
    let sum = checksum(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// A world with one carved chunk, saved into a new folder `tag`: the
/// folder, the chunk and its file bytes.
fn saved_world(tag: &str) -> (std::path::PathBuf, ChunkCoord, Vec<u8>, u64) {
    let (mut app, world, _focus) = save_app(new_world());
    let c = at(0, 0);
    carve(&mut app, world, dodecahedron(4.0, inside(c, 0)));
    settle(&mut app, world);
    let dir = temp_folder(tag);
    save(&mut app, world, &dir).expect("saves");
    let bytes = std::fs::read(dir.join(TerrainWorld::chunk_file_name(c))).expect("file");
    (dir, c, bytes, terrain(&app, world, c).state_hash())
}

fn write_chunk(dir: &Path, c: ChunkCoord, bytes: &[u8]) {
    std::fs::write(dir.join(TerrainWorld::chunk_file_name(c)), bytes).expect("written");
}

#[test]
fn chunk_files_without_seeds_of_the_older_format_still_load() {
    assert_eq!(FORMAT_VERSION, 3);
    let (dir, c, bytes, hash) = saved_world("seeds-old-format");
    // Version 2: the same file without the seeds' count.
    let mut old = with_seeds(&bytes, &[]);
    old[8..12].copy_from_slice(&2u32.to_le_bytes());
    let sum = checksum(&old[..old.len() - 8]);
    let at_sum = old.len() - 8;
    old[at_sum..].copy_from_slice(&sum.to_le_bytes());
    assert_eq!(old.len(), bytes.len() - 4);
    let terrain_v2 = Terrain::from_bytes(&old).expect("version 2 loads");
    assert!(
        terrain_v2.to_bytes() == bytes,
        "saved again: the same chunk, version 3"
    );
    write_chunk(&dir, c, &old);
    let loaded = new_world().load_edits(&dir).expect("loads");
    let (app, world, _focus) = save_app(loaded);
    assert_eq!(terrain(&app, world, c).state_hash(), hash);
    assert_eq!(
        the_world(&app, world).stats().debris_searches,
        0,
        "no seeds"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_seeds_in_a_chunk_file_are_an_error_naming_the_file() {
    let (dir, c, bytes, _) = saved_world("seeds-bad");
    let name = TerrainWorld::chunk_file_name(c);
    let key = |depth: u8, pos: [u32; 3]| {
        let mut k = vec![depth];
        pos.iter()
            .for_each(|p| k.extend_from_slice(&p.to_le_bytes()));
        k
    };
    let count = |n: u32| n.to_le_bytes().to_vec();
    let cases: [(Vec<u8>, &str); 3] = [
        // A position outside its depth's cube, a depth deeper than any
        // cube, and a count with no keys behind it.
        ([count(1), key(3, [8, 0, 0])].concat(), "names no cell"),
        ([count(1), key(28, [0; 3])].concat(), "names no cell"),
        (count(5), ""),
    ];
    for (seeds, why) in cases {
        write_chunk(&dir, c, &with_seeds(&bytes, &seeds));
        let error = new_world().load_edits(&dir).err().expect("refused");
        let TerrainError::InFile { path, error } = &error else {
            panic!("not named: {error:?}");
        };
        assert!(path.ends_with(&name), "{path}");
        match &**error {
            TerrainError::Corrupt { reason } => assert!(reason.contains(why), "{reason}"),
            TerrainError::Truncated { .. } => assert!(why.is_empty()),
            other => panic!("{other:?}"),
        }
    }
    // Good seeds load, and the world searches from them.
    let good = [count(2), key(5, [3, 2, 4]), key(5, [3, 2, 5])].concat();
    write_chunk(&dir, c, &with_seeds(&bytes, &good));
    let terrain_file = Terrain::from_bytes(&with_seeds(&bytes, &good)).expect("loads");
    assert!(terrain_file.to_bytes() == with_seeds(&bytes, &good), "kept");
    let loaded = new_world().load_edits(&dir).expect("loads");
    let (app, world, _focus) = save_app(loaded);
    assert_eq!(the_world(&app, world).stats().debris_searches, 1);
    let _ = std::fs::remove_dir_all(&dir);
}
