//! Level of detail of a streamed world (`MinimalPlugins`, no renderer):
//! a carve across the boundary between a full-detail chunk and a coarse
//! one leaves no crack (rays on a dense grid, vertical and slanted, all
//! hit the drawn meshes), the coarse chunk shows the crater within its
//! stated error, and the two swap when the focus moves; skirts shade as
//! the ground they hang from.

use bevy::asset::AssetPlugin;
use bevy::mesh::{Indices, VertexAttributeValues};
use std::collections::HashMap;

use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_chisel::bsp::octree::Edit;
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::mesh::cell_meshes;
use bevy_chisel::terrain::world::lod_mesh::{LodPyramid, edited_pyramid, source_pyramid};
use bevy_chisel::terrain::{
    CarveTool, ChunkCoord, LodMesh, LodSettings, NoiseOctave, StreamSettings, Terrain,
    TerrainFocus, TerrainPlugin, TerrainWorld, ValueNoise, WorldCarve, WorldLayout, WorldLod,
};

/// Grid unit 1; chunks of 32, samples 2 apart (16 squares a side, levels
/// 1..=4), a 3-deep band of label 2 over label 1.
fn layout() -> WorldLayout {
    WorldLayout {
        quantization: Quantization::new(1.0, [0.0; 3]).expect("valid unit"),
        chunk_log2: 5,
        spacing_log2: 1,
        floor: 0,
        label: 1,
        layers: vec![(3, 2)],
    }
}

fn source() -> ValueNoise {
    ValueNoise {
        base: 10,
        octaves: vec![NoiseOctave {
            cell: 4,
            amplitude: 6,
            seed: 3,
        }],
    }
}

/// Only the chunk under the focus is full detail (its neighbours are 16
/// away); coarse chunks out to 60.
fn app(focus: Vec3) -> (App, Entity, Entity) {
    let world = TerrainWorld::new(layout(), source())
        .expect("valid layout")
        .with_streaming(StreamSettings {
            load_radius: 8.0,
            unload_radius: 12.0,
            max_building: 4,
        })
        .expect("valid settings");
    let lod = WorldLod::new(LodSettings {
        far_radius: 60.0,
        ..LodSettings::default()
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
    .init_asset::<StandardMaterial>();
    let world = app.world_mut().spawn((world, lod)).id();
    let focus = app
        .world_mut()
        .spawn((TerrainFocus, Transform::from_translation(focus)))
        .id();
    settle(&mut app, world);
    (app, world, focus)
}

fn settle(app: &mut App, world: Entity) {
    let mut calm = 0;
    for _ in 0..20_000 {
        app.update();
        let w = app.world().get::<TerrainWorld>(world).expect("world");
        let lod = app.world().get::<WorldLod>(world).expect("lod");
        let idle = w.is_settled()
            && lod.is_settled()
            && w.live_chunks()
                .all(|(_, e)| app.world().get::<Terrain>(e).is_some_and(Terrain::is_idle));
        calm = if idle { calm + 1 } else { 0 };
        if calm == 5 {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    panic!("the world did not settle");
}

type Triangle = [Vec3; 3];

fn triangles_of(mesh: &Mesh) -> Vec<Triangle> {
    let Ok(Some(VertexAttributeValues::Float32x3(p))) =
        mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
    else {
        panic!("mesh without positions");
    };
    let indices: Vec<usize> = match mesh.try_indices_option() {
        Ok(Some(Indices::U16(v))) => v.iter().map(|&i| usize::from(i)).collect(),
        Ok(Some(Indices::U32(v))) => v.iter().map(|&i| i as usize).collect(),
        _ => (0..p.len()).collect(),
    };
    indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| Vec3::from_array(p[t[k]])))
        .collect()
}

/// Every drawn triangle: the live chunks' cells and the coarse chunks,
/// with the coarse ones of `coarse_of` apart.
fn drawn(app: &mut App, world: Entity, coarse_of: ChunkCoord) -> (Vec<Triangle>, Vec<Triangle>) {
    let live: Vec<Entity> = app
        .world()
        .get::<TerrainWorld>(world)
        .expect("world")
        .live_chunks()
        .map(|(_, e)| e)
        .collect();
    let mut handles = Vec::new();
    for e in live {
        let terrain = app.world().get::<Terrain>(e).expect("terrain");
        for (_, cells) in terrain.cells() {
            for cell in cells {
                if let Some(mesh) = app.world().get::<Mesh3d>(cell) {
                    handles.push((false, mesh.0.clone()));
                }
            }
        }
    }
    let mut query = app.world_mut().query::<(&LodMesh, &Mesh3d)>();
    let coarse: Vec<(bool, Handle<Mesh>)> = query
        .iter(app.world())
        .map(|(l, m)| (l.coord == coarse_of, m.0.clone()))
        .collect();
    handles.extend(coarse);
    let meshes = app.world().resource::<Assets<Mesh>>();
    let (mut all, mut mine) = (Vec::new(), Vec::new());
    for (is_mine, handle) in handles {
        let t = triangles_of(meshes.get(&handle).expect("mesh asset"));
        if is_mine {
            mine.extend(t.iter().copied());
        }
        all.extend(t);
    }
    (all, mine)
}

/// The nearest hit of a ray with a triangle, either side (Möller–Trumbore).
fn hit(origin: Vec3, dir: Vec3, t: &Triangle) -> Option<f32> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-9 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - t[0];
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    let eps = 1e-5;
    if u < -eps || v < -eps || u + v > 1.0 + eps {
        return None;
    }
    let d = e2.dot(q) * inv;
    (d > 0.0).then_some(d)
}

fn first_hit(origin: Vec3, dir: Vec3, triangles: &[Triangle]) -> Option<f32> {
    triangles
        .iter()
        .filter_map(|t| hit(origin, dir, t))
        .fold(None, |a: Option<f32>, d| Some(a.map_or(d, |a| a.min(d))))
}

/// Rays across the border plane `x = plane`: vertical ones on a grid over
/// both sides, and slanted ones through points of the plane from the
/// floor up to above the surface, both ways. Returns the rays that hit
/// nothing, and how many were cast.
fn rays_missing(triangles: &[Triangle], plane: f32) -> (Vec<(Vec3, Vec3)>, usize) {
    let mut rays = Vec::new();
    let mut x = plane - 10.0;
    while x <= plane + 10.0 {
        let mut z = 1.0;
        while z <= 31.0 {
            rays.push((Vec3::new(x, 40.0, z), Vec3::NEG_Y));
            z += 0.7;
        }
        x += 0.7;
    }
    let slants = [
        Vec3::new(1.0, -0.4, 0.0),
        Vec3::new(-1.0, -0.4, 0.0),
        Vec3::new(1.0, -1.0, 0.3),
        Vec3::new(-1.0, -0.7, -0.4),
    ];
    let mut z = 1.3;
    while z <= 31.0 {
        let mut y = 1.0;
        while y <= 20.0 {
            for d in slants {
                let d = d.normalize();
                rays.push((Vec3::new(plane, y, z) - d * 40.0, d));
            }
            y += 0.5;
        }
        z += 0.9;
    }
    let cast = rays.len();
    let missing = rays
        .into_iter()
        .filter(|&(o, d)| first_hit(o, d, triangles).is_none())
        .collect();
    (missing, cast)
}

/// Distance from `p` to triangle `t`.
fn distance_to_triangle(p: Vec3, t: &Triangle) -> f32 {
    let [a, b, c] = t.map(Vec3::as_dvec3);
    let p = p.as_dvec3();
    let n = (b - a).cross(c - a);
    if n.length_squared() > 1e-18 {
        let n = n.normalize();
        let q = p - n * (p - a).dot(n);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= -1e-12);
        if inside {
            return (p - q).length() as f32;
        }
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(u, v)| {
            let d = v - u;
            let s = if d.length_squared() > 0.0 {
                ((p - u).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (u + d * s)).length()
        })
        .fold(f64::INFINITY, f64::min) as f32
}

/// The exact surface of `terrain` as triangles.
fn exact_triangles(terrain: &Terrain) -> Vec<Triangle> {
    let octree = terrain.octree();
    octree
        .leaves()
        .iter()
        .flat_map(|(key, _)| cell_meshes(octree, terrain.quantization(), *key))
        .flat_map(|m| {
            m.collider
                .triangles
                .iter()
                .map(|t| t.map(|v| m.collider.positions[v as usize]))
                .collect::<Vec<_>>()
        })
        .collect()
}

fn vertical_hit(triangles: &[Triangle], x: f32, z: f32) -> f32 {
    let d = first_hit(Vec3::new(x, 40.0, z), Vec3::NEG_Y, triangles).expect("a hit");
    40.0 - d
}

#[test]
fn a_carve_across_a_lod_boundary_leaves_no_crack() {
    let (mut app, world, focus) = app(Vec3::new(16.0, 30.0, 16.0));
    let (full, coarse) = (ChunkCoord { x: 0, z: 0 }, ChunkCoord { x: 1, z: 0 });
    {
        let w = app.world().get::<TerrainWorld>(world).expect("world");
        assert_eq!(w.live_chunks().map(|(c, _)| c).collect::<Vec<_>>(), [full]);
        let lod = app.world().get::<WorldLod>(world).expect("lod");
        assert!(lod.drawn_level(full).is_none(), "full detail draws (0, 0)");
        assert_eq!(lod.drawn_level(coarse).map(|l| l.0), Some(1));
        // Coarser with distance, out to the far radius.
        let far = lod
            .drawn_level(ChunkCoord { x: 2, z: 0 })
            .expect("drawn coarse");
        assert!(far.0 >= 1);
        let stats = lod.stats();
        println!("coarse chunks: {stats:?}");
        assert!(stats.drawn_per_level.iter().sum::<usize>() >= 20);
    }
    let (before, _) = drawn(&mut app, world, coarse);
    let (missing, cast) = rays_missing(&before, 32.0);
    assert!(
        missing.is_empty(),
        "{} of {cast} rays miss: {:?}",
        missing.len(),
        &missing[..missing.len().min(5)]
    );

    // A crater across x = 32: half in the full-detail chunk, half in the
    // coarse one (built full for the carve, then streamed out and kept).
    let tool = CarveTool::dodecahedron(7.0, Vec3::new(32.0, 12.0, 16.0));
    app.world_mut().write_message(WorldCarve {
        world,
        tool: tool.clone(),
        edit: Edit::Subtract,
    });
    settle(&mut app, world);
    let w = app.world().get::<TerrainWorld>(world).expect("world");
    assert_eq!(w.stored_chunks().collect::<Vec<_>>(), [coarse]);
    let grid = tool.to_grid(&layout().quantization).expect("on the grid");
    let unedited = w.generate_chunk(coarse).expect("builds");
    let mut exact = w.generate_chunk(coarse).expect("builds");
    exact.apply_now(&grid, Edit::Subtract).expect("carves");
    let lod = app.world().get::<WorldLod>(world).expect("lod");
    let (level, error) = lod.drawn_level(coarse).expect("drawn coarse");
    assert_eq!(level, 1);
    // Level 1 of an edited chunk: clusters of edge 2, error √3·2.
    assert!((error - 2.0 * 3f32.sqrt()).abs() < 1e-5, "{error}");
    assert_eq!(
        lod.pyramid(coarse).map(|p| p.basis),
        Some(bevy_chisel::terrain::world::LodBasis::Edited(
            exact.state_hash()
        ))
    );

    let (after, mine) = drawn(&mut app, world, coarse);
    let (missing, cast) = rays_missing(&after, 32.0);
    assert!(
        missing.is_empty(),
        "{} of {cast} rays miss after the carve: {:?}",
        missing.len(),
        &missing[..missing.len().min(5)]
    );

    // Every vertex of the coarse chunk's surface (the skirts' bottoms
    // left out) lies within the error of the exact surface.
    let exact_tris = exact_triangles(&exact);
    let mut worst = 0.0f32;
    for p in mine.iter().flatten().filter(|p| p.y > 1e-3) {
        let d = exact_tris
            .iter()
            .map(|t| distance_to_triangle(*p, t))
            .fold(f32::INFINITY, f32::min);
        worst = worst.max(d);
    }
    println!("coarse vertices: at most {worst:.3} from the exact surface (bound {error:.3})");
    assert!(worst <= error + 1e-3, "{worst} > {error}");
    // The crater shows: the coarse surface dips where the exact one does.
    let (x, z) = (34.5, 16.3);
    let (y_unedited, y_exact) = (
        vertical_hit(&exact_triangles(&unedited), x, z),
        vertical_hit(&exact_tris, x, z),
    );
    let y_coarse = vertical_hit(&mine, x, z);
    println!("at ({x}, {z}): unedited {y_unedited:.2}, exact {y_exact:.2}, coarse {y_coarse:.2}");
    assert!(y_unedited - y_exact > 4.0, "a deep crater");
    assert!(
        (y_coarse - y_exact).abs() <= error,
        "the coarse surface at the crater: {y_coarse} vs {y_exact}"
    );

    // The focus moves over the carved chunk: it is full detail, (0, 0)
    // (edited too) coarse, and the border is still closed.
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(48.0, 30.0, 16.0);
    settle(&mut app, world);
    let w = app.world().get::<TerrainWorld>(world).expect("world");
    assert_eq!(
        w.live_chunks().map(|(c, _)| c).collect::<Vec<_>>(),
        [coarse]
    );
    let lod = app.world().get::<WorldLod>(world).expect("lod");
    assert!(lod.drawn_level(coarse).is_none());
    assert_eq!(lod.drawn_level(full).map(|l| l.0), Some(1));
    let (swapped, _) = drawn(&mut app, world, full);
    let (missing, cast) = rays_missing(&swapped, 32.0);
    assert!(
        missing.is_empty(),
        "{} of {cast} rays miss after the swap",
        missing.len()
    );
}

/// Horizontal distance from `(x, z)` to chunk `c`'s square (grid unit 1,
/// edge 32).
fn distance_to_chunk(x: f32, z: f32, c: ChunkCoord) -> f32 {
    let gap = |p: f32, i: i64| {
        let (lo, hi) = ((i * 32) as f32, ((i + 1) * 32) as f32);
        (lo - p).max(p - hi).max(0.0)
    };
    gap(x, c.x).hypot(gap(z, c.z))
}

/// Frames (counted in `Last`) in which the world's [`WorldLod`] was marked
/// changed.
#[derive(Resource, Default)]
struct LodChanges(usize);

fn count_lod_changes(changed: Query<(), Changed<WorldLod>>, mut count: ResMut<LodChanges>) {
    if !changed.is_empty() {
        count.0 += 1;
    }
}

fn lod_changes(app: &App) -> usize {
    app.world().resource::<LodChanges>().0
}

fn run_frames(app: &mut App, frames: usize) {
    for _ in 0..frames {
        app.update();
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
}

#[test]
fn a_still_focus_costs_no_pass_over_the_coarse_chunks() {
    let (mut app, world, focus) = app(Vec3::new(16.0, 30.0, 16.0));
    let passes = |app: &App| {
        let lod = app.world().get::<WorldLod>(world).expect("lod");
        lod.stats().full_passes
    };
    app.init_resource::<LodChanges>()
        .add_systems(Last, count_lod_changes);
    // A system's first run sees every component as changed.
    app.update();
    app.world_mut().resource_mut::<LodChanges>().0 = 0;
    let settled = passes(&app);
    assert!(settled > 0);
    run_frames(&mut app, 30);
    assert_eq!(passes(&app), settled, "a still focus: no full pass");
    assert_eq!(lod_changes(&app), 0, "a still focus: `WorldLod` unchanged");

    // A step of 3 (under a quarter of the 32 edge): still none.
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(19.0, 30.0, 16.0);
    run_frames(&mut app, 30);
    assert_eq!(passes(&app), settled, "a small step: no full pass");
    assert_eq!(lod_changes(&app), 0, "a small step: `WorldLod` unchanged");

    // A step of 8.5 from where the last pass looked: a full pass, after
    // which every chunk within the far radius is drawn coarse (but the
    // live one) at the level a fresh choice gives at the new focus, and
    // none beyond the drop distance is kept.
    let (x, z) = (10.0, 10.0);
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation = Vec3::new(x, 30.0, z);
    // (The transform reaches `GlobalTransform` after the pass's frame.)
    run_frames(&mut app, 2);
    assert!(passes(&app) > settled, "a step of a quarter chunk: a pass");
    assert!(lod_changes(&app) > 0, "a pass marks `WorldLod` changed");
    settle(&mut app, world);
    let lod = app.world().get::<WorldLod>(world).expect("lod");
    let settings = lod.settings().clone();
    let view = bevy_chisel::terrain::world::LodView::new(settings.fov_y, settings.viewport_height);
    let mut checked = 0;
    for cx in -4..=4 {
        for cz in -4..=4 {
            let c = ChunkCoord { x: cx, z: cz };
            let d = distance_to_chunk(x, z, c);
            if c == (ChunkCoord { x: 0, z: 0 }) {
                assert!(lod.drawn_level(c).is_none(), "full detail draws (0, 0)");
                continue;
            }
            if d > settings.far_radius * (1.0 + settings.hysteresis) {
                assert!(lod.drawn_level(c).is_none(), "{c:?} at {d} is dropped");
                continue;
            }
            if d > settings.far_radius {
                continue;
            }
            let (level, _) = lod.drawn_level(c).expect("drawn coarse");
            let errors = lod.pyramid(c).expect("built").errors();
            let fresh = bevy_chisel::terrain::world::choose_level(
                &errors,
                d,
                Some(level),
                view,
                settings.pixel_tolerance,
                settings.hysteresis,
            );
            assert_eq!(level, fresh, "{c:?} at {d}");
            checked += 1;
        }
    }
    assert!(checked >= 20, "{checked}");
}

/// Every vertex of every level's meshes has an upward normal, and the
/// vertices at one position share one normal: a skirt's top vertex has
/// the normal of the ground vertex it hangs from. Returns how many
/// vertices met another at their position.
fn assert_skirts_shade_as_the_ground(pyramid: &LodPyramid) -> usize {
    let mut shared = 0;
    for level in &pyramid.levels {
        for (_, mesh) in &level.meshes {
            let attribute = |name| match mesh.try_attribute_option(name) {
                Ok(Some(VertexAttributeValues::Float32x3(values))) => values.clone(),
                _ => panic!("level {}: Float32x3 positions and normals", level.level),
            };
            let normals = attribute(Mesh::ATTRIBUTE_NORMAL);
            let mut at: HashMap<[u32; 3], [f32; 3]> = HashMap::new();
            for (p, n) in attribute(Mesh::ATTRIBUTE_POSITION).iter().zip(&normals) {
                assert!(
                    n[1] > 0.0,
                    "level {}: vertex {p:?} has normal {n:?}",
                    level.level
                );
                if let Some(other) = at.insert(p.map(f32::to_bits), *n) {
                    assert_eq!(other, *n, "level {}: two normals at {p:?}", level.level);
                    shared += 1;
                }
            }
        }
    }
    shared
}

#[test]
fn skirts_shade_as_the_ground_they_hang_from() {
    let (layout, source) = (layout(), source());
    let coord = ChunkCoord { x: 1, z: -2 };
    let unedited = source_pyramid(&layout, &source, coord).expect("source pyramid");
    let world = TerrainWorld::new(layout.clone(), source.clone()).expect("a valid world");
    let chunk = world.generate_chunk(coord).expect("chunk");
    let edited =
        edited_pyramid(&layout, &source, coord, chunk.octree(), 0).expect("edited pyramid");
    for pyramid in [&unedited, &edited] {
        // Skirt tops coincide with ground vertices along all four sides.
        let shared = assert_skirts_shade_as_the_ground(pyramid);
        assert!(shared > 0, "no skirt vertex met a ground vertex");
    }
}
