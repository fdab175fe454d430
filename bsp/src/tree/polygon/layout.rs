//! The layout of a part of a split polygon (paper 1 §3.6): for each of
//! its edges, the index of the original edge it keeps, or [`NONE`] where
//! the splitting plane closes it; and the corners a part does not share
//! with the original polygon.
//!
//! Notation as in the parent module: edge planes `e_k`, corner `k` the
//! meet of `s`, `e_{k−1}` and `e_k`; `p` the splitting plane, closing the
//! part below as `p` and the part above as `−p`.

use super::meet;
use crate::exact::{Plane, Point4, Sign};

/// Polygons with at most this many corners are laid out for a split in
/// working memory on the stack: few polygons have more, and a larger
/// buffer costs its filling at every split.
pub(super) const FEW_CORNERS: usize = 12;

/// Working memory for the layouts of a split ([`layout`]): `M` entries on
/// the stack, enough for polygons of up to [`FEW_CORNERS`] corners, and the
/// heap beyond.
pub(super) struct LayoutMemory<const M: usize> {
    stack: [u32; M],
    heap: Vec<u32>,
}

impl<const M: usize> LayoutMemory<M> {
    pub(super) fn new() -> Self {
        Self {
            stack: [NONE; M],
            heap: Vec::new(),
        }
    }

    /// `len` entries, on the stack when they fit.
    pub(super) fn entries(&mut self, len: usize) -> &mut [u32] {
        if len <= M {
            &mut self.stack[..len]
        } else {
            self.heap.resize(len, NONE);
            &mut self.heap
        }
    }
}

/// Marks the closing plane in a part's layout.
pub(super) const NONE: u32 = u32::MAX;

/// The other part of a split, already built: its layout and corners.
pub(super) type Other<'a> = (&'a [u32], &'a [Point4]);

/// The end of the run of consecutive original edges starting at position
/// `j` of a layout (`origin[j]` is not NONE); inside the run the corners
/// are the original ones too.
#[inline]
pub(super) fn run_end(origin: &[u32], j: usize) -> usize {
    let mut end = j + 1;
    while end < origin.len() && origin[end] == origin[end - 1].wrapping_add(1) {
        end += 1;
    }
    end
}

/// The corner of a part between its edges `(prev, plane)` and `(o,
/// plane)` (original indices, NONE for the closing plane) that is not an
/// original corner: the one `other` has between the same original edge and
/// its closing plane (the same exact vertex: the homogeneous coordinates of
/// a three-plane meet change only by a common sign when the planes are
/// reordered or one is flipped, and the sign is normalised), else the meet.
#[inline]
pub(super) fn new_corner(
    support: &Plane,
    (prev, a): (u32, &Plane),
    (o, b): (u32, &Plane),
    other: Option<Other<'_>>,
) -> Point4 {
    let key = match (prev, o) {
        (NONE, NONE) => None,
        (NONE, k) | (k, NONE) => Some(k),
        _ => None,
    };
    if let (Some(key), Some((origin, corners))) = (key, other) {
        let m = origin.len();
        for (j, &o) in origin.iter().enumerate() {
            if o != NONE {
                continue;
            }
            let next = (j + 1) % m;
            let found = if origin[(j + m - 1) % m] == key {
                &corners[j]
            } else if origin[next] == key {
                &corners[next]
            } else {
                continue;
            };
            // Tested against a fresh `meet` in `split_parts_keep_exact_corners`.
            return *found;
        }
    }
    meet(support, a, b)
}

/// Writes the layout of the part on side `keep` into `origin` (as
/// [`Polygon::part`] builds it: the original index of each kept edge, NONE
/// where the closing plane goes) and returns its length.
#[inline]
pub(super) fn layout(sides: &[Sign], keep: Sign, origin: &mut [u32]) -> usize {
    let n = sides.len();
    let reaches = |k: usize| sides[k] == keep || sides[(k + 1) % n] == keep;
    let across = -keep;
    let mut m = 0;
    for k in 0..n {
        if reaches(k) {
            origin[m] = k as u32;
            m += 1;
            let next = (k + 1) % n;
            if sides[next] == across || !reaches(next) {
                origin[m] = NONE;
                m += 1;
            }
        }
    }
    m
}

/// The original corner a part reuses between its edges `prev` and `o`
/// (consecutive original edges), if any.
#[inline]
pub(super) fn reused_corner(prev: u32, o: u32, n: usize) -> Option<usize> {
    (prev != NONE && o != NONE && o as usize == (prev as usize + 1) % n).then_some(o as usize)
}

/// Whether the part with this layout can be written over the original
/// polygon front to back: no more edges, none moving to a later position.
#[inline]
pub(super) fn fits_in_place(origin: &[u32], n: usize) -> bool {
    origin.len() <= n
        && origin
            .iter()
            .enumerate()
            .all(|(j, &o)| o == NONE || o as usize >= j)
}
