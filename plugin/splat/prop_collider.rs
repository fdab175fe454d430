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
//! come in (so a changed scene gets a new collider too); an engine's plugin
//! ([`super::avian::PropAvianPlugin`], [`super::rapier::PropRapierPlugin`])
//! turns them into its static voxel collider on the prop entity, which the
//! engine scales and places with the entity's transform.

use bevy::ecs::system::EntityCommands;
use bevy::math::DVec3;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task, futures::check_ready};
use chisel_quadric::Dnf;

use super::prop::{PropBounds, PropSplats, QuadricProp, QuadricScene};

/// Voxels along each edge of a prop's bounding cube, unless the engine's
/// plugin says otherwise.
pub const DEFAULT_RESOLUTION: u32 = 48;

/// Makes an engine's static collider of a prop's voxels on its entity;
/// `false` when it cannot (no voxel).
pub type InsertCollider = fn(&PropVoxels, &mut EntityCommands) -> bool;

/// Adds the voxelization systems, with `insert` making the engine's
/// collider and `resolution` voxels along each edge (at least 2).
pub fn add_prop_colliders(app: &mut App, resolution: u32, insert: InsertCollider) {
    app.insert_resource(PropColliderSettings {
        resolution: resolution.max(2),
        insert,
    })
    .register_type::<PropCollider>()
    .add_systems(Update, (start_colliders, finish_colliders).chain());
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

#[derive(Component)]
struct PropColliderTask(Task<Result<PropVoxels, chisel_quadric::Error>>);

/// The solid voxels of a prop in its local frame: voxel `k` spans
/// `[k·size, (k+1)·size]` on each axis.
#[derive(Clone, Debug, PartialEq)]
pub struct PropVoxels {
    /// Edge length of a voxel.
    pub size: f32,
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
            size: size as f32,
            cells,
        }
    }
}

/// Starts a voxelization for every prop whose splats came in or changed.
fn start_colliders(
    settings: Res<PropColliderSettings>,
    scenes: Res<Assets<QuadricScene>>,
    props: Query<(Entity, &QuadricProp), Changed<PropSplats>>,
    mut commands: Commands,
) {
    for (entity, prop) in &props {
        let Some(scene) = scenes.get(&prop.scene) else {
            continue;
        };
        let Some(bounds) = PropBounds::resolve(prop.bounds, &scene.0) else {
            continue;
        };
        let scene = scene.0.clone();
        let resolution = settings.resolution;
        let task = AsyncComputeTaskPool::get().spawn(async move {
            let dnf = scene.dnf()?;
            Ok(PropVoxels::of_solid(&dnf, bounds, resolution))
        });
        commands.entity(entity).insert(PropColliderTask(task));
    }
}

/// Inserts the finished colliders.
fn finish_colliders(
    settings: Res<PropColliderSettings>,
    mut tasks: Query<(Entity, &mut PropColliderTask)>,
    mut commands: Commands,
) {
    for (entity, mut task) in &mut tasks {
        let Some(result) = check_ready(&mut task.0) else {
            continue;
        };
        let mut prop = commands.entity(entity);
        prop.remove::<PropColliderTask>();
        match result {
            Ok(voxels) => {
                if (settings.insert)(&voxels, &mut prop) {
                    prop.insert(PropCollider {
                        voxels: voxels.cells.len(),
                        voxel_size: voxels.size,
                    });
                } else {
                    warn!(
                        "quadric prop {entity}: no voxel centre is inside the solid; it gets no \
                         collider (raise the prop collider plugin's resolution)"
                    );
                }
            }
            Err(e) => error!("quadric prop {entity}: no collider: {e}"),
        }
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
        let volume = v.cells.len() as f64 * f64::from(v.size).powi(3);
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
