//! Debris: solid pieces a carve cut loose from the anchored terrain.
//!
//! After every carve the job asks the kernel for the pieces no anchor
//! holds any more ([`chisel_bsp::octree::Octree::detach_after`]: connected
//! through shared faces of positive area, found and removed exactly, with
//! exact volumes). Each piece is meshed on the worker, positioned about its
//! centre, and, with a physics backend, given a dynamic body whose
//! collider is a compound of convex hulls: the piece's convex cells (an
//! exact convex decomposition the BSP already has), merged into a few
//! hulls ([`super::debris_hulls`]). The upload spawns it as a
//! [`TerrainDebris`] entity in the frame the carve's cells change, and
//! writes a [`DebrisDetached`].
//!
//! What anchors a terrain and how much one carve may detach is the
//! terrain's [`DebrisConfig`] ([`super::Terrain::with_debris`]); a carve
//! that would detach more is rejected and changes nothing.

use std::collections::BTreeMap;

use bevy::prelude::*;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::{DebrisCell, DebrisPiece, ExactVolume};
use chisel_bsp::tree::Label;

use super::debris_hulls::collider_hulls;
use super::jobs::JobContext;
use super::mesh::cell_meshes_of;
use super::physics::{ConvexPiece, PhysicsInsert};

pub use chisel_bsp::octree::{DebrisConfig, DebrisLimits};

/// Density of debris by default, in mass units per cubic world unit
/// (rock, in kg/m³).
pub const DEFAULT_DEBRIS_DENSITY: f32 = 2500.0;

/// A piece cut loose from a terrain, spawned as an entity of its own:
/// its meshes are children ([`DebrisPart`]), and with a physics backend it
/// is a dynamic body.
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(Component, from_reflect = false)]
pub struct TerrainDebris {
    /// The terrain it came from.
    pub terrain: Entity,
    /// Its exact volume in cubic grid units.
    #[reflect(ignore)]
    pub exact_volume: ExactVolume,
    /// Its exact volume per material, in cubic grid units.
    #[reflect(ignore)]
    pub volumes: BTreeMap<Label, ExactVolume>,
    /// Its volume in cubic world units.
    pub volume: f32,
}

/// One material's mesh of a debris piece; a child of its
/// [`TerrainDebris`]. Gets the material of its label from the terrain's
/// material table, as the terrain's cells do.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component)]
pub struct DebrisPart {
    /// The terrain the piece came from.
    pub terrain: Entity,
    /// The material.
    pub label: Label,
}

/// A piece was cut loose from a terrain and spawned.
#[derive(Message, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct DebrisDetached {
    /// The terrain it came from.
    pub terrain: Entity,
    /// The debris entity ([`TerrainDebris`]).
    pub entity: Entity,
    /// Its meshes, one per material (per material and chunk for a piece
    /// across chunk borders), in the entity's frame.
    pub meshes: Vec<(Label, Handle<Mesh>)>,
    /// Where its centre was in the terrain's frame.
    pub centre: Vec3,
    /// Its volume in cubic world units.
    pub volume: f32,
    /// Its exact volume in cubic grid units.
    #[reflect(ignore)]
    pub exact_volume: ExactVolume,
    /// The material with the largest volume in it.
    pub main_label: Label,
    /// The number of the networked client's prediction whose carve cut
    /// it loose ([`super::CarveApplied::predicted`]); `None` for any
    /// other carve. The client despawns it when a roll back undoes that
    /// prediction (`bevy_chisel::net::predict`).
    pub predicted: Option<u64>,
}

/// A piece built on the worker, ready to spawn.
pub(crate) struct BuiltDebris {
    pub centre: Vec3,
    pub meshes: Vec<(Label, Mesh)>,
    pub body: Option<PhysicsInsert>,
    pub exact_volume: ExactVolume,
    pub volumes: BTreeMap<Label, ExactVolume>,
    pub volume: f32,
}

impl BuiltDebris {
    /// The material with the largest volume.
    pub fn main_label(&self) -> Label {
        self.volumes
            .iter()
            .max_by(|a, b| a.1.cmp(b.1))
            .map_or(0, |(label, _)| *label)
    }
}

/// Meshes a piece about its centre and builds its body.
pub(crate) fn build_debris(piece: &DebrisPiece, context: &JobContext) -> BuiltDebris {
    build_debris_of(&[piece], context)
}

/// Meshes the parts of one piece (its shares in neighbouring chunks of a
/// [`super::TerrainWorld`], on one grid) together about their centre, and
/// builds one body for all of them.
pub(crate) fn build_debris_of(parts: &[&DebrisPiece], context: &JobContext) -> BuiltDebris {
    let q = &context.quantization;
    let unit = q.unit();
    let cells: Vec<DebrisCell> = parts.iter().flat_map(|p| p.cells.iter().cloned()).collect();
    // The centre: the volume-weighted mean of the cells' corner averages.
    let (mut sum, mut total) = ([0.0f64; 3], 0.0f64);
    for cell in &cells {
        let v = cell.volume.to_f64();
        let n = cell.vertices.len().max(1) as f64;
        for a in 0..3 {
            sum[a] += v * cell.vertices.iter().map(|p| p[a]).sum::<f64>() / n;
        }
        total += v;
    }
    let grid_centre = if total > 0.0 {
        sum.map(|c| c / total)
    } else {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for b in parts.iter().map(|p| p.bounds) {
            for a in 0..3 {
                lo[a] = lo[a].min(b.min[a] as f64);
                hi[a] = hi[a].max(b.max[a] as f64);
            }
        }
        [0, 1, 2].map(|a| {
            if lo[a] <= hi[a] {
                0.5 * (lo[a] + hi[a])
            } else {
                0.0
            }
        })
    };
    let centre = Vec3::from_array(q.to_world(grid_centre).map(|c| c as f32));
    let local = |p: [f64; 3]| {
        let w = q.to_world(p);
        Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32) - centre
    };

    // One mesh per part and material: the parts' walls on shared chunk
    // sides meet face to face inside the piece, where nothing sees them.
    let meshes = parts
        .iter()
        .flat_map(|part| {
            let surface = SurfaceMesh::from_face_vec(part.solid.surface());
            cell_meshes_of(&surface, q, context.smoothing_degrees)
        })
        .map(|mut mesh| {
            for p in &mut mesh.positions {
                *p = (Vec3::from_array(*p) - centre).to_array();
            }
            (mesh.label, mesh.into_mesh())
        })
        .collect();

    let mut volumes: BTreeMap<Label, Vec<ExactVolume>> = BTreeMap::new();
    for part in parts {
        for (label, v) in &part.volumes {
            volumes.entry(*label).or_default().push(v.clone());
        }
    }
    let volumes: BTreeMap<Label, ExactVolume> = volumes
        .into_iter()
        .map(|(label, v)| (label, ExactVolume::sum_balanced(v)))
        .collect();
    let exact_volume = ExactVolume::sum_balanced(volumes.values().cloned().collect());
    let volume = (exact_volume.to_f64() * unit * unit * unit) as f32;
    let body = context.physics.as_ref().and_then(|physics| {
        let pieces: Vec<ConvexPiece> = collider_hulls(&cells, context.max_debris_hulls)
            .into_iter()
            .map(|corners| ConvexPiece {
                corners: corners.into_iter().map(local).collect(),
            })
            .collect();
        physics.debris_body(&pieces, volume * context.debris_density)
    });
    BuiltDebris {
        centre,
        meshes,
        body,
        exact_volume,
        volumes,
        volume,
    }
}
