//! Sampling planes and heightfields of a quadric (paper 2, §3.2, §3.4, §4.1).
//!
//! Notation: the principal frame (centre `q`, axes `u₀ u₁ u₂`, eigenvalues
//! `λ`) turns `Q` into the *local form*
//!
//! `Q(q + Σ xₘ uₘ) = Σ λₘ xₘ² + 2 βₘ xₘ + γ`, `βₘ = uₘ·(Aq − b)`, `γ = Q(q)`,
//!
//! with `βₘ = 0` wherever `λₘ ≠ 0`. The sampling plane `P_ij` (axes `i < j`,
//! normal axis `k`) sees the surface as a heightfield over `(x, y) = (xᵢ, xⱼ)`:
//!
//! - `λₖ ≠ 0` (*root* heightfield, eq. 7): `t = ±√r(x, y)` with
//!   `r = −(λᵢx² + 2βᵢx + λⱼy² + 2βⱼy + γ) / λₖ`; for `β = 0` this is
//!   `αₓx² + α_y y² + α_c` of the paper. Two branches, `t ≥ 0` and `t ≤ 0`.
//!   Normal `∝ (r_x/2, r_y/2, −t)`, distortion `δ² = 1 + (r_x² + r_y²)/4r` (eq. 13).
//! - `λₖ = 0, βₖ ≠ 0` (*polynomial* heightfield: paraboloids along their
//!   axis, planes): `t = p(x, y) = −(λᵢx² + 2βᵢx + λⱼy² + 2βⱼy + γ) / 2βₖ`,
//!   one branch, normal `∝ (−p_x, −p_y, 1)`, `δ² = 1 + p_x² + p_y²`.
//! - `λₖ = 0, βₖ = 0` (a cylinder seen along its axis): no heightfield.
//!
//! A point belongs to plane `k`'s low-distortion region (§4.1) when its
//! normal's largest component is `k`: `|nₖ| ≥ |nᵢ|` and `|nₖ| ≥ |nⱼ|`. For a
//! root heightfield these are `r − r_x²/4 ≥ 0` and `r − r_y²/4 ≥ 0` (the
//! conics of eqs. 15–16), for a polynomial one `1 − p_x² ≥ 0` and
//! `1 − p_y² ≥ 0`. Every one of these functions, like `r` and `p`, is
//! *separable*: a quadratic in `x` plus a quadratic in `y`, so its exact
//! range over an axis-aligned box is the sum of two 1D ranges. Per axis each
//! part is either `a x² + c` or `b x + c`, so all of them are affine in the
//! warped coordinates of [`warp`](crate::sampling::warp) (`x²` or `x`),
//! where the ownership conics are lines.

use glam::{DMat3, DVec2, DVec3};

use crate::frame::PrincipalFrame;
use crate::quadric::Quadric;
pub use crate::sampling::separable::{Quad1, Separable};
use crate::sampling::warp::Warp;

/// Relative size below which a local linear coefficient `βₘ` counts as zero.
const BETA_ZERO_RELATIVE: f64 = 1e-11;

/// How a sampling plane's heightfield is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeightKind {
    /// `t = branch · √r(x, y)`, with `branch = ±1`.
    Root {
        /// `true` for the `t ≥ 0` branch.
        positive: bool,
    },
    /// `t = p(x, y)`.
    Polynomial,
}

/// One heightfield of a quadric: a sampling plane, a branch, and the
/// separable functions that describe surface, normal and ownership.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Heightfield {
    /// The quadric's centre `q` (world).
    pub centre: DVec3,
    /// Columns: the plane's `x` axis `uᵢ`, `y` axis `uⱼ`, and normal axis `uₖ`.
    pub axes: DMat3,
    /// Index `k` of the plane's normal axis in the principal frame.
    pub normal_axis: usize,
    /// Root or polynomial, and the branch.
    pub kind: HeightKind,
    /// `r(x, y)` (root) or `p(x, y)` (polynomial).
    pub value: Separable,
    /// `≥ 0` where `|nₖ| ≥ |nᵢ|` (eq. 15).
    pub owns_x: Separable,
    /// `≥ 0` where `|nₖ| ≥ |nⱼ|` (eq. 16).
    pub owns_y: Separable,
    /// Derived once from the fields above (by the constructors, which the
    /// fields must not be changed after): a root heightfield whose value
    /// and ownership functions are all affine in the warped coordinates of
    /// every cell, so that a box on one side of each quadratic axis is in
    /// the corner form of [`distortion_bounds`](Self::distortion_bounds).
    corner_cells: bool,
    /// Derived likewise: the branch of a root heightfield as a factor,
    /// `±1` (`0` for a polynomial one).
    branch: f64,
}

/// The local form of a quadric: its frame with `λ`, `β` and `γ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalForm {
    /// Centre `q`.
    pub centre: DVec3,
    /// Orthonormal axes as columns; within the null space of `A`, the first
    /// null axis carries all of `β`.
    pub axes: DMat3,
    /// `λₘ` (exactly zero for singular axes).
    pub lambda: DVec3,
    /// `βₘ` (zero for non-singular axes).
    pub beta: DVec3,
    /// `γ = Q(q)`.
    pub gamma: f64,
}

impl LocalForm {
    /// The local form of `quadric`.
    #[must_use]
    pub fn new(quadric: &Quadric) -> Self {
        let frame = PrincipalFrame::new(quadric);
        let centre = frame.centre;
        let mut axes = frame.axes;
        let null: Vec<usize> = (0..3).filter(|&m| frame.singular[m]).collect();
        // Align the null space so that the linear part lies along one axis.
        let g = quadric.half_gradient(centre);
        let bn: DVec3 = null.iter().map(|&m| axes.col(m) * axes.col(m).dot(g)).sum();
        if let (true, Some(dir)) = (null.len() >= 2, bn.try_normalize()) {
            let first = dir;
            let second = if null.len() == 2 {
                let fixed = (0..3).find(|m| !frame.singular[*m]).unwrap_or(0);
                axes.col(fixed).cross(first).normalize()
            } else {
                first.any_orthonormal_vector()
            };
            let mut cols = [axes.x_axis, axes.y_axis, axes.z_axis];
            cols[null[0]] = first;
            cols[null[1]] = second;
            if null.len() == 3 {
                cols[null[2]] = first.cross(second);
            }
            axes = DMat3::from_cols(cols[0], cols[1], cols[2]);
        }
        let scale = quadric.max_abs_coefficient() * (1.0 + centre.abs().element_sum());
        let mut lambda = frame.eigenvalues;
        let mut beta = axes.transpose() * g;
        for m in 0..3 {
            if frame.singular[m] {
                lambda[m] = 0.0;
                if beta[m].abs() <= BETA_ZERO_RELATIVE * scale {
                    beta[m] = 0.0;
                }
            } else {
                beta[m] = 0.0;
            }
        }
        Self {
            centre,
            axes,
            lambda,
            beta,
            gamma: quadric.value(centre),
        }
    }

    /// The heightfields of the three sampling planes (up to six: two
    /// branches for root heightfields, none along a cylinder's axis).
    #[must_use]
    pub fn heightfields(&self) -> Vec<Heightfield> {
        let mut out = Vec::with_capacity(6);
        for k in (0..3).rev() {
            let (i, j) = match k {
                0 => (1, 2),
                1 => (0, 2),
                _ => (0, 1),
            };
            let axes = DMat3::from_cols(self.axes.col(i), self.axes.col(j), self.axes.col(k));
            let (li, lj, lk) = (self.lambda[i], self.lambda[j], self.lambda[k]);
            let (bi, bj, bk) = (self.beta[i], self.beta[j], self.beta[k]);
            let base = Heightfield {
                centre: self.centre,
                axes,
                normal_axis: k,
                kind: HeightKind::Polynomial,
                value: zero_separable(),
                owns_x: zero_separable(),
                owns_y: zero_separable(),
                corner_cells: false,
                branch: 0.0,
            };
            if lk != 0.0 {
                // r = ρx(x) + ρy(y) + ρc.
                let s = -1.0 / lk;
                let fx = Quad1 {
                    a: s * li,
                    b: s * 2.0 * bi,
                    c: s * self.gamma,
                };
                let fy = Quad1 {
                    a: s * lj,
                    b: s * 2.0 * bj,
                    c: 0.0,
                };
                let value = Separable { x: fx, y: fy };
                // r − r_x²/4: the x part minus (2a x + b)²/4.
                let minus_slope = |f: Quad1| Quad1 {
                    a: f.a - f.a * f.a,
                    b: f.b - f.a * f.b,
                    c: f.c - f.b * f.b / 4.0,
                };
                let owns_x = Separable {
                    x: minus_slope(fx),
                    y: fy,
                };
                let owns_y = Separable {
                    x: fx,
                    y: minus_slope(fy),
                };
                for positive in [true, false] {
                    out.push(
                        Heightfield {
                            kind: HeightKind::Root { positive },
                            value,
                            owns_x,
                            owns_y,
                            ..base
                        }
                        .with_derived(),
                    );
                }
            } else if bk != 0.0 {
                let s = -1.0 / (2.0 * bk);
                let px = Quad1 {
                    a: s * li,
                    b: s * 2.0 * bi,
                    c: s * self.gamma,
                };
                let py = Quad1 {
                    a: s * lj,
                    b: s * 2.0 * bj,
                    c: 0.0,
                };
                // 1 − (2a x + b)².
                let one_minus_slope = |f: Quad1| Quad1 {
                    a: -4.0 * f.a * f.a,
                    b: -4.0 * f.a * f.b,
                    c: 1.0 - f.b * f.b,
                };
                let zero = Quad1 {
                    a: 0.0,
                    b: 0.0,
                    c: 0.0,
                };
                out.push(
                    Heightfield {
                        kind: HeightKind::Polynomial,
                        value: Separable { x: px, y: py },
                        owns_x: Separable {
                            x: one_minus_slope(px),
                            y: zero,
                        },
                        owns_y: Separable {
                            x: zero,
                            y: one_minus_slope(py),
                        },
                        ..base
                    }
                    .with_derived(),
                );
            }
        }
        out
    }
}

/// The smaller of two numbers that are not NaN (one comparison, no NaN
/// handling: `minsd` on x86).
#[inline]
fn min2(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not NaN.
#[inline]
fn max2(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

fn zero_separable() -> Separable {
    let z = Quad1 {
        a: 0.0,
        b: 0.0,
        c: 0.0,
    };
    Separable { x: z, y: z }
}

impl Heightfield {
    /// The height `t` above `p`, or `None` outside the heightfield's domain (`r < 0`).
    ///
    /// Branch-free apart from the kind (the same for every call on one
    /// heightfield): the square root is taken unconditionally, the domain
    /// test selects, and the branch is a factor `±1`, so that a batch of
    /// calls vectorizes.
    #[must_use]
    #[inline]
    pub fn height(&self, p: DVec2) -> Option<f64> {
        debug_assert!(self.derived_fields_hold());
        let v = self.value.value(p);
        let t = self.branch * v.sqrt();
        match self.kind {
            HeightKind::Polynomial => Some(v),
            HeightKind::Root { .. } => (v >= 0.0).then_some(t),
        }
    }

    /// The world point above `p` (eq. 7), or `None` outside the domain.
    #[must_use]
    #[inline]
    pub fn point(&self, p: DVec2) -> Option<DVec3> {
        let t = self.height(p)?;
        Some(self.centre + self.axes * DVec3::new(p.x, p.y, t))
    }

    /// The plane coordinates `(x, y)` of a world point.
    #[must_use]
    pub fn project(&self, world: DVec3) -> DVec2 {
        let local = self.axes.transpose() * (world - self.centre);
        DVec2::new(local.x, local.y)
    }

    /// The distortion `δ(x, y) = |n| / |nₖ|` (eq. 13); `+∞` on the domain's rim.
    ///
    /// `δ² = 1 + (r_x² + r_y²)/4r` (root) or `1 + p_x² + p_y²`
    /// (polynomial), computed without branches: both arguments and the rim
    /// test are selected, so one division and one square root per call and
    /// a batch of calls vectorizes.
    #[must_use]
    #[inline]
    pub fn distortion(&self, p: DVec2) -> f64 {
        self.distortion_squared(p).sqrt()
    }

    /// `δ²` at `p` (see [`distortion`](Self::distortion)); `+∞` on the
    /// domain's rim.
    #[inline]
    fn distortion_squared(&self, p: DVec2) -> f64 {
        let sx = self.value.x.slope(p.x);
        let sy = self.value.y.slope(p.y);
        let (sx2, sy2) = (sx * sx, sy * sy);
        let r = self.value.value(p);
        let root = matches!(self.kind, HeightKind::Root { .. });
        let d2 = if root {
            1.0 + (sx2 + sy2) / (4.0 * r)
        } else {
            1.0 + sx2 + sy2
        };
        if root && r <= 0.0 { f64::INFINITY } else { d2 }
    }

    /// Bounds `(min, max)` of the distortion over the box `[lo, hi]` (§3.4).
    ///
    /// Polynomial heightfields: exact (both slopes are separable). Root
    /// heightfields, on a box inside one cell of the [`warp`](Self::warp):
    /// the extrema lie at the corners (the paper's property of eq. 13, see
    /// [`warp`](crate::sampling::warp)). Otherwise interval bounds
    /// `δ² ∈ 1 + [N₋/r₊, N₊/r₋]`, `N = (r_x² + r_y²)/4`.
    /// The maximum is `+∞` when the box reaches the domain's rim.
    ///
    /// The common case, a root heightfield on a box of one cell (which
    /// `corner_cells` and two sign tests decide), is the corner form: per
    /// axis the two end values `v` and squared slopes `s`, the range of `r`
    /// from the end values (no vertex is strictly inside such a box), and
    /// for a box inside the domain `δ²` at the four corners,
    /// `1 + (sxᵢ + syⱼ)/4(vxᵢ + vyⱼ)` as [`distortion`](Self::distortion)
    /// computes it (two pairs of divisions), the extremes by comparisons and
    /// one square root for each. Polynomial heightfields take their exact
    /// bound here too; root heightfields on boxes across cells go to
    /// [`distortion_bounds_general`](Self::distortion_bounds_general).
    #[must_use]
    #[inline(always)]
    pub fn distortion_bounds(&self, lo: DVec2, hi: DVec2) -> (f64, f64) {
        debug_assert!(self.derived_fields_hold());
        let one_side = |square: bool, lo: f64, hi: f64| !square | (lo >= 0.0) | (hi <= 0.0);
        let (fx, fy) = (&self.value.x, &self.value.y);
        if matches!(self.kind, HeightKind::Polynomial) {
            // Exact: `δ² = 1 + p_x² + p_y²` is separable (planes and
            // paraboloids along their axis; constant on a plane).
            let (ax0, ax1) = fx.slope_squared_range(lo.x, hi.x);
            let (ay0, ay1) = fy.slope_squared_range(lo.y, hi.y);
            return ((1.0 + ax0 + ay0).sqrt(), (1.0 + ax1 + ay1).sqrt());
        }
        if !(self.corner_cells
            & one_side(fx.a != 0.0, lo.x, hi.x)
            & one_side(fy.a != 0.0, lo.y, hi.y))
        {
            return self.distortion_bounds_general(lo, hi);
        }
        let square = |s: f64| s * s;
        let vx = [fx.value(lo.x), fx.value(hi.x)];
        let vy = [fy.value(lo.y), fy.value(hi.y)];
        let sx = [square(fx.slope(lo.x)), square(fx.slope(hi.x))];
        let sy = [square(fy.slope(lo.y)), square(fy.slope(hi.y))];
        let r0 = min2(vx[0], vx[1]) + min2(vy[0], vy[1]);
        if r0 > 0.0 {
            let d00 = 1.0 + (sx[0] + sy[0]) / (4.0 * (vx[0] + vy[0]));
            let d10 = 1.0 + (sx[1] + sy[0]) / (4.0 * (vx[1] + vy[0]));
            let d01 = 1.0 + (sx[0] + sy[1]) / (4.0 * (vx[0] + vy[1]));
            let d11 = 1.0 + (sx[1] + sy[1]) / (4.0 * (vx[1] + vy[1]));
            let min = min2(min2(d00, d01), min2(d10, d11));
            let max = max2(max2(d00, d01), max2(d10, d11));
            // `√` is monotone: one square root per extreme.
            return (min.sqrt(), max.sqrt());
        }
        let r1 = max2(vx[0], vx[1]) + max2(vy[0], vy[1]);
        if r1 <= 0.0 {
            return (f64::INFINITY, f64::INFINITY);
        }
        // The box reaches the rim: the interval bound of the general path,
        // whose squared-slope ranges are the end values here (a slope keeps
        // its sign across a box of one cell).
        let n = min2(sx[0], sx[1]) + min2(sy[0], sy[1]);
        ((1.0 + n / (4.0 * r1)).sqrt(), f64::INFINITY)
    }

    /// [`distortion_bounds`](Self::distortion_bounds) for polynomial
    /// heightfields, boxes across cells, and boxes that reach the rim:
    /// exact ranges of the separable parts and interval arithmetic.
    #[must_use]
    #[inline(never)]
    pub fn distortion_bounds_general(&self, lo: DVec2, hi: DVec2) -> (f64, f64) {
        let (ax0, ax1) = self.value.x.slope_squared_range(lo.x, hi.x);
        let (ay0, ay1) = self.value.y.slope_squared_range(lo.y, hi.y);
        match self.kind {
            HeightKind::Polynomial => ((1.0 + ax0 + ay0).sqrt(), (1.0 + ax1 + ay1).sqrt()),
            HeightKind::Root { .. } => {
                let (r0, r1) = self.value.range(lo, hi);
                if r1 <= 0.0 {
                    return (f64::INFINITY, f64::INFINITY);
                }
                let min = (1.0 + (ax0 + ay0) / (4.0 * r1)).sqrt();
                let max = if r0 > 0.0 {
                    (1.0 + (ax1 + ay1) / (4.0 * r0)).sqrt()
                } else {
                    f64::INFINITY
                };
                (min, max)
            }
        }
    }

    /// Whether the derived fields agree with the others (they are public,
    /// and must not be changed after construction).
    fn derived_fields_hold(&self) -> bool {
        let derived = self.with_derived();
        derived.corner_cells == self.corner_cells && derived.branch == self.branch
    }

    /// This heightfield with its derived fields set from the others (see
    /// `corner_cells` and `branch`).
    #[must_use]
    fn with_derived(self) -> Self {
        let square = [self.value.x.a != 0.0, self.value.y.a != 0.0];
        let affine = |q: &Quad1, square: bool| if square { q.b == 0.0 } else { q.a == 0.0 };
        let corner_cells = matches!(self.kind, HeightKind::Root { .. })
            && [&self.value, &self.owns_x, &self.owns_y]
                .iter()
                .all(|f| affine(&f.x, square[0]) && affine(&f.y, square[1]));
        let branch = match self.kind {
            HeightKind::Root { positive: true } => 1.0,
            HeightKind::Root { positive: false } => -1.0,
            HeightKind::Polynomial => 0.0,
        };
        Self {
            corner_cells,
            branch,
            ..self
        }
    }

    /// Bounds `(min, max)` of the distortion over a set whose image in the
    /// warped plane is convex with the extreme points `vertices` (a region
    /// of one cell of the [`warp`](Self::warp), e.g. a curved triangle):
    /// the distortion at the vertices, by the linear-fractional form of
    /// eq. 13 in `w`. The maximum is `+∞` when a vertex is on the rim.
    #[must_use]
    pub fn distortion_bounds_at(&self, vertices: &[DVec2]) -> (f64, f64) {
        // `√` is monotone: the extremes of `δ²` (never NaN: `+∞` on the
        // rim), then one root for each.
        let (min, max) = vertices
            .iter()
            .map(|v| self.distortion_squared(*v))
            .fold((f64::INFINITY, 0.0), |(lo, hi), d| {
                (min2(lo, d), max2(hi, d))
            });
        (min.sqrt(), max.sqrt())
    }

    /// The slopes `(|∂t/∂x|, |∂t/∂y|)` at `p`; `+∞` on the domain's rim
    /// and outside the domain.
    #[must_use]
    pub fn slopes(&self, p: DVec2) -> DVec2 {
        let s = DVec2::new(self.value.x.slope(p.x), self.value.y.slope(p.y)).abs();
        match self.kind {
            HeightKind::Polynomial => s,
            HeightKind::Root { .. } => {
                let r = self.value.value(p);
                if r > 0.0 {
                    s / (2.0 * r.sqrt())
                } else {
                    DVec2::INFINITY
                }
            }
        }
    }

    /// The gradient `(∂t/∂x, ∂t/∂y)` at `p`, or `None` on the domain's rim
    /// and outside the domain.
    #[must_use]
    pub fn gradient(&self, p: DVec2) -> Option<DVec2> {
        let g = DVec2::new(self.value.x.slope(p.x), self.value.y.slope(p.y));
        match self.kind {
            HeightKind::Polynomial => Some(g),
            HeightKind::Root { positive } => {
                let r = self.value.value(p);
                (r > 0.0).then(|| g * (if positive { 0.5 } else { -0.5 } / r.sqrt()))
            }
        }
    }

    /// Bounds `(min, max)` of each component of the [`gradient`](Self::gradient)
    /// over the box `[lo, hi]` (interval arithmetic on `r_x / 2√r` for a
    /// root heightfield: `r_x` depends on `x` only, `r` lies in its exact
    /// range), or `None` where the box reaches the domain's rim.
    #[must_use]
    pub fn gradient_bounds(&self, lo: DVec2, hi: DVec2) -> Option<(DVec2, DVec2)> {
        let ends = |q: &Quad1, a: f64, b: f64| {
            let (u, v) = (q.slope(a), q.slope(b));
            (u.min(v), u.max(v))
        };
        let (x0, x1) = ends(&self.value.x, lo.x, hi.x);
        let (y0, y1) = ends(&self.value.y, lo.y, hi.y);
        let (min, max) = (DVec2::new(x0, y0), DVec2::new(x1, y1));
        match self.kind {
            HeightKind::Polynomial => Some((min, max)),
            HeightKind::Root { positive } => {
                let (r0, r1) = self.value.range(lo, hi);
                if r0.is_nan() || r0 <= 0.0 {
                    return None;
                }
                // Divided by the interval [2√r₀, 2√r₁] of positive numbers.
                let (m0, m1) = (2.0 * r0.sqrt(), 2.0 * r1.sqrt());
                let low = (min / m0).min(min / m1);
                let high = (max / m0).max(max / m1);
                Some(if positive { (low, high) } else { (-high, -low) })
            }
        }
    }

    /// Bounds `(Sₓ, S_y)` of the slopes `|∂t/∂x|` and `|∂t/∂y|` over the
    /// box `[lo, hi]`, taken as [`distortion_bounds`](Self::distortion_bounds)
    /// takes `δ₊`: exact for polynomial heightfields; at the corners for a
    /// root heightfield on a box inside one cell of the warp (each squared
    /// slope `r_x²/4r` is linear-fractional in `w` there); else the interval
    /// bound `r_x²/4r ≤ max r_x² / 4 r₋`. `+∞` where the box reaches the
    /// domain's rim.
    #[must_use]
    pub fn slope_bounds(&self, lo: DVec2, hi: DVec2) -> DVec2 {
        let (_, ax) = self.value.x.slope_squared_range(lo.x, hi.x);
        let (_, ay) = self.value.y.slope_squared_range(lo.y, hi.y);
        match self.kind {
            HeightKind::Polynomial => DVec2::new(ax, ay).map(f64::sqrt),
            HeightKind::Root { .. } => {
                let (r0, _) = self.value.range(lo, hi);
                if r0 <= 0.0 {
                    return DVec2::INFINITY;
                }
                if self.warp(lo, hi).is_some() {
                    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
                    return self.slope_bounds_at(&corners);
                }
                (DVec2::new(ax, ay) / (4.0 * r0)).map(f64::sqrt)
            }
        }
    }

    /// Bounds `(Sₓ, S_y)` of the slopes over a set whose image in the
    /// warped plane is convex with the extreme points `vertices` (as for
    /// [`distortion_bounds_at`](Self::distortion_bounds_at)): each squared
    /// slope is affine (polynomial) or linear-fractional (root) in `w`, so
    /// its maximum is at a vertex.
    #[must_use]
    pub fn slope_bounds_at(&self, vertices: &[DVec2]) -> DVec2 {
        vertices
            .iter()
            .map(|v| self.slopes(*v))
            .fold(DVec2::ZERO, DVec2::max)
    }

    /// The warp of the cell containing the box `[lo, hi]` (see
    /// [`warp`](crate::sampling::warp)), or `None` when the box straddles
    /// `0` on a quadratic axis or a separable part is not affine in the
    /// warped coordinates.
    #[must_use]
    pub fn warp(&self, lo: DVec2, hi: DVec2) -> Option<Warp> {
        let square = [self.value.x.a != 0.0, self.value.y.a != 0.0];
        let side = |square: bool, lo: f64, hi: f64| {
            if !square || lo >= 0.0 {
                Some(1.0)
            } else if hi <= 0.0 {
                Some(-1.0)
            } else {
                None
            }
        };
        let sign = DVec2::new(side(square[0], lo.x, hi.x)?, side(square[1], lo.y, hi.y)?);
        let warp = Warp::new(square, sign);
        for f in [&self.value, &self.owns_x, &self.owns_y] {
            warp.affine(f)?;
        }
        Some(warp)
    }

    /// Whether no point of the box `[lo, hi]` is in this plane's
    /// low-distortion region or in the heightfield's domain (exact for boxes).
    #[must_use]
    pub fn box_is_foreign(&self, lo: DVec2, hi: DVec2) -> bool {
        if matches!(self.kind, HeightKind::Root { .. }) && self.value.range(lo, hi).1 < 0.0 {
            return true;
        }
        self.owns_x.range(lo, hi).1 < 0.0 || self.owns_y.range(lo, hi).1 < 0.0
    }

    /// `(foreign, owned)` for the box `[lo, hi]`: whether it is foreign as
    /// for [`box_is_foreign`](Self::box_is_foreign), and whether it lies
    /// wholly in the domain and in this plane's low-distortion region (as
    /// for [`box_is_owned`](Self::box_is_owned)), so that no box inside it
    /// is foreign. One range per function.
    #[must_use]
    pub fn box_ownership(&self, lo: DVec2, hi: DVec2) -> (bool, bool) {
        let root = matches!(self.kind, HeightKind::Root { .. });
        let domain = if root {
            let (v0, v1) = self.value.range(lo, hi);
            if v1 < 0.0 {
                return (true, false);
            }
            v0 >= 0.0
        } else {
            true
        };
        let (x0, x1) = self.owns_x.range(lo, hi);
        let (y0, y1) = self.owns_y.range(lo, hi);
        if x1 < 0.0 || y1 < 0.0 {
            return (true, false);
        }
        (false, domain && x0 >= 0.0 && y0 >= 0.0)
    }

    /// A world ball `(centre, radius)` containing the surface over the box
    /// `[lo, hi]`: the circumscribed ball of the local box spanned by the
    /// plane box and the range of heights over it. `None` where the box has
    /// no surface.
    #[must_use]
    pub fn patch_ball(&self, lo: DVec2, hi: DVec2) -> Option<(DVec3, f64)> {
        let (v0, v1) = self.value.range(lo, hi);
        let (t0, t1) = match self.kind {
            HeightKind::Polynomial => (v0, v1),
            HeightKind::Root { positive } => {
                if v1 < 0.0 {
                    return None;
                }
                let (a, b) = (v0.max(0.0).sqrt(), v1.sqrt());
                if positive { (a, b) } else { (-b, -a) }
            }
        };
        let local_lo = DVec3::new(lo.x, lo.y, t0);
        let local_hi = DVec3::new(hi.x, hi.y, t1);
        let centre = self.centre + self.axes * (0.5 * (local_lo + local_hi));
        Some((centre, 0.5 * local_lo.distance(local_hi)))
    }

    /// Whether the whole box `[lo, hi]` lies in this plane's low-distortion region.
    #[must_use]
    pub fn box_is_owned(&self, lo: DVec2, hi: DVec2) -> bool {
        self.owns_x.range(lo, hi).0 >= 0.0 && self.owns_y.range(lo, hi).0 >= 0.0
    }
}

#[cfg(test)]
mod exactness;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_heightfields_lie_on_the_sphere() {
        let q = Quadric::sphere(DVec3::new(1.0, 2.0, 3.0), 2.0).unwrap();
        let local = LocalForm::new(&q);
        let hfs = local.heightfields();
        assert_eq!(hfs.len(), 6);
        for h in &hfs {
            let p = h.point(DVec2::new(0.5, -0.7)).unwrap();
            assert!(q.value(p).abs() < 1e-12);
            assert!(h.point(DVec2::new(3.0, 0.0)).is_none());
            // At the pole the distortion is 1.
            assert!((h.distortion(DVec2::ZERO) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn paraboloid_and_plane_have_polynomial_heightfields() {
        let para = Quadric::elliptic_paraboloid(DVec2::new(1.0, 2.0)).unwrap();
        let hfs = LocalForm::new(&para).heightfields();
        let poly: Vec<_> = hfs
            .iter()
            .filter(|h| h.kind == HeightKind::Polynomial)
            .collect();
        assert_eq!(poly.len(), 1);
        let p = poly[0].point(DVec2::new(0.3, 0.4)).unwrap();
        assert!(para.value(p).abs() < 1e-12);
        for h in &hfs {
            if let Some(p) = h.point(DVec2::new(0.2, 0.9)) {
                assert!(para.value(p).abs() < 1e-9, "{h:?}");
            }
        }
        let plane = Quadric::half_space(DVec3::new(1.0, 2.0, 2.0), 3.0).unwrap();
        let hfs = LocalForm::new(&plane).heightfields();
        assert_eq!(hfs.len(), 1);
        assert!((hfs[0].distortion(DVec2::new(5.0, 7.0)) - 1.0).abs() < 1e-12);
        let p = hfs[0].point(DVec2::new(5.0, 7.0)).unwrap();
        assert!(plane.value(p).abs() < 1e-9);
    }

    #[test]
    fn cylinder_has_no_axial_heightfield() {
        let q = Quadric::cylinder(DVec3::ZERO, DVec3::Z, 1.0).unwrap();
        assert_eq!(LocalForm::new(&q).heightfields().len(), 4);
    }

    #[test]
    fn corner_distortion_bounds_hold_inside() {
        // Dense check of the corner property for all sign patterns.
        for (ax, ay, ac) in [
            (-1.0, -2.0, 4.0),
            (1.0, -0.5, 1.0),
            (0.5, 2.0, -0.3),
            (-0.3, 1.5, 2.0),
            (2.0, 3.0, 0.5),
        ] {
            let f = |a: f64, c: f64| Quad1 { a, b: 0.0, c };
            let h = Heightfield {
                centre: DVec3::ZERO,
                axes: DMat3::IDENTITY,
                normal_axis: 2,
                kind: HeightKind::Root { positive: true },
                value: Separable {
                    x: f(ax, ac),
                    y: f(ay, 0.0),
                },
                owns_x: zero_separable(),
                owns_y: zero_separable(),
                corner_cells: false,
                branch: 0.0,
            }
            .with_derived();
            for (lo, hi) in [
                (DVec2::new(0.1, 0.2), DVec2::new(0.9, 0.6)),
                (DVec2::new(0.0, 0.0), DVec2::new(0.5, 0.5)),
                (DVec2::new(0.7, 0.1), DVec2::new(1.3, 1.1)),
            ] {
                if h.value.range(lo, hi).0 <= 0.0 {
                    continue;
                }
                let (min, max) = h.distortion_bounds(lo, hi);
                for s in 0..=20 {
                    for t in 0..=20 {
                        let p = lo + (hi - lo) * DVec2::new(f64::from(s), f64::from(t)) / 20.0;
                        let d = h.distortion(p);
                        assert!(d <= max * (1.0 + 1e-12) && d >= min * (1.0 - 1e-12));
                    }
                }
            }
        }
    }
}
