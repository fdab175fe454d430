//! Saving a streamed world in the background (`MinimalPlugins`): a
//! [`SaveWorld`] writes every chunk as it was in the frame it was read,
//! while carves go on; later saves write only the chunks that changed (a
//! chunk streamed out or back in unchanged is not written again); an undo
//! back to the base removes the chunk's file; a failed save names the path
//! and leaves the record as it was; requests while one is written wait
//! their turn (waiting for a whole state: `world_save_wait`). What a
//! request costs its frame: the `terrain` bench, `saving_a_world`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::tasks::IoTaskPool;
use bevy_chisel::terrain::{
    ChunkCoord, SaveWorld, Terrain, TerrainError, TerrainSystems, TerrainWorld, WorldSaveFailed,
    WorldSaved, WorldUndo,
};

use super::terrain_world::{
    app_with, carve, chunk_files, dodecahedron, settle, terrain, the_world, world as new_world,
};
use super::world_save_seeds::without_seeds;

pub(super) const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// A point inside chunk `c` under its surface (heights 8..=20), moved
/// by `step` so that repeated carves there differ.
pub(super) fn inside(c: ChunkCoord, step: u32) -> Vec3 {
    let s = step as f32;
    Vec3::new(
        c.x as f32 * 32.0 + 10.0 + 1.5 * (s % 8.0),
        12.0,
        c.z as f32 * 32.0 + 16.0,
    )
}

/// What the save messages said so far, and the frames in which the world
/// was marked changed.
#[derive(Resource, Default)]
pub(super) struct Heard {
    pub(super) saved: Vec<WorldSaved>,
    pub(super) failed: Vec<WorldSaveFailed>,
    pub(super) world_changed: usize,
}

pub(super) fn hear(
    mut saved: MessageReader<WorldSaved>,
    mut failed: MessageReader<WorldSaveFailed>,
    worlds: Query<Ref<TerrainWorld>>,
    mut heard: ResMut<Heard>,
) {
    heard.saved.extend(saved.read().cloned());
    heard.failed.extend(failed.read().cloned());
    heard.world_changed += worlds.iter().filter(|w| w.is_changed()).count();
}

pub(super) fn save_app(world: TerrainWorld) -> (App, Entity, Entity) {
    save_app_at(world, Vec3::new(16.0, 30.0, 16.0))
}

pub(super) fn save_app_at(world: TerrainWorld, focus: Vec3) -> (App, Entity, Entity) {
    let share = IoPoolShare::take();
    let (mut app, world, focus) = app_with(world, focus);
    app.insert_resource(share)
        .init_resource::<Heard>()
        .add_systems(Update, hear.after(TerrainSystems::Mesh));
    (app, world, focus)
}

pub(super) fn heard(app: &App) -> &Heard {
    app.world().resource::<Heard>()
}

pub(super) fn temp_folder(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "bevy_chisel-world-save-{tag}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_file(&dir);
    dir
}

/// Sends a [`SaveWorld`] and runs frames until it is answered; `each`
/// runs before every frame after the request frame.
pub(super) fn save_with(
    app: &mut App,
    world: Entity,
    folder: &Path,
    mut each: impl FnMut(&mut App, u32),
) -> Result<WorldSaved, WorldSaveFailed> {
    let (saved, failed) = (heard(app).saved.len(), heard(app).failed.len());
    app.world_mut().write_message(SaveWorld {
        world,
        folder: folder.to_path_buf(),
    });
    for frame in 0..20_000 {
        if frame > 0 {
            each(app, frame);
        }
        app.update();
        let h = heard(app);
        if let Some(done) = h.saved.get(saved) {
            assert_eq!(h.failed.len(), failed, "one answer");
            return Ok(done.clone());
        }
        if let Some(error) = h.failed.get(failed) {
            return Err(error.clone());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    panic!("the save was not answered");
}

pub(super) fn save(
    app: &mut App,
    world: Entity,
    folder: &Path,
) -> Result<WorldSaved, WorldSaveFailed> {
    save_with(app, world, folder, |_, _| {})
}

/// The file bytes of every edited chunk now (live ones serialized, stored
/// ones as kept).
pub(super) fn edited_bytes(app: &App, world: Entity) -> BTreeMap<ChunkCoord, Vec<u8>> {
    let w = the_world(app, world);
    let mut bytes: BTreeMap<ChunkCoord, Vec<u8>> = w
        .live_chunks()
        .filter_map(|(coord, e)| {
            let t = app.world().get::<Terrain>(e)?;
            w.chunk_edited(coord, t).then(|| (coord, t.to_bytes()))
        })
        .collect();
    for coord in w.stored_chunks() {
        let stored = w.stored_chunk(coord).expect("stored bytes");
        bytes.insert(coord, stored.to_vec());
    }
    bytes
}

pub(super) fn names(coords: &[ChunkCoord]) -> Vec<String> {
    let mut names: Vec<String> = coords
        .iter()
        .map(|&c| TerrainWorld::chunk_file_name(c))
        .collect();
    names.sort();
    names
}

fn move_focus(app: &mut App, world: Entity, focus: Entity, to: Vec3) {
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = to;
    settle(app, world);
}

#[test]
fn a_background_save_writes_the_request_frame_while_carves_go_on() {
    let (mut app, world, _focus) = save_app(new_world());
    let live = [at(0, 0), at(1, 0), at(0, 1), at(-1, -1)];
    let far = at(-5, 3);
    for (i, &c) in live.iter().chain([&far]).enumerate() {
        carve(&mut app, world, dodecahedron(4.0, inside(c, i as u32)));
    }
    settle(&mut app, world);
    assert_eq!(
        the_world(&app, world).stored_chunks().collect::<Vec<_>>(),
        [far]
    );
    let at_save = edited_bytes(&app, world);
    let mut all: Vec<ChunkCoord> = at_save.keys().copied().collect();
    all.sort();
    assert_eq!(all.len(), 5);

    // Carve on in every frame after the request frame until it is saved.
    let dir = temp_folder("frame");
    let mut carves = 0;
    let done = save_with(&mut app, world, &dir, |app, frame| {
        let c = live[frame as usize % 2];
        carve(app, world, dodecahedron(3.0, inside(c, frame + 7)));
        carves += 1;
    })
    .expect("saves");
    assert!(carves > 0, "carves were sent while it wrote");
    assert_eq!(done.world, world);
    assert_eq!(done.folder, dir);
    assert_eq!(done.written, all);
    assert_eq!(done.unchanged, 0);
    assert_eq!(done.bytes, at_save.values().map(Vec::len).sum::<usize>());
    assert_eq!(chunk_files(&dir), names(&all));
    settle(&mut app, world);
    let later = edited_bytes(&app, world);
    assert!(
        live[..2].iter().any(|c| later[c] != at_save[c]),
        "the later carves landed"
    );

    // A fresh world from the folder holds exactly the request frame's
    // chunks: the same file bytes, so the same octrees, journals, undo
    // histories and state hashes.
    let loaded = new_world().load_edits(&dir).expect("loads");
    for (coord, bytes) in &at_save {
        let stored = loaded.stored_chunk(*coord).expect("loaded chunk");
        assert!(
            stored == bytes.as_slice(),
            "chunk {coord:?} is the saved one"
        );
        let hash = Terrain::from_bytes(bytes).expect("valid").state_hash();
        let back = Terrain::from_bytes(stored).expect("valid");
        assert_eq!(back.state_hash(), hash);
        assert_eq!(
            bevy_chisel::bsp::octree::StateHash::of(back.octree()).value(),
            hash
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn later_saves_write_only_the_chunks_that_changed() {
    let (mut app, world, focus) = save_app(new_world());
    let chunks = [at(-1, 0), at(0, 0), at(1, 1)];
    for (i, &c) in chunks.iter().enumerate() {
        carve(&mut app, world, dodecahedron(4.0, inside(c, i as u32)));
    }
    settle(&mut app, world);
    let dir = temp_folder("changed");
    let first = save(&mut app, world, &dir).expect("saves");
    assert_eq!(first.written, chunks);

    // One more carve in one chunk: only its file is written.
    carve(&mut app, world, dodecahedron(3.0, inside(chunks[1], 5)));
    settle(&mut app, world);
    let want = edited_bytes(&app, world);
    heard_reset(&mut app);
    let second = save(&mut app, world, &dir).expect("saves");
    assert_eq!(second.written, [chunks[1]]);
    assert_eq!(second.unchanged, 2);
    assert_eq!(second.bytes, want[&chunks[1]].len());
    for (coord, bytes) in &want {
        let file = std::fs::read(dir.join(TerrainWorld::chunk_file_name(*coord))).expect("file");
        assert!(file == *bytes, "chunk {coord:?} on disk is the chunk now");
    }

    // Nothing changed: nothing written, and the world is never marked
    // changed by saving.
    let third = save(&mut app, world, &dir).expect("saves");
    assert_eq!(
        (third.written.len(), third.unchanged, third.bytes),
        (0, 3, 0)
    );
    assert_eq!(heard(&app).world_changed, 0, "saving marks no change");

    // Streamed out (stored) and back in (new entities), unchanged: not
    // written again.
    let away = Vec3::new(16.0 + 32.0 * 8.0, 30.0, 16.0);
    move_focus(&mut app, world, focus, away);
    assert_eq!(the_world(&app, world).stored_chunks().count(), 3);
    let out = save(&mut app, world, &dir).expect("saves");
    assert_eq!((out.written.len(), out.unchanged), (0, 3));
    move_focus(&mut app, world, focus, Vec3::new(16.0, 30.0, 16.0));
    assert_eq!(the_world(&app, world).stored_chunks().count(), 0);
    let back = save(&mut app, world, &dir).expect("saves");
    assert_eq!((back.written.len(), back.unchanged), (0, 3));

    // A synchronous save writes everything and keeps the record: the
    // background save after it writes nothing.
    let sync = the_world(&app, world)
        .save(&dir, |e| app.world().get::<Terrain>(e))
        .expect("saves");
    assert_eq!(sync, chunks);
    let after_sync = save(&mut app, world, &dir).expect("saves");
    assert_eq!((after_sync.written.len(), after_sync.unchanged), (0, 3));
    assert_eq!(edited_bytes(&app, world), want);
    let _ = std::fs::remove_dir_all(&dir);
}

fn heard_reset(app: &mut App) {
    app.world_mut().resource_mut::<Heard>().world_changed = 0;
}

#[test]
fn an_undo_back_to_the_base_removes_the_chunk_file() {
    let (mut app, world, _focus) = save_app(new_world());
    let (kept, undone) = (at(0, 0), at(1, 0));
    carve(&mut app, world, dodecahedron(4.0, inside(kept, 0)));
    settle(&mut app, world);
    carve(&mut app, world, dodecahedron(4.0, inside(undone, 1)));
    settle(&mut app, world);
    let dir = temp_folder("undo");
    std::fs::create_dir_all(&dir).expect("folder");
    std::fs::write(dir.join("notes.txt"), b"not a chunk").expect("writes");
    let first = save(&mut app, world, &dir).expect("saves");
    assert_eq!(first.written, [kept, undone]);
    assert_eq!(chunk_files(&dir), names(&[kept, undone]));

    app.world_mut().write_message(WorldUndo { world });
    settle(&mut app, world);
    assert!(terrain(&app, world, undone).journal().is_empty());
    let second = save(&mut app, world, &dir).expect("saves");
    assert_eq!((second.written.len(), second.unchanged), (0, 1));
    assert_eq!(chunk_files(&dir), names(&[kept]));
    assert!(dir.join("notes.txt").exists(), "other files stay");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failed_save_names_the_path_and_leaves_the_record_as_it_was() {
    let (mut app, world, _focus) = save_app(new_world());
    let (a, b) = (at(0, 0), at(1, 0));
    for (i, c) in [a, b].into_iter().enumerate() {
        carve(&mut app, world, dodecahedron(4.0, inside(c, i as u32)));
    }
    settle(&mut app, world);

    // The folder path is a regular file: refused, naming it, nothing
    // written beside it.
    let parent = temp_folder("failed-parent");
    std::fs::create_dir_all(&parent).expect("folder");
    let file = parent.join("not-a-folder");
    std::fs::write(&file, b"a file").expect("writes");
    let failed = save(&mut app, world, &file).expect_err("a file is no folder");
    assert_eq!((failed.world, &failed.folder), (world, &file));
    let TerrainError::Io { message } = &failed.error else {
        panic!("an i/o error, got {:?}", failed.error);
    };
    assert!(message.contains(&file.display().to_string()), "{message}");
    assert_eq!(std::fs::read(&file).expect("file"), b"a file");
    assert_eq!(std::fs::read_dir(&parent).expect("folder").count(), 1);

    // A save that fails half way (chunk b's file is a folder): a is
    // written, b is not, no stale file is removed, and the next save
    // writes both again.
    let dir = temp_folder("failed");
    assert_eq!(save(&mut app, world, &dir).expect("saves").written, [a, b]);
    for (i, c) in [a, b].into_iter().enumerate() {
        carve(&mut app, world, dodecahedron(3.0, inside(c, i as u32 + 3)));
    }
    settle(&mut app, world);
    let b_path = dir.join(TerrainWorld::chunk_file_name(b));
    std::fs::remove_file(&b_path).expect("removes");
    std::fs::create_dir_all(b_path.join("inside")).expect("a folder in the way");
    let stale = dir.join(TerrainWorld::chunk_file_name(at(9, 9)));
    std::fs::copy(dir.join(TerrainWorld::chunk_file_name(a)), &stale).expect("copies");
    let failed = save(&mut app, world, &dir).expect_err("b cannot be written");
    let TerrainError::Io { message } = &failed.error else {
        panic!("an i/o error, got {:?}", failed.error);
    };
    assert!(message.contains(&b_path.display().to_string()), "{message}");
    assert!(stale.exists(), "nothing removed after a failure");
    std::fs::remove_dir_all(&b_path).expect("removes");
    let retried = save(&mut app, world, &dir).expect("saves");
    assert_eq!(retried.written, [a, b], "the failure advanced nothing");
    assert!(
        !stale.exists(),
        "the stale file goes with a save that succeeds"
    );
    assert_eq!(chunk_files(&dir), names(&[a, b]));
    let now = edited_bytes(&app, world);
    for (coord, bytes) in &now {
        let file = std::fs::read(dir.join(TerrainWorld::chunk_file_name(*coord))).expect("file");
        assert!(file == *bytes, "chunk {coord:?} on disk is the chunk now");
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&parent);
}

/// Who uses Bevy's I/O task pool among the save tests. The pool is global
/// to the test binary, so while one test holds all of its threads
/// ([`IoPoolHeld`]) the saves of the tests running beside it would wait,
/// and those that bound the frames a save may take would fail. Each save
/// test's app keeps an [`IoPoolShare`]; holding the pool waits until no
/// other test has one, and a share waits while the pool is held.
struct IoPoolGate {
    shares: usize,
    held: bool,
}

static IO_POOL_GATE: Mutex<IoPoolGate> = Mutex::new(IoPoolGate {
    shares: 0,
    held: false,
});
static IO_POOL_TURN: Condvar = Condvar::new();

/// The gate, also after a test panicked while it had it.
fn io_pool_gate() -> MutexGuard<'static, IoPoolGate> {
    IO_POOL_GATE.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A save test's use of the I/O task pool, for as long as its app lives.
#[derive(Resource)]
pub(super) struct IoPoolShare;

impl IoPoolShare {
    /// Waits while another test holds the pool.
    pub(super) fn take() -> Self {
        let mut gate = io_pool_gate();
        while gate.held {
            gate = IO_POOL_TURN
                .wait(gate)
                .unwrap_or_else(PoisonError::into_inner);
        }
        gate.shares += 1;
        Self
    }
}

impl Drop for IoPoolShare {
    fn drop(&mut self) {
        io_pool_gate().shares -= 1;
        IO_POOL_TURN.notify_all();
    }
}

/// Holds every thread of the I/O task pool until dropped, so that a save
/// started meanwhile is surely still being written in the next frames.
struct IoPoolHeld(Arc<AtomicBool>);

impl IoPoolHeld {
    /// Waits until the calling test's app (one [`IoPoolShare`]) is the
    /// pool's only user, then returns once every thread of the pool runs
    /// one of its blockers: a blocker only queued could run after a save
    /// spawned later (a busy machine wakes the pool's threads late, and a
    /// thread may take the save first), and the save would be written at
    /// once.
    fn new() -> Self {
        let mut gate = io_pool_gate();
        while gate.held || gate.shares > 1 {
            gate = IO_POOL_TURN
                .wait(gate)
                .unwrap_or_else(PoisonError::into_inner);
        }
        gate.held = true;
        drop(gate);
        let released = Arc::new(AtomicBool::new(false));
        let started = Arc::new(AtomicUsize::new(0));
        let pool = IoTaskPool::get();
        let threads = pool.thread_num().max(1);
        for _ in 0..threads {
            let (released, started) = (released.clone(), started.clone());
            pool.spawn(async move {
                started.fetch_add(1, Ordering::AcqRel);
                while !released.load(Ordering::Acquire) {
                    std::thread::sleep(Duration::from_millis(1));
                }
            })
            .detach();
        }
        let held = Self(released);
        let begun = Instant::now();
        while started.load(Ordering::Acquire) < threads {
            assert!(
                begun.elapsed() < Duration::from_secs(60),
                "the I/O pool's {threads} threads did not all take a blocker"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
        held
    }
}

impl Drop for IoPoolHeld {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
        io_pool_gate().held = false;
        IO_POOL_TURN.notify_all();
    }
}

/// Runs frames until `count` saves are answered (successes and
/// failures together).
pub(super) fn until_answered(app: &mut App, count: usize) {
    for _ in 0..20_000 {
        let h = heard(app);
        if h.saved.len() + h.failed.len() >= count {
            return;
        }
        app.update();
        std::thread::sleep(Duration::from_millis(1));
    }
    panic!("the saves were not answered");
}

#[test]
fn requests_while_a_save_is_written_wait_their_turn() {
    let (mut app, world, _focus) = save_app(new_world());
    let chunks = [at(0, 0), at(1, 0)];
    for (i, &c) in chunks.iter().enumerate() {
        carve(&mut app, world, dodecahedron(4.0, inside(c, i as u32)));
    }
    settle(&mut app, world);
    let (dir, other) = (temp_folder("twice"), temp_folder("twice-other"));
    let send = |app: &mut App, folder: &PathBuf| {
        app.world_mut().write_message(SaveWorld {
            world,
            folder: folder.clone(),
        });
    };
    // The first starts at once (the world is settled); the second, for
    // another folder, waits for it.
    let held = IoPoolHeld::new();
    send(&mut app, &dir);
    send(&mut app, &other);
    app.update();
    // The first is being written (its outcome is read in a later frame).
    let w = the_world(&app, world);
    assert!(w.is_saving());
    assert_eq!(w.waiting_saves().collect::<Vec<_>>(), [other.as_path()]);
    // The synchronous save does not wait: it is refused meanwhile.
    let sync = w.save(&other, |e| app.world().get::<Terrain>(e));
    let running = TerrainError::WorldSaveRunning {
        folder: dir.display().to_string(),
    };
    assert_eq!(sync, Err(running));

    // A carve, and a request for the folder being written: not merged
    // into that save, it waits behind the other folder's and writes only
    // the carved chunk; the save to `other` writes every chunk.
    carve(&mut app, world, dodecahedron(3.0, inside(chunks[1], 5)));
    send(&mut app, &dir);
    app.update();
    let w = the_world(&app, world);
    assert!(w.is_saving(), "the first is still being written");
    assert_eq!(
        w.waiting_saves().collect::<Vec<_>>(),
        [other.as_path(), dir.as_path()]
    );
    assert!(heard(&app).failed.is_empty(), "nothing refused");
    drop(held);
    until_answered(&mut app, 3);
    let h = heard(&app);
    assert!(h.failed.is_empty(), "{:?}", h.failed);
    let folders: Vec<&PathBuf> = h.saved.iter().map(|s| &s.folder).collect();
    assert_eq!(folders, [&dir, &other, &dir], "in the order they were read");
    assert_eq!(h.saved[0].written, chunks);
    assert_eq!(
        (h.saved[1].written.as_slice(), h.saved[1].unchanged),
        (&chunks[..], 0)
    );
    assert_eq!(
        (h.saved[2].written.as_slice(), h.saved[2].unchanged),
        (&chunks[1..], 1)
    );
    let w = the_world(&app, world);
    assert!(!w.is_saving() && !w.save_waiting());
    settle(&mut app, world);
    let now = edited_bytes(&app, world);
    for folder in [&dir, &other] {
        assert_eq!(chunk_files(folder), names(&chunks));
        for (coord, bytes) in &now {
            let file =
                std::fs::read(folder.join(TerrainWorld::chunk_file_name(*coord))).expect("file");
            // Saved with the seeds its search had not applied yet.
            assert!(
                without_seeds(&file) == *bytes,
                "chunk {coord:?} in {folder:?} is the chunk now"
            );
        }
    }
    assert_eq!(heard(&app).saved.len(), 3, "one answer each");

    // A request for an entity with no world is refused in its frame.
    let nobody = app.world_mut().spawn_empty().id();
    let none = save(&mut app, nobody, &dir).expect_err("no world");
    assert!(matches!(none.error, TerrainError::InvalidWorld { .. }));
    for folder in [&dir, &other] {
        let _ = std::fs::remove_dir_all(folder);
    }
}
