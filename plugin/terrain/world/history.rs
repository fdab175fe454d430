//! What a world records for [`WorldUndo`](super::WorldUndo) and
//! [`WorldRedo`](super::WorldRedo): one world step per routed world
//! carve, what it did to each chunk, the steps undone (for redo), and the
//! undos and redos waiting for their chunks. The rules are in the
//! [`super::undo`] and [`super::redo`] module docs.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use chisel_bsp::octree::{CellKey, Edit, Octree};

use super::debris_order::DebrisRole;
use super::redo::{StreamedRedo, UndoneStep};
use super::{ChunkCoord, TerrainWorld};
use crate::terrain::component::{DEFAULT_MAX_UNDO, Terrain};
use crate::terrain::tool::GridTool;

/// The world's undo steps, the steps undone since the last world carve,
/// and the undos and redos waiting to be carried out.
pub(crate) struct WorldHistory {
    /// Most steps kept (and undo steps kept per chunk).
    pub(crate) max: usize,
    pub(super) steps: VecDeque<WorldStep>,
    /// The steps [`WorldUndo`](super::WorldUndo) took back since the last
    /// world carve, the latest last: what
    /// [`WorldRedo`](super::WorldRedo) re-applies.
    pub(super) undone: Vec<UndoneStep>,
    /// Undos and redos asked for and not yet carried out, oldest first.
    pub(super) waiting: VecDeque<Waiting>,
    /// World carves asked for after a waiting undo or redo, routed after
    /// it.
    held: Vec<(GridTool, Edit, Vec<ChunkCoord>)>,
    /// The id of the next hold put in the chunks' queues.
    next_hold: u64,
    /// The redo steps of chunks streamed out, by chunk ([`super::redo`]).
    pub(super) streamed_redo: BTreeMap<ChunkCoord, StreamedRedo>,
}

impl Default for WorldHistory {
    fn default() -> Self {
        Self {
            max: DEFAULT_MAX_UNDO,
            steps: VecDeque::new(),
            undone: Vec::new(),
            waiting: VecDeque::new(),
            held: Vec::new(),
            next_hold: 0,
            streamed_redo: BTreeMap::new(),
        }
    }
}

/// One world carve's record.
pub(super) struct WorldStep {
    /// The request id of its chunk carves.
    pub(super) request: u64,
    pub(super) chunks: BTreeMap<ChunkCoord, StepChunk>,
    /// Seeds its detaches searched from, given back on undo.
    pub(super) seeds: BTreeMap<ChunkCoord, Vec<CellKey>>,
}

/// What a world step did to one chunk.
pub(super) struct StepChunk {
    pub(super) carve: CarveState,
    /// State hash and journal length of the chunk as the step left it.
    pub(super) after: u64,
    pub(super) journal: usize,
    /// The chunk before a detach of the step that did not join its own
    /// undo step.
    pub(super) detach: Option<BeforeDetach>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum CarveState {
    /// Routed, not applied yet.
    Waiting,
    /// Applied: the chunk's undo step holds its octree before.
    Landed,
    /// Refused by the chunk, or not routed to it.
    None,
}

pub(super) struct BeforeDetach {
    pub(super) octree: Octree,
    pub(super) keys: Vec<CellKey>,
    pub(super) detached_across: bool,
}

/// Which request waits.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum WorldOp {
    /// A [`WorldUndo`](super::WorldUndo).
    Undo,
    /// A [`WorldRedo`](super::WorldRedo).
    Redo,
}

/// A [`WorldUndo`](super::WorldUndo) or [`WorldRedo`](super::WorldRedo)
/// waiting for its chunks to hold every earlier request.
pub(super) struct Waiting {
    pub(super) op: WorldOp,
    /// The world step it undoes or redoes.
    pub(super) request: u64,
    /// The id of its hold in the chunks' queues.
    pub(super) hold: u64,
    /// Chunks whose queues hold it.
    pub(super) held: BTreeSet<ChunkCoord>,
}

/// A tracked carve a chunk's job applied or refused: its request id and,
/// when applied, the chunk's state hash and journal length right after.
pub(crate) type Landed = (u64, Option<(u64, usize)>);

/// One chunk a detach across chunk borders changed, as the world's undo
/// needs it ([`note_detach`]).
pub(crate) struct DetachedChunk {
    coord: ChunkCoord,
    before: Octree,
    hash_before: u64,
    hash_after: u64,
    journal: usize,
    detached_across: bool,
    keys: Vec<CellKey>,
    landed: Vec<Landed>,
}

impl DetachedChunk {
    /// `terrain` (chunk `coord`) right after a detach swapped in its
    /// octree: `before` and `hash_before` are its octree and hash before,
    /// `detached_across` its flag before, `keys` the cells changed.
    pub(crate) fn new(
        coord: ChunkCoord,
        terrain: &mut Terrain,
        before: Octree,
        hash_before: u64,
        detached_across: bool,
        keys: &[CellKey],
    ) -> Self {
        Self {
            coord,
            before,
            hash_before,
            hash_after: terrain.hash.value(),
            journal: terrain.journal.len(),
            detached_across,
            keys: keys.to_vec(),
            landed: std::mem::take(&mut terrain.runtime.landed),
        }
    }
}

impl WorldHistory {
    /// World steps that can be undone now.
    pub(crate) fn depth(&self) -> usize {
        self.steps.len()
    }

    /// World steps undone that can be redone now.
    pub(crate) fn redo_depth(&self) -> usize {
        self.undone.len()
    }

    /// Forgets every step, undone step and waiting request (a networked
    /// world's reset).
    #[cfg(feature = "net")]
    pub(crate) fn clear(&mut self) {
        self.steps.clear();
        self.undone.clear();
        self.waiting.clear();
        self.held.clear();
        self.streamed_redo.clear();
    }

    /// Whether world carves wait for an undo or redo
    /// ([`WorldHistory::hold`]).
    pub(crate) fn holds_carves(&self) -> bool {
        !self.waiting.is_empty()
    }

    /// Keeps a world carve asked for while an undo or redo waits.
    pub(crate) fn hold(&mut self, tool: GridTool, edit: Edit, coords: Vec<ChunkCoord>) {
        self.held.push((tool, edit, coords));
    }

    /// The world carves held while undos or redos waited, once none does.
    pub(super) fn take_held(&mut self) -> Vec<(GridTool, Edit, Vec<ChunkCoord>)> {
        if self.waiting.is_empty() {
            std::mem::take(&mut self.held)
        } else {
            Vec::new()
        }
    }

    /// The record of world step `request`, done or undone.
    pub(super) fn step(&self, request: u64) -> Option<&WorldStep> {
        (self.steps.iter().rev().find(|s| s.request == request))
            .or_else(|| (self.undone.iter().rev()).find_map(|u| u.for_request(request)))
    }

    /// The chunks waiting undos and redos need live.
    pub(crate) fn wanted(&self) -> impl Iterator<Item = ChunkCoord> + '_ {
        self.waiting.iter().flat_map(|waiting| {
            (self.step(waiting.request).into_iter())
                .flat_map(|s| s.chunks.iter())
                .filter(|(_, c)| c.needs_hold())
                .map(|(&coord, _)| coord)
        })
    }

    /// Claims the step a new `op` would take: the last step done (for an
    /// undo) or undone (for a redo) once the waiting requests are carried
    /// out; queues the request and returns `true`, or `false` when there
    /// is none. A world carve held meanwhile forgets the steps a redo
    /// would take.
    pub(super) fn claim(&mut self, op: WorldOp) -> bool {
        let mut done: Vec<u64> = self.steps.iter().map(|s| s.request).collect();
        let mut undone: Vec<u64> = self.undone.iter().map(UndoneStep::request).collect();
        for waiting in &self.waiting {
            let (from, to) = match waiting.op {
                WorldOp::Undo => (&mut done, &mut undone),
                WorldOp::Redo => (&mut undone, &mut done),
            };
            to.extend(from.pop());
        }
        if !self.held.is_empty() {
            undone.clear();
        }
        let top = match op {
            WorldOp::Undo => done.last(),
            WorldOp::Redo => undone.last(),
        };
        let Some(&request) = top else {
            return false;
        };
        self.waiting.push_back(Waiting {
            op,
            request,
            hold: self.next_hold,
            held: BTreeSet::new(),
        });
        self.next_hold = self.next_hold.wrapping_add(1);
        true
    }

    /// Records a world carve routed to `coords` under `request`.
    /// A new world carve forgets the steps undone before it.
    pub(crate) fn push_step(&mut self, request: u64, coords: &[ChunkCoord]) {
        self.undone.clear();
        if self.max == 0 {
            return;
        }
        let chunks = coords
            .iter()
            .map(|&coord| {
                let chunk = StepChunk {
                    carve: CarveState::Waiting,
                    after: 0,
                    journal: 0,
                    detach: None,
                };
                (coord, chunk)
            })
            .collect();
        self.steps.push_back(WorldStep {
            request,
            chunks,
            seeds: BTreeMap::new(),
        });
        while self.steps.len() > self.max {
            self.steps.pop_front();
        }
    }

    /// Notes what chunk `coord`'s jobs applied or refused.
    pub(super) fn land(&mut self, coord: ChunkCoord, landed: Vec<Landed>) {
        for (request, outcome) in landed {
            let Some(step) = self.steps.iter_mut().rev().find(|s| s.request == request) else {
                continue;
            };
            let Some(chunk) = step.chunks.get_mut(&coord) else {
                continue;
            };
            match outcome {
                Some((hash, journal)) => {
                    chunk.carve = CarveState::Landed;
                    chunk.after = hash;
                    chunk.journal = journal;
                }
                None => chunk.carve = CarveState::None,
            }
        }
    }
}

impl StepChunk {
    /// Whether the undo has anything to do in this chunk (and so holds it).
    pub(super) fn needs_hold(&self) -> bool {
        self.carve != CarveState::None || self.detach.is_some()
    }
}

/// Records a detach across chunk borders in the world step it belongs to
/// (the [module docs](self)): `chunks` are those it changed, `seeds` those
/// it searched from, by chunk.
pub(crate) fn note_detach(
    world: &mut TerrainWorld,
    chunks: Vec<DetachedChunk>,
    seeds: Vec<(ChunkCoord, Vec<CellKey>)>,
) {
    let history = &mut world.history;
    let mut chunks = chunks;
    for chunk in &mut chunks {
        world.routed.land(chunk.coord, &chunk.landed);
        history.land(chunk.coord, std::mem::take(&mut chunk.landed));
    }
    if world.debris_role != DebrisRole::Local {
        return;
    }
    let near: BTreeSet<ChunkCoord> = (chunks.iter().map(|c| c.coord))
        .chain(seeds.iter().map(|(c, _)| *c))
        .collect();
    let Some(step) = history.steps.iter_mut().rev().find(|s| {
        (s.chunks.iter()).any(|(c, chunk)| chunk.carve == CarveState::Landed && near.contains(c))
    }) else {
        return;
    };
    for chunk in chunks {
        let entry = step.chunks.entry(chunk.coord).or_insert(StepChunk {
            carve: CarveState::None,
            after: chunk.hash_before,
            journal: chunk.journal,
            detach: None,
        });
        if entry.carve == CarveState::Landed || entry.detach.is_some() {
            // Its own step of this carve holds it (the removal joined the
            // chunk's last step), or an earlier detach of this step kept
            // its state: move on with it unless something else changed
            // the chunk in between (the undo then refuses).
            if entry.after == chunk.hash_before && entry.journal == chunk.journal {
                entry.after = chunk.hash_after;
                if let Some(before) = &mut entry.detach {
                    before.keys.extend(chunk.keys);
                    before.keys.sort_unstable();
                    before.keys.dedup();
                }
            }
        } else {
            entry.after = chunk.hash_after;
            entry.journal = chunk.journal;
            entry.detach = Some(BeforeDetach {
                octree: chunk.before,
                keys: chunk.keys,
                detached_across: chunk.detached_across,
            });
        }
    }
    for (coord, keys) in seeds {
        step.seeds.entry(coord).or_default().extend(keys);
    }
}
