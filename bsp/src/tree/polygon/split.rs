//! Splitting a polygon it owns by a plane (paper 1 §3.6): the sides of
//! the corners give the [layout](super::layout) of each part; runs of kept
//! edges and corners are copied whole, a corner on the plane that both
//! parts have is computed once, and a part that fits is written over the
//! polygon's own memory.
//!
//! Notation as in the parent module: edge planes `e_k`, corner `k` the
//! meet of `s`, `e_{k−1}` and `e_k`; `p` the splitting plane.

use super::Polygon;
use super::classify::Sides;
use super::layout::{
    FEW_CORNERS, LayoutMemory, NONE, Other, fits_in_place, layout, new_corner, reused_corner,
    run_end,
};
use super::spare::spare_buffers;
use crate::exact::{Plane, Sign};

impl Polygon {
    /// The parts below and above `p`. A polygon lying in `p` goes to the
    /// side its outward normal points to (the region in front of it).
    pub(crate) fn split(self, p: &Plane) -> (Option<Self>, Option<Self>) {
        self.split_wanted(p, [true; 2])
    }

    /// [`Self::split`], building only the parts `wanted` (below, above):
    /// a part not wanted is `None`, a part wanted is the one `split` gives.
    pub(crate) fn split_wanted(self, p: &Plane, wanted: [bool; 2]) -> (Option<Self>, Option<Self>) {
        let mut sides = Sides::default();
        let sides = sides.for_corners(self.corners.len());
        let [want_below, want_above] = wanted;
        match self.whole_side(p, sides) {
            Some(false) => (want_below.then_some(self), None),
            Some(true) => (None, want_above.then_some(self)),
            None => self.split_known(sides, p, wanted),
        }
    }

    /// The parts `wanted` (below, above) of a polygon with corners on both
    /// sides of `p` (`sides` as [`Self::whole_side`] wrote them): those
    /// [`Self::split_wanted`] gives.
    pub(crate) fn split_known(
        self,
        sides: &[Sign],
        p: &Plane,
        wanted: [bool; 2],
    ) -> (Option<Self>, Option<Self>) {
        match wanted {
            [true, true] => {
                let (b, a) = self.split_straddling(sides, p);
                (Some(b), Some(a))
            }
            [true, false] => (Some(self.one_part(sides, p, Sign::Negative)), None),
            [false, true] => (None, Some(self.one_part(sides, p, Sign::Positive))),
            [false, false] => (None, None),
        }
    }

    /// The part on side `keep` (Negative or Positive) of `p` of a polygon
    /// with corners on both sides: the part [`Self::split_straddling`]
    /// gives on that side (its corners on `p` are the same exact meets),
    /// rewritten in place when it fits.
    pub(crate) fn one_part(mut self, sides: &[Sign], p: &Plane, keep: Sign) -> Self {
        let n = self.edges.len();
        let mut memory = LayoutMemory::<{ 2 * FEW_CORNERS }>::new();
        let buffer = memory.entries(2 * n);
        let m = layout(sides, keep, buffer);
        let origin = &buffer[..m];
        let closing = if keep == Sign::Negative {
            *p
        } else {
            p.flipped()
        };
        if fits_in_place(origin, n) {
            self.rewrite(origin, &closing, None);
            self
        } else {
            self.assemble(origin, &closing, None)
        }
    }

    /// The parts below and above `p` of a polygon with corners on both
    /// sides (`sides` as [`classify_polygon_corners`] gives them): the same as
    /// [`Self::part`] on each side, but each corner on `p` that both parts
    /// share is computed once, runs of kept edges and corners are copied
    /// whole, and one part reuses this polygon's memory.
    pub(crate) fn split_straddling(mut self, sides: &[Sign], p: &Plane) -> (Self, Self) {
        let n = self.edges.len();
        // The layout of each part: the original index of each of its edges
        // (NONE for the closing one). At most 2n entries each (n + 1 for a
        // convex polygon).
        let mut memory = LayoutMemory::<{ 4 * FEW_CORNERS }>::new();
        let buffer = memory.entries(4 * n);
        let (low, high) = buffer.split_at_mut(2 * n);
        let (mb, ma) = (
            layout(sides, Sign::Negative, low),
            layout(sides, Sign::Positive, high),
        );
        let (below, above) = (&low[..mb], &high[..ma]);
        let flipped = p.flipped();
        // The part whose edges all stay at or before their position is
        // rewritten in place, after the other is built into new memory.
        if fits_in_place(below, n) {
            let a = self.assemble(above, &flipped, None);
            self.rewrite(below, p, Some((above, &a.corners)));
            (self, a)
        } else if fits_in_place(above, n) {
            let b = self.assemble(below, p, None);
            self.rewrite(above, &flipped, Some((below, &b.corners)));
            (b, self)
        } else {
            let b = self.assemble(below, p, None);
            let a = self.assemble(above, &flipped, Some((below, &b.corners)));
            (b, a)
        }
    }

    /// The part with edges `origin` (original indices, NONE for
    /// `closing`), in new memory; corners on `p` are taken from `other`
    /// (the other part's layout and corners) where it has them.
    fn assemble(&self, origin: &[u32], closing: &Plane, other: Option<Other<'_>>) -> Self {
        let (n, m) = (self.edges.len(), origin.len());
        let (mut edges, mut corners) = spare_buffers(m);
        let mut j = 0;
        while j < m {
            let o = origin[j];
            if o == NONE {
                edges.push(*closing);
                j += 1;
            } else {
                let end = run_end(origin, j);
                edges.extend_from_slice(&self.edges[o as usize..o as usize + (end - j)]);
                j = end;
            }
        }
        let mut j = 0;
        while j < m {
            let (prev, o) = (origin[(j + m - 1) % m], origin[j]);
            if let Some(k) = reused_corner(prev, o, n) {
                let end = run_end(origin, j);
                corners.extend_from_slice(&self.corners[k..k + (end - j)]);
                j = end;
            } else {
                let plane = |o: u32| match o {
                    NONE => closing,
                    o => &self.edges[o as usize],
                };
                corners.push(new_corner(
                    &self.support,
                    (prev, plane(prev)),
                    (o, plane(o)),
                    other,
                ));
                j += 1;
            }
        }
        Self {
            support: self.support,
            edges,
            corners,
        }
    }

    /// This polygon turned, in place, into the part with edges `origin`
    /// (which [`fits_in_place`]); corners on `p` are taken from `other`
    /// where it has them.
    fn rewrite(&mut self, origin: &[u32], closing: &Plane, other: Option<Other<'_>>) {
        let (n, m) = (self.edges.len(), origin.len());
        // Entry j reads original position origin[j] ≥ j, not yet written.
        let mut j = 0;
        while j < m {
            let o = origin[j];
            if o == NONE {
                self.edges[j] = *closing;
                j += 1;
            } else {
                let end = run_end(origin, j);
                if o as usize != j {
                    self.edges
                        .copy_within(o as usize..o as usize + (end - j), j);
                }
                j = end;
            }
        }
        // The edges are final; corner j lies between edges j − 1 and j.
        let mut j = 0;
        while j < m {
            let (prev, o) = (origin[(j + m - 1) % m], origin[j]);
            if let Some(k) = reused_corner(prev, o, n) {
                let end = run_end(origin, j);
                if k != j {
                    self.corners.copy_within(k..k + (end - j), j);
                }
                j = end;
            } else {
                self.corners[j] = new_corner(
                    &self.support,
                    (prev, &self.edges[(j + m - 1) % m]),
                    (o, &self.edges[j]),
                    other,
                );
                j += 1;
            }
        }
        self.edges.truncate(m);
        self.corners.truncate(m);
    }
}
