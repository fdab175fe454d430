//! Checks of an input triangle mesh before import (paper 1 §4.6: import
//! is exact only for closed meshes without self-intersections).
//!
//! Notation: `orient` — the exact sign of a tetrahedron's volume
//! ([`crate::exact::orient`]); a triangle is *proper* when its corners are
//! not collinear. Two proper triangles may share a corner or an edge (as
//! neighbours in a mesh do) and must meet nowhere else:
//! - sharing an edge, they meet elsewhere only if coplanar and on the same
//!   side of it;
//! - sharing one corner `v`, they meet elsewhere exactly when the edge of
//!   one opposite `v` meets the other triangle (the two triangles cut the
//!   line where their planes meet in segments starting at `v`, and the
//!   shorter one ends on an opposite edge inside the other triangle);
//! - sharing nothing, they meet exactly when an edge of one meets the
//!   other.
//!
//! Candidate pairs come from a uniform grid over the triangles' bounding
//! boxes; every decision is exact.
//!
//! Nesting: a *shell* is a set of triangles connected through edges, with
//! `s = sign(6V)` its orientation (+1 outward, −1 a cavity). The winding
//! number `w(p)` of the other shells around a point `p` of a shell is the
//! signed count of their triangles crossed by the ray from `p` along +x,
//! exact under the symbolic perturbation `p + (ε³, ε, ε²)` (simulation of
//! simplicity), so rays through edges and corners need no special case.
//! The mesh bounds a solid exactly when every point has winding number 0
//! or 1: an outward shell must have `w = 0`, a cavity `w = 1`. Shells
//! nested with the same orientation give 2 inside the inner one, where the
//! even-odd and nonzero readings of the mesh disagree.

use std::collections::HashMap;

use super::cell::CellBox;
use crate::Error;
use crate::exact::IntPoint;
use crate::exact::orient::{cross, orient, orient_2d, sub};

type P = [i64; 3];

/// Checks that every directed edge is used as often as its opposite, every
/// corner lies in `cube`, and no two triangles intersect improperly.
///
/// # Errors
/// [`Error::OutsideOctree`], [`Error::NotWatertight`],
/// [`Error::InsideOut`] or [`Error::SelfIntersecting`].
pub(crate) fn check_mesh(triangles: &[[IntPoint; 3]], cube: &CellBox) -> Result<(), Error> {
    check_closed(triangles, cube)?;
    let tris: Vec<[P; 3]> = triangles
        .iter()
        .map(|t| t.map(|p| p.coords()))
        .filter(|c| c[0] != c[1] && c[1] != c[2] && c[2] != c[0])
        .collect();
    let shells = shells(&tris);
    check_orientation(&shells)?;
    if let Some((i, j)) = first_intersection(triangles) {
        return Err(Error::SelfIntersecting {
            triangles: [i, j],
            corners: Box::new([
                triangles[i].map(|p| p.coords()),
                triangles[j].map(|p| p.coords()),
            ]),
        });
    }
    check_nesting(&tris, &shells)
}

/// Triangles connected through edges, with 6 × their signed volume and
/// their box.
struct Shell {
    six_volume: i128,
    lo: P,
    hi: P,
    triangles: Vec<usize>,
}

/// The shells of `tris` (each triangle's corners distinct), in the order
/// of their first triangle.
fn shells(tris: &[[P; 3]]) -> Vec<Shell> {
    let six_volume = |t: &[P; 3]| -> i128 {
        let [a, b, c] = t.map(|p| p.map(i128::from));
        let bc = [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ];
        a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]
    };
    // Union–find over triangles sharing an edge.
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first_on_edge: HashMap<(P, P), usize> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            let edge = (u.min(v), u.max(v));
            let j = *first_on_edge.entry(edge).or_insert(i);
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            parent[a.max(b)] = a.min(b);
        }
    }
    let mut index: HashMap<usize, usize> = HashMap::new();
    let mut shells: Vec<Shell> = Vec::new();
    for (i, t) in tris.iter().enumerate() {
        let root = find(&mut parent, i);
        let (lo, hi) = bounds(t);
        let k = *index.entry(root).or_insert_with(|| {
            shells.push(Shell {
                six_volume: 0,
                lo,
                hi,
                triangles: Vec::new(),
            });
            shells.len() - 1
        });
        let shell = &mut shells[k];
        shell.six_volume += six_volume(t);
        shell.lo = [0, 1, 2].map(|a| shell.lo[a].min(lo[a]));
        shell.hi = [0, 1, 2].map(|a| shell.hi[a].max(hi[a]));
        shell.triangles.push(i);
    }
    shells
}

fn check_closed(triangles: &[[IntPoint; 3]], cube: &CellBox) -> Result<(), Error> {
    let mut edges: HashMap<(P, P), u32> = HashMap::new();
    for t in triangles {
        let c = t.map(|p| p.coords());
        if c[0] == c[1] || c[1] == c[2] || c[2] == c[0] {
            continue;
        }
        for p in c {
            if (0..3).any(|a| p[a] < cube.min[a] || p[a] > cube.max[a]) {
                return Err(Error::OutsideOctree { point: p });
            }
        }
        for k in 0..3 {
            *edges.entry((c[k], c[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let mut open: Vec<(P, P)> = edges
        .iter()
        .filter(|&(&(a, b), &n)| edges.get(&(b, a)) != Some(&n))
        .map(|(&e, _)| e)
        .collect();
    if open.is_empty() {
        return Ok(());
    }
    open.sort_unstable();
    Err(Error::NotWatertight {
        open_edges: open.len(),
        example: [open[0].0, open[0].1],
    })
}

/// Checks the orientation of a closed mesh from exact signed volumes
/// (`6V = Σ a · (b × c)` over its triangles, exact in `i128`: each term is
/// below `3·2^26·2^53 < 2^81`). The whole mesh must enclose a positive
/// volume, and each shell with a negative volume — a cavity — must lie
/// inside the box of a shell with a positive one. Exact nesting is decided
/// later ([`check_nesting`]), once the shells are known not to cross.
fn check_orientation(shells: &[Shell]) -> Result<(), Error> {
    let total: i128 = shells.iter().map(|s| s.six_volume).sum();
    let inside_out = |six: i128, shell: &str| Error::InsideOut {
        volume: six as f64 / 6.0,
        shell: shell.to_string(),
    };
    if total < 0 {
        return Err(inside_out(total, "the mesh as a whole"));
    }
    let mut roots: Vec<(i128, P, P)> = shells.iter().map(|s| (s.six_volume, s.lo, s.hi)).collect();
    roots.sort_unstable();
    for (six, lo, hi) in roots.iter().filter(|s| s.0 < 0) {
        let held = roots
            .iter()
            .any(|(v, l, h)| *v > 0 && (0..3).all(|a| l[a] <= lo[a] && hi[a] <= h[a]));
        if !held {
            return Err(inside_out(
                *six,
                &format!("a shell from {lo:?} to {hi:?}, inside no outward shell"),
            ));
        }
    }
    Ok(())
}

/// Checks that the shells, which cross nowhere, nest as the boundary of a
/// solid: each outward shell inside no other (winding number 0), each
/// cavity directly inside an outward shell (winding number 1); see the
/// module notes. The point tested on a shell is the centroid of one of its
/// proper triangles, which no other shell meets (triangles sharing an edge
/// are in one shell, and shells cross nowhere); coordinates are scaled by
/// 3 to keep it on the grid.
///
/// # Errors
/// [`Error::MisnestedShell`] for the first shell (in triangle order) that
/// breaks the rule.
fn check_nesting(tris: &[[P; 3]], shells: &[Shell]) -> Result<(), Error> {
    if shells.len() < 2 {
        return Ok(());
    }
    let scaled = |p: P| p.map(|c| 3 * i128::from(c));
    for (j, shell) in shells.iter().enumerate() {
        if shell.six_volume == 0 {
            continue;
        }
        let Some(t) = shell
            .triangles
            .iter()
            .map(|&i| &tris[i])
            .find(|t| cross(sub(t[1], t[0]), sub(t[2], t[0])) != [0; 3])
        else {
            continue;
        };
        let p: [i128; 3] =
            [0, 1, 2].map(|a| i128::from(t[0][a]) + i128::from(t[1][a]) + i128::from(t[2][a]));
        let mut winding = 0i64;
        for (i, other) in shells.iter().enumerate() {
            let (lo, hi) = (scaled(other.lo), scaled(other.hi));
            if i == j || !(0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a]) {
                continue;
            }
            for &k in &other.triangles {
                winding += i64::from(ray_crossing(p, tris[k].map(scaled)));
            }
        }
        let expected = if shell.six_volume > 0 { 0 } else { 1 };
        if winding != expected {
            return Err(Error::MisnestedShell {
                volume: shell.six_volume as f64 / 6.0,
                winding,
                shell: format!("the shell from {:?} to {:?}", shell.lo, shell.hi),
            });
        }
    }
    Ok(())
}

/// The signed crossing of the ray from `p + (ε³, ε, ε²)` along +x with
/// triangle `t`: +1 where the ray leaves through its outer side, −1 where
/// it enters, 0 where it misses. Exact in `i128`: scaled coordinates below
/// 2^29 give differences below 2^30, normals below 2^61 and the plane
/// test below 2^93.
fn ray_crossing(p: [i128; 3], t: [[i128; 3]; 3]) -> i8 {
    let [a, b, c] = t;
    let (u, v) = (
        [0, 1, 2].map(|k| b[k] - a[k]),
        [0, 1, 2].map(|k| c[k] - a[k]),
    );
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    // Parallel to the ray: never crossed by the perturbed ray.
    if n[0] == 0 {
        return 0;
    }
    // First non-zero term of a sign under the perturbation.
    let sign = |terms: [i128; 3]| terms.into_iter().find(|&x| x != 0).map_or(0, i128::signum);
    // Orientation of the perturbed point against edge (e, f) in the
    // y-z plane: (f − e) × (p + (ε, ε²) − e), expanded in ε.
    let edge = |e: [i128; 3], f: [i128; 3]| {
        let (dy, dz) = (f[1] - e[1], f[2] - e[2]);
        sign([dy * (p[2] - e[2]) - dz * (p[1] - e[1]), -dz, dy])
    };
    let sides = [edge(a, b), edge(b, c), edge(c, a)];
    if sides[0] != sides[1] || sides[1] != sides[2] {
        return 0;
    }
    // Which side of the plane the perturbed point lies on; the ray meets
    // the plane ahead of it when that side is the one −x points to.
    let d = (0..3).map(|k| n[k] * (p[k] - a[k])).sum::<i128>();
    let side = sign([d, n[1], n[2]]);
    let side = if side == 0 { n[0].signum() } else { side };
    if side == n[0].signum() {
        return 0;
    }
    if n[0] > 0 { 1 } else { -1 }
}

/// The first pair (by index) of proper triangles that intersect
/// improperly, if any.
fn first_intersection(triangles: &[[IntPoint; 3]]) -> Option<(usize, usize)> {
    let tris: Vec<(usize, [P; 3])> = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| (i, t.map(|p| p.coords())))
        .filter(|(_, t)| cross(sub(t[1], t[0]), sub(t[2], t[0])) != [0; 3])
        .collect();
    if tris.len() < 2 {
        return None;
    }
    let boxes: Vec<(P, P)> = tris.iter().map(|(_, t)| bounds(t)).collect();
    // Grid cells about the size of an average triangle.
    let mean_extent = boxes
        .iter()
        .map(|(lo, hi)| (0..3).map(|a| hi[a] - lo[a]).max().unwrap_or(0) as f64)
        .sum::<f64>()
        / boxes.len() as f64;
    let size = (mean_extent.ceil() as i64).max(1);
    let cell_of = |p: P| p.map(|x| x.div_euclid(size));
    let mut grid: HashMap<P, Vec<u32>> = HashMap::new();
    for (k, (lo, hi)) in boxes.iter().enumerate() {
        let (a, b) = (cell_of(*lo), cell_of(*hi));
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    grid.entry([x, y, z]).or_default().push(k as u32);
                }
            }
        }
    }
    let mut found: Option<(usize, usize)> = None;
    for (cell, members) in &grid {
        for (m, &i) in members.iter().enumerate() {
            for &j in &members[m + 1..] {
                let (bi, bj) = (&boxes[i as usize], &boxes[j as usize]);
                if !(0..3).all(|a| bi.0[a] <= bj.1[a] && bj.0[a] <= bi.1[a]) {
                    continue;
                }
                // Test each pair once: in the cell holding the lower corner
                // of the boxes' overlap.
                let corner = [0, 1, 2].map(|a| bi.0[a].max(bj.0[a]));
                if cell_of(corner) != *cell {
                    continue;
                }
                let (ti, tj) = (&tris[i as usize], &tris[j as usize]);
                if triangles_meet_improperly(&ti.1, &tj.1) {
                    let pair = (ti.0.min(tj.0), ti.0.max(tj.0));
                    if found.is_none_or(|f| pair < f) {
                        found = Some(pair);
                    }
                }
            }
        }
    }
    found
}

fn bounds(t: &[P; 3]) -> (P, P) {
    let lo = [0, 1, 2].map(|a| t.iter().map(|p| p[a]).min().unwrap_or(0));
    let hi = [0, 1, 2].map(|a| t.iter().map(|p| p[a]).max().unwrap_or(0));
    (lo, hi)
}

/// Whether two proper triangles meet anywhere but in shared corners and a
/// shared edge.
fn triangles_meet_improperly(t: &[P; 3], u: &[P; 3]) -> bool {
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| t[i] == u[j])
        .collect();
    match shared.len() {
        0 => {
            (0..3).any(|k| segment_meets_triangle(t[k], t[(k + 1) % 3], u))
                || (0..3).any(|k| segment_meets_triangle(u[k], u[(k + 1) % 3], t))
        }
        1 => {
            let (i, j) = shared[0];
            segment_meets_triangle(t[(i + 1) % 3], t[(i + 2) % 3], u)
                || segment_meets_triangle(u[(j + 1) % 3], u[(j + 2) % 3], t)
        }
        2 => {
            // The corners off the shared edge, on the same side of it in a
            // common plane, overlap.
            let (e0, e1) = (t[shared[0].0], t[shared[1].0]);
            let x = t[3 - shared[0].0 - shared[1].0];
            let y = u[3 - shared[0].1 - shared[1].1];
            if orient(e0, e1, x, y) != 0 {
                return false;
            }
            let axis = dominant_axis(t);
            orient_2d(e0, e1, x, axis).signum() == orient_2d(e0, e1, y, axis).signum()
        }
        // The same three corners: a doubled face.
        _ => true,
    }
}

/// The coordinate axis most normal to triangle `t` (projecting along it
/// keeps `t` proper).
fn dominant_axis(t: &[P; 3]) -> usize {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    (0..3).max_by_key(|&a| n[a].unsigned_abs()).unwrap_or(2)
}

/// Whether the closed segment `pq` meets the closed proper triangle `t`.
fn segment_meets_triangle(p: P, q: P, t: &[P; 3]) -> bool {
    let (op, oq) = (orient(t[0], t[1], t[2], p), orient(t[0], t[1], t[2], q));
    if op.signum() * oq.signum() > 0 {
        return false;
    }
    if op == 0 && oq == 0 {
        let axis = dominant_axis(t);
        return point_in_triangle_2d(p, t, axis)
            || point_in_triangle_2d(q, t, axis)
            || (0..3).any(|k| segments_meet_2d(p, q, t[k], t[(k + 1) % 3], axis));
    }
    // The segment reaches the plane; the line through it meets the closed
    // triangle when it passes no edge on the outside.
    let s = [
        orient(p, q, t[0], t[1]).signum(),
        orient(p, q, t[1], t[2]).signum(),
        orient(p, q, t[2], t[0]).signum(),
    ];
    !(s.contains(&1) && s.contains(&-1))
}

fn point_in_triangle_2d(p: P, t: &[P; 3], axis: usize) -> bool {
    let s = [
        orient_2d(t[0], t[1], p, axis).signum(),
        orient_2d(t[1], t[2], p, axis).signum(),
        orient_2d(t[2], t[0], p, axis).signum(),
    ];
    !(s.contains(&1) && s.contains(&-1))
}

/// Whether closed segments `ab` and `cd`, lying in one plane, meet (in the
/// projection along `axis`, which is faithful for that plane).
fn segments_meet_2d(a: P, b: P, c: P, d: P, axis: usize) -> bool {
    let (d1, d2) = (orient_2d(a, b, c, axis), orient_2d(a, b, d, axis));
    let (d3, d4) = (orient_2d(c, d, a, axis), orient_2d(c, d, b, axis));
    if d1.signum() * d2.signum() < 0 && d3.signum() * d4.signum() < 0 {
        return true;
    }
    let within =
        |p: P, q: P, r: P| (0..3).all(|k| p[k].min(q[k]) <= r[k] && r[k] <= p[k].max(q[k]));
    (d1 == 0 && within(a, b, c))
        || (d2 == 0 && within(a, b, d))
        || (d3 == 0 && within(c, d, a))
        || (d4 == 0 && within(c, d, b))
}
