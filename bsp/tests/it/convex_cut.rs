//! Cutting convex polyhedra by planes: every edge-descent cut is compared
//! element for element with the classify-all-vertices cut, its outcome is
//! checked against exact classification of the vertices, and every part is
//! validated (closed, consistent, strictly convex) after every cut.

use crate::common;

use chisel_bsp::convex::{ConvexArena, CutOutcome, KeptOutcome, NO_TAG, Part, PolyId};
use chisel_bsp::exact::{IntPoint, Plane, Sign, classify_vertex, plane_from_points};
use common::volume::volume;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn p(x: i64, y: i64, z: i64) -> IntPoint {
    IntPoint::new(x, y, z).unwrap()
}

fn unit_box(arena: &mut ConvexArena, size: i64) -> PolyId {
    arena.add_box(p(0, 0, 0), p(size, size, size)).unwrap()
}

fn sides(arena: &ConvexArena, poly: PolyId, s: &Plane) -> Vec<Sign> {
    arena
        .vertices_of(poly)
        .iter()
        .map(|&v| classify_vertex(arena.point(v), s))
        .collect()
}

/// Cuts, then checks the outcome against the vertices' sides and validates
/// the parts; returns the parts that have volume.
fn checked_cut(arena: &mut ConvexArena, poly: PolyId, s: &Plane) -> Vec<PolyId> {
    let before = sides(arena, poly, s);
    let volume_before = volume(arena, poly);
    let mut reference = arena.clone();
    let one_sided = [Part::Below, Part::Above].map(|part| {
        let mut copy = arena.clone();
        let kept = copy.cut_keeping(poly, s, part, NO_TAG);
        (copy, kept)
    });
    let expected = reference.cut_naive(poly, s, NO_TAG, NO_TAG);
    let outcome = arena.cut(poly, s, NO_TAG, NO_TAG);
    assert_eq!(outcome, expected, "edge descent and classify-all disagree");
    assert_same_arena(arena, &reference);
    assert_one_sided_cuts_agree(arena, outcome, &one_sided);
    let has = |x| before.contains(&x);
    match outcome {
        CutOutcome::Above => {
            assert!(!has(Sign::Negative));
            arena.validate(poly).unwrap();
            vec![poly]
        }
        CutOutcome::Below => {
            assert!(!has(Sign::Positive));
            arena.validate(poly).unwrap();
            vec![poly]
        }
        CutOutcome::Split { below, above } => {
            assert!(has(Sign::Negative) && has(Sign::Positive));
            arena
                .validate(below)
                .unwrap_or_else(|e| panic!("below part: {e}"));
            arena
                .validate(above)
                .unwrap_or_else(|e| panic!("above part: {e}"));
            assert!(sides(arena, below, s).iter().all(|&x| x != Sign::Positive));
            assert!(sides(arena, above, s).iter().all(|&x| x != Sign::Negative));
            assert!(sides(arena, below, s).contains(&Sign::Negative));
            assert!(sides(arena, above, s).contains(&Sign::Positive));
            // Volume is conserved exactly, and both parts have some.
            let (vb, va) = (volume(arena, below), volume(arena, above));
            assert!(vb.is_positive() && va.is_positive());
            assert_eq!(
                vb.add(&va),
                volume_before,
                "the parts' volumes add up exactly"
            );
            // The parts share no vertex.
            let a = arena.vertices_of(below);
            assert!(arena.vertices_of(above).iter().all(|v| !a.contains(v)));
            vec![below, above]
        }
    }
}

/// Each one-sided cut has the outcome of the two-sided cut and builds the
/// same part, element for element once extracted.
fn assert_one_sided_cuts_agree(
    arena: &ConvexArena,
    outcome: CutOutcome,
    one_sided: &[(ConvexArena, KeptOutcome); 2],
) {
    for (k, (copy, kept)) in one_sided.iter().enumerate() {
        match (outcome, *kept) {
            (CutOutcome::Below, KeptOutcome::Below) | (CutOutcome::Above, KeptOutcome::Above) => {}
            (CutOutcome::Split { below, above }, KeptOutcome::Cut(id)) => {
                copy.validate(id)
                    .unwrap_or_else(|e| panic!("one-sided part {k}: {e}"));
                let part = [below, above][k];
                let (a, ia) = copy.extract(id);
                let (b, ib) = arena.extract(part);
                assert_eq!(ia, ib);
                assert_same_arena(&a, &b);
            }
            _ => panic!("one-sided cut {k}: {kept:?}, two-sided: {outcome:?}"),
        }
    }
}

/// Element-for-element equality of two arenas.
fn assert_same_arena(a: &ConvexArena, b: &ConvexArena) {
    assert_eq!(a.half_edges(), b.half_edges());
    assert_eq!(a.faces().len(), b.faces().len());
    for (f, (x, y)) in (0..).zip(a.faces().iter().zip(b.faces())) {
        assert_eq!((x.half_edge, x.tag), (y.half_edge, y.tag));
        assert_eq!(a.face_plane(f), b.face_plane(f));
    }
    assert_eq!(a.vertex_count(), b.vertex_count());
    for v in 0..a.vertex_count() as u32 {
        assert_eq!(a.vertex_half_edge(v), b.vertex_half_edge(v));
        let (x, y) = (a.point(v), b.point(v));
        assert!(x.xyz() == y.xyz() && x.w() == y.w());
    }
}

#[test]
fn a_box_is_a_valid_polyhedron() {
    let mut arena = ConvexArena::new();
    let b = unit_box(&mut arena, 10);
    arena.validate(b).unwrap();
    assert_eq!(volume(&arena, b).num, 1000.into());
    assert_eq!(arena.faces_of(b).len(), 6);
    assert_eq!(arena.vertices_of(b).len(), 8);
    assert!(arena.add_box(p(0, 0, 0), p(0, 1, 1)).is_err());
}

#[test]
fn extracting_a_part_gives_the_same_polyhedron_compactly() {
    let (arena, parts) = random_cuts(5, 60);
    for &part in &parts {
        let (copy, id) = arena.extract(part);
        copy.validate(id).unwrap();
        assert_eq!(copy.faces().len(), arena.faces_of(part).len());
        assert_eq!(copy.vertex_count(), arena.vertices_of(part).len());
        let planes = |a: &ConvexArena, p: PolyId| {
            let mut v: Vec<_> = a
                .faces_of(p)
                .iter()
                .map(|&f| a.face_plane(f).normal())
                .collect();
            v.sort();
            v
        };
        assert_eq!(planes(&copy, id), planes(&arena, part));
    }
}

#[test]
fn an_axis_plane_halves_a_box() {
    let mut arena = ConvexArena::new();
    let b = unit_box(&mut arena, 10);
    let s = Plane::new(1, 0, 0, -4).unwrap();
    let parts = checked_cut(&mut arena, b, &s);
    assert_eq!(parts.len(), 2);
    for part in parts {
        assert_eq!(arena.faces_of(part).len(), 6);
        assert_eq!(arena.vertices_of(part).len(), 8);
    }
}

#[test]
fn planes_touching_a_box_do_not_cut_it() {
    let mut arena = ConvexArena::new();
    let b = unit_box(&mut arena, 10);
    // Coplanar with a face, through an edge, through a corner, outside.
    for s in [
        Plane::new(0, 0, 1, -10).unwrap(),
        Plane::new(0, 0, -1, 0).unwrap(),
        Plane::new(1, 1, 0, -20).unwrap(),
        Plane::new(1, 1, 1, -30).unwrap(),
        Plane::new(1, 1, 1, 1).unwrap(),
    ] {
        let parts = checked_cut(&mut arena, b, &s);
        assert_eq!(parts, vec![b]);
    }
}

#[test]
fn a_diagonal_plane_through_two_edges_splits_into_prisms() {
    let mut arena = ConvexArena::new();
    let b = unit_box(&mut arena, 10);
    // x = y contains the edges (0,0,z) and (10,10,z).
    let s = plane_from_points(p(0, 0, 0), p(0, 0, 10), p(10, 10, 0)).unwrap();
    let parts = checked_cut(&mut arena, b, &s);
    assert_eq!(parts.len(), 2);
    for part in parts {
        assert_eq!(arena.faces_of(part).len(), 5, "a triangular prism");
        assert_eq!(arena.vertices_of(part).len(), 6);
    }
}

#[test]
fn a_corner_cut_gives_a_tetrahedron() {
    let mut arena = ConvexArena::new();
    let b = unit_box(&mut arena, 10);
    let s = Plane::new(1, 1, 1, -5).unwrap();
    let parts = checked_cut(&mut arena, b, &s);
    let tet = parts[0];
    let v = volume(&arena, tet);
    assert_eq!((v.num, v.den), (125.into(), 6.into()), "5³/6");
    assert_eq!(arena.faces_of(tet).len(), 4);
    assert_eq!(arena.vertices_of(tet).len(), 4);
    assert_eq!(arena.faces_of(parts[1]).len(), 7);
}

/// Hundreds of random cuts, many through existing vertices and edges, each
/// part validated after every cut.
#[test]
fn random_cut_sequences_keep_every_part_valid() {
    for seed in 0..12 {
        let (arena, parts) = random_cuts(seed, 200);
        assert!(
            parts.len() > 50,
            "most cuts split something: {} parts",
            parts.len()
        );
        assert!(!arena.faces().is_empty());
    }
}

/// Same cuts, same arena, bit for bit.
#[test]
fn cutting_is_deterministic() {
    let (a, pa) = random_cuts(99, 120);
    let (b, pb) = random_cuts(99, 120);
    assert_eq!(pa, pb);
    assert_same_arena(&a, &b);
}

/// Applies `steps` random cuts to random parts of a box, checking each.
fn random_cuts(seed: u64, steps: usize) -> (ConvexArena, Vec<PolyId>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let size = 1 << 20;
    {
        let mut arena = ConvexArena::new();
        let mut parts = vec![unit_box(&mut arena, size)];
        for _ in 0..steps {
            let k = rng.random_range(0..parts.len());
            let poly = parts.swap_remove(k);
            // Through three points: random ones, or the polyhedron's own
            // vertices (rounded), which produces plenty of degenerate cuts.
            let verts = arena.vertices_of(poly);
            let pick = |rng: &mut ChaCha8Rng| -> IntPoint {
                if rng.random_bool(0.5) {
                    let v = verts[rng.random_range(0..verts.len())];
                    let [x, y, z] = arena.position(v);
                    p(x.round() as i64, y.round() as i64, z.round() as i64)
                } else {
                    p(
                        rng.random_range(0..=size),
                        rng.random_range(0..=size),
                        rng.random_range(0..=size),
                    )
                }
            };
            let (a, b, c) = (pick(&mut rng), pick(&mut rng), pick(&mut rng));
            let Ok(s) = plane_from_points(a, b, c) else {
                parts.push(poly);
                continue;
            };
            parts.extend(checked_cut(&mut arena, poly, &s.normalized()));
        }
        (arena, parts)
    }
}

/// A box's corners are exactly the points where the planes of its three
/// sides meet (`intersect_3_planes`), and the box is a valid polyhedron,
/// for random boxes up to the coordinate budget.
#[test]
fn box_corners_are_the_exact_meets_of_its_side_planes() {
    use chisel_bsp::exact::budget::MAX_COORD;
    use chisel_bsp::exact::intersect_3_planes;
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    for case in 0..200 {
        let limit = if case % 2 == 0 { MAX_COORD } else { 1000 };
        let (mut lo, mut hi) = ([0i64; 3], [0i64; 3]);
        for a in 0..3 {
            let (u, w) = (
                rng.random_range(-limit..=limit),
                rng.random_range(-limit..=limit),
            );
            (lo[a], hi[a]) = (u.min(w), u.max(w));
            if lo[a] == hi[a] {
                lo[a] -= 1;
            }
        }
        let mut arena = ConvexArena::new();
        let poly = arena
            .add_box(p(lo[0], lo[1], lo[2]), p(hi[0], hi[1], hi[2]))
            .unwrap();
        arena.validate(poly).unwrap();
        let side = |axis: usize, upper: bool| {
            let mut n = [0i64; 3];
            n[axis] = if upper { 1 } else { -1 };
            let d = if upper { -hi[axis] } else { lo[axis] };
            Plane::new(n[0], n[1], n[2], i128::from(d)).unwrap()
        };
        let vertices = arena.vertices_of(poly);
        assert_eq!(vertices.len(), 8);
        for v in vertices {
            let at = arena.position(v);
            let upper = [0, 1, 2].map(|a| at[a] == hi[a] as f64);
            let expected =
                intersect_3_planes(&side(0, upper[0]), &side(1, upper[1]), &side(2, upper[2]))
                    .unwrap();
            let got = arena.point(v);
            assert_eq!(
                (got.xyz(), got.w(), got.approx().map(f64::to_bits)),
                (
                    expected.xyz(),
                    expected.w(),
                    expected.approx().map(f64::to_bits)
                ),
                "case {case}: {lo:?} {hi:?}"
            );
        }
    }
}
