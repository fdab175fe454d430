//! Basic regions on a sampling plane (paper 2, §4.1, Fig. 8).
//!
//! Notation: `(x, y)` plane coordinates of a [`Heightfield`]; the domain is
//! the axis-aligned box `[c − R, c + R]²` around the bounding sphere's
//! projected centre `c` (radius `R`). It is cut by the coordinate axes into
//! quadrant rectangles, and where the heightfield has octant diagonals
//! (`|sx·x| = |sy·y|`, where two normal components are equal) each quadrant
//! is cut along its diagonal into triangles. On each side of a diagonal only
//! one ownership conic (eq. 15 or 16) can bound the low-distortion region;
//! a triangle crossed by it is an *elliptic* or *hyperbolic triangle*, its
//! curved side given implicitly by the conic (exact on boxes, see
//! [`Heightfield::box_is_owned`]). Regions are convex polygons of three or
//! four vertices; subdivision halves the longest edge.

use glam::DVec2;

use crate::sampling::heightfield::{HeightKind, Heightfield, Separable};

/// What a basic region is (Fig. 8a).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RegionKind {
    /// A triangle wholly inside the low-distortion region.
    Triangle,
    /// An axis-aligned rectangle.
    Rectangle,
    /// A triangle whose curved side is part of an ellipse centred at the origin.
    EllipticTriangle,
    /// A triangle whose curved side is part of a hyperbola centred at the origin.
    HyperbolicTriangle,
}

/// A convex region of a sampling plane: a triangle or a rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    vertices: [DVec2; 4],
    count: u8,
}

impl Region {
    /// A triangle.
    #[must_use]
    pub fn triangle(a: DVec2, b: DVec2, c: DVec2) -> Self {
        Self {
            vertices: [a, b, c, c],
            count: 3,
        }
    }

    /// The axis-aligned rectangle `[lo, hi]`.
    #[must_use]
    pub fn rectangle(lo: DVec2, hi: DVec2) -> Self {
        Self {
            vertices: [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)],
            count: 4,
        }
    }

    /// The vertices in order.
    #[must_use]
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices[..usize::from(self.count)]
    }

    /// `true` for a rectangle.
    #[must_use]
    pub fn is_rectangle(&self) -> bool {
        self.count == 4
    }

    /// The bounding box `(lo, hi)`.
    #[must_use]
    pub fn bounds(&self) -> (DVec2, DVec2) {
        let v = self.vertices();
        let lo = v.iter().copied().fold(DVec2::INFINITY, DVec2::min);
        let hi = v.iter().copied().fold(DVec2::NEG_INFINITY, DVec2::max);
        (lo, hi)
    }

    /// The largest distance from vertex `i` to any point of the region.
    #[must_use]
    pub fn reach(&self, i: usize) -> f64 {
        let v = self.vertices();
        v.iter().map(|w| w.distance(v[i])).fold(0.0, f64::max)
    }

    /// The largest distance between two vertices (the diameter of a convex polygon).
    #[must_use]
    pub fn diameter(&self) -> f64 {
        (0..self.vertices().len())
            .map(|i| self.reach(i))
            .fold(0.0, f64::max)
    }

    /// A radius `ρ` such that discs of radius `ρ` around all vertices cover
    /// the region: half the diagonal of a rectangle; the circumradius of an
    /// acute triangle, half the longest edge of an obtuse one.
    #[must_use]
    pub fn cover_radius(&self) -> f64 {
        let v = self.vertices();
        if self.is_rectangle() {
            return 0.5 * v[0].distance(v[2]);
        }
        let (a, b, c) = (v[0], v[1], v[2]);
        let (la, lb, lc) = (
            b.distance_squared(c),
            a.distance_squared(c),
            a.distance_squared(b),
        );
        let longest = la.max(lb).max(lc);
        if 2.0 * longest >= la + lb + lc {
            // Right or obtuse: the longest edge's midpoint is farthest.
            return 0.5 * longest.sqrt();
        }
        let area2 = (b - a).perp_dot(c - a).abs();
        if area2 == 0.0 {
            return 0.5 * longest.sqrt();
        }
        (la * lb * lc).sqrt() / (2.0 * area2)
    }

    /// Splits the longest edge in half (Fig. 8c).
    #[must_use]
    pub fn split(&self) -> [Self; 2] {
        let v = self.vertices;
        if self.is_rectangle() {
            let (lo, hi) = (v[0], v[2]);
            let mid = 0.5 * (lo + hi);
            return if hi.x - lo.x >= hi.y - lo.y {
                [
                    Self::rectangle(lo, DVec2::new(mid.x, hi.y)),
                    Self::rectangle(DVec2::new(mid.x, lo.y), hi),
                ]
            } else {
                [
                    Self::rectangle(lo, DVec2::new(hi.x, mid.y)),
                    Self::rectangle(DVec2::new(lo.x, mid.y), hi),
                ]
            };
        }
        let edges = [(0, 1, 2), (1, 2, 0), (2, 0, 1)];
        let (i, j, k) = edges
            .into_iter()
            .max_by(|a, b| {
                v[a.0]
                    .distance_squared(v[a.1])
                    .total_cmp(&v[b.0].distance_squared(v[b.1]))
            })
            .unwrap_or((0, 1, 2));
        let m = 0.5 * (v[i] + v[j]);
        [Self::triangle(v[i], m, v[k]), Self::triangle(m, v[j], v[k])]
    }

    /// The point of the region nearest to `p`.
    #[must_use]
    pub fn closest_point(&self, p: DVec2) -> DVec2 {
        let v = self.vertices();
        if self.is_rectangle() {
            return p.clamp(v[0], v[2]);
        }
        let inside = (0..3).all(|e| {
            let (a, b) = (v[e], v[(e + 1) % 3]);
            let orient = (v[1] - v[0]).perp_dot(v[2] - v[0]).signum();
            (b - a).perp_dot(p - a) * orient >= 0.0
        });
        if inside {
            return p;
        }
        (0..3)
            .map(|e| {
                let (a, b) = (v[e], v[(e + 1) % 3]);
                let ab = b - a;
                let len2 = ab.length_squared();
                let t = if len2 > 0.0 {
                    ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                a + t * ab
            })
            .min_by(|a, b| a.distance_squared(p).total_cmp(&b.distance_squared(p)))
            .unwrap_or(v[0])
    }
}

/// Splits `[lo, hi]` at `x = 0` and `y = 0` into quadrant boxes.
fn quadrant_boxes(lo: DVec2, hi: DVec2) -> Vec<(DVec2, DVec2)> {
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

/// Clips a convex polygon to the half-plane `n·p ≥ 0`.
fn clip(poly: &[DVec2], n: DVec2) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da < 0.0) != (db < 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// Triangle fan of a convex polygon, dropping degenerate triangles.
fn fan(poly: &[DVec2]) -> Vec<Region> {
    (1..poly.len().saturating_sub(1))
        .map(|i| Region::triangle(poly[0], poly[i], poly[i + 1]))
        .filter(|t| {
            let v = t.vertices();
            (v[1] - v[0]).perp_dot(v[2] - v[0]).abs() > 0.0
        })
        .collect()
}

/// The basic regions of `hf` over the domain box `[lo, hi]`, with their kinds.
///
/// Regions wholly outside the plane's low-distortion region are dropped.
#[must_use]
pub fn basic_regions(hf: &Heightfield, lo: DVec2, hi: DVec2) -> Vec<(Region, RegionKind)> {
    let mut out = Vec::new();
    for (qlo, qhi) in quadrant_boxes(lo, hi) {
        if qhi.x <= qlo.x || qhi.y <= qlo.y || hf.box_is_foreign(qlo, qhi) {
            continue;
        }
        let rect = Region::rectangle(qlo, qhi);
        let Some((sx, sy)) = hf.octant_slopes() else {
            out.push((rect, RegionKind::Rectangle));
            continue;
        };
        // The diagonal through this quadrant: |sx|·|x| = |sy|·|y|, as the
        // line n·p = 0 with n ⟂ to it.
        let centre = 0.5 * (qlo + qhi);
        let (gx, gy) = (sx.abs() * centre.x.signum(), sy.abs() * centre.y.signum());
        let normal = DVec2::new(gx, -gy);
        let poly = rect.vertices().to_vec();
        let sides = [clip(&poly, normal), clip(&poly, -normal)];
        if sides.iter().any(|s| s.len() < 3) {
            out.push((rect, RegionKind::Rectangle));
            continue;
        }
        for (side, poly) in sides.iter().enumerate() {
            // Side 0: |nᵢ| ≥ |nⱼ| there, so only conic 15 (owns_x) bounds it.
            let conic = if side == 0 { &hf.owns_x } else { &hf.owns_y };
            for tri in fan(poly) {
                let (tlo, thi) = tri.bounds();
                if hf.box_is_foreign(tlo, thi) {
                    continue;
                }
                let kind = if hf.box_is_owned(tlo, thi) {
                    RegionKind::Triangle
                } else {
                    conic_kind(hf, conic)
                };
                out.push((tri, kind));
            }
        }
    }
    out
}

/// Elliptic or hyperbolic, by the signs of the conic's square terms.
fn conic_kind(hf: &Heightfield, conic: &Separable) -> RegionKind {
    let elliptic = match hf.kind {
        HeightKind::Root { .. } => conic.x.a * conic.y.a > 0.0,
        HeightKind::Polynomial => true,
    };
    if elliptic {
        RegionKind::EllipticTriangle
    } else {
        RegionKind::HyperbolicTriangle
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cover_radius_covers() {
        let regions = [
            Region::rectangle(DVec2::ZERO, DVec2::new(2.0, 1.0)),
            Region::triangle(DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(1.0, 1.5)),
            Region::triangle(DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(1.0, 0.3)),
        ];
        for r in regions {
            let rho = r.cover_radius();
            let (lo, hi) = r.bounds();
            for s in 0..=40 {
                for t in 0..=40 {
                    let p = lo + (hi - lo) * DVec2::new(f64::from(s), f64::from(t)) / 40.0;
                    if r.closest_point(p).distance(p) > 1e-12 {
                        continue;
                    }
                    let near = r
                        .vertices()
                        .iter()
                        .map(|v| v.distance(p))
                        .fold(f64::INFINITY, f64::min);
                    assert!(near <= rho * (1.0 + 1e-12), "{r:?} {p}");
                }
            }
            let [a, b] = r.split();
            assert!(a.diameter() <= r.diameter() && b.diameter() <= r.diameter());
        }
    }
}
