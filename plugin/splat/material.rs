//! The PBR material of a prop: what Bevy's lighting needs beyond the
//! quadrics' own base colours (and their own metallic and roughness, where
//! the scene file gives them).

use bevy::prelude::*;

/// On a prop (beside its [`QuadricProp`](super::QuadricProp) or
/// [`PropSplats`](super::PropSplats)): the metallic, perceptual roughness
/// and reflectance with which Bevy's PBR lights every quadric of the prop,
/// as the same fields of a `StandardMaterial` do; the base colour is each
/// quadric's own (linear RGB, from the scene file), and a primitive with
/// its own `metallic` or `roughness` in the scene file keeps those in
/// place of this component's. A prop without one is
/// drawn with [`PropMaterial::default`], which matches
/// `StandardMaterial::default()`.
///
/// ```
/// use bevy_chisel::splat::PropMaterial;
///
/// // Brushed metal.
/// let material = PropMaterial {
///     metallic: 1.0,
///     perceptual_roughness: 0.35,
///     ..Default::default()
/// };
/// assert!(material.validated().is_some());
/// ```
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PropMaterial {
    /// 0 (dielectric) to 1 (metal).
    pub metallic: f32,
    /// 0 (mirror) to 1 (fully rough); Bevy clamps it to at least 0.089.
    pub perceptual_roughness: f32,
    /// Specular intensity of dielectrics, 0 to 1 (0.5 is 4 %).
    pub reflectance: f32,
}

impl Default for PropMaterial {
    /// `StandardMaterial::default()`'s values: metallic 0, perceptual
    /// roughness 0.5, reflectance 0.5.
    fn default() -> Self {
        Self {
            metallic: 0.0,
            perceptual_roughness: 0.5,
            reflectance: 0.5,
        }
    }
}

impl PropMaterial {
    /// The material with every field clamped to `[0, 1]`, or `None` if a
    /// field is not finite (such a prop is drawn with the default
    /// material, and the plugin logs a warning when the component changes).
    #[must_use]
    pub fn validated(&self) -> Option<Self> {
        let fields = [self.metallic, self.perceptual_roughness, self.reflectance];
        fields.iter().all(|v| v.is_finite()).then(|| Self {
            metallic: self.metallic.clamp(0.0, 1.0),
            perceptual_roughness: self.perceptual_roughness.clamp(0.0, 1.0),
            reflectance: self.reflectance.clamp(0.0, 1.0),
        })
    }
}

/// Warns, once per change, about a [`PropMaterial`] with a field that is
/// not finite: the render world draws that prop with the default material.
pub(crate) fn warn_on_unusable_materials(
    materials: Query<(Entity, &PropMaterial), Changed<PropMaterial>>,
) {
    for (entity, material) in &materials {
        if material.validated().is_none() {
            warn!(
                "prop {entity}: {material:?} has a field that is not a finite number; \
                 the prop is drawn with PropMaterial::default()"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_the_standard_materials() {
        let standard = StandardMaterial::default();
        let prop = PropMaterial::default();
        assert_eq!(prop.metallic, standard.metallic);
        assert_eq!(prop.perceptual_roughness, standard.perceptual_roughness);
        assert_eq!(prop.reflectance, standard.reflectance);
    }

    #[test]
    fn out_of_range_fields_are_clamped_and_non_finite_ones_refused() {
        let bright = PropMaterial {
            metallic: 2.0,
            perceptual_roughness: -1.0,
            reflectance: 0.3,
        };
        assert_eq!(
            bright.validated(),
            Some(PropMaterial {
                metallic: 1.0,
                perceptual_roughness: 0.0,
                reflectance: 0.3,
            })
        );
        let broken = PropMaterial {
            metallic: f32::NAN,
            ..default()
        };
        assert_eq!(broken.validated(), None);
    }
}
