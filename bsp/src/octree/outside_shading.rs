//! The surface of other octrees around points on this octree's cube, for
//! smooth normals that agree across the cubes of neighbouring octrees (the
//! chunks of a large world), as [`super::shading`] makes them agree across
//! the cells of one octree.
//!
//! Notation as in [`super::shading`]; besides, an octree's *border
//! wedges* in a region are, at each shaded point of its leaves lying in
//! that region, the merged union of the own wedges of all its leaves
//! there ([`SeamedMesher::border_wedges_in`]); its *outside wedges* are
//! the border wedges of the octrees over neighbouring cubes on its cube
//! ([`SeamedMesher::set_outside_wedges`]).
//!
//! An update adds, at every shaded point of a leaf that lies on the cube
//! and has outside wedges, those wedges to the surface around it, so a
//! point's merged wedges in the sealed meshes of every octree that has it
//! are the same list: the merged union over all of them. When the outside
//! wedges at a point change (appear, go, or differ exactly), the leaves
//! with that shaded point are handed back too, sealed again from their
//! kept meshes, as for a neighbouring leaf's change of surface.
//!
//! Border wedges come from an octree's own leaves, never from outside
//! wedges, so they never depend on another octree's wedges; which points
//! carry them depends on the outside points (they are vertices of the
//! sealed meshes), so after an exchange of points, one of wedges settles
//! the border.
//!
//! A point that is a vertex of one octree's meshes but lies strictly
//! inside a polygon of another's (only a polygon lying in the shared side
//! can, such as a chunk's side wall, facing into the first octree) is no
//! shaded point there: that polygon's whole-plane wedge is not added.

use super::cell::{CellBox, CellKey};
use super::seams::{SeamedMesher, boxes_around, in_closed_box, may_be_in_box, same_point};
use super::shading::{close, near_walls};
use super::tree::Octree;
use crate::exact::Point4;
use crate::mesh::weld::Welder;
use crate::mesh::{Wedge, merge_wedges};

/// Points with their merged wedges: border or outside wedges.
pub type PointWedges = Vec<(Point4, Vec<Wedge>)>;

/// The outside wedges a mesher holds, by point, and the points whose
/// wedges changed since the last update.
#[derive(Clone, Debug, Default)]
pub(super) struct OutsideWedges {
    points: Vec<Point4>,
    /// Their `f64` positions, for cheap filters.
    points_f64: Vec<[f64; 3]>,
    /// Point `i`'s wedges are `wedges[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    wedges: Vec<Wedge>,
    /// `(x, point)` sorted by the `f64` x, to find a point.
    by_x: Vec<(f64, u32)>,
    /// Points whose wedges appeared, went or changed since the last
    /// update.
    pub(super) changed: Vec<Point4>,
}

impl OutsideWedges {
    /// Whether no point has outside wedges.
    pub(super) fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Replaces the wedges by `list` (points may repeat: their wedges are
    /// merged together), noting the points whose wedges changed.
    fn set(&mut self, list: PointWedges) {
        let mut welder = Welder::with_capacity(list.len());
        let mut grouped: Vec<Vec<Wedge>> = Vec::with_capacity(list.len());
        for (p, wedges) in list {
            let i = welder.index(&p) as usize;
            if i == grouped.len() {
                grouped.push(Vec::new());
            }
            grouped[i].extend(wedges);
        }
        let mut new = Self {
            changed: std::mem::take(&mut self.changed),
            ..Self::default()
        };
        new.start.push(0);
        for (p, mut wedges) in welder.into_vertices().into_iter().zip(grouped) {
            merge_wedges(&mut wedges);
            if wedges.is_empty() {
                continue;
            }
            let q = p.to_f64();
            new.by_x.push((q[0], new.points.len() as u32));
            new.points.push(p);
            new.points_f64.push(q);
            new.wedges.extend(wedges);
            new.start.push(new.wedges.len() as u32);
        }
        new.by_x.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        for (i, (p, q)) in new.points.iter().zip(&new.points_f64).enumerate() {
            if self.at(p, *q) != Some(new.of(i)) {
                new.changed.push(*p);
            }
        }
        for (i, (p, q)) in self.points.iter().zip(&self.points_f64).enumerate() {
            if new.find(p, *q).is_none() {
                new.changed.push(*p);
            }
            debug_assert!(!self.of(i).is_empty());
        }
        *self = new;
    }

    /// The wedges of point `i`.
    fn of(&self, i: usize) -> &[Wedge] {
        &self.wedges[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// The index of `p` (at `f64` position `q`), exactly.
    fn find(&self, p: &Point4, q: [f64; 3]) -> Option<usize> {
        let margin = (q[0].abs() + 1.0) * f64::powi(2.0, -40);
        let first = self.by_x.partition_point(|&(x, _)| x < q[0] - margin);
        self.by_x[first..]
            .iter()
            .take_while(|&&(x, _)| x <= q[0] + margin)
            .map(|&(_, i)| i as usize)
            .find(|&i| close(self.points_f64[i], q) && same_point(&self.points[i], p))
    }

    /// The wedges at `p` (at `q`), if it has any.
    pub(super) fn at(&self, p: &Point4, q: [f64; 3]) -> Option<&[Wedge]> {
        self.find(p, q).map(|i| self.of(i))
    }

    /// Every point with its wedges.
    fn to_list(&self) -> PointWedges {
        (0..self.points.len())
            .map(|i| (self.points[i], self.of(i).to_vec()))
            .collect()
    }
}

impl SeamedMesher {
    /// The border wedges of `octree` (the octree of the last update) in
    /// the closed box `region`: at each shaded point of its leaves lying
    /// there, exactly, the merged own wedges of every leaf that has it,
    /// each position once, in leaf order. With `region` the part of a
    /// neighbouring octree's cube this cube shares, what that octree's
    /// mesher takes as outside wedges. Empty for a mesher without shading
    /// ([`SeamedMesher::with_shading`]).
    #[must_use]
    pub fn border_wedges_in(&self, octree: &Octree, region: &CellBox) -> PointWedges {
        let mut welder = Welder::with_capacity(0);
        let mut grouped: Vec<Vec<Wedge>> = Vec::new();
        octree.for_leaves_touching_each(std::slice::from_ref(region), |key, _| {
            let Some(shading) = self.shading.get(&key) else {
                return;
            };
            for j in 0..shading.points.len() {
                let p = &shading.points[j];
                if may_be_in_box(shading.points_f64[j], region) && in_closed_box(p, region) {
                    let i = welder.index(p) as usize;
                    if i == grouped.len() {
                        grouped.push(Vec::new());
                    }
                    grouped[i].extend_from_slice(shading.wedges(j));
                }
            }
        });
        welder
            .into_vertices()
            .into_iter()
            .zip(grouped)
            .map(|(p, mut wedges)| {
                merge_wedges(&mut wedges);
                (p, wedges)
            })
            .collect()
    }

    /// Sets the outside wedges: the border wedges of the meshers of
    /// octrees over neighbouring cubes on this octree's cube
    /// ([`SeamedMesher::border_wedges_in`]; a point given by several is
    /// merged over all), added to the surface around the shaded points of
    /// the leaves on the cube (see [`super::outside_shading`]). The next
    /// [`SeamedMesher::update_shaded`] hands back every leaf with a
    /// shaded point whose outside wedges changed, whatever keys it is
    /// given. A mesher without shading keeps them but uses none.
    pub fn set_outside_wedges(&mut self, wedges: PointWedges) {
        self.outside_wedges.set(wedges);
        if !self.shaded {
            self.outside_wedges.changed.clear();
        }
    }

    /// The outside wedges, each point once with its merged wedges
    /// ([`SeamedMesher::set_outside_wedges`]).
    #[must_use]
    pub fn outside_wedges(&self) -> PointWedges {
        self.outside_wedges.to_list()
    }

    /// The leaves not in `listed` (sorted) with a shaded point among
    /// `changed`, by key: those whose outside wedges changed.
    pub(super) fn touched_by_outside(
        &self,
        octree: &Octree,
        changed: &[Point4],
        listed: &[CellKey],
    ) -> Vec<CellKey> {
        if changed.is_empty() {
            return Vec::new();
        }
        let positions: Vec<[f64; 3]> = changed.iter().map(Point4::to_f64).collect();
        let around = boxes_around(&positions);
        let mut out = Vec::new();
        octree.for_leaves_touching_each(&around, |key, hits| {
            if listed.binary_search(&key).is_ok() {
                return;
            }
            let Some(shading) = self.shading.get(&key) else {
                return;
            };
            let has = hits.iter().any(|&i| {
                (0..shading.points.len()).any(|j| {
                    close(shading.points_f64[j], positions[i])
                        && same_point(&shading.points[j], &changed[i])
                })
            });
            if has {
                out.push(key);
            }
        });
        out.sort_unstable();
        out
    }

    /// Per leaf of `keys` (each with the shading kept for the mesh handed
    /// back), its outside wedges as `(vertex of its sealed mesh, wedges)`,
    /// appended to `foreign` (in the order of `keys`).
    pub(super) fn add_outside_wedges<'a>(
        &'a self,
        octree: &Octree,
        keys: &[CellKey],
        foreign: &mut [Vec<(u32, &'a [Wedge])>],
    ) {
        if self.outside_wedges.is_empty() {
            return;
        }
        let root = octree.root_box();
        for (key, more) in keys.iter().zip(foreign) {
            let cell = octree.cell_box(*key);
            let on_side = (0..3).any(|a| cell.min[a] == root.min[a] || cell.max[a] == root.max[a]);
            if !on_side {
                continue;
            }
            let Some(shading) = self.shading.get(key) else {
                continue;
            };
            for j in 0..shading.points.len() {
                let (p, q) = (&shading.points[j], shading.points_f64[j]);
                if near_walls(q, &root) == 0 {
                    continue;
                }
                if let Some(wedges) = self.outside_wedges.at(p, q) {
                    more.push((shading.vertices[j], wedges));
                }
            }
        }
    }
}
