//! Warped plane coordinates, in which the boundaries of the low-distortion
//! regions are straight lines (paper 2, §3.4 and §4.1).
//!
//! Notation: `(x, y)` plane coordinates of a [`Heightfield`]; `w = (u, v)`
//! warped coordinates. Every separable part of a heightfield is, per axis,
//! either *quadratic* without a linear term (`a x² + c`, an axis with
//! `λ ≠ 0`) or *linear* (`b x + c`, a singular axis). The warp maps each
//! quadratic axis by `u = x²` (within one sign half `σx ≥ 0`, `σ = ±1`) and
//! leaves a linear axis as it is (`u = x`). Then:
//!
//! - the heightfield value `r` (or `p`), the ownership functions of
//!   eqs. 15–16 and the distortion's numerator `r_x² + r_y²` (`r_x = 2a x`,
//!   so `r_x² = 4a² u`) are all affine in `w`: the conics centred at the
//!   origin that bound the low-distortion regions (ellipses, hyperbolas;
//!   parabolas where one axis is linear) become straight lines;
//! - hence the part of a low-distortion region inside one cell (a box on
//!   which the warp is one-to-one) is a convex polygon in `w`, and
//! - `δ² = 1 + N/r` (eq. 13, `N`, `r` affine in `w`, `r > 0`) is a
//!   linear-fractional function of `w`: on any convex set of `w` its
//!   extrema lie at extreme points. On a box this is the paper's corner
//!   property (§3.4); on a triangle of `w` it is its three vertices.
//!
//! Arcs. The preimage of a `w`-segment from `p` to `q` is a conic arc,
//! monotone in `x` and `y` (so inside the box spanned by `p` and `q`) and
//! without inflection. Along the common parameter `t` of the segment and
//! the chord, a quadratic axis deviates from the chord by
//! `√(lerp(x_p², x_q², t)) − lerp(|x_p|, |x_q|, t) ∈ [0, ε]` with
//! `ε = (|x_p| − |x_q|)² / (4(|x_p| + |x_q|))` (the maximum sits where
//! `|x|` is the mean of the ends); a linear axis does not deviate. So the
//! arc stays within `|n̂ₓ|εₓ + |n̂_y|ε_y` of the chord (`n̂` its unit
//! normal): its *sagitta*. A convex arc with chord `ℓ` and sagitta `s` is at
//! most `ℓ + 2s` long (it bounds, with its chord, a convex set inside an
//! `ℓ × s` rectangle).
//!
//! [`Heightfield`]: crate::sampling::heightfield::Heightfield

use glam::DVec2;

use crate::sampling::separable::{Quad1, Separable};

/// Relative size below which a side counts as axis-aligned or through the
/// origin in [`Warp::arc_kind`].
const STRAIGHT_TOLERANCE: f64 = 1e-13;

/// The warp of one cell of a sampling plane (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Warp {
    /// Per axis: `true` for a quadratic axis (`u = x²`), `false` for a
    /// linear one (`u = x`).
    pub square: [bool; 2],
    /// Per quadratic axis, the sign `σ` of the cell's half (`±1`).
    pub sign: DVec2,
}

/// Which conic an arc lies on, by the type of its line in `w`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArcKind {
    /// A straight segment in the plane too.
    Straight,
    /// An ellipse centred at the origin (both axes quadratic, the line in
    /// `w` falling).
    Elliptic,
    /// A hyperbola centred at the origin (both axes quadratic, the line in
    /// `w` rising).
    Hyperbolic,
    /// A parabola (one axis linear).
    Parabolic,
}

/// `(|a| − |b|)² / (4(|a| + |b|))`: the largest gap between `√` of a linear
/// function and its chord, for ends of absolute values `a` and `b`.
#[must_use]
#[inline]
fn bulge(a: f64, b: f64) -> f64 {
    let (a, b) = (a.abs(), b.abs());
    let sum = a + b;
    if sum > 0.0 {
        (a - b) * (a - b) / (4.0 * sum)
    } else {
        0.0
    }
}

impl Warp {
    /// The warp for axes `square` in the half signs `sign`.
    #[must_use]
    pub fn new(square: [bool; 2], sign: DVec2) -> Self {
        Self { square, sign }
    }

    /// `w` of plane point `p`.
    #[must_use]
    #[inline]
    pub fn to_w(&self, p: DVec2) -> DVec2 {
        DVec2::new(
            if self.square[0] { p.x * p.x } else { p.x },
            if self.square[1] { p.y * p.y } else { p.y },
        )
    }

    /// The plane point of `w` (negative `w` of a quadratic axis counts as 0).
    #[must_use]
    #[inline]
    pub fn from_w(&self, w: DVec2) -> DVec2 {
        DVec2::new(
            if self.square[0] {
                self.sign.x * w.x.max(0.0).sqrt()
            } else {
                w.x
            },
            if self.square[1] {
                self.sign.y * w.y.max(0.0).sqrt()
            } else {
                w.y
            },
        )
    }

    /// The image `(lo, hi)` in `w` of the plane box `[lo, hi]`, which must
    /// lie in the warp's cell.
    #[must_use]
    pub fn w_box(&self, lo: DVec2, hi: DVec2) -> (DVec2, DVec2) {
        let (a, b) = (self.to_w(lo), self.to_w(hi));
        (a.min(b), a.max(b))
    }

    /// `(g, c)` with `f(p) = g·w(p) + c`, or `None` when `f` is not affine
    /// in `w` (a quadratic axis with a linear term, or a linear axis with a
    /// square term).
    #[must_use]
    pub fn affine(&self, f: &Separable) -> Option<(DVec2, f64)> {
        let part = |q: &Quad1, square: bool| {
            if square {
                (q.b == 0.0).then_some(q.a)
            } else {
                (q.a == 0.0).then_some(q.b)
            }
        };
        Some((
            DVec2::new(part(&f.x, self.square[0])?, part(&f.y, self.square[1])?),
            f.x.c + f.y.c,
        ))
    }

    /// The kind of the arc above the `w`-segment from `a` to `b`.
    #[must_use]
    pub fn arc_kind(&self, a: DVec2, b: DVec2) -> ArcKind {
        let d = b - a;
        // Axis-aligned up to rounding (a side computed on a cut or on an
        // ownership line of one variable).
        let flat = |i: usize| d[i].abs() <= STRAIGHT_TOLERANCE * (a[i].abs() + b[i].abs());
        if flat(0) || flat(1) {
            return ArcKind::Straight;
        }
        match self.square {
            [false, false] => ArcKind::Straight,
            [true, true] => {
                // Through the origin (`v = m u`, i.e. `|y| = √m |x|`): the
                // line's distance from the origin, `|a × b| / |b − a|`, is
                // negligible against the segment's reach (a cone's apex
                // value is zero only up to rounding).
                let cross = a.perp_dot(b);
                if cross.abs() <= STRAIGHT_TOLERANCE * d.length() * a.length().max(b.length()) {
                    ArcKind::Straight
                } else if d.x * d.y < 0.0 {
                    ArcKind::Elliptic
                } else {
                    ArcKind::Hyperbolic
                }
            }
            _ => ArcKind::Parabolic,
        }
    }

    /// An upper bound of the distance between the arc from plane point `p`
    /// to plane point `q` (above the `w`-segment between them) and its chord.
    #[must_use]
    pub fn sagitta(&self, p: DVec2, q: DVec2) -> f64 {
        let d = q - p;
        let len = d.length();
        if len == 0.0 {
            return 0.0;
        }
        let ex = if self.square[0] { bulge(p.x, q.x) } else { 0.0 };
        let ey = if self.square[1] { bulge(p.y, q.y) } else { 0.0 };
        (d.y.abs() * ex + d.x.abs() * ey) / len
    }

    /// An upper bound of the length of the arc (above a `w`-segment)
    /// between two plane points at most `t` apart, both with `|x| ≥ floor.x`
    /// and `|y| ≥ floor.y`: `t + 2s` with the largest sagitta `s` such
    /// points can have.
    #[must_use]
    pub fn path_length(&self, t: f64, floor: DVec2) -> f64 {
        // `bulge` grows with the difference and shrinks with the sum of its
        // ends: the worst pair is `(floor, floor + t)` on each axis.
        let e = |square: bool, m: f64| {
            if square {
                bulge(m.abs(), m.abs() + t)
            } else {
                0.0
            }
        };
        let s = DVec2::new(e(self.square[0], floor.x), e(self.square[1], floor.y)).length();
        t + 2.0 * s
    }

    /// The largest `h ≤ ρ` whose [`path_length`](Self::path_length) is at
    /// most `ρ` (up to rounding), for the same `floor`.
    #[must_use]
    pub fn step_within(&self, rho: f64, floor: DVec2) -> f64 {
        // `path_length(t)/t` grows with `t`, so scaling `ρ` by its own
        // ratio is on the safe side.
        let ratio = self.path_length(rho, floor) / rho;
        rho / ratio
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc_points(w: &Warp, a: DVec2, b: DVec2, n: u32) -> Vec<DVec2> {
        let (wa, wb) = (w.to_w(a), w.to_w(b));
        (0..=n)
            .map(|i| w.from_w(wa.lerp(wb, f64::from(i) / f64::from(n))))
            .collect()
    }

    #[test]
    fn sagitta_and_length_bound_the_arc() {
        let warps = [
            Warp::new([true, true], DVec2::new(1.0, -1.0)),
            Warp::new([true, false], DVec2::new(-1.0, 1.0)),
        ];
        let pairs = [
            (DVec2::new(1.0, -0.1), DVec2::new(0.2, -1.3)),
            (DVec2::new(0.0, -0.5), DVec2::new(0.9, -0.6)),
            (DVec2::new(0.3, -0.0), DVec2::new(0.31, -2.0)),
        ];
        for w in warps {
            for (a, b) in pairs {
                let (a, b) = (a * DVec2::new(w.sign.x, 1.0), b * DVec2::new(w.sign.x, 1.0));
                let s = w.sagitta(a, b);
                let pts = arc_points(&w, a, b, 400);
                let n = (b - a).perp().normalize();
                let mut length = 0.0;
                for (i, p) in pts.iter().enumerate() {
                    assert!((*p - a).dot(n).abs() <= s * (1.0 + 1e-9) + 1e-12, "{a} {b}");
                    if i > 0 {
                        length += p.distance(pts[i - 1]);
                    }
                }
                let floor = a.abs().min(b.abs());
                assert!(length <= w.path_length(a.distance(b), floor) * (1.0 + 1e-9));
                assert!(length <= a.distance(b) + 2.0 * s + 1e-12);
                let h = w.step_within(0.3, floor);
                assert!(w.path_length(h, floor) <= 0.3 * (1.0 + 1e-12) && h > 0.0);
            }
        }
    }

    #[test]
    fn conics_become_lines() {
        let w = Warp::new([true, true], DVec2::ONE);
        // x²/4 + y² = 1 and x² − y² = 1.
        let ellipse = Separable {
            x: Quad1 {
                a: 0.25,
                b: 0.0,
                c: -1.0,
            },
            y: Quad1 {
                a: 1.0,
                b: 0.0,
                c: 0.0,
            },
        };
        let (g, c) = w.affine(&ellipse).unwrap();
        for t in [0.1, 0.7, 1.3] {
            let p = DVec2::new(2.0 * f64::cos(t), f64::sin(t)).abs();
            assert!((g.dot(w.to_w(p)) + c).abs() < 1e-12);
        }
        let (a, b) = (DVec2::new(2.0, 0.0), DVec2::new(0.0, 1.0));
        assert_eq!(w.arc_kind(w.to_w(a), w.to_w(b)), ArcKind::Elliptic);
        let (a, b) = (DVec2::new(1.0, 0.0), DVec2::new(2.0, 3f64.sqrt()));
        assert_eq!(w.arc_kind(w.to_w(a), w.to_w(b)), ArcKind::Hyperbolic);
        let (a, b) = (DVec2::new(1.0, 2.0), DVec2::new(2.0, 4.0));
        assert_eq!(w.arc_kind(w.to_w(a), w.to_w(b)), ArcKind::Straight);
        let lin = Separable {
            x: Quad1 {
                a: 0.0,
                b: 2.0,
                c: 1.0,
            },
            y: Quad1 {
                a: 3.0,
                b: 0.0,
                c: 0.0,
            },
        };
        assert!(w.affine(&lin).is_none());
        let w2 = Warp::new([false, true], DVec2::ONE);
        assert_eq!(w2.affine(&lin), Some((DVec2::new(2.0, 3.0), 1.0)));
    }
}
