//! Curved triangles: the elliptic, hyperbolic (and parabolic) basic
//! regions of paper 2, §4.1 (Fig. 8a), and their subdivision.
//!
//! Notation: `(x, y)` plane coordinates, `w = (u, v)` the warped
//! coordinates of one cell ([`Warp`]: `u = x²` on a quadratic axis, `u = x`
//! on a linear one). Conics centred at the origin are lines in `w`.
//!
//! *Parametrisation.* A curved triangle is a triangle `W₀W₁W₂` of `w`; the
//! region is its preimage, a triangle of the plane whose sides are arcs of
//! conics centred at the origin (or straight). The paper's *elliptic
//! triangle* (an axis-aligned right triangle whose diagonal is part of an
//! ellipse) and *hyperbolic triangle* (one side part of a hyperbola) are
//! such triangles with one side on the boundary of a low-distortion region
//! (eq. 15 or 16) and the others straight.
//!
//! *Subdivision.* The side with the longest chord is split at the point of
//! its arc whose dominant plane coordinate is the chord's midpoint (in `w`:
//! the point at `t = (x_m² − x₀²)/(x₁² − x₀²) ∈ [¼, ¾]`); both halves are
//! again triangles of `w`, so they stay in the parent (and in the
//! low-distortion region).
//!
//! *Distortion bound.* `δ` (eq. 13) is linear-fractional in `w`, so on a
//! triangle of `w` its extrema lie at the three vertices
//! ([`Heightfield::distortion_bounds_at`]); inside a low-distortion region
//! they are at most `√3`.
//!
//! *Coverage.* A region of the plane that is not convex needs paths that
//! stay inside it: between two of its points the arc above their
//! `w`-segment does (the region is convex in `w`), and it is at most
//! `t + 2s` long for points `t` apart ([`Warp::path_length`]), `s` being the
//! largest sagitta such points can have. The surface stretches plane lengths
//! by at most `δ₊`, so the world distance of the surface points above two
//! points of the region is at most `δ₊·path_length(t)`. Every point of the
//! region lies within `σ` (the largest sagitta of its sides) of the
//! straight triangle of its vertices, because the sides lie within `σ` of
//! their chords and the region is enclosed by them; so
//! [`cover_radius`](CurvedTriangle::cover_radius) and
//! [`reach`](CurvedTriangle::reach) are path lengths over the straight
//! triangle's radii plus `σ`, and the fill places samples on grid cells
//! whose points are within a path length `r/δ₊` of them.

use glam::DVec2;

use crate::sampling::heightfield::Heightfield;
use crate::sampling::polygon::triangle_cover_radius;
use crate::sampling::warp::{ArcKind, Warp};

/// Relative tolerance of the containment test in `w`.
const CONTAINS_TOLERANCE: f64 = 1e-12;

/// A triangle of the warped plane and its preimage (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvedTriangle {
    /// The vertices in the plane.
    xy: [DVec2; 3],
    /// The vertices in `w`.
    w: [DVec2; 3],
    /// The warp of the cell the triangle lies in.
    warp: Warp,
}

impl CurvedTriangle {
    /// The triangle of `w` with vertices `w` in the cell of `warp`.
    #[must_use]
    pub fn new(warp: Warp, w: [DVec2; 3]) -> Self {
        Self {
            xy: w.map(|p| warp.from_w(p)),
            w,
            warp,
        }
    }

    /// The vertices in the plane.
    #[must_use]
    pub fn vertices(&self) -> &[DVec2] {
        &self.xy
    }

    /// The vertices in `w`.
    #[must_use]
    pub fn warped(&self) -> &[DVec2; 3] {
        &self.w
    }

    /// The warp of its cell.
    #[must_use]
    pub fn warp(&self) -> &Warp {
        &self.warp
    }

    /// The arc kind of side `i` (from vertex `i` to vertex `i + 1`).
    #[must_use]
    pub fn side_kind(&self, i: usize) -> ArcKind {
        self.warp.arc_kind(self.w[i], self.w[(i + 1) % 3])
    }

    /// The bounding box `(lo, hi)`: every side lies in the box of its ends.
    #[must_use]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let lo = self.xy[0].min(self.xy[1]).min(self.xy[2]);
        let hi = self.xy[0].max(self.xy[1]).max(self.xy[2]);
        (lo, hi)
    }

    /// The smallest `|x|` and `|y|` over the region (at a vertex: `u`
    /// and `v` are linear on the triangle of `w`).
    fn floor(&self) -> DVec2 {
        self.xy[0].abs().min(self.xy[1].abs()).min(self.xy[2].abs())
    }

    /// `σ`: the largest sagitta of the three sides.
    #[must_use]
    pub fn side_sagitta(&self) -> f64 {
        (0..3)
            .map(|i| self.warp.sagitta(self.xy[i], self.xy[(i + 1) % 3]))
            .fold(0.0, f64::max)
    }

    /// An upper bound of the length of the path inside the region between
    /// two of its points at most `t` apart.
    #[must_use]
    pub fn path_length(&self, t: f64) -> f64 {
        self.warp.path_length(t, self.floor())
    }

    /// The largest distance `h` between two points whose path inside the
    /// region is at most `rho` long.
    #[must_use]
    pub fn step_within(&self, rho: f64) -> f64 {
        self.warp.step_within(rho, self.floor())
    }

    /// A path length `ρ` such that every point of the region has a vertex
    /// within a path of length `ρ` inside the region.
    #[must_use]
    pub fn cover_radius(&self) -> f64 {
        let [a, b, c] = self.xy;
        self.path_length(triangle_cover_radius(a, b, c) + self.side_sagitta())
    }

    /// The longest path inside the region from vertex `i` to any point of it.
    #[must_use]
    pub fn reach(&self, i: usize) -> f64 {
        let far = self
            .xy
            .iter()
            .map(|v| v.distance(self.xy[i]))
            .fold(0.0, f64::max);
        self.path_length(far + self.side_sagitta())
    }

    /// An upper bound of the diameter.
    #[must_use]
    pub fn diameter(&self) -> f64 {
        let far = (0..3)
            .map(|i| self.xy[i].distance(self.xy[(i + 1) % 3]))
            .fold(0.0, f64::max);
        far + 2.0 * self.side_sagitta()
    }

    /// Bounds `(min, max)` of the distortion of `hf` over the region (at
    /// the vertices, see the module notes).
    #[must_use]
    pub fn distortion_bounds(&self, hf: &Heightfield) -> (f64, f64) {
        hf.distortion_bounds_at(&self.xy)
    }

    /// Splits the side with the longest chord (see the module notes).
    #[must_use]
    pub fn split(&self) -> [Self; 2] {
        let len = |i: usize| self.xy[i].distance_squared(self.xy[(i + 1) % 3]);
        let i = (0..3)
            .max_by(|a, b| len(*a).total_cmp(&len(*b)))
            .unwrap_or(0);
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let (p, q) = (self.xy[i], self.xy[j]);
        let d = (q - p).abs();
        let axis = usize::from(d.y > d.x);
        let t = if self.warp.square[axis] {
            let (a, b) = (p[axis], q[axis]);
            let (wa, wb) = (a * a, b * b);
            let m = 0.5 * (a + b);
            if wb == wa {
                0.5
            } else {
                ((m * m - wa) / (wb - wa)).clamp(0.0, 1.0)
            }
        } else {
            0.5
        };
        let wm = self.w[i].lerp(self.w[j], t);
        let m = self.warp.from_w(wm);
        let (xk, wk) = (self.xy[k], self.w[k]);
        [
            Self {
                xy: [p, m, xk],
                w: [self.w[i], wm, wk],
                warp: self.warp,
            },
            Self {
                xy: [m, q, xk],
                w: [wm, self.w[j], wk],
                warp: self.warp,
            },
        ]
    }

    /// Whether plane point `p` lies in the region (a small relative
    /// tolerance in `w`).
    #[must_use]
    pub fn contains(&self, p: DVec2) -> bool {
        let w = self.warp.to_w(p);
        let [a, b, c] = self.w;
        let area = (b - a).perp_dot(c - a);
        if area == 0.0 {
            return false;
        }
        let tol = -CONTAINS_TOLERANCE * area.abs();
        let s = area.signum();
        (b - a).perp_dot(w - a) * s >= tol
            && (c - b).perp_dot(w - b) * s >= tol
            && (a - c).perp_dot(w - c) * s >= tol
    }

    /// A point of the region inside the plane box `[lo, hi]` (within the
    /// region's cell), or `None` when they meet in no area: the preimage of
    /// the centroid of the triangle of `w` clipped to the box's image.
    #[must_use]
    pub fn point_in_box(&self, lo: DVec2, hi: DVec2) -> Option<DVec2> {
        let (wlo, whi) = self.warp.w_box(lo, hi);
        // A triangle clipped by four half-planes has at most seven corners.
        let mut poly = [DVec2::ZERO; 8];
        let mut next = [DVec2::ZERO; 8];
        poly[..3].copy_from_slice(&self.w);
        let mut len = 3;
        for (axis, at, above) in [
            (0, wlo.x, true),
            (0, whi.x, false),
            (1, wlo.y, true),
            (1, whi.y, false),
        ] {
            let side = |p: DVec2| if above { p[axis] - at } else { at - p[axis] };
            let mut out = 0;
            for i in 0..len {
                let (a, b) = (poly[i], poly[(i + 1) % len]);
                let (da, db) = (side(a), side(b));
                if da >= 0.0 {
                    next[out] = a;
                    out += 1;
                }
                if (da < 0.0) != (db < 0.0) {
                    let mut p = a + (b - a) * (da / (da - db));
                    p[axis] = at;
                    next[out] = p;
                    out += 1;
                }
            }
            if out < 3 {
                return None;
            }
            poly[..out].copy_from_slice(&next[..out]);
            len = out;
        }
        let poly = &poly[..len];
        let area2: f64 = (1..len - 1)
            .map(|i| (poly[i] - poly[0]).perp_dot(poly[i + 1] - poly[0]))
            .sum();
        if area2 == 0.0 {
            return None;
        }
        #[allow(clippy::cast_precision_loss)]
        let centroid = poly.iter().copied().sum::<DVec2>() / len as f64;
        Some(self.warp.from_w(centroid).clamp(lo, hi))
    }

    /// Whether the region meets the plane box `[lo, hi]` (within its cell):
    /// the separating-axis test of the triangle and the box's image in `w`.
    #[must_use]
    pub fn meets_box(&self, lo: DVec2, hi: DVec2) -> bool {
        let (wlo, whi) = self.warp.w_box(lo, hi);
        let [a, b, c] = self.w;
        if a.max(b).max(c).cmplt(wlo).any() || a.min(b).min(c).cmpgt(whi).any() {
            return false;
        }
        let corners = [wlo, DVec2::new(whi.x, wlo.y), whi, DVec2::new(wlo.x, whi.y)];
        let orientation = (b - a).perp_dot(c - a).signum();
        [(a, b), (b, c), (c, a)].into_iter().all(|(p, q)| {
            corners
                .iter()
                .any(|k| (q - p).perp_dot(*k - p) * orientation >= 0.0)
        })
    }

    /// The point of the region whose `w` is nearest to that of plane point
    /// `p` (`p` itself when it is inside): a point of the region near `p`.
    #[must_use]
    pub fn nearest_to(&self, p: DVec2) -> DVec2 {
        if self.contains(p) {
            return p;
        }
        let w = self.warp.to_w(p);
        let on_side = |a: DVec2, b: DVec2| {
            let ab = b - a;
            let len2 = ab.length_squared();
            let t = if len2 > 0.0 {
                ((w - a).dot(ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            a + t * ab
        };
        let [a, b, c] = self.w;
        let best = [on_side(a, b), on_side(b, c), on_side(c, a)]
            .into_iter()
            .min_by(|x, y| x.distance_squared(w).total_cmp(&y.distance_squared(w)))
            .unwrap_or(a);
        self.warp.from_w(best)
    }

    /// Checks the invariants: finite vertices, the plane vertices are the
    /// preimages of the `w` vertices, all in one cell of the warp, and a
    /// triangle of positive area in `w`.
    ///
    /// Errors: a message naming the broken invariant.
    pub fn validate(&self) -> Result<(), String> {
        for (p, w) in self.xy.iter().zip(&self.w) {
            if !p.is_finite() || !w.is_finite() {
                return Err(format!("non-finite vertex {p} / {w}"));
            }
            if *p != self.warp.from_w(*w) {
                return Err(format!("vertex {p} is not the preimage of {w}"));
            }
            for axis in 0..2 {
                if self.warp.square[axis] && (w[axis] < 0.0 || p[axis] * self.warp.sign[axis] < 0.0)
                {
                    return Err(format!("vertex {p} outside the warp's cell"));
                }
            }
        }
        let [a, b, c] = self.w;
        if (b - a).perp_dot(c - a) == 0.0 {
            return Err("zero area in w".to_owned());
        }
        Ok(())
    }
}

/// Clips a convex polygon to the half-plane `n·p + c ≥ 0`. On an
/// axis-aligned line the new vertices get the line's coordinate exactly,
/// so that sides along it stay axis-aligned.
pub(crate) fn clip_half_plane(poly: &[DVec2], n: DVec2, c: f64) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (n.dot(a) + c, n.dot(b) + c);
        if da >= 0.0 {
            out.push(a);
        }
        if (da < 0.0) != (db < 0.0) {
            let mut p = a + (b - a) * (da / (da - db));
            if n.y == 0.0 {
                p.x = -c / n.x;
            } else if n.x == 0.0 {
                p.y = -c / n.y;
            }
            out.push(p);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An elliptic triangle of the unit circle in the first quadrant:
    /// right angle at `(0.3, 0.2)`, diagonal on `x² + y² = 1`.
    fn elliptic() -> CurvedTriangle {
        let warp = Warp::new([true, true], DVec2::ONE);
        let k = DVec2::new(0.3, 0.2);
        let a = DVec2::new((1.0f64 - 0.04).sqrt(), 0.2);
        let b = DVec2::new(0.3, (1.0f64 - 0.09).sqrt());
        CurvedTriangle::new(warp, [warp.to_w(a), warp.to_w(b), warp.to_w(k)])
    }

    /// A hyperbolic triangle touching the axis `y = 0`, in the quadrant
    /// `x < 0, y < 0`: `x² − y² = 1` from `(−1, 0)` to `(−2, −√3)`, and the
    /// corner `(−2, 0)`.
    fn hyperbolic() -> CurvedTriangle {
        let warp = Warp::new([true, true], DVec2::NEG_ONE);
        let w = [
            DVec2::new(1.0, 0.0),
            DVec2::new(4.0, 3.0),
            DVec2::new(4.0, 0.0),
        ];
        CurvedTriangle::new(warp, w)
    }

    /// Points of the region on a fine grid of its box.
    fn inside(t: &CurvedTriangle, n: u32) -> Vec<DVec2> {
        let (lo, hi) = t.bounds();
        let mut out = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let p = lo + (hi - lo) * DVec2::new(f64::from(i), f64::from(j)) / f64::from(n);
                if t.contains(p) {
                    out.push(p);
                }
            }
        }
        out
    }

    #[test]
    fn kinds_and_validity() {
        let side_kinds = |t: CurvedTriangle| [0, 1, 2].map(|i| t.side_kind(i));
        assert!(side_kinds(elliptic()).contains(&ArcKind::Elliptic));
        assert!(side_kinds(hyperbolic()).contains(&ArcKind::Hyperbolic));
        for t in [elliptic(), hyperbolic()] {
            t.validate().unwrap();
            for c in t.split() {
                c.validate().unwrap();
            }
        }
    }

    #[test]
    fn cover_and_reach_are_path_lengths() {
        for t in [elliptic(), hyperbolic()] {
            let pts = inside(&t, 60);
            assert!(pts.len() > 300);
            let cover = t.cover_radius();
            for p in &pts {
                let best = t
                    .vertices()
                    .iter()
                    .map(|v| arc_length(&t, *v, *p))
                    .fold(f64::INFINITY, f64::min);
                assert!(best <= cover * (1.0 + 1e-9), "{p}: {best} > {cover}");
                for i in 0..3 {
                    assert!(arc_length(&t, t.vertices()[i], *p) <= t.reach(i) * (1.0 + 1e-9));
                }
            }
        }
    }

    /// The length of the arc above the `w`-segment from `p` to `q`.
    fn arc_length(t: &CurvedTriangle, p: DVec2, q: DVec2) -> f64 {
        let (a, b) = (t.warp.to_w(p), t.warp.to_w(q));
        let mut prev = p;
        let mut len = 0.0;
        for i in 1..=200 {
            let x = t.warp.from_w(a.lerp(b, f64::from(i) / 200.0));
            len += x.distance(prev);
            prev = x;
        }
        len
    }

    #[test]
    fn children_partition_the_parent_and_shrink() {
        for t in [elliptic(), hyperbolic()] {
            let area = |t: &CurvedTriangle| {
                let [a, b, c] = t.w;
                (b - a).perp_dot(c - a).abs()
            };
            let mut level = vec![t];
            for _ in 0..8 {
                let next: Vec<CurvedTriangle> =
                    level.iter().flat_map(CurvedTriangle::split).collect();
                let sum: f64 = next.iter().map(area).sum();
                assert!((sum - area(&t)).abs() <= 1e-12 * area(&t));
                level = next;
            }
            let big = level
                .iter()
                .map(CurvedTriangle::diameter)
                .fold(0.0, f64::max);
            assert!(big < 0.25 * t.diameter(), "{big} vs {}", t.diameter());
            // Every point of the parent is in some leaf.
            for p in inside(&t, 40) {
                assert!(level.iter().any(|c| c.contains(p)), "{p}");
            }
        }
    }

    #[test]
    fn boxes_find_points_inside() {
        let t = elliptic();
        let (lo, hi) = t.bounds();
        let mut found = 0;
        for i in 0..10 {
            for j in 0..10 {
                let a = lo + (hi - lo) * DVec2::new(f64::from(i), f64::from(j)) / 10.0;
                let b = a + (hi - lo) / 10.0;
                if let Some(p) = t.point_in_box(a, b) {
                    assert!(t.contains(p) && p.cmpge(a).all() && p.cmple(b).all());
                    assert!(t.meets_box(a, b));
                    found += 1;
                } else {
                    // Boxes that only touch the region may still "meet" it.
                    let touch = t.meets_box(a, b);
                    assert!(!touch || t.point_in_box(a - 1e-9, b + 1e-9).is_some());
                }
                let c = 0.5 * (a + b);
                let near = t.nearest_to(c);
                assert!(t.contains(near));
                if t.contains(c) {
                    assert_eq!(near, c);
                }
            }
        }
        assert!(found > 30);
        assert!(
            t.point_in_box(DVec2::splat(0.9), DVec2::splat(1.0))
                .is_none()
        );
    }
}
