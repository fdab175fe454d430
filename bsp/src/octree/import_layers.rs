//! Octree import of a heightfield with material layers by depth, in one
//! pass (paper 1 §3.9, with labelled faces as in §3.6).
//!
//! Notation: a *square* is the footprint of four neighbouring samples; its
//! *top* is two triangles split along the diagonal from sample `(i+1, j)`
//! to `(i, j+1)`; `L` is the *lower hull* of the square's four corners
//! (two triangles split along the diagonal that makes it convex from
//! below; `L ≤ top`); a *half* `τ` is one of the two triangles of `L`'s
//! split; band `k` has depth `d_k` and label `l_k`, and `S_k = L − d_k`
//! is its lower surface; `t = L(x, z) − y` is how far a point lies below
//! `L`.
//!
//! A point of the solid has the label of the shallowest band whose
//! surface it lies on or above (`t ≤ d_k`), else the field's own label —
//! the solid that painting band `k` with one convex column per square,
//! from `S_k` up past the top, deepest band first, gives. Here that solid
//! is written down as labelled faces and imported once:
//!
//! 1. Bands are sorted by depth (of equal depths the later one wins, as it
//!    painted last); the first band deeper than the field is high holds
//!    all the solid under the shallower ones, so those under it go and its
//!    depth is cut to that height; a band labelled as the material under
//!    it is dropped: its surface separates nothing.
//! 2. Per half `τ`: the surfaces `S_k` over `τ`, cut off below the bottom
//!    plane, with `l_k` above and the next deeper label below; the bottom
//!    under `τ` and the walls on the square's border edges in `τ`, split
//!    by the planes of the `S_k` over `τ` (exact: plane-based polygons,
//!    no new vertex is rounded), each part with the label of its side.
//!    The top lies above every `S_k`, so it carries the shallowest label.
//! 3. The faces are imported as a closed mesh is ([`super::import`]):
//!    a triangle octree, a BSP per cell, flood fill of the free cells.

use super::cell::CellKey;
use super::import::build_cell;
use super::tree::{Octree, OctreeConfig};
use crate::Error;
use crate::exact::{IntPoint, Plane, Sign, plane_from_points};
use crate::tree::polygon::{Polygon, side_of};
use crate::tree::{EMPTY, Label};

/// A heightfield on the grid with bands of material under its surface:
/// samples `heights[i + j·nx]` at `(corner.x + i·spacing, heights[..],
/// corner.z + j·spacing)`, a flat bottom at `y = bottom`, the solid
/// between labelled `label`, and every band `(depth, label)` holding what
/// lies less than `depth` below the surface (measured vertically at the
/// samples, and from the lower hull of each square's corners in between).
/// Shallower bands lie over deeper ones.
#[derive(Clone, Copy, Debug)]
pub struct LayeredHeightfield<'a> {
    /// Grid x and z of sample `(0, 0)`.
    pub corner: [i64; 2],
    /// Samples along x and along z (at least 2 each).
    pub samples: [u32; 2],
    /// Grid distance between neighbouring samples (positive).
    pub spacing: i64,
    /// Grid y of every sample, row by row (x fastest), above `bottom`.
    pub heights: &'a [i64],
    /// Grid y of the flat bottom.
    pub bottom: i64,
    /// The material below every band.
    pub label: Label,
    /// Bands `(depth, label)`, depths positive; of two with the same
    /// depth the later one counts.
    pub bands: &'a [(i64, Label)],
}

impl Octree {
    /// The solid of a layered heightfield in the cube at `origin` with
    /// edge `2^size_log2`, every band labelled (see the module notes).
    ///
    /// # Errors
    /// [`Error::OctreeSize`] for a bad cube, [`Error::InvalidHeightfield`] for a
    /// malformed field (too few samples, a height at or below the bottom, a
    /// depth not positive), [`Error::OutsideOctree`] for a sample outside
    /// the cube, [`Error::CoordinateOutOfRange`] for a band surface beyond
    /// the grid.
    pub fn from_layered_heightfield(
        origin: [i64; 3],
        size_log2: u8,
        field: &LayeredHeightfield<'_>,
        config: OctreeConfig,
    ) -> Result<Octree, Error> {
        let mut octree = Octree::new(origin, size_log2, EMPTY, config)?;
        let root = octree.root_box();
        field.check(&root)?;
        // A band deeper than the field is high reaches below the bottom
        // everywhere: it is cut to that depth, which keeps its region and
        // every coordinate on the grid.
        let highest = field.heights.iter().copied().max().unwrap_or(field.bottom);
        let bands = effective_bands(field.bands, field.label, highest - field.bottom + 1);
        let mut pieces = Vec::new();
        let [nx, nz] = field.samples;
        for j in 0..nz - 1 {
            for i in 0..nx - 1 {
                field.square_faces(i, j, &bands, &mut pieces)?;
            }
        }
        let (node, free) = build_cell(pieces, CellKey::ROOT, root, &config);
        octree.root = node;
        octree.fill_free_cells(free);
        octree.root = super::import::merge_uniform(octree.root.clone());
        Ok(octree)
    }
}

/// The bands that separate something, shallowest first: sorted by depth,
/// the later of equal depths kept, those under the first band at least
/// `reach` deep dropped (it holds all the solid under the shallower ones)
/// and that band cut to `reach`, and a band dropped where the material
/// under it has its label.
fn effective_bands(bands: &[(i64, Label)], base: Label, reach: i64) -> Vec<(i64, Label)> {
    let mut sorted: Vec<(usize, i64, Label)> = bands
        .iter()
        .enumerate()
        .map(|(n, &(depth, label))| (n, depth, label))
        .collect();
    // By depth, and of equal depths the latest first.
    sorted.sort_by_key(|&(n, depth, _)| (depth, std::cmp::Reverse(n)));
    sorted.dedup_by_key(|&mut (_, depth, _)| depth);
    if let Some(first_deep) = sorted.iter().position(|&(_, depth, _)| depth >= reach) {
        sorted.truncate(first_deep + 1);
        sorted[first_deep].1 = reach;
    }
    let mut kept = Vec::with_capacity(sorted.len());
    let mut under = base;
    for &(_, depth, label) in sorted.iter().rev() {
        if label != under {
            kept.push((depth, label));
            under = label;
        }
    }
    kept.reverse();
    kept
}

/// Corner offsets `(di, dj)` of a square: `00, 10, 01, 11`.
const CORNERS: [(u32, u32); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];

impl LayeredHeightfield<'_> {
    fn check(&self, root: &super::cell::CellBox) -> Result<(), Error> {
        let bad = |reason: String| Err(Error::InvalidHeightfield { reason });
        let [nx, nz] = self.samples;
        if nx < 2 || nz < 2 {
            return bad(format!("a heightfield needs 2×2 samples, got {nx}×{nz}"));
        }
        if self.heights.len() != nx as usize * nz as usize {
            return bad(format!(
                "{} heights for {nx}×{nz} samples",
                self.heights.len()
            ));
        }
        if self.spacing <= 0 {
            return bad(format!("sample spacing {} is not positive", self.spacing));
        }
        if let Some(h) = self.heights.iter().find(|&&h| h <= self.bottom) {
            return bad(format!(
                "height {h} is not above the bottom {}",
                self.bottom
            ));
        }
        if let Some(&(depth, _)) = self.bands.iter().find(|&&(d, _)| d <= 0) {
            return bad(format!("band depth {depth} is not positive"));
        }
        let far = |n: u32| i64::from(n - 1).checked_mul(self.spacing);
        let top = self.heights.iter().copied().max().unwrap_or(self.bottom);
        let (Some(fx), Some(fz)) = (far(nx), far(nz)) else {
            return bad("the field's extent overflows".into());
        };
        for point in [
            [self.corner[0], self.bottom, self.corner[1]],
            [
                self.corner[0].saturating_add(fx),
                top,
                self.corner[1].saturating_add(fz),
            ],
        ] {
            if (0..3).any(|a| point[a] < root.min[a] || point[a] > root.max[a]) {
                return Err(Error::OutsideOctree { point });
            }
        }
        Ok(())
    }

    /// Grid point of sample `(i, j)` at height `y`.
    fn at(&self, i: u32, j: u32, y: i64) -> Result<IntPoint, Error> {
        IntPoint::new(
            self.corner[0] + i64::from(i) * self.spacing,
            y,
            self.corner[1] + i64::from(j) * self.spacing,
        )
    }

    fn height(&self, i: u32, j: u32) -> i64 {
        self.heights[(i + j * self.samples[0]) as usize]
    }

    /// The labelled faces of square `(i, j)`, appended to `out`.
    fn square_faces(
        &self,
        i: u32,
        j: u32,
        bands: &[(i64, Label)],
        out: &mut Vec<(Polygon, Label, Label)>,
    ) -> Result<(), Error> {
        let h = CORNERS.map(|(a, b)| self.height(i + a, j + b));
        let top = |c: usize, depth: i64| {
            let (a, b) = CORNERS[c];
            self.at(i + a, j + b, h[c] - depth)
        };
        let floor = |c: usize| {
            let (a, b) = CORNERS[c];
            self.at(i + a, j + b, self.bottom)
        };
        let shallowest = bands.first().map_or(self.label, |&(_, l)| l);
        // The top, split as the field's surface is.
        for t in [[0, 2, 1], [1, 2, 3]] {
            if let Some(p) = Polygon::triangle([top(t[0], 0)?, top(t[1], 0)?, top(t[2], 0)?])? {
                out.push((p, shallowest, EMPTY));
            }
        }
        // The halves of the lower hull, counter-clockwise from above.
        let halves: [[usize; 3]; 2] = if h[1] + h[2] <= h[0] + h[3] {
            [[0, 2, 1], [1, 2, 3]]
        } else {
            [[0, 2, 3], [0, 3, 1]]
        };
        let bottom_plane = Plane::new(0, 1, 0, -i128::from(self.bottom))?;
        let [nx, nz] = self.samples;
        // Border edges of the square (from, to) as the top runs them, so
        // that a wall under (u, v) is v, u, u_bottom, v_bottom.
        let mut borders: Vec<(usize, usize)> = Vec::with_capacity(4);
        if i == 0 {
            borders.push((0, 2));
        }
        if j == 0 {
            borders.push((1, 0));
        }
        if j + 2 == nz {
            borders.push((2, 3));
        }
        if i + 2 == nx {
            borders.push((3, 1));
        }
        for half in halves {
            let mut planes = Vec::with_capacity(bands.len());
            for (k, &(depth, above)) in bands.iter().enumerate() {
                let corners = [
                    top(half[0], depth)?,
                    top(half[1], depth)?,
                    top(half[2], depth)?,
                ];
                let plane = plane_from_points(corners[0], corners[1], corners[2])?.normalized();
                planes.push(plane);
                let below = bands.get(k + 1).map_or(self.label, |&(_, l)| l);
                if let Some(p) = Polygon::triangle(corners)?
                    && let Some(p) = keep_above(p, &bottom_plane)
                {
                    out.push((p, below, above));
                }
            }
            let labels: Vec<Label> = bands.iter().map(|&(_, l)| l).collect();
            let mut faces = Vec::with_capacity(3);
            faces.push([floor(half[0])?, floor(half[2])?, floor(half[1])?]);
            for &(u, v) in &borders {
                if half.contains(&u) && half.contains(&v) {
                    faces.push([top(v, 0)?, top(u, 0)?, floor(u)?]);
                    faces.push([top(v, 0)?, floor(u)?, floor(v)?]);
                }
            }
            for face in faces {
                if let Some(p) = Polygon::triangle(face)? {
                    split_by_bands(p, &planes, &labels, self.label, out);
                }
            }
        }
        Ok(())
    }
}

/// The part of `p` on or above `plane` (its positive side), if it has
/// area there.
fn keep_above(p: Polygon, plane: &Plane) -> Option<Polygon> {
    let sides: Vec<Sign> = p.vertices().iter().map(|v| side_of(v, plane)).collect();
    let below = sides.contains(&Sign::Negative);
    let above = sides.contains(&Sign::Positive);
    match (below, above) {
        (_, false) => None,
        (false, true) => Some(p),
        (true, true) => Some(p.part(&sides, plane, Sign::Positive)),
    }
}

/// `face` (solid behind it) split by the band planes, shallowest first:
/// a part on or above plane `k` has label `labels[k]`; a part below every
/// plane has `base`.
fn split_by_bands(
    face: Polygon,
    planes: &[Plane],
    labels: &[Label],
    base: Label,
    out: &mut Vec<(Polygon, Label, Label)>,
) {
    let mut rest = Some(face);
    for (plane, &label) in planes.iter().zip(labels) {
        let Some(p) = rest.take() else {
            return;
        };
        let sides: Vec<Sign> = p.vertices().iter().map(|v| side_of(v, plane)).collect();
        let below = sides.contains(&Sign::Negative);
        let above = sides.contains(&Sign::Positive);
        if !below {
            out.push((p, label, EMPTY));
            return;
        }
        if above {
            out.push((p.part(&sides, plane, Sign::Positive), label, EMPTY));
            rest = Some(p.part(&sides, plane, Sign::Negative));
        } else {
            rest = Some(p);
        }
    }
    if let Some(p) = rest {
        out.push((p, base, EMPTY));
    }
}
