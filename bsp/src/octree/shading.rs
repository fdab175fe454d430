//! The surface around cell-border vertices, shared between the sealed
//! meshes of neighbouring leaves, so that smooth normals agree on both
//! sides of a border (a [`SeamedMesher`] made by
//! [`SeamedMesher::with_shading`]).
//!
//! Notation as in [`super::seams`]; besides, a leaf's *shaded points* are
//! the vertices of its sealed mesh lying on its walls with a surface
//! polygon of the leaf around them, and its *own wedges* at one are the
//! merged corner wedges of those polygons there
//! ([`crate::mesh::wedge`]).
//!
//! Sealed meshes meet edge to edge, so every leaf whose surface holds a
//! point on a border has it as a vertex, and the surface around it is the
//! union of the leaves' own wedges there. The mesher keeps every leaf's
//! shaded points with their own wedges. An update hands back, with each
//! sealed mesh, the merged wedges around every vertex: its own, and at
//! its shaded points the neighbours' too ([`ShadedCell`]). A point whose
//! own wedges in some leaf changed (appeared, went, or differ exactly)
//! changes the surface around it for every other leaf that has it as a
//! shaded point: those leaves are handed back too, sealed again from
//! their kept unsealed meshes (the same mesh as before, with new wedges
//! only). The wedges are exact; turning them into normals is the
//! renderer's work.

use std::collections::BTreeSet;

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::seams::{SeamedMesher, may_be_in_box, same_point};
use super::tree::Octree;
use crate::exact::Point4;
use crate::mesh::weld::Welder;
use crate::mesh::{SurfaceAround, SurfaceMesh, Wedge, merge_wedges};

/// A leaf's sealed mesh with the surface around each of its vertices:
/// its own polygons' wedges, and at its shaded points those of the
/// neighbouring leaves that have the point.
#[derive(Debug, Default)]
pub struct ShadedCell {
    /// The sealed mesh ([`SeamedMesher::update`]).
    pub mesh: SurfaceMesh,
    /// Per vertex of `mesh`, the merged wedges of every leaf's surface
    /// around it.
    pub around: SurfaceAround,
}

/// What a shading mesher keeps of one leaf: its shaded points and own
/// wedges there (see the module docs).
#[derive(Clone, Debug, Default)]
pub(super) struct CellShading {
    points: Vec<Point4>,
    /// Their `f64` positions, for cheap filters.
    points_f64: Vec<[f64; 3]>,
    /// Their vertex numbers in the sealed mesh they come from.
    vertices: Vec<u32>,
    /// Point `i`'s own wedges are `wedges[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    wedges: Vec<Wedge>,
}

impl CellShading {
    /// The shaded points of a sealed `mesh` among the vertices `wall` (its
    /// vertices on the cell's walls), with their own wedges from
    /// `around` ([`SurfaceMesh::surface_around`] of `mesh`).
    pub(super) fn of(
        mesh: &SurfaceMesh,
        wall: impl IntoIterator<Item = u32>,
        around: &SurfaceAround,
    ) -> Self {
        let wall = wall.into_iter();
        let room = wall.size_hint().0;
        let mut out = Self {
            points: Vec::with_capacity(room),
            points_f64: Vec::with_capacity(room),
            vertices: Vec::with_capacity(room),
            start: Vec::with_capacity(room + 1),
            wedges: Vec::with_capacity(room * 2),
        };
        out.start.push(0);
        for v in wall {
            let wedges = around.of_vertex(v);
            if wedges.is_empty() {
                continue;
            }
            let p = mesh.vertices()[v as usize];
            out.points.push(p);
            out.points_f64.push(p.to_f64());
            out.vertices.push(v);
            out.wedges.extend_from_slice(wedges);
            out.start.push(out.wedges.len() as u32);
        }
        out
    }

    fn wedges(&self, i: usize) -> &[Wedge] {
        &self.wedges[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// One sealed leaf of an update, before the shading step: its mesh and,
/// for a shading mesher, its own surface around each vertex and its
/// shaded points.
pub(super) type SealedLeaf = (CellKey, SurfaceMesh, Option<(SurfaceAround, CellShading)>);

impl SeamedMesher {
    /// A mesher that also keeps the surface around every leaf's border
    /// vertices, so that [`SeamedMesher::update_shaded`] hands back with
    /// each sealed mesh the wedges of all leaves around its vertices, and
    /// also the leaves whose meshes stay but whose surroundings changed
    /// (see [`super::shading`]).
    #[must_use]
    pub fn with_shading() -> Self {
        let mut mesher = Self::default();
        mesher.shaded = true;
        mesher
    }

    /// Whether the mesher keeps the surface around border vertices
    /// ([`SeamedMesher::with_shading`]).
    #[must_use]
    pub fn keeps_shading(&self) -> bool {
        self.shaded
    }

    /// The shading step of an update: keeps the shaded points of the
    /// leaves `sealed` (every leaf sealed in this update) and forgets those
    /// of `gone`, finds the other leaves whose surroundings changed and
    /// seals them again from their kept meshes, then hands back every one
    /// with the wedges of its neighbours added, sorted by key.
    pub(super) fn shade(
        &mut self,
        octree: &Octree,
        sealed: Vec<SealedLeaf>,
        gone: Vec<CellKey>,
    ) -> Vec<(CellKey, Option<ShadedCell>)> {
        let mut before = Vec::with_capacity(sealed.len() + gone.len());
        let mut cells: Vec<(CellKey, SurfaceMesh, SurfaceAround)> =
            Vec::with_capacity(sealed.len());
        let mut now = Vec::with_capacity(sealed.len());
        for (key, mesh, shading) in sealed {
            let (around, shading) = shading.unwrap_or_default();
            before.extend(self.shading.remove(&key).map(|s| (key, s)));
            now.push((key, shading));
            cells.push((key, mesh, around));
        }
        for key in &gone {
            before.extend(self.shading.remove(key).map(|s| (*key, s)));
        }
        // The points whose own wedges changed in some leaf, the other
        // leaves that have them, and of those points, the ones where the
        // union over all these leaves changed.
        let candidates = candidate_points(&before, &now);
        let listed: BTreeSet<CellKey> = cells.iter().map(|(key, ..)| *key).collect();
        let near = self.shaded_at(octree, &candidates, &listed);
        let mut asked: Vec<usize> = near.iter().flat_map(|(_, at)| at.iter().copied()).collect();
        asked.sort_unstable();
        asked.dedup();
        let changed = changed_unions(&before, &now, &candidates, &asked);
        let again: Vec<CellKey> = near
            .into_iter()
            .filter(|(_, at)| at.iter().any(|i| changed.binary_search(i).is_ok()))
            .map(|(key, _)| key)
            .collect();
        for (key, shading) in now {
            if !shading.points.is_empty() {
                self.shading.insert(key, shading);
            }
        }
        let around = self.extra_points_of(octree, &again);
        let this = &*self;
        let resealed: Vec<SealedLeaf> = again
            .into_par_iter()
            .zip(around)
            .filter_map(|(key, extra)| {
                let unsealed = this.unsealed.get(&key)?;
                let (mesh, shading) = this.seal_shaded(key, unsealed, extra);
                Some((key, mesh, shading))
            })
            .collect();
        for (key, mesh, shading) in resealed {
            let (around, shading) = shading.unwrap_or_default();
            // The same points and own wedges; only the vertex numbers may
            // differ.
            self.shading.insert(key, shading);
            cells.push((key, mesh, around));
        }
        let keys: Vec<CellKey> = cells.iter().map(|(key, ..)| *key).collect();
        let foreign = self.neighbour_wedges(octree, &keys);
        let mut out: Vec<(CellKey, Option<ShadedCell>)> = cells
            .into_par_iter()
            .zip(foreign)
            .map(|((key, mesh, mut around), more)| {
                around.add(more);
                (key, Some(ShadedCell { mesh, around }))
            })
            .collect();
        out.extend(gone.into_iter().map(|key| (key, None)));
        out.sort_unstable_by_key(|(key, _)| *key);
        out
    }

    /// The leaves not `listed` with some of the points `changed` among
    /// their shaded points, by key, each with those points' indices.
    fn shaded_at(
        &self,
        octree: &Octree,
        changed: &[Point4],
        listed: &BTreeSet<CellKey>,
    ) -> Vec<(CellKey, Vec<usize>)> {
        if changed.is_empty() {
            return Vec::new();
        }
        let positions: Vec<[f64; 3]> = changed.iter().map(Point4::to_f64).collect();
        let boxes: Vec<CellBox> = positions
            .iter()
            .map(|q| CellBox {
                min: q.map(|c| c.floor() as i64 - 1),
                max: q.map(|c| c.ceil() as i64 + 1),
            })
            .collect();
        let mut out = Vec::new();
        octree.for_leaves_touching_each(&boxes, |key, near| {
            if listed.contains(&key) {
                return;
            }
            let Some(shading) = self.shading.get(&key) else {
                return;
            };
            let index = PointIndex::of(shading);
            let at: Vec<usize> = near
                .iter()
                .copied()
                .filter(|&i| index.find(shading, &changed[i], positions[i]).is_some())
                .collect();
            if !at.is_empty() {
                out.push((key, at));
            }
        });
        out.sort_unstable();
        out
    }

    /// Per leaf of `keys`, the own wedges of its neighbours at its shaded
    /// points, as `(vertex of its sealed mesh, wedges)`.
    fn neighbour_wedges(&self, octree: &Octree, keys: &[CellKey]) -> Vec<Vec<(u32, &[Wedge])>> {
        let cells: Vec<CellBox> = keys.iter().map(|&key| octree.cell_box(key)).collect();
        let mut near: Vec<Vec<CellKey>> = vec![Vec::new(); keys.len()];
        octree.for_leaves_touching_each(&cells, |other, hits| {
            if self.shading.contains_key(&other) {
                for &i in hits {
                    if keys[i] != other {
                        near[i].push(other);
                    }
                }
            }
        });
        keys.par_iter()
            .zip(cells)
            .zip(near)
            .map(|((key, cell), near)| {
                let Some(own) = self.shading.get(key) else {
                    return Vec::new();
                };
                let index = PointIndex::of(own);
                let mut more = Vec::new();
                for other in near {
                    let theirs = &self.shading[&other];
                    for (j, (p, q)) in theirs.points.iter().zip(&theirs.points_f64).enumerate() {
                        if may_be_in_box(*q, &cell)
                            && let Some(i) = index.find(own, p, *q)
                        {
                            more.push((own.vertices[i], theirs.wedges(j)));
                        }
                    }
                }
                more
            })
            .collect()
    }

    /// Seals leaf `key`'s unsealed mesh at the neighbours' wall points
    /// `extra` (the mesh an update would hand back for it), with its own
    /// surface and shaded points.
    fn seal_shaded(
        &self,
        key: CellKey,
        unsealed: &crate::mesh::UnsealedMesh,
        extra: Vec<&Point4>,
    ) -> (SurfaceMesh, Option<(SurfaceAround, CellShading)>) {
        let edges = self
            .borders
            .get(&key)
            .map_or(&[][..], |b| b.edges.as_slice());
        let wall = unsealed.wall_vertex_indices();
        let own = unsealed.vertex_count() as u32;
        let (mesh, _) = unsealed.clone().seal_with_edges(extra, edges);
        let shading = own_shading(&mesh, wall, own);
        (mesh, Some(shading))
    }
}

/// The own surface around the border vertices of a sealed `mesh` (the
/// other vertices get no wedges) and its shaded points, given the vertices `wall` of its unsealed mesh on the cell's
/// walls and that mesh's vertex count `own` (the vertices from `own` on
/// are seam points, all on walls).
pub(super) fn own_shading(
    mesh: &SurfaceMesh,
    mut wall: Vec<u32>,
    own: u32,
) -> (SurfaceAround, CellShading) {
    wall.extend(own..mesh.vertices().len() as u32);
    let around = mesh.surface_around_at(&wall);
    let shading = CellShading::of(mesh, wall, &around);
    (around, shading)
}

/// The points whose own wedges changed in one of the leaves `before` and
/// `now` (all the leaves an update sealed or dropped, before and after it,
/// by key): its points that differ from its old ones, and every point of a
/// leaf new or gone. Distinct.
fn candidate_points(
    before: &[(CellKey, CellShading)],
    now: &[(CellKey, CellShading)],
) -> Vec<Point4> {
    let old_of = |key: &CellKey| {
        before
            .binary_search_by_key(key, |(k, _)| *k)
            .ok()
            .map(|i| &before[i].1)
    };
    let mut candidates = Welder::with_capacity(0);
    for (key, new) in now {
        let Some(old) = old_of(key) else {
            for p in &new.points {
                candidates.index(p);
            }
            continue;
        };
        let index = PointIndex::of(old);
        let mut matched = vec![false; old.points.len()];
        for (i, p) in new.points.iter().enumerate() {
            match index.find(old, p, new.points_f64[i]) {
                Some(j) => {
                    matched[j] = true;
                    if old.wedges(j) != new.wedges(i) {
                        candidates.index(p);
                    }
                }
                None => {
                    candidates.index(p);
                }
            }
        }
        for (p, _) in old.points.iter().zip(matched).filter(|(_, m)| !m) {
            candidates.index(p);
        }
    }
    for (key, old) in before {
        if now.binary_search_by_key(key, |(k, _)| *k).is_err() {
            for p in &old.points {
                candidates.index(p);
            }
        }
    }
    candidates.into_vertices()
}

/// The indices, among `asked` (ascending), of the `candidates` where the
/// union of the own wedges of the leaves `before` differs from that of
/// the leaves `now`: what the other leaves that have such a point must see
/// anew. A leaf split or merged with the same surface changes no point on
/// its outer walls, though each of its points is a candidate.
fn changed_unions(
    before: &[(CellKey, CellShading)],
    now: &[(CellKey, CellShading)],
    candidates: &[Point4],
    asked: &[usize],
) -> Vec<usize> {
    if asked.is_empty() {
        return Vec::new();
    }
    let union = |shadings: &mut dyn Iterator<Item = &CellShading>| {
        let mut lists: Vec<Vec<Wedge>> = vec![Vec::new(); asked.len()];
        for shading in shadings {
            let index = PointIndex::of(shading);
            for (list, &c) in lists.iter_mut().zip(asked) {
                let p = &candidates[c];
                if let Some(j) = index.find(shading, p, p.to_f64()) {
                    list.extend_from_slice(shading.wedges(j));
                }
            }
        }
        for list in &mut lists {
            merge_wedges(list);
        }
        lists
    };
    let old = union(&mut before.iter().map(|(_, s)| s));
    let new = union(&mut now.iter().map(|(_, s)| s));
    asked
        .iter()
        .zip(old.iter().zip(&new))
        .filter(|(_, (a, b))| a != b)
        .map(|(&c, _)| c)
        .collect()
}

/// A leaf's shaded points by `f64` x, to find a point among them.
struct PointIndex(Vec<(f64, u32)>);

impl PointIndex {
    fn of(shading: &CellShading) -> Self {
        let mut order: Vec<(f64, u32)> = shading
            .points_f64
            .iter()
            .enumerate()
            .map(|(i, q)| (q[0], i as u32))
            .collect();
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        Self(order)
    }

    /// The index of `p` (at `f64` position `q`) among the points of
    /// `shading`, exactly.
    fn find(&self, shading: &CellShading, p: &Point4, q: [f64; 3]) -> Option<usize> {
        let margin = (q[0].abs() + 1.0) * f64::powi(2.0, -40);
        let first = self.0.partition_point(|&(x, _)| x < q[0] - margin);
        self.0[first..]
            .iter()
            .take_while(|&&(x, _)| x <= q[0] + margin)
            .map(|&(_, i)| i as usize)
            .find(|&i| close(shading.points_f64[i], q) && same_point(&shading.points[i], p))
    }
}

/// Whether two `f64` positions of exact points may be the same point
/// (each within `2^-51` relative; a margin of `2^-40`).
fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|i| {
        let margin = (a[i].abs().max(b[i].abs()) + 1.0) * f64::powi(2.0, -40);
        (a[i] - b[i]).abs() <= margin
    })
}

impl SeamedMesher {
    /// Leaves whose shaded points are kept.
    #[must_use]
    pub fn shaded_cells(&self) -> usize {
        self.shading.len()
    }
}
