//! Line–quadric intersection, numerically stable (paper 2, §3.1, eqs. 5–6).
//!
//! Notation: the line `x(t) = o + t·v` (`v` need not be unit). Substituting
//! into `Q` gives the quadratic
//!
//! `Q(o + t v) = a t² + 2 β t + γ`,  `a = vᵀAv`, `β = vᵀ(Ao − b)`, `γ = Q(o)`.
//!
//! Roots use the cancellation-free pair `s = −(β + sign(β)·√(β² − aγ))`,
//! `t₁ = s / a`, `t₂ = γ / s`, so the near root stays accurate when `a → 0`
//! (a ray almost parallel to a cylinder's axis or a cone's asymptote); for
//! `a = 0` (relative to the size of its terms) the equation is linear, eq. 6:
//! `t = −γ / 2β`. If `a`, `β` and `γ` all vanish the line lies in the surface
//! (a ruling of a cylinder, cone, hyperboloid or a plane).
//!
//! The result is the set of `t` where the line is *inside* (`Q < 0`): at most
//! two spans, each from an entry to an exit parameter, either possibly
//! infinite.

use glam::DVec3;

use crate::error::{Error, Result};
use crate::quadric::Quadric;

/// Relative size below which `β` and `γ` count as zero (deciding whether a
/// line with `a = 0` lies in the surface).
pub const ZERO_RELATIVE: f64 = 1e-13;

/// Relative size below which `a` counts as zero: the rounding noise of
/// `vᵀAv`. Above it the quadratic is solved as such (its far root may be
/// huge); below it `a` is not resolvable and the equation is taken as linear.
pub const A_ZERO_RELATIVE: f64 = 64.0 * f64::EPSILON;

/// A ray or line `origin + t·direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// The point at `t = 0`.
    pub origin: DVec3,
    /// The direction (not necessarily unit; `t` is measured in its length).
    pub direction: DVec3,
}

impl Ray {
    /// A ray from finite `origin` along finite, non-zero `direction`.
    ///
    /// Errors: [`Error::NonFinite`], [`Error::ZeroDirection`].
    pub fn new(origin: DVec3, direction: DVec3) -> Result<Self> {
        if !origin.is_finite() || !direction.is_finite() {
            return Err(Error::NonFinite { what: "ray" });
        }
        if direction == DVec3::ZERO {
            return Err(Error::ZeroDirection {
                what: "ray direction",
            });
        }
        Ok(Self { origin, direction })
    }

    /// The point at parameter `t`.
    #[must_use]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.direction
    }
}

/// A parameter interval `(entry, exit)` where the line is inside the quadric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// Where the line enters (`−∞` if it starts inside).
    pub entry: f64,
    /// Where the line leaves (`+∞` if it never does); `entry ≤ exit`.
    pub exit: f64,
}

/// A surface crossing along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The ray parameter of the crossing.
    pub t: f64,
    /// `true` when the ray enters the inside here, `false` when it leaves.
    pub entering: bool,
}

/// Where a line is inside a quadric: up to two sorted, disjoint spans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineHits {
    spans: [Span; 2],
    count: u8,
    in_surface: bool,
}

impl LineHits {
    const NONE: Self = Self {
        spans: [Span {
            entry: 0.0,
            exit: 0.0,
        }; 2],
        count: 0,
        in_surface: false,
    };

    fn one(entry: f64, exit: f64) -> Self {
        let mut h = Self::NONE;
        h.spans[0] = Span { entry, exit };
        h.count = 1;
        h
    }

    fn two(first: Span, second: Span) -> Self {
        Self {
            spans: [first, second],
            count: 2,
            in_surface: false,
        }
    }

    /// The spans where the line is inside, sorted by parameter.
    ///
    /// A tangent line gives one span of zero length at the touching point.
    #[must_use]
    pub fn spans(&self) -> &[Span] {
        &self.spans[..usize::from(self.count)]
    }

    /// `true` when the whole line lies in the surface (`Q ≡ 0` along it),
    /// e.g. a ray along a ruling of a cylinder, cone or hyperboloid.
    #[must_use]
    pub fn lies_in_surface(&self) -> bool {
        self.in_surface
    }

    /// The finite crossing parameters in ascending order, each with its direction.
    #[must_use]
    pub fn hits(&self) -> Vec<Hit> {
        let mut out = Vec::with_capacity(4);
        for s in self.spans() {
            if s.entry.is_finite() {
                out.push(Hit {
                    t: s.entry,
                    entering: true,
                });
            }
            if s.exit.is_finite() {
                out.push(Hit {
                    t: s.exit,
                    entering: false,
                });
            }
        }
        out
    }

    /// The first crossing with `t > t_min`, if any.
    #[must_use]
    pub fn first_hit_after(&self, t_min: f64) -> Option<Hit> {
        self.hits().into_iter().find(|h| h.t > t_min)
    }

    /// Whether parameter `t` lies inside one of the spans (open intervals).
    #[must_use]
    pub fn contains(&self, t: f64) -> bool {
        self.spans().iter().any(|s| s.entry < t && t < s.exit)
    }
}

/// The coefficients of `Q(o + t v) = a t² + 2 β t + γ`, with the magnitudes
/// of the terms that produced them (to decide what is zero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineQuadratic {
    /// `a = vᵀAv`.
    pub a: f64,
    /// `β = vᵀ(Ao − b)`.
    pub beta: f64,
    /// `γ = Q(o)`.
    pub gamma: f64,
    scale_a: f64,
    scale_beta: f64,
    scale_gamma: f64,
}

impl LineQuadratic {
    /// The restriction of `quadric` to the line of `ray`.
    #[must_use]
    pub fn new(quadric: &Quadric, ray: &Ray) -> Self {
        let (o, v) = (ray.origin, ray.direction);
        let a_mat = quadric.a();
        let k = quadric.max_abs_coefficient();
        let (lo, lv) = (o.abs().element_sum(), v.abs().element_sum());
        Self {
            a: v.dot(a_mat * v),
            beta: v.dot(quadric.half_gradient(o)),
            gamma: quadric.value(o),
            scale_a: k * lv * lv,
            scale_beta: k * lv * (lo + 1.0),
            scale_gamma: k * (lo + 1.0) * (lo + 1.0),
        }
    }

    /// The value at parameter `t`.
    #[must_use]
    pub fn value(&self, t: f64) -> f64 {
        (self.a * t + 2.0 * self.beta) * t + self.gamma
    }

    /// Solves for the inside spans.
    #[must_use]
    pub fn solve(&self) -> LineHits {
        let a_zero = self.a.abs() <= A_ZERO_RELATIVE * self.scale_a;
        if a_zero {
            return self.solve_linear();
        }
        let (a, beta, gamma) = (self.a, self.beta, self.gamma);
        let disc = beta * beta - a * gamma;
        if disc < 0.0 {
            return if a > 0.0 {
                LineHits::NONE
            } else {
                LineHits::one(f64::NEG_INFINITY, f64::INFINITY)
            };
        }
        let s = -(beta + disc.sqrt().copysign(beta));
        let (t1, t2) = if s == 0.0 {
            // β = 0 and aγ = 0 with a ≠ 0: double root at 0.
            (0.0, 0.0)
        } else {
            let (p, q) = (s / a, gamma / s);
            if p <= q { (p, q) } else { (q, p) }
        };
        if a > 0.0 {
            LineHits::one(t1, t2)
        } else {
            LineHits::two(
                Span {
                    entry: f64::NEG_INFINITY,
                    exit: t1,
                },
                Span {
                    entry: t2,
                    exit: f64::INFINITY,
                },
            )
        }
    }

    fn solve_linear(&self) -> LineHits {
        let beta_zero = self.beta.abs() <= ZERO_RELATIVE * self.scale_beta;
        if beta_zero {
            let gamma_zero = self.gamma.abs() <= ZERO_RELATIVE * self.scale_gamma;
            return if gamma_zero {
                LineHits {
                    in_surface: true,
                    ..LineHits::NONE
                }
            } else if self.gamma < 0.0 {
                LineHits::one(f64::NEG_INFINITY, f64::INFINITY)
            } else {
                LineHits::NONE
            };
        }
        let t = -self.gamma / (2.0 * self.beta);
        if self.beta > 0.0 {
            LineHits::one(f64::NEG_INFINITY, t)
        } else {
            LineHits::one(t, f64::INFINITY)
        }
    }
}

impl Quadric {
    /// Where the line of `ray` is inside this quadric, over all `t ∈ ℝ`.
    ///
    /// Handles a vanishing leading coefficient (eq. 6) and lines lying in the
    /// surface ([`LineHits::lies_in_surface`]).
    #[must_use]
    pub fn intersect_line(&self, ray: &Ray) -> LineHits {
        LineQuadratic::new(self, ray).solve()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_two_crossings() {
        let q = Quadric::sphere(DVec3::ZERO, 1.0).unwrap();
        let r = Ray::new(DVec3::new(-3.0, 0.0, 0.0), DVec3::X).unwrap();
        let h = q.intersect_line(&r);
        assert_eq!(h.spans().len(), 1);
        let s = h.spans()[0];
        assert!((s.entry - 2.0).abs() < 1e-15 && (s.exit - 4.0).abs() < 1e-15);
        assert_eq!(h.first_hit_after(2.5).map(|h| h.entering), Some(false));
    }

    #[test]
    fn plane_is_linear() {
        let q = Quadric::half_space(DVec3::Z, 1.0).unwrap();
        let r = Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z).unwrap();
        let h = q.intersect_line(&r);
        assert_eq!(
            h.spans(),
            &[Span {
                entry: 4.0,
                exit: f64::INFINITY
            }]
        );
    }

    #[test]
    fn cylinder_axis_ray_is_all_inside_or_in_surface() {
        let q = Quadric::cylinder(DVec3::ZERO, DVec3::Z, 1.0).unwrap();
        let inside = q.intersect_line(&Ray::new(DVec3::ZERO, DVec3::Z).unwrap());
        assert_eq!(inside.spans()[0].entry, f64::NEG_INFINITY);
        let ruling = q.intersect_line(&Ray::new(DVec3::X, DVec3::Z).unwrap());
        assert!(ruling.lies_in_surface());
        assert!(ruling.spans().is_empty());
        let outside = q.intersect_line(&Ray::new(DVec3::X * 2.0, DVec3::Z).unwrap());
        assert!(outside.spans().is_empty() && !outside.lies_in_surface());
    }

    #[test]
    fn hyperboloid_ruling() {
        // x² + y² − z² = 1 contains the line (1, t, t).
        let q = Quadric::hyperboloid_one_sheet(DVec3::ONE).unwrap();
        let r = Ray::new(DVec3::X, DVec3::new(0.0, 1.0, 1.0)).unwrap();
        assert!(q.intersect_line(&r).lies_in_surface());
    }

    #[test]
    fn ray_errors() {
        assert!(Ray::new(DVec3::ZERO, DVec3::ZERO).is_err());
        assert!(Ray::new(DVec3::splat(f64::NAN), DVec3::X).is_err());
    }
}
