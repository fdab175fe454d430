//! The surface around border vertices ([`SeamedMesher::with_shading`]):
//! after every edit of a random sequence (meshed from the edits' fresh
//! faces, with undos), the wedges handed back with each leaf's sealed mesh
//! at its border vertices are exactly the merged union of every leaf's own
//! wedges at that point, and those unions equal the ones of a build from
//! scratch (split into other pieces): merged wedges depend on the surface
//! only. The same edits on one and two threads give the same wedges.

use std::collections::BTreeMap;

use crate::common::shapes::{placed_dodecahedron, random_rotation};
use chisel_bsp::exact::{IntPoint, Point4};
use chisel_bsp::mesh::weld::Welder;
use chisel_bsp::mesh::{SurfaceAround, SurfaceMesh, Turn, Wedge, merge_wedges};
use chisel_bsp::octree::{
    CellBox, CellKey, Changes, Edit, Octree, OctreeConfig, SeamedMesher, ShadedCell, Tool,
};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const K: u8 = 12;
const SIZE: i64 = 1 << K;
/// Height of the ground's flat top (on no cell plane).
const GROUND: i64 = SIZE / 2 - 37;

fn terrain() -> Octree {
    let ground = CellBox {
        min: [0; 3],
        max: [SIZE, SIZE, GROUND],
    };
    let config = OctreeConfig {
        max_bsp_nodes: 24,
        max_depth: 6,
    };
    Octree::from_box([0; 3], K, ground, 1, config).unwrap()
}

/// A turned dodecahedron near the ground's top, in the middle of the cube.
fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
    let at = [
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.7),
        rng.random_range(SIZE as f64 * 0.3..SIZE as f64 * 0.7),
        rng.random_range(GROUND as f64 - 200.0..GROUND as f64 + 40.0),
    ];
    let scale = rng.random_range(30.0..160.0);
    let rotation = random_rotation(rng);
    placed_dodecahedron(scale, rotation, at)
}

/// Takes an update's cells into `kept`; how many it handed back.
fn keep(
    kept: &mut BTreeMap<CellKey, ShadedCell>,
    cells: Vec<(CellKey, Option<ShadedCell>)>,
) -> usize {
    let n = cells.len();
    for (key, cell) in cells {
        match cell {
            Some(cell) => {
                kept.insert(key, cell);
            }
            None => {
                kept.remove(&key);
            }
        }
    }
    n
}

/// Per distinct point of the meshes (welded into `welder`), the merged
/// union of the leaves' own wedges there, and how many leaves have it.
fn unions<'a>(
    welder: &mut Welder,
    meshes: impl IntoIterator<Item = &'a SurfaceMesh>,
) -> (Vec<Vec<Wedge>>, Vec<usize>) {
    let (mut wedges, mut leaves): (Vec<Vec<Wedge>>, Vec<usize>) = (Vec::new(), Vec::new());
    for mesh in meshes {
        let own: SurfaceAround = mesh.surface_around();
        for (v, p) in mesh.vertices().iter().enumerate() {
            let at = welder.index(p) as usize;
            if at >= wedges.len() {
                wedges.resize(at + 1, Vec::new());
                leaves.resize(at + 1, 0);
            }
            wedges[at].extend_from_slice(own.of_vertex(v as u32));
            leaves[at] += 1;
        }
    }
    for list in &mut wedges {
        merge_wedges(list);
    }
    (wedges, leaves)
}

/// The kept wedges are the unions at every border vertex, complete (a
/// point of two leaves has them), and the unions equal a build from
/// scratch's wherever both have the point.
fn check(octree: &Octree, kept: &BTreeMap<CellKey, ShadedCell>) -> usize {
    let mut all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    all.sort_unstable();
    assert!(kept.keys().eq(all.iter()), "one kept mesh per leaf");
    let mut welder = Welder::with_capacity(0);
    let (union, leaves) = unions(&mut welder, kept.values().map(|c| &c.mesh));
    let mut checked = 0;
    for (key, cell) in kept {
        for (v, p) in cell.mesh.vertices().iter().enumerate() {
            let at = welder.index(p) as usize;
            let around = cell.around.of_vertex(v as u32);
            if around.is_empty() {
                assert!(
                    leaves[at] < 2 || union[at].is_empty(),
                    "{key:?}: a vertex of {} leaves has no wedges",
                    leaves[at]
                );
                continue;
            }
            assert_eq!(around, union[at].as_slice(), "{key:?} at {:?}", p.to_f64());
            checked += 1;
        }
    }
    let mut scratch = SeamedMesher::with_shading();
    let fresh: Vec<ShadedCell> = scratch
        .update_shaded(octree, all, BTreeMap::new())
        .into_iter()
        .filter_map(|(_, cell)| cell)
        .collect();
    let known = union.len();
    let (again, _) = unions(&mut welder, fresh.iter().map(|c| &c.mesh));
    for (at, list) in again.iter().enumerate().take(known) {
        if !list.is_empty() && leaves[at] > 1 {
            assert_eq!(
                list, &union[at],
                "a union differs from a build from scratch"
            );
        }
    }
    checked
}

/// A random sequence of 40 edits (subtracts, adds, undos) meshed after
/// each, from the edits' faces: the kept cells, the border vertices
/// [`check`]ed after each edit (none unless `checked`) and the undos.
fn edit_sequence(checked: bool) -> (BTreeMap<CellKey, ShadedCell>, usize, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut octree = terrain();
    let mut mesher = SeamedMesher::with_shading();
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    let mut kept = BTreeMap::new();
    keep(
        &mut kept,
        mesher.update_shaded(&octree, all, BTreeMap::new()),
    );
    let check_now = |octree: &Octree, kept: &BTreeMap<CellKey, ShadedCell>| {
        if checked { check(octree, kept) } else { 0 }
    };
    let (mut count, mut undos) = (check_now(&octree, &kept), 0);
    let mut last: Option<(Octree, Changes)> = None;
    for _ in 0..40 {
        if rng.random_range(0..6) == 0
            && let Some((before, changes)) = last.take()
        {
            octree = before;
            let keys = changes.changed.iter().chain(&changes.removed).copied();
            keep(
                &mut kept,
                mesher.update_shaded(&octree, keys, BTreeMap::new()),
            );
            undos += 1;
        } else {
            let edit = if rng.random_range(0..4) == 0 {
                Edit::Add(2)
            } else {
                Edit::Subtract
            };
            let before = octree.clone();
            let tool = random_tool(&mut rng);
            let (changes, faces) = octree.apply_with_faces(&tool, edit).unwrap();
            let keys: Vec<CellKey> = changes
                .changed
                .iter()
                .chain(&changes.removed)
                .copied()
                .collect();
            keep(
                &mut kept,
                mesher.update_shaded(&octree, keys, faces.into_iter().collect()),
            );
            last = Some((before, changes));
        }
        count += check_now(&octree, &kept);
    }
    (kept, count, undos)
}

#[test]
fn border_wedges_are_the_unions_of_every_leaf_and_match_a_fresh_build() {
    let (_, checked, undos) = edit_sequence(true);
    assert!(undos > 0);
    assert!(checked > 1000, "only {checked} border vertices checked");
}

/// The same edits on one and on two threads give the same meshes and the
/// same wedges at every vertex.
#[test]
fn wedges_are_the_same_for_one_and_two_threads() {
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| edit_sequence(false).0)
    };
    let (one, two) = (on(1), on(2));
    assert!(one.keys().eq(two.keys()));
    for (key, a) in &one {
        let b = &two[key];
        let digits = |c: &ShadedCell| -> Vec<_> {
            c.mesh.vertices().iter().map(|p| (p.xyz(), p.w())).collect()
        };
        assert_eq!(digits(a), digits(b), "{key:?}");
        for v in 0..a.mesh.vertices().len() as u32 {
            assert_eq!(
                a.around.of_vertex(v),
                b.around.of_vertex(v),
                "{key:?} vertex {v}"
            );
        }
    }
}

/// A flat top split among four cells: at the point where they meet the
/// top's wedges chain into the whole plane, at a point on the top's edge
/// between two cells into half of it (and the side's into half of its
/// plane), whichever cell is asked.
#[test]
fn wedges_chain_across_cells_into_whole_and_half_planes() {
    let ground = CellBox {
        min: [0, 0, 0],
        max: [64, 64, 40],
    };
    // A budget of 0 splits down to the depth limit: 4 × 4 × 4 cells.
    let config = OctreeConfig {
        max_bsp_nodes: 0,
        max_depth: 2,
    };
    let octree = Octree::from_box([0; 3], 6, ground, 1, config).unwrap();
    let all: Vec<CellKey> = octree.leaves().into_iter().map(|(k, _)| k).collect();
    let cells: Vec<ShadedCell> = SeamedMesher::with_shading()
        .update_shaded(&octree, all, BTreeMap::new())
        .into_iter()
        .filter_map(|(_, cell)| cell)
        .collect();
    let at = |x: i64, y: i64, z: i64| {
        let target = Point4::from(IntPoint::new(x, y, z).unwrap());
        let mut seen = Vec::new();
        for cell in &cells {
            for (v, p) in cell.mesh.vertices().iter().enumerate() {
                if p.same_position(&target) {
                    seen.push(cell.around.of_vertex(v as u32).to_vec());
                }
            }
        }
        assert!(seen.len() > 1, "({x}, {y}, {z}) is shared");
        assert!(seen.windows(2).all(|w| w[0] == w[1]), "every cell agrees");
        seen.swap_remove(0)
    };
    let top = at(32, 32, 40);
    assert_eq!(top.len(), 1);
    assert_eq!((top[0].normal, top[0].turn), ([0, 0, 1], Turn::Full));
    let edge = at(32, 0, 40);
    let turns: Vec<([i64; 3], Turn)> = edge.iter().map(|w| (w.normal, w.turn)).collect();
    assert_eq!(
        turns,
        vec![([0, -1, 0], Turn::Straight), ([0, 0, 1], Turn::Straight)]
    );
}
