//! Textured PBR terrain without UVs: [`TriplanarMaterial`], Bevy's
//! [`StandardMaterial`] extended by [`TriplanarExtension`].
//!
//! The fragment shader (`shaders/terrain_triplanar.wgsl`) projects an
//! albedo and a tangent-space normal texture along the three world axes,
//! at [`TriplanarExtension::scale`] repeats per world unit, and blends the
//! three samples by the world normal raised to
//! [`TriplanarExtension::sharpness`]. Normals are blended with the
//! whiteout blend (each projection's normal-map vector added to the
//! surface normal in that projection's tangent frame), so relief follows
//! every face of a carved crater. The result feeds Bevy's PBR lighting:
//! shadows, fog, ambient and environment light, exposure and tonemapping
//! as for any `StandardMaterial`, whose `base_color` tints the albedo and
//! whose roughness and metallic apply as they are. It relies only on the
//! world position and world normal of the mesh, so cell meshes need no UVs
//! or tangents, and the pattern stays fixed in the world when cells are
//! re-meshed. Forward rendering only (under deferred rendering the
//! `StandardMaterial` part is drawn untextured).
//!
//! Textures: [`TerrainSurface`] names the four that ship with the crate
//! (rock, dirt, grass, ore; made by `scripts/make_textures.py`), compiled
//! in and added by [`TriplanarMaterialPlugin`] with mipmaps and repeat
//! sampling. A game's own textures load with [`TriplanarExtension::load`].

use bevy::asset::{AssetPath, RenderAssetUsages, uuid_handle};
use bevy::image::{
    CompressedImageFormats, ImageAddressMode, ImageFilterMode, ImageLoaderSettings, ImageSampler,
    ImageSamplerDescriptor, ImageType,
};
use bevy::pbr::{ExtendedMaterial, MaterialExtension};
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, TextureFormat};
use bevy::shader::{Shader, ShaderRef};
use chisel_bsp::tree::Label;

use super::{TerrainMaterialPlugin, TerrainMaterials};

/// Textured PBR terrain: a [`StandardMaterial`] whose albedo and normal
/// come from triplanar-mapped textures ([`TriplanarExtension`]).
pub type TriplanarMaterial = ExtendedMaterial<StandardMaterial, TriplanarExtension>;

/// The fragment shader (`shaders/terrain_triplanar.wgsl`).
pub const TRIPLANAR_SHADER: Handle<Shader> = uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f011");

/// The triplanar part of a [`TriplanarMaterial`]: textures and mapping.
/// Bindings 100–104 of the material bind group (0–99 are the
/// `StandardMaterial`'s).
#[derive(Asset, AsBindGroup, Reflect, Debug, Clone)]
pub struct TriplanarExtension {
    /// Texture repeats per world unit: `0.25` shows one texture over 4 m.
    #[uniform(100)]
    pub scale: f32,
    /// Exponent of the blend weights `|n|^sharpness`: `1` blends the three
    /// projections broadly, larger values keep each face to its dominant
    /// axis (`4` is a good start; must be positive).
    #[uniform(100)]
    pub sharpness: f32,
    /// Factor on the normal texture's tilt: `0` is flat, `1` as authored.
    #[uniform(100)]
    pub normal_strength: f32,
    /// Brightness variation against visible tiling: `0` is none; `t`
    /// scales the albedo by `mix(1, b, t)`, `b` the brightness of the
    /// albedo sampled at an eighth of the frequency over its mean, read
    /// from its last mip level (so the albedo needs a full mip chain;
    /// clamped to 0.5–1.5).
    #[uniform(100)]
    pub macro_variation: f32,
    /// Albedo (sRGB), tinted by the base material's `base_color`. Sampled
    /// with repeat addressing: see [`triplanar_sampler`].
    #[texture(101)]
    #[sampler(102)]
    pub albedo: Handle<Image>,
    /// Tangent-space normal map (linear, OpenGL convention: green is +Y
    /// up the image).
    #[texture(103)]
    #[sampler(104)]
    pub normal: Handle<Image>,
}

impl TriplanarExtension {
    /// Triplanar mapping of `albedo` and `normal`, one repeat per 4 world
    /// units, sharpness 4, normals as authored, macro variation 0.6.
    #[must_use]
    pub fn new(albedo: Handle<Image>, normal: Handle<Image>) -> Self {
        Self {
            scale: 0.25,
            sharpness: 4.0,
            normal_strength: 1.0,
            macro_variation: 0.6,
            albedo,
            normal,
        }
    }

    /// Loads an albedo (as sRGB) and a normal map (as linear) with the
    /// asset server, both with [`triplanar_sampler`]. Loaded images have
    /// the mipmaps their files hold (none for PNG; prefer KTX2 with mips
    /// for large scenes, or build images with [`triplanar_image`]).
    #[must_use]
    pub fn load<'a>(
        assets: &AssetServer,
        albedo: impl Into<AssetPath<'a>>,
        normal: impl Into<AssetPath<'a>>,
    ) -> Self {
        let load = |path: AssetPath<'a>, srgb: bool| {
            assets
                .load_builder()
                .with_settings(move |s: &mut ImageLoaderSettings| {
                    s.is_srgb = srgb;
                    s.sampler = ImageSampler::Descriptor(triplanar_sampler());
                })
                .load(path)
        };
        Self::new(load(albedo.into(), true), load(normal.into(), false))
    }

    /// With `scale` texture repeats per world unit.
    #[must_use]
    pub fn with_scale(mut self, scale: f32) -> Self {
        self.scale = scale;
        self
    }

    /// With blend exponent `sharpness`.
    #[must_use]
    pub fn with_sharpness(mut self, sharpness: f32) -> Self {
        self.sharpness = sharpness;
        self
    }

    /// With normal-map factor `strength`.
    #[must_use]
    pub fn with_normal_strength(mut self, strength: f32) -> Self {
        self.normal_strength = strength;
        self
    }

    /// With macro variation `amount`.
    #[must_use]
    pub fn with_macro_variation(mut self, amount: f32) -> Self {
        self.macro_variation = amount;
        self
    }
}

impl MaterialExtension for TriplanarExtension {
    fn fragment_shader() -> ShaderRef {
        ShaderRef::Handle(TRIPLANAR_SHADER)
    }
}

/// Repeat addressing on every axis, trilinear filtering, 8× anisotropy:
/// what triplanar textures need (world coordinates run far outside
/// `[0, 1]`).
#[must_use]
pub fn triplanar_sampler() -> ImageSamplerDescriptor {
    ImageSamplerDescriptor {
        label: Some("bevy_chisel triplanar".into()),
        address_mode_u: ImageAddressMode::Repeat,
        address_mode_v: ImageAddressMode::Repeat,
        address_mode_w: ImageAddressMode::Repeat,
        mag_filter: ImageFilterMode::Linear,
        min_filter: ImageFilterMode::Linear,
        mipmap_filter: ImageFilterMode::Linear,
        anisotropy_clamp: 8,
        ..default()
    }
}

/// The textures shipped with the crate, tileable, 256×256.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TerrainSurface {
    /// Grey stone in irregular plates.
    Rock,
    /// Brown soil with pebbles.
    Dirt,
    /// Grass turf.
    Grass,
    /// Dark stone with veins and flecks of gold.
    Ore,
}

/// `(surface, albedo handle, normal handle, albedo PNG, normal PNG)`.
type SurfaceTextures = (
    TerrainSurface,
    Handle<Image>,
    Handle<Image>,
    &'static [u8],
    &'static [u8],
);

const SURFACES: [SurfaceTextures; 4] = [
    (
        TerrainSurface::Rock,
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f101"),
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f102"),
        include_bytes!("../../../assets/textures/rock_albedo.png"),
        include_bytes!("../../../assets/textures/rock_normal.png"),
    ),
    (
        TerrainSurface::Dirt,
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f201"),
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f202"),
        include_bytes!("../../../assets/textures/dirt_albedo.png"),
        include_bytes!("../../../assets/textures/dirt_normal.png"),
    ),
    (
        TerrainSurface::Grass,
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f301"),
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f302"),
        include_bytes!("../../../assets/textures/grass_albedo.png"),
        include_bytes!("../../../assets/textures/grass_normal.png"),
    ),
    (
        TerrainSurface::Ore,
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f401"),
        uuid_handle!("3b8f4a2e-6c1d-4e7f-9a05-b2d4c6e8f402"),
        include_bytes!("../../../assets/textures/ore_albedo.png"),
        include_bytes!("../../../assets/textures/ore_normal.png"),
    ),
];

impl TerrainSurface {
    /// Every shipped surface.
    pub const ALL: [Self; 4] = [Self::Rock, Self::Dirt, Self::Grass, Self::Ore];

    fn textures(self) -> &'static SurfaceTextures {
        &SURFACES[self as usize]
    }

    /// The albedo texture (added by [`TriplanarMaterialPlugin`]).
    #[must_use]
    pub fn albedo(self) -> Handle<Image> {
        self.textures().1.clone()
    }

    /// The normal texture (added by [`TriplanarMaterialPlugin`]).
    #[must_use]
    pub fn normal(self) -> Handle<Image> {
        self.textures().2.clone()
    }

    /// The surface's textured material: its textures at a scale that suits
    /// the surface, with roughness and metallic to match.
    #[must_use]
    pub fn material(self) -> TriplanarMaterial {
        let (scale, roughness, metallic) = match self {
            Self::Rock => (0.25, 0.85, 0.0),
            Self::Dirt => (0.4, 0.95, 0.0),
            Self::Grass => (0.3, 0.9, 0.0),
            Self::Ore => (0.25, 0.5, 0.3),
        };
        ExtendedMaterial {
            base: StandardMaterial {
                perceptual_roughness: roughness,
                metallic,
                ..default()
            },
            extension: TriplanarExtension::new(self.albedo(), self.normal()).with_scale(scale),
        }
    }
}

/// A label table of shipped surfaces: each `(label, surface)` gets the
/// surface's [`TerrainSurface::material`], other labels `fallback`'s.
pub fn surface_table(
    materials: &mut Assets<TriplanarMaterial>,
    entries: impl IntoIterator<Item = (Label, TerrainSurface)>,
    fallback: TerrainSurface,
) -> TerrainMaterials<TriplanarMaterial> {
    let mut made: Vec<(TerrainSurface, Handle<TriplanarMaterial>)> = Vec::new();
    let mut handle = |surface: TerrainSurface| {
        if let Some((_, h)) = made.iter().find(|(s, _)| *s == surface) {
            return h.clone();
        }
        let h = materials.add(surface.material());
        made.push((surface, h.clone()));
        h
    };
    let by_label: Vec<_> = entries
        .into_iter()
        .map(|(label, surface)| (label, handle(surface)))
        .collect();
    TerrainMaterials::new(by_label, handle(fallback))
}

/// An image for triplanar mapping from encoded bytes (`extension` as
/// `"png"`, `"ktx2"`, …): albedo with `srgb`, a normal map without;
/// [`triplanar_sampler`] and a full mip chain (box filtered, normals
/// renormalized) for 8-bit RGBA images.
///
/// # Errors
/// When the bytes do not decode.
pub fn triplanar_image(
    bytes: &[u8],
    extension: &str,
    srgb: bool,
) -> Result<Image, bevy::image::TextureError> {
    let mut image = Image::from_buffer(
        bytes,
        ImageType::Extension(extension),
        CompressedImageFormats::NONE,
        srgb,
        ImageSampler::Descriptor(triplanar_sampler()),
        RenderAssetUsages::RENDER_WORLD,
    )?;
    add_mip_chain(&mut image, !srgb);
    Ok(image)
}

/// Appends mip levels down to 1×1 to a single-level 8-bit RGBA image with
/// power-of-two sides; leaves other images as they are. `normal_map`
/// averages unit vectors and renormalizes; otherwise colours are averaged
/// in linear light when the format is sRGB.
fn add_mip_chain(image: &mut Image, normal_map: bool) {
    let format = image.texture_descriptor.format;
    let srgb = match format {
        TextureFormat::Rgba8UnormSrgb => true,
        TextureFormat::Rgba8Unorm => false,
        _ => return,
    };
    let (mut w, mut h) = (image.width() as usize, image.height() as usize);
    if image.texture_descriptor.mip_level_count != 1 || !w.is_power_of_two() || !h.is_power_of_two()
    {
        return;
    }
    let Some(data) = image.data.as_mut() else {
        return;
    };
    let to_linear = |b: u8| {
        let c = f32::from(b) / 255.0;
        if srgb { c.powf(2.2) } else { c }
    };
    let from_linear = |c: f32| {
        let c = if srgb { c.max(0.0).powf(1.0 / 2.2) } else { c };
        (c * 255.0).round().clamp(0.0, 255.0) as u8
    };
    let mut levels = 1;
    let mut level: Vec<u8> = data.clone();
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut next = vec![0u8; nw * nh * 4];
        for y in 0..nh {
            for x in 0..nw {
                let mut sum = [0.0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                    let p = &level[(sy * w + sx) * 4..][..4];
                    for c in 0..3 {
                        sum[c] += if normal_map {
                            f32::from(p[c]) / 127.5 - 1.0
                        } else {
                            to_linear(p[c])
                        };
                    }
                    sum[3] += f32::from(p[3]) / 255.0;
                }
                let out = &mut next[(y * nw + x) * 4..][..4];
                if normal_map {
                    let n = Vec3::new(sum[0], sum[1], sum[2]).normalize_or(Vec3::Z);
                    for (c, v) in n.to_array().into_iter().enumerate() {
                        out[c] = ((v * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
                    }
                } else {
                    for c in 0..3 {
                        out[c] = from_linear(sum[c] / 4.0);
                    }
                }
                out[3] = (sum[3] / 4.0 * 255.0).round() as u8;
            }
        }
        data.extend_from_slice(&next);
        level = next;
        (w, h) = (nw, nh);
        levels += 1;
    }
    image.texture_descriptor.mip_level_count = levels;
}

/// Textured terrain: the triplanar shader, the shipped
/// [`TerrainSurface`] textures, Bevy's `MaterialPlugin` for
/// [`TriplanarMaterial`] and the [`TerrainMaterialPlugin`] that puts it on
/// cells. Needs rendering (`DefaultPlugins`) and [`super::super::TerrainPlugin`].
pub struct TriplanarMaterialPlugin;

impl Plugin for TriplanarMaterialPlugin {
    fn build(&self, app: &mut App) {
        match app.world_mut().get_resource_mut::<Assets<Shader>>() {
            Some(mut shaders) => {
                let shader = Shader::from_wgsl(
                    include_str!("../../../shaders/terrain_triplanar.wgsl"),
                    "shaders/terrain_triplanar.wgsl",
                );
                if let Err(e) = shaders.insert(TRIPLANAR_SHADER.id(), shader) {
                    error!("bevy_chisel: cannot add the triplanar shader: {e}");
                }
            }
            None => warn!("bevy_chisel: no shader assets (is the RenderPlugin added?)"),
        }
        match app.world_mut().get_resource_mut::<Assets<Image>>() {
            Some(mut images) => {
                for (surface, albedo, normal, albedo_png, normal_png) in &SURFACES {
                    for (handle, bytes, srgb) in
                        [(albedo, albedo_png, true), (normal, normal_png, false)]
                    {
                        match triplanar_image(bytes, "png", srgb) {
                            Ok(image) => {
                                if let Err(e) = images.insert(handle.id(), image) {
                                    error!("bevy_chisel: cannot add the {surface:?} texture: {e}");
                                }
                            }
                            Err(e) => {
                                error!("bevy_chisel: cannot decode the {surface:?} texture: {e}");
                            }
                        }
                    }
                }
            }
            None => warn!("bevy_chisel: no image assets (is the ImagePlugin added?)"),
        }
        app.add_plugins((
            MaterialPlugin::<TriplanarMaterial>::default(),
            TerrainMaterialPlugin::<TriplanarMaterial>::default(),
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_textures_decode_with_a_full_mip_chain() {
        for (surface, _, _, albedo, normal) in &SURFACES {
            for (bytes, srgb) in [(albedo, true), (normal, false)] {
                let image = triplanar_image(bytes, "png", srgb).expect("shipped PNG decodes");
                assert_eq!(image.width(), 256, "{surface:?}");
                assert_eq!(image.texture_descriptor.mip_level_count, 9, "{surface:?}");
                // 256² + 128² + … + 1² texels of 4 bytes.
                let texels: usize = (0..9).map(|k| (256usize >> k).pow(2)).sum();
                assert_eq!(image.data.as_ref().map(Vec::len), Some(texels * 4));
            }
        }
    }

    #[test]
    fn surface_table_shares_one_material_per_surface() {
        let mut materials = Assets::<TriplanarMaterial>::default();
        let table = surface_table(
            &mut materials,
            [(1, TerrainSurface::Rock), (2, TerrainSurface::Dirt)],
            TerrainSurface::Rock,
        );
        assert_eq!(materials.len(), 2);
        assert_eq!(table.get(1), table.get(9));
        assert_ne!(table.get(1), table.get(2));
    }
}
