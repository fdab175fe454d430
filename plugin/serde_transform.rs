//! `serde` for Bevy's `Transform` as `{ translation, rotation, scale }` (glam
//! types), for the plain-data types of the `serde` feature; Bevy's own
//! `serialize` feature is not needed.

use bevy::math::{Quat, Vec3};
use bevy::transform::components::Transform;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

#[derive(Serialize, Deserialize)]
struct Pose {
    translation: Vec3,
    rotation: Quat,
    scale: Vec3,
}

impl From<&Transform> for Pose {
    fn from(t: &Transform) -> Self {
        Self {
            translation: t.translation,
            rotation: t.rotation,
            scale: t.scale,
        }
    }
}

impl From<Pose> for Transform {
    fn from(p: Pose) -> Self {
        Self {
            translation: p.translation,
            rotation: p.rotation,
            scale: p.scale,
        }
    }
}

pub(crate) fn serialize<S: Serializer>(t: &Transform, s: S) -> Result<S::Ok, S::Error> {
    Pose::from(t).serialize(s)
}

pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Transform, D::Error> {
    Pose::deserialize(d).map(Transform::from)
}

/// The same for `Option<Transform>`.
pub(crate) mod option {
    use super::*;

    pub(crate) fn serialize<S: Serializer>(t: &Option<Transform>, s: S) -> Result<S::Ok, S::Error> {
        t.as_ref().map(Pose::from).serialize(s)
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<Transform>, D::Error> {
        Option::<Pose>::deserialize(d).map(|p| p.map(Transform::from))
    }
}
