//! Soak test of the terrain plugin in an app without rendering
//! (`MinimalPlugins`): 10,000 carves (craters cut, material added, material
//! painted), with undo, save and load interleaved, on a small terrain.
//! The tools are drawn at random from a fixed palette of craters, so that
//! the terrain's content (cells, BSP nodes, meshes) reaches a steady size
//! after warm-up: a leak then shows as growth, not as a terrain that keeps
//! getting more detailed.
//!
//! Checks:
//! - at every checkpoint (each 1,000 carves) the octree passes the kernel's
//!   checks ([`validate_octree`]) and the terrain's state hash, kept up to
//!   date per carve, equals one computed afresh;
//! - the live heap is flat after warm-up: a counting global allocator in
//!   this test binary measures the bytes allocated and not yet freed, and
//!   after the first [`WARM_UP`] carves each checkpoint stays within
//!   [`slack`] of the level at the end of warm-up, plus twice the heap the
//!   journal of carves has gained since (the journal keeps every carve not
//!   undone, by design, so it grows with the carve count);
//! - a reloaded terrain has the saved terrain's hash;
//! - at the end the state hash and the octree's bytes equal those of a
//!   fresh terrain that replays the final journal with
//!   [`Terrain::apply_now`].
//!
//! `CHISEL_SOAK_CARVES=N` sets the number of carves (default 10,000).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};
use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, Octree, OctreeConfig, StateHash};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveRejected, CarveTool, Terrain, TerrainBase, TerrainDebris,
    TerrainError, TerrainPlugin, UndoCarve,
};

/// Counts the bytes held by live allocations of this process.
struct Counting;

/// Bytes allocated and not yet freed.
static LIVE: AtomicIsize = AtomicIsize::new(0);

fn add(bytes: usize) {
    LIVE.fetch_add(bytes as isize, Ordering::Relaxed);
}

fn sub(bytes: usize) {
    LIVE.fetch_sub(bytes as isize, Ordering::Relaxed);
}

// SAFETY: every call is forwarded to the system allocator unchanged; the
// counter only observes sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract is the system allocator's.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            add(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            add(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as `alloc`.
        unsafe { System.dealloc(ptr, layout) };
        sub(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as `alloc`.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            add(new_size);
            sub(layout.size());
        }
        p
    }
}

#[global_allocator]
static HEAP: Counting = Counting;

fn live_bytes() -> isize {
    LIVE.load(Ordering::Relaxed)
}

/// Resident set size from `/proc/self/statm`, in bytes (0 where there is
/// no such file); reported, not checked (the allocator's count is exact,
/// the RSS depends on how the system allocator returns pages).
fn rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map_or(0, |pages| pages * 4096)
}

/// Carves before the heap is taken as warmed up: caches, message
/// buffers, asset storage and the undo history (64 steps) have reached
/// their working size by then.
const WARM_UP: usize = 2_000;
/// Carves between checkpoints.
const CHECK_EVERY: usize = 1_000;
/// Carves between saves (each followed by a load that replaces the
/// terrain entity).
const SAVE_EVERY: usize = 750;

/// How far the live heap may rise above its level at the end of warm-up,
/// besides the journal's growth: a quarter of that level or 4 MiB,
/// whichever is more (the terrain's own size varies with what the carves
/// left: more or fewer cells, meshes and BSP nodes).
fn slack(warm: isize) -> isize {
    (warm / 4).max(4 << 20)
}

/// SplitMix64: a seeded, reproducible sequence.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }

    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Craters in the palette.
const PALETTE: usize = 24;

/// A 24³ block of rock (label 1; grid unit = 1 world unit) in a 32³ cube;
/// sand (2) and ore (3) may be added and painted.
fn block() -> Terrain {
    let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 5,
        solid: CellBox {
            min: [0; 3],
            max: [24; 3],
        },
        label: 1,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 64,
        max_depth: 20,
    };
    Terrain::from_base(grid, base, config)
        .expect("valid block")
        .with_labels([2, 3])
}

/// What the app reported.
#[derive(Resource, Default)]
struct Seen {
    carves: usize,
    undos: usize,
    nothing_to_undo: usize,
    other_rejections: Vec<TerrainError>,
}

fn record(
    mut seen: ResMut<Seen>,
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
) {
    for a in applied.read() {
        match a.edit {
            Some(_) => seen.carves += 1,
            None => seen.undos += 1,
        }
    }
    for r in rejected.read() {
        match r.error {
            TerrainError::NothingToUndo => seen.nothing_to_undo += 1,
            ref e => seen.other_rejections.push(e.clone()),
        }
    }
}

fn terrain(app: &App, entity: Entity) -> &Terrain {
    app.world().get::<Terrain>(entity).expect("terrain entity")
}

/// Runs frames until every carve is applied and meshed.
fn settle(app: &mut App, entity: Entity) {
    for _ in 0..100_000 {
        app.update();
        if terrain(app, entity).is_idle() {
            // One more frame so that the recorder sees the last messages.
            app.update();
            return;
        }
        std::thread::sleep(Duration::from_micros(100));
    }
    panic!("terrain did not settle");
}

/// The kernel's checks on an octree: the leaves tile the cube, every
/// leaf's BSP is a tree with its indices in range, and the octree passes
/// the checks of the kernel's file reader (every plane within its bit
/// budget, every BSP well formed, the cells tiling the cube) and encodes
/// back to the same bytes.
fn validate_octree(octree: &Octree) {
    let volume = |b: &CellBox| -> u128 {
        (0..3)
            .map(|i| u128::try_from(b.max[i] - b.min[i]).expect("a box has min <= max"))
            .product()
    };
    let root = octree.root_box();
    let mut covered = 0u128;
    for (key, leaf) in octree.leaves() {
        let cell = octree.cell_box(key);
        assert!(
            (0..3).all(|i| root.min[i] <= cell.min[i] && cell.max[i] <= root.max[i]),
            "{key:?} outside the cube"
        );
        covered += volume(&cell);
        if let Err(e) = leaf.to_bsp().validate() {
            panic!("leaf {key:?}: {e:?}");
        }
    }
    assert_eq!(covered, volume(&root), "the leaves do not tile the cube");
    let bytes = octree.to_bytes();
    let back = Octree::from_bytes(&bytes).expect("the kernel's checks pass");
    assert!(back.to_bytes() == bytes, "the octree does not round-trip");
}

/// The heap held by a copy of `terrain`'s journal (what the journal costs
/// without spare capacity).
fn journal_bytes(terrain: &Terrain) -> isize {
    let before = live_bytes();
    let copy = terrain.journal().to_vec();
    let bytes = live_bytes() - before;
    drop(copy);
    bytes
}

fn carve_count() -> usize {
    std::env::var("CHISEL_SOAK_CARVES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000)
}

#[test]
fn ten_thousand_carves_with_undo_save_and_load() {
    let total = carve_count();
    let started = Instant::now();
    let file = std::env::temp_dir().join(format!(
        "bevy_chisel_soak_{}.chiselterrain",
        std::process::id()
    ));
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TerrainPlugin))
        .init_resource::<Seen>()
        .add_systems(
            Update,
            record.after(bevy_chisel::terrain::TerrainSystems::Mesh),
        );
    let mut entity = app.world_mut().spawn(block()).id();
    settle(&mut app, entity);

    let mut rng = Rng(0x005e_ed0f_50a6);
    // Craters around the block's top and sides, 2 to 5 units across.
    let palette: Vec<CarveTool> = (0..PALETTE)
        .map(|_| {
            let centre = Vec3::new(rng.unit(), 0.5 + 0.5 * rng.unit(), rng.unit()) * 26.0;
            CarveTool::dodecahedron(2.0 + 3.0 * rng.unit(), centre)
        })
        .collect();
    let (mut sent, mut undos_sent, mut loads) = (0usize, 0usize, 0usize);
    let mut next_check = CHECK_EVERY;
    let mut next_save = SAVE_EVERY;
    // (live heap, journal heap) at the end of warm-up.
    let mut warm: Option<(isize, isize)> = None;
    let mut peak_excess: Option<isize> = None;
    println!("carves   live heap     RSS  journal  leaves  cells  seconds");
    while sent < total {
        // One to four carves in one frame (they run as one batch), and now
        // and then one to three undos after them.
        let batch = (1 + rng.below(4) as usize).min(total - sent);
        for _ in 0..batch {
            let tool = palette[rng.below(PALETTE as u64) as usize].clone();
            let edit = match rng.below(20) {
                0..11 => Edit::Subtract,
                11..16 => Edit::Add(2),
                _ => Edit::Paint(3),
            };
            app.world_mut().write_message(Carve {
                terrain: entity,
                tool,
                edit,
            });
        }
        sent += batch;
        if rng.below(4) == 0 {
            for _ in 0..=rng.below(3) {
                app.world_mut().write_message(UndoCarve { terrain: entity });
                undos_sent += 1;
            }
        }
        settle(&mut app, entity);
        // A game clears away what fell off.
        let debris: Vec<Entity> = app
            .world_mut()
            .query_filtered::<Entity, With<TerrainDebris>>()
            .iter(app.world())
            .collect();
        for piece in debris {
            app.world_mut().despawn(piece);
        }

        if sent >= next_save {
            next_save += SAVE_EVERY;
            let saved = terrain(&app, entity);
            let hash = saved.state_hash();
            let bytes = saved.octree().to_bytes();
            saved.save(&file).expect("save");
            let loaded = Terrain::load(&file).expect("load");
            assert_eq!(loaded.state_hash(), hash, "reloaded hash");
            assert!(loaded.octree().to_bytes() == bytes, "reloaded octree");
            app.world_mut().despawn(entity);
            entity = app.world_mut().spawn(loaded).id();
            settle(&mut app, entity);
            loads += 1;
        }

        if sent >= next_check {
            next_check += CHECK_EVERY;
            let t = terrain(&app, entity);
            validate_octree(t.octree());
            assert_eq!(
                StateHash::of(t.octree()).value(),
                t.state_hash(),
                "the incremental state hash drifted after {sent} carves"
            );
            let (live, journal) = (live_bytes(), journal_bytes(t));
            println!(
                "{sent:>6} {:>8.2} MiB {:>5.0} MiB {:>5.0} KiB {:>7} {:>6} {:>8.1}",
                live as f64 / f64::from(1 << 20),
                rss_bytes() as f64 / f64::from(1 << 20),
                journal as f64 / 1024.0,
                t.octree().leaves().len(),
                t.cells().count(),
                started.elapsed().as_secs_f64(),
            );
            match warm {
                None if sent >= WARM_UP => warm = Some((live, journal)),
                None => {}
                Some((warm_live, warm_journal)) => {
                    let excess = live - warm_live - 2 * (journal - warm_journal).max(0);
                    peak_excess = Some(peak_excess.map_or(excess, |p| p.max(excess)));
                    assert!(
                        excess <= slack(warm_live),
                        "live heap {live} B after {sent} carves: {excess} B above the \
                         warm-up level {warm_live} B (journal growth taken out), more \
                         than {} B",
                        slack(warm_live)
                    );
                }
            }
        }
    }

    let seen = app.world().resource::<Seen>();
    assert!(
        seen.other_rejections.is_empty(),
        "{:?}",
        seen.other_rejections
    );
    assert_eq!(seen.carves, total, "every carve is applied");
    assert_eq!(seen.undos + seen.nothing_to_undo, undos_sent);
    let t = terrain(&app, entity);
    assert_eq!(t.journal().len(), seen.carves - seen.undos);
    assert!(seen.undos > total / 10, "undo is exercised: {}", seen.undos);
    validate_octree(t.octree());

    // The same journal, replayed in a fresh terrain, gives the same octree.
    let mut fresh = block().with_max_undo(0);
    for entry in t.journal() {
        fresh
            .apply_now(&entry.tool, entry.edit)
            .expect("a replayed carve");
    }
    assert_eq!(fresh.state_hash(), t.state_hash(), "replay hash");
    assert!(
        fresh.octree().to_bytes() == t.octree().to_bytes(),
        "the replayed octree differs"
    );
    let _ = std::fs::remove_file(&file);
    println!(
        "{} carves applied, {} undone ({} undos refused: nothing left), {loads} save/load \
         cycles, journal {} carves, {} leaves; live heap {:.2} MiB, peak excess over \
         warm-up {:.2} MiB (bound {:.2} MiB); {:.1} s",
        seen.carves,
        seen.undos,
        seen.nothing_to_undo,
        t.journal().len(),
        t.octree().leaves().len(),
        live_bytes() as f64 / f64::from(1 << 20),
        peak_excess.unwrap_or(0) as f64 / f64::from(1 << 20),
        warm.map_or(0, |(w, _)| slack(w)) as f64 / f64::from(1 << 20),
        started.elapsed().as_secs_f64(),
    );
}
