//! Seams across the chunk borders of a streamed world: after carves
//! across a border, on the corner line of four chunks and beside a border
//! inside one chunk, the chunks' meshes meet edge to edge (no vertex of
//! one strictly inside an edge of another) and, without the side walls on
//! shared sides, form one closed surface.

use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant};

use bevy::mesh::{Indices, VertexAttributeValues};
use bevy::prelude::*;
use bevy_chisel::bsp::exact::Point4;
use bevy_chisel::bsp::mesh::SurfaceMesh;
use bevy_chisel::bsp::octree::{CellBox, CellKey, Edit, SeamedMesher};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::mesh::{DEFAULT_SMOOTHING_DEGREES, cell_meshes_around, cell_meshes_of};
use bevy_chisel::terrain::{
    CarveTool, ChunkCoord, NoiseOctave, Terrain, TerrainWorld, ValueNoise, WorldLayout, WorldSource,
};

use super::terrain_world::{
    app_with, carve, dodecahedron, layout, settle, terrain, the_world, world,
};

/// A world at rest makes no pass over its seams: 60 still frames after
/// the first chunks, after a carve across a border and after streaming two
/// chunks on; each of those events makes at least one, and every live
/// chunk is given its neighbours' outside points.
#[test]
fn still_frames_make_no_pass_over_the_seams() {
    let (mut app, world, focus) = app_with(world(), Vec3::new(48.0, 20.0, 48.0));
    let passes = |app: &App| the_world(app, world).seam_passes();
    let seamed_every_live_chunk = |app: &App| {
        let w = the_world(app, world);
        w.seamed_chunks() == w.live_chunks().count()
    };
    let still = |app: &mut App| {
        for _ in 0..60 {
            app.update();
        }
    };
    let settled = passes(&app);
    assert!(settled > 0, "the first chunks were stitched");
    assert!(seamed_every_live_chunk(&app));
    still(&mut app);
    assert_eq!(passes(&app), settled, "a still world made a pass");

    // A carve across a border changes both chunks' border points.
    carve(
        &mut app,
        world,
        dodecahedron(3.0, Vec3::new(32.0, 12.0, 40.0)),
    );
    settle(&mut app, world);
    let carved = passes(&app);
    assert!(
        carved > settled,
        "the carve's new border points were stitched"
    );
    still(&mut app);
    assert_eq!(passes(&app), carved, "a still world made a pass");

    // Two chunks on: chunks stream in and out, each new one is seamed.
    app.world_mut()
        .get_mut::<Transform>(focus)
        .expect("focus")
        .translation
        .x += 64.0;
    settle(&mut app, world);
    let moved = passes(&app);
    assert!(moved > carved, "streamed chunks were stitched");
    assert!(seamed_every_live_chunk(&app));
    still(&mut app);
    assert_eq!(passes(&app), moved, "a still world made a pass");
}

#[test]
fn chunks_meet_without_t_junctions_where_four_meet_and_after_carves_beside_a_border() {
    let (mut app, world, _) = app_with(world(), Vec3::new(32.0, 30.0, 32.0));
    let chunk = |x, z| ChunkCoord { x, z };
    // A crater on the corner line x = z = 32, shared by four chunks.
    carve(
        &mut app,
        world,
        dodecahedron(6.0, Vec3::new(32.0, 13.0, 32.0)),
    );
    settle(&mut app, world);
    let check = |app: &App| {
        for (a, b, axis) in [
            (chunk(0, 0), chunk(1, 0), 0),
            (chunk(0, 1), chunk(1, 1), 0),
            (chunk(0, 0), chunk(0, 1), 2),
            (chunk(1, 0), chunk(1, 1), 2),
        ] {
            let found = seam_t_junctions(app, world, a, b, axis, 32.0);
            assert_eq!(found, (0, 0), "T-junctions between {a:?} and {b:?}");
        }
        assert_closed_across(app, world);
    };
    check(&app);
    for c in [chunk(0, 0), chunk(1, 0), chunk(0, 1), chunk(1, 1)] {
        assert_eq!(terrain(&app, world, c).journal().len(), 1, "{c:?}");
    }
    // Small carves beside the sides, each inside one chunk: they split
    // its border cells, and its neighbours are sealed again at the new
    // points.
    for centre in [Vec3::new(30.5, 12.0, 20.0), Vec3::new(34.0, 11.0, 30.0)] {
        carve(&mut app, world, dodecahedron(1.2, centre));
        settle(&mut app, world);
        check(&app);
    }
    assert_eq!(terrain(&app, world, chunk(0, 0)).journal().len(), 2);
    assert_eq!(terrain(&app, world, chunk(1, 0)).journal().len(), 2);
    assert_eq!(terrain(&app, world, chunk(1, 1)).journal().len(), 1);
}

/// Asserts that the cell meshes of all live chunks, without the triangles
/// lying in a side shared by two live chunks (their side walls), are one
/// closed surface: every directed edge (between exact vertices, which
/// round to the same `f32` bits in every cell) is matched by the opposite
/// one. A T-junction across a border leaves edges unmatched.
pub(crate) fn assert_closed_across(app: &App, world: Entity) {
    let w = the_world(app, world);
    let live: BTreeSet<ChunkCoord> = w.live_chunks().map(|(c, _)| c).collect();
    let edge = layout().chunk_edge() as f32;
    // Whether the corners lie in a plane x = c or z = c with live chunks
    // on both sides of it where they are.
    let shared = |t: [[f32; 3]; 3]| {
        [0usize, 2].into_iter().any(|axis| {
            let c = t[0][axis];
            if t.iter().any(|p| p[axis] != c) || (c / edge).fract() != 0.0 {
                return false;
            }
            let other = 2 - axis;
            let mid = (t[0][other] + t[1][other] + t[2][other]) / 3.0;
            let (k, o) = ((c / edge) as i64, (mid / edge).floor() as i64);
            let at = |i: i64| {
                if axis == 0 {
                    ChunkCoord { x: i, z: o }
                } else {
                    ChunkCoord { x: o, z: i }
                }
            };
            live.contains(&at(k - 1)) && live.contains(&at(k))
        })
    };
    let mut edges: std::collections::HashMap<([u32; 3], [u32; 3]), i64> =
        std::collections::HashMap::new();
    let meshes = app.world().resource::<Assets<Mesh>>();
    let mut triangles = 0;
    for (_, entity) in w.live_chunks() {
        let t = app.world().get::<Terrain>(entity).expect("terrain");
        for (_, entities) in t.cells() {
            for e in entities {
                let Some(handle) = app.world().get::<Mesh3d>(e) else {
                    continue;
                };
                let mesh = meshes.get(&handle.0).expect("cell mesh");
                let Ok(Some(VertexAttributeValues::Float32x3(p))) =
                    mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
                else {
                    panic!("cell mesh without positions");
                };
                let Ok(Some(Indices::U32(indices))) = mesh.try_indices_option() else {
                    panic!("cell mesh without u32 indices");
                };
                for tri in indices.chunks_exact(3) {
                    let corners = [0, 1, 2].map(|k| p[tri[k] as usize]);
                    if shared(corners) {
                        continue;
                    }
                    triangles += 1;
                    for k in 0..3 {
                        let (u, v) = (corners[k], corners[(k + 1) % 3]);
                        let (u, v) = (u.map(f32::to_bits), v.map(f32::to_bits));
                        if u < v {
                            *edges.entry((u, v)).or_default() += 1;
                        } else {
                            *edges.entry((v, u)).or_default() -= 1;
                        }
                    }
                }
            }
        }
    }
    let open: Vec<_> = edges.iter().filter(|(_, n)| **n != 0).collect();
    assert!(
        open.is_empty(),
        "{} of {} edges of {triangles} triangles unmatched across the chunks, e.g. {:?}",
        open.len(),
        edges.len(),
        open.first()
            .map(|((u, v), n)| (u.map(f32::from_bits), v.map(f32::from_bits), n))
    );
}

/// The T-junctions across the side shared by chunks `a` and `b`, in the
/// plane `x_axis = plane`: the vertices of each one's border edges
/// strictly inside an edge of the other's ([`t_junctions`], which also
/// checks that every such vertex lies on the other's edges).
pub(crate) fn seam_t_junctions(
    app: &App,
    world: Entity,
    a: ChunkCoord,
    b: ChunkCoord,
    axis: usize,
    plane: f32,
) -> (usize, usize) {
    let (ea, eb) = (
        border_edges(app, world, a, axis, plane),
        border_edges(app, world, b, axis, plane),
    );
    assert!(!ea.is_empty() && !eb.is_empty());
    let found = (t_junctions(&ea, &eb), t_junctions(&eb, &ea));
    println!(
        "chunks {a:?} | {b:?}: {} and {} border edges, {} + {} T-junctions",
        ea.len(),
        eb.len(),
        found.0,
        found.1
    );
    found
}

/// The edges lying in the plane `x_axis = plane` (axis 0 or 2) of a
/// chunk's cell meshes, as segments in the other horizontal coordinate and
/// y, leaving out triangles that lie in the plane (the chunk's side wall):
/// where its surface meets its side.
fn border_edges(
    app: &App,
    world: Entity,
    coord: ChunkCoord,
    axis: usize,
    plane: f32,
) -> Vec<[[f32; 2]; 2]> {
    let other = 2 - axis;
    let meshes = app.world().resource::<Assets<Mesh>>();
    let mut edges = Vec::new();
    for (_, entities) in terrain(app, world, coord).cells() {
        for entity in entities {
            let Some(handle) = app.world().get::<Mesh3d>(entity) else {
                continue;
            };
            let mesh = meshes.get(&handle.0).expect("cell mesh");
            let Ok(Some(VertexAttributeValues::Float32x3(p))) =
                mesh.try_attribute_option(Mesh::ATTRIBUTE_POSITION)
            else {
                panic!("cell mesh without positions");
            };
            let indices: Vec<usize> = match mesh.try_indices_option() {
                Ok(Some(Indices::U16(v))) => v.iter().map(|&i| usize::from(i)).collect(),
                Ok(Some(Indices::U32(v))) => v.iter().map(|&i| i as usize).collect(),
                _ => (0..p.len()).collect(),
            };
            let on = |i: usize| (p[i][axis] - plane).abs() < 1e-4;
            for t in indices.chunks_exact(3) {
                if t.iter().all(|&i| on(i)) {
                    continue;
                }
                for k in 0..3 {
                    let (u, v) = (t[k], t[(k + 1) % 3]);
                    if on(u) && on(v) {
                        edges.push([[p[u][other], p[u][1]], [p[v][other], p[v][1]]]);
                    }
                }
            }
        }
    }
    edges
}

/// Asserts that every endpoint of `mine` lies on an edge of `theirs`, and
/// counts those strictly inside one (T-junctions).
fn t_junctions(mine: &[[[f32; 2]; 2]], theirs: &[[[f32; 2]; 2]]) -> usize {
    let close = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-3;
    let on_segment = |q: [f32; 2], [a, b]: [[f32; 2]; 2]| {
        let (d, e) = ([b[0] - a[0], b[1] - a[1]], [q[0] - a[0], q[1] - a[1]]);
        let len2 = d[0] * d[0] + d[1] * d[1];
        if len2 == 0.0 {
            return close(q, a);
        }
        let t = ((e[0] * d[0] + e[1] * d[1]) / len2).clamp(0.0, 1.0);
        close(q, [a[0] + t * d[0], a[1] + t * d[1]])
    };
    let mut points: Vec<[f32; 2]> = mine.iter().flatten().copied().collect();
    points.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    points.dedup_by(|a, b| close(*a, *b));
    let mut inside = 0;
    for q in points {
        assert!(
            theirs.iter().any(|&e| on_segment(q, e)),
            "border vertex {q:?} lies on no edge of the neighbour"
        );
        if !theirs.iter().flatten().any(|&v| close(q, v)) {
            inside += 1;
        }
    }
    inside
}

/// One chunk of the cost measurement: its octree, mesher and the outside
/// points it was last given.
struct Measured {
    octree: bevy_chisel::bsp::octree::Octree,
    mesher: SeamedMesher,
}

/// The chunk's border points toward every other chunk of `all` it
/// touches, what a job of the chunk hands back ([`SeamedMesher::wall_points_in`]
/// of each neighbour's cube).
fn outside_of(all: &[(ChunkCoord, Measured)], i: usize) -> Vec<Point4> {
    let cube = all[i].1.octree.root_box();
    all.iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .flat_map(|(_, (_, m))| m.mesher.wall_points_in(&m.octree, &cube))
        .collect()
}

/// The chunk's wall points on its sides and corner lines toward each of
/// its eight neighbours, what a job of a world chunk hands back.
fn border_points(m: &Measured) -> Vec<Vec<Point4>> {
    border_regions(&m.octree.root_box())
        .iter()
        .map(|region| m.mesher.wall_points_in(&m.octree, region))
        .collect()
}

/// Render meshes of the sealed cells, as a job builds them.
fn meshes_of(out: &[(CellKey, Option<SurfaceMesh>)], grid: &Quantization) -> usize {
    out.iter()
        .filter_map(|(_, m)| m.as_ref())
        .map(|m| cell_meshes_of(m, grid, DEFAULT_SMOOTHING_DEGREES).len())
        .sum()
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// What stitching adds to a chunk build and to a carve beside a border,
/// in the `world` example's world (1 cm grid, 20.48 m chunks, grass and
/// dirt bands): the steps a chunk's jobs run, through the kernel API, on
/// one thread each, and what the border wedges add with smoothing across
/// chunks. Prints the figures; checks that only a change of points seals
/// again.
#[test]
fn the_cost_of_stitching_chunk_borders() {
    let grid = Quantization::new(0.01, [0.0; 3]).expect("valid unit");
    let octave = |cell, amplitude, seed| NoiseOctave {
        cell,
        amplitude,
        seed,
    };
    let noise = ValueNoise {
        base: 100,
        octaves: vec![octave(24, 650, 1), octave(6, 180, 2)],
    };
    let layout = WorldLayout {
        quantization: grid,
        chunk_log2: 11,
        spacing_log2: 7,
        floor: 0,
        label: 1,
        layers: vec![(120, 2), (25, 3)],
    };
    let source = TerrainWorld::new(layout, noise.clone()).expect("valid layout");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    pool.install(|| {
        // Four chunks around the corner (20.48 m, 20.48 m); (1, 1) comes
        // last.
        let mut chunks: Vec<(ChunkCoord, Measured)> = Vec::new();
        let (mut generate, mut first_mesh) = (Vec::new(), Vec::new());
        for (x, z) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let coord = ChunkCoord { x, z };
            let start = Instant::now();
            let terrain = source.generate_chunk(coord).expect("chunk builds");
            generate.push(ms(start.elapsed()));
            let octree = terrain.octree().clone();
            let keys: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
            let mut mesher = SeamedMesher::new();
            let start = Instant::now();
            let out = mesher.update(&octree, keys, BTreeMap::new());
            meshes_of(&out, &grid);
            first_mesh.push(ms(start.elapsed()));
            chunks.push((coord, Measured { octree, mesher }));
        }
        // Chunk (1, 1) streams in: its border points, its first build with
        // its neighbours' points against one without, and its three
        // neighbours sealed again at its points.
        let last = 3;
        let (mut points, mut with, mut without) = (Vec::new(), Vec::new(), Vec::new());
        let outside = outside_of(&chunks, last);
        let keys: Vec<CellKey> = chunks[last]
            .1
            .octree
            .leaves()
            .into_iter()
            .map(|(k, _)| k)
            .collect();
        for _ in 0..5 {
            let octree = &chunks[last].1.octree;
            let mut plain = SeamedMesher::new();
            let start = Instant::now();
            let out = plain.update(octree, keys.clone(), BTreeMap::new());
            meshes_of(&out, &grid);
            without.push(ms(start.elapsed()));
            let mut stitched = SeamedMesher::new();
            let start = Instant::now();
            stitched.set_outside_points(outside.clone());
            let out = stitched.update(octree, keys.clone(), BTreeMap::new());
            meshes_of(&out, &grid);
            with.push(ms(start.elapsed()));
            let start = Instant::now();
            for (_, m) in &chunks {
                std::hint::black_box(border_points(m));
            }
            points.push(ms(start.elapsed()) / 4.0);
        }
        chunks[last].1.mesher.set_outside_points(outside);
        let m = &mut chunks[last].1;
        let out = m.mesher.update(&m.octree, keys, BTreeMap::new());
        assert!(!out.is_empty());
        let (mut reseal, mut resealed) = (0.0, 0);
        for i in 0..last {
            let outside = outside_of(&chunks, i);
            let m = &mut chunks[i].1;
            let start = Instant::now();
            m.mesher.set_outside_points(outside);
            let out = m.mesher.update(&m.octree, [], BTreeMap::new());
            meshes_of(&out, &grid);
            reseal += ms(start.elapsed());
            resealed += out.len();
        }
        println!(
            "chunk build, one thread: generate median {:.1} ms, first mesh median {:.1} ms; \
             stitching: border points {:.2} ms per chunk, first mesh with outside points {:.1} \
             ms against {:.1} ms without (medians of 5), three neighbours sealed again \
             {reseal:.2} ms ({resealed} cells)",
            median(generate),
            median(first_mesh),
            median(points),
            median(with),
            median(without),
        );
        // The same points again seal nothing.
        let mut given = Vec::new();
        for i in 0..4 {
            let outside = outside_of(&chunks, i);
            let m = &mut chunks[i].1;
            m.mesher.set_outside_points(outside.clone());
            assert!(m.mesher.update(&m.octree, [], BTreeMap::new()).is_empty());
            given.push(outside);
        }

        // Craters (1.6 m) within 2.5 m of the side x = 20.48 m between
        // (0, 0) and (1, 0), some across it.
        let (mut job, mut extra, mut neighbours) = (Vec::new(), Vec::new(), 0);
        for k in 0..24 {
            let x = 20.48 + (k as f32 * 0.37).sin() * 2.5;
            let z = 3.0 + 0.6 * k as f32;
            let ground = noise.height((x / 1.28).round() as i64, (z / 1.28).round() as i64);
            let tool = CarveTool::dodecahedron(1.6, Vec3::new(x, ground as f32 * 0.01, z))
                .to_grid(&grid)
                .and_then(|t| t.build())
                .expect("a tool");
            let (mut carve_ms, mut stitch_ms) = (0.0, 0.0);
            let mut carved = Vec::new();
            for (i, (_, m)) in chunks.iter_mut().enumerate() {
                if !tool.bounds().overlaps(&m.octree.root_box()) {
                    continue;
                }
                let start = Instant::now();
                let (changes, faces) = m
                    .octree
                    .apply_with_faces(&tool, Edit::Subtract)
                    .expect("carve applies");
                let keys: Vec<CellKey> = changes
                    .changed
                    .iter()
                    .chain(&changes.removed)
                    .copied()
                    .collect();
                let out = m
                    .mesher
                    .update(&m.octree, keys, faces.into_iter().collect());
                meshes_of(&out, &grid);
                carve_ms += ms(start.elapsed());
                let start = Instant::now();
                std::hint::black_box(border_points(m));
                stitch_ms += ms(start.elapsed());
                carved.push(i);
            }
            // The neighbours of the carved chunks whose outside points
            // changed, sealed again.
            for i in 0..4 {
                let outside = outside_of(&chunks, i);
                if same_points(&given[i], &outside) {
                    continue;
                }
                given[i].clone_from(&outside);
                let m = &mut chunks[i].1;
                let start = Instant::now();
                m.mesher.set_outside_points(outside);
                let out = m.mesher.update(&m.octree, [], BTreeMap::new());
                meshes_of(&out, &grid);
                stitch_ms += ms(start.elapsed());
                neighbours += 1;
            }
            assert!(!carved.is_empty());
            job.push(carve_ms);
            extra.push(stitch_ms);
        }
        println!(
            "24 craters beside a chunk side, one thread: carve jobs (apply, seal, mesh) median \
             {:.2} ms per crater; stitching (border points, neighbours sealed again, {neighbours} \
             of them) median {:.2} ms per crater",
            median(job),
            median(extra),
        );
        assert!(neighbours > 0, "no carve changed a neighbour's points");

        // With smooth_across_cells: the border wedges every job adds, and
        // the four chunks shaded with their first outside wedges.
        let mut shaded: Vec<(ChunkCoord, Measured)> = Vec::new();
        for (coord, m) in &chunks {
            let octree = m.octree.clone();
            let keys: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
            let mut mesher = SeamedMesher::with_shading();
            mesher.set_outside_points(m.mesher.outside_points().to_vec());
            mesher.update_shaded(&octree, keys, BTreeMap::new());
            shaded.push((*coord, Measured { octree, mesher }));
        }
        let mut wedges = Vec::new();
        for _ in 0..5 {
            let start = Instant::now();
            for (_, m) in &shaded {
                let cube = m.octree.root_box();
                for region in border_regions(&cube) {
                    std::hint::black_box(m.mesher.border_wedges_in(&m.octree, &region));
                }
            }
            wedges.push(ms(start.elapsed()) / 4.0);
        }
        let (mut shade, mut reshaded) = (0.0, 0);
        for i in 0..4 {
            let cube = shaded[i].1.octree.root_box();
            let outside: Vec<_> = shaded
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .flat_map(|(_, (_, m))| m.mesher.border_wedges_in(&m.octree, &cube))
                .collect();
            let m = &mut shaded[i].1;
            let start = Instant::now();
            m.mesher.set_outside_wedges(outside);
            for (_, cell) in m.mesher.update_shaded(&m.octree, [], BTreeMap::new()) {
                let cell = cell.expect("a leaf");
                let built =
                    cell_meshes_around(&cell.mesh, &cell.around, &grid, DEFAULT_SMOOTHING_DEGREES);
                std::hint::black_box(built);
                reshaded += 1;
            }
            shade += ms(start.elapsed());
        }
        println!(
            "smoothing across chunks, one thread: border wedges {:.2} ms per chunk (median of \
             5); four chunks shaded with their first outside wedges {shade:.2} ms ({reshaded} \
             cells)",
            median(wedges),
        );
        assert!(reshaded > 0, "no cell took its neighbours' wedges");
    });
}

/// The sides and corner lines `cube` shares with its eight neighbours.
fn border_regions(cube: &CellBox) -> Vec<CellBox> {
    let mut out = Vec::new();
    for dx in -1..=1i64 {
        for dz in -1..=1i64 {
            if (dx, dz) == (0, 0) {
                continue;
            }
            let mut region = *cube;
            for (axis, d) in [(0, dx), (2, dz)] {
                match d {
                    -1 => region.max[axis] = cube.min[axis],
                    1 => region.min[axis] = cube.max[axis],
                    _ => {}
                }
            }
            out.push(region);
        }
    }
    out
}

/// Whether the lists hold the same points in the same order (what the
/// world compares before it queues a re-seal).
fn same_points(a: &[Point4], b: &[Point4]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| p.same_position(q))
}
