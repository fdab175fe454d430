//! Crack-free seams between cell meshes (paper 1 §3.4 across cells).
//!
//! Notation: the *neighbours* of a leaf are the other leaves whose closed
//! box shares a point with its closed box (across a face, an edge or a
//! corner, at any depth); a leaf's *walls* are the six planes of its box,
//! its *wall points* the vertices of its merged, unsplit surface mesh
//! lying on them ([`UnsealedMesh::wall_vertices`]), its *border edges* the
//! edges of that mesh lying in a wall, and its *seam points* the wall
//! points of its neighbours strictly inside one of its border edges, no
//! vertex of its own.
//!
//! A *sealed* cell mesh is its surface split at every T-junction, and
//! every border edge also at the neighbours' wall points inside it
//! ([`crate::mesh::seal`]). Every vertex of any cell's sealed mesh is a
//! wall point of some cell, and one on an edge of another cell's mesh lies
//! on both closed boxes, so it is a wall point of a neighbour there: the
//! sealed meshes of all leaves meet edge to edge with identical exact
//! vertices, whatever the cells' sizes.
//!
//! [`SeamedMesher`] keeps each leaf's wall points, border edges and seam
//! points between edits, so that meshing a cell needs its neighbours'
//! wall points only, not their surfaces. It also keeps each leaf's
//! unsealed mesh, so that a leaf whose surface did not change but whose
//! seams did is only sealed again, not cut out of its tree again. A leaf
//! outside the edited cells is meshed again in two cases only:
//!
//! - a wall point gained or lost by a cell meshed in this update lies
//!   strictly inside one of its border edges (and is no vertex of its
//!   own), and its seam points, recomputed, differ from those kept: its
//!   kept unsealed mesh is sealed again;
//! - one of its polygons lies in a wall and shares area with a cell whose
//!   leaf was replaced: that face is clipped against the new leaf (the
//!   same surface, possibly in other pieces, cut again from
//!   [`Octree::cell_surface`]), and its wall points differ.
//!
//! Either may change its wall points in turn, so both repeat until no
//! wall point changes; a cell's own wall points change at most once.
//!
//! *Outside points* ([`SeamedMesher::set_outside_points`]) are wall points
//! of another octree's mesher lying on this octree's cube, where two
//! octrees over neighbouring cubes meet (the chunks of a large world).
//! They count as the wall points of one more neighbour of every leaf
//! whose closed box holds them, so the border edges on the cube's sides
//! are split at them too; when they change, the leaves whose seams they
//! change are sealed again at the next update, as for a neighbour's wall
//! points. Each octree's wall points come from its own unsealed meshes,
//! so two meshers that take each other's
//! ([`SeamedMesher::wall_points_in`]) need one exchange, not a loop.
//!
//! A mesher made with [`SeamedMesher::with_shading`] also keeps the
//! surface around every leaf's border vertices and hands it back with the
//! sealed meshes, for smooth normals that agree across cell borders
//! ([`super::shading`]), and across the cubes of neighbouring octrees
//! with *outside wedges* ([`super::outside_shading`]).

use std::collections::{BTreeMap, BTreeSet};

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::outside_shading::OutsideWedges;
use super::shading::{CellShading, SealedLeaf, ShadedCell, own_shading};
use super::tree::{Leaf, OctNode, Octree};
use crate::exact::{Plane, Point4};
use crate::exact::{Sign, classify_vertex};
use crate::mesh::weld::Welder;
use crate::mesh::{BorderEdge, SurfaceAround, SurfaceMesh, UnsealedMesh};
use crate::tree::BoundaryFace;

impl Octree {
    /// Every leaf whose closed box shares a point with the closed box
    /// `region` (the leaves holding it and their neighbours across faces,
    /// edges and corners), in leaf order ([`Octree::leaves`]).
    #[must_use]
    pub fn leaves_touching(&self, region: &CellBox) -> Vec<CellKey> {
        let mut out = Vec::new();
        self.for_leaves_touching_each(std::slice::from_ref(region), |key, _| out.push(key));
        out
    }

    /// [`Octree::leaves_touching`] for many regions in one walk: calls
    /// `visit` with every leaf whose closed box shares a point with one of
    /// the closed boxes `regions`, in leaf order, and the indices of those
    /// regions (ascending).
    pub fn for_leaves_touching_each(
        &self,
        regions: &[CellBox],
        mut visit: impl FnMut(CellKey, &[usize]),
    ) {
        let root = self.root_box();
        // The region indices of every node on the stack, one run each.
        let mut runs: Vec<usize> = (0..regions.len())
            .filter(|&i| root.touches(&regions[i]))
            .collect();
        let mut stack = vec![(&self.root, CellKey::ROOT, 0..runs.len())];
        // Per region of the run on top, the children it touches.
        let mut children_touched: Vec<u8> = Vec::new();
        while let Some((node, key, run)) = stack.pop() {
            match node {
                OctNode::Leaf(_) => visit(key, &runs[run.clone()]),
                OctNode::Inner(children) => {
                    let mid = self.cell_box(key).mid();
                    children_touched.clear();
                    children_touched.extend(
                        runs[run.clone()]
                            .iter()
                            .map(|&r| children_touching(&regions[r], mid)),
                    );
                    for i in (0..8).rev() {
                        let start = runs.len();
                        for (k, &touched) in run.clone().zip(&children_touched) {
                            if touched & (1 << i) != 0 {
                                runs.push(runs[k]);
                            }
                        }
                        if runs.len() > start {
                            stack.push((&children[i], key.child(i), start..runs.len()));
                        }
                    }
                }
            }
            // The runs past the one on top of the stack are done with.
            runs.truncate(stack.last().map_or(0, |(_, _, run)| run.end));
        }
    }

    /// The sealed mesh of leaf `key` (empty when `key` is not a leaf),
    /// from scratch: the surfaces of all its neighbours are meshed here to
    /// find their wall points. The same mesh as a first
    /// [`SeamedMesher::update`] over all leaves gives for `key`; that one
    /// is far cheaper per cell.
    #[must_use]
    pub fn sealed_cell_mesh(&self, key: CellKey) -> SurfaceMesh {
        if self.leaf(key).is_none() {
            return SurfaceMesh::default();
        }
        let cell = self.cell_box(key);
        let mut extra = Vec::new();
        for other in self.leaves_touching(&cell) {
            if other != key {
                let mesh =
                    UnsealedMesh::new(self.cell_surface(other), &walls(&self.cell_box(other)));
                extra.extend(
                    mesh.wall_vertices()
                        .filter(|p| may_be_in_box(p.to_f64(), &cell))
                        .copied(),
                );
            }
        }
        UnsealedMesh::new(self.cell_surface(key), &walls(&cell))
            .seal(&extra)
            .0
    }
}

/// What a [`SeamedMesher`] keeps of one leaf: its wall points, border
/// edges and seam points (see the module docs).
#[derive(Clone, Debug, Default)]
pub(super) struct CellBorder {
    wall_points: Vec<Point4>,
    /// Their `f64` positions ([`Point4::to_f64`]), for cheap filters.
    wall_f64: Vec<[f64; 3]>,
    pub(super) edges: Vec<BorderEdge>,
    seams: Vec<Point4>,
    /// The polygons lying in a wall: the wall (`2·axis + upper`) and the
    /// `f64` box of the corners.
    exposed: Vec<(usize, [f64; 3], [f64; 3])>,
}

/// Sealed meshes of octree leaves kept up to date across edits: after
/// every edit (or undo), [`SeamedMesher::update`] meshes the cells it may
/// have changed, and the neighbours whose seams it changed.
///
/// Holds, per leaf with a wall point, its wall points, border edges and
/// seam points (a few exact points and planes per cell of the surface).
#[derive(Clone, Debug, Default)]
pub struct SeamedMesher {
    pub(super) borders: BTreeMap<CellKey, CellBorder>,
    /// The leaf each meshed cell held when last meshed (shared with the
    /// octree, so no copy): an edited cell whose leaf is the same stored
    /// value was only touched, and its neighbours' faces are clipped
    /// against it as before.
    leaves: BTreeMap<CellKey, Leaf>,
    /// The unsealed mesh of every leaf meshed so far, as of the last
    /// update: what [`Octree::cell_surface`] gives while the leaf and the
    /// leaves it faces across its walls stay the same.
    pub(super) unsealed: BTreeMap<CellKey, UnsealedMesh>,
    /// The outside points, distinct, with their `f64` positions.
    outside: Vec<Point4>,
    outside_f64: Vec<[f64; 3]>,
    /// Outside points gained or lost since the last update.
    outside_changed: Vec<Point4>,
    /// Whether the shaded points of every leaf are kept
    /// ([`SeamedMesher::with_shading`]).
    pub(super) shaded: bool,
    /// Per leaf with shaded points, those points and its own wedges
    /// there ([`super::shading`]).
    pub(super) shading: BTreeMap<CellKey, CellShading>,
    /// The surface of other octrees around points on the cube
    /// ([`super::outside_shading`]).
    pub(super) outside_wedges: OutsideWedges,
}

impl SeamedMesher {
    /// A mesher that knows no cell yet: its first update should list every
    /// leaf (`octree.leaves()`).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Leaves whose wall points are kept (those with surface on their box).
    #[must_use]
    pub fn cells(&self) -> usize {
        self.borders.len()
    }

    /// The wall points kept for leaf `key` (empty when none are).
    #[must_use]
    pub fn wall_points(&self, key: CellKey) -> &[Point4] {
        self.borders
            .get(&key)
            .map_or(&[][..], |b| b.wall_points.as_slice())
    }

    /// The points outside the octree's cells that border edges are also
    /// split at ([`SeamedMesher::set_outside_points`]), distinct.
    #[must_use]
    pub fn outside_points(&self) -> &[Point4] {
        &self.outside
    }

    /// Sets the outside points: wall points of the meshers of octrees over
    /// neighbouring cubes that lie on this octree's cube
    /// ([`SeamedMesher::wall_points_in`] of that cube), which the border
    /// edges on the cube's sides are split at like a neighbouring leaf's
    /// wall points (see the module docs). Points off the cube split
    /// nothing. The next [`SeamedMesher::update`] seals again every leaf
    /// whose seams the points gained or lost change, whatever `keys` it is
    /// given (none: only those); before a first update, set them and every
    /// leaf is sealed with them.
    pub fn set_outside_points(&mut self, points: Vec<Point4>) {
        let mut welder = Welder::with_capacity(self.outside.len() + points.len());
        // Per distinct point: bit 0 if it was an outside point, bit 1 if
        // it is one now.
        let mut held: Vec<u8> = Vec::with_capacity(self.outside.len() + points.len());
        for (list, bit) in [(&self.outside, 1u8), (&points, 2u8)] {
            for p in list {
                let i = welder.index(p) as usize;
                if i == held.len() {
                    held.push(0);
                }
                held[i] |= bit;
            }
        }
        let all = welder.into_vertices();
        self.outside_changed.extend(
            all.iter()
                .zip(&held)
                .filter(|&(_, &h)| h == 1 || h == 2)
                .map(|(p, _)| *p),
        );
        self.outside = all
            .into_iter()
            .zip(&held)
            .filter(|&(_, &h)| h & 2 != 0)
            .map(|(p, _)| p)
            .collect();
        self.outside_f64 = self.outside.iter().map(Point4::to_f64).collect();
    }

    /// The wall points kept for the leaves of `octree` (the octree of the
    /// last update) that lie in the closed box `region`, exactly, each
    /// position once, in leaf order: with `region` the cube of a
    /// neighbouring octree, what that octree's mesher takes as outside
    /// points.
    #[must_use]
    pub fn wall_points_in(&self, octree: &Octree, region: &CellBox) -> Vec<Point4> {
        let mut welder = Welder::with_capacity(0);
        octree.for_leaves_touching_each(std::slice::from_ref(region), |key, _| {
            let Some(border) = self.borders.get(&key) else {
                return;
            };
            for (p, q) in border.wall_points.iter().zip(&border.wall_f64) {
                if may_be_in_box(*q, region) && in_closed_box(p, region) {
                    welder.index(p);
                }
            }
        });
        welder.into_vertices()
    }

    /// Meshes the cells `keys` of `octree` that an edit or undo may have
    /// changed ([`Changes::changed`](super::Changes::changed) and
    /// [`Changes::removed`](super::Changes::removed); every leaf for a
    /// first build), and the other leaves whose meshes that changes (see
    /// the module docs), and hands back each one's sealed mesh, sorted by
    /// key: `None` for a key that is no longer a leaf (it is forgotten),
    /// else the mesh (empty where the cell has no surface). A leaf in
    /// `fresh` is meshed from those boundary faces
    /// ([`Octree::apply_with_faces`], [`Octree::cell_surface_from`])
    /// rather than cut again: the same surface, possibly in other pieces
    /// than a build from the octree gives, so with `fresh` the meshes are
    /// sealed and watertight together but need not equal a first build.
    ///
    /// The leaves not listed must hold the surface they had at the last
    /// update. Cells run in parallel; the result does not depend on the
    /// thread count. A mesher [`SeamedMesher::with_shading`] also hands
    /// back the leaves whose surroundings changed
    /// ([`SeamedMesher::update_shaded`]).
    pub fn update(
        &mut self,
        octree: &Octree,
        keys: impl IntoIterator<Item = CellKey>,
        fresh: BTreeMap<CellKey, Vec<BoundaryFace>>,
    ) -> Vec<(CellKey, Option<SurfaceMesh>)> {
        self.update_shaded(octree, keys, fresh)
            .into_iter()
            .map(|(key, cell)| (key, cell.map(|cell| cell.mesh)))
            .collect()
    }

    /// [`SeamedMesher::update`], handing back with each sealed mesh the
    /// surface around each of its vertices: for a mesher
    /// [`SeamedMesher::with_shading`], the wedges of every leaf's surface
    /// there (see [`super::shading`]), and the leaves whose meshes stay
    /// but whose border vertices' surroundings changed are handed back too;
    /// otherwise no wedges at all.
    pub fn update_shaded(
        &mut self,
        octree: &Octree,
        keys: impl IntoIterator<Item = CellKey>,
        mut fresh: BTreeMap<CellKey, Vec<BoundaryFace>>,
    ) -> Vec<(CellKey, Option<ShadedCell>)> {
        let mut keys: Vec<CellKey> = keys.into_iter().chain(fresh.keys().copied()).collect();
        keys.sort_unstable();
        keys.dedup();
        let (live, gone): (Vec<CellKey>, Vec<CellKey>) =
            keys.iter().partition(|&&key| octree.leaf(key).is_some());
        let jobs: Vec<(CellKey, Option<Vec<BoundaryFace>>)> =
            live.iter().map(|&key| (key, fresh.remove(&key))).collect();
        // The cells to seal, each with its new unsealed mesh, or `None`
        // where the kept one is still right.
        let mut pending: Pending = jobs
            .into_par_iter()
            .map(|(key, faces)| {
                let faces = match faces {
                    Some(faces) => octree.cell_surface_from(key, faces),
                    None => octree.cell_surface(key),
                };
                (
                    key,
                    Some(UnsealedMesh::new(faces, &walls(&octree.cell_box(key)))),
                )
            })
            .collect::<Vec<_>>()
            .into_iter()
            .collect();
        // Outside points gained or lost count as changed wall points.
        let mut changed = std::mem::take(&mut self.outside_changed);
        for key in &gone {
            self.leaves.remove(key);
            self.unsealed.remove(key);
            if let Some(old) = self.borders.remove(key) {
                changed.extend(old.wall_points);
            }
        }
        let mut replaced = Vec::new();
        for &key in &live {
            let leaf = octree.leaf(key).expect("a live key is a leaf");
            if !self.leaves.get(&key).is_some_and(|old| old.same_as(leaf)) {
                replaced.push(key);
                self.leaves.insert(key, leaf.clone());
            }
        }
        for (key, mesh) in &pending {
            if let Some(mesh) = mesh {
                self.record(*key, mesh, &mut changed);
            }
        }
        // Leaves with a face on a wall against an edited cell: the face is
        // clipped against that cell's new tree, the same surface possibly
        // in other pieces (with other wall points).
        let this = &*self;
        let facing = this.facing(octree, &replaced, &pending);
        let again: Vec<(CellKey, UnsealedMesh, bool)> = facing
            .into_par_iter()
            .map(|key| {
                let mesh =
                    UnsealedMesh::new(octree.cell_surface(key), &walls(&octree.cell_box(key)));
                let same = same_set(
                    &mesh.wall_vertices().copied().collect::<Vec<_>>(),
                    this.wall_points(key),
                );
                (key, mesh, same)
            })
            .collect();
        for (key, mesh, same) in again {
            if same {
                // The same wall points, so the same seams: the sealed mesh
                // on screen stays, but the kept one follows the octree.
                self.unsealed.insert(key, mesh);
            } else {
                self.record(key, &mesh, &mut changed);
                pending.insert(key, Some(mesh));
            }
        }
        // The neighbours whose seams the changed wall points change, meshed
        // again (from the octree); where that changes their own wall
        // points, their neighbours in turn.
        while !changed.is_empty() {
            let this = &*self;
            let candidates = this.touched_by(octree, &changed, &pending);
            let around = this.extra_points_of(octree, &candidates);
            let again: Vec<(CellKey, Option<UnsealedMesh>)> = candidates
                .into_par_iter()
                .zip(around)
                .filter_map(|(key, extra)| this.remesh_if_seams_change(octree, key, &extra))
                .collect();
            changed.clear();
            for (key, mesh) in again {
                match mesh {
                    Some(mesh) => {
                        self.record(key, &mesh, &mut changed);
                        pending.insert(key, Some(mesh));
                    }
                    None => {
                        if let Some(kept) = self.unsealed.remove(&key) {
                            self.record(key, &kept, &mut changed);
                            self.unsealed.insert(key, kept);
                        }
                        pending.insert(key, None);
                    }
                }
            }
        }
        let this = &*self;
        let pending: Vec<(CellKey, Option<UnsealedMesh>)> = pending.into_iter().collect();
        let keys: Vec<CellKey> = pending.iter().map(|(key, _)| *key).collect();
        let (around, near) = this.extra_points_and_neighbours(octree, &keys);
        let shaded = self.shaded;
        let sealed: Vec<(CellKey, SealedLeaf, Vec<Point4>, Option<UnsealedMesh>)> = pending
            .into_par_iter()
            .zip(around)
            .map(|((key, mesh), extra)| {
                let unsealed = mesh.as_ref().or_else(|| this.unsealed.get(&key));
                // Recorded from this very mesh (none where it has no wall
                // point, so no border edge).
                let edges = this
                    .borders
                    .get(&key)
                    .map_or(&[][..], |b| b.edges.as_slice());
                let (sealed, seams, shading) = unsealed.map_or_else(
                    || (SurfaceMesh::default(), Vec::new(), None),
                    |mesh| {
                        let wall =
                            shaded.then(|| (mesh.wall_vertex_indices(), mesh.vertex_count()));
                        let (sealed, seams) = mesh.clone().seal_with_edges(extra, edges);
                        let shading = wall.map(|(wall, own)| {
                            own_shading(&sealed, wall, own as u32, &octree.cell_box(key))
                        });
                        (sealed, seams, shading)
                    },
                );
                (key, (key, sealed, shading), seams, mesh)
            })
            .collect();
        let mut leaves = Vec::with_capacity(sealed.len());
        for (key, leaf, seams, unsealed) in sealed {
            if let Some(border) = self.borders.get_mut(&key) {
                border.seams = seams;
            }
            if let Some(unsealed) = unsealed {
                self.unsealed.insert(key, unsealed);
            }
            leaves.push(leaf);
        }
        if shaded {
            return self.shade(octree, leaves, near, gone);
        }
        let mut out: Vec<(CellKey, Option<ShadedCell>)> =
            gone.into_iter().map(|key| (key, None)).collect();
        out.extend(leaves.into_iter().map(|(key, mesh, _)| {
            let around = SurfaceAround::default();
            (key, Some(ShadedCell { mesh, around }))
        }));
        out.sort_unstable_by_key(|(key, _)| *key);
        out
    }

    /// Keeps the wall points and border edges of leaf `key` from its
    /// unsealed `mesh` (its seam points are set once it is sealed), and
    /// appends to `changed` the wall points it gained or lost.
    fn record(&mut self, key: CellKey, mesh: &UnsealedMesh, changed: &mut Vec<Point4>) {
        let new = CellBorder {
            wall_points: mesh.wall_vertices().copied().collect(),
            wall_f64: mesh.wall_vertices().map(Point4::to_f64).collect(),
            edges: mesh.border_edges(),
            seams: Vec::new(),
            exposed: mesh.wall_polygons(),
        };
        let old = if new.wall_points.is_empty() {
            self.borders.remove(&key)
        } else {
            self.borders.insert(key, new)
        };
        let old = old.map(|b| b.wall_points).unwrap_or_default();
        let now = self.wall_points(key);
        if !identical(&old, now) {
            changed.extend(
                old.iter()
                    .filter(|p| !now.iter().any(|q| same_digits(p, q))),
            );
            changed.extend(
                now.iter()
                    .filter(|q| !old.iter().any(|p| same_digits(p, q))),
            );
        }
    }

    /// The leaves not in `pending` with a polygon lying in a wall, across
    /// which that polygon shares area with the box of a `replaced` cell.
    fn facing(&self, octree: &Octree, replaced: &[CellKey], pending: &Pending) -> Vec<CellKey> {
        let cells: Vec<CellBox> = replaced.iter().map(|&key| octree.cell_box(key)).collect();
        let mut out = Vec::new();
        octree.for_leaves_touching_each(&cells, |key, near| {
            if pending.contains_key(&key) {
                return;
            }
            let Some(border) = self.borders.get(&key) else {
                return;
            };
            let own = octree.cell_box(key);
            let across = near
                .iter()
                .any(|&i| faces_across(&border.exposed, &own, &cells[i]));
            if across {
                out.push(key);
            }
        });
        out.sort_unstable();
        out
    }

    /// The leaves not in `pending` with a border edge strictly holding one
    /// of the `changed` points that is no wall point of their own, by key:
    /// the only leaves whose seam points may change.
    fn touched_by(&self, octree: &Octree, changed: &[Point4], pending: &Pending) -> Vec<CellKey> {
        let positions: Vec<[f64; 3]> = changed.iter().map(Point4::to_f64).collect();
        let around = boxes_around(&positions);
        let mut near = BTreeSet::new();
        octree.for_leaves_touching_each(&around, |key, points| {
            if !pending.contains_key(&key)
                && let Some(border) = self.borders.get(&key)
                && points.iter().any(|&i| {
                    let (p, q) = (&changed[i], positions[i]);
                    // The `f64` box first: most edges are far.
                    border
                        .edges
                        .iter()
                        .any(|e| e.may_hold(q) && e.holds_strictly(p))
                        && !border.wall_points.iter().any(|w| same_point(w, p))
                })
            {
                near.insert(key);
            }
        });
        near.into_iter().collect()
    }

    /// Whether leaf `key` (not edited, with a changed point strictly
    /// inside one of its border edges) needs sealing again: its seam
    /// points among the neighbours' wall points `extra` differ from those
    /// kept. Hands back its unsealed mesh from the octree where none is
    /// kept (`None`: seal the kept one).
    fn remesh_if_seams_change(
        &self,
        octree: &Octree,
        key: CellKey,
        extra: &[&Point4],
    ) -> Option<(CellKey, Option<UnsealedMesh>)> {
        let border = self.borders.get(&key)?;
        let mut seams: Vec<Point4> = Vec::new();
        for &p in extra {
            let q = p.to_f64();
            if border
                .edges
                .iter()
                .any(|e| e.may_hold(q) && e.holds_strictly(p))
                && !border.wall_points.iter().any(|w| same_point(w, p))
                && !seams.iter().any(|s| same_point(s, p))
            {
                seams.push(*p);
            }
        }
        if same_set(&seams, &border.seams) {
            return None;
        }
        if self.unsealed.contains_key(&key) {
            return Some((key, None));
        }
        let mesh = UnsealedMesh::new(octree.cell_surface(key), &walls(&octree.cell_box(key)));
        Some((key, Some(mesh)))
    }

    /// The wall points of the neighbours of each leaf of `keys` that may
    /// lie on its closed box, neighbour by neighbour in leaf order: the
    /// points its border edges are split at.
    pub(super) fn extra_points_of(&self, octree: &Octree, keys: &[CellKey]) -> Vec<Vec<&Point4>> {
        self.extra_points_and_neighbours(octree, keys).0
    }

    /// [`Self::extra_points_of`], and per leaf of `keys` its neighbours
    /// with wall points (every leaf with shaded points among them).
    pub(super) fn extra_points_and_neighbours(
        &self,
        octree: &Octree,
        keys: &[CellKey],
    ) -> (Vec<Vec<&Point4>>, Vec<Vec<CellKey>>) {
        let cells: Vec<CellBox> = keys.iter().map(|&key| octree.cell_box(key)).collect();
        let mut extra = vec![Vec::new(); keys.len()];
        let mut neighbours: Vec<Vec<CellKey>> =
            (0..keys.len()).map(|_| Vec::with_capacity(32)).collect();
        octree.for_leaves_touching_each(&cells, |other, near| {
            let Some(border) = self.borders.get(&other) else {
                return;
            };
            for &i in near {
                if keys[i] != other {
                    neighbours[i].push(other);
                    extra[i].extend(
                        border
                            .wall_points
                            .iter()
                            .zip(&border.wall_f64)
                            .filter(|(_, q)| may_be_in_box(**q, &cells[i]))
                            .map(|(p, _)| p),
                    );
                }
            }
        });
        if !self.outside.is_empty() {
            let root = octree.root_box();
            for (cell, extra) in cells.iter().zip(&mut extra) {
                let on_side =
                    (0..3).any(|a| cell.min[a] == root.min[a] || cell.max[a] == root.max[a]);
                if on_side {
                    extra.extend(
                        self.outside
                            .iter()
                            .zip(&self.outside_f64)
                            .filter(|(_, q)| may_be_in_box(**q, cell))
                            .map(|(p, _)| p),
                    );
                }
            }
        }
        (extra, neighbours)
    }
}

/// Whether one of the polygons `exposed` lying in a wall of the leaf box
/// `own` shares area with the box `cell` across that wall.
fn faces_across(exposed: &[(usize, [f64; 3], [f64; 3])], own: &CellBox, cell: &CellBox) -> bool {
    exposed.iter().any(|&(wall, lo, hi)| {
        let axis = wall / 2;
        let at = if wall % 2 == 0 {
            own.min[axis]
        } else {
            own.max[axis]
        };
        let on_wall = if wall % 2 == 0 {
            cell.max[axis] == at
        } else {
            cell.min[axis] == at
        };
        // Widened far beyond the rounding of the corners, so that no
        // polygon sharing area is missed.
        let slack = f64::from(1u32 << 26) * f64::powi(2.0, -40);
        on_wall
            && (0..3)
                .filter(|&a| a != axis)
                .all(|a| lo[a] < cell.max[a] as f64 + slack && (cell.min[a] as f64) - slack < hi[a])
    })
}

/// The children (one bit each, as [`CellKey::child`] numbers them) of a
/// cell with centre `mid` whose closed boxes touch the closed box
/// `region`, which touches the cell: along each axis, the lower half
/// `[min, mid]` unless the region starts above `mid`, the upper half
/// `[mid, max]` unless it ends below (the same answers as
/// [`CellBox::touches`] with each child's box).
fn children_touching(region: &CellBox, mid: [i64; 3]) -> u8 {
    /// Per axis, the children in its upper half.
    const UPPER: [u8; 3] = [0b1010_1010, 0b1100_1100, 0b1111_0000];
    let mut touched = u8::MAX;
    for a in 0..3 {
        if region.min[a] > mid[a] {
            touched &= UPPER[a];
        }
        if region.max[a] < mid[a] {
            touched &= !UPPER[a];
        }
    }
    touched
}

/// The cells an update seals, by key: each with its new unsealed mesh, or
/// `None` where the kept one is still right.
type Pending = BTreeMap<CellKey, Option<UnsealedMesh>>;

/// The six planes of a box's faces, `x = min_x, x = max_x, y = min_y, …`.
fn walls(cell: &CellBox) -> [Plane; 6] {
    [0, 1, 2, 3, 4, 5].map(|i| {
        let axis = i / 2;
        let at = if i % 2 == 0 {
            cell.min[axis]
        } else {
            cell.max[axis]
        };
        axis_plane(axis, at)
    })
}

/// The plane `x_axis = at`, positive side above.
fn axis_plane(axis: usize, at: i64) -> Plane {
    let mut n = [0i64; 3];
    n[axis] = 1;
    Plane::new(n[0], n[1], n[2], -i128::from(at)).expect("cell coordinates are in range")
}

/// Whether the exact point at `f64` position `q` ([`Point4::to_f64`],
/// within `2^-51` relative) may lie in the closed box `cell`: false only
/// where `q` is farther outside than a margin of `2^-40` of the box's
/// coordinates. A cheap filter: the exact decisions are made against the
/// edges themselves.
pub(super) fn may_be_in_box(q: [f64; 3], cell: &CellBox) -> bool {
    q.iter().enumerate().all(|(axis, &c)| {
        let (lo, hi) = (cell.min[axis] as f64, cell.max[axis] as f64);
        let margin = (lo.abs().max(hi.abs()) + 1.0) * f64::powi(2.0, -40);
        lo - margin <= c && c <= hi + margin
    })
}

/// Whether the exact point `p` lies in the closed box `cell`.
pub(super) fn in_closed_box(p: &Point4, cell: &CellBox) -> bool {
    (0..3).all(|axis| {
        classify_vertex(p, &axis_plane(axis, cell.min[axis])) != Sign::Negative
            && classify_vertex(p, &axis_plane(axis, cell.max[axis])) != Sign::Positive
    })
}

/// Whether `a` and `b` are the same point (identical digits first).
pub(super) fn same_point(a: &Point4, b: &Point4) -> bool {
    (a.xyz_digits == b.xyz_digits && a.w_digits == b.w_digits) || a.same_position(b)
}

/// Whether the points have the same digits (the same point built the
/// same way).
fn same_digits(a: &Point4, b: &Point4) -> bool {
    a.xyz_digits == b.xyz_digits && a.w_digits == b.w_digits
}

/// Whether the lists hold the same points with the same digits, in order.
fn identical(a: &[Point4], b: &[Point4]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(p, q)| same_digits(p, q))
}

/// Whether the lists hold the same points, as sets.
fn same_set(a: &[Point4], b: &[Point4]) -> bool {
    a.iter().all(|p| b.iter().any(|q| same_point(p, q)))
        && b.iter().all(|q| a.iter().any(|p| same_point(p, q)))
}

/// Per `f64` position of an exact point, an integer box holding the point
/// with a margin of one grid unit (the position rounded out): the leaves
/// whose closed boxes touch it are all those that may hold the point.
pub(super) fn boxes_around(positions: &[[f64; 3]]) -> Vec<CellBox> {
    positions
        .iter()
        .map(|q| CellBox {
            min: q.map(|c| c.floor() as i64 - 1),
            max: q.map(|c| c.ceil() as i64 + 1),
        })
        .collect()
}
