//! GPU data layouts of the splat and global passes, declared once here.
//!
//! These `ShaderType` structs are the only GPU form of the kernel's plain
//! records: [`QuadricRecord`] converts from a
//! [`chisel_quadric::ColoredQuadric`] and [`SplatRecord`] from a
//! [`chisel_quadric::Splat`]. The other buffers hold `u32`s the kernel
//! encodes itself (clip lists and [`chisel_quadric::encode_normal_form`],
//! both of [`chisel_quadric::literal_reference`]s).
//!
//! Every struct is `#[repr(C)]` with explicit padding, so its `encase`
//! (WGSL) layout and its Rust layout coincide; the WGSL mirror is
//! `shaders/quadric_common.wgsl` (same names, same field order).
//! `tests/it/shaders_validate.rs` checks every WGSL mirror's member names,
//! offsets and size, as naga lays them out, against these structs and the
//! bytes `encase` writes for them, and the WGSL flag constants against the
//! kernel's.

use bevy::math::{DMat3, DVec3, Mat4, UVec2, Vec2, Vec3, Vec4};
use bevy::render::render_resource::ShaderType;
use bevy::render::view::ExtractedView;
use chisel_quadric::{ColoredQuadric, Splat, SymmetricEigen};

use super::SplatSettings;

/// Per-view data of the splat pass (WGSL `SplatView`, group 2, dynamic
/// offset); lights, exposure and the rest of the view come from Bevy's mesh
/// view bindings (groups 0 and 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
#[repr(C)]
pub struct SplatViewUniform {
    /// World to clip space (reverse-Z).
    pub clip_from_world: Mat4,
    /// Eye position; `w` is 1 for a perspective view, 0 for orthographic.
    pub camera_position: Vec4,
    /// Unit view direction (`w` unused).
    pub view_forward: Vec4,
    /// Splats with a normal extent below `flat_ratio · radius` are drawn as
    /// one quad ([`SplatSettings::flat_ratio`](super::SplatSettings::flat_ratio)).
    pub flat_ratio: f32,
    /// Hits are kept within `radius · radius_tolerance` of their sample
    /// ([`SplatSettings::radius_tolerance`](super::SplatSettings::radius_tolerance)).
    pub radius_tolerance: f32,
    /// Padding to 16 bytes.
    pub pad: UVec2,
}

impl SplatViewUniform {
    /// The uniform of `view` (a camera's or a light's shadow view) drawn
    /// with `settings`.
    #[must_use]
    pub fn new(view: &ExtractedView, settings: &SplatSettings) -> Self {
        let clip_from_world = view
            .clip_from_world
            .unwrap_or_else(|| view.clip_from_view * view.world_from_view.to_matrix().inverse());
        let orthographic = view.clip_from_view.w_axis.w == 1.0;
        let eye = view.world_from_view.translation();
        let forward = view.world_from_view.forward().as_vec3();
        Self {
            clip_from_world,
            camera_position: eye.extend(if orthographic { 0.0 } else { 1.0 }),
            view_forward: forward.extend(0.0),
            flat_ratio: settings.flat_ratio,
            radius_tolerance: settings.radius_tolerance,
            pad: UVec2::ZERO,
        }
    }

    /// Whether the view is orthographic (`camera_position.w` is 0).
    #[must_use]
    pub fn is_orthographic(&self) -> bool {
        self.camera_position.w == 0.0
    }
}

/// Per-prop data (WGSL `Prop`, group 3 binding 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
#[repr(C)]
pub struct PropUniform {
    /// The prop's local (scene) coordinates to world.
    pub world_from_local: Mat4,
    /// Inverse of `world_from_local`.
    pub local_from_world: Mat4,
    /// Inverse transpose of the linear part of `world_from_local`.
    pub normal_from_local: Mat4,
    /// Local bounding sphere: centre (`xyz`) and radius (`w`).
    pub bounds: Vec4,
    /// Number of products of the normal form.
    pub product_count: u32,
    /// Largest stretch of `world_from_local` (its largest singular value):
    /// a local sphere of radius `r` lies in a world sphere of radius
    /// `r · max_scale`.
    pub max_scale: f32,
    /// `−1` when `world_from_local` mirrors (negative determinant), `+1`
    /// otherwise. The vertex stages negate one tangent axis of every box
    /// by it, which reverses the boxes' winding in local space so that it
    /// comes out counter-clockwise (front-facing) again in clip space.
    pub mirror_sign: f32,
    /// The prop's [`PropMaterial::metallic`](super::PropMaterial::metallic).
    pub metallic: f32,
    /// The prop's [`PropMaterial::perceptual_roughness`](super::PropMaterial::perceptual_roughness).
    pub perceptual_roughness: f32,
    /// The prop's [`PropMaterial::reflectance`](super::PropMaterial::reflectance).
    pub reflectance: f32,
    /// Padding to 16 bytes.
    pub pad: UVec2,
}

/// One entry of the quadric buffer (WGSL `Quadric`): a
/// [`ColoredQuadric`] as four `vec4`.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
#[repr(C)]
pub struct QuadricRecord {
    /// `[q00 q01 q02 q03] [q11 q12 q13 q22] [q23 q33 r g] [b m ρ 0]`: the
    /// coefficients as [`ColoredQuadric::scaled_coefficients`], the
    /// colour, then the primitive's metallic `m` and perceptual roughness
    /// `ρ`, each [`PROP_MATERIAL`] where the primitive leaves it to the
    /// prop's [`PropMaterial`](super::PropMaterial).
    pub c: [Vec4; 4],
}

/// A metallic or roughness slot of a [`QuadricRecord`] that takes the
/// prop's value (WGSL: any negative value).
pub const PROP_MATERIAL: f32 = -1.0;

impl From<&ColoredQuadric> for QuadricRecord {
    fn from(q: &ColoredQuadric) -> Self {
        let k = q.scaled_coefficients();
        let [r, g, b] = q.color;
        // The scene loader refuses values outside [0, 1]; a DAG built in
        // code may hold any: a non-finite one takes the prop's, the rest
        // are clamped as `PropMaterial::validated` clamps.
        let slot = |v: Option<f32>| {
            v.filter(|v| v.is_finite())
                .map_or(PROP_MATERIAL, |v| v.clamp(0.0, 1.0))
        };
        Self {
            c: [
                Vec4::new(k[0], k[1], k[2], k[3]),
                Vec4::new(k[4], k[5], k[6], k[7]),
                Vec4::new(k[8], k[9], r, g),
                Vec4::new(
                    b,
                    slot(q.material.metallic),
                    slot(q.material.perceptual_roughness),
                    0.0,
                ),
            ],
        }
    }
}

/// One entry of the instance buffer (WGSL `Splat`): a kernel [`Splat`] in
/// `f32`.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
#[repr(C)]
pub struct SplatRecord {
    /// Sample position (local coordinates).
    pub position: Vec3,
    /// Radius to cover.
    pub radius: f32,
    /// Outward unit normal (zero at a singular point).
    pub normal: Vec3,
    /// Half-extent of the surface-aligned box along the normal.
    pub normal_extent: f32,
    /// The box's first tangent axis (unit, orthogonal to `normal`; the
    /// second is `normal × tangent`).
    pub tangent: Vec3,
    /// How fast the outward normal can turn, per unit of distance from
    /// the sample: `‖A‖₂ / |As − b|` of the splat's quadric (spectral
    /// norm of its quadratic part, its largest absolute eigenvalue,
    /// against its half gradient at the sample), `f32::MAX` where unknown.
    /// The splat pass drops a splat facing away from the eye by more than
    /// this turn over its radius (`SplatSettings::cull_facing_away`).
    pub normal_turn: f32,
    /// Half-extents of the box along the two tangent axes
    /// ([`chisel_quadric::Splat::tangent_extent`]: the surface over the
    /// sample's cell, at most `radius`).
    pub tangent_extent: Vec2,
    /// The literal the splat lies on ([`chisel_quadric::literal_reference`]).
    pub quadric: u32,
    /// Start of the clip list in the clip-index buffer.
    pub clip_start: u32,
    /// Length of the clip list.
    pub clip_count: u32,
    /// Padding to 16 bytes.
    pub pad: [u32; 3],
}

impl SplatRecord {
    /// The record of kernel splat `s`, whose literal indexes `quadrics`.
    /// Where the quadric is missing, the gradient vanishes at the sample or
    /// `s.normal` is not the literal's outward unit gradient direction,
    /// `normal_turn` is `f32::MAX` (never culled).
    // f64 → f32 is the point of this conversion.
    #[allow(clippy::cast_possible_truncation)]
    #[must_use]
    pub fn new(s: &Splat, quadrics: &[ColoredQuadric]) -> Self {
        let index = (s.quadric & chisel_quadric::INDEX_MASK) as usize;
        let normal_turn = quadrics.get(index).map_or(f32::MAX, |q| {
            let [q00, q01, q02, q03, q11, q12, q13, q22, q23, _] = q.coefficients;
            let p = s.position;
            let mut g = DVec3::new(
                q00 * p.x + q01 * p.y + q02 * p.z + q03,
                q01 * p.x + q11 * p.y + q12 * p.z + q13,
                q02 * p.x + q12 * p.y + q22 * p.z + q23,
            );
            if s.quadric & chisel_quadric::OUTSIDE_FLAG != 0 {
                g = -g;
            }
            let a_norm = spectral_norm([q00, q01, q02, q11, q12, q22]);
            let len = g.length();
            let turn = a_norm / len;
            let aligned = len > 0.0 && g.dot(s.normal) >= len * (1.0 - 1e-6);
            if aligned && turn.is_finite() && turn < f64::from(f32::MAX) {
                // Rounded up, so the bound stays conservative in f32.
                (turn * (1.0 + 1e-6)) as f32
            } else {
                f32::MAX
            }
        });
        // Extents rounded up, so the f32 box still holds the f64 one.
        let up = |x: f64| (x * (1.0 + 1e-6)) as f32;
        Self {
            position: s.position.as_vec3(),
            radius: s.radius as f32,
            normal: s.normal.as_vec3(),
            normal_extent: up(s.normal_extent),
            tangent: s.tangent.as_vec3(),
            normal_turn,
            tangent_extent: s.tangent_extent.to_array().map(up).into(),
            quadric: s.quadric,
            clip_start: s.clip_start,
            clip_count: s.clip_count,
            pad: [0; 3],
        }
    }
}

/// The spectral norm `‖A‖₂` of the symmetric `A` with packed entries
/// `[a00, a01, a02, a11, a12, a22]`: its largest absolute eigenvalue,
/// widened by `10⁻⁹ ‖A‖_F` against the solver's rounding (so never below
/// the true norm); `‖A‖_F` itself (an upper bound) where the solver's
/// answer is not finite.
fn spectral_norm([a00, a01, a02, a11, a12, a22]: [f64; 6]) -> f64 {
    let frobenius =
        (a00 * a00 + a11 * a11 + a22 * a22 + 2.0 * (a01 * a01 + a02 * a02 + a12 * a12)).sqrt();
    let a = DMat3::from_cols_array(&[a00, a01, a02, a01, a11, a12, a02, a12, a22]);
    let eigen = SymmetricEigen::new(a);
    let largest = eigen.max_value().abs().max(eigen.min_value().abs());
    if largest.is_finite() {
        (largest + 1e-9 * frobenius).min(frobenius)
    } else {
        frobenius
    }
}

#[cfg(test)]
mod tests {
    use chisel_quadric::SurfaceMaterial;

    use super::*;

    #[test]
    fn rust_sizes_match_the_wgsl_sizes() {
        assert_eq!(SplatRecord::min_size().get(), 80);
        assert_eq!(QuadricRecord::min_size().get(), 64);
        assert_eq!(
            SplatRecord::min_size().get() as usize,
            size_of::<SplatRecord>()
        );
        assert_eq!(
            QuadricRecord::min_size().get() as usize,
            size_of::<QuadricRecord>()
        );
        assert_eq!(
            PropUniform::min_size().get() as usize,
            size_of::<PropUniform>()
        );
        assert_eq!(
            SplatViewUniform::min_size().get() as usize,
            size_of::<SplatViewUniform>()
        );
    }

    #[test]
    fn records_copy_the_kernel_fields() {
        let mut quadric = ColoredQuadric {
            coefficients: [-4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 2.0, 1.0],
            color: [0.1, 0.2, 0.3],
            material: SurfaceMaterial::default(),
        };
        let r = QuadricRecord::from(&quadric);
        assert_eq!(r.c[0], Vec4::new(-1.0, -0.75, -0.5, -0.25));
        assert_eq!(r.c[1], Vec4::new(0.0, 0.25, 0.5, 0.75));
        assert_eq!(r.c[2], Vec4::new(0.5, 0.25, 0.1, 0.2));
        assert_eq!(r.c[3], Vec4::new(0.3, PROP_MATERIAL, PROP_MATERIAL, 0.0));
        quadric.material = SurfaceMaterial {
            metallic: Some(0.75),
            perceptual_roughness: Some(0.125),
        };
        let r = QuadricRecord::from(&quadric);
        assert_eq!(r.c[3], Vec4::new(0.3, 0.75, 0.125, 0.0));
        // Built in code without the loader's check: clamped, or the prop's.
        quadric.material = SurfaceMaterial {
            metallic: Some(1.5),
            perceptual_roughness: Some(f32::NAN),
        };
        let r = QuadricRecord::from(&quadric);
        assert_eq!(r.c[3], Vec4::new(0.3, 1.0, PROP_MATERIAL, 0.0));
        let s = Splat {
            position: DVec3::new(1.0, 2.0, 3.0),
            normal: DVec3::Z,
            radius: 0.5,
            normal_extent: 0.01,
            tangent: DVec3::X,
            tangent_extent: bevy::math::DVec2::new(0.25, 0.5),
            quadric: 7 | chisel_quadric::OUTSIDE_FLAG,
            clip_start: 4,
            clip_count: 2,
        };
        let r = SplatRecord::new(&s, &[]);
        assert_eq!(r.position, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!((r.radius, r.normal, r.tangent), (0.5, Vec3::Z, Vec3::X));
        // Extents rounded up by a hair, never down.
        assert!(r.normal_extent >= 0.01 && r.normal_extent < 0.01 * (1.0 + 1e-5));
        assert!(r.tangent_extent.cmpge(Vec2::new(0.25, 0.5)).all());
        assert!(
            r.tangent_extent
                .cmplt(Vec2::new(0.25, 0.5) * (1.0 + 1e-5))
                .all()
        );
        assert_eq!(r.quadric, s.quadric);
        assert_eq!((r.clip_start, r.clip_count), (4, 2));
        assert_eq!(r.normal_turn, f32::MAX, "no quadric: never culled");
        // The unit sphere, outside it (complement): at (0, 0, 2) the outward
        // normal is −z, |As − b| = 2, ‖A‖₂ = 1 (‖A‖_F = √3).
        let sphere = ColoredQuadric {
            coefficients: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, -1.0],
            ..quadric
        };
        let outside = Splat {
            position: DVec3::new(0.0, 0.0, 2.0),
            normal: DVec3::NEG_Z,
            quadric: chisel_quadric::OUTSIDE_FLAG,
            ..s
        };
        let r = SplatRecord::new(&outside, &[sphere]);
        assert!(r.normal_turn >= 0.5 && r.normal_turn - 0.5 < 1e-5);
        // A cylinder along z, x² + y² = 1 scaled by 3: ‖A‖₂ = 3 against
        // ‖A‖_F = 3√2; at (1, 0, 0) |As − b| = 3.
        let cylinder = ColoredQuadric {
            coefficients: [3.0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 0.0, -3.0],
            ..quadric
        };
        let on_cylinder = Splat {
            position: DVec3::X,
            normal: DVec3::X,
            quadric: 0,
            ..s
        };
        let r = SplatRecord::new(&on_cylinder, &[cylinder]);
        assert!(r.normal_turn >= 1.0 && r.normal_turn - 1.0 < 1e-5);
        let inverted = Splat {
            normal: DVec3::Z,
            ..outside
        };
        let r = SplatRecord::new(&inverted, &[sphere]);
        assert_eq!(r.normal_turn, f32::MAX, "normal against the gradient");
    }
}
