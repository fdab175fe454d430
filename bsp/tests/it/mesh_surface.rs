//! Surface meshes of BSP boundaries (§3.4, T-junction removal): after
//! welding and T-junction splitting every boundary is watertight (and
//! before splitting it often is not), the polygons and the triangles
//! enclose exactly the BSP's volume, no triangle has zero area, and the
//! result is deterministic.

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::exact::{IntPoint, Point4};
use chisel_bsp::mesh::{EdgeProblem, SurfaceMesh, TriangleMesh};
use chisel_bsp::tools::convex_hull;
use chisel_bsp::tree::{BooleanOp, BoundaryFace, Bsp, EMPTY, Label};
use common::backends::to_big;
use common::shapes::{self, p};
use common::surface::{H, boundary, bounds, box_bsp, corners, merge, polygons_volume_of};
use common::volume::{Fraction, polygons_volume, volume};
use num_bigint::BigInt;
use num_traits::Signed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const CUTS: usize = 5;

/// The exact volume of the BSP's solid (all materials) inside the bounds.
fn solid_volume(bsp: &Bsp) -> Fraction {
    let mut arena = ConvexArena::new();
    let bd = bounds(&mut arena);
    let mut total = Fraction::zero();
    for cell in bsp.cells(&mut arena, bd) {
        if cell.label != EMPTY {
            total = total.add(&volume(&arena, cell.poly));
        }
    }
    total
}

/// The exact volume enclosed by the triangles.
fn triangles_volume(mesh: &SurfaceMesh, triangles: &TriangleMesh) -> Fraction {
    let polygons: Vec<Vec<Point4>> = triangles.indices.iter().map(|t| corners(mesh, t)).collect();
    polygons_volume(&polygons)
}

/// `W`-scaled homogeneous coordinates as big integers.
fn big(v: &Point4) -> ([BigInt; 3], BigInt) {
    let [x, y, z] = v.xyz();
    (
        [to_big(&x.limbs()), to_big(&y.limbs()), to_big(&z.limbs())],
        to_big(&v.w().limbs()),
    )
}

/// Asserts, exactly, that every triangle has non-zero area and turns
/// counter-clockwise around its polygon's outward normal: with
/// `u = X₁W₀ − X₀W₁` and `v = X₂W₀ − X₀W₂` (the edge vectors times
/// `W₀W₁ > 0` and `W₀W₂ > 0`), `(u × v)·n > 0`.
fn assert_triangles_proper(mesh: &SurfaceMesh, triangles: &TriangleMesh) {
    for (t, tri) in triangles.indices.iter().enumerate() {
        let [(x0, w0), (x1, w1), (x2, w2)] = tri.map(|v| big(&mesh.vertices()[v as usize]));
        let u: Vec<BigInt> = (0..3).map(|i| &x1[i] * &w0 - &x0[i] * &w1).collect();
        let v: Vec<BigInt> = (0..3).map(|i| &x2[i] * &w0 - &x0[i] * &w2).collect();
        let cross = [
            &u[1] * &v[2] - &u[2] * &v[1],
            &u[2] * &v[0] - &u[0] * &v[2],
            &u[0] * &v[1] - &u[1] * &v[0],
        ];
        let plane = mesh.polygons()[triangles.polygons[t] as usize].plane;
        let n = plane.normal().map(BigInt::from);
        let dot = &cross[0] * &n[0] + &cross[1] * &n[1] + &cross[2] * &n[2];
        assert!(
            dot.is_positive(),
            "triangle {t} {tri:?} is degenerate or flipped"
        );
    }
}

/// What every boundary surface of a manifold solid must satisfy; returns
/// whether the welded mesh (before T-junction splitting) was already
/// closed.
fn check_surface(bsp: &Bsp, what: &str) -> bool {
    check_surface_of(bsp, what, Manifold::Yes)
}

/// Whether a solid may touch itself along edges (then its surface is closed
/// but not manifold there).
#[derive(Clone, Copy, PartialEq)]
enum Manifold {
    Yes,
    Maybe,
}

fn check_surface_of(bsp: &Bsp, what: &str, manifold: Manifold) -> bool {
    let faces = boundary(bsp);
    let mesh = SurfaceMesh::from_faces(&faces);
    mesh.validate().unwrap_or_else(|e| panic!("{what}: {e}"));
    if let Err(e) = mesh.check_closed() {
        panic!("{what}: not closed: {e}");
    }
    match mesh.check_watertight() {
        Ok(()) => {}
        Err(e) if manifold == Manifold::Maybe && e.open == 0 && e.opposite_repeated == 0 => {}
        Err(e) => panic!("{what}: {e}"),
    }
    let welded_ok = SurfaceMesh::welded(&faces).check_closed().is_ok();

    let expected = solid_volume(bsp);
    assert_eq!(
        polygons_volume_of(&mesh),
        expected,
        "{what}: polygon volume"
    );
    let triangles = mesh.triangles();
    let corner_count: usize = mesh.polygons().iter().map(|p| p.corners.len() - 2).sum();
    assert_eq!(
        triangles.len(),
        corner_count,
        "{what}: m − 2 triangles per polygon"
    );
    assert_eq!(triangles.normals.len(), triangles.len());
    assert_eq!(triangles.labels.len(), triangles.len());
    assert_eq!(triangles.positions.len(), mesh.vertices().len());
    assert_triangles_proper(&mesh, &triangles);
    assert_eq!(
        triangles_volume(&mesh, &triangles),
        expected,
        "{what}: triangle volume"
    );
    assert_triangle_mesh_closed(&triangles, what);

    // Deterministic: the same faces give the identical mesh.
    let again = SurfaceMesh::from_faces(&boundary(bsp));
    assert_eq!(again.polygons(), mesh.polygons(), "{what}: determinism");
    assert_eq!(again.triangles(), triangles, "{what}: determinism");
    // Splitting is idempotent.
    let mut twice = mesh.clone();
    twice.split_t_junctions();
    assert_eq!(twice.polygons(), mesh.polygons(), "{what}: idempotence");
    welded_ok
}

/// Every directed triangle edge is used as often as its opposite (once,
/// unless the solid touches itself along that edge).
fn assert_triangle_mesh_closed(triangles: &TriangleMesh, what: &str) {
    let mut edges = std::collections::HashMap::new();
    for t in &triangles.indices {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(u, v), &n) in &edges {
        assert_eq!(
            edges.get(&(v, u)),
            Some(&n),
            "{what}: triangle edge {u}->{v} open"
        );
    }
}

#[test]
fn a_box_with_a_half_height_box_beside_it_needs_t_junction_splitting() {
    let a = box_bsp([0, 0, 0], [10, 10, 10], 1);
    let b = box_bsp([10, 0, 0], [20, 5, 10], 1);
    let union = merge(&a, &b, BooleanOp::Union);
    let faces = boundary(&union);
    let welded = SurfaceMesh::welded(&faces);
    let err = welded.check_watertight().unwrap_err();
    assert!(err.open > 0, "{err}");
    assert_eq!(err.example.problem, EdgeProblem::Open);
    assert!(err.to_string().contains("not watertight"), "{err}");
    assert!(!check_surface(&union, "L-shaped union"));
    // The corners (10, 5, 0) and (10, 5, 10) become corners of the big
    // box's faces z = 0 and z = 10 (and nothing else is inserted).
    let mesh = SurfaceMesh::from_faces(&faces);
    let inserted: usize = mesh
        .polygons()
        .iter()
        .map(|p| p.corners.len() - p.original_len())
        .sum();
    assert!(inserted >= 2, "{inserted} corners inserted");
    assert_eq!(polygons_volume_of(&mesh).num, 1500.into());
}

#[test]
fn random_convex_solids_and_their_booleans_are_watertight_with_exact_volume() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let convex =
        |rng: &mut ChaCha8Rng| shapes::random_convex_bsp(rng, 1, H / 4, (H / 8, H / 3), CUTS);
    let mut cases = 0;
    let mut needed_splitting = 0;
    for _ in 0..80 {
        let (a, b) = (convex(&mut rng), convex(&mut rng));
        check_surface(&a, "a convex solid");
        cases += 1;
        for op in [
            BooleanOp::Union,
            BooleanOp::Difference,
            BooleanOp::Intersection,
        ] {
            let result = merge(&a, &b, op);
            if !check_surface(&result, &format!("{op:?}")) {
                needed_splitting += 1;
            }
            cases += 1;
        }
    }
    assert!(
        needed_splitting > 0,
        "{needed_splitting} of {cases} cases needed T-junction splitting"
    );
}

#[test]
fn boolean_sequences_stay_watertight() {
    let mut rng = ChaCha8Rng::seed_from_u64(32);
    for round in 0..12 {
        let mut solid = box_bsp([-H / 2; 3], [H / 2; 3], 1);
        for step in 0..6 {
            let tool = shapes::random_convex_bsp(&mut rng, 1, H / 2, (H / 10, H / 4), CUTS);
            let op = if rng.random_bool(0.7) {
                BooleanOp::Difference
            } else {
                BooleanOp::Union
            };
            solid = merge(&solid, &tool, op);
            check_surface(&solid, &format!("round {round}, step {step}, {op:?}"));
        }
    }
}

#[test]
fn axis_aligned_boxes_with_shared_faces_are_watertight() {
    // Boxes on a coarse integer grid share faces, edges and corners in all
    // ways, the hardest case for T-junctions; they may touch along edges
    // only, where the surface is closed but not manifold.
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    let mut needed_splitting = 0;
    for round in 0..60 {
        let mut solid = Bsp::uniform(EMPTY);
        for _ in 0..5 {
            let min = [0; 3].map(|_| rng.random_range(-4..3i64) * 1000);
            let max = min.map(|m| m + rng.random_range(1..4i64) * 1000);
            let op = if rng.random_bool(0.75) {
                BooleanOp::Union
            } else {
                BooleanOp::Difference
            };
            solid = merge(&solid, &box_bsp(min, max, 1), op);
        }
        if !check_surface_of(&solid, &format!("box round {round}"), Manifold::Maybe) {
            needed_splitting += 1;
        }
    }
    assert!(needed_splitting > 0);
}

/// The faces of `poly` (integer vertices) as a fan-triangulated soup.
fn soup(arena: &ConvexArena, poly: PolyId) -> Vec<[IntPoint; 3]> {
    let mut out = Vec::new();
    for f in arena.faces_of(poly) {
        let corners: Vec<IntPoint> = arena
            .face_loop(f)
            .map(|h| {
                let [x, y, z] = arena.position(arena.half_edges()[h as usize].origin);
                p(x as i64, y as i64, z as i64)
            })
            .collect();
        for k in 1..corners.len() - 1 {
            out.push([corners[0], corners[k], corners[k + 1]]);
        }
    }
    out
}

#[test]
fn imported_triangle_soups_and_their_booleans_are_watertight() {
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    for round in 0..10 {
        let r = H / 3;
        let points: Vec<IntPoint> = (0..20)
            .map(|_| {
                p(
                    rng.random_range(-r..r),
                    rng.random_range(-r..r),
                    rng.random_range(-r..r),
                )
            })
            .collect();
        let mut arena = ConvexArena::new();
        let hull = convex_hull(&mut arena, &points).unwrap();
        let imported = Bsp::from_triangles(&soup(&arena, hull), 1, round).unwrap();
        check_surface(&imported, "imported hull");
        let tool = shapes::random_convex_bsp(&mut rng, 1, H / 4, (H / 8, H / 4), CUTS);
        let carved = merge(&imported, &tool, BooleanOp::Difference);
        check_surface(&carved, "imported hull minus a tool");
    }
}

#[test]
fn two_materials_have_a_watertight_outer_surface() {
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    for round in 0..30 {
        let a = shapes::random_convex_bsp(&mut rng, 1, H / 4, (H / 8, H / 3), CUTS);
        let b = shapes::random_convex_bsp(&mut rng, 2, H / 4, (H / 8, H / 3), CUTS);
        let both = merge(&a, &b, BooleanOp::Union);
        let faces = boundary(&both);
        let mut mesh = SurfaceMesh::from_faces(&faces);
        mesh.validate().unwrap();
        let interfaces = mesh
            .polygons()
            .iter()
            .filter(|p| p.outside != EMPTY)
            .count();
        let triangles = mesh.triangles();
        let visible = triangles.without_interfaces();
        assert!(visible.outside.iter().all(|&o| o == EMPTY));
        assert_eq!(
            visible.len(),
            triangles.outside.iter().filter(|&&o| o == EMPTY).count()
        );
        mesh.retain(|p| p.outside == EMPTY);
        mesh.check_watertight()
            .unwrap_or_else(|e| panic!("round {round} ({interfaces} interfaces): {e}"));
        assert_eq!(polygons_volume_of(&mesh), solid_volume(&both));
        let labels: std::collections::BTreeSet<Label> =
            mesh.polygons().iter().map(|p| p.label).collect();
        assert!(labels.iter().all(|&l| l == 1 || l == 2));
    }
}

#[test]
fn solids_cut_by_the_bounds_are_closed_by_faces_on_the_bounds() {
    let solid = box_bsp([-2 * H, -H / 2, -H / 2], [0, H / 2, H / 2], 1);
    let slab = box_bsp([-H / 4, -2 * H, -H / 4], [H / 4, 2 * H, H / 4], 1);
    let union = merge(&solid, &slab, BooleanOp::Union);
    check_surface(&union, "solid through the bounds");
    let mesh = SurfaceMesh::from_faces(&boundary(&union));
    assert!(mesh.polygons().iter().any(|p| p.on_bounds));
    let triangles = mesh.triangles();
    assert!(triangles.on_bounds.iter().any(|&b| b));
    check_surface(&Bsp::uniform(3), "all solid");
}

#[test]
fn flat_shading_duplicates_vertices_with_face_normals() {
    let a = box_bsp([0, 0, 0], [10, 10, 10], 1);
    let b = box_bsp([10, 0, 0], [20, 5, 10], 1);
    let mesh = SurfaceMesh::from_faces(&boundary(&merge(&a, &b, BooleanOp::Union)));
    let triangles = mesh.triangles();
    let flat = triangles.flat_shaded();
    assert_eq!(flat.len(), triangles.len());
    assert_eq!(flat.positions.len(), 3 * triangles.len());
    assert_eq!(flat.normals.len(), 3 * triangles.len());
    for (t, tri) in triangles.indices.iter().enumerate() {
        for (k, &v) in tri.iter().enumerate() {
            assert_eq!(flat.positions[3 * t + k], triangles.positions[v as usize]);
            assert_eq!(flat.normals[3 * t + k], triangles.normals[t]);
        }
        // Axis-aligned faces: the normal is a signed unit axis.
        let n = triangles.normals[t];
        assert_eq!(n.iter().map(|c| c.abs()).sum::<f32>(), 1.0);
    }
}

#[test]
fn missing_and_doubled_polygons_are_reported() {
    let faces = boundary(&box_bsp([0, 0, 0], [10, 10, 10], 1));
    let mut mesh = SurfaceMesh::from_faces(&faces);
    mesh.check_watertight().unwrap();

    let mut doubled = faces.clone();
    doubled.push(faces[0].clone());
    let err = SurfaceMesh::from_faces(&doubled)
        .check_watertight()
        .unwrap_err();
    assert_eq!(err.repeated, 4, "{err}");
    assert_eq!(err.example.problem, EdgeProblem::Repeated);

    let mut first = true;
    mesh.retain(|_| !std::mem::take(&mut first));
    let err = mesh.check_watertight().unwrap_err();
    assert_eq!((err.open, err.repeated), (4, 0), "{err}");
    let [a, b] = [err.example.from_position, err.example.to_position];
    assert!(a.iter().chain(&b).all(|c| *c == 0.0 || *c == 10.0), "{err}");
}

/// The boundary faces of `bsp` extracted separately in the eight octants of
/// the bounds, as an octree of cells would: each cell's faces are cut by
/// its own BSP cells, so the assembled surface has T-junctions across cell
/// borders.
fn octant_faces(bsp: &Bsp) -> Vec<BoundaryFace> {
    let mut faces = Vec::new();
    for octant in 0..8 {
        let lo = [0, 1, 2].map(|i| if octant >> i & 1 == 0 { -H } else { 0 });
        let hi = lo.map(|l| l + H);
        let mut arena = ConvexArena::new();
        let cell = arena
            .add_box(p(lo[0], lo[1], lo[2]), p(hi[0], hi[1], hi[2]))
            .unwrap();
        faces.extend(bsp.boundary(&mut arena, cell));
    }
    faces
}

#[test]
fn faces_from_octree_cells_weld_into_one_watertight_surface() {
    let mut rng = ChaCha8Rng::seed_from_u64(36);
    let mut needed_splitting = 0;
    for round in 0..25 {
        let a = shapes::random_convex_bsp(&mut rng, 1, H / 4, (H / 8, H / 3), CUTS);
        let b = shapes::random_convex_bsp(&mut rng, 1, H / 4, (H / 8, H / 3), CUTS);
        let op = [BooleanOp::Union, BooleanOp::Difference][round % 2];
        let solid = merge(&a, &b, op);
        let what = format!("round {round}, {op:?} in octants");
        let faces = octant_faces(&solid);
        // With the faces on the cell borders the surface is closed (four
        // polygons meet where it crosses a border); without them it is the
        // solid's own, manifold surface.
        let mesh = SurfaceMesh::from_faces(&faces);
        mesh.validate().unwrap_or_else(|e| panic!("{what}: {e}"));
        mesh.check_closed()
            .unwrap_or_else(|e| panic!("{what}: not closed: {e}"));
        assert_eq!(polygons_volume_of(&mesh), solid_volume(&solid), "{what}");
        let mut surface = mesh.clone();
        surface.retain(|p| !p.on_bounds);
        surface
            .check_watertight()
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(polygons_volume_of(&surface), solid_volume(&solid), "{what}");
        let triangles = surface.triangles();
        assert_triangles_proper(&surface, &triangles);
        assert_triangle_mesh_closed(&triangles, &what);
        assert_eq!(
            triangles_volume(&surface, &triangles),
            solid_volume(&solid),
            "{what}"
        );

        let mut welded = SurfaceMesh::welded(&faces);
        welded.retain(|p| !p.on_bounds);
        if welded.check_watertight().is_err() {
            needed_splitting += 1;
        }
    }
    assert!(needed_splitting > 0, "no case had T-junctions across cells");
}

/// An octree whose upper part is repainted: its surface (interfaces
/// reported once) is not closed as one mesh, but every material's region
/// is, and is watertight; dropping one polygon opens a region.
#[test]
fn every_material_region_of_a_painted_octree_is_closed() {
    use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
    let block = CellBox {
        min: [0; 3],
        max: [1000; 3],
    };
    let mut octree = Octree::from_box([0; 3], 11, block, 1, OctreeConfig::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for label in 2..6 {
        let min = [0; 3].map(|_: i64| rng.random_range(-200..800));
        let max = min.map(|m| m + rng.random_range(100..600));
        let paint = Tool::cuboid(CellBox { min, max }).unwrap();
        octree.apply(&paint, Edit::Paint(label)).unwrap();
    }
    let mut mesh = SurfaceMesh::from_faces(&octree.surface());
    let interfaces = mesh
        .polygons()
        .iter()
        .filter(|p| p.outside != EMPTY)
        .count();
    assert!(interfaces > 0);
    assert!(mesh.check_closed().is_err(), "interfaces are reported once");
    mesh.check_regions_closed().unwrap();
    mesh.check_regions_watertight().unwrap();
    let mut first = true;
    mesh.retain(|_| !std::mem::take(&mut first));
    assert!(mesh.check_regions_closed().is_err());
}
