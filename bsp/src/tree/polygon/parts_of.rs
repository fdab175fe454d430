//! Splitting a polygon read where it lies (paper 1 §3.6), such as a face
//! in a convex arena: both parts are built straight from its planes and
//! corners, without a copy of it to cut down.
//!
//! Notation as in the parent module: edge planes `e_k`, corner `k` the
//! meet of `s`, `e_{k−1}` and `e_k`; `p` the splitting plane.

use std::slice;

use super::Polygon;
use super::layout::{FEW_CORNERS, LayoutMemory, NONE, Other, layout, new_corner, reused_corner};
use super::spare::spare_buffers;
use crate::exact::{Plane, Point4, Sign};

impl Polygon {
    /// The parts `wanted` (below, above) of the polygon with support
    /// `support`, edge planes `edge(k)` and corners `corner(k)` for `k` in
    /// `0..sides.len()`, which has corners on both sides of `p` (`sides` as
    /// [`Self::whole_side`] writes them): the parts [`Self::split_known`]
    /// gives, built straight from where the polygon lies (such as a face
    /// read in place in a convex arena) instead of from a copy of it that
    /// would be cut down. A corner on `p` that both parts have is computed
    /// once.
    pub(crate) fn parts_of<'a>(
        support: &Plane,
        edge: impl Fn(usize) -> &'a Plane,
        corner: impl Fn(usize) -> &'a Point4,
        sides: &[Sign],
        p: &Plane,
        wanted: [bool; 2],
    ) -> (Option<Self>, Option<Self>) {
        let n = sides.len();
        let mut memory = LayoutMemory::<{ 4 * FEW_CORNERS }>::new();
        let buffer = memory.entries(4 * n);
        let (low, high) = buffer.split_at_mut(2 * n);
        let build = |origin: &[u32], closing: &Plane, other: Option<Other<'_>>| {
            let plane = |o: u32| match o {
                NONE => closing,
                o => edge(o as usize),
            };
            let m = origin.len();
            let (mut edges, mut corners) = spare_buffers(m);
            for &o in origin {
                edges.extend_from_slice(slice::from_ref(plane(o)));
            }
            for j in 0..m {
                let (prev, o) = (origin[(j + m - 1) % m], origin[j]);
                match reused_corner(prev, o, n) {
                    Some(k) => corners.extend_from_slice(slice::from_ref(corner(k))),
                    None => corners.push(new_corner(
                        support,
                        (prev, plane(prev)),
                        (o, plane(o)),
                        other,
                    )),
                }
            }
            Self {
                support: *support,
                edges,
                corners,
            }
        };
        let below = wanted[0].then(|| {
            let m = layout(sides, Sign::Negative, low);
            build(&low[..m], p, None)
        });
        let above = wanted[1].then(|| {
            let m = layout(sides, Sign::Positive, high);
            let other = below
                .as_ref()
                .map(|b| (&low[..b.corners.len()], &b.corners[..]));
            build(&high[..m], &p.flipped(), other)
        });
        (below, above)
    }
}
