//! Main world: props seen by a shadow-casting light are visible.
//!
//! Bevy marks a mesh visible (`ViewVisibility`) when it lies in a camera's
//! frustum or in the shadow frustum of a light that casts shadows, so that
//! a mesh outside every camera still reaches the render world and casts
//! its shadow into view. Bevy's light checks take only `Mesh3d`s; this
//! does the same for props, with the same tests: a directional light's
//! cascades (near plane not tested: a caster may lie between the light and
//! a cascade), a point light's range sphere, a spot light's range and
//! frustum. Props with `NotShadowCaster`, hidden ones and those whose
//! render layers the light does not share are left alone. Which shadow map
//! each prop is drawn into is decided per shadow view in the render world
//! (`shadow.rs`).

use bevy::camera::primitives::{Aabb, CascadesFrusta, CubemapFrusta, Frustum, Sphere};
use bevy::camera::visibility::{RenderLayers, SetViewVisibility};
use bevy::light::NotShadowCaster;
use bevy::math::{Affine3A, Vec3A};
use bevy::prelude::*;

use super::PropSplats;

/// Marks every prop inside a shadow-casting light's shadow frusta visible.
pub(crate) fn mark_props_seen_by_lights(
    directional: Query<(
        &DirectionalLight,
        &CascadesFrusta,
        &ViewVisibility,
        Option<&RenderLayers>,
    )>,
    point: Query<(
        &PointLight,
        &GlobalTransform,
        &CubemapFrusta,
        Option<&RenderLayers>,
    )>,
    spot: Query<(
        &SpotLight,
        &GlobalTransform,
        &Frustum,
        Option<&RenderLayers>,
    )>,
    mut props: Query<
        (
            &InheritedVisibility,
            &mut ViewVisibility,
            &Aabb,
            &GlobalTransform,
            Option<&RenderLayers>,
        ),
        (
            With<PropSplats>,
            Without<NotShadowCaster>,
            Without<DirectionalLight>,
            Without<PointLight>,
            Without<SpotLight>,
        ),
    >,
) {
    let default_layers = RenderLayers::default();
    for (inherited, mut view_visibility, aabb, transform, layers) in &mut props {
        if !inherited.get() || view_visibility.get() {
            continue;
        }
        let layers = layers.unwrap_or(&default_layers);
        let affine = transform.affine();
        let seen_by_directional = directional.iter().any(|(light, frusta, visible, mask)| {
            light.shadow_maps_enabled
                && visible.get()
                && mask.unwrap_or(&default_layers).intersects(layers)
                && frusta
                    .frusta
                    .values()
                    .flatten()
                    .any(|f| f.intersects_obb(aabb, &affine, false, true))
        });
        let seen_by_point = || {
            point.iter().any(|(light, at, frusta, mask)| {
                light.shadow_maps_enabled
                    && mask.unwrap_or(&default_layers).intersects(layers)
                    && in_range(at, light.range, aabb, &affine)
                    && frusta
                        .iter()
                        .any(|f| f.intersects_obb(aabb, &affine, true, true))
            })
        };
        let seen_by_spot = || {
            spot.iter().any(|(light, at, frustum, mask)| {
                light.shadow_maps_enabled
                    && mask.unwrap_or(&default_layers).intersects(layers)
                    && in_range(at, light.range, aabb, &affine)
                    && frustum.intersects_obb(aabb, &affine, true, true)
            })
        };
        if seen_by_directional || seen_by_point() || seen_by_spot() {
            view_visibility.set_visible();
        }
    }
}

/// Whether the box `aabb` placed by `affine` meets the sphere of radius
/// `range` around the light at `at`.
fn in_range(at: &GlobalTransform, range: f32, aabb: &Aabb, affine: &Affine3A) -> bool {
    Sphere {
        center: Vec3A::from(at.translation()),
        radius: range,
    }
    .intersects_obb(aabb, affine)
}
