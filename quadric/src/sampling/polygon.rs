//! Straight regions of a sampling plane (paper 2, §4.1–4.2, Fig. 8):
//! triangles and axis-aligned rectangles, and the cover radius of a
//! triangle, which the curved triangles of
//! [`curved`](crate::sampling::curved) build on.
//!
//! Notation: `(x, y)` plane coordinates of a heightfield; paths inside a
//! polygon are straight, so its radii are plane distances.

use glam::DVec2;

/// The cover radius of a triangle: the circumradius of an acute triangle,
/// half the longest edge of a right or obtuse one (discs of that radius
/// around the vertices cover it).
#[must_use]
pub fn triangle_cover_radius(a: DVec2, b: DVec2, c: DVec2) -> f64 {
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

/// A convex region of a sampling plane: a triangle or a rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polygon {
    vertices: [DVec2; 4],
    count: u8,
}

impl Polygon {
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
        // One square root of the largest squared distance (`√` is monotone).
        let v = self.vertices();
        v.iter()
            .map(|w| w.distance_squared(v[i]))
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// The largest distance between two vertices (the diameter of a convex polygon).
    #[must_use]
    pub fn diameter(&self) -> f64 {
        let v = self.vertices();
        if self.is_rectangle() {
            // Both diagonals have the same length.
            return v[0].distance(v[2]);
        }
        let longest = (0..3)
            .map(|i| v[i].distance_squared(v[(i + 1) % 3]))
            .fold(0.0, f64::max);
        longest.sqrt()
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
        triangle_cover_radius(v[0], v[1], v[2])
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cover_radius_covers() {
        let regions = [
            Polygon::rectangle(DVec2::ZERO, DVec2::new(2.0, 1.0)),
            Polygon::triangle(DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(1.0, 1.5)),
            Polygon::triangle(DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(1.0, 0.3)),
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
