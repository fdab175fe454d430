//! Splat data for the renderer (paper 2, §6, §6.1).
//!
//! Notation: a sample `s` on literal `L_ab` (quadric `Q_ab`) with radius `r`.
//!
//! - Quadric buffer: one entry per quadric of the normal form, the ten
//!   packed coefficients and a colour.
//! - Clip list of `s`: the literals `L_aj`, `j ≠ b`, of its own product whose
//!   surface may come within `r` of `s`, i.e. `|d(Q_aj, s)| < r` (eq. 12).
//!   A fragment at `p` is kept only if every listed literal holds at `p`.
//!   Entries are literal references ([`literal_reference`]: the quadric
//!   index, with [`OUTSIDE_FLAG`] set for a literal `Q ≥ 0`). Lists are
//!   sorted and stored once each in a shared clip-index buffer
//!   (deduplicated).
//! - Surface-aligned box: tangent half-extent `r`, normal half-extent
//!   `r · (max δ − min δ)` over the plane box `(x ± r, y ± r)` (eq. 23),
//!   capped at `r` (the splat's patch always lies within its sphere).
//!   Tightened to the sample's own cell ([`cell_box`]): a splat need only
//!   bound the surface it is there to cover, the lifted plane box
//!   `uv ± h` ([`Sample::cell`](crate::Sample::cell)), not its whole
//!   sphere; boxes of a grid fill then overlap their neighbours by the
//!   cells' stretch only, not by the disc around each cell.
//! - Term buffer ([`encode_normal_form`]): the whole normal form for the
//!   global ray-tracing pass, `(start, count)` per product, then the literal
//!   references of every product.
//!
//! These are the plain records of everything the renderer reads; the
//! plugin's GPU structs (`bevy_chisel::splat::gpu`) convert from them, and
//! the shaders (`shaders/quadric_common.wgsl`) repeat the two flag constants.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use crate::csg::{Color, CsgDag, Dnf, Literal, Side, SurfaceMaterial};
use crate::distance::QuadricDistance;
use crate::sampling::heightfield::Heightfield;
use crate::sampling::{Sample, SampleSet};
use crate::scene::DEFAULT_COLOR;

/// Set in a literal reference when the solid lies where `Q ≥ 0` (the
/// literal is the complement): clipping keeps `Q ≥ 0`, the outward normal is `−∇Q`.
pub const OUTSIDE_FLAG: u32 = 1 << 31;

/// The quadric index bits of a literal reference: `reference & INDEX_MASK`
/// indexes [`SplatSet::quadrics`].
pub const INDEX_MASK: u32 = !OUTSIDE_FLAG;

/// One splat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// The sample position (on the CSG surface).
    pub position: DVec3,
    /// The solid's outward unit normal at the sample.
    pub normal: DVec3,
    /// Radius to cover (`≤` the sampling radius; reduced where regions were small, §6.1).
    pub radius: f64,
    /// Half-extent of the surface-aligned box along the normal (eq. 23,
    /// tightened to the cell by [`cell_box`]).
    pub normal_extent: f64,
    /// The box's first tangent axis (unit, orthogonal to `normal`); the
    /// second is `normal × tangent`.
    pub tangent: DVec3,
    /// Half-extents of the box along `tangent` and `normal × tangent`,
    /// each at most `radius`.
    pub tangent_extent: DVec2,
    /// The literal the splat lies on ([`literal_reference`]): quadric
    /// index, with [`OUTSIDE_FLAG`] for a complemented literal.
    pub quadric: u32,
    /// Start of the clip list in [`SplatSet::clip_indices`].
    pub clip_start: u32,
    /// Length of the clip list.
    pub clip_count: u32,
}

/// One entry of the quadric buffer: a quadric of the normal form and the
/// colour and surface parameters of the primitive it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColoredQuadric {
    /// Packed coefficients `[q00, q01, q02, q03, q11, q12, q13, q22, q23, q33]`.
    pub coefficients: [f64; 10],
    /// Linear RGB colour of the source primitive.
    pub color: Color,
    /// Metallic and roughness of the source primitive, where it sets them.
    pub material: SurfaceMaterial,
}

/// Splats with their quadric and clip-index buffers.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatSet {
    /// One splat per sample, in sample order.
    pub splats: Vec<Splat>,
    /// The deduplicated clip lists, concatenated.
    pub clip_indices: Vec<u32>,
    /// One record per quadric of the normal form.
    pub quadrics: Vec<ColoredQuadric>,
}

impl SplatSet {
    /// Builds splats for `samples` of `dnf`, colours taken from the primitives of `dag`.
    #[must_use]
    pub fn new(dnf: &Dnf, dag: &CsgDag, samples: &SampleSet) -> Self {
        let distances: Vec<QuadricDistance> = dnf
            .quadrics()
            .iter()
            .map(|q| QuadricDistance::new(&q.quadric))
            .collect();
        let quadrics = dnf
            .quadrics()
            .iter()
            .map(|q| {
                let primitive = dag.primitives().get(q.primitive);
                ColoredQuadric {
                    coefficients: q.quadric.coefficients(),
                    color: primitive.map_or(DEFAULT_COLOR, |p| p.color),
                    material: primitive.map(|p| p.material).unwrap_or_default(),
                }
            })
            .collect();
        let mut lists: HashMap<Vec<u32>, u32> = HashMap::new();
        let mut clip_indices = Vec::new();
        let mut splats = Vec::with_capacity(samples.samples.len());
        let mut list = Vec::new();
        for s in &samples.samples {
            let patch = samples.patch_of(s);
            let product = &dnf.products()[patch.product as usize];
            let r = f64::from(s.radius);
            let (position, normal, uv) = (
                s.position.as_dvec3(),
                samples.normal_of(dnf, s),
                samples.uv_of(s),
            );
            list.clear();
            for (j, l) in product.iter().enumerate() {
                if j == patch.literal as usize {
                    continue;
                }
                if distances[l.quadric].distance(position).abs() < r {
                    list.push(literal_reference(*l));
                }
            }
            list.sort_unstable();
            let count = len_u32(list.len());
            let start = if list.is_empty() {
                0
            } else if let Some(&start) = lists.get(&list) {
                start
            } else {
                let start = len_u32(clip_indices.len());
                clip_indices.extend_from_slice(&list);
                lists.insert(list.clone(), start);
                start
            };
            let own = product[patch.literal as usize];
            let hf = &patch.heightfield;
            let (dmin, dmax) = hf.distortion_bounds(uv - DVec2::splat(r), uv + DVec2::splat(r));
            let cell = cell_box(hf, s, normal).unwrap_or_else(|| {
                let extent = r * (dmax - dmin);
                CellBox {
                    normal_extent: if extent.is_finite() { extent.min(r) } else { r },
                    ..CellBox::sphere(normal, r)
                }
            });
            splats.push(Splat {
                position,
                normal,
                radius: r,
                normal_extent: cell.normal_extent,
                tangent: cell.tangent,
                tangent_extent: cell.tangent_extent,
                quadric: literal_reference(own),
                clip_start: start,
                clip_count: count,
            });
        }
        Self {
            splats,
            clip_indices,
            quadrics,
        }
    }

    /// Whether the fragment point `p` of `splat` survives its local clipping
    /// (§6, step 3): every literal of its clip list holds at `p`.
    #[must_use]
    pub fn keeps(&self, splat: &Splat, p: DVec3) -> bool {
        let start = splat.clip_start as usize;
        self.clip_indices[start..start + splat.clip_count as usize]
            .iter()
            .all(|&c| {
                let k = self.quadrics[(c & INDEX_MASK) as usize].coefficients;
                let v = crate::Quadric::from_coefficients(k).map_or(0.0, |q| q.value(p));
                if c & OUTSIDE_FLAG == 0 {
                    v <= 0.0
                } else {
                    v >= 0.0
                }
            })
    }
}

impl Splat {
    /// Whether `p` lies in the splat's box (its centre the position, axes
    /// `tangent`, `normal × tangent` and `normal`), every half-extent
    /// widened by the factor `tolerance`. A splat without a normal (a
    /// singular point) has the box of its whole sphere.
    #[must_use]
    pub fn box_holds(&self, p: DVec3, tolerance: f64) -> bool {
        let d = p - self.position;
        if self.normal.length_squared() < 0.25 {
            return d.abs().max_element() <= self.radius * tolerance;
        }
        let t2 = self.normal.cross(self.tangent);
        d.dot(self.tangent).abs() <= self.tangent_extent.x * tolerance
            && d.dot(t2).abs() <= self.tangent_extent.y * tolerance
            && d.dot(self.normal).abs() <= self.normal_extent * tolerance
    }
}

impl ColoredQuadric {
    /// The coefficients as the renderer reads them: scaled to a largest
    /// magnitude of 1 (the surface and the sign of `Q` are unchanged), as
    /// `f32`, in the packed order of [`coefficients`](Self::coefficients).
    #[must_use]
    // f64 → f32 is the point of this conversion.
    #[allow(clippy::cast_possible_truncation)]
    pub fn scaled_coefficients(&self) -> [f32; 10] {
        let scale = self
            .coefficients
            .iter()
            .fold(0.0_f64, |s, c| s.max(c.abs()));
        let inv = if scale > 0.0 { 1.0 / scale } else { 1.0 };
        self.coefficients.map(|c| (c * inv) as f32)
    }
}

/// A splat's box bound from its cell: axes and half-extents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellBox {
    /// First tangent axis (unit, orthogonal to the normal).
    pub tangent: DVec3,
    /// Half-extents along `tangent` and `normal × tangent`.
    pub tangent_extent: DVec2,
    /// Half-extent along the normal.
    pub normal_extent: f64,
}

impl CellBox {
    /// The box of the whole sphere of radius `r` around a sample with
    /// `normal`: tangent half-extents `r` in the frame the renderer builds
    /// for a zero or unknown tangent (`shaders/splat.wgsl`).
    #[must_use]
    pub fn sphere(normal: DVec3, r: f64) -> Self {
        let helper = if normal.x.abs() > 0.9 {
            DVec3::Y
        } else {
            DVec3::X
        };
        Self {
            tangent: helper.cross(normal).try_normalize().unwrap_or(DVec3::X),
            tangent_extent: DVec2::splat(r),
            normal_extent: r,
        }
    }
}

/// Steps of the bound on `ε` in [`cell_box`].
const CELL_BOX_STEPS: u32 = 4;

/// Relative widening of a [`cell_box`] against the `f64` rounding of its
/// bounds (the sample's own offset from the lifted plane point is added
/// exactly).
const CELL_BOX_MARGIN: f64 = 1e-9;

/// The box around sample `s` of heightfield `hf` with outward unit normal
/// `normal` ([`SampleSet::normal_of`](crate::SampleSet::normal_of)) that
/// holds the surface over its cell, within its radius; `None` where the cell or the gradient
/// is unbounded (then the sphere's box, [`CellBox::sphere`]).
///
/// Notation: `X, Y, Z` the heightfield's plane axes and normal axis, `t`
/// its height, `g = ∇t` at the sample's plane point `uv`, `h` the cell's
/// half size (at most `r`: a covered point is within `r` of the sample,
/// and the plane is nearer). A plane offset `Δ` with `|Δᵢ| ≤ hᵢ` lifts to
/// `Δp = Δₓ A₁ + Δ_y A₂ + ε Z` exactly, with the tangents `A₁ = X + gₓZ`,
/// `A₂ = Y + g_yZ` and `ε = t(uv + Δ) − t(uv) − g·Δ`. By the mean value
/// theorem, `ε = ∫₀¹ (∇t(uv + sΔ) − g)·Δ ds`; for `s` in
/// `[(k − 1)/K, k/K]` the point lies in the box `uv ± (k/K) h`, so
/// `|ε| ≤ (1/K) Σₖ Σᵢ hᵢ max|∇ᵢt − gᵢ|` over those boxes
/// ([`Heightfield::gradient_bounds`], `K` = `CELL_BOX_STEPS`: about
/// `5/8` of the one-box bound where `∇t` varies linearly). Along any unit `d`,
/// `|d·Δp| ≤ hₓ|d·A₁| + h_y|d·A₂| + |ε||d·Z|`: the box's half-extents
/// along `t₁ ∝ A₁ − (A₁·n)n`, `t₂ = n × t₁` and `n` (each capped at `r`),
/// plus `|p − P(uv)|`, the offset of the box's centre, the sample's stored
/// position `p`, from the surface point `P(uv)` the offsets `Δp` start at
/// (the sample was polished onto the quadric and rounded to `f32`).
///
/// [`Heightfield::gradient_bounds`]: crate::sampling::heightfield::Heightfield::gradient_bounds
#[must_use]
pub fn cell_box(hf: &Heightfield, s: &Sample, normal: DVec3) -> Option<CellBox> {
    let r = f64::from(s.radius);
    let n = normal;
    if n.length_squared().is_nan() || n.length_squared() <= 0.25 || !s.cell.is_finite() {
        return None;
    }
    let position = s.position.as_dvec3();
    let uv = hf.project(position);
    let half = s.cell.as_dvec2().min(DVec2::splat(r));
    let g = hf.gradient(uv)?;
    let offset = position.distance(hf.point(uv)?);
    let mut eps = 0.0;
    for k in 1..=CELL_BOX_STEPS {
        let part = f64::from(k) / f64::from(CELL_BOX_STEPS);
        let (low, high) = hf.gradient_bounds(uv - part * half, uv + part * half)?;
        eps += (high - g).max(g - low).dot(half) / f64::from(CELL_BOX_STEPS);
    }
    let (x, y, z) = (hf.axes.x_axis, hf.axes.y_axis, hf.axes.z_axis);
    let (a1, a2) = (x + g.x * z, y + g.y * z);
    let t1 = (a1 - a1.dot(n) * n).try_normalize()?;
    let t2 = n.cross(t1);
    let margin = CELL_BOX_MARGIN * (r + position.length()) + offset;
    let extent = |d: DVec3| {
        let e = half.x * d.dot(a1).abs() + half.y * d.dot(a2).abs() + eps * d.dot(z).abs();
        (e * (1.0 + CELL_BOX_MARGIN) + margin).min(r)
    };
    let b = CellBox {
        tangent: t1,
        tangent_extent: DVec2::new(extent(t1), extent(t2)),
        normal_extent: extent(n),
    };
    (b.tangent_extent.is_finite() && b.normal_extent.is_finite()).then_some(b)
}

/// How the renderer refers to a literal: its quadric index, with
/// [`OUTSIDE_FLAG`] set when the solid lies where `Q ≥ 0`.
#[must_use]
pub fn literal_reference(literal: Literal) -> u32 {
    let q = len_u32(literal.quadric);
    match literal.side {
        Side::Inside => q,
        Side::Outside => q | OUTSIDE_FLAG,
    }
}

/// The normal form `dnf` as the term buffer of the global ray-tracing pass:
/// for each product `a`, entries `2a` and `2a + 1` hold the start (an index
/// into this same buffer) and the length of its literal list; the lists
/// follow, one [`literal_reference`] per literal, in product order.
#[must_use]
pub fn encode_normal_form(dnf: &Dnf) -> Vec<u32> {
    let products = dnf.products();
    let header = 2 * products.len();
    let literal_count: usize = products.iter().map(Vec::len).sum();
    let mut terms = Vec::with_capacity(header + literal_count);
    let mut start = header;
    for product in products {
        terms.push(len_u32(start));
        terms.push(len_u32(product.len()));
        start += product.len();
    }
    terms.extend(products.iter().flatten().map(|&l| literal_reference(l)));
    terms
}

/// Buffer lengths and indices fit in `u32` for any splat set a GPU can hold.
fn len_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::Quadric;

    /// A cube with a ball taken out, united with a second ball: two
    /// products, one of them with a complemented literal.
    fn two_products() -> Dnf {
        let mut dag = CsgDag::new();
        let cube = dag
            .cuboid(DVec3::ZERO, DVec3::ONE, [0.8, 0.6, 0.3])
            .unwrap();
        let bite = Quadric::sphere(DVec3::ONE, 0.5).unwrap();
        let bite = dag.primitive(bite, [0.3, 0.5, 0.9]);
        let bitten = dag.difference(cube, &[bite]).unwrap();
        let ball = Quadric::sphere(DVec3::splat(3.0), 1.0).unwrap();
        let ball = dag.primitive(ball, [0.9, 0.9, 0.9]);
        let root = dag.union(&[bitten, ball]).unwrap();
        Dnf::from_dag(&dag, root).unwrap()
    }

    #[test]
    fn normal_form_encodes_every_product_in_order() {
        let dnf = two_products();
        let terms = encode_normal_form(&dnf);
        let products = dnf.products();
        assert_eq!(products.len(), 2);
        for (a, product) in products.iter().enumerate() {
            let start = terms[2 * a] as usize;
            let count = terms[2 * a + 1] as usize;
            assert_eq!(count, product.len());
            for (&reference, literal) in terms[start..start + count].iter().zip(product) {
                assert_eq!((reference & INDEX_MASK) as usize, literal.quadric);
                let outside = reference & OUTSIDE_FLAG != 0;
                assert_eq!(outside, literal.side == Side::Outside);
            }
        }
        let literals: usize = products.iter().map(Vec::len).sum();
        assert_eq!(terms.len(), 2 * products.len() + literals);
        assert!(terms.iter().any(|&t| t & OUTSIDE_FLAG != 0));
    }

    #[test]
    fn scaled_coefficients_keep_the_sign_with_a_unit_maximum() {
        let dnf = two_products();
        for q in dnf.quadrics() {
            let record = ColoredQuadric {
                coefficients: q.quadric.coefficients(),
                color: DEFAULT_COLOR,
                material: SurfaceMaterial::default(),
            };
            let scaled = record.scaled_coefficients();
            let largest = scaled.iter().fold(0.0_f32, |m, c| m.max(c.abs()));
            assert!((largest - 1.0).abs() < 1e-6);
            for (s, c) in scaled.iter().zip(record.coefficients) {
                assert_eq!(s.signum(), c.signum() as f32);
            }
        }
    }
}
