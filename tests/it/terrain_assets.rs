//! Terrain files and heightfields through Bevy's asset server: a
//! `TerrainSource` entity gets the file's terrain bit for bit, a changed
//! asset replaces it (the hot-reload path) with none of the old cells left,
//! a damaged file fails its load, and a heightfield loaded as an asset
//! equals the one read from the same image directly.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::time::Duration;

use bevy::asset::{AssetPlugin, LoadState};
use bevy::prelude::*;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    Heightfield, HeightfieldSettings, Terrain, TerrainAsset, TerrainCell, TerrainPlugin,
    TerrainSource,
};

fn grid() -> Quantization {
    Quantization::new(0.001, [0.0; 3]).expect("valid grid")
}

fn slab(height: f32) -> Terrain {
    Terrain::from_box(
        grid(),
        Vec3::new(-4.0, -height, -4.0),
        Vec3::new(4.0, 0.0, 4.0),
        1,
    )
    .expect("valid box")
}

/// A directory of its own for this test's asset files.
fn asset_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chisel-assets-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn app_in(dir: &std::path::Path) -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        AssetPlugin {
            file_path: dir.to_string_lossy().into_owned(),
            ..default()
        },
        TerrainPlugin,
    ))
    .init_asset::<StandardMaterial>();
    app
}

/// Runs frames until `done` holds (or fails after a generous limit).
fn run_until(app: &mut App, what: &str, mut done: impl FnMut(&mut App) -> bool) {
    for _ in 0..20_000 {
        app.update();
        if done(app) {
            return;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    panic!("timed out waiting for {what}");
}

fn cells_of(app: &mut App, terrain: Entity) -> BTreeSet<Entity> {
    let mut query = app.world_mut().query::<(Entity, &TerrainCell)>();
    query
        .iter(app.world())
        .filter(|(_, cell)| cell.terrain == terrain)
        .map(|(e, _)| e)
        .collect()
}

fn settled(app: &mut App, entity: Entity) -> bool {
    app.world()
        .get::<Terrain>(entity)
        .is_some_and(Terrain::is_idle)
}

#[test]
fn a_terrain_source_gets_the_file_and_follows_changes() {
    let dir = asset_dir("source");
    let original = slab(2.0);
    original
        .save(dir.join("level.chiselterrain"))
        .expect("write the file");
    let mut app = app_in(&dir);
    let handle: Handle<TerrainAsset> = app
        .world()
        .resource::<AssetServer>()
        .load("level.chiselterrain");
    let entity = app.world_mut().spawn(TerrainSource(handle.clone())).id();
    run_until(&mut app, "the terrain file", |app| settled(app, entity));
    app.update();
    let loaded = app.world().get::<Terrain>(entity).expect("terrain");
    assert_eq!(
        loaded.to_bytes(),
        original.to_bytes(),
        "bit-identical terrain"
    );
    let before = cells_of(&mut app, entity);
    assert!(!before.is_empty(), "the loaded terrain is meshed");

    // What a file watcher does on a change: the asset is replaced.
    let changed = slab(3.0);
    let expected = changed.to_bytes();
    app.world_mut()
        .resource_mut::<Assets<TerrainAsset>>()
        .insert(handle.id(), TerrainAsset::from(changed))
        .expect("replace the asset");
    run_until(&mut app, "the reloaded terrain", |app| {
        settled(app, entity)
            && app
                .world()
                .get::<Terrain>(entity)
                .is_some_and(|t| t.to_bytes() == expected)
    });
    app.update();
    let after = cells_of(&mut app, entity);
    assert!(!after.is_empty(), "the reloaded terrain is meshed");
    assert!(
        before.is_disjoint(&after),
        "the old cells are gone, the new ones are new entities"
    );
    for old in &before {
        assert!(
            app.world().get_entity(*old).is_err(),
            "old cell {old} despawned"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_damaged_terrain_file_fails_its_load() {
    let dir = asset_dir("damaged");
    let mut bytes = slab(2.0).to_bytes();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x40;
    std::fs::write(dir.join("bad.chiselterrain"), bytes).expect("write the file");
    let mut app = app_in(&dir);
    let handle: Handle<TerrainAsset> = app
        .world()
        .resource::<AssetServer>()
        .load("bad.chiselterrain");
    let entity = app.world_mut().spawn(TerrainSource(handle.clone())).id();
    run_until(&mut app, "the failed load", |app| {
        matches!(
            app.world()
                .resource::<AssetServer>()
                .get_load_state(&handle),
            Some(LoadState::Failed(_))
        )
    });
    app.update();
    assert!(
        app.world().get::<Terrain>(entity).is_none(),
        "no terrain from a damaged file"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_heightfield_asset_equals_the_image_read_directly() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets");
    let mut app = app_in(&root);
    let settings = HeightfieldSettings {
        spacing: 0.5,
        low: -1.0,
        high: 6.0,
        depth: 3.0,
        label: 2,
        ..default()
    };
    let given = settings.clone();
    let handle: Handle<Heightfield> = app
        .world()
        .resource::<AssetServer>()
        .load_builder()
        .with_settings(move |s: &mut HeightfieldSettings| *s = given.clone())
        .load("terrain/quarry_height.png");
    run_until(&mut app, "the heightfield", |app| {
        app.world()
            .resource::<Assets<Heightfield>>()
            .contains(&handle)
    });
    let direct = Heightfield::load_image(
        root.join("terrain/quarry_height.png"),
        settings.spacing,
        settings.low,
        settings.high,
        settings.depth,
        settings.label,
    )
    .expect("read the image");
    let asset = app
        .world()
        .resource::<Assets<Heightfield>>()
        .get(&handle)
        .expect("loaded")
        .clone();
    assert_eq!(asset, direct);
    assert!(asset.size.x > 1 && asset.size.y > 1);
}
