//! Prop colliders, whatever the physics engine: the voxels of a quadric
//! CSG prop's solid, computed off the main thread.
//!
//! A quadric CSG prop has no mesh to hand a physics engine, but its solid
//! is known exactly: [`chisel_quadric::Dnf::contains`] decides for any point
//! whether it is inside. The prop's bounding cube is divided into
//! `resolution`³ voxels, and a voxel is solid when its centre is inside the
//! solid. Holes, arches and hollows larger than a voxel stay open, so a
//! player walks through a ring and bumps into a cube's edge where it is
//! drawn; the collider's surface lies within half a voxel diagonal of the
//! drawn one. Features thinner than a voxel may be missed: raise the
//! resolution for such props.
//!
//! The voxels are computed on the async compute pool when a prop's splats
//! come in (so a changed scene, or a carved prop, gets a new collider too:
//! the voxels are those of the solid with the carves its splats include,
//! [`super::prop_carve`]); an engine's plugin
//! ([`super::avian::PropAvianPlugin`], [`super::rapier::PropRapierPlugin`])
//! turns them into its static voxel collider.
//!
//! The collider sits on a child of the prop, a [`PropColliderShape`],
//! whose transform undoes the prop's scale: the voxels are fitted to that
//! scale here, exactly (edges `size·|s|` per axis, the cells of a mirrored
//! axis mirrored), so the engine places them by the prop's rotation and
//! translation and never scales a voxel shape itself. (avian3d 0.7 scales
//! a voxel collider's voxels but not the boxes of their chunks, and a
//! scaled prop then misses contacts.) When the prop's scale changes the
//! voxels are fitted again, with no new voxelization; a prop with a zero
//! scale is not drawn and has no collider. Contacts name the shape entity:
//! its [`ChildOf`] is the prop.

use std::sync::Arc;

use bevy::ecs::system::EntityCommands;
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};
use chisel_quadric::Dnf;

use super::prop::{PropBounds, PropSplats, QuadricProp, QuadricScene};
use super::prop_carve::PropCarves;

/// Voxels along each edge of a prop's bounding cube, unless the engine's
/// plugin says otherwise.
pub const DEFAULT_RESOLUTION: u32 = 48;

/// Makes an engine's static collider of a prop's voxels on the prop's
/// [`PropColliderShape`] entity (the voxels fitted to the prop's scale);
/// `false` when it cannot (no voxel).
pub type InsertCollider = fn(&PropVoxels, &mut EntityCommands) -> bool;

/// A prop's scale is taken for zero, and the prop gets no collider, below
/// this on any axis.
const MIN_SCALE: f32 = 1e-6;

/// A prop's scale differs from the one its collider is fitted to when it
/// moves by more than this fraction of its largest axis.
const SCALE_TOLERANCE: f32 = 1e-5;

/// Adds the voxelization systems, with `insert` making the engine's
/// collider and `resolution` voxels along each edge (at least 2).
pub fn add_prop_colliders(app: &mut App, resolution: u32, insert: InsertCollider) {
    app.insert_resource(PropColliderSettings {
        resolution: resolution.max(2),
        insert,
    })
    .register_type::<PropCollider>()
    .register_type::<PropColliderShape>()
    .add_systems(
        Update,
        (start_colliders, finish_colliders, fit_colliders).chain(),
    );
}

/// As given to [`add_prop_colliders`], for the systems.
#[derive(Resource, Clone, Copy)]
struct PropColliderSettings {
    resolution: u32,
    insert: InsertCollider,
}

/// A prop's collider is in place: how many voxels it has and their edge
/// length in the prop's local units.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct PropCollider {
    /// Solid voxels.
    pub voxels: usize,
    /// Edge length of a voxel (local units).
    pub voxel_size: f32,
}

/// The child of a prop that carries its collider: its transform is the
/// inverse of `scale`, and its collider the prop's voxels fitted to it.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component)]
pub struct PropColliderShape {
    /// The prop's scale (from its `GlobalTransform`) the voxels are fitted
    /// to.
    pub scale: Vec3,
}

#[derive(Component)]
struct PropColliderTask(Task<Result<PropVoxels, chisel_quadric::Error>>);

/// A prop's voxels in its local frame, and the shape entity made of them.
#[derive(Component)]
struct PropColliderVoxels {
    voxels: Arc<PropVoxels>,
    shape: Option<Entity>,
}

/// The solid voxels of a prop: voxel `k` spans `[k·size, (k+1)·size]`
/// (component by component).
#[derive(Clone, Debug, PartialEq)]
pub struct PropVoxels {
    /// Edge lengths of a voxel along x, y and z (equal in the prop's local
    /// frame).
    pub size: Vec3,
    /// Grid coordinates of the solid voxels.
    pub cells: Vec<IVec3>,
}

impl PropVoxels {
    /// The voxels of `dnf`'s solid inside the cube around `bounds`, with
    /// `resolution` voxels along each edge: a voxel is solid when its
    /// centre is inside.
    #[must_use]
    pub fn of_solid(dnf: &Dnf, bounds: PropBounds, resolution: u32) -> Self {
        let n = resolution.max(2);
        let size = 2.0 * f64::from(bounds.radius) / f64::from(n);
        let centre = bounds.centre.as_dvec3();
        // The cube's lowest voxel, in grid coordinates.
        let low = ((centre - DVec3::splat(f64::from(bounds.radius))) / size).floor();
        let mut cells = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let key = low + DVec3::new(f64::from(i), f64::from(j), f64::from(k));
                    if dnf.contains((key + DVec3::splat(0.5)) * size) {
                        cells.push(key.as_ivec3());
                    }
                }
            }
        }
        Self {
            size: Vec3::splat(size as f32),
            cells,
        }
    }

    /// These voxels in a frame scaled by `scale` along their axes: edges
    /// `size·|scale|`, and along an axis whose scale is negative voxel
    /// `k` becomes `-k - 1` (its mirror image). `None` when a scale is
    /// not finite or below `1e-6` in size (nothing to collide with).
    #[must_use]
    pub fn scaled(&self, scale: Vec3) -> Option<Self> {
        if !scale.is_finite() || scale.abs().min_element() < MIN_SCALE {
            return None;
        }
        let mirror = |k: i32, s: f32| if s < 0.0 { -k - 1 } else { k };
        let cells = self
            .cells
            .iter()
            .map(|k| {
                IVec3::new(
                    mirror(k.x, scale.x),
                    mirror(k.y, scale.y),
                    mirror(k.z, scale.z),
                )
            })
            .collect();
        Some(Self {
            size: self.size * scale.abs(),
            cells,
        })
    }
}

/// Starts a voxelization for every prop whose splats came in or changed.
fn start_colliders(
    settings: Res<PropColliderSettings>,
    scenes: Res<Assets<QuadricScene>>,
    props: Query<(Entity, &QuadricProp, Option<&PropCarves>), Changed<PropSplats>>,
    mut commands: Commands,
) {
    for (entity, prop, carves) in &props {
        let Some(scene) = scenes.get(&prop.scene) else {
            continue;
        };
        let Some(bounds) = PropBounds::resolve(prop.bounds, &scene.0) else {
            continue;
        };
        let scene = scene.0.clone();
        // The carves the new splats include.
        let carves = carves.map_or_else(Vec::new, |c| c.carves()[..c.drawn()].to_vec());
        let resolution = settings.resolution;
        let task = AsyncComputeTaskPool::get().spawn(async move {
            let dnf = scene.carved(&carves)?.dnf()?;
            Ok(PropVoxels::of_solid(&dnf, bounds, resolution))
        });
        commands.entity(entity).insert(PropColliderTask(task));
    }
}

/// Takes in the finished voxelizations: the prop keeps its voxels (and
/// loses the shape made of earlier ones); [`fit_colliders`] makes the
/// collider.
fn finish_colliders(
    mut tasks: Query<(Entity, &mut PropColliderTask, Option<&PropColliderVoxels>)>,
    mut commands: Commands,
) {
    for (entity, mut task, held) in &mut tasks {
        // Polling is no change of the component.
        let Some(result) = check_ready(&mut task.bypass_change_detection().0) else {
            continue;
        };
        let mut prop = commands.entity(entity);
        prop.remove::<PropColliderTask>();
        let voxels = match result {
            Ok(voxels) => voxels,
            Err(e) => {
                error!("quadric prop {entity}: no collider: {e}");
                continue;
            }
        };
        if let Some(shape) = held.and_then(|held| held.shape) {
            commands.entity(shape).try_despawn();
        }
        let mut prop = commands.entity(entity);
        if voxels.cells.is_empty() {
            warn!(
                "quadric prop {entity}: no voxel centre is inside the solid; it gets no \
                 collider (raise the prop collider plugin's resolution)"
            );
            prop.remove::<(PropColliderVoxels, PropCollider)>();
            continue;
        }
        prop.insert((
            PropCollider {
                voxels: voxels.cells.len(),
                voxel_size: voxels.size.x,
            },
            PropColliderVoxels {
                voxels: Arc::new(voxels),
                shape: None,
            },
        ));
    }
}

/// Gives each prop with voxels a shape entity fitted to its scale, and
/// fits it again when the scale changed (removes it at a zero scale).
fn fit_colliders(
    settings: Res<PropColliderSettings>,
    mut props: Query<(Entity, &GlobalTransform, &mut PropColliderVoxels)>,
    shapes: Query<&PropColliderShape>,
    mut commands: Commands,
) {
    for (prop, global, mut held) in &mut props {
        let (scale, _, _) = global.to_scale_rotation_translation();
        let shape = held.shape.filter(|&shape| shapes.contains(shape));
        // A moving or turning prop's decomposed scale wobbles in its last
        // bits: refit only for a change the voxels could show.
        let fitted = shape.and_then(|shape| shapes.get(shape).ok());
        if fitted.is_some_and(|s| {
            s.scale
                .abs_diff_eq(scale, SCALE_TOLERANCE * scale.abs().max_element())
        }) {
            continue;
        }
        let Some(fitted) = held.voxels.scaled(scale) else {
            if let Some(shape) = held.shape.take() {
                commands.entity(shape).try_despawn();
            }
            continue;
        };
        let shape = shape.unwrap_or_else(|| commands.spawn(ChildOf(prop)).id());
        held.shape = Some(shape);
        let transform = Transform::from_scale(scale.recip());
        let mut shape = commands.entity(shape);
        // The global transform too, so that an engine that creates the body
        // before transforms propagate places it right.
        shape.insert((
            PropColliderShape { scale },
            transform,
            global.mul_transform(transform),
            Name::new("prop collider"),
        ));
        (settings.insert)(&fitted, &mut shape);
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use chisel_quadric::Scene;

    const SPHERE: &str = r#"Scene(
        primitives: [(name: "A", shape: Sphere(center: (0, 0, 0), radius: 10))],
        root: Ref("A"),
    )"#;

    const RING: &str = r#"Scene(
        primitives: [
            (name: "outer", shape: Cylinder(point: (0, 0, 0), axis: (0, 0, 1), radius: 10)),
            (name: "inner", shape: Cylinder(point: (0, 0, 0), axis: (0, 0, 1), radius: 5)),
            (name: "slab", shape: Box(min: (-20, -20, -2), max: (20, 20, 2))),
        ],
        root: Difference([Intersection([Ref("outer"), Ref("slab")]), Ref("inner")]),
    )"#;

    fn voxels(text: &str, radius: f32, resolution: u32) -> PropVoxels {
        let scene = Scene::from_ron(text).expect("valid scene");
        let dnf = scene.dnf().expect("normal form");
        let bounds = PropBounds {
            centre: Vec3::ZERO,
            radius,
        };
        PropVoxels::of_solid(&dnf, bounds, resolution)
    }

    #[test]
    fn a_sphere_fills_its_volume_within_a_voxel() {
        let v = voxels(SPHERE, 12.0, 48);
        let volume = v.cells.len() as f64 * f64::from(v.size.x).powi(3);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 1000.0;
        assert!(
            (volume / exact - 1.0).abs() < 0.05,
            "voxel volume {volume} vs {exact}"
        );
        // Every solid voxel's centre is inside, and the sphere's own
        // centre is solid.
        for c in &v.cells {
            let centre = (c.as_vec3() + Vec3::splat(0.5)) * v.size;
            assert!(centre.length() < 10.0);
        }
        let origin = (Vec3::ZERO / v.size).floor().as_ivec3();
        assert!(v.cells.contains(&origin));
    }

    /// The voxels of a ring: radii 5 to 10 around the z axis, 4 thick.
    pub(in crate::splat) fn ring_voxels() -> PropVoxels {
        voxels(RING, 12.0, 48)
    }

    #[test]
    fn scaled_voxels_are_the_voxels_scaled_and_mirrored() {
        let v = ring_voxels();
        let scale = Vec3::new(-2.0, 0.5, -0.25);
        let fitted = v.scaled(scale).expect("an invertible scale");
        assert_eq!(fitted.size, v.size * scale.abs());
        assert_eq!(fitted.cells.len(), v.cells.len());
        for (k, fitted_k) in v.cells.iter().zip(&fitted.cells) {
            let centre = (k.as_vec3() + Vec3::splat(0.5)) * v.size * scale;
            let fitted_centre = (fitted_k.as_vec3() + Vec3::splat(0.5)) * fitted.size;
            assert!(
                (centre - fitted_centre).abs().max_element() < 1e-4,
                "voxel {k}: {centre} against {fitted_centre}"
            );
        }
        assert_eq!(v.scaled(Vec3::ONE).as_ref(), Some(&v));
    }

    #[test]
    fn a_zero_or_broken_scale_has_no_voxels() {
        let v = ring_voxels();
        assert!(v.scaled(Vec3::new(1.0, 0.0, 1.0)).is_none());
        assert!(v.scaled(Vec3::new(1.0, 1.0, -1e-9)).is_none());
        assert!(v.scaled(Vec3::new(f32::NAN, 1.0, 1.0)).is_none());
        assert!(v.scaled(Vec3::splat(f32::INFINITY)).is_none());
    }

    #[test]
    fn a_ring_keeps_its_hole_open() {
        let v = ring_voxels();
        assert!(!v.cells.is_empty());
        for c in &v.cells {
            let centre = (c.as_vec3() + Vec3::splat(0.5)) * v.size;
            let r = centre.truncate().length();
            assert!((5.0..10.0).contains(&r), "voxel at radius {r}");
            assert!(centre.z.abs() < 2.0);
        }
    }
}
