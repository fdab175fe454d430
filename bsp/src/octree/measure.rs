//! Volumes of an octree's materials, for reports.
//!
//! The regions are exact; only the summation is in `f64`: every convex
//! cell of every leaf contributes the tetrahedra fanned from one of its
//! corners, with positions taken relative to that corner (correctly
//! rounded), so the relative error stays near 1e-15 per cell.

use std::collections::BTreeMap;

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::tree::{Leaf, Octree};
use crate::convex::{ConvexArena, PolyId};
use crate::tree::{EMPTY, Label};

impl Octree {
    /// The volume of every non-empty material, in cubic grid units.
    #[must_use]
    pub fn volumes(&self) -> BTreeMap<Label, f64> {
        self.volumes_of(&self.leaves())
    }

    /// The volume of every non-empty material of `leaves`, each measured
    /// inside its cell (the octree's leaves, or the parts of them in
    /// smaller cells).
    pub(super) fn volumes_of(&self, leaves: &[(CellKey, &Leaf)]) -> BTreeMap<Label, f64> {
        let per_leaf: Vec<Vec<(Label, f64)>> = leaves
            .par_iter()
            .map(|&(key, leaf)| leaf_volumes(leaf, &self.cell_box(key)))
            .collect();
        let mut out = BTreeMap::new();
        for (label, v) in per_leaf.into_iter().flatten() {
            *out.entry(label).or_insert(0.0) += v;
        }
        out
    }

    /// The volume of all material together, in cubic grid units.
    #[must_use]
    pub fn solid_volume(&self) -> f64 {
        self.volumes().values().sum()
    }
}

/// The volume per label of one leaf's convex cells inside `cell` (the
/// part of the leaf's regions in `cell`, when `cell` lies inside the
/// leaf's own), one entry per convex cell.
fn leaf_volumes(leaf: &Leaf, cell: &CellBox) -> Vec<(Label, f64)> {
    let bsp = leaf.to_bsp();
    let mut arena = ConvexArena::new();
    let Ok(bounds) = cell.add_to(&mut arena) else {
        return Vec::new();
    };
    bsp.cells(&mut arena, bounds)
        .into_iter()
        .filter(|c| c.label != EMPTY)
        .map(|c| (c.label, polyhedron_volume(&arena, c.poly)))
        .collect()
}

fn polyhedron_volume(arena: &ConvexArena, poly: PolyId) -> f64 {
    let position = |v: u32| arena.position(v);
    let faces = arena.faces_of(poly);
    let Some(&first) = faces.first() else {
        return 0.0;
    };
    let Some(h0) = arena.face_loop(first).next() else {
        return 0.0;
    };
    let apex = position(arena.half_edges()[h0 as usize].origin);
    let rel = |p: [f64; 3]| [p[0] - apex[0], p[1] - apex[1], p[2] - apex[2]];
    let mut six = 0.0;
    for f in faces {
        let corners: Vec<[f64; 3]> = arena
            .face_loop(f)
            .map(|h| rel(position(arena.half_edges()[h as usize].origin)))
            .collect();
        for k in 1..corners.len().saturating_sub(1) {
            let (a, b, c) = (corners[0], corners[k], corners[k + 1]);
            six += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
    }
    six / 6.0
}
