//! Streamed terrain worlds in an app without rendering (`MinimalPlugins`):
//! only chunks near the focus exist, with hysteresis; an edit survives its
//! chunk streaming out and back in bit-identically; a carve across a chunk
//! border removes exactly what one terrain over both chunks loses; saving
//! writes only the edited chunks, removes the files of chunks undone to
//! their base once every file is written, and loading is exact.

use std::collections::BTreeSet;
use std::path::PathBuf;

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::bsp::octree::{Edit, StateHash};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    CarveApplied, CarveRejected, CarveTool, ChunkCoord, GridHeightfield, HeightArray, Heightfield,
    NoiseOctave, StreamSettings, Terrain, TerrainBase, TerrainError, TerrainFocus, TerrainPlugin,
    TerrainWorld, ValueNoise, WorldCarve, WorldLayout, WorldSource, terrain_octree_config,
};

/// Grid unit = 1 world unit; chunks of 32, samples 4 apart (8 squares a
/// side); heights 8..=20 above the floor at 0.
pub(crate) fn layout() -> WorldLayout {
    WorldLayout {
        quantization: Quantization::new(1.0, [0.0; 3]).expect("valid unit"),
        chunk_log2: 5,
        spacing_log2: 2,
        floor: 0,
        label: 1,
        layers: Vec::new(),
    }
}

pub(crate) fn height(i: i64, j: i64) -> i64 {
    8 + (i * 7 + j * 13).rem_euclid(9) + (i * j).rem_euclid(5)
}

pub(crate) fn world() -> TerrainWorld {
    TerrainWorld::new(layout(), height)
        .expect("valid layout")
        .with_streaming(StreamSettings {
            load_radius: 40.0,
            unload_radius: 72.0,
            max_building: 4,
        })
        .expect("valid settings")
}

#[derive(Resource, Default)]
struct Applied(Vec<CarveApplied>);

#[derive(Resource, Default)]
struct Rejected(Vec<CarveRejected>);

fn record(
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    mut seen: ResMut<Applied>,
    mut refused: ResMut<Rejected>,
) {
    seen.0.extend(applied.read().cloned());
    refused.0.extend(rejected.read().cloned());
}

pub(crate) fn app_with(world: TerrainWorld, focus: Vec3) -> (App, Entity, Entity) {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        TerrainPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .init_resource::<Applied>()
    .init_resource::<Rejected>()
    .add_systems(
        Update,
        record.after(bevy_chisel::terrain::TerrainSystems::Mesh),
    );
    let world = app.world_mut().spawn(world).id();
    let focus = app
        .world_mut()
        .spawn((TerrainFocus, Transform::from_translation(focus)))
        .id();
    settle(&mut app, world);
    (app, world, focus)
}

pub(crate) fn the_world(app: &App, world: Entity) -> &TerrainWorld {
    app.world()
        .get::<TerrainWorld>(world)
        .expect("world entity")
}

pub(crate) fn terrain(app: &App, world: Entity, coord: ChunkCoord) -> &Terrain {
    let entity = the_world(app, world)
        .chunk_entity(coord)
        .unwrap_or_else(|| panic!("chunk {coord:?} is not live"));
    app.world().get::<Terrain>(entity).expect("chunk terrain")
}

/// Runs frames until nothing builds, no carve waits, every live chunk is
/// idle and the set of live chunks stayed the same for a few frames.
pub(crate) fn settle(app: &mut App, world: Entity) {
    let mut calm = 0;
    let mut last = Vec::new();
    for _ in 0..20_000 {
        app.update();
        let w = the_world(app, world);
        let live: Vec<_> = w.live_chunks().collect();
        let idle = w.is_settled()
            && live
                .iter()
                .all(|&(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle));
        calm = if idle && live == last { calm + 1 } else { 0 };
        last = live;
        if calm == 5 {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    panic!("the world did not settle");
}

fn move_focus(app: &mut App, world: Entity, focus: Entity, to: Vec3) {
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = to;
    settle(app, world);
}

fn live(app: &App, world: Entity) -> BTreeSet<ChunkCoord> {
    the_world(app, world)
        .live_chunks()
        .map(|(c, _)| c)
        .collect()
}

fn square(
    xs: std::ops::RangeInclusive<i64>,
    zs: std::ops::RangeInclusive<i64>,
) -> BTreeSet<ChunkCoord> {
    xs.flat_map(|x| zs.clone().map(move |z| ChunkCoord { x, z }))
        .collect()
}

/// The exact volume under the world's surface over chunk `coord`: every
/// triangle's prism, area × mean height (in sixths, as integers).
fn prism_volume(coord: ChunkCoord) -> f64 {
    let (n, s) = (8i64, 4i64);
    let mut sixths = 0i128;
    for j in coord.z * n..(coord.z + 1) * n {
        for i in coord.x * n..(coord.x + 1) * n {
            let (h00, h10) = (height(i, j), height(i + 1, j));
            let (h01, h11) = (height(i, j + 1), height(i + 1, j + 1));
            // Each triangle: (s²/2) · (sum of heights / 3).
            sixths += i128::from(s * s) * i128::from(h00 + h01 + h10 + h10 + h01 + h11);
        }
    }
    sixths as f64 / 6.0
}

pub(crate) fn dodecahedron(radius: f32, centre: Vec3) -> CarveTool {
    CarveTool::dodecahedron(radius, centre)
}

pub(crate) fn carve(app: &mut App, world: Entity, tool: CarveTool) {
    app.world_mut().write_message(WorldCarve {
        world,
        tool,
        edit: Edit::Subtract,
    });
}

/// Chunk `coord` as generated, with `tools` applied synchronously: the
/// reference of what the app's chunk must hold.
pub(crate) fn reference(world: &TerrainWorld, coord: ChunkCoord, tools: &[CarveTool]) -> Terrain {
    let mut terrain = world.generate_chunk(coord).expect("chunk builds");
    for tool in tools {
        let grid = tool.to_grid(&layout().quantization).expect("tool on grid");
        terrain
            .apply_now(&grid, Edit::Subtract)
            .expect("carve applies");
    }
    terrain
}

#[test]
fn only_chunks_within_the_radius_exist_with_hysteresis() {
    let (mut app, world, focus) = app_with(world(), Vec3::new(16.0, 30.0, 16.0));
    // Squares within 40 of (16, 16): x and z in -1..=1 (the next ones are
    // 48 away).
    assert_eq!(live(&app, world), square(-1..=1, -1..=1));
    let stats = the_world(&app, world).stats().clone();
    assert_eq!((stats.live, stats.building, stats.stored), (9, 0, 0));
    assert_eq!(stats.generated, 9);
    // Every chunk is the exact solid under the source's surface.
    for (coord, entity) in the_world(&app, world).live_chunks() {
        let t = app.world().get::<Terrain>(entity).expect("terrain");
        let (got, want) = (t.octree().solid_volume(), prism_volume(coord));
        assert!(
            (got - want).abs() <= 1e-9 * want,
            "{coord:?}: {got} != {want}"
        );
        assert!(t.cells().count() > 0, "{coord:?} has no cells shown");
    }

    // 20 to the right: column 2 comes within 40 (28 away), column -1 is
    // 36 away and stays.
    move_focus(&mut app, world, focus, Vec3::new(36.0, 30.0, 16.0));
    assert_eq!(live(&app, world), square(-1..=2, -1..=1));

    // 64 further: column -1 is 100 away (beyond 72) and goes; column 0 is
    // 68 away, beyond the load radius but within the unload radius, and
    // stays; columns 3 and 4 come in (0 and 28 away), 5 does not (60).
    let before = the_world(&app, world).chunk_entity(ChunkCoord { x: -1, z: 0 });
    let kept = the_world(&app, world).chunk_entity(ChunkCoord { x: 0, z: 0 });
    move_focus(&mut app, world, focus, Vec3::new(100.0, 30.0, 16.0));
    assert_eq!(live(&app, world), square(0..=4, -1..=1));
    assert!(app.world().get_entity(before.expect("was live")).is_err());
    assert_eq!(
        the_world(&app, world).chunk_entity(ChunkCoord { x: 0, z: 0 }),
        kept,
        "a chunk between the radii is kept as it was"
    );
    let stats = the_world(&app, world).stats();
    assert_eq!(stats.released, 3);
    assert_eq!(stats.stored, 0, "unedited chunks are never stored");

    // Back to the start: column 0 is wanted again, -1 is regenerated.
    move_focus(&mut app, world, focus, Vec3::new(16.0, 30.0, 16.0));
    assert_eq!(live(&app, world), square(-1..=2, -1..=1));
}

#[test]
fn an_edit_far_from_the_focus_survives_streaming_out_and_in() {
    let (mut app, world, focus) = app_with(world(), Vec3::new(16.0, 30.0, 16.0));
    // Chunk (6, 0) is 176 away: the carve builds it, applies, and it
    // streams out again, its state kept.
    let far = ChunkCoord { x: 6, z: 0 };
    let tool = dodecahedron(5.0, Vec3::new(6.0 * 32.0 + 12.0, 14.0, 16.0));
    carve(&mut app, world, tool.clone());
    settle(&mut app, world);
    let w = the_world(&app, world);
    assert_eq!(w.stored_chunks().collect::<Vec<_>>(), vec![far]);
    assert!(w.chunk_entity(far).is_none());
    assert_eq!(app.world().resource::<Applied>().0.len(), 1);
    let want = reference(w, far, std::slice::from_ref(&tool));
    let unedited = w.generate_chunk(far).expect("chunk builds");
    assert_ne!(want.state_hash(), unedited.state_hash());

    // Stream it in: restored bit-identically, journal and undo included.
    for round in 0..2 {
        move_focus(
            &mut app,
            world,
            focus,
            Vec3::new(6.0 * 32.0 + 16.0, 30.0, 16.0),
        );
        let got = terrain(&app, world, far);
        assert_eq!(got.state_hash(), want.state_hash(), "round {round}");
        assert_eq!(
            StateHash::of(got.octree()).value(),
            want.state_hash(),
            "round {round}: the octree itself"
        );
        assert_eq!(got.journal(), want.journal());
        assert_eq!(got.undo_depth(), 1);
        assert!(the_world(&app, world).stored_chunks().next().is_none());
        // An unedited neighbour is rebuilt from the source, not stored.
        let next = ChunkCoord { x: 7, z: 0 };
        assert_eq!(
            terrain(&app, world, next).state_hash(),
            w_generate(&app, world, next)
        );
        move_focus(&mut app, world, focus, Vec3::new(16.0, 30.0, 16.0));
        assert_eq!(
            the_world(&app, world).stored_chunks().collect::<Vec<_>>(),
            vec![far]
        );
    }
    assert!(the_world(&app, world).stats().restored >= 2);
}

/// A chunk whose restore finishes in the frame it is no longer wanted is
/// released no earlier than the next frame, stored again: its terrain is
/// spawned by that frame's commands and cannot be read before, and the
/// release took it for an unedited chunk and lost its edits.
#[test]
fn an_edited_chunk_restored_as_its_focus_leaves_keeps_its_edits() {
    let home = Vec3::new(16.0, 30.0, 16.0);
    let (mut app, world, focus) = app_with(world(), home);
    let far = ChunkCoord { x: 6, z: 0 };
    let tool = dodecahedron(5.0, Vec3::new(6.0 * 32.0 + 12.0, 14.0, 16.0));
    carve(&mut app, world, tool.clone());
    settle(&mut app, world);
    let want = reference(the_world(&app, world), far, std::slice::from_ref(&tool));
    assert_eq!(
        the_world(&app, world).stored_chunks().collect::<Vec<_>>(),
        vec![far]
    );
    // The focus goes to the chunk for one frame: its restore starts (the
    // nearest wanted chunk first).
    let place = |app: &mut App, at: Vec3| {
        let mut entity = app.world_mut().entity_mut(focus);
        *entity.get_mut::<Transform>().expect("focus") = Transform::from_translation(at);
        *entity.get_mut::<GlobalTransform>().expect("focus") =
            GlobalTransform::from_translation(at);
    };
    place(&mut app, Vec3::new(6.0 * 32.0 + 16.0, 30.0, 16.0));
    app.update();
    assert!(the_world(&app, world).stats().building > 0, "restoring");
    // It leaves before the restore is collected, which then happens in
    // the frame the chunk is beyond the unload radius.
    place(&mut app, home);
    std::thread::sleep(std::time::Duration::from_millis(500));
    app.update();
    settle(&mut app, world);
    let w = the_world(&app, world);
    assert!(w.chunk_entity(far).is_none());
    assert_eq!(
        w.stored_chunks().collect::<Vec<_>>(),
        vec![far],
        "the chunk's edits are kept"
    );
    move_focus(
        &mut app,
        world,
        focus,
        Vec3::new(6.0 * 32.0 + 16.0, 30.0, 16.0),
    );
    assert_eq!(terrain(&app, world, far).state_hash(), want.state_hash());
    assert_eq!(terrain(&app, world, far).journal(), want.journal());
}

fn w_generate(app: &App, world: Entity, coord: ChunkCoord) -> u64 {
    the_world(app, world)
        .generate_chunk(coord)
        .expect("chunk builds")
        .state_hash()
}

#[test]
fn a_carve_across_a_chunk_border_edits_both_and_the_volumes_add_up() {
    let (mut app, world, _) = app_with(world(), Vec3::new(32.0, 30.0, 16.0));
    let (left, right) = (ChunkCoord { x: 0, z: 0 }, ChunkCoord { x: 1, z: 0 });
    let volume = |app: &App, c| terrain(app, world, c).octree().solid_volume();
    let before = [volume(&app, left), volume(&app, right)];
    let tool = dodecahedron(6.0, Vec3::new(32.0, 13.0, 16.0));
    carve(&mut app, world, tool.clone());
    settle(&mut app, world);
    let after = [volume(&app, left), volume(&app, right)];
    let removed = [before[0] - after[0], before[1] - after[1]];
    assert!(
        removed.iter().all(|&r| r > 1.0),
        "both chunks lose: {removed:?}"
    );
    for c in [left, right] {
        assert_eq!(terrain(&app, world, c).journal().len(), 1);
        let want = reference(the_world(&app, world), c, std::slice::from_ref(&tool));
        assert_eq!(terrain(&app, world, c).state_hash(), want.state_hash());
    }
    assert_eq!(app.world().resource::<Applied>().0.len(), 2);

    // The drawn surfaces meet on the shared side x = 32, edge to edge:
    // every vertex of one chunk's border edges is a vertex of the other's.
    let (t_left, t_right) =
        super::terrain_world_seams::seam_t_junctions(&app, world, left, right, 0, 32.0);
    assert_eq!((t_left, t_right), (0, 0), "T-junctions across x = 32");

    super::terrain_world_seams::assert_closed_across(&app, world);

    // One terrain over both chunks, built from the same samples.
    let mut heights = Vec::new();
    for j in 0..=8 {
        for i in 0..=16 {
            heights.push(height(i, j));
        }
    }
    let base = TerrainBase::Heightfield {
        origin: [0; 3],
        size_log2: 6,
        field: GridHeightfield {
            corner: [0; 3],
            samples: [17, 9],
            spacing: 4,
            heights,
            bottom: 0,
            label: 1,
            layers: Vec::new(),
        },
    };
    let mut whole = Terrain::from_base(layout().quantization, base, terrain_octree_config())
        .expect("whole builds")
        .with_debris(None);
    let whole_before = whole.octree().solid_volume();
    let sum_before = before[0] + before[1];
    assert!((whole_before - sum_before).abs() <= 1e-9 * whole_before);
    let grid = tool.to_grid(&layout().quantization).expect("tool on grid");
    whole
        .apply_now(&grid, Edit::Subtract)
        .expect("carve applies");
    let whole_removed = whole_before - whole.octree().solid_volume();
    let sum = removed[0] + removed[1];
    assert!(
        (whole_removed - sum).abs() <= 1e-9 * whole_removed,
        "one terrain loses {whole_removed}, the chunks {sum}"
    );
}

fn temp_folder(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bevy_chisel-world-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn saving_writes_only_edited_chunks_and_loading_is_exact() {
    let (mut app, world, focus) = app_with(world(), Vec3::new(16.0, 30.0, 16.0));
    let near = ChunkCoord { x: 0, z: 0 };
    let far = ChunkCoord { x: -5, z: 3 };
    carve(
        &mut app,
        world,
        dodecahedron(4.0, Vec3::new(10.0, 14.0, 20.0)),
    );
    carve(
        &mut app,
        world,
        dodecahedron(4.0, Vec3::new(-5.0 * 32.0 + 16.0, 15.0, 3.0 * 32.0 + 16.0)),
    );
    settle(&mut app, world);
    let w = the_world(&app, world);
    assert_eq!(w.stored_chunks().collect::<Vec<_>>(), vec![far]);
    let dir = temp_folder("save");
    let written = w
        .save(&dir, |e| app.world().get::<Terrain>(e))
        .expect("saves");
    assert_eq!(written, vec![far, near]);
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        vec!["chunk_-5_3.chiselterrain", "chunk_0_0.chiselterrain"]
    );
    let near_hash = terrain(&app, world, near).state_hash();
    let far_bytes = std::fs::read(dir.join("chunk_-5_3.chiselterrain")).expect("file");
    let far_hash = Terrain::from_bytes(&far_bytes).expect("loads").state_hash();

    // A new app with the loaded world: the edited chunks come back exact.
    let loaded = world_loaded(&dir);
    let (mut app2, world2, focus2) = app_with(loaded, Vec3::new(16.0, 30.0, 16.0));
    assert_eq!(terrain(&app2, world2, near).state_hash(), near_hash);
    assert_eq!(terrain(&app2, world2, near).journal().len(), 1);
    move_focus(
        &mut app2,
        world2,
        focus2,
        Vec3::new(-5.0 * 32.0 + 16.0, 30.0, 3.0 * 32.0 + 16.0),
    );
    assert_eq!(terrain(&app2, world2, far).state_hash(), far_hash);
    move_focus(
        &mut app,
        world,
        focus,
        Vec3::new(-5.0 * 32.0 + 16.0, 30.0, 3.0 * 32.0 + 16.0),
    );
    assert_eq!(terrain(&app, world, far).state_hash(), far_hash);

    // A chunk file of another world is refused.
    let other = TerrainWorld::new(layout(), |i: i64, j: i64| height(i, j) + 1).expect("valid");
    assert!(other.load_edits(&dir).is_err());
    // A damaged chunk file is refused by name; the world is not loaded.
    let damaged = dir.join(&chunk_files(&dir)[0]);
    std::fs::write(&damaged, b"not a terrain").expect("writes");
    let error = self::world().load_edits(&dir).err().expect("refused");
    assert!(
        matches!(
            error.in_file(),
            TerrainError::BadMagic | TerrainError::Truncated { .. }
        ),
        "{error:?}"
    );
    assert!(
        error.to_string().contains(&*damaged.to_string_lossy()),
        "{error}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The chunk files in `dir`, sorted.
pub(crate) fn chunk_files(dir: &std::path::Path) -> Vec<String> {
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with("chunk_"))
        .collect();
    files.sort();
    files
}

#[test]
fn saving_removes_the_files_of_chunks_undone_to_the_base() {
    let (mut app, world, _focus) = app_with(world(), Vec3::new(16.0, 30.0, 16.0));
    let near = ChunkCoord { x: 0, z: 0 };
    let far = ChunkCoord { x: -5, z: 3 };
    carve(
        &mut app,
        world,
        dodecahedron(4.0, Vec3::new(10.0, 14.0, 20.0)),
    );
    carve(
        &mut app,
        world,
        dodecahedron(4.0, Vec3::new(-5.0 * 32.0 + 16.0, 15.0, 3.0 * 32.0 + 16.0)),
    );
    settle(&mut app, world);
    let dir = temp_folder("stale");
    let save = |app: &App| the_world(app, world).save(&dir, |e| app.world().get::<Terrain>(e));
    assert_eq!(save(&app).expect("saves"), vec![far, near]);
    std::fs::write(dir.join("notes.txt"), b"not a chunk").expect("writes");
    let far_file = std::fs::read(dir.join("chunk_-5_3.chiselterrain")).expect("far file");

    // Undo the near chunk back to its base, and edit a third chunk.
    let entity = the_world(&app, world).chunk_entity(near).expect("live");
    app.world_mut()
        .get_mut::<Terrain>(entity)
        .expect("terrain")
        .undo_now()
        .expect("one carve to undo");
    let third = ChunkCoord { x: 4, z: -2 };
    carve(
        &mut app,
        world,
        dodecahedron(4.0, Vec3::new(4.0 * 32.0 + 16.0, 15.0, -2.0 * 32.0 + 16.0)),
    );
    settle(&mut app, world);

    // A save that fails to write the third chunk's file removes nothing:
    // the folder still holds the complete earlier save.
    let blocked = dir.join("chunk_4_-2.chiselterrain");
    std::fs::create_dir(&blocked).expect("blocks the file");
    assert!(matches!(save(&app), Err(TerrainError::Io { .. })));
    assert_eq!(
        chunk_files(&dir),
        vec![
            "chunk_-5_3.chiselterrain",
            "chunk_0_0.chiselterrain",
            "chunk_4_-2.chiselterrain"
        ]
    );
    std::fs::remove_dir(&blocked).expect("unblocks");

    // The save that completes removes the undone chunk's file, keeps the
    // others and any file that is not a chunk file.
    assert_eq!(save(&app).expect("saves"), vec![far, third]);
    assert_eq!(
        chunk_files(&dir),
        vec!["chunk_-5_3.chiselterrain", "chunk_4_-2.chiselterrain"]
    );
    assert!(dir.join("notes.txt").exists());
    assert_eq!(
        std::fs::read(dir.join("chunk_-5_3.chiselterrain")).expect("far file"),
        far_file
    );

    // Loaded, the undone chunk is its base again and the others are exact.
    let (app2, world2, _) = app_with(world_loaded(&dir), Vec3::new(16.0, 30.0, 16.0));
    assert!(terrain(&app2, world2, near).journal().is_empty());
    assert_eq!(
        terrain(&app2, world2, near).state_hash(),
        the_world(&app2, world2)
            .generate_chunk(near)
            .expect("generates")
            .state_hash()
    );
    let mut stored: Vec<ChunkCoord> = the_world(&app2, world2).stored_chunks().collect();
    stored.sort();
    assert_eq!(stored, vec![far, third]);
    let _ = std::fs::remove_dir_all(&dir);
}

fn world_loaded(dir: &std::path::Path) -> TerrainWorld {
    world().load_edits(dir).expect("loads")
}

#[test]
fn a_height_array_and_value_noise_give_exact_chunks_that_meet() {
    // The test surface sampled into a world-unit heightfield over chunks
    // (0, 0) and (1, 0) gives the same chunks as the function.
    let (nx, nz) = (17u32, 9u32);
    let heights: Vec<f32> = (0..nz)
        .flat_map(|j| (0..nx).map(move |i| height(i64::from(i), i64::from(j)) as f32))
        .collect();
    let field = Heightfield {
        size: UVec2::new(nx, nz),
        heights,
        spacing: 4.0,
        corner: Vec3::ZERO,
        bottom: 0.0,
        label: 1,
        layers: Vec::new(),
    };
    let array = HeightArray::from_heightfield(&field, &layout()).expect("on the lattice");
    let from_array = TerrainWorld::new(layout(), array.clone()).expect("valid");
    for coord in [ChunkCoord { x: 0, z: 0 }, ChunkCoord { x: 1, z: 0 }] {
        let (a, f) = (
            from_array.generate_chunk(coord).expect("builds"),
            world().generate_chunk(coord).expect("builds"),
        );
        assert_eq!(a.base(), f.base());
        assert_eq!(a.state_hash(), f.state_hash());
    }
    // Beyond the array the edge samples repeat.
    assert_eq!(array.height(20, 3), height(16, 3));
    assert_eq!(array.height(-4, -2), height(0, 0));
    // A heightfield off the lattice, or with another spacing, is refused.
    for (corner, spacing) in [(Vec3::new(1.0, 0.0, 0.0), 4.0), (Vec3::ZERO, 2.0)] {
        let off = Heightfield {
            corner,
            spacing,
            ..field.clone()
        };
        assert!(matches!(
            HeightArray::from_heightfield(&off, &layout()),
            Err(TerrainError::InvalidHeightfield { .. })
        ));
    }

    // Value noise stays in its range, and neighbouring chunks read the
    // same heights on their shared side.
    let noise = noisy_source();
    let (low, high) = noise.range();
    assert_eq!((low, high), (3, 3 + 19 + 5));
    let mut seen = BTreeSet::new();
    for j in -20..20 {
        for i in -20..20 {
            let h = noise.height(i, j);
            assert!((low..=high).contains(&h), "{h} at ({i}, {j})");
            assert_eq!(h, noise.height(i, j));
            seen.insert(h);
        }
    }
    assert!(seen.len() > 10, "the noise varies: {seen:?}");
    let noisy = TerrainWorld::new(layout(), noise).expect("valid");
    let column =
        |coord: ChunkCoord, i: usize| match noisy.layout().chunk_base(&noisy_source(), coord) {
            Ok(TerrainBase::Heightfield { field, .. }) => {
                (0..9).map(|j| field.heights[i + 9 * j]).collect::<Vec<_>>()
            }
            other => panic!("{other:?}"),
        };
    assert_eq!(
        column(ChunkCoord { x: -1, z: 2 }, 8),
        column(ChunkCoord { x: 0, z: 2 }, 0)
    );
    let (a, b) = (
        noisy
            .generate_chunk(ChunkCoord { x: -1, z: 2 })
            .expect("builds"),
        noisy
            .generate_chunk(ChunkCoord { x: 0, z: 2 })
            .expect("builds"),
    );
    assert!(a.octree().solid_volume() > 0.0 && b.octree().solid_volume() > 0.0);
}

fn noisy_source() -> ValueNoise {
    ValueNoise {
        base: 3,
        octaves: vec![
            NoiseOctave {
                cell: 5,
                amplitude: 20,
                seed: 7,
            },
            NoiseOctave {
                cell: 2,
                amplitude: 6,
                seed: 8,
            },
        ],
    }
}

#[test]
fn bad_worlds_and_carves_are_typed_errors_that_change_nothing() {
    let bad = WorldLayout {
        spacing_log2: 5,
        ..layout()
    };
    assert!(matches!(
        TerrainWorld::new(bad, height),
        Err(TerrainError::InvalidWorld { .. })
    ));
    let settings = StreamSettings {
        load_radius: 50.0,
        unload_radius: 40.0,
        max_building: 1,
    };
    assert!(matches!(
        world().with_streaming(settings),
        Err(TerrainError::InvalidWorld { .. })
    ));
    // A source above the chunk's top: the chunk fails to build, typed.
    let too_high = TerrainWorld::new(layout(), |_: i64, _: i64| 33)
        .expect("valid")
        .with_streaming(world().streaming().clone())
        .expect("valid settings");
    assert!(matches!(
        too_high.generate_chunk(ChunkCoord { x: 0, z: 0 }),
        Err(TerrainError::InvalidWorld { .. })
    ));

    let (mut app, world, _) = app_with(world(), Vec3::new(16.0, 30.0, 16.0));
    let hashes = |app: &App| {
        the_world(app, world)
            .live_chunks()
            .map(|(_, e)| app.world().get::<Terrain>(e).expect("terrain").state_hash())
            .collect::<Vec<_>>()
    };
    let before = hashes(&app);
    // Above every chunk's cube, and a material the world does not know.
    carve(
        &mut app,
        world,
        dodecahedron(3.0, Vec3::new(16.0, 40.0, 16.0)),
    );
    app.world_mut().write_message(WorldCarve {
        world,
        tool: dodecahedron(3.0, Vec3::new(16.0, 14.0, 16.0)),
        edit: Edit::Add(9),
    });
    settle(&mut app, world);
    let rejected = &app.world().resource::<Rejected>().0;
    assert_eq!(rejected.len(), 2);
    assert!(rejected.iter().all(|r| r.terrain == world));
    assert!(matches!(
        rejected[0].error,
        TerrainError::OutsideTerrain { .. }
    ));
    assert!(matches!(
        rejected[1].error,
        TerrainError::UnknownLabel { label: 9, .. }
    ));
    assert_eq!(hashes(&app), before);
    assert!(app.world().resource::<Applied>().0.is_empty());

    // Chunks whose build fails are counted, not retried, and not live.
    let (app, world, _) = app_with(too_high, Vec3::new(16.0, 30.0, 16.0));
    let stats = the_world(&app, world).stats();
    assert_eq!((stats.live, stats.failed), (0, 9));
}
