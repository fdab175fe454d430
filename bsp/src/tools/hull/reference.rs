//! The construction of a hull's faces that [`super::polygons`] replaced
//! (coplanar triangles grouped through sorted edge lists, each group's
//! boundary from its sorted edges), kept as the reference its output must
//! equal, face for face, corner for corner, plane for plane.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::incremental::Triangle;
use super::{MAX_HULL_POINTS, Scratch};
use crate::convex::ConvexArena;
use crate::exact::orient::{cross, sub};
use crate::exact::{IntPoint, Plane, Point4};

/// The faces of the hull triangles `faces` (living, in order) as the
/// previous construction made them: vertices (point indices in order of
/// first appearance) and, per face, its plane and corners.
fn reference_polygons(
    pts: &[[i64; 3]],
    faces: &[Triangle],
) -> (Vec<usize>, Vec<(Plane, Vec<u32>)>) {
    let groups = coplanar_groups(pts, faces);
    let mut index_of = vec![u32::MAX; pts.len()];
    let mut used: Vec<usize> = Vec::new();
    let mut polygons: Vec<(Plane, Vec<u32>)> = Vec::with_capacity(groups.len());
    let (mut edges, mut boundary) = (Vec::new(), Vec::new());
    for group in &groups {
        let first = &faces[group[0]];
        let corners: Vec<usize> = if let [_] = group[..] {
            // One triangle: its corners from the smallest.
            let v = first.corners;
            let k = (0..3).min_by_key(|&k| v[k]).unwrap_or(0);
            vec![v[k], v[(k + 1) % 3], v[(k + 2) % 3]]
        } else {
            boundary_loop(pts, faces, group, &mut edges, &mut boundary)
        };
        let loop_ids = corners
            .iter()
            .map(|&c| {
                if index_of[c] == u32::MAX {
                    index_of[c] = used.len() as u32;
                    used.push(c);
                }
                index_of[c]
            })
            .collect();
        polygons.push((first.plane().normalized(), loop_ids));
    }
    (used, polygons)
}

/// The triangles grouped by supporting plane (indices into `faces`), in
/// order of each group's first triangle: neighbours across an edge are
/// joined when the one's far corner lies in the other's plane.
fn coplanar_groups(pts: &[[i64; 3]], faces: &[Triangle]) -> Vec<Vec<usize>> {
    // Directed edges (from, to, triangle), sorted: the neighbour across
    // `(u, w)` holds `(w, u)`.
    let mut ends: Vec<(usize, usize, usize)> = faces
        .iter()
        .enumerate()
        .flat_map(|(t, f)| {
            let v = f.corners;
            [(v[0], v[1], t), (v[1], v[2], t), (v[2], v[0], t)]
        })
        .collect();
    ends.sort_unstable();
    let mut root: Vec<usize> = (0..faces.len()).collect();
    fn find(root: &mut [usize], mut t: usize) -> usize {
        while root[t] != t {
            root[t] = root[root[t]];
            t = root[t];
        }
        t
    }
    for &(u, w, t) in &ends {
        if u > w {
            continue; // each undirected edge once
        }
        let i = ends.partition_point(|&(x, y, _)| (x, y) < (w, u));
        let Some(&(_, _, s)) = ends.get(i).filter(|&&(x, y, _)| (x, y) == (w, u)) else {
            continue;
        };
        let far = faces[s]
            .corners
            .into_iter()
            .find(|&k| k != u && k != w)
            .unwrap_or(u);
        if faces[t].side(pts[far]) == 0 {
            let (rt, rs) = (find(&mut root, t), find(&mut root, s));
            root[rt.max(rs)] = rt.min(rs);
        }
    }
    let mut group_of = vec![usize::MAX; faces.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for t in 0..faces.len() {
        let r = find(&mut root, t);
        if group_of[r] == usize::MAX {
            group_of[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of[r]].push(t);
    }
    groups
}

/// The corners of a group of coplanar triangles: its boundary loop from
/// its smallest vertex, without vertices in the middle of a straight side.
fn boundary_loop(
    pts: &[[i64; 3]],
    faces: &[Triangle],
    group: &[usize],
    edges: &mut Vec<(usize, usize)>,
    boundary: &mut Vec<(usize, usize)>,
) -> Vec<usize> {
    edges.clear();
    edges.extend(group.iter().flat_map(|&t| {
        let v = faces[t].corners;
        [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])]
    }));
    edges.sort_unstable();
    // The group's boundary, sorted by first vertex: one edge leaves each
    // boundary vertex of a convex polygon.
    boundary.clear();
    boundary.extend(
        edges
            .iter()
            .filter(|&&(u, w)| edges.binary_search(&(w, u)).is_err()),
    );
    let after = |v: usize| -> usize {
        let i = boundary
            .binary_search_by_key(&v, |&(u, _)| u)
            .expect("the boundary is a closed loop");
        boundary[i].1
    };
    let start = boundary.first().expect("a face has a boundary").0;
    let mut ring = vec![start];
    let mut v = after(start);
    while v != start {
        ring.push(v);
        v = after(v);
    }
    let n = ring.len();
    (0..n)
        .filter(|&k| {
            let (prev, cur, next) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
            cross(sub(pts[cur], pts[prev]), sub(pts[next], pts[cur])) != [0; 3]
        })
        .map(|k| ring[k])
        .collect()
}

/// Random clouds: small grids (many coplanar and collinear points),
/// spheres and wide random clouds.
fn random_cloud(rng: &mut ChaCha8Rng, round: usize) -> Vec<IntPoint> {
    let n = rng.random_range(4..120);
    let pts: Vec<[i64; 3]> = match round % 4 {
        0 => (0..n)
            .map(|_| [0; 3].map(|_| rng.random_range(-3..=3)))
            .collect(),
        1 => (0..n)
            .map(|_| {
                let (u, v): (f64, f64) = (rng.random(), rng.random());
                let (t, z) = (u * std::f64::consts::TAU, 2.0 * v - 1.0);
                let r = (1.0 - z * z).sqrt() * 1e6;
                [r * t.cos(), r * t.sin(), z * 1e6].map(|x| x.round() as i64)
            })
            .collect(),
        // A prism swept along a step (the shape of a swept cutter): large
        // coplanar faces with many collinear points.
        2 => {
            let sides = rng.random_range(3..24);
            let step = [0; 3].map(|_| rng.random_range(-2000..=2000));
            let mut pts = Vec::new();
            for k in 0..sides {
                let t = k as f64 * std::f64::consts::TAU / sides as f64;
                let c = [3000.0 * t.cos(), 3000.0 * t.sin()].map(|x| x.round() as i64);
                for (s, h) in [(0, 0), (1, 0), (0, 5000), (1, 5000)] {
                    pts.push([c[0] + s * step[0], c[1] + s * step[1], h + s * step[2]]);
                }
            }
            pts
        }
        _ => (0..n)
            .map(|_| [0; 3].map(|_| rng.random_range(-(1 << 26)..=1 << 26)))
            .collect(),
    };
    pts.into_iter()
        .map(|p| IntPoint::from_array(p).expect("in budget"))
        .collect()
}

#[test]
fn faces_by_adjacency_equal_the_sorted_construction() {
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let mut scratch = Scratch::default();
    let mut compared = 0;
    for round in 0..400 {
        let points = random_cloud(&mut rng, round);
        if scratch.hull(&points).is_err() {
            continue;
        }
        compared += 1;
        let pts = &scratch.pts;
        assert!(pts.len() <= MAX_HULL_POINTS);
        let living: Vec<Triangle> = scratch
            .incremental
            .faces
            .iter()
            .filter(|f| f.alive)
            .copied()
            .collect();
        let (used, polygons) = reference_polygons(pts, &living);
        let hull = &scratch.polygons;
        let vertices: Vec<[i64; 3]> = used.iter().map(|&i| pts[i]).collect();
        assert_eq!(hull.vertices, vertices, "round {round}");
        assert_eq!(hull.face_count(), polygons.len(), "round {round}");
        for (f, (plane, corners)) in polygons.iter().enumerate() {
            assert_eq!(hull.planes[f], *plane, "round {round}, face {f}");
            assert_eq!(hull.face(f), &corners[..], "round {round}, face {f}");
        }
        // Neighbours and the breadth-first order, against the arena's.
        let mut arena = ConvexArena::new();
        let poly = super::add_polygons(&mut arena, hull);
        arena.validate(poly).expect("a valid polyhedron");
        // The same half-edges as pairing the sides by sorting.
        let mut sorted = ConvexArena::new();
        let points: Vec<_> = hull
            .vertices
            .iter()
            .map(|&p| Point4::from(IntPoint::from_array(p).expect("in budget")))
            .collect();
        sorted.add_polyhedron(&points, &polygons);
        assert_eq!(
            format!("{:?}", arena.half_edges()),
            format!("{:?}", sorted.half_edges()),
            "round {round}"
        );
        let arena_faces = arena.faces_of(poly);
        let first_face = arena_faces.iter().min().copied().unwrap_or(0);
        let order: Vec<u32> = arena_faces.iter().map(|&f| f - first_face).collect();
        assert_eq!(hull.breadth_first, order, "round {round}");
        for f in 0..hull.face_count() {
            let across: Vec<u32> = arena
                .face_loop(first_face + f as u32)
                .map(|h| {
                    let twin = arena.half_edges()[h as usize].twin;
                    arena.half_edges()[twin as usize].face - first_face
                })
                .collect();
            assert_eq!(hull.face_across(f), &across[..], "round {round}, face {f}");
        }
    }
    assert!(compared > 300, "{compared} hulls compared");
}
