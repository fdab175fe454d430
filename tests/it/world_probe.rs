//! Point queries (`MinimalPlugins`): [`Terrain::material_at`] and
//! [`TerrainWorld::material_at`] in a flat world of rock (label 1) under
//! 4 units of soil (label 2), with a box crater carved across the soil
//! into the rock. Exact answers inside and outside the crater, on its
//! floor and walls, at the layer boundary and the surface (a point on a
//! face reports the greater label, material over air), across a chunk
//! border; the rounding to the grid; `None` outside the terrain; typed
//! errors for NaN, a point beyond the grid's range and a chunk that is
//! not loaded.

use bevy::prelude::*;
use bevy_chisel::bsp::Error as KernelError;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tree::{EMPTY, Label};
use bevy_chisel::terrain::{ChunkCoord, Terrain, TerrainError, TerrainWorld, WorldCarve};

use super::terrain_world::{app_with, layout, settle, terrain, the_world};
use super::terrain_world_debris::cuboid;

const ROCK: Label = 1;
const SOIL: Label = 2;

const fn at(x: i64, z: i64) -> ChunkCoord {
    ChunkCoord { x, z }
}

/// Flat at height 16 over the floor at 0, soil in the top 4 units (from
/// 12), rock below; chunks of 32.
fn flat_world() -> TerrainWorld {
    let mut layout = layout();
    layout.label = ROCK;
    layout.layers = vec![(4, SOIL)];
    TerrainWorld::new(layout, |_, _| 16).expect("valid layout")
}

/// The crater: x and z 8..14, from y = 10 (in the rock) up through the
/// surface.
const CRATER: ([i64; 3], [i64; 3]) = ([8, 10, 8], [14, 20, 14]);

/// The world with its crater, settled, focus over chunk (0, 0).
fn cratered() -> (App, Entity) {
    let (mut app, world, _) = app_with(flat_world(), Vec3::new(16.0, 30.0, 16.0));
    settle(&mut app, world);
    app.world_mut().write_message(WorldCarve {
        world,
        tool: cuboid(CRATER.0, CRATER.1),
        edit: Edit::Subtract,
    });
    settle(&mut app, world);
    (app, world)
}

fn world_at(app: &App, world: Entity, p: [f32; 3]) -> Result<Option<Label>, TerrainError> {
    the_world(app, world).material_at(Vec3::from_array(p), |e| app.world().get::<Terrain>(e))
}

#[test]
fn materials_at_points_around_a_crater_and_a_layer_boundary_are_exact() {
    let (app, world) = cratered();
    let chunk = terrain(&app, world, at(0, 0));
    let cases: [([f32; 3], Label); 16] = [
        // In the crater: air, in the soil band's height and the rock's.
        ([11.0, 14.0, 11.0], EMPTY),
        ([11.0, 11.0, 11.0], EMPTY),
        // Its floor, on the face: the rock; just below it, rock.
        ([11.0, 10.0, 11.0], ROCK),
        ([11.0, 9.0, 11.0], ROCK),
        // Rounded to the grid: 10.4 is on the floor, 10.6 above it.
        ([11.0, 10.4, 11.0], ROCK),
        ([11.0, 10.6, 11.0], EMPTY),
        // Its walls, on the faces: soil above 12, rock below.
        ([8.0, 14.0, 11.0], SOIL),
        ([14.0, 11.0, 11.0], ROCK),
        // Its rim, where the wall meets the surface.
        ([8.0, 16.0, 11.0], SOIL),
        // Beside it: soil, the boundary (the greater label), rock.
        ([20.0, 14.0, 20.0], SOIL),
        ([20.0, 12.0, 20.0], SOIL),
        ([20.0, 11.0, 20.0], ROCK),
        ([20.0, 2.0, 20.0], ROCK),
        // The surface (material over air), and just above it.
        ([20.0, 16.0, 20.0], SOIL),
        ([20.0, 16.6, 20.0], EMPTY),
        ([20.0, 30.0, 20.0], EMPTY),
    ];
    for (p, label) in cases {
        let local = chunk.material_at(Vec3::from_array(p));
        assert_eq!(local, Ok(Some(label)), "chunk at {p:?}");
        assert_eq!(world_at(&app, world, p), Ok(Some(label)), "world at {p:?}");
    }
    // Strictly inside a region the kernel's own lookup agrees.
    let octree = chunk.octree();
    for (p, label) in [
        ([11, 14, 11], EMPTY),
        ([11, 9, 11], ROCK),
        ([20, 14, 20], SOIL),
        ([20, 11, 20], ROCK),
    ] {
        assert_eq!(octree.label_at(p).expect("in range"), Some(label), "{p:?}");
    }
    // Outside the chunk's cube (its faces count as inside).
    assert_eq!(chunk.material_at(Vec3::new(40.0, 10.0, 11.0)), Ok(None));
    assert_eq!(chunk.material_at(Vec3::new(11.0, 33.0, 11.0)), Ok(None));
    assert_eq!(
        chunk.material_at(Vec3::new(11.0, 32.0, 11.0)),
        Ok(Some(EMPTY))
    );
    assert_eq!(chunk.material_at(Vec3::new(11.0, -1.0, 11.0)), Ok(None));
    assert_eq!(
        chunk.material_at(Vec3::new(11.0, 0.0, 11.0)),
        Ok(Some(ROCK))
    );
    // Above the chunks' cubes and below the floor: nothing, loaded or not.
    assert_eq!(world_at(&app, world, [11.0, 33.0, 11.0]), Ok(None));
    assert_eq!(world_at(&app, world, [11.0, -0.6, 11.0]), Ok(None));
    assert_eq!(world_at(&app, world, [5000.0, 40.0, 5000.0]), Ok(None));
}

#[test]
fn a_point_on_a_chunk_border_asks_both_chunks() {
    let (mut app, world) = cratered();
    // A crater whose wall is the border x = 32: air in chunk (1, 0) only.
    app.world_mut().write_message(WorldCarve {
        world,
        tool: cuboid([32, 10, 20], [36, 20, 24]),
        edit: Edit::Subtract,
    });
    settle(&mut app, world);
    let [west, east] = [at(0, 0), at(1, 0)].map(|c| terrain(&app, world, c));
    let p = Vec3::new(32.0, 14.0, 22.0);
    assert_eq!(west.material_at(p), Ok(Some(SOIL)), "the west chunk's side");
    assert_eq!(
        east.material_at(p),
        Ok(Some(EMPTY)),
        "the crater reaches its side"
    );
    let inside = Vec3::new(33.0, 14.0, 22.0);
    assert_eq!(east.material_at(inside), Ok(Some(EMPTY)));
    assert_eq!(west.material_at(inside), Ok(None), "outside its cube");
    // The world asks both: the wall is the west chunk's.
    assert_eq!(world_at(&app, world, p.to_array()), Ok(Some(SOIL)));
    assert_eq!(world_at(&app, world, inside.to_array()), Ok(Some(EMPTY)));
    // The corner of four chunks, on the surface.
    assert_eq!(world_at(&app, world, [32.0, 16.0, 32.0]), Ok(Some(SOIL)));
    assert_eq!(world_at(&app, world, [32.0, 17.0, 32.0]), Ok(Some(EMPTY)));
}

#[test]
fn bad_points_and_chunks_not_loaded_are_typed_errors() {
    let (app, world) = cratered();
    let chunk = terrain(&app, world, at(0, 0));
    for p in [
        Vec3::new(f32::NAN, 10.0, 10.0),
        Vec3::new(10.0, f32::INFINITY, 10.0),
    ] {
        let non_finite = |r: Result<Option<Label>, TerrainError>| {
            matches!(r, Err(TerrainError::Kernel(KernelError::NonFinite { .. })))
        };
        assert!(non_finite(chunk.material_at(p)), "{p:?}");
        assert!(non_finite(world_at(&app, world, p.to_array())), "{p:?}");
    }
    // Beyond the grid's range (±2^26 grid units).
    let far = Vec3::new(1.0e9, 10.0, 10.0);
    let out_of_range = |r: Result<Option<Label>, TerrainError>| {
        matches!(
            r,
            Err(TerrainError::Kernel(KernelError::CoordinateOutOfRange {
                axis: 0,
                ..
            }))
        )
    };
    assert!(out_of_range(chunk.material_at(far)));
    assert!(out_of_range(world_at(&app, world, far.to_array())));
    // Far, in range: the chunk holding it is not loaded.
    assert_eq!(
        world_at(&app, world, [5000.0, 10.0, -5000.0]),
        Err(TerrainError::ChunkNotLoaded { chunk: [156, -157] })
    );
    // A live chunk whose terrain is not given counts as not loaded.
    let w = the_world(&app, world);
    assert_eq!(
        w.material_at(Vec3::new(11.0, 10.0, 11.0), |_| None),
        Err(TerrainError::ChunkNotLoaded { chunk: [0, 0] })
    );
}

/// Every grid point around the crater, on faces, edges and corners too,
/// against the regions the world is made of: the greatest label whose
/// region's closure holds the point.
#[test]
fn every_grid_point_around_the_crater_reports_the_greatest_label_touching_it() {
    let (app, world) = cratered();
    let strictly_in_crater = |p: [i64; 3]| (0..3).all(|a| CRATER.0[a] < p[a] && p[a] < CRATER.1[a]);
    let in_closed_crater = |p: [i64; 3]| (0..3).all(|a| CRATER.0[a] <= p[a] && p[a] <= CRATER.1[a]);
    let mut faces = 0;
    let start = std::time::Instant::now();
    for x in 4..=18 {
        for y in 6..=20 {
            for z in 4..=18 {
                let p = [x, y, z];
                let solid = !strictly_in_crater(p);
                let soil = solid && (12..=16).contains(&y);
                let rock = solid && y <= 12;
                let air = y >= 16 || in_closed_crater(p);
                let expected = if soil {
                    SOIL
                } else if rock {
                    ROCK
                } else {
                    EMPTY
                };
                faces += usize::from(air && (soil || rock));
                let got = world_at(&app, world, p.map(|c| c as f32));
                assert_eq!(got, Ok(Some(expected)), "{p:?}");
            }
        }
    }
    println!(
        "{} world point queries in {:?} ({faces} on faces)",
        15 * 15 * 15,
        start.elapsed()
    );
    assert!(
        faces > 100,
        "{faces} points on faces between air and material"
    );
}
