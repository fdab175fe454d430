//! Basic regions of a sampling plane (paper 2, §4.1, Figs. 7–8).
//!
//! Notation: `(x, y)` plane coordinates of a [`Heightfield`], `w = (u, v)`
//! the warped coordinates of one cell ([`Warp`]: `u = x²` on a quadratic
//! axis, `u = x` on a linear one). The domain is the box `[c − R, c + R]²`
//! around the bounding sphere's projected centre `c` (radius `R`), cut at
//! `x = 0` and `y = 0` into cells.
//!
//! In `w` the ownership conics of eqs. 15–16 are lines, so the part of the
//! plane's low-distortion region inside a cell is the convex polygon
//! `Π = box ∩ {owns_x ≥ 0} ∩ {owns_y ≥ 0}`. Its sides are axis-aligned
//! (straight in the plane too) or on an ownership line (an arc of an
//! ellipse, hyperbola or parabola in the plane, unless the line is
//! axis-aligned or, both axes quadratic, through the origin). `Π` is cut
//! into basic regions (Fig. 8a):
//!
//! 1. a cell wholly inside the region: one **rectangle**;
//! 2. while `Π` has a curved side `E→X` whose inner corner `K` of the box
//!    spanned by `E` and `X` lies in `Π`: the right triangle `EXK` of `w`
//!    is an **elliptic** (**hyperbolic**, parabolic) **triangle**, an
//!    axis-aligned right triangle whose diagonal is the conic, and the rest
//!    of `Π`, cut by the two axis-aligned lines through `K`, is two convex
//!    polygons treated the same way;
//! 3. a polygon with straight sides only is convex in the plane too: one
//!    rectangle or a fan of straight **triangles**;
//! 4. otherwise (both ownership lines meet at an angle that holds no axis
//!    direction) a fan of triangles of `w`: curved triangles with the kind
//!    of their conic side, like the paper's hyperbolic triangles bounded by
//!    a line through the origin.
//!
//! The pieces cover `Π` (up to a relative `1e-12` widening of the ownership
//! half-planes, so that the regions of neighbouring planes meet without
//! rounding gaps), hence the basic regions of the three planes cover the
//! surface inside the sphere's box, and each lies in its plane's
//! low-distortion region (distortion at most `√3`). A cell whose ownership
//! functions are not affine in `w` (never produced by
//! [`LocalForm`](crate::sampling::heightfield::LocalForm)) falls back to
//! one rectangle that straddles the seam; the subdivision copes with it.

use glam::DVec2;

use crate::sampling::curved::{CurvedTriangle, clip_half_plane};
use crate::sampling::heightfield::Heightfield;
use crate::sampling::regions::{Region, RegionKind};
use crate::sampling::warp::{ArcKind, Warp};

/// Relative widening of the ownership half-planes (see the module notes).
const OWNERSHIP_SLACK: f64 = 1e-12;

/// Relative size below which an ownership line counts as through the origin.
const APEX_TOLERANCE: f64 = 1e-13;

/// Pieces a cell may be cut into before the rest is fanned (the cuts of
/// step 2 end after two, this only guards against rounding loops).
const MAX_PIECES: usize = 16;

/// The basic regions of `hf` over the domain box `[lo, hi]`, with their kinds.
///
/// Cells wholly outside the plane's low-distortion region or the
/// heightfield's domain give none.
#[must_use]
pub fn basic_regions(hf: &Heightfield, lo: DVec2, hi: DVec2) -> Vec<(Region, RegionKind)> {
    let mut out = Vec::new();
    for (clo, chi) in cells(lo, hi) {
        if chi.x <= clo.x || chi.y <= clo.y || hf.box_is_foreign(clo, chi) {
            continue;
        }
        let rect = (Region::rectangle(clo, chi), RegionKind::Rectangle);
        if hf.box_is_owned(clo, chi) {
            out.push(rect);
            continue;
        }
        match hf.warp(clo, chi) {
            Some(warp) => decompose_cell(hf, &warp, clo, chi, &mut out),
            None => out.push(rect),
        }
    }
    out
}

/// Splits `[lo, hi]` at `x = 0` and `y = 0` into cells.
fn cells(lo: DVec2, hi: DVec2) -> Vec<(DVec2, DVec2)> {
    let cuts = |a: f64, b: f64| {
        if a < 0.0 && 0.0 < b {
            vec![(a, 0.0), (0.0, b)]
        } else {
            vec![(a, b)]
        }
    };
    let mut out = Vec::new();
    for (y0, y1) in cuts(lo.y, hi.y) {
        for (x0, x1) in cuts(lo.x, hi.x) {
            out.push((DVec2::new(x0, y0), DVec2::new(x1, y1)));
        }
    }
    out
}

/// Twice the signed area of a polygon.
fn area2(poly: &[DVec2]) -> f64 {
    (1..poly.len().saturating_sub(1))
        .map(|i| (poly[i] - poly[0]).perp_dot(poly[i + 1] - poly[0]))
        .sum()
}

/// Drops repeated consecutive vertices (clipping repeats a vertex that
/// lies on the clipping line).
fn dedup(mut poly: Vec<DVec2>) -> Vec<DVec2> {
    poly.dedup();
    while poly.len() > 1 && poly.first() == poly.last() {
        poly.pop();
    }
    poly
}

/// Step 2–4 of the module notes for one cell `[lo, hi]` that the region
/// neither fills nor misses.
fn decompose_cell(
    hf: &Heightfield,
    warp: &Warp,
    lo: DVec2,
    hi: DVec2,
    out: &mut Vec<(Region, RegionKind)>,
) {
    let (wlo, whi) = warp.w_box(lo, hi);
    let mut poly = vec![wlo, DVec2::new(whi.x, wlo.y), whi, DVec2::new(wlo.x, whi.y)];
    // The sign of each coordinate of `w` in the cell (cells do not
    // straddle 0), for widening `g·w + c ≥ 0` to
    // `g·w + c + slack·(|g|·|w| + |c|) ≥ 0`: linear in `w`, and still
    // through the origin or axis-aligned when the line was.
    let side = (wlo + whi).signum();
    let reach = wlo.abs().max(whi.abs());
    for f in [&hf.owns_x, &hf.owns_y] {
        let Some((g, c)) = warp.affine(f) else {
            out.push((Region::rectangle(lo, hi), RegionKind::Rectangle));
            return;
        };
        // A cone's lines pass through the origin up to the rounding of its
        // apex value; through it exactly, the apex stays a vertex (where
        // the distortion is unbounded) instead of a rounding-sized edge.
        let c = if c.abs() <= APEX_TOLERANCE * g.abs().dot(reach) {
            0.0
        } else {
            c
        };
        let g = g + OWNERSHIP_SLACK * g.abs() * side;
        let c = c + OWNERSHIP_SLACK * c.abs();
        poly = clip_half_plane(&poly, g, c);
        if poly.len() < 3 {
            return;
        }
    }
    let mut stack = vec![poly];
    let mut pieces = 0;
    while let Some(poly) = stack.pop() {
        let poly = dedup(poly);
        let area = area2(&poly);
        if poly.len() < 3 || area == 0.0 {
            continue;
        }
        pieces += 1;
        let curved = (0..poly.len())
            .any(|i| warp.arc_kind(poly[i], poly[(i + 1) % poly.len()]) != ArcKind::Straight);
        if !curved {
            emit_straight(warp, &poly, out);
            continue;
        }
        match corner_cut(warp, &poly, area.signum()) {
            Some((i, k)) if pieces < MAX_PIECES => {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                let triangle = CurvedTriangle::new(*warp, [a, b, k]);
                out.push((Region::Curved(triangle), RegionKind::of_curved(&triangle)));
                let mid = 0.5 * (a + b);
                let (with_edge, other) = split_at(&poly, 0, k.x, mid.x);
                stack.push(other);
                let (_, rest) = split_at(&with_edge, 1, k.y, mid.y);
                stack.push(rest);
            }
            _ => emit_fan(warp, &poly, out),
        }
    }
}

/// Cuts a convex polygon at `w[axis] = at` into the piece on the side of
/// `probe` and the other one (the cut sides stay exactly axis-aligned).
fn split_at(poly: &[DVec2], axis: usize, at: f64, probe: f64) -> (Vec<DVec2>, Vec<DVec2>) {
    let n = if axis == 0 { DVec2::X } else { DVec2::Y };
    let above = clip_half_plane(poly, n, -at);
    let below = clip_half_plane(poly, -n, at);
    if probe >= at {
        (above, below)
    } else {
        (below, above)
    }
}

/// A curved side `i` (from vertex `i` to `i + 1`) whose inner corner `K`
/// lies in the polygon, with `K` (step 2 of the module notes).
fn corner_cut(warp: &Warp, poly: &[DVec2], orientation: f64) -> Option<(usize, DVec2)> {
    let n = poly.len();
    let scale = poly.iter().map(|p| p.length_squared()).fold(0.0, f64::max);
    let tol = 1e-12 * scale;
    let inside = |k: DVec2| {
        (0..n).all(|j| {
            let (a, b) = (poly[j], poly[(j + 1) % n]);
            (b - a).perp_dot(k - a) * orientation >= -tol
        })
    };
    (0..n).find_map(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if warp.arc_kind(a, b) == ArcKind::Straight {
            return None;
        }
        let k = [DVec2::new(a.x, b.y), DVec2::new(b.x, a.y)]
            .into_iter()
            .find(|k| (b - a).perp_dot(*k - a) * orientation > 0.0)?;
        inside(k).then_some((i, k))
    })
}

/// A polygon of `w` with straight sides: its preimage, convex in the plane,
/// as a rectangle or a fan of triangles.
fn emit_straight(warp: &Warp, poly: &[DVec2], out: &mut Vec<(Region, RegionKind)>) {
    let xy: Vec<DVec2> = poly.iter().map(|w| warp.from_w(*w)).collect();
    let n = xy.len();
    let axis_aligned = (0..n).all(|i| xy[i].x == xy[(i + 1) % n].x || xy[i].y == xy[(i + 1) % n].y);
    if n == 4 && axis_aligned {
        let lo = xy.iter().copied().fold(DVec2::INFINITY, DVec2::min);
        let hi = xy.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max);
        out.push((Region::rectangle(lo, hi), RegionKind::Rectangle));
        return;
    }
    for i in 1..n - 1 {
        let (a, b, c) = (xy[0], xy[i], xy[i + 1]);
        if (b - a).perp_dot(c - a) != 0.0 {
            out.push((Region::triangle(a, b, c), RegionKind::Triangle));
        }
    }
}

/// A fan of triangles of `w` (step 4): straight ones as triangles of the
/// plane, the others as curved triangles.
fn emit_fan(warp: &Warp, poly: &[DVec2], out: &mut Vec<(Region, RegionKind)>) {
    for i in 1..poly.len() - 1 {
        let w = [poly[0], poly[i], poly[i + 1]];
        if (w[1] - w[0]).perp_dot(w[2] - w[0]) == 0.0 {
            continue;
        }
        let triangle = CurvedTriangle::new(*warp, w);
        match RegionKind::of_curved(&triangle) {
            RegionKind::Triangle => {
                let [a, b, c] = w.map(|p| warp.from_w(p));
                out.push((Region::triangle(a, b, c), RegionKind::Triangle));
            }
            kind => out.push((Region::Curved(triangle), kind)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Quadric;
    use crate::sampling::heightfield::LocalForm;
    use glam::DVec3;

    /// Whether plane point `p` is owned by `hf` (both ownership functions
    /// non-negative).
    fn owned(hf: &Heightfield, p: DVec2) -> bool {
        hf.owns_x.value(p) >= 0.0 && hf.owns_y.value(p) >= 0.0
    }

    fn contains(region: &Region, p: DVec2) -> bool {
        match region {
            Region::Curved(c) => c.contains(p),
            Region::Polygon(poly) => poly.closest_point(p).distance(p) <= 1e-12,
        }
    }

    /// The basic regions cover exactly the owned part of the domain, each
    /// curved triangle is valid and lies in the low-distortion region.
    fn check(q: &Quadric, half: f64) -> [usize; RegionKind::COUNT] {
        let mut kinds = [0; RegionKind::COUNT];
        for hf in LocalForm::new(q).heightfields() {
            let (lo, hi) = (DVec2::splat(-half), DVec2::splat(half));
            let regions = basic_regions(&hf, lo, hi);
            for (region, kind) in &regions {
                kinds[kind.index()] += 1;
                if let Region::Curved(c) = region {
                    c.validate().unwrap();
                    let (_, max) = c.distortion_bounds(&hf);
                    assert!(max <= 3f64.sqrt() * (1.0 + 1e-6), "{max} {c:?}");
                }
            }
            let n = 97;
            for i in 0..=n {
                for j in 0..=n {
                    let p = lo + (hi - lo) * DVec2::new(f64::from(i), f64::from(j)) / f64::from(n);
                    let inside = regions.iter().any(|(r, _)| contains(r, p));
                    let margin = 1e-9;
                    let clearly_owned = hf.owns_x.value(p) > margin && hf.owns_y.value(p) > margin;
                    if clearly_owned {
                        assert!(inside, "{q:?}: owned {p} not covered");
                    }
                    let clearly_foreign =
                        hf.owns_x.value(p) < -margin || hf.owns_y.value(p) < -margin;
                    if clearly_foreign {
                        assert!(!inside, "{q:?}: foreign {p} covered");
                    }
                    assert!(!inside || owned(&hf, p) || !clearly_foreign);
                }
            }
        }
        kinds
    }

    #[test]
    fn sphere_has_elliptic_triangles() {
        let q = Quadric::sphere(DVec3::ZERO, 1.0).unwrap();
        let kinds = check(&q, 1.2);
        // Per plane and branch, four quadrants of a square and two
        // elliptic triangles each.
        assert_eq!(kinds[RegionKind::Rectangle.index()], 6 * 4);
        assert_eq!(kinds[RegionKind::EllipticTriangle.index()], 6 * 8);
        assert_eq!(kinds[RegionKind::HyperbolicTriangle.index()], 0);
    }

    #[test]
    fn hyperboloids_have_hyperbolic_triangles() {
        let one = Quadric::hyperboloid_one_sheet(DVec3::new(1.0, 1.0, 0.7)).unwrap();
        let kinds = check(&one, 2.5);
        assert!(
            kinds[RegionKind::HyperbolicTriangle.index()] > 0,
            "{kinds:?}"
        );
        let two = Quadric::hyperboloid_two_sheets(DVec3::new(1.0, 0.8, 1.2)).unwrap();
        let kinds = check(&two, 2.5);
        assert!(
            kinds[RegionKind::HyperbolicTriangle.index()] > 0,
            "{kinds:?}"
        );
    }

    #[test]
    fn other_quadrics_are_covered() {
        let shapes = [
            Quadric::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.5, 2.0)),
            Quadric::elliptic_paraboloid(DVec2::new(0.5, 1.0)),
            Quadric::hyperbolic_paraboloid(DVec2::new(0.7, 1.0)),
            Quadric::elliptic_cone(DVec2::new(0.6, 1.1)),
            Quadric::cylinder(DVec3::ZERO, DVec3::Z, 0.7),
        ];
        let mut parabolic = 0;
        for q in shapes {
            parabolic += check(&q.unwrap(), 2.0)[RegionKind::ParabolicTriangle.index()];
        }
        assert!(parabolic > 0);
    }
}
