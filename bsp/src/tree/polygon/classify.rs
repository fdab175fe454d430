//! Which side of a plane a polygon and its corners are on (paper 1
//! §3.6): the `f64` filter first, and the exact predicate only where it
//! cannot decide; a corner on one of its own edge planes, or a polygon in
//! its own support, is found on the plane without arithmetic.
//!
//! Notation as in the parent module: support `s`, edge planes `e_k`,
//! corner `k` the meet of `s`, `e_{k−1}` and `e_k`; `p` the plane asked
//! about.

use super::{Polygon, SMALL};
use crate::exact::{Plane, Point4, Sign, classify_vertex_exact, classify_vertex_filtered};

impl Polygon {
    /// The side of `p` the polygon lies on whole (`false` below, `true`
    /// above; a polygon lying in `p` goes to the side it faces, as in
    /// [`Self::split`]), or `None` when it has corners on both sides; the
    /// sides of the corners are written to `sides` (one per corner).
    #[inline]
    pub(crate) fn whole_side(&self, p: &Plane, sides: &mut [Sign]) -> Option<bool> {
        let (mut below, mut above) = (false, false);
        for (k, side) in sides.iter_mut().enumerate() {
            *side = self.corner_side(k, p);
            below |= *side == Sign::Negative;
            above |= *side == Sign::Positive;
        }
        self.side_from_corners(below, above, p)
    }

    /// The side of `p` a polygon with corners `below` and `above` it lies
    /// on whole: see [`Self::whole_side`].
    #[inline]
    pub(super) fn side_from_corners(&self, below: bool, above: bool, p: &Plane) -> Option<bool> {
        match (below, above) {
            (true, true) => None,
            (true, false) => Some(false),
            (false, true) => Some(true),
            (false, false) => Some(faces_along(&self.support, p)),
        }
    }

    /// The side of `p` that corner `k` is on: the filter's answer, else
    /// the exact side ([`corner_side_exact`]).
    #[inline]
    fn corner_side(&self, k: usize, p: &Plane) -> Sign {
        classify_vertex_filtered(&self.corners[k], p)
            .unwrap_or_else(|| corner_side_exact(&self.edges, &self.corners, k, p))
    }

    /// [`Self::whole_side`], without recording the sides of the corners:
    /// it stops at the first corner that shows the polygon straddles `p`.
    #[inline]
    pub(crate) fn side_of_plane(&self, p: &Plane) -> Option<bool> {
        let (mut below, mut above) = (false, false);
        for k in 0..self.corners.len() {
            match self.corner_side(k, p) {
                Sign::Negative => below = true,
                Sign::Positive => above = true,
                Sign::Zero => {}
            }
            if below && above {
                return None;
            }
        }
        self.side_from_corners(below, above, p)
    }

    /// Whether some of the polygon goes to side `above` of `p` (`false`
    /// below): whether [`Self::side_of_plane`] is `None` or that side. It
    /// stops at the first corner strictly on that side.
    #[inline]
    pub(crate) fn reaches_side(&self, p: &Plane, above: bool) -> bool {
        let wanted = if above {
            Sign::Positive
        } else {
            Sign::Negative
        };
        let mut off = false;
        for k in 0..self.corners.len() {
            let side = self.corner_side(k, p);
            if side == wanted {
                return true;
            }
            off |= side != Sign::Zero;
        }
        // No corner strictly on that side: the polygon goes there only
        // lying in `p` and facing that way.
        !off && faces_along(&self.support, p) == above
    }
}

/// Room for the sides of a polygon's corners: on the stack for the usual
/// small polygon.
pub(crate) struct Sides {
    small: [Sign; SMALL],
    large: Vec<Sign>,
}

impl Default for Sides {
    fn default() -> Self {
        Self {
            small: [Sign::Zero; SMALL],
            large: Vec::new(),
        }
    }
}

impl Sides {
    /// Room for the sides of `n` corners.
    #[inline]
    pub(crate) fn for_corners(&mut self, n: usize) -> &mut [Sign] {
        if n <= SMALL {
            &mut self.small[..n]
        } else {
            self.large.resize(n, Sign::Zero);
            &mut self.large
        }
    }
}

/// Whether a polygon with support `support` lying in `p` faces along `p`
/// (the supports are positive multiples of each other, not opposite).
#[inline]
pub(crate) fn faces_along(support: &Plane, p: &Plane) -> bool {
    p.normal()
        .iter()
        .zip(support.normal())
        .all(|(a, b)| a.signum() == b.signum())
}

/// The side of `p` that `v` is on ([`crate::exact::classify_vertex`], with
/// the filter inlined).
#[inline]
pub(crate) fn side_of(v: &Point4, p: &Plane) -> Sign {
    classify_vertex_filtered(v, p).unwrap_or_else(|| classify_vertex_exact(v, p))
}

/// The sides of `corners` with respect to `p`, written to `sides`, and
/// whether any is below and any above.
#[cfg(test)]
pub(crate) fn classify_corners(corners: &[Point4], p: &Plane, sides: &mut [Sign]) -> (bool, bool) {
    let (mut below, mut above) = (false, false);
    for (side, v) in sides.iter_mut().zip(corners) {
        *side = side_of(v, p);
        below |= *side == Sign::Negative;
        above |= *side == Sign::Positive;
    }
    (below, above)
}

/// The sides of the corners of a polygon in plane-based form (support
/// `support`, edge planes `edges`, corners `corners`) with respect to `p`,
/// written to `sides`, and whether any is below and any above: the sides
/// [`side_of`] gives, but a polygon lying in `p` (its support is
/// `p`, as given or flipped) and a corner where one of its edge planes is
/// `p` are found on `p` without arithmetic — as where the polygon is a
/// piece of a face already in a tree, or was cut by `p`.
#[inline]
pub(crate) fn classify_polygon_corners(
    support: &Plane,
    edges: &[Plane],
    corners: &[Point4],
    p: &Plane,
    sides: &mut [Sign],
) -> (bool, bool) {
    if same_plane_either_way(support, p) {
        sides.fill(Sign::Zero);
        return (false, false);
    }
    let (mut below, mut above) = (false, false);
    for (k, side) in sides.iter_mut().enumerate() {
        *side = classify_vertex_filtered(&corners[k], p)
            .unwrap_or_else(|| corner_side_exact(edges, corners, k, p));
        below |= *side == Sign::Negative;
        above |= *side == Sign::Positive;
    }
    (below, above)
}

/// The exact side of `p` that corner `k` of a polygon with edge planes
/// `edges` and corners `corners` is on: zero without arithmetic when `p`
/// is one of the two edge planes meeting there (as given, or flipped).
#[cold]
#[inline(never)]
fn corner_side_exact(edges: &[Plane], corners: &[Point4], k: usize, p: &Plane) -> Sign {
    let n = edges.len();
    if same_plane_either_way(&edges[k], p) || same_plane_either_way(&edges[(k + n - 1) % n], p) {
        Sign::Zero
    } else {
        classify_vertex_exact(&corners[k], p)
    }
}

/// Whether `e` has the coefficients of `p` or of `p` flipped.
#[inline]
fn same_plane_either_way(e: &Plane, p: &Plane) -> bool {
    (e.a, e.b, e.c, e.d) == (p.a, p.b, p.c, p.d) || (e.a, e.b, e.c, e.d) == (-p.a, -p.b, -p.c, -p.d)
}
