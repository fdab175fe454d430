//! Splat data for the renderer (paper 2, §6, §6.1).
//!
//! Notation: a sample `s` on literal `L_ab` (quadric `Q_ab`) with radius `r`.
//!
//! - Quadric buffer: one entry per quadric of the normal form, the ten
//!   packed coefficients and a colour.
//! - Clip list of `s`: the literals `L_aj`, `j ≠ b`, of its own product whose
//!   surface may come within `r` of `s`, i.e. `|d(Q_aj, s)| < r` (eq. 12).
//!   A fragment at `p` is kept only if every listed literal holds at `p`.
//!   Entries are quadric indices, with [`OUTSIDE_FLAG`] set for a literal
//!   `Q ≥ 0`. Lists are sorted and stored once each in a shared
//!   clip-index buffer (deduplicated).
//! - Surface-aligned box: tangent half-extent `r`, normal half-extent
//!   `r · (max δ − min δ)` over the plane box `(x ± r, y ± r)` (eq. 23),
//!   capped at `r` (the splat's patch always lies within its sphere).

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use crate::csg::{Color, CsgDag, Dnf, Side};
use crate::distance::QuadricDistance;
use crate::sampling::SampleSet;
use crate::scene::DEFAULT_COLOR;

/// Set in a quadric reference when the solid lies where `Q ≥ 0` (the
/// literal is the complement): clipping keeps `Q ≥ 0`, the outward normal is `−∇Q`.
pub const OUTSIDE_FLAG: u32 = 1 << 31;

/// One splat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// The sample position (on the CSG surface).
    pub position: DVec3,
    /// The solid's outward unit normal at the sample.
    pub normal: DVec3,
    /// Radius to cover (`≤` the sampling radius; reduced where regions were small, §6.1).
    pub radius: f64,
    /// Half-extent of the surface-aligned box along the normal (eq. 23).
    pub normal_extent: f64,
    /// Quadric index, with [`OUTSIDE_FLAG`] for a complemented literal.
    pub quadric: u32,
    /// Start of the clip list in [`SplatSet::clip_indices`].
    pub clip_start: u32,
    /// Length of the clip list.
    pub clip_count: u32,
}

/// One entry of the quadric buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadricRecord {
    /// Packed coefficients `[q00, q01, q02, q03, q11, q12, q13, q22, q23, q33]`.
    pub coefficients: [f64; 10],
    /// Linear RGB colour of the source primitive.
    pub color: Color,
}

/// Splats with their quadric and clip-index buffers.
#[derive(Clone, Debug, PartialEq)]
pub struct SplatSet {
    /// One splat per sample, in sample order.
    pub splats: Vec<Splat>,
    /// The deduplicated clip lists, concatenated.
    pub clip_indices: Vec<u32>,
    /// One record per quadric of the normal form.
    pub quadrics: Vec<QuadricRecord>,
}

/// The GPU form of a [`QuadricRecord`]: 16 `f32` (64 bytes): the ten
/// coefficients scaled so that the largest is `±1`, then `r, g, b`, then zeros.
pub type GpuQuadric = [f32; 16];

/// The GPU form of a [`Splat`]: 12 words (48 bytes), `#[repr(C)]`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuSplat {
    /// Position.
    pub position: [f32; 3],
    /// Radius.
    pub radius: f32,
    /// Outward unit normal.
    pub normal: [f32; 3],
    /// Normal half-extent of the box.
    pub normal_extent: f32,
    /// Quadric index with [`OUTSIDE_FLAG`].
    pub quadric: u32,
    /// Clip list start.
    pub clip_start: u32,
    /// Clip list length.
    pub clip_count: u32,
    /// Padding to 16-byte alignment.
    pub pad: u32,
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
            .map(|q| QuadricRecord {
                coefficients: q.quadric.coefficients(),
                color: dag
                    .primitives()
                    .get(q.primitive)
                    .map_or(DEFAULT_COLOR, |p| p.color),
            })
            .collect();
        let mut lists: HashMap<Vec<u32>, u32> = HashMap::new();
        let mut clip_indices = Vec::new();
        let mut splats = Vec::with_capacity(samples.samples.len());
        let mut list = Vec::new();
        for s in &samples.samples {
            let product = &dnf.products()[s.product as usize];
            list.clear();
            for (j, l) in product.iter().enumerate() {
                if j == s.literal as usize {
                    continue;
                }
                if distances[l.quadric].distance(s.position).abs() < s.radius {
                    list.push(flagged(l.quadric, l.side));
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
            let own = product[s.literal as usize];
            let hf = &samples.patches[s.patch as usize].heightfield;
            let r = s.radius;
            let (dmin, dmax) = hf.distortion_bounds(s.uv - DVec2::splat(r), s.uv + DVec2::splat(r));
            let extent = r * (dmax - dmin);
            splats.push(Splat {
                position: s.position,
                normal: s.normal,
                radius: r,
                normal_extent: if extent.is_finite() { extent.min(r) } else { r },
                quadric: flagged(own.quadric, own.side),
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
                let k = self.quadrics[(c & !OUTSIDE_FLAG) as usize].coefficients;
                let v = crate::Quadric::from_coefficients(k).map_or(0.0, |q| q.value(p));
                if c & OUTSIDE_FLAG == 0 {
                    v <= 0.0
                } else {
                    v >= 0.0
                }
            })
    }

    /// The quadric buffer in GPU form.
    #[must_use]
    pub fn gpu_quadrics(&self) -> Vec<GpuQuadric> {
        self.quadrics.iter().map(QuadricRecord::to_gpu).collect()
    }

    /// The splats in GPU form.
    #[must_use]
    pub fn gpu_splats(&self) -> Vec<GpuSplat> {
        self.splats.iter().map(Splat::to_gpu).collect()
    }
}

impl QuadricRecord {
    /// The GPU form: coefficients scaled to a largest magnitude of 1 (the
    /// surface and the sign are unchanged), as `f32`, then the colour.
    #[must_use]
    // f64 → f32 is the point of this conversion.
    #[allow(clippy::cast_possible_truncation)]
    pub fn to_gpu(&self) -> GpuQuadric {
        let scale = self
            .coefficients
            .iter()
            .fold(0.0_f64, |s, c| s.max(c.abs()));
        let inv = if scale > 0.0 { 1.0 / scale } else { 1.0 };
        let mut out = [0.0_f32; 16];
        for (o, c) in out.iter_mut().zip(self.coefficients) {
            *o = (c * inv) as f32;
        }
        out[10..13].copy_from_slice(&self.color);
        out
    }
}

impl Splat {
    /// The GPU form (`f32` positions and sizes).
    #[must_use]
    #[allow(clippy::cast_possible_truncation)]
    pub fn to_gpu(&self) -> GpuSplat {
        GpuSplat {
            position: self.position.as_vec3().to_array(),
            radius: self.radius as f32,
            normal: self.normal.as_vec3().to_array(),
            normal_extent: self.normal_extent as f32,
            quadric: self.quadric,
            clip_start: self.clip_start,
            clip_count: self.clip_count,
            pad: 0,
        }
    }
}

fn flagged(quadric: usize, side: Side) -> u32 {
    let q = len_u32(quadric);
    match side {
        Side::Inside => q,
        Side::Outside => q | OUTSIDE_FLAG,
    }
}

/// Buffer lengths and indices fit in `u32` for any splat set a GPU can hold.
fn len_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}
