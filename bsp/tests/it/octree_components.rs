//! Solid components against a brute-force reference: every pair of convex
//! solid cells of the octree is tested for a shared face of positive area
//! directly (two coplanar, opposite faces whose polygons overlap: no edge
//! line of either has the other's corners all on its outer side, decided
//! with exact classification), the pairs are joined with union–find, and
//! the partition and the anchoring (a face on the bottom of the cube) must
//! be those of [`Octree::solid_components`]. Random scenes of boxes and
//! tilted hulls, on small budgets, so that many leaves of different sizes
//! meet along their walls.

use std::collections::BTreeMap;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::exact::{IntPoint, Plane, Point4, Sign, classify_vertex};
use chisel_bsp::octree::{Anchors, CellBox, Edit, Octree, OctreeConfig, SolidCell, Tool};
use chisel_bsp::tree::EMPTY;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 9;
const SIZE: i64 = 1 << K;

/// One face of a cell: its plane and corners, and the planes of the faces
/// across its edges (its edge lines within its plane).
struct Face {
    plane: Plane,
    corners: Vec<Point4>,
    edges: Vec<Plane>,
}

struct RefCell {
    id: SolidCell,
    bounds: CellBox,
    faces: Vec<Face>,
}

fn faces_of(arena: &ConvexArena, poly: PolyId) -> Vec<Face> {
    arena
        .faces_of(poly)
        .into_iter()
        .map(|f| {
            let halves: Vec<u32> = arena.face_loop(f).collect();
            Face {
                plane: *arena.face_plane(f),
                corners: halves
                    .iter()
                    .map(|&h| *arena.point(arena.half_edges()[h as usize].origin))
                    .collect(),
                edges: halves
                    .iter()
                    .map(|&h| {
                        let twin = arena.half_edges()[h as usize].twin;
                        *arena.face_plane(arena.half_edges()[twin as usize].face)
                    })
                    .collect(),
            }
        })
        .collect()
}

fn cells(octree: &Octree) -> Vec<RefCell> {
    let mut out = Vec::new();
    for (key, leaf) in octree.leaves() {
        let bounds = octree.cell_box(key);
        let mut arena = ConvexArena::new();
        let root = bounds.add_to(&mut arena).unwrap();
        for c in leaf.to_bsp().cells(&mut arena, root) {
            if c.label != EMPTY {
                out.push(RefCell {
                    id: SolidCell { key, node: c.leaf },
                    bounds,
                    faces: faces_of(&arena, c.poly),
                });
            }
        }
    }
    out
}

/// Whether `q`'s corners all lie on the closed outer side of some edge
/// line of `p` (the polygons' interiors are then disjoint).
fn separated_by_edges_of(p: &Face, q: &Face) -> bool {
    p.edges.iter().any(|e| {
        q.corners
            .iter()
            .all(|c| classify_vertex(c, e) != Sign::Negative)
    })
}

/// Whether the faces are coplanar, opposite and overlap with positive area.
fn share_area(a: &Face, b: &Face) -> bool {
    let (na, nb) = (a.plane.normal(), b.plane.normal());
    let cross = [
        i128::from(na[1]) * i128::from(nb[2]) - i128::from(na[2]) * i128::from(nb[1]),
        i128::from(na[2]) * i128::from(nb[0]) - i128::from(na[0]) * i128::from(nb[2]),
        i128::from(na[0]) * i128::from(nb[1]) - i128::from(na[1]) * i128::from(nb[0]),
    ];
    let dot: i128 = (0..3).map(|i| i128::from(na[i]) * i128::from(nb[i])).sum();
    if cross != [0; 3] || dot >= 0 {
        return false;
    }
    if b.corners
        .iter()
        .any(|c| classify_vertex(c, &a.plane) != Sign::Zero)
    {
        return false;
    }
    !separated_by_edges_of(a, b) && !separated_by_edges_of(b, a)
}

fn find(parent: &mut [usize], i: usize) -> usize {
    let mut r = i;
    while parent[r] != r {
        r = parent[r];
    }
    let mut i = i;
    while parent[i] != r {
        let next = parent[i];
        parent[i] = r;
        i = next;
    }
    r
}

/// The components as sorted cell lists, each with whether a cell has a
/// face on the bottom of the cube.
fn reference_components(octree: &Octree) -> Vec<(Vec<SolidCell>, bool)> {
    let cells = cells(octree);
    let mut parent: Vec<usize> = (0..cells.len()).collect();
    for i in 0..cells.len() {
        for j in i + 1..cells.len() {
            if !cells[i].bounds.touches(&cells[j].bounds) {
                continue;
            }
            let adjacent = cells[i]
                .faces
                .iter()
                .any(|a| cells[j].faces.iter().any(|b| share_area(a, b)));
            if adjacent {
                let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                parent[ri] = rj;
            }
        }
    }
    let bottom = Plane::new(0, -1, 0, 0).unwrap();
    let mut groups: BTreeMap<usize, (Vec<SolidCell>, bool)> = BTreeMap::new();
    for (i, cell) in cells.iter().enumerate() {
        let root = find(&mut parent, i);
        let group = groups.entry(root).or_default();
        group.0.push(cell.id);
        group.1 |= cell.faces.iter().any(|f| {
            f.plane.normal() == [0, -1, 0]
                && f.corners
                    .iter()
                    .all(|c| classify_vertex(c, &bottom) == Sign::Zero)
        });
    }
    let mut out: Vec<(Vec<SolidCell>, bool)> = groups
        .into_values()
        .map(|(mut cells, anchored)| {
            cells.sort_unstable();
            (cells, anchored)
        })
        .collect();
    out.sort();
    out
}

fn random_box(rng: &mut ChaCha8Rng, size: std::ops::Range<i64>) -> CellBox {
    let mut min = [0; 3];
    let mut max = [0; 3];
    for a in 0..3 {
        let e = rng.random_range(size.clone());
        // Often on a multiple of 32, so that boxes meet along leaf walls.
        let at = rng.random_range(0..SIZE - e);
        min[a] = if rng.random_bool(0.5) {
            at / 32 * 32
        } else {
            at
        };
        max[a] = min[a] + e;
    }
    CellBox { min, max }
}

fn random_hull(rng: &mut ChaCha8Rng) -> Tool {
    let c = [0; 3].map(|_| rng.random_range(60..SIZE - 60));
    let points: Vec<IntPoint> = (0..7)
        .map(|_| {
            let q = c.map(|x| x + rng.random_range(-50..=50));
            IntPoint::new(q[0], q[1], q[2]).unwrap()
        })
        .collect();
    Tool::convex_hull(&points).unwrap()
}

#[test]
fn components_match_the_brute_force_reference() {
    let anchors = Anchors::default();
    let (mut compared, mut split, mut unanchored) = (0, 0, 0);
    for seed in 0..6 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let config = OctreeConfig {
            max_bsp_nodes: [6, 12, 30][seed as usize % 3],
            max_depth: 5,
        };
        let mut octree = Octree::new([0; 3], K, EMPTY, config).unwrap();
        for i in 0..14 {
            let (tool, edit) = match i % 4 {
                3 => (random_hull(&mut rng), Edit::Subtract),
                2 => (
                    Tool::cuboid(random_box(&mut rng, 16..120)).unwrap(),
                    Edit::Subtract,
                ),
                _ => (
                    Tool::cuboid(random_box(&mut rng, 32..200)).unwrap(),
                    Edit::Add(rng.random_range(1..=3)),
                ),
            };
            octree.apply(&tool, edit).unwrap();
            if i % 2 == 1 {
                let mut ours: Vec<(Vec<SolidCell>, bool)> = octree
                    .solid_components(&anchors)
                    .into_iter()
                    .map(|c| (c.cells, c.anchored))
                    .collect();
                ours.sort();
                let reference = reference_components(&octree);
                assert_eq!(ours, reference, "seed {seed}, edit {i}");
                compared += 1;
                split += usize::from(reference.len() > 1);
                unanchored += reference.iter().filter(|c| !c.1).count();
            }
        }
    }
    assert!(
        compared == 42 && split > 10 && unanchored > 10,
        "{split} {unanchored}"
    );
}
