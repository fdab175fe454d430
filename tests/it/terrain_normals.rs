//! Smooth normals across cell borders: on a gently curved heightfield cut
//! into many cells, every vertex shared by the meshes of two cells gets
//! the same normal bits in both, after the first build and after carves
//! meshed incrementally (from the carves' fresh faces), and each cell's
//! normals at its border vertices equal those of a build from scratch.
//! The cell meshes smoothed over their own polygons only (the code before
//! border smoothing) disagree there, which shows the check can fail. The
//! plugin's meshes do the same, and go back to per-cell smoothing with
//! `TerrainSettings::smooth_across_cells` off.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::time::Duration;

use bevy::asset::AssetPlugin;
use bevy::mesh::VertexAttributeValues;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellKey, Edit, Octree, OctreeConfig, SeamedMesher, ShadedCell};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::mesh::{
    CellMesh, DEFAULT_SMOOTHING_DEGREES, cell_meshes_around, cell_meshes_of,
};
use bevy_chisel::terrain::{
    CarveTool, GridHeightfield, Terrain, TerrainBase, TerrainCell, TerrainPlugin, TerrainSettings,
    apply_carve_with_faces,
};

/// Cell meshes by key.
type Meshes = BTreeMap<CellKey, Vec<CellMesh>>;

/// A 24 × 24 heightfield of gentle waves (slopes under 17°) on a 1 cm
/// grid, 1 m between samples, in cells of at most 40 BSP nodes.
fn gentle_hills() -> (Octree, Quantization) {
    let (base, config, grid) = gentle_hills_base();
    let octree = base.build(config).expect("a valid heightfield");
    (octree, grid)
}

/// What [`gentle_hills`] builds its octree from.
fn gentle_hills_base() -> (TerrainBase, OctreeConfig, Quantization) {
    let n = 24u32;
    let heights = (0..n * n)
        .map(|k| {
            let (i, j) = (f64::from(k % n), f64::from(k / n));
            (500.0 + 100.0 * (0.3 * i).sin() * (0.25 * j + 0.5).cos()).round() as i64
        })
        .collect();
    let base = TerrainBase::Heightfield {
        origin: [-200, -200, -200],
        size_log2: 12,
        field: GridHeightfield {
            corner: [0, 0, 0],
            samples: [n, n],
            spacing: 100,
            heights,
            bottom: 0,
            label: 1,
            layers: Vec::new(),
        },
    };
    let config = OctreeConfig {
        max_bsp_nodes: 40,
        ..OctreeConfig::default()
    };
    let grid = Quantization::new(0.01, [0.0; 3]).expect("a valid unit");
    (base, config, grid)
}

/// Takes an update's cells into `meshes`, smoothed across borders
/// (`across`) or over each cell's own polygons.
fn take(
    meshes: &mut Meshes,
    cells: Vec<(CellKey, Option<ShadedCell>)>,
    grid: &Quantization,
    across: bool,
) {
    for (key, cell) in cells {
        match cell {
            None => {
                meshes.remove(&key);
            }
            Some(cell) => {
                let built = if across {
                    cell_meshes_around(&cell.mesh, &cell.around, grid, DEFAULT_SMOOTHING_DEGREES)
                } else {
                    cell_meshes_of(&cell.mesh, grid, DEFAULT_SMOOTHING_DEGREES)
                };
                meshes.insert(key, built);
            }
        }
    }
}

/// Every leaf meshed from scratch.
fn from_scratch(octree: &Octree, grid: &Quantization, across: bool) -> Meshes {
    let mut mesher = SeamedMesher::with_shading();
    let all = octree.leaves().into_iter().map(|(key, _)| key);
    let mut meshes = Meshes::new();
    take(
        &mut meshes,
        mesher.update_shaded(octree, all, BTreeMap::new()),
        grid,
        across,
    );
    meshes
}

/// Per cell, per position (bits), the normals (bits) of its render
/// vertices there.
fn normals_by_position(
    meshes: &Meshes,
) -> BTreeMap<CellKey, HashMap<[u32; 3], BTreeSet<[u32; 3]>>> {
    meshes
        .iter()
        .map(|(key, list)| {
            let mut at: HashMap<[u32; 3], BTreeSet<[u32; 3]>> = HashMap::new();
            for mesh in list {
                for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
                    at.entry(p.map(f32::to_bits))
                        .or_default()
                        .insert(n.map(f32::to_bits));
                }
            }
            (*key, at)
        })
        .collect()
}

/// The positions held by the meshes of two or more cells.
fn shared_positions(
    by_cell: &BTreeMap<CellKey, HashMap<[u32; 3], BTreeSet<[u32; 3]>>>,
) -> HashMap<[u32; 3], Vec<CellKey>> {
    let mut cells: HashMap<[u32; 3], Vec<CellKey>> = HashMap::new();
    for (key, at) in by_cell {
        for p in at.keys() {
            cells.entry(*p).or_default().push(*key);
        }
    }
    cells.retain(|_, keys| keys.len() > 1);
    cells
}

/// At the positions shared by cells that each have one normal there (a
/// smooth spot), how many were compared, how many disagree and the
/// largest angle between two cells' normals (degrees).
fn border_agreement(meshes: &Meshes) -> (usize, usize, f32) {
    let by_cell = normals_by_position(meshes);
    let (mut compared, mut disagree, mut worst) = (0, 0, 0.0f32);
    for (p, keys) in shared_positions(&by_cell) {
        let normals: Vec<&BTreeSet<[u32; 3]>> = keys.iter().map(|k| &by_cell[k][&p]).collect();
        if normals.iter().any(|n| n.len() != 1) {
            continue;
        }
        compared += 1;
        let first = normals[0].first().expect("one normal");
        if normals.iter().any(|n| n.first() != Some(first)) {
            disagree += 1;
            let a = Vec3::from_array(first.map(f32::from_bits));
            for n in &normals {
                let b = Vec3::from_array(n.first().expect("one normal").map(f32::from_bits));
                worst = worst.max(a.angle_between(b).to_degrees());
            }
        }
    }
    (compared, disagree, worst)
}

/// At every position shared by cells in the build from scratch, each
/// cell's normals there in `meshes` equal those from scratch (positions a
/// cell has in only one of them are skipped); how many were compared.
fn agrees_with_scratch(meshes: &Meshes, scratch: &Meshes) -> usize {
    let (ours, theirs) = (normals_by_position(meshes), normals_by_position(scratch));
    let mut compared = 0;
    for (p, keys) in shared_positions(&theirs) {
        for key in keys {
            let Some(mine) = ours.get(&key).and_then(|at| at.get(&p)) else {
                continue;
            };
            compared += 1;
            assert_eq!(
                mine,
                &theirs[&key][&p],
                "cell {key:?} at {:?}: normals differ from a build from scratch",
                p.map(f32::from_bits)
            );
        }
    }
    compared
}

#[test]
fn smooth_normals_agree_across_cell_borders_and_after_carves() {
    let (mut octree, grid) = gentle_hills();
    assert!(octree.leaves().len() > 20, "many cells");

    // The first build: border vertices agree; smoothed over each cell's
    // own polygons they do not.
    let mut mesher = SeamedMesher::with_shading();
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(key, _)| key).collect();
    let mut meshes = Meshes::new();
    take(
        &mut meshes,
        mesher.update_shaded(&octree, all, BTreeMap::new()),
        &grid,
        true,
    );
    let (compared, disagree, worst) = border_agreement(&meshes);
    eprintln!("first build: {compared} shared smooth vertices, {disagree} disagree");
    assert!(compared > 100, "only {compared} shared smooth vertices");
    assert_eq!(
        disagree, 0,
        "normals differ across borders by up to {worst}°"
    );
    let own_only = from_scratch(&octree, &grid, false);
    let (compared, disagree, worst) = border_agreement(&own_only);
    eprintln!(
        "smoothed within each cell: {compared} shared smooth vertices, {disagree} disagree, \
         by up to {worst:.3}°"
    );
    assert!(disagree > compared / 4, "the check has no teeth");

    // Carves meshed incrementally from their fresh faces, some across
    // cell borders and corners.
    let craters = [
        (1.2, Vec3::new(6.0, 5.6, 6.0)),
        (0.8, Vec3::new(10.24, 5.5, 10.24)),
        (1.5, Vec3::new(15.0, 5.2, 8.0)),
        (0.6, Vec3::new(7.68, 5.3, 15.36)),
        (1.0, Vec3::new(12.8, 5.6, 12.8)),
    ];
    for (radius, centre) in craters {
        let tool = CarveTool::dodecahedron(radius, centre)
            .to_grid(&grid)
            .expect("a valid tool");
        let (changes, faces) =
            apply_carve_with_faces(&mut octree, &tool, Edit::Subtract).expect("a valid carve");
        let keys: Vec<CellKey> = changes
            .changed
            .iter()
            .chain(&changes.removed)
            .copied()
            .collect();
        let fresh = faces.into_iter().collect();
        take(
            &mut meshes,
            mesher.update_shaded(&octree, keys, fresh),
            &grid,
            true,
        );
        let (compared, disagree, worst) = border_agreement(&meshes);
        assert!(compared > 100, "only {compared} shared smooth vertices");
        assert_eq!(
            disagree, 0,
            "after a carve at {centre}, normals differ across borders by up to {worst}°"
        );
    }
    let scratch = from_scratch(&octree, &grid, true);
    assert_eq!(
        meshes.keys().collect::<Vec<_>>(),
        scratch.keys().collect::<Vec<_>>(),
        "the same cells"
    );
    let compared = agrees_with_scratch(&meshes, &scratch);
    eprintln!("after the carves: {compared} border vertices equal to a build from scratch");
    assert!(compared > 200, "only {compared} border vertices compared");
}

/// The cell meshes a terrain entity shows, by cell.
fn shown_meshes(app: &mut App) -> Meshes {
    let mut query = app.world_mut().query::<(&TerrainCell, &Mesh3d)>();
    let shown: Vec<(CellKey, u8, AssetId<Mesh>)> = query
        .iter(app.world())
        .map(|(cell, mesh)| (cell.key, cell.label, mesh.id()))
        .collect();
    let assets = app.world().resource::<Assets<Mesh>>();
    let mut meshes = Meshes::new();
    for (key, label, id) in shown {
        let mesh = assets.get(id).expect("a shown mesh");
        let attribute = |name| match mesh.try_attribute_option(name) {
            Ok(Some(VertexAttributeValues::Float32x3(values))) => values.clone(),
            _ => panic!("cell meshes have Float32x3 positions and normals"),
        };
        meshes.entry(key).or_default().push(CellMesh {
            label,
            positions: attribute(Mesh::ATTRIBUTE_POSITION),
            normals: attribute(Mesh::ATTRIBUTE_NORMAL),
            ..CellMesh::default()
        });
    }
    meshes
}

/// The gentle hills as a terrain entity, meshed by the plugin with
/// `TerrainSettings::smooth_across_cells` as given.
fn plugin_meshes(smooth_across_cells: bool) -> Meshes {
    let (base, config, grid) = gentle_hills_base();
    let terrain = Terrain::from_base(grid, base, config).expect("a valid terrain");
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TerrainPlugin))
        .init_asset::<Mesh>()
        .init_asset::<StandardMaterial>()
        .insert_resource(TerrainSettings {
            smooth_across_cells,
            ..TerrainSettings::default()
        });
    let entity = app.world_mut().spawn(terrain).id();
    for _ in 0..20_000 {
        app.update();
        let idle = app
            .world()
            .get::<Terrain>(entity)
            .is_some_and(Terrain::is_idle);
        if idle
            && app
                .world_mut()
                .query::<&TerrainCell>()
                .iter(app.world())
                .count()
                > 0
        {
            app.update();
            return shown_meshes(&mut app);
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("the terrain did not settle");
}

#[test]
fn the_plugin_shares_border_normals_unless_told_not_to() {
    let shared = plugin_meshes(true);
    let (compared, disagree, worst) = border_agreement(&shared);
    assert!(compared > 100, "only {compared} shared smooth vertices");
    assert_eq!(
        disagree, 0,
        "normals differ across borders by up to {worst}°"
    );
    let own = plugin_meshes(false);
    let (compared, disagree, _) = border_agreement(&own);
    assert!(
        disagree > compared / 4,
        "with smooth_across_cells off, {disagree} of {compared} border vertices differ"
    );
}
