//! What a terrain builds for its changed cells ([`CellOutput`]), in an app
//! without rendering: a dedicated server with no meshes carves to exactly
//! the octree and state hash of a game client that meshes, builds no cell
//! entities, and shows every cell once it is asked for meshes again; with
//! colliders only (avian), cell entities carry colliders and no mesh.

use avian3d::prelude::*;
use bevy::asset::AssetPlugin;
use bevy::mesh::{Indices, MeshPlugin, VertexAttributeValues};
use bevy::prelude::*;
use bevy_chisel::bsp::octree::{CellBox, Edit, OctreeConfig};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::avian::TerrainAvianPlugin;
use bevy_chisel::terrain::{
    Carve, CarveApplied, CarveTool, CellOutput, Terrain, TerrainBase, TerrainCell, TerrainPlugin,
    TerrainSettings, TerrainSystems,
};

use crate::terrain_common::settle;

#[derive(Resource, Default)]
struct Applied(Vec<CarveApplied>);

fn record(mut seen: ResMut<Applied>, mut applied: MessageReader<CarveApplied>) {
    seen.0.extend(applied.read().cloned());
}

/// A 64³ block (grid unit = 1 world unit) in a 128³ cube, in small cells.
fn block() -> Terrain {
    let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
    let base = TerrainBase::Box {
        origin: [0; 3],
        size_log2: 7,
        solid: CellBox {
            min: [0; 3],
            max: [64; 3],
        },
        label: 1,
    };
    let config = OctreeConfig {
        max_bsp_nodes: 12,
        max_depth: 20,
    };
    Terrain::from_base(grid, base, config).expect("valid block")
}

/// An app with `output`, and avian colliders when `physics`.
fn app_with(output: CellOutput, physics: bool) -> (App, Entity) {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin::default(),
        MeshPlugin,
        TerrainPlugin,
    ))
    .init_asset::<StandardMaterial>()
    .insert_resource(TerrainSettings {
        output,
        ..TerrainSettings::default()
    })
    .init_resource::<Applied>()
    .add_systems(Update, record.after(TerrainSystems::Mesh));
    if physics {
        app.add_plugins((PhysicsPlugins::default(), TerrainAvianPlugin::default()));
    }
    app.finish();
    app.cleanup();
    let entity = app.world_mut().spawn(block()).id();
    settle(&mut app, entity);
    (app, entity)
}

fn terrain(app: &App, entity: Entity) -> &Terrain {
    app.world().get::<Terrain>(entity).expect("terrain entity")
}

/// Five overlapping craters on the block's top and one on a side.
fn carve_all(app: &mut App, entity: Entity) {
    let craters = [
        (Vec3::new(20.0, 64.0, 20.0), 9.0),
        (Vec3::new(30.0, 62.0, 24.0), 7.0),
        (Vec3::new(44.0, 64.0, 40.0), 12.0),
        (Vec3::new(10.0, 60.0, 50.0), 6.5),
        (Vec3::new(32.0, 66.0, 32.0), 5.0),
        (Vec3::new(64.0, 30.0, 30.0), 8.0),
    ];
    for (at, radius) in craters {
        app.world_mut().write_message(Carve {
            terrain: entity,
            tool: CarveTool::dodecahedron(radius, at),
            edit: Edit::Subtract,
        });
    }
    settle(app, entity);
}

/// (cell entities, of which with a mesh, of which with a collider).
fn cell_entities(app: &mut App) -> (usize, usize, usize) {
    let mut query = app
        .world_mut()
        .query::<(&TerrainCell, Option<&Mesh3d>, Option<&Collider>)>();
    query
        .iter(app.world())
        .fold((0, 0, 0), |(n, m, c), (_, mesh, collider)| {
            (
                n + 1,
                m + usize::from(mesh.is_some()),
                c + usize::from(collider.is_some()),
            )
        })
}

/// Total area of the shown cell meshes (indexed triangle lists).
fn shown_area(app: &mut App) -> f64 {
    let mut query = app.world_mut().query::<(&TerrainCell, &Mesh3d)>();
    let handles: Vec<AssetId<Mesh>> = query.iter(app.world()).map(|(_, m)| m.id()).collect();
    let meshes = app.world().resource::<Assets<Mesh>>();
    let mut area = 0.0;
    for id in handles {
        let mesh = meshes.get(id).expect("a shown mesh");
        let Ok(Some(VertexAttributeValues::Float32x3(p))) =
            mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
        else {
            panic!("cell meshes have Float32x3 positions");
        };
        let Some(Indices::U32(indices)) = mesh.indices() else {
            panic!("cell meshes have u32 indices");
        };
        for t in indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| Vec3::from(p[v as usize]).as_dvec3());
            area += 0.5 * (b - a).cross(c - a).length();
        }
    }
    area
}

#[test]
fn a_server_without_meshes_carves_to_the_same_hash_and_builds_no_cells() {
    let (mut client, on_client) = app_with(CellOutput::Meshes, false);
    let (mut server, on_server) = app_with(CellOutput::Nothing, false);
    assert_eq!(cell_entities(&mut server), (0, 0, 0), "no cells at spawn");
    carve_all(&mut client, on_client);
    carve_all(&mut server, on_server);
    let applied = |app: &App| app.world().resource::<Applied>().0.len();
    assert_eq!(applied(&server), 6, "every carve is reported");
    assert_eq!(applied(&client), 6);
    let (a, b) = (terrain(&client, on_client), terrain(&server, on_server));
    assert_eq!(a.state_hash(), b.state_hash(), "the same octree");
    assert_eq!(
        a.octree().exact_solid_volume(),
        b.octree().exact_solid_volume()
    );
    assert_eq!(b.triangle_count(), 0);
    assert_eq!(cell_entities(&mut server), (0, 0, 0), "still no cells");
    let shown = cell_entities(&mut client);
    assert!(
        shown.0 > 10 && shown.1 == shown.0,
        "client cells: {shown:?}"
    );

    // Asked for meshes again, the server shows what the client shows.
    server.world_mut().resource_mut::<TerrainSettings>().output = CellOutput::Meshes;
    settle(&mut server, on_server);
    assert_eq!(cell_entities(&mut server), shown);
    // The same surface, perhaps in other triangles: the client meshed the
    // carved cells from the faces each carve handed back.
    let (a, b) = (shown_area(&mut client), shown_area(&mut server));
    assert!((a - b).abs() <= 1e-6 * a, "areas {a} and {b}");

    // And back to nothing: the cells are taken away.
    server.world_mut().resource_mut::<TerrainSettings>().output = CellOutput::Nothing;
    settle(&mut server, on_server);
    assert_eq!(cell_entities(&mut server), (0, 0, 0));
}

#[test]
fn colliders_only_gives_every_cell_a_collider_and_no_mesh() {
    let (mut app, entity) = app_with(CellOutput::Colliders, true);
    carve_all(&mut app, entity);
    let (cells, meshes, colliders) = cell_entities(&mut app);
    assert!(cells > 10, "{cells} cells");
    assert_eq!(meshes, 0, "no render meshes");
    assert_eq!(colliders, cells, "a collider on every cell");
    assert!(
        app.world().resource::<Assets<Mesh>>().is_empty(),
        "no mesh assets"
    );
    // The same cells a meshing app gives colliders to.
    let (mut meshed, on_meshed) = app_with(CellOutput::Meshes, true);
    carve_all(&mut meshed, on_meshed);
    assert_eq!(cell_entities(&mut meshed), (cells, cells, cells));
}
