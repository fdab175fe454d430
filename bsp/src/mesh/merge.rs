//! Merging coplanar fragments: two polygons on the same plane, with the
//! same materials, that share a whole edge become one polygon when their
//! union is convex.
//!
//! Notation as in [`super`]: face plane `s`, edge planes `e_k`, corners
//! `c_k = s ∩ e_{k−1} ∩ e_k`. Faces come fragmented by the planes of the
//! BSP they were cut from: a face split by a plane `h` leaves two pieces
//! whose common edge lies on `h` (one piece on `h`, the other on `−h`), and
//! after welding both pieces name the same two vertices `P, Q` for it, in
//! opposite directions.
//!
//! # The merge
//!
//! Polygon `A` (corners `… a_{−1}, P, Q, a_1 …`, edge `P → Q` on plane
//! `e_A`) and polygon `B` (`… b_{−1}, Q, P, b_1 …`, edge `Q → P`) with the
//! same support plane `s` (identical coefficients, hence the same
//! orientation), label, outside label and `on_bounds`:
//!
//! - *opposite sides*: `e_A(b_1) > 0`. `B` is strictly convex, so it then
//!   lies across the line `PQ` from `A`, and the union is a simple polygon;
//! - *corner `P`*: the union runs `a_{−1} → P → b_1`, with incoming edge
//!   plane `e_in` (`A`'s edge into `P`). `e_in(b_1) < 0`: a convex corner,
//!   kept; `= 0`: `b_1` lies on the line of the incoming edge, beyond `P`
//!   (it is across `PQ`), so `P` is no corner any more and is dropped with
//!   `B`'s edge out of it (`e_in` carries the whole straight edge: it meets
//!   `s` in the same line); `> 0`: a reflex corner, no merge;
//! - *corner `Q`*: the same with `b_{−1} → Q → a_1` and `B`'s edge into
//!   `Q`.
//!
//! Two pieces of one split mostly need no arithmetic: their common edge is
//! on `h` and `−h` (then `e_A(b_1) > 0`, as `b_1` is strictly inside `B`),
//! and where the split crossed an edge plane `e` of the parent, both keep
//! `e` on either side of the corner, which is then straight.
//!
//! Every other corner keeps its strictly convex angle, and a simple polygon
//! whose corners all turn the same way (or not at all) is convex, so these
//! three exact signs ([`classify_vertex`]) decide. The merged polygon is
//! again strictly convex in its corners, each the meet of `s` and the
//! planes of its two edges, so [`super::tjunction`] and
//! [`super::triangulate`] apply unchanged. The union covers exactly the
//! two pieces, so the surface as a point set — areas, volumes, closure — is
//! unchanged; only the polygons are fewer and larger.
//!
//! Merges repeat while any applies: pieces of one face split
//! hierarchically by a BSP merge back up its split tree wherever the
//! labels agree. A directed edge used by more than one polygon (a solid
//! touching itself along an edge) is never merged across.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::hash::BuildHasherDefault;

use super::{MeshPolygon, spare};
use crate::exact::{Plane, Point4, Sign, classify_vertex};
use crate::pool::{PerThread, Pool};
use crate::tree::polygon::{give_back_edge_buffers, spare_edge_buffer};
use crate::word_hash::WordHasher;

/// The owner of a directed edge used by more than one polygon.
const SHARED: u32 = u32::MAX;

/// Directed edge `(from, to)` packed into one word.
#[inline]
fn edge_key(from: u32, to: u32) -> u64 {
    (u64::from(from) << 32) | u64::from(to)
}

/// Merges, in place, every pair of polygons that the module docs allow,
/// until none is left; returns whether any merge happened. The polygons
/// must have no inserted corners (as [`super::SurfaceMesh::welded`] makes
/// them); the merged ones have none either. The order of the remaining
/// polygons is that of their first pieces.
pub(crate) fn merge_coplanar(vertices: &[Point4], polygons: &mut Vec<MeshPolygon>) -> bool {
    let mut scratch = SCRATCH.take().unwrap_or_default();
    let merged_any = merge_in(vertices, polygons, &mut scratch);
    if scratch.owners.capacity() <= KEEP_MAX {
        SCRATCH.keep(scratch);
    }
    merged_any
}

/// Working memory of [`merge_coplanar`], kept per thread (a game
/// re-meshes a few cells after every edit, each about as large as the
/// last): the owner of each directed edge, which polygons are still
/// alive, and the polygons still to try.
#[derive(Default)]
struct Scratch {
    owners: HashMap<u64, u32, BuildHasherDefault<WordHasher>>,
    alive: Vec<bool>,
    pending: Vec<u32>,
}

thread_local! {
    /// The [`Scratch`] of this thread, between calls.
    static SCRATCH: Pool<Scratch> = const { Pool::new(1) };
}

/// Edges above which the working memory is freed rather than kept (after
/// a whole-surface mesh).
const KEEP_MAX: usize = 1 << 14;

/// [`merge_coplanar`] with the working memory `scratch`.
fn merge_in(vertices: &[Point4], polygons: &mut Vec<MeshPolygon>, scratch: &mut Scratch) -> bool {
    let Scratch {
        owners,
        alive,
        pending,
    } = scratch;
    owners.clear();
    owners.reserve(polygons.len() * 4);
    for (f, polygon) in polygons.iter().enumerate() {
        let n = polygon.corners.len();
        for k in 0..n {
            let key = edge_key(polygon.corners[k], polygon.corners[(k + 1) % n]);
            match owners.entry(key) {
                Entry::Occupied(mut owner) => {
                    *owner.get_mut() = SHARED;
                }
                Entry::Vacant(owner) => {
                    owner.insert(f as u32);
                }
            }
        }
    }
    alive.clear();
    alive.resize(polygons.len(), true);
    let mut merged_any = false;
    pending.clear();
    pending.extend((0..polygons.len() as u32).rev());
    while let Some(a) = pending.pop() {
        let a = a as usize;
        if !alive[a] {
            continue;
        }
        let n = polygons[a].corners.len();
        for k in 0..n {
            let (p, q) = (polygons[a].corners[k], polygons[a].corners[(k + 1) % n]);
            let Some(&b) = owners.get(&edge_key(q, p)) else {
                continue;
            };
            let b = b as usize;
            if b == SHARED as usize
                || b == a
                || !same_support(&polygons[a], &polygons[b])
                || owners.get(&edge_key(p, q)) != Some(&(a as u32))
            {
                continue;
            }
            let Some(j) = position_of_edge(&polygons[b], q, p) else {
                continue;
            };
            let Some(union) = merged(vertices, &polygons[a], k, &polygons[b], j) else {
                continue;
            };
            // Re-own the edges: those of both pieces go, those of the union
            // come (all of them unused before, or used by `a` or `b`).
            // An edge also used elsewhere stays marked as shared.
            for f in [a, b] {
                let c = &polygons[f].corners;
                for i in 0..c.len() {
                    let key = edge_key(c[i], c[(i + 1) % c.len()]);
                    if owners.get(&key) == Some(&(f as u32)) {
                        owners.remove(&key);
                    }
                }
            }
            let m = union.corners.len();
            for i in 0..m {
                let key = edge_key(union.corners[i], union.corners[(i + 1) % m]);
                owners
                    .entry(key)
                    .and_modify(|owner| *owner = SHARED)
                    .or_insert(a as u32);
            }
            recycle(&mut std::mem::replace(&mut polygons[a], union));
            alive[b] = false;
            merged_any = true;
            pending.push(a as u32);
            break;
        }
    }
    if merged_any {
        let mut f = 0;
        polygons.retain_mut(|polygon| {
            f += 1;
            if !alive[f - 1] {
                recycle(polygon);
            }
            alive[f - 1]
        });
    }
    merged_any
}

/// Hands the buffers of a polygon merged away to the spare buffers of
/// this thread, leaving it empty.
fn recycle(polygon: &mut MeshPolygon) {
    give_back_edge_buffers(std::iter::once(std::mem::take(&mut polygon.edges)));
    spare::give_back(
        [
            std::mem::take(&mut polygon.corners),
            std::mem::take(&mut polygon.originals),
        ]
        .into_iter(),
    );
}

/// Whether `a` and `b` lie on the same oriented plane with the same
/// materials on both sides.
#[inline]
fn same_support(a: &MeshPolygon, b: &MeshPolygon) -> bool {
    a.plane == b.plane && a.label == b.label && a.outside == b.outside && a.on_bounds == b.on_bounds
}

/// The position `j` of the edge `from → to` in `polygon`'s corners.
#[inline]
fn position_of_edge(polygon: &MeshPolygon, from: u32, to: u32) -> Option<usize> {
    let c = &polygon.corners;
    (0..c.len()).find(|&j| c[j] == from && c[(j + 1) % c.len()] == to)
}

/// How the union turns at a corner where one piece's edge ends and the
/// other's begins.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Turn {
    Convex,
    Straight,
}

/// The turn at the corner between edge planes `incoming` and `outgoing`,
/// where `outgoing` leads on to corner `next`, or `None` for a reflex
/// corner. The same plane on both sides is straight without arithmetic
/// (`next` lies on `outgoing`).
#[inline]
fn turn(next: &Point4, incoming: &Plane, outgoing: &Plane) -> Option<Turn> {
    if incoming == outgoing {
        return Some(Turn::Straight);
    }
    match classify_vertex(next, incoming) {
        Sign::Negative => Some(Turn::Convex),
        Sign::Zero => Some(Turn::Straight),
        Sign::Positive => None,
    }
}

/// The union of `a` and `b` across `a`'s edge `k` (`P → Q`), which is
/// `b`'s edge `j` (`Q → P`), when it is convex (see the module docs).
fn merged(
    vertices: &[Point4],
    a: &MeshPolygon,
    k: usize,
    b: &MeshPolygon,
    j: usize,
) -> Option<MeshPolygon> {
    let (na, nb) = (a.corners.len(), b.corners.len());
    let vertex = |v: u32| &vertices[v as usize];
    // b_1, the corner of `b` after P; a_1, the corner of `a` after Q.
    let b1 = b.corners[(j + 2) % nb];
    let a1 = a.corners[(k + 2) % na];
    // Pieces of one split share the splitting plane, flipped, and keep the
    // parent's edge planes on either side: those signs are known.
    if b.edges[j] != a.edges[k].flipped()
        && classify_vertex(vertex(b1), &a.edges[k]) != Sign::Positive
    {
        return None;
    }
    let at_p = turn(
        vertex(b1),
        &a.edges[(k + na - 1) % na],
        &b.edges[(j + 1) % nb],
    )?;
    let at_q = turn(
        vertex(a1),
        &b.edges[(j + nb - 1) % nb],
        &a.edges[(k + 1) % na],
    )?;
    let mut corners = spare::index_buffer(na + nb - 2);
    let mut edges = spare_edge_buffer(na + nb - 2);
    // Q, a_1, …, a_{−1} with their outgoing edges: `a` from Q round to the
    // corner before P. Q is dropped when straight: B's edge into Q then
    // runs on to a_1, and stays the last edge below.
    for i in 1..na {
        let c = (k + i) % na;
        if i == 1 && at_q == Turn::Straight {
            continue;
        }
        corners.push(a.corners[c]);
        edges.push(a.edges[c]);
    }
    // P with B's edge out of it, unless straight: then A's edge into P
    // (the last pushed) runs on to b_1.
    if at_p == Turn::Convex {
        corners.push(a.corners[k]);
        edges.push(b.edges[(j + 1) % nb]);
    }
    // b_1, …, b_{−1} with their outgoing edges (the last one into Q).
    for i in 2..nb {
        let c = (j + i) % nb;
        corners.push(b.corners[c]);
        edges.push(b.edges[c]);
    }
    let mut originals = spare::index_buffer(corners.len());
    originals.extend(0..corners.len() as u32);
    Some(MeshPolygon {
        plane: a.plane,
        originals,
        edges,
        corners,
        label: a.label,
        outside: a.outside,
        on_bounds: a.on_bounds,
    })
}
