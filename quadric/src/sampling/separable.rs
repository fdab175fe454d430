//! Separable functions `f(x) + g(y)` of two quadratics, with exact ranges
//! over axis-aligned boxes (paper 2, §3.4, §4.1).
//!
//! Notation: `f(x) = a x² + b x + c`. The range of `f` over `[lo, hi]` is
//! taken at the ends and, if inside, at the vertex `x = −b / 2a`; the range
//! of `f(x) + g(y)` over a box is the sum of the two ranges (exact, since
//! the two parts vary independently).

use glam::DVec2;

/// A quadratic `a x² + b x + c` in one variable.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad1 {
    /// Coefficient of `x²`.
    pub a: f64,
    /// Coefficient of `x`.
    pub b: f64,
    /// Constant.
    pub c: f64,
}

impl Quad1 {
    /// The value at `x`.
    #[must_use]
    #[inline]
    pub fn value(&self, x: f64) -> f64 {
        (self.a * x + self.b) * x + self.c
    }

    /// The derivative `2a x + b` at `x`.
    #[must_use]
    #[inline]
    pub fn slope(&self, x: f64) -> f64 {
        2.0 * self.a * x + self.b
    }

    /// The exact range `(min, max)` over `[lo, hi]`.
    #[must_use]
    pub fn range(&self, lo: f64, hi: f64) -> (f64, f64) {
        let (u, v) = (self.value(lo), self.value(hi));
        let (mut min, mut max) = (u.min(v), u.max(v));
        if self.a != 0.0 {
            // `b = 0` (a quadric's principal axes) needs no division.
            let vertex = if self.b == 0.0 {
                0.0
            } else {
                -self.b / (2.0 * self.a)
            };
            if lo < vertex && vertex < hi {
                let w = self.value(vertex);
                min = min.min(w);
                max = max.max(w);
            }
        }
        (min, max)
    }

    /// The exact range of the squared slope `(2a x + b)²` over `[lo, hi]`.
    #[must_use]
    pub fn slope_squared_range(&self, lo: f64, hi: f64) -> (f64, f64) {
        let (u, v) = (self.slope(lo), self.slope(hi));
        let max = (u * u).max(v * v);
        let min = if u.signum() != v.signum() {
            0.0
        } else {
            (u * u).min(v * v)
        };
        (min, max)
    }
}

/// A separable function `f(x) + g(y)` (constants folded into `f`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Separable {
    /// The part in `x`, with the constant.
    pub x: Quad1,
    /// The part in `y` (its constant is zero).
    pub y: Quad1,
}

impl Separable {
    /// The value at `p`.
    #[must_use]
    #[inline]
    pub fn value(&self, p: DVec2) -> f64 {
        self.x.value(p.x) + self.y.value(p.y)
    }

    /// The exact range `(min, max)` over the box `[lo, hi]`.
    #[must_use]
    pub fn range(&self, lo: DVec2, hi: DVec2) -> (f64, f64) {
        let (a, b) = self.x.range(lo.x, hi.x);
        let (c, d) = self.y.range(lo.y, hi.y);
        (a + c, b + d)
    }
}
