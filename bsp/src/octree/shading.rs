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

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::seams::{SeamedMesher, may_be_in_box, same_point};
use super::tree::Octree;
use crate::exact::Point4;
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
    pub(super) points: Vec<Point4>,
    /// Their `f64` positions, for cheap filters.
    pub(super) points_f64: Vec<[f64; 3]>,
    /// Their vertex numbers in the sealed mesh they come from.
    pub(super) vertices: Vec<u32>,
    /// Per point, the walls of the leaf's box it may lie on (`2·axis +
    /// upper`, one bit each; a cheap filter: the exact test decides).
    walls: Vec<u8>,
    /// Per wall, the points that may lie on it.
    on_wall: [Vec<u32>; 6],
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
        cell: &CellBox,
    ) -> Self {
        let wall = wall.into_iter();
        let room = wall.size_hint().0;
        let mut out = Self {
            points: Vec::with_capacity(room),
            points_f64: Vec::with_capacity(room),
            vertices: Vec::with_capacity(room),
            walls: Vec::with_capacity(room),
            on_wall: Default::default(),
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
            let q = p.to_f64();
            let walls = near_walls(q, cell);
            for (w, list) in out.on_wall.iter_mut().enumerate() {
                if walls & (1 << w) != 0 {
                    list.push(out.points.len() as u32);
                }
            }
            out.walls.push(walls);
            out.points.push(p);
            out.points_f64.push(q);
            out.vertices.push(v);
            out.wedges.extend_from_slice(wedges);
            out.start.push(out.wedges.len() as u32);
        }
        out
    }

    /// The own wedges at point `i`.
    pub(super) fn wedges(&self, i: usize) -> &[Wedge] {
        &self.wedges[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// The indices of the points that may lie on the part of the leaf's
    /// box `own` it shares with the box `other` (a face, an edge or a
    /// corner).
    fn facing<'a>(&'a self, own: &CellBox, other: &CellBox) -> impl Iterator<Item = usize> + 'a {
        let mut required = 0u8;
        for a in 0..3 {
            if own.min[a] == other.max[a] {
                required |= 1 << (2 * a);
            }
            if own.max[a] == other.min[a] {
                required |= 1 << (2 * a + 1);
            }
        }
        let list: &[u32] = if required == 0 {
            &[]
        } else {
            &self.on_wall[required.trailing_zeros() as usize]
        };
        list.iter()
            .map(|&i| i as usize)
            .filter(move |&i| self.walls[i] & required == required)
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
    /// leaves `sealed` (every leaf sealed in this update; `near`: per
    /// leaf, its neighbours with wall points) and forgets those of `gone`,
    /// finds the other leaves whose surroundings changed and
    /// seals them again from their kept meshes, then hands back every one
    /// with the wedges of its neighbours added, sorted by key.
    pub(super) fn shade(
        &mut self,
        octree: &Octree,
        sealed: Vec<SealedLeaf>,
        near: Vec<Vec<CellKey>>,
        gone: Vec<CellKey>,
    ) -> Vec<(CellKey, Option<ShadedCell>)> {
        let mut before = Vec::with_capacity(sealed.len() + gone.len());
        let mut cells: Vec<(CellKey, SurfaceMesh, SurfaceAround)> =
            Vec::with_capacity(sealed.len());
        for (key, mesh, shading) in sealed {
            let (around, shading) = shading.unwrap_or_default();
            before.extend(self.shading.remove(&key).map(|s| (key, s)));
            if !shading.points.is_empty() {
                self.shading.insert(key, shading);
            }
            cells.push((key, mesh, around));
        }
        for key in &gone {
            before.extend(self.shading.remove(key).map(|s| (*key, s)));
        }
        before.sort_unstable_by_key(|(key, _)| *key);
        let outside_changed = std::mem::take(&mut self.outside_wedges.changed);
        let keys: Vec<CellKey> = cells.iter().map(|(key, ..)| *key).collect();
        let (mut foreign, maybe) = self.neighbour_wedges(octree, &keys, &near, Some(&before));
        let mut again = self.surroundings_changed(octree, &keys, &before, maybe);
        // Leaves whose outside wedges changed ([`super::outside_shading`]).
        let mut sorted = keys.clone();
        sorted.sort_unstable();
        again.extend(self.touched_by_outside(octree, &outside_changed, &sorted));
        again.sort_unstable();
        again.dedup();
        if again.is_empty() {
            self.add_outside_wedges(octree, &keys, &mut foreign);
            return finish(cells, foreign, gone);
        }
        let around = self.extra_points_of(octree, &again);
        let this = &*self;
        let resealed: Vec<SealedLeaf> = again
            .par_iter()
            .zip(around)
            .filter_map(|(&key, extra)| {
                let unsealed = this.unsealed.get(&key)?;
                let cell = octree.cell_box(key);
                let (mesh, shading) = this.seal_shaded(key, &cell, unsealed, extra);
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
        let near = self.neighbours_of(octree, &keys);
        let (mut foreign, _) = self.neighbour_wedges(octree, &keys, &near, None);
        self.add_outside_wedges(octree, &keys, &mut foreign);
        finish(cells, foreign, gone)
    }

    /// Per leaf of `keys`, the other leaves with shaded points whose
    /// closed boxes touch its own.
    fn neighbours_of(&self, octree: &Octree, keys: &[CellKey]) -> Vec<Vec<CellKey>> {
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
        near
    }

    /// Of the leaves `maybe` found with a shaded point where a listed
    /// leaf's own wedges changed ([`SeamedMesher::neighbour_wedges`]),
    /// those where the union of the own wedges of the listed and gone
    /// leaves there changed too: before, that of the shadings `before` (the
    /// listed and gone leaves' old ones, by key); now, that of the listed
    /// leaves' kept ones. By key.
    #[inline(never)]
    fn surroundings_changed(
        &self,
        octree: &Octree,
        listed: &[CellKey],
        before: &[(CellKey, CellShading)],
        mut maybe: Vec<(CellKey, usize)>,
    ) -> Vec<CellKey> {
        maybe.sort_unstable();
        maybe.dedup();
        let mut indices = Indices::default();
        let mut out: Vec<CellKey> = Vec::new();
        for (other, j) in maybe {
            if out.last() == Some(&other) {
                continue;
            }
            let theirs = &self.shading[&other];
            let (p, q) = (&theirs.points[j], theirs.points_f64[j]);
            if self.union_changed(octree, listed, before, &mut indices, p, q) {
                out.push(other);
            }
        }
        out
    }

    /// Whether the merged union of the own wedges at `p` (at `q`) of the
    /// leaves `before` differs from that of the listed leaves now.
    fn union_changed(
        &self,
        octree: &Octree,
        listed: &[CellKey],
        before: &[(CellKey, CellShading)],
        indices: &mut Indices,
        p: &Point4,
        q: [f64; 3],
    ) -> bool {
        let mut old = Vec::new();
        for (key, shading) in before {
            if may_be_in_box(q, &octree.cell_box(*key)) {
                old.extend_from_slice(indices.wedges_at(shading, p, q));
            }
        }
        let mut new = Vec::new();
        for key in listed {
            if let Some(shading) = self.shading.get(key)
                && may_be_in_box(q, &octree.cell_box(*key))
            {
                new.extend_from_slice(indices.wedges_at(shading, p, q));
            }
        }
        merge_wedges(&mut old);
        merge_wedges(&mut new);
        old != new
    }

    /// Per leaf of `keys` (sorted), the own wedges of its neighbours
    /// `near` at its shaded points, as `(vertex of its sealed mesh,
    /// wedges)`. With `before` (the old shadings of the leaves of `keys`
    /// and the gone ones, by key), also the shaded points of the
    /// neighbours not in `keys` where the leaf's own wedges differ from
    /// its old ones, or the leaf is new, as `(neighbour, point)`: where the
    /// surroundings of that neighbour may have changed. A point on several
    /// leaves of `keys` is looked at from each, so where a leaf's own
    /// wedges stay, the union over all of them changes only through
    /// another.
    #[inline(never)]
    fn neighbour_wedges(
        &self,
        octree: &Octree,
        keys: &[CellKey],
        near: &[Vec<CellKey>],
        before: Option<&[(CellKey, CellShading)]>,
    ) -> (Vec<Vec<(u32, &[Wedge])>>, Vec<(CellKey, usize)>) {
        let per_leaf: Vec<(Vec<(u32, &[Wedge])>, Vec<(CellKey, usize)>)> = keys
            .par_iter()
            .zip(near)
            .map(|(key, near)| {
                let own = self.shading.get(key);
                let old = before.map(|before| {
                    before
                        .binary_search_by_key(key, |(k, _)| *k)
                        .ok()
                        .map(|i| &before[i].1)
                });
                let cell = octree.cell_box(*key);
                let index = own.map(PointIndex::of);
                let mut old_index: Option<PointIndex> = None;
                let mut more = Vec::with_capacity(own.map_or(0, |own| 2 * own.points.len()));
                let mut maybe = Vec::new();
                for &other in near {
                    let outside = old.is_some() && keys.binary_search(&other).is_err();
                    if own.is_none() && !outside {
                        continue;
                    }
                    let Some(theirs) = self.shading.get(&other) else {
                        continue;
                    };
                    for j in theirs.facing(&octree.cell_box(other), &cell) {
                        let (p, q) = (&theirs.points[j], theirs.points_f64[j]);
                        if !may_be_in_box(q, &cell) {
                            continue;
                        }
                        let found = own
                            .zip(index.as_ref())
                            .and_then(|(own, index)| index.find(own, p, q).map(|i| (own, i)));
                        if let Some((own, i)) = found {
                            more.push((own.vertices[i], theirs.wedges(j)));
                        }
                        if outside {
                            let now = found.map_or(&[][..], |(own, i)| own.wedges(i));
                            let changed = match old {
                                Some(Some(old)) => {
                                    let index =
                                        old_index.get_or_insert_with(|| PointIndex::of(old));
                                    let was =
                                        index.find(old, p, q).map_or(&[][..], |i| old.wedges(i));
                                    was != now
                                }
                                _ => true,
                            };
                            if changed {
                                maybe.push((other, j));
                            }
                        }
                    }
                }
                (more, maybe)
            })
            .collect();
        let mut maybe = Vec::new();
        let more = per_leaf
            .into_iter()
            .map(|(more, m)| {
                maybe.extend(m);
                more
            })
            .collect();
        (more, maybe)
    }

    /// Seals leaf `key`'s unsealed mesh at the neighbours' wall points
    /// `extra` (the mesh an update would hand back for it), with its own
    /// surface and shaded points.
    fn seal_shaded(
        &self,
        key: CellKey,
        cell: &CellBox,
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
        let shading = own_shading(&mesh, wall, own, cell);
        (mesh, Some(shading))
    }
}

/// The own surface around the border vertices of a sealed `mesh` (the
/// other vertices get no wedges) and its shaded points, given the vertices `wall` of its unsealed mesh on the cell's
/// walls and that mesh's vertex count `own` (the vertices from `own` on
/// are seam points, all on walls), in the leaf's box `cell`.
pub(super) fn own_shading(
    mesh: &SurfaceMesh,
    mut wall: Vec<u32>,
    own: u32,
    cell: &CellBox,
) -> (SurfaceAround, CellShading) {
    wall.extend(own..mesh.vertices().len() as u32);
    let around = mesh.surface_around_at(&wall);
    let shading = CellShading::of(mesh, wall, &around, cell);
    (around, shading)
}

/// Every leaf of an update with its neighbours' wedges added (`foreign`,
/// in the order of `cells`), and `None` for every gone key, by key.
fn finish(
    cells: Vec<(CellKey, SurfaceMesh, SurfaceAround)>,
    foreign: Vec<Vec<(u32, &[Wedge])>>,
    gone: Vec<CellKey>,
) -> Vec<(CellKey, Option<ShadedCell>)> {
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

/// The [`PointIndex`] of each shading asked so far, by address (the
/// shadings outlive it).
#[derive(Default)]
struct Indices(std::collections::HashMap<*const CellShading, PointIndex>);

impl Indices {
    /// The own wedges of `shading` at `p` (at `q`); none where it does not
    /// have the point.
    fn wedges_at<'a>(&mut self, shading: &'a CellShading, p: &Point4, q: [f64; 3]) -> &'a [Wedge] {
        let index = self
            .0
            .entry(std::ptr::from_ref(shading))
            .or_insert_with(|| PointIndex::of(shading));
        index.find(shading, p, q).map_or(&[], |i| shading.wedges(i))
    }
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

/// The walls of the box `cell` (`2·axis + upper`, one bit each) that the
/// exact point at `f64` position `q` may lie on: those within a margin of
/// `2^-40` of the box's coordinates (far more than the rounding of `q`).
pub(super) fn near_walls(q: [f64; 3], cell: &CellBox) -> u8 {
    let mut walls = 0;
    for (a, &c) in q.iter().enumerate() {
        for (upper, at) in [(0, cell.min[a]), (1, cell.max[a])] {
            let at = at as f64;
            let margin = (at.abs() + 1.0) * f64::powi(2.0, -40);
            if (c - at).abs() <= margin {
                walls |= 1 << (2 * a + upper);
            }
        }
    }
    walls
}

/// Whether two `f64` positions of exact points may be the same point
/// (each within `2^-51` relative; a margin of `2^-40`).
pub(super) fn close(a: [f64; 3], b: [f64; 3]) -> bool {
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
