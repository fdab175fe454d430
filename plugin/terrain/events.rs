//! Entity events beside the messages: the reports of [`super::carve`],
//! triggered on the terrain entity so that an observer on one terrain
//! (`commands.entity(terrain).observe(..)`) or on all of them
//! (`app.add_observer(..)`) hears about its carves.
//!
//! ```
//! use bevy::prelude::*;
//! use bevy_chisel::terrain::{TerrainCarved, TerrainCellRebuilt};
//!
//! fn watch(mut commands: Commands, terrain: Entity) {
//!     commands
//!         .entity(terrain)
//!         .observe(|carved: On<TerrainCarved>| {
//!             info!("{} cells changed in {:?}", carved.report.cells, carved.report.latency);
//!         })
//!         .observe(|cell: On<TerrainCellRebuilt>| {
//!             info!("cell {:?} now has {} meshes", cell.change.key, cell.change.entities.len());
//!         });
//! }
//! # let _ = watch;
//! ```

use bevy::prelude::*;

use super::carve::{CarveApplied, CarveRejected, TerrainCellChanged};
use super::debris::DebrisDetached;

/// A carve (or undo) of this terrain is applied and its meshes and
/// colliders are in place: the [`CarveApplied`] message, as an entity event.
#[derive(EntityEvent, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct TerrainCarved {
    /// The terrain entity.
    pub entity: Entity,
    /// The report.
    pub report: CarveApplied,
}

/// A carve or undo of this terrain was refused and the terrain is
/// unchanged: the [`CarveRejected`] message, as an entity event.
#[derive(EntityEvent, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct TerrainCarveRejected {
    /// The terrain entity.
    pub entity: Entity,
    /// The refusal.
    pub rejection: CarveRejected,
}

/// One leaf cell of this terrain was rebuilt or removed: the
/// [`TerrainCellChanged`] message, as an entity event.
#[derive(EntityEvent, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct TerrainCellRebuilt {
    /// The terrain entity.
    pub entity: Entity,
    /// The cell and its entities now.
    pub change: TerrainCellChanged,
}

/// A piece broke off this terrain: the [`DebrisDetached`] message, as an
/// entity event.
#[derive(EntityEvent, Reflect, Clone, Debug)]
#[reflect(from_reflect = false)]
pub struct TerrainDebrisDetached {
    /// The terrain entity.
    pub entity: Entity,
    /// The piece.
    pub debris: DebrisDetached,
}

/// Triggers the entity events of the messages written this frame (after
/// [`super::TerrainSystems::Mesh`]). Terrains that were despawned in the
/// meantime are skipped.
pub(crate) fn trigger_events(
    mut applied: MessageReader<CarveApplied>,
    mut rejected: MessageReader<CarveRejected>,
    mut cells: MessageReader<TerrainCellChanged>,
    mut debris: MessageReader<DebrisDetached>,
    exists: Query<()>,
    mut commands: Commands,
) {
    for change in cells.read() {
        if exists.contains(change.terrain) {
            commands.trigger(TerrainCellRebuilt {
                entity: change.terrain,
                change: change.clone(),
            });
        }
    }
    for piece in debris.read() {
        if exists.contains(piece.terrain) {
            commands.trigger(TerrainDebrisDetached {
                entity: piece.terrain,
                debris: piece.clone(),
            });
        }
    }
    for report in applied.read() {
        if exists.contains(report.terrain) {
            commands.trigger(TerrainCarved {
                entity: report.terrain,
                report: report.clone(),
            });
        }
    }
    for rejection in rejected.read() {
        if exists.contains(rejection.terrain) {
            commands.trigger(TerrainCarveRejected {
                entity: rejection.terrain,
                rejection: rejection.clone(),
            });
        }
    }
}
