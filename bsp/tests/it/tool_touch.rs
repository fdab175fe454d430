//! The exact contact test between a closed tool and a closed box
//! ([`Tool::touches`]): contact at a vertex, along an edge or on a face
//! counts, one grid unit away does not; on random small cases it agrees
//! with a brute-force reference that enumerates the candidate vertices of
//! the intersection (every triple of the tool's and the box's planes).

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::octree::{CellBox, Tool};
use chisel_bsp::tools::{Pose, convex_hull, dodecahedron_corners};
use common::shapes::p;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn cell(min: [i64; 3], max: [i64; 3]) -> CellBox {
    CellBox { min, max }
}

fn shifted(b: CellBox, axis: usize, by: i64) -> CellBox {
    let mut out = b;
    out.min[axis] += by;
    out.max[axis] += by;
    out
}

fn tetrahedron() -> Tool {
    Tool::convex_hull(&[p(0, 0, 0), p(4, 0, 0), p(0, 4, 0), p(0, 0, 4)]).unwrap()
}

#[test]
fn a_tetrahedron_touching_at_a_vertex_an_edge_and_a_face() {
    let t = tetrahedron();
    // Vertex (4, 0, 0), from the outer orthant; one unit further in x,
    // apart.
    let vertex = cell([4, -2, -2], [6, 0, 0]);
    assert!(t.touches(&vertex));
    assert!(!t.touches(&shifted(vertex, 0, 1)));
    // The slanted face x + y + z = 4 at the box corner (1, 1, 2).
    let face = cell([1, 1, 2], [3, 3, 4]);
    assert!(t.touches(&face));
    assert!(!t.touches(&shifted(face, 2, 1)));
    // The face z = 0 over a square.
    let bottom = cell([1, 1, -3], [2, 2, 0]);
    assert!(t.touches(&bottom));
    assert!(!t.touches(&shifted(bottom, 2, -1)));
    // The edge from (4, 0, 0) to (0, 4, 0) at the box corner (2, 2, 0).
    // One unit away in x, no face plane of the tetrahedron and no box axis
    // separates them: only the axis (edge × ẑ) = (1, 1, 0) does.
    let edge = cell([2, 2, -2], [4, 4, 0]);
    assert!(t.touches(&edge));
    let apart = shifted(edge, 0, 1);
    assert!(t.bounds().touches(&apart));
    assert!(!t.touches(&apart));
    // Inside, and around.
    assert!(t.touches(&cell([1, 1, 1], [1, 1, 1])));
    assert!(t.touches(&cell([-9, -9, -9], [9, 9, 9])));
}

/// The tool's hull in an arena, for its exact planes and vertices.
fn hull(points: &[[i64; 3]]) -> (ConvexArena, PolyId) {
    let mut arena = ConvexArena::new();
    let points: Vec<_> = points.iter().map(|&[x, y, z]| p(x, y, z)).collect();
    let poly = convex_hull(&mut arena, &points).unwrap();
    (arena, poly)
}

fn integer_vertices(arena: &ConvexArena, poly: PolyId) -> Vec<[i64; 3]> {
    arena
        .vertices_of(poly)
        .into_iter()
        .map(|v| {
            let point = arena.point(v);
            let w = point.w().to_i128().unwrap();
            point.xyz().map(|x| {
                let x = x.to_i128().unwrap();
                assert_eq!(x % w, 0, "hull vertices are integer points");
                i64::try_from(x / w).unwrap()
            })
        })
        .collect()
}

fn dot(u: [i64; 3], x: [i64; 3]) -> i128 {
    (0..3).map(|a| i128::from(u[a]) * i128::from(x[a])).sum()
}

/// Every supporting axis `u` of the hull (face normals, and edge
/// directions crossed with the box axes): the box with a corner at a
/// vertex maximising `u·x`, extending away along `u`, touches the tool;
/// the same box one unit further along an axis where `u` is non-zero does
/// not.
fn check_supporting_boxes(points: &[[i64; 3]]) -> usize {
    let (arena, poly) = hull(points);
    let tool = Tool::from_polyhedron(&arena, poly);
    let vertices = integer_vertices(&arena, poly);
    let mut axes: Vec<[i64; 3]> = arena
        .faces_of(poly)
        .into_iter()
        .map(|f| arena.face_plane(f).normal())
        .collect();
    for f in arena.faces_of(poly) {
        for h in arena.face_loop(f) {
            let from = arena.point(arena.half_edges()[h as usize].origin);
            let to = arena.point(arena.dest(h));
            let (from, to) = (position(from), position(to));
            let e = [0, 1, 2].map(|a| to[a] - from[a]);
            axes.extend([[0, e[2], -e[1]], [-e[2], 0, e[0]], [e[1], -e[0], 0]]);
        }
    }
    axes.retain(|u| *u != [0; 3]);
    let k = 3;
    for u in &axes {
        let top = vertices.iter().max_by_key(|v| dot(*u, **v)).unwrap();
        let mut b = cell(*top, *top);
        for (a, &c) in u.iter().enumerate() {
            if c >= 0 {
                b.max[a] += k;
            }
            if c <= 0 {
                b.min[a] -= k;
            }
        }
        assert!(tool.touches(&b), "{u:?}: {b:?} touches at {top:?}");
        for a in (0..3).filter(|&a| u[a] != 0) {
            let away = shifted(b, a, u[a].signum());
            assert!(!tool.touches(&away), "{u:?}: {away:?} is apart");
        }
    }
    axes.len()
}

fn position(point: &chisel_bsp::exact::Point4) -> [i64; 3] {
    let w = point.w().to_i128().unwrap();
    point
        .xyz()
        .map(|x| i64::try_from(x.to_i128().unwrap() / w).unwrap())
}

#[test]
fn boxes_on_every_supporting_axis_touch_and_one_unit_away_do_not() {
    let tetra = [[0, 0, 0], [4, 0, 0], [0, 4, 0], [0, 0, 4]];
    assert!(check_supporting_boxes(&tetra) > 4);
    let pose = Pose::at([100.0, -50.0, 30.0]);
    let dodeca: Vec<[i64; 3]> = dodecahedron_corners(40.0)
        .into_iter()
        .map(|c| pose.place(c).unwrap().coords())
        .collect();
    assert!(check_supporting_boxes(&dodeca) > 12);
}

/// Brute force: the closed polyhedra `{n·x + d ≤ 0}` (the tool's face
/// planes and the box's six) meet exactly when the intersection, bounded
/// by the box, has a vertex: a point where three planes with independent
/// normals meet that satisfies every inequality (exact, by Cramer's rule).
fn reference_touches(arena: &ConvexArena, poly: PolyId, b: &CellBox) -> bool {
    let mut planes: Vec<([i128; 3], i128)> = arena
        .faces_of(poly)
        .into_iter()
        .map(|f| {
            let plane = arena.face_plane(f);
            (plane.normal().map(i128::from), plane.offset())
        })
        .collect();
    for a in 0..3 {
        let mut n = [0; 3];
        n[a] = -1;
        planes.push((n, i128::from(b.min[a])));
        n[a] = 1;
        planes.push((n, -i128::from(b.max[a])));
    }
    let det = |m: [[i128; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let len = planes.len();
    for i in 0..len {
        for j in i + 1..len {
            for k in j + 1..len {
                let rows = [planes[i], planes[j], planes[k]];
                let w = det(rows.map(|r| r.0));
                if w == 0 {
                    continue;
                }
                // x = X / w with X_c the determinant with column c
                // replaced by −d.
                let x: [i128; 3] = [0, 1, 2].map(|c| {
                    det(rows.map(|r| {
                        let mut row = r.0;
                        row[c] = -r.1;
                        row
                    }))
                });
                let sign = w.signum();
                if planes
                    .iter()
                    .all(|(n, d)| sign * (n[0] * x[0] + n[1] * x[1] + n[2] * x[2] + d * w) <= 0)
                {
                    return true;
                }
            }
        }
    }
    false
}

#[test]
fn random_small_tools_and_boxes_agree_with_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let (mut touching, mut apart, mut only_exact) = (0, 0, 0);
    for case in 0..300 {
        let points: Vec<[i64; 3]> = (0..rng.random_range(4..9))
            .map(|_| [0; 3].map(|_| rng.random_range(0..7)))
            .collect();
        let mut arena = ConvexArena::new();
        let ints: Vec<_> = points.iter().map(|&[x, y, z]| p(x, y, z)).collect();
        let Ok(poly) = convex_hull(&mut arena, &ints) else {
            continue;
        };
        let tool = Tool::from_polyhedron(&arena, poly);
        for _ in 0..8 {
            let min = [0; 3].map(|_| rng.random_range(-2..8));
            let max = [0, 1, 2].map(|a| min[a] + rng.random_range(0..4));
            let b = cell(min, max);
            let expected = reference_touches(&arena, poly, &b);
            assert_eq!(tool.touches(&b), expected, "case {case}: {points:?} {b:?}");
            if expected {
                touching += 1;
            } else {
                apart += 1;
                only_exact += usize::from(tool.bounds().touches(&b));
            }
        }
    }
    assert!(touching > 300 && apart > 300, "{touching} / {apart}");
    assert!(
        only_exact > 100,
        "{only_exact} boxes only the exact test rules out"
    );
}

#[test]
fn a_union_touches_where_one_of_its_pieces_does() {
    let a = tetrahedron();
    let b = Tool::cuboid(cell([10, 0, 0], [12, 2, 2])).unwrap();
    let both = Tool::union(&[a.clone(), b.clone()]).unwrap();
    let boxes = [
        cell([4, -2, -2], [6, 0, 0]),
        cell([5, -2, -2], [7, 0, 0]),
        cell([12, 2, 2], [13, 3, 3]),
        cell([13, 2, 2], [14, 3, 3]),
        cell([6, 1, 1], [8, 2, 2]),
        cell([9, 1, 1], [9, 2, 2]),
        cell([10, 1, 1], [10, 2, 2]),
    ];
    let mut seen = [false; 2];
    for bx in &boxes {
        let expected = a.touches(bx) || b.touches(bx);
        assert_eq!(both.touches(bx), expected, "{bx:?}");
        seen[usize::from(expected)] = true;
    }
    assert_eq!(seen, [true, true]);
    // Between the pieces, inside the union's bounds.
    assert!(both.bounds().touches(&boxes[4]) && !both.touches(&boxes[4]));
}
