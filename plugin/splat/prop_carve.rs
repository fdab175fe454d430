//! Carving props at runtime: a shot or a blast bites into a quadric prop
//! as it does into the terrain, and the bite is drawn as exactly as the
//! rest of the prop (per-fragment ray tracing of its quadrics).
//!
//! A [`CarveProp`] message asks for a sphere in world space to be cut
//! from one prop. The sphere is mapped into the prop's local frame through
//! its `GlobalTransform`: an affine map takes a sphere to an ellipsoid,
//! exactly a quadric (`Q_local(x) = Q_world(A·x)`), so non-uniform scale,
//! shear and mirroring carve the shape the player sees. The tool becomes a
//! [`Carve`] of that prop instance only ([`PropCarves`]): props sharing a
//! [`QuadricScene`](super::QuadricScene) asset keep their own shape, and a
//! reloaded scene file keeps the carves of each prop.
//!
//! The prop is then re-sampled on the async compute pool like an edited
//! scene ([`super::prop`]): the normal form gains the literal "outside the
//! tool" in every product ([`chisel_quadric::scene::carve`]), and
//! [`RegionSamples::resample`](chisel_quadric::sampling::partial::RegionSamples::resample)
//! samples only the regions near the tool and the tool's own surface. The
//! old splats are drawn until the new ones swap in, and then
//! [`PropCarved`] is sent. Carves asked for while a sampling runs are
//! sampled together after it. A prop collider
//! ([`prop_collider`](super::prop_collider)) is voxelized again from the
//! carved solid when the new splats come in.
//!
//! A carve that cannot be done changes nothing and sends
//! [`PropCarveRefused`] with a [`CarveRefusal`]: the entity is not a prop,
//! the prop has no splats yet, the tool is not finite or has no positive
//! radius, the prop's transform is singular, the prop has
//! [`MAX_CARVES`] carves already (each adds a literal to every product of
//! the normal form, so sampling and drawing grow with them), the tool
//! misses the prop's surface, or the sampling of the carved prop failed
//! (the carves it added are taken back).
//!
//! "Misses" is decided on the drawn splats: every surface point of the
//! prop inside its bounds has a splat within that splat's radius (the
//! sampler's coverage guarantee), so a tool whose conservative distance
//! from every splat exceeds the splat's radius cuts no visible surface —
//! it lies wholly outside the solid, or wholly inside it where it would
//! only hollow out a hidden cavity.

use bevy::prelude::*;
use chisel_quadric::scene::carve::{Carve, MAX_CARVES};
use chisel_quadric::{Quadric, QuadricDistance, affine_inverse};

use super::prop::{PropSampleError, PropSampling, PropSplats, QuadricProp};

/// The colour of the faces a carve cuts unless the message gives one: a
/// dark, raw-material grey.
pub const DEFAULT_CARVE_COLOR: Color = Color::linear_rgb(0.18, 0.17, 0.16);

/// Cut a sphere, in world space, from one prop (see the module notes).
#[derive(Message, Clone, Copy, Debug, PartialEq)]
pub struct CarveProp {
    /// The prop entity (a [`QuadricProp`]).
    pub prop: Entity,
    /// The sphere's centre, in world space.
    pub center: Vec3,
    /// The sphere's radius, in world units (positive).
    pub radius: f32,
    /// The colour of the faces it cuts.
    pub color: Color,
}

impl CarveProp {
    /// A sphere of `radius` around `center` (world space) cut from `prop`,
    /// its faces in [`DEFAULT_CARVE_COLOR`].
    #[must_use]
    pub fn sphere(prop: Entity, center: Vec3, radius: f32) -> Self {
        Self {
            prop,
            center,
            radius,
            color: DEFAULT_CARVE_COLOR,
        }
    }

    /// The same carve with its cut faces in `color`.
    #[must_use]
    pub fn with_color(self, color: Color) -> Self {
        Self { color, ..self }
    }
}

/// The splats of a prop with its carves came in: it is drawn with
/// `carves` carves now.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub struct PropCarved {
    /// The prop.
    pub prop: Entity,
    /// The carves drawn now (all since the prop was spawned).
    pub carves: usize,
}

/// A carve that was not done; the prop is unchanged.
#[derive(Message, Clone, Debug, PartialEq)]
pub struct PropCarveRefused {
    /// The entity the carve was for.
    pub prop: Entity,
    /// Why.
    pub reason: CarveRefusal,
}

/// Why a [`CarveProp`] was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CarveRefusal {
    /// The entity is not a [`QuadricProp`] (or does not exist).
    #[error("the entity is not a quadric prop")]
    NotAProp,
    /// The prop has no splats yet: carve once it is drawn.
    #[error("the prop is not sampled yet; carve once it is drawn")]
    NotSampled,
    /// The centre or the radius is NaN or infinite.
    #[error("the carve's centre or radius is not finite")]
    NonFinite,
    /// The radius is zero or negative.
    #[error("the carve's radius {radius} is not positive")]
    DegenerateRadius {
        /// The radius given.
        radius: f32,
    },
    /// The prop's transform has no inverse (a zero scale).
    #[error("the prop's transform is singular (a zero scale)")]
    SingularTransform,
    /// The prop has as many carves as it may have.
    #[error("the prop has {limit} carves already, its limit")]
    LimitReached {
        /// The limit, [`MAX_CARVES`].
        limit: usize,
    },
    /// The tool reaches no surface of the prop.
    #[error("the carve misses the prop's surface")]
    Misses,
    /// Sampling the carved prop failed; the carves it added were taken
    /// back.
    #[error("sampling the carved prop failed: {0}")]
    Sampling(PropSampleError),
}

/// The carves of one prop instance, in its local frame (every
/// [`QuadricProp`] has one, empty until a [`CarveProp`] is done).
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct PropCarves {
    carves: Vec<Carve>,
    /// How many of them the splats drawn now include.
    drawn: usize,
}

impl PropCarves {
    /// Every carve accepted so far, in order (local frame), drawn or
    /// still being sampled.
    #[must_use]
    pub fn carves(&self) -> &[Carve] {
        &self.carves
    }

    /// The carves the splats drawn now include (the first
    /// [`drawn`](Self::drawn) of [`carves`](Self::carves)).
    #[must_use]
    pub fn drawn(&self) -> usize {
        self.drawn
    }

    /// The carves a sampling started now includes.
    pub(crate) fn snapshot(&self) -> Vec<Carve> {
        self.carves.clone()
    }

    /// A sampling of the first `n` carves came in: `Some(n)` when that is
    /// news.
    pub(crate) fn sampled(&mut self, n: usize) -> Option<usize> {
        let news = n != self.drawn;
        self.drawn = n;
        news.then_some(n)
    }

    /// A sampling of the first `n` carves failed: the carves it added
    /// (after the drawn ones) are taken back; returns how many.
    pub(crate) fn failed(&mut self, n: usize) -> usize {
        let end = n.min(self.carves.len());
        if end <= self.drawn {
            return 0;
        }
        self.carves.drain(self.drawn..end);
        end - self.drawn
    }
}

/// The tool of `carve` in the local frame of a prop placed by `transform`.
fn local_tool(carve: &CarveProp, transform: &GlobalTransform) -> Result<Quadric, CarveRefusal> {
    if !carve.center.is_finite() || !carve.radius.is_finite() {
        return Err(CarveRefusal::NonFinite);
    }
    if carve.radius <= 0.0 {
        return Err(CarveRefusal::DegenerateRadius {
            radius: carve.radius,
        });
    }
    let world = Quadric::sphere(carve.center.as_dvec3(), f64::from(carve.radius))
        .map_err(|_| CarveRefusal::NonFinite)?;
    let m = transform.to_matrix().as_dmat4();
    affine_inverse(&m).map_err(|_| CarveRefusal::SingularTransform)?;
    // Q_local(x) = Q_world(M x): the matrix Mᵀ Q M, made exactly symmetric.
    let q = m.transpose() * world.matrix() * m;
    let sym = (q + q.transpose()) * 0.5;
    Quadric::from_matrix(sym).map_err(|_| CarveRefusal::SingularTransform)
}

/// Whether `tool` (local frame) comes within a splat's radius of any of
/// the prop's splats (see the module notes).
fn reaches_surface(tool: &Quadric, splats: &PropSplats) -> bool {
    let distance = QuadricDistance::new(tool);
    splats.0.splats.iter().any(|s| {
        let d = distance.distance(s.position.as_dvec3());
        // The stored position's f32 rounding, and a margin.
        let slack = 1e-6 * s.position.abs().max_element().max(1.0);
        d <= f64::from(s.radius) * 1.001 + f64::from(slack)
    })
}

/// Takes the [`CarveProp`] messages: each one is refused or added to its
/// prop's [`PropCarves`], and the prop re-sampled.
pub(crate) fn apply_carves(
    mut requests: MessageReader<CarveProp>,
    mut refused: MessageWriter<PropCarveRefused>,
    mut props: Query<
        (
            &GlobalTransform,
            Option<&PropSplats>,
            Option<&mut PropSampling>,
            &mut PropCarves,
        ),
        With<QuadricProp>,
    >,
) {
    for carve in requests.read() {
        let mut refuse = |reason| {
            refused.write(PropCarveRefused {
                prop: carve.prop,
                reason,
            });
        };
        let Ok((transform, splats, sampling, mut carves)) = props.get_mut(carve.prop) else {
            refuse(CarveRefusal::NotAProp);
            continue;
        };
        let (Some(splats), Some(mut sampling)) = (splats, sampling) else {
            refuse(CarveRefusal::NotSampled);
            continue;
        };
        let tool = match local_tool(carve, transform) {
            Ok(tool) => tool,
            Err(reason) => {
                refuse(reason);
                continue;
            }
        };
        if carves.carves.len() >= MAX_CARVES {
            refuse(CarveRefusal::LimitReached { limit: MAX_CARVES });
            continue;
        }
        if !reaches_surface(&tool, splats) {
            refuse(CarveRefusal::Misses);
            continue;
        }
        let c = carve.color.to_linear();
        carves
            .carves
            .push(Carve::new(tool, [c.red, c.green, c.blue]));
        sampling.request();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::math::DVec3;

    #[test]
    fn a_scaled_prop_gets_the_ellipsoid_of_the_sphere() {
        let transform = GlobalTransform::from(
            Transform::from_xyz(1.0, 2.0, 3.0)
                .with_rotation(Quat::from_rotation_y(0.7))
                .with_scale(Vec3::new(2.0, 0.5, -1.5)),
        );
        let carve = CarveProp::sphere(Entity::PLACEHOLDER, Vec3::new(2.0, 1.0, 0.0), 1.5);
        let tool = local_tool(&carve, &transform).expect("tool");
        let m = transform.to_matrix().as_dmat4();
        // Points on the world sphere are on the local surface, points
        // inside it inside.
        for k in 0..50 {
            let t = f64::from(k) * 0.37;
            let dir = DVec3::new(
                t.cos() * (2.0 * t).sin(),
                t.sin() * (2.0 * t).sin(),
                (2.0 * t).cos(),
            );
            let world = carve.center.as_dvec3() + dir * f64::from(carve.radius);
            let local = m.inverse().transform_point3(world);
            assert!(tool.value(local).abs() < 1e-9, "{k}: {}", tool.value(local));
            let inside = m
                .inverse()
                .transform_point3(carve.center.as_dvec3() + dir * 1.4);
            assert!(tool.value(inside) < 0.0);
            let outside = m
                .inverse()
                .transform_point3(carve.center.as_dvec3() + dir * 1.6);
            assert!(tool.value(outside) > 0.0);
        }
    }

    #[test]
    fn bad_tools_are_refused() {
        let t = GlobalTransform::IDENTITY;
        let carve = |center, radius| CarveProp::sphere(Entity::PLACEHOLDER, center, radius);
        assert_eq!(
            local_tool(&carve(Vec3::NAN, 1.0), &t),
            Err(CarveRefusal::NonFinite)
        );
        assert_eq!(
            local_tool(&carve(Vec3::ZERO, f32::INFINITY), &t),
            Err(CarveRefusal::NonFinite)
        );
        assert_eq!(
            local_tool(&carve(Vec3::ZERO, 0.0), &t),
            Err(CarveRefusal::DegenerateRadius { radius: 0.0 })
        );
        let flat = GlobalTransform::from(Transform::from_scale(Vec3::new(1.0, 0.0, 1.0)));
        assert_eq!(
            local_tool(&carve(Vec3::ZERO, 1.0), &flat),
            Err(CarveRefusal::SingularTransform)
        );
    }

    #[test]
    fn failed_samplings_take_their_carves_back() {
        let tool = Carve::new(Quadric::sphere(DVec3::ZERO, 1.0).expect("sphere"), [0.0; 3]);
        let mut carves = PropCarves {
            carves: vec![tool; 3],
            drawn: 1,
        };
        // A sampling of two carves failed while a third one waits.
        assert_eq!(carves.failed(2), 1);
        assert_eq!((carves.carves().len(), carves.drawn()), (2, 1));
        assert_eq!(carves.sampled(2), Some(2));
        assert_eq!(carves.sampled(2), None);
        assert_eq!(carves.failed(2), 0);
    }
}
