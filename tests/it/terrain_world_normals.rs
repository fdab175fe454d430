//! Smooth normals across the chunk borders of a streamed world: on gentle
//! waves cut into the four chunks around one corner line, every vertex
//! that the meshes of two or more chunks share gets the same normal bits
//! in each, after the first build and after carves across a border and on
//! the corner line; with `TerrainSettings::smooth_across_cells` off (each
//! chunk smoothed over its own faces) they differ, which shows that the
//! check can fail. After the chunks stream out and back in (rebuilt from
//! scratch from their stored octrees), the normals at those vertices are
//! the same bits as after the incremental updates.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use bevy::asset::AssetPlugin;
use bevy::mesh::VertexAttributeValues;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    CarveTool, ChunkCoord, StreamSettings, TerrainFocus, TerrainPlugin, TerrainSettings,
    TerrainWorld, WorldLayout,
};

use super::terrain_world::{carve, settle, the_world};

/// Per chunk, per position (bits), the normals (bits) of its render
/// vertices there.
type Normals = BTreeMap<ChunkCoord, HashMap<[u32; 3], BTreeSet<[u32; 3]>>>;

/// Quarter-unit grid; chunks of 32 world units (128 grid units), samples
/// 4 apart (8 squares a side).
fn layout() -> WorldLayout {
    WorldLayout {
        quantization: Quantization::new(0.25, [0.0; 3]).expect("valid unit"),
        chunk_log2: 7,
        spacing_log2: 4,
        floor: 0,
        label: 1,
        layers: Vec::new(),
    }
}

/// Gentle waves (slopes under 15°), in grid units.
fn waves(i: i64, j: i64) -> i64 {
    let (i, j) = (i as f64, j as f64);
    64 + (10.0 * (0.4 * i).sin() * (0.3 * j + 0.5).cos()).round() as i64
}

/// An app with the waves streamed around the corner line x = z = 32 (the
/// chunks x, z in 0..=1), `smooth_across_cells` as given.
fn app(smooth_across_cells: bool) -> (App, Entity, Entity) {
    let world = TerrainWorld::new(layout(), waves)
        .expect("valid layout")
        .with_streaming(StreamSettings {
            load_radius: 20.0,
            unload_radius: 30.0,
            max_building: 4,
        })
        .expect("valid settings");
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        TerrainPlugin,
    ))
    .init_asset::<Mesh>()
    .init_asset::<StandardMaterial>()
    .insert_resource(TerrainSettings {
        smooth_across_cells,
        ..TerrainSettings::default()
    });
    let world = app.world_mut().spawn(world).id();
    let focus = app
        .world_mut()
        .spawn((TerrainFocus, Transform::from_xyz(32.0, 20.0, 32.0)))
        .id();
    settle(&mut app, world);
    let live: Vec<ChunkCoord> = the_world(&app, world)
        .live_chunks()
        .map(|(c, _)| c)
        .collect();
    assert_eq!(live.len(), 4, "the four chunks around the corner: {live:?}");
    (app, world, focus)
}

/// The normals of every live chunk's cell meshes, by position.
fn normals(app: &App, world: Entity) -> Normals {
    let meshes = app.world().resource::<Assets<Mesh>>();
    let mut out = Normals::new();
    for (coord, entity) in the_world(app, world).live_chunks() {
        let terrain = app
            .world()
            .get::<bevy_chisel::terrain::Terrain>(entity)
            .expect("chunk terrain");
        let at = out.entry(coord).or_default();
        for (_, entities) in terrain.cells() {
            for e in entities {
                let Some(handle) = app.world().get::<Mesh3d>(e) else {
                    continue;
                };
                let mesh = meshes.get(&handle.0).expect("cell mesh");
                let attribute = |name| match mesh.try_attribute_option(name) {
                    Ok(Some(VertexAttributeValues::Float32x3(values))) => values.clone(),
                    _ => panic!("cell meshes have Float32x3 positions and normals"),
                };
                let positions = attribute(Mesh::ATTRIBUTE_POSITION);
                for (p, n) in positions.iter().zip(attribute(Mesh::ATTRIBUTE_NORMAL)) {
                    at.entry(p.map(f32::to_bits))
                        .or_default()
                        .insert(n.map(f32::to_bits));
                }
            }
        }
    }
    out
}

/// The positions held by the meshes of two or more chunks.
fn shared(normals: &Normals) -> HashMap<[u32; 3], Vec<ChunkCoord>> {
    let mut chunks: HashMap<[u32; 3], Vec<ChunkCoord>> = HashMap::new();
    for (coord, at) in normals {
        for p in at.keys() {
            chunks.entry(*p).or_default().push(*coord);
        }
    }
    chunks.retain(|_, list| list.len() > 1);
    chunks
}

/// At the positions shared by chunks that each have one normal there
/// besides those of their side walls (a smooth spot; a side wall's
/// normal is the axis across it, as its faces meet the others at more
/// than the smoothing angle): how many were compared, how many disagree,
/// and the largest angle between two chunks' normals (degrees).
fn border_agreement(normals: &Normals) -> (usize, usize, f32) {
    let wall = |n: &[u32; 3]| {
        let n = n.map(f32::from_bits);
        n[0].abs() == 1.0 || n[2].abs() == 1.0
    };
    let (mut compared, mut disagree, mut worst) = (0, 0, 0.0f32);
    for (p, chunks) in shared(normals) {
        let smooth: Vec<Vec<&[u32; 3]>> = chunks
            .iter()
            .map(|c| normals[c][&p].iter().filter(|n| !wall(n)).collect())
            .collect();
        if smooth.iter().any(|n| n.len() != 1) {
            continue;
        }
        compared += 1;
        let first = smooth[0][0];
        if smooth.iter().any(|n| n[0] != first) {
            disagree += 1;
            let a = Vec3::from_array(first.map(f32::from_bits));
            for n in &smooth {
                let b = Vec3::from_array(n[0].map(f32::from_bits));
                worst = worst.max(a.angle_between(b).to_degrees());
            }
        }
    }
    (compared, disagree, worst)
}

/// Asserts that at every position shared by chunks in `scratch`, each
/// chunk's normals there in `kept` equal those in `scratch` (positions a
/// chunk has in only one of them are skipped); how many were compared.
fn agrees_with_scratch(kept: &Normals, scratch: &Normals) -> usize {
    let mut compared = 0;
    for (p, chunks) in shared(scratch) {
        for c in chunks {
            let Some(mine) = kept.get(&c).and_then(|at| at.get(&p)) else {
                continue;
            };
            compared += 1;
            assert_eq!(
                mine,
                &scratch[&c][&p],
                "chunk {c:?} at {:?}: normals differ from a build from scratch",
                p.map(f32::from_bits)
            );
        }
    }
    compared
}

/// Craters across the border x = 32 and over the corner line, their
/// centres off both (a crater centred on a side has edges in it, where
/// the chunks' faces meet at more than the smoothing angle and rightly
/// get different normals).
const CRATERS: [(f32, Vec3); 2] = [
    (2.5, Vec3::new(32.3, 16.5, 12.4)),
    (3.0, Vec3::new(32.4, 16.0, 31.7)),
];

#[test]
fn chunk_border_normals_agree_after_carves_and_match_a_rebuild() {
    let (mut app, world, focus) = app(true);
    let (compared, disagree, worst) = border_agreement(&normals(&app, world));
    eprintln!("first build: {compared} shared smooth vertices, {disagree} disagree");
    assert!(compared > 12, "only {compared} shared smooth vertices");
    assert_eq!(
        disagree, 0,
        "normals differ across borders by up to {worst}°"
    );

    for (radius, centre) in CRATERS {
        carve(&mut app, world, CarveTool::dodecahedron(radius, centre));
        settle(&mut app, world);
        let (compared, disagree, worst) = border_agreement(&normals(&app, world));
        eprintln!("crater at {centre}: {compared} shared smooth vertices, {disagree} disagree");
        assert!(compared > 12, "only {compared} shared smooth vertices");
        assert_eq!(
            disagree, 0,
            "after a crater at {centre}, normals differ across borders by up to {worst}°"
        );
    }
    let kept = normals(&app, world);

    // Away and back: every chunk streams out and is rebuilt from scratch
    // (the carved ones from their stored octrees).
    for x in [1000.0, 32.0] {
        app.world_mut()
            .get_mut::<Transform>(focus)
            .expect("focus")
            .translation
            .x = x;
        settle(&mut app, world);
    }
    assert!(
        the_world(&app, world).stats().restored >= 3,
        "carved chunks restored"
    );
    let scratch = normals(&app, world);
    let (compared, disagree, worst) = border_agreement(&scratch);
    assert!(compared > 12, "only {compared} shared smooth vertices");
    assert_eq!(
        disagree, 0,
        "rebuilt, normals differ across borders by up to {worst}°"
    );
    let compared = agrees_with_scratch(&kept, &scratch);
    eprintln!("after the craters: {compared} border vertices equal to a rebuild");
    assert!(compared > 40, "only {compared} border vertices compared");
}

#[test]
fn chunk_borders_show_a_line_with_smoothing_across_cells_off() {
    let (app, world, _) = app(false);
    let (compared, disagree, worst) = border_agreement(&normals(&app, world));
    eprintln!(
        "smoothed within each chunk: {compared} shared smooth vertices, {disagree} disagree, \
         by up to {worst:.3}°"
    );
    assert!(compared > 12, "only {compared} shared smooth vertices");
    assert!(
        disagree > compared / 4,
        "with smooth_across_cells off, only {disagree} of {compared} border vertices differ"
    );
}
