//! The [`Terrain`] component and the components of its cells: data only.
//!
//! A terrain holds its octree with its grid, the record of what it was
//! built from, the journal of carves and the undo history; its work in
//! progress (queued requests, the running job, cells waiting to be shown)
//! is the job runtime's (module `jobs`), kept in the component so that
//! it travels with the terrain entity. Carving runs from the messages in
//! [`super::carve`] through the systems of [`super::queue`] and
//! [`super::upload`]; [`Terrain::apply_now`] is the synchronous twin for
//! code outside the ECS.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::sync::Arc;

use bevy::prelude::*;
use chisel_bsp::octree::{CellKey, Changes, DebrisConfig, Edit, Octree, OctreeConfig, StateHash};
use chisel_bsp::tools::Quantization;
use chisel_bsp::tree::Label;

use super::base::TerrainBase;
use super::error::TerrainError;
use super::jobs::{Runtime, apply_carve};
use super::tool::GridTool;

/// One carve in a terrain's record: the exact tool and the edit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct JournalEntry {
    /// The tool on the grid.
    pub tool: GridTool,
    /// What the carve did.
    pub edit: Edit,
}

/// The state before one carve, kept for undo.
#[derive(Clone, Debug)]
pub(crate) struct UndoStep {
    pub(crate) before: Octree,
    pub(crate) changes: Changes,
    /// The number of the networked client's prediction this carve was
    /// (`None` for any other carve).
    pub(crate) predicted: Option<u64>,
    /// A prediction's carve: the redo steps it cleared, back when it is
    /// taken back, so that a roll back leaves the redo steps as they were
    /// (empty for any other carve).
    pub(crate) redo: Vec<RedoStep>,
}

/// The state after one undone carve, kept for redo: the octree the undo
/// took back (bit-identical to the one after the carve), the cells it
/// changed and the journal entry it took out.
#[derive(Clone, Debug)]
pub(crate) struct RedoStep {
    pub(crate) after: Octree,
    pub(crate) changes: Changes,
    pub(crate) entry: Option<JournalEntry>,
}

/// Destructible terrain: a persistent octree of exact BSPs on an integer
/// grid, with one child entity per (leaf cell, material) that has a
/// visible surface ([`TerrainCell`]).
///
/// Coordinates of tools, rays and meshes are in the terrain's local frame;
/// the [`Quantization`] maps them to the grid. Carve with the
/// [`super::Carve`] message; undo with [`super::UndoCarve`] and redo what
/// was undone with [`super::RedoCarve`].
///
/// # Change detection
///
/// `Changed<Terrain>` (and `Ref::is_changed`) marks the frames in which
/// what a game reads of the terrain's content changed: its octree, state
/// hash, journal, undo history or [`Terrain::last_request`] (a carve
/// applied, a tracked carve refused, an undo, solid a detach across chunk
/// borders took out or a world undo gave back), its material labels
/// ([`Terrain::material_labels`]), the component inserted again (a
/// snapshot or file loaded), and any write of the game's own through
/// `&mut Terrain`. The plugin's bookkeeping marks nothing: requests queued,
/// jobs started and polled, cells and meshes shown
/// ([`Terrain::cells`], [`Terrain::triangle_count`], [`Terrain::is_idle`]
/// follow [`super::TerrainCellChanged`] and [`super::CarveApplied`]
/// instead), seams sealed again. A settled terrain is never marked; a
/// carve marks the frame its octree is swapped in, an undo or redo the
/// frame it is applied, before their meshes are shown (the same or a later frame).
#[derive(Component, Reflect)]
#[reflect(Component, from_reflect = false)]
#[require(Transform)]
#[cfg_attr(feature = "render", require(Visibility))]
pub struct Terrain {
    #[reflect(ignore)]
    pub(crate) octree: Octree,
    #[reflect(ignore)]
    pub(crate) quantization: Quantization,
    #[reflect(ignore)]
    pub(crate) base: Arc<TerrainBase>,
    #[reflect(ignore)]
    pub(crate) journal: Vec<JournalEntry>,
    #[reflect(ignore)]
    pub(crate) history: VecDeque<UndoStep>,
    /// The carves undone since the last carve, the latest last.
    #[reflect(ignore)]
    pub(crate) redo: Vec<RedoStep>,
    #[reflect(ignore)]
    pub(crate) max_undo: usize,
    #[reflect(ignore)]
    pub(crate) debris: Option<DebrisConfig>,
    /// The materials carves may add or paint.
    #[reflect(ignore)]
    pub(crate) labels: BTreeSet<Label>,
    /// The state hash of `octree`, kept up to date per carve.
    #[reflect(ignore)]
    pub(crate) hash: StateHash,
    /// The request id of the latest tracked carve ([`super::GridCarve`])
    /// the octree includes, applied or refused.
    #[reflect(ignore)]
    pub(crate) last_request: Option<u64>,
    #[reflect(ignore)]
    pub(crate) runtime: Runtime,
    /// Whether a detach across chunk borders took solid out of it
    /// (a chunk of a [`super::TerrainWorld`]): it then differs from its
    /// source even with no carve of its own.
    #[reflect(ignore)]
    pub(crate) detached_across: bool,
}

/// Undo steps kept by default.
pub const DEFAULT_MAX_UNDO: usize = 64;

impl Terrain {
    /// A terrain built from `base` on the grid `quantization`.
    ///
    /// # Errors
    /// As [`TerrainBase::build`].
    pub fn from_base(
        quantization: Quantization,
        base: TerrainBase,
        config: OctreeConfig,
    ) -> Result<Self, TerrainError> {
        let octree = base.build(config)?;
        Ok(Self {
            hash: StateHash::of(&octree),
            last_request: None,
            octree,
            quantization,
            debris: Some(base.debris_config()),
            labels: base.labels(),
            base: Arc::new(base),
            journal: Vec::new(),
            history: VecDeque::new(),
            redo: Vec::new(),
            max_undo: DEFAULT_MAX_UNDO,
            runtime: Runtime::default(),
            detached_across: false,
        })
    }

    /// Keeps at most `steps` carves for undo (older snapshots are dropped).
    #[must_use]
    pub fn with_max_undo(mut self, steps: usize) -> Self {
        self.max_undo = steps;
        while self.history.len() > steps {
            self.history.pop_front();
        }
        self
    }

    /// What anchors the terrain and how much one carve may cut loose
    /// (`None`: pieces cut loose stay where they are, part of the terrain).
    /// The default anchors whatever has volume in the lowest grid layer of
    /// the base solid ([`TerrainBase::debris_config`]), with no limit.
    #[must_use]
    pub fn with_debris(mut self, config: Option<DebrisConfig>) -> Self {
        self.debris = config;
        self
    }

    /// Refuses carves that would cut loose more than `volume` cubic world
    /// units of debris in one go ([`chisel_bsp::Error::TooMuchDebris`]).
    /// Does nothing when debris detection is off.
    #[must_use]
    pub fn with_max_debris_volume(mut self, volume: f64) -> Self {
        let unit = self.quantization.unit();
        if let Some(config) = &mut self.debris {
            let grid = (volume / (unit * unit * unit)).max(0.0);
            config.max_volume = Some(if grid.is_finite() && grid < u128::MAX as f64 {
                grid as u128
            } else {
                u128::MAX
            });
        }
        self
    }

    /// Declares more materials that carves may add or paint. A terrain
    /// knows the labels of its base ([`TerrainBase::labels`]) and these;
    /// an [`Edit::Add`] or [`Edit::Paint`] of any other label is rejected
    /// with [`TerrainError::UnknownLabel`] and changes nothing. A loaded
    /// terrain knows its base's labels and those its journal used.
    #[must_use]
    pub fn with_labels(mut self, labels: impl IntoIterator<Item = Label>) -> Self {
        self.labels.extend(labels);
        self
    }

    /// The materials carves may add or paint ([`Terrain::with_labels`]).
    #[must_use]
    pub fn labels(&self) -> &BTreeSet<Label> {
        &self.labels
    }

    /// Checks that `edit` only adds or paints materials the terrain knows
    /// and, when the terrain entity has a material table
    /// (`TerrainMaterials`, feature `render`), materials the table has an
    /// entry for: what [`super::Carve`], [`Terrain::apply_now`] and the
    /// multiplayer server check before a carve.
    ///
    /// # Errors
    /// [`TerrainError::UnknownLabel`], or [`TerrainError::NoMaterial`] for
    /// a label the table would draw with its fallback. Label 0 (empty) is
    /// left to the kernel, which rejects it as an invalid edit.
    pub fn check_edit(&self, edit: Edit) -> Result<(), TerrainError> {
        self.check_label(edit)?;
        match (edit, &self.runtime.material_labels) {
            (Edit::Add(label) | Edit::Paint(label), Some(table))
                if label != chisel_bsp::tree::EMPTY && !table.contains(&label) =>
            {
                Err(TerrainError::NoMaterial {
                    label,
                    table: table.iter().copied().collect(),
                })
            }
            _ => Ok(()),
        }
    }

    /// Checks that `edit` only adds or paints materials the terrain knows,
    /// whatever its material table holds: the check of a replicated carve
    /// ([`super::GridCarve`]), which every peer must apply as the server
    /// accepted it, so that the octrees stay identical.
    ///
    /// # Errors
    /// [`TerrainError::UnknownLabel`].
    pub fn check_label(&self, edit: Edit) -> Result<(), TerrainError> {
        match edit {
            Edit::Add(label) | Edit::Paint(label)
                if label != chisel_bsp::tree::EMPTY && !self.labels.contains(&label) =>
            {
                Err(TerrainError::UnknownLabel {
                    label,
                    known: self.labels.iter().copied().collect(),
                })
            }
            _ => Ok(()),
        }
    }

    /// The labels the terrain's material table has materials for (`None`
    /// when the terrain entity has no `TerrainMaterials`).
    #[must_use]
    pub fn material_labels(&self) -> Option<&BTreeSet<Label>> {
        self.runtime.material_labels.as_ref()
    }

    /// The debris settings ([`Terrain::with_debris`]).
    #[must_use]
    pub fn debris(&self) -> Option<&DebrisConfig> {
        self.debris.as_ref()
    }

    /// Forgets every undo step and every redo step (the carves stay in the
    /// journal): for edits that are part of building a level, such as
    /// painting ore veins.
    pub fn clear_undo(&mut self) {
        self.history.clear();
        self.redo.clear();
    }

    /// The current octree (after every carve applied so far; meshes may lag
    /// by a few frames, see [`Terrain::is_idle`]).
    #[must_use]
    pub fn octree(&self) -> &Octree {
        &self.octree
    }

    /// The state hash of the octree's content ([`chisel_bsp::octree::hash`]):
    /// equal on every peer whose octree is bit-identical, whatever the
    /// thread count; updated per carve from the cells it changed.
    #[must_use]
    pub fn state_hash(&self) -> u64 {
        self.hash.value()
    }

    /// The request id of the latest tracked carve ([`super::GridCarve`])
    /// the octree includes, whether the kernel applied or refused it
    /// (`None` before the first); on a replicated terrain (feature `net`),
    /// of the latest op of its network order, carve or undo. A snapshot taken now ([`Terrain::to_bytes`])
    /// holds exactly the tracked carves up to this one.
    #[must_use]
    pub fn last_request(&self) -> Option<u64> {
        self.last_request
    }

    /// The volume of each material in the terrain, in cubic world units
    /// (exact regions, their volumes summed in `f64`). It walks every leaf:
    /// milliseconds for a large terrain; to follow what carves take out,
    /// add up their [`CarveApplied::volume_change`](super::CarveApplied::volume_change) instead.
    #[must_use]
    pub fn volumes(&self) -> BTreeMap<Label, f64> {
        self.quantization.to_world_volumes(self.octree.volumes())
    }

    /// The grid: unit and origin.
    #[must_use]
    pub fn quantization(&self) -> &Quantization {
        &self.quantization
    }

    /// What the terrain was built from.
    #[must_use]
    pub fn base(&self) -> &TerrainBase {
        &self.base
    }

    /// Every carve applied since the base, in order (undone carves removed).
    #[must_use]
    pub fn journal(&self) -> &[JournalEntry] {
        &self.journal
    }

    /// How many carves can be undone now.
    #[must_use]
    pub fn undo_depth(&self) -> usize {
        self.history.len()
    }

    /// How many undone carves can be redone now ([`super::RedoCarve`]):
    /// the undos since the last carve, none after a carve, a load, a
    /// detach across chunk borders or a world undo or redo of the chunk
    /// (a world chunk keeps them while it streams out and in unchanged).
    #[must_use]
    pub fn redo_depth(&self) -> usize {
        self.redo.len()
    }

    /// Whether every requested carve and undo is applied and every mesh is
    /// up to date.
    #[must_use]
    pub fn is_idle(&self) -> bool {
        let r = &self.runtime;
        r.queue.is_empty()
            && r.task.is_none()
            && r.uploads.is_empty()
            && !(r.needs_full_mesh && r.builds_cells)
    }

    /// Whether the terrain is idle but for sealing cells again at new
    /// points of neighbouring chunks ([`super::TerrainWorld`]): work that
    /// leaves the octree, journal and undo history as they are, and that
    /// a chunk streaming out may drop.
    pub(crate) fn is_idle_but_for_seams(&self) -> bool {
        let r = &self.runtime;
        r.queue
            .iter()
            .all(|job| matches!(job, super::jobs::Job::Reseal { .. }))
            && (r.task.is_none() || r.resealing)
            && r.uploads
                .iter()
                .all(|u| u.reports.is_empty() && u.debris.is_empty())
            && !(r.needs_full_mesh && r.builds_cells)
    }

    /// Whether the terrain differs from its base: a carve in its journal
    /// or undo history, or solid a detach across chunk borders took out.
    pub(crate) fn is_edited(&self) -> bool {
        !self.journal.is_empty() || !self.history.is_empty() || self.detached_across
    }

    /// Triangles currently shown.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.runtime.triangles
    }

    /// The entities showing leaf cell `key`, one per material.
    #[must_use]
    pub fn cell_entities(&self, key: CellKey) -> Vec<Entity> {
        self.runtime
            .cells
            .get(&key)
            .map(|v| v.iter().map(|&(_, e, _)| e).collect())
            .unwrap_or_default()
    }

    /// Every leaf cell with entities, with those entities.
    pub fn cells(&self) -> impl Iterator<Item = (CellKey, Vec<Entity>)> + '_ {
        self.runtime
            .cells
            .iter()
            .map(|(k, v)| (*k, v.iter().map(|&(_, e, _)| e).collect()))
    }

    /// Applies a carve synchronously to the octree and records it (journal
    /// and undo; the carves undone before it can no longer be redone),
    /// without touching meshes: for tools, tests and benchmarks
    /// outside the ECS. In an app, send [`super::Carve`] instead. Pieces
    /// the carve cuts loose are removed as in the app (without spawning
    /// anything), so the octree is the one the app would have.
    ///
    /// # Errors
    /// As [`super::apply_carve`], [`Terrain::check_edit`], and
    /// [`chisel_bsp::Error::TooMuchDebris`]; the terrain is then unchanged.
    pub fn apply_now(&mut self, tool: &GridTool, edit: Edit) -> Result<Changes, TerrainError> {
        self.check_edit(edit)?;
        let mut octree = self.octree.clone();
        let changes = apply_carve(&mut octree, tool, edit)?;
        let changes = match &self.debris {
            Some(config) => octree.detach_after(&changes, config)?.changes,
            None => changes,
        };
        let before = std::mem::replace(&mut self.octree, octree);
        self.hash
            .update(&self.octree, changes.changed.iter().chain(&changes.removed));
        self.record(before, changes.clone(), tool.clone(), edit, None);
        Ok(changes)
    }

    /// Undoes the last carve synchronously (no meshes touched); returns the
    /// cells whose surface may differ. The carve becomes the next one
    /// [`Terrain::redo_now`] (or [`super::RedoCarve`]) redoes.
    ///
    /// # Errors
    /// [`TerrainError::NothingToUndo`].
    pub fn undo_now(&mut self) -> Result<Vec<CellKey>, TerrainError> {
        self.undo_now_from(false).map(|(_, keys)| keys)
    }

    /// The prediction number of the last undo step (`None` when that step
    /// is no prediction, or there is none).
    pub(crate) fn top_prediction(&self) -> Option<u64> {
        self.history.back().and_then(|step| step.predicted)
    }

    /// The most undo steps kept ([`Terrain::with_max_undo`]).
    #[must_use]
    pub fn max_undo(&self) -> usize {
        self.max_undo
    }

    /// [`Terrain::undo_now`], also handing back the octree it undid. The
    /// undone carve becomes the next one to redo, but for a networked
    /// client's roll back (`rollback`: the step is the prediction's own,
    /// taken back), which leaves the redo steps as they were before the
    /// prediction.
    pub(crate) fn undo_now_from(
        &mut self,
        rollback: bool,
    ) -> Result<(Octree, Vec<CellKey>), TerrainError> {
        let step = self.history.pop_back().ok_or(TerrainError::NothingToUndo)?;
        let entry = self.journal.pop();
        let undone = std::mem::replace(&mut self.octree, step.before);
        let keys = changed_keys(&step.changes);
        self.hash.update(&self.octree, &keys);
        if rollback {
            // A prediction rolled back is not redone (the server's carves
            // follow); the redo steps it cleared are back.
            self.redo = step.redo;
        } else {
            self.redo.push(RedoStep {
                after: undone.clone(),
                changes: step.changes,
                entry,
            });
        }
        Ok((undone, keys))
    }

    /// Redoes the carve the last undo took back, synchronously (no meshes
    /// touched): the octree and its state hash become bit-identical to
    /// those right after that carve (the pieces it cut loose taken out
    /// again), its journal entry and undo step come back. Returns the
    /// cells whose surface may differ.
    ///
    /// # Errors
    /// [`TerrainError::NothingToRedo`] when no undo since the last carve
    /// is left to redo; the terrain is then unchanged.
    pub fn redo_now(&mut self) -> Result<Vec<CellKey>, TerrainError> {
        self.redo_now_from().map(|(_, keys, _)| keys)
    }

    /// [`Terrain::redo_now`], also handing back the octree it replaced and
    /// the edit redone (`None` where the journal had lost its entry).
    pub(crate) fn redo_now_from(
        &mut self,
    ) -> Result<(Octree, Vec<CellKey>, Option<Edit>), TerrainError> {
        let step = self.redo.pop().ok_or(TerrainError::NothingToRedo)?;
        let before = std::mem::replace(&mut self.octree, step.after);
        let keys = changed_keys(&step.changes);
        self.hash.update(&self.octree, &keys);
        let edit = step.entry.as_ref().map(|entry| entry.edit);
        if let Some(entry) = step.entry {
            self.journal.push(entry);
        }
        self.push_undo(before.clone(), step.changes, None, Vec::new());
        Ok((before, keys, edit))
    }

    /// Records a new carve: journal and undo step (of prediction
    /// `predicted`, if any); what was undone before it can no longer be
    /// redone.
    pub(crate) fn record(
        &mut self,
        before: Octree,
        changes: Changes,
        tool: GridTool,
        edit: Edit,
        predicted: Option<u64>,
    ) {
        self.journal.push(JournalEntry { tool, edit });
        let cleared = std::mem::take(&mut self.redo);
        let stashed = if predicted.is_some() {
            cleared
        } else {
            Vec::new()
        };
        self.push_undo(before, changes, predicted, stashed);
    }

    /// Keeps an undo step (of prediction `predicted`, if any, with the
    /// redo steps it cleared), within the depth limit.
    fn push_undo(
        &mut self,
        before: Octree,
        changes: Changes,
        predicted: Option<u64>,
        redo: Vec<RedoStep>,
    ) {
        if self.max_undo > 0 {
            self.history.push_back(UndoStep {
                before,
                changes,
                predicted,
                redo,
            });
            while self.history.len() > self.max_undo {
                self.history.pop_front();
            }
        }
    }
}

/// The cells `changes` changed or removed, sorted, each once.
fn changed_keys(changes: &Changes) -> Vec<CellKey> {
    let mut keys: Vec<CellKey> = (changes.changed.iter())
        .chain(&changes.removed)
        .copied()
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// One entity showing the surface of one material in one leaf cell; a
/// child of its terrain. Its mesh is rebuilt only when the cell changes.
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component, from_reflect = false)]
pub struct TerrainCell {
    /// The terrain entity.
    pub terrain: Entity,
    /// The octree cell.
    #[reflect(ignore)]
    pub key: CellKey,
    /// The material shown.
    pub label: Label,
}

#[cfg(test)]
mod tests {
    use chisel_bsp::octree::CellBox;

    use super::*;

    /// An 8-high block in a 32³ cube with one box carved out of it, that
    /// carve recorded as prediction `predicted` (if any).
    fn carved(predicted: Option<u64>) -> Terrain {
        let grid = Quantization::new(1.0, [0.0; 3]).expect("valid unit");
        let base = TerrainBase::Box {
            origin: [0; 3],
            size_log2: 5,
            solid: CellBox {
                min: [0; 3],
                max: [16, 8, 16],
            },
            label: 1,
        };
        let mut terrain =
            Terrain::from_base(grid, base, OctreeConfig::default()).expect("valid box");
        let corners = (0..8)
            .map(|i: usize| {
                let pick = |a: usize, lo: i64, hi: i64| if i >> a & 1 == 0 { lo } else { hi };
                [pick(0, 2, 5), pick(1, 2, 6), pick(2, 2, 6)]
            })
            .collect();
        let tool = GridTool {
            pieces: vec![corners],
        };
        let mut octree = terrain.octree.clone();
        let changes = apply_carve(&mut octree, &tool, Edit::Subtract).expect("carves");
        let before = std::mem::replace(&mut terrain.octree, octree);
        terrain.hash = StateHash::of(&terrain.octree);
        terrain.record(before, changes, tool, Edit::Subtract, predicted);
        terrain
    }

    #[test]
    fn a_rolled_back_prediction_leaves_nothing_to_redo() {
        // A plain carve undone is redone exactly.
        let mut plain = carved(None);
        let after = (plain.octree.to_bytes(), plain.state_hash());
        plain.undo_now().expect("undoes");
        assert_eq!(plain.redo_depth(), 1);
        plain.redo_now().expect("redoes");
        assert_eq!((plain.octree.to_bytes(), plain.state_hash()), after);
        // A prediction taken back is not.
        let mut predicted = carved(Some(7));
        predicted.undo_now_from(true).expect("undoes");
        assert_eq!(predicted.redo_depth(), 0);
        assert_eq!(predicted.redo_now(), Err(TerrainError::NothingToRedo));
        // A prediction confirmed and then undone in the server's order is
        // redone like any carve.
        let mut confirmed = carved(Some(8));
        confirmed.undo_now().expect("undoes");
        assert_eq!(confirmed.redo_depth(), 1);
        confirmed.redo_now().expect("redoes");
        assert_eq!((confirmed.octree.to_bytes(), confirmed.state_hash()), after);
    }
}
