//! GPU data layouts of the splat and global passes, declared once here.
//!
//! Every struct is `#[repr(C)]` with explicit padding, so its `encase`
//! (WGSL) layout and its Rust layout coincide; the WGSL mirror is
//! `shaders/quadric_common.wgsl` (same names, same field order). Tests check
//! the sizes against the kernel's own GPU records
//! ([`chisel_quadric::GpuSplat`], [`chisel_quadric::GpuQuadric`]), and
//! `tests/shaders_validate.rs` checks every WGSL mirror's member names and
//! offsets, as naga lays them out, against these structs.

use bevy::math::{Mat4, UVec2, Vec3, Vec4};
use bevy::render::render_resource::ShaderType;
use chisel_quadric::{GpuQuadric, GpuSplat};

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

/// One entry of the quadric buffer (WGSL `Quadric`): the kernel's
/// [`GpuQuadric`] as four `vec4`.
#[derive(Clone, Copy, Debug, Default, PartialEq, ShaderType)]
#[repr(C)]
pub struct QuadricRecord {
    /// `[q00 q01 q02 q03] [q11 q12 q13 q22] [q23 q33 r g] [b 0 0 0]`.
    pub c: [Vec4; 4],
}

impl From<&GpuQuadric> for QuadricRecord {
    fn from(q: &GpuQuadric) -> Self {
        Self {
            c: [
                Vec4::new(q[0], q[1], q[2], q[3]),
                Vec4::new(q[4], q[5], q[6], q[7]),
                Vec4::new(q[8], q[9], q[10], q[11]),
                Vec4::new(q[12], q[13], q[14], q[15]),
            ],
        }
    }
}

/// One entry of the instance buffer (WGSL `Splat`): the kernel's
/// [`GpuSplat`] field for field.
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
    /// Quadric index with [`chisel_quadric::OUTSIDE_FLAG`].
    pub quadric: u32,
    /// Start of the clip list in the clip-index buffer.
    pub clip_start: u32,
    /// Length of the clip list.
    pub clip_count: u32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

impl From<&GpuSplat> for SplatRecord {
    fn from(s: &GpuSplat) -> Self {
        Self {
            position: Vec3::from_array(s.position),
            radius: s.radius,
            normal: Vec3::from_array(s.normal),
            normal_extent: s.normal_extent,
            quadric: s.quadric,
            clip_start: s.clip_start,
            clip_count: s.clip_count,
            pad: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wgsl_sizes_match_rust_and_kernel_layouts() {
        assert_eq!(SplatRecord::min_size().get(), 48);
        assert_eq!(size_of::<SplatRecord>(), size_of::<GpuSplat>());
        assert_eq!(
            SplatRecord::min_size().get() as usize,
            size_of::<GpuSplat>()
        );
        assert_eq!(
            QuadricRecord::min_size().get() as usize,
            size_of::<GpuQuadric>()
        );
        assert_eq!(size_of::<QuadricRecord>(), size_of::<GpuQuadric>());
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
        let q: GpuQuadric = std::array::from_fn(|i| i as f32);
        let r = QuadricRecord::from(&q);
        assert_eq!(r.c[2], Vec4::new(8.0, 9.0, 10.0, 11.0));
        let s = GpuSplat {
            position: [1.0, 2.0, 3.0],
            radius: 0.5,
            normal: [0.0, 0.0, 1.0],
            normal_extent: 0.01,
            quadric: 7 | chisel_quadric::OUTSIDE_FLAG,
            clip_start: 4,
            clip_count: 2,
            pad: 0,
        };
        let r = SplatRecord::from(&s);
        assert_eq!(r.position, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(r.quadric, s.quadric);
        assert_eq!((r.clip_start, r.clip_count), (4, 2));
    }
}
