//! Boolean operations by merging two BSPs (paper 1 §3.5).
//!
//! Notation: `A`, `B` — the operands; `f(a, b)` — the label function
//! ([`BooleanOp::apply`]); `C` — the convex cell of the current recursion,
//! cut exactly from the bounds.
//!
//! The merge recurses on `A`. At an inner node it cuts `C` by the node's
//! plane: a proper cut recurses into both children, otherwise only into the
//! child that holds `C`, dropping the plane. At a leaf of `A` with label
//! `a`, it inserts `B` restricted to `C` the same way, with leaf labels
//! `f(a, b)` — so the result never keeps a plane that does not cut its cell.
//! Where `f(a, ·)` is constant (solid `a` in a union, empty `a` in the
//! other operations) it inserts that leaf without looking at `B`.
//! A split whose two children are equal leaves collapses into the leaf.
//!
//! The cells form a stack: a cell is dead once the recursion below it
//! returns, so everything a recursion adds to the arena is discarded when
//! it returns, and the arena stays as small as one root-to-leaf path.
//!
//! [`Bsp::merge_cells`] keeps the cells instead: each output leaf's cell,
//! exactly as [`Bsp::cells`] of the result would cut it, for the redundancy
//! removal that follows (§3.7: "the merge procedure already produces a
//! convex cell for each leaf node"). The cuts are the same ones in the same
//! order, so the cells are identical element for element; two things need
//! care:
//! - Tags. A cap faces the sibling subtree's node. The upper part's sibling
//!   is the split's lower child, always the next node; the lower part's
//!   sibling, the upper child, is numbered only after the lower recursion,
//!   so its caps carry a pending tag (the split node, marked) that is
//!   resolved once the tree is complete.
//! - Collapsed splits. Their cell is the uncut one, so every proper cut
//!   first saves the records of its cell (`Survey::save`); when the split
//!   collapses, the pieces are discarded and the saved records written
//!   back (`Survey::restore`): the cell is again exactly as it was before
//!   the cut, and becomes the leaf's cell.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use super::cells::{Cell, Reach, Survey};
use crate::convex::{ConvexArena, CutOutcome, NO_TAG, PolyId};
use crate::exact::{Plane, Sign, classify_vertex};
use crate::pool::{PerThread, Pool};
use crate::word_hash::WordHasher;

/// How the labels of two overlapping regions combine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BooleanOp {
    /// `A ∪ B`: material of `A` where it has some, else that of `B`
    /// (adding material never replaces existing material).
    Union,
    /// `A ∩ B`: material of `A` where `B` has material.
    Intersection,
    /// `A − B`: material of `A` where `B` is empty.
    Difference,
    /// Material of `A`, repainted with the label where `B` has material.
    Paint(Label),
}

impl BooleanOp {
    /// The label of a region labelled `a` in `A` and `b` in `B`.
    #[must_use]
    #[inline]
    pub fn apply(self, a: Label, b: Label) -> Label {
        match self {
            BooleanOp::Union => {
                if a != EMPTY {
                    a
                } else {
                    b
                }
            }
            BooleanOp::Intersection => {
                if b != EMPTY {
                    a
                } else {
                    EMPTY
                }
            }
            BooleanOp::Difference => {
                if b != EMPTY {
                    EMPTY
                } else {
                    a
                }
            }
            BooleanOp::Paint(m) => {
                if a != EMPTY && b != EMPTY {
                    m
                } else {
                    a
                }
            }
        }
    }

    /// The label of a region labelled `a` in `A` whatever `B` holds there,
    /// when [`BooleanOp::apply`] does not depend on `b` for this `a`.
    #[must_use]
    #[inline]
    pub fn regardless_of_b(self, a: Label) -> Option<Label> {
        match self {
            BooleanOp::Union => (a != EMPTY).then_some(a),
            BooleanOp::Intersection | BooleanOp::Difference => (a == EMPTY).then_some(EMPTY),
            // Empty stays empty; material already of the paint's label keeps it.
            BooleanOp::Paint(m) => (a == EMPTY || a == m).then_some(a),
        }
    }
}

/// Builds the merged tree.
struct Merger<'a> {
    a: &'a Bsp,
    b: &'a Bsp,
    op: BooleanOp,
    arena: &'a mut ConvexArena,
    planes: Vec<Plane>,
    plane_index: HashMap<Plane, u32, BuildHasherDefault<WordHasher>>,
    /// The output palette index of each input plane once it is known
    /// (`A`'s planes first, then `B`'s; `u32::MAX` before), so that the
    /// palette is hashed once per input plane rather than once per split.
    known: Vec<u32>,
    nodes: Vec<Node>,
    /// The output leaves' cells when they are kept ([`Bsp::merge_cells`]).
    cells: Option<KeptCells>,
    /// What is known of each split of `B` below the current leaf of `A`,
    /// and which are set.
    facts: Vec<SplitFacts>,
    facts_set: Vec<NodeId>,
}

/// What is known of a split of `B` below a leaf of `A` with cell `C`,
/// before any piece of `C` reaches it.
#[derive(Clone, Copy, Debug, Default)]
struct SplitFacts {
    /// A proper cut there cannot collapse ([`Merger::find_sure_splits`]).
    sure: bool,
    /// The side of the plane `C` lies on ([`Reach::Below`] or
    /// [`Reach::Above`]), found by [`Merger::labels_reached`]: every piece
    /// of `C` lies there too, and the cut is not proper.
    side: Option<Reach>,
}

/// What the merge knows of a split of `A` or `B` before cutting the cell
/// by it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Expect {
    /// A proper cut cannot collapse: the cell is cut without a save.
    Sure,
    /// A split of `B`, often not cutting the cell: the sides are found
    /// from the cell's vertices first, and the cell saved only before a
    /// proper cut.
    Unknown,
    /// A split of `A`, whose simplified tree has almost only splits that
    /// cut their cells: the cell is surveyed and saved in one walk, and
    /// the cut itself tells whether it is proper.
    Proper,
}

/// The cells [`Bsp::merge_cells`] keeps, with the working memory of the
/// saves.
struct KeptCells {
    cells: Vec<Cell>,
    survey: Survey,
    /// The cell `survey` describes, while it is unchanged: a cell that
    /// does not cut properly is tested against the next plane as it is.
    surveyed: Option<PolyId>,
}

thread_local! {
    /// The survey memory of earlier merges on this thread, kept so that a
    /// merge does not regrow it.
    static SURVEYS: Pool<Survey> = const { Pool::new(MAX_SURVEYS) };
}

/// Survey memories kept per thread: more than merges nest.
const MAX_SURVEYS: usize = 16;

/// Marks a pending tag: the upper child of the split node in the low bits,
/// numbered once the lower recursion has returned.
const PENDING: u32 = 1 << 31;

/// An input plane: its slot in [`Merger::known`] and the plane.
#[derive(Clone, Copy)]
struct InputPlane<'a> {
    slot: usize,
    plane: &'a Plane,
}

impl<'a> Merger<'a> {
    /// The output palette index of an input plane, added on first use
    /// (equal planes of `A` and `B` share one entry).
    fn plane(&mut self, input: InputPlane<'_>) -> u32 {
        if self.known[input.slot] != u32::MAX {
            return self.known[input.slot];
        }
        let next = self.planes.len() as u32;
        let index = *self.plane_index.entry(*input.plane).or_insert_with(|| {
            self.planes.push(*input.plane);
            next
        });
        self.known[input.slot] = index;
        index
    }

    /// Appends the merge of `A`'s subtree `n` restricted to `cell`; returns
    /// its node.
    fn merge_a(&mut self, n: NodeId, cell: PolyId) -> NodeId {
        match self.a.nodes()[n as usize] {
            // Where the label does not depend on B, inserting B would only
            // make splits that all collapse into this one leaf.
            Node::Leaf(label) => match self.op.regardless_of_b(label) {
                Some(label) => self.leaf(label, cell),
                None => {
                    let node = match self.one_label_of_b(cell, label) {
                        Some(label) => self.leaf(label, cell),
                        None => {
                            self.find_sure_splits(label);
                            self.insert_b(0, cell, label)
                        }
                    };
                    for n in self.facts_set.drain(..) {
                        self.facts[n as usize] = SplitFacts::default();
                    }
                    node
                }
            },
            Node::Split {
                plane,
                below,
                above,
            } => {
                let s = InputPlane {
                    slot: plane as usize,
                    plane: &self.a.planes()[plane as usize],
                };
                self.split(s, cell, below, above, Expect::Proper, Self::merge_a)
            }
        }
    }

    /// The label every region of `B` in `cell` gives with `a`, when the
    /// vertices of `cell` show that it is one, without cutting: then
    /// [`Merger::insert_b`] would make only splits that all collapse, and
    /// its result is this leaf with the uncut cell. Only where cells are
    /// kept (the survey lists the vertices).
    fn one_label_of_b(&mut self, cell: PolyId, a: Label) -> Option<Label> {
        let kept = self.cells.as_mut()?;
        if kept.surveyed != Some(cell) {
            kept.survey.survey(self.arena, cell);
            kept.surveyed = Some(cell);
        }
        if self.facts.len() < self.b.nodes().len() {
            self.facts
                .resize(self.b.nodes().len(), SplitFacts::default());
        }
        let mut found = None;
        self.labels_reached(0, a, &mut found).then_some(found?)
    }

    /// Whether the leaves of `B`'s subtree `n` that the surveyed cell
    /// reaches give one label with `a` (also `found`'s, when set): a
    /// split whose plane the cell straddles is followed on both sides, so
    /// every leaf a cut of the cell would reach is visited. Notes the side
    /// of each plane the cell lies on.
    fn labels_reached(&mut self, n: NodeId, a: Label, found: &mut Option<Label>) -> bool {
        match self.b.nodes()[n as usize] {
            Node::Leaf(b) => {
                let label = self.op.apply(a, b);
                *found.get_or_insert(label) == label
            }
            Node::Split {
                plane,
                below,
                above,
            } => {
                let Some(kept) = &self.cells else {
                    return false;
                };
                let reach = kept
                    .survey
                    .reach(self.arena, &self.b.planes()[plane as usize]);
                if reach != Reach::Both {
                    self.facts[n as usize].side = Some(reach);
                    self.facts_set.push(n);
                }
                match reach {
                    Reach::Below => self.labels_reached(below, a, found),
                    Reach::Above => self.labels_reached(above, a, found),
                    Reach::Both => {
                        self.labels_reached(above, a, found) && self.labels_reached(below, a, found)
                    }
                }
            }
        }
    }

    /// Marks the splits of `B` whose proper cut cannot collapse under the
    /// surveyed cell `C` with label `a` in `A`, from a witness: a vertex
    /// `v` of `C` strictly inside a leaf region of `B`, with label `x`
    /// there. Each split on the way to that leaf is reached by the piece
    /// of `C` around `v`, whose part near `v` has volume and goes on to the
    /// leaf: the child towards `v` yields a leaf `x` or a split. When the
    /// other child is a leaf of another label, a proper cut there makes two
    /// different children, and the cell need not be saved before it.
    fn find_sure_splits(&mut self, a: Label) {
        let Some(kept) = &self.cells else {
            return;
        };
        let nodes = self.b.nodes();
        let label_of = |n: NodeId| match nodes[n as usize] {
            Node::Leaf(b) => Some(self.op.apply(a, b)),
            Node::Split { .. } => None,
        };
        let mut marked = false;
        for &v in kept.survey.vertices() {
            let point = self.arena.point(v);
            let mut n = 0;
            let x = loop {
                match nodes[n as usize] {
                    Node::Leaf(b) => break Some(self.op.apply(a, b)),
                    Node::Split {
                        plane,
                        below,
                        above,
                    } => {
                        n = match classify_vertex(point, &self.b.planes()[plane as usize]) {
                            Sign::Negative => below,
                            Sign::Positive => above,
                            Sign::Zero => break None,
                        };
                    }
                }
            };
            let Some(x) = x else { continue };
            // Down the same way again, marking the splits.
            let mut n = 0;
            while let Node::Split {
                plane,
                below,
                above,
            } = nodes[n as usize]
            {
                let (on, off) = match classify_vertex(point, &self.b.planes()[plane as usize]) {
                    Sign::Negative => (below, above),
                    _ => (above, below),
                };
                if label_of(off).is_some_and(|y| y != x) {
                    self.facts[n as usize].sure = true;
                    self.facts_set.push(n);
                    marked = true;
                }
                n = on;
            }
            if marked {
                return;
            }
        }
    }

    /// Appends `B`'s subtree `n` restricted to `cell`, labels combined with
    /// `a`; returns its node.
    fn insert_b(&mut self, n: NodeId, cell: PolyId, a: Label) -> NodeId {
        match self.b.nodes()[n as usize] {
            Node::Leaf(b) => self.leaf(self.op.apply(a, b), cell),
            Node::Split {
                plane,
                below,
                above,
            } => {
                let s = InputPlane {
                    slot: self.a.planes().len() + plane as usize,
                    plane: &self.b.planes()[plane as usize],
                };
                let facts = self.facts.get(n as usize).copied().unwrap_or_default();
                let expect = if facts.sure {
                    Expect::Sure
                } else {
                    Expect::Unknown
                };
                match facts.side {
                    Some(Reach::Below) => self.insert_b(below, cell, a),
                    Some(Reach::Above) => self.insert_b(above, cell, a),
                    _ => self.split(s, cell, below, above, expect, |m, child, c| {
                        m.insert_b(child, c, a)
                    }),
                }
            }
        }
    }

    /// Cuts `cell` by `s` and recurses with `step` into the children it
    /// reaches; a split node only when the cut is proper. `cell` is used up.
    fn split(
        &mut self,
        s: InputPlane<'a>,
        cell: PolyId,
        below: NodeId,
        above: NodeId,
        expect: Expect,
        mut step: impl FnMut(&mut Self, NodeId, PolyId) -> NodeId,
    ) -> NodeId {
        if self.cells.is_some() {
            return match expect {
                Expect::Sure => self.split_unsaved(s, cell, below, above, step),
                Expect::Unknown => self.split_keeping(s, cell, below, above, false, step),
                Expect::Proper => self.split_keeping(s, cell, below, above, true, step),
            };
        }
        let mark = self.arena.mark();
        let node = match self.arena.cut(cell, s.plane, NO_TAG, NO_TAG) {
            CutOutcome::Below => step(self, below, cell),
            CutOutcome::Above => step(self, above, cell),
            CutOutcome::Split {
                below: cb,
                above: ca,
            } => self.proper(s, (cb, ca), below, above, step).0,
        };
        // The cell and all its pieces are dead now.
        self.arena.release_to(mark);
        node
    }

    /// [`Merger::split`] keeping the output leaves' cells: a proper cut
    /// saves the cell first, for the case that the split collapses.
    /// `proper_likely`: save before knowing whether the cut is proper
    /// ([`Expect::Proper`]).
    fn split_keeping(
        &mut self,
        s: InputPlane<'a>,
        cell: PolyId,
        below: NodeId,
        above: NodeId,
        proper_likely: bool,
        mut step: impl FnMut(&mut Self, NodeId, PolyId) -> NodeId,
    ) -> NodeId {
        let kept = self.cells.as_mut().expect("cells are kept");
        // A cut changes the cell in place: the cell is saved before a
        // proper one, for the case that the split collapses.
        let saved = if proper_likely {
            let saved = if kept.surveyed == Some(cell) {
                kept.survey.save(self.arena)
            } else {
                kept.survey.survey_and_save(self.arena, cell)
            };
            kept.surveyed = Some(cell);
            saved
        } else {
            if kept.surveyed != Some(cell) {
                kept.survey.survey(self.arena, cell);
                kept.surveyed = Some(cell);
            }
            match kept.survey.reach(self.arena, s.plane) {
                Reach::Below => return step(self, below, cell),
                Reach::Above => return step(self, above, cell),
                Reach::Both => {}
            }
            kept.survey.save(self.arena)
        };
        let first_cell = kept.cells.len();
        let before_cut = self.arena.mark();
        let node = self.nodes.len() as NodeId;
        let (cb, ca) = match self.arena.cut(cell, s.plane, PENDING | node, node + 1) {
            CutOutcome::Split { below, above } => (below, above),
            // Not proper: the cell is unchanged, and still surveyed.
            outcome => {
                kept.survey.drop_saved(saved);
                let child = if outcome == CutOutcome::Below {
                    below
                } else {
                    above
                };
                return step(self, child, cell);
            }
        };
        // The cut changed the cell, and a collapse below releases pieces.
        kept.surveyed = None;
        let (node, collapsed) = self.proper(s, (cb, ca), below, above, step);
        let kept = self.cells.as_mut().expect("cells are kept");
        if let Some(label) = collapsed {
            // The pieces are dead; the cell, restored uncut, is the leaf's.
            self.arena.release_to(before_cut);
            kept.survey.restore(self.arena, saved);
            kept.surveyed = None;
            kept.cells.truncate(first_cell);
            kept.cells.push(Cell {
                poly: cell,
                leaf: node,
                label,
            });
        } else {
            kept.survey.drop_saved(saved);
        }
        node
    }

    /// [`Merger::split_keeping`] where a proper cut cannot collapse: the
    /// cell is cut without a survey or a save.
    fn split_unsaved(
        &mut self,
        s: InputPlane<'a>,
        cell: PolyId,
        below: NodeId,
        above: NodeId,
        mut step: impl FnMut(&mut Self, NodeId, PolyId) -> NodeId,
    ) -> NodeId {
        let node = self.nodes.len() as NodeId;
        match self.arena.cut(cell, s.plane, PENDING | node, node + 1) {
            CutOutcome::Below => step(self, below, cell),
            CutOutcome::Above => step(self, above, cell),
            CutOutcome::Split {
                below: cb,
                above: ca,
            } => {
                if let Some(kept) = &mut self.cells {
                    kept.surveyed = None;
                }
                let (node, collapsed) = self.proper(s, (cb, ca), below, above, step);
                debug_assert!(collapsed.is_none(), "a sure split collapsed");
                node
            }
        }
    }

    /// The split for a proper cut into `cb` below and `ca` above, or the
    /// leaf it collapses into (then also its label).
    fn proper(
        &mut self,
        s: InputPlane<'a>,
        (cb, ca): (PolyId, PolyId),
        below: NodeId,
        above: NodeId,
        mut step: impl FnMut(&mut Self, NodeId, PolyId) -> NodeId,
    ) -> (NodeId, Option<Label>) {
        let palette = self.planes.len();
        let plane = self.plane(s);
        let node = self.push(Node::Leaf(EMPTY));
        let b = step(self, below, cb);
        let a = step(self, above, ca);
        self.nodes[node as usize] = match (self.nodes[b as usize], self.nodes[a as usize]) {
            // Equal leaves on both sides: the plane separates nothing.
            (Node::Leaf(x), Node::Leaf(y)) if x == y => {
                self.nodes.truncate(node as usize);
                self.forget_planes_from(palette);
                return (self.push(Node::Leaf(x)), Some(x));
            }
            _ => Node::Split {
                plane,
                below: b,
                above: a,
            },
        };
        (node, None)
    }

    /// Appends a leaf, keeping its cell when cells are kept.
    fn leaf(&mut self, label: Label, cell: PolyId) -> NodeId {
        let leaf = self.push(Node::Leaf(label));
        if let Some(kept) = &mut self.cells {
            kept.cells.push(Cell {
                poly: cell,
                leaf,
                label,
            });
        }
        leaf
    }

    /// Drops the palette entries from `len` on, which no node uses (a
    /// collapsed split's and those of the splits below it), so that the
    /// palette holds exactly the planes of the tree's splits, in the order
    /// they were first used.
    fn forget_planes_from(&mut self, len: usize) {
        if self.planes.len() == len {
            return;
        }
        for plane in self.planes.drain(len..) {
            self.plane_index.remove(&plane);
        }
        for index in &mut self.known {
            if *index != u32::MAX && *index as usize >= len {
                *index = u32::MAX;
            }
        }
    }

    fn push(&mut self, node: Node) -> NodeId {
        self.nodes.push(node);
        self.nodes.len() as NodeId - 1
    }
}

impl Bsp {
    /// `self op other` inside the convex polyhedron `bounds` of `arena`
    /// (which is used up: the arena keeps its elements from before the call,
    /// but `bounds` is no longer a valid polyhedron; outside `bounds` the
    /// result is empty).
    /// Exact: the result's regions are exactly those of the label function.
    #[must_use]
    pub fn merge(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> Bsp {
        self.merger(other, op, arena, None).run(bounds).0
    }

    /// [`Bsp::merge`], also returning the result's cells inside `bounds`,
    /// left in `arena`: the same list, polyhedron for polyhedron and tag for
    /// tag, as [`Bsp::cells`] of the result would cut from `bounds` (but
    /// without cutting again).
    #[must_use]
    pub fn merge_cells(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> (Bsp, Vec<Cell>) {
        let survey = SURVEYS.take().unwrap_or_default();
        let kept = KeptCells {
            cells: Vec::new(),
            survey,
            surveyed: None,
        };
        let first_face = arena.faces().len();
        let (bsp, cells) = self.merger(other, op, arena, Some(kept)).run(bounds);
        // Resolve the pending tags. Every face since the start is scanned,
        // discarded copies included: a pending tag of a discarded face may
        // name a node that is gone, and is left as it is.
        for face in &mut arena.faces[first_face..] {
            if face.tag != NO_TAG && face.tag & PENDING != 0 {
                let split = (face.tag & !PENDING) as usize;
                if let Some(Node::Split { above, .. }) = bsp.nodes().get(split) {
                    face.tag = *above;
                }
            }
        }
        let Some(kept) = cells else {
            unreachable!("cells are kept")
        };
        SURVEYS.keep(kept.survey);
        (bsp, kept.cells)
    }

    fn merger<'a>(
        &'a self,
        other: &'a Bsp,
        op: BooleanOp,
        arena: &'a mut ConvexArena,
        cells: Option<KeptCells>,
    ) -> Merger<'a> {
        Merger {
            a: self,
            b: other,
            op,
            arena,
            planes: Vec::new(),
            plane_index: HashMap::with_capacity_and_hasher(
                self.planes().len() + other.planes().len(),
                BuildHasherDefault::default(),
            ),
            known: vec![u32::MAX; self.planes().len() + other.planes().len()],
            nodes: Vec::new(),
            cells,
            facts: Vec::new(),
            facts_set: Vec::new(),
        }
    }
}

impl Merger<'_> {
    /// The merged tree (and the kept cells).
    fn run(mut self, bounds: PolyId) -> (Bsp, Option<KeptCells>) {
        // Nodes are appended in depth-first order, so the first one is the
        // root (a collapsed split is replaced in place).
        let root = self.merge_a(0, bounds);
        debug_assert_eq!(root, 0);
        (Bsp::from_parts(self.planes, self.nodes), self.cells)
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::exact::IntPoint;
    use crate::octree::{CellBox, Tool};

    /// `regardless_of_b` promises exactly what `apply` does, for every
    /// label on either side.
    #[test]
    fn labels_regardless_of_b_agree_with_apply() {
        let ops = [
            BooleanOp::Union,
            BooleanOp::Intersection,
            BooleanOp::Difference,
            BooleanOp::Paint(7),
        ];
        for op in ops {
            for a in 0..=Label::MAX {
                let labels: Vec<Label> = (0..=Label::MAX).map(|b| op.apply(a, b)).collect();
                let constant = labels.iter().all(|&l| l == labels[0]);
                match op.regardless_of_b(a) {
                    Some(l) => assert!(constant && labels[0] == l, "{op:?} {a}"),
                    None => assert!(!constant, "{op:?} {a}: a constant missed"),
                }
            }
        }
    }

    fn random_hull(rng: &mut ChaCha8Rng, centre: i64, radius: i64) -> Bsp {
        loop {
            let points: Vec<IntPoint> = (0..10)
                .map(|_| {
                    let c = [0; 3].map(|_: i64| centre + rng.random_range(-radius..=radius));
                    IntPoint::from_array(c).unwrap()
                })
                .collect();
            if let Ok(tool) = Tool::convex_hull(&points) {
                return tool.bsp().clone();
            }
        }
    }

    /// With cells kept or not, the merge gives the same tree, and its
    /// palette holds exactly the planes of its splits, each once: the
    /// splits that collapse, and those skipped because they would, leave
    /// nothing in it.
    #[test]
    fn palette_holds_exactly_the_planes_of_the_splits() {
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        let ops = [
            BooleanOp::Union,
            BooleanOp::Intersection,
            BooleanOp::Difference,
            BooleanOp::Paint(2),
        ];
        let cell = CellBox {
            min: [-40; 3],
            max: [40; 3],
        };
        for round in 0..40 {
            let (one, two) = (random_hull(&mut rng, 0, 50), random_hull(&mut rng, 10, 50));
            let mut arena = ConvexArena::new();
            let poly = cell.add_to(&mut arena).unwrap();
            let a = one.merge(&two, BooleanOp::Difference, &mut arena, poly);
            let b = random_hull(&mut rng, 0, 45);
            let op = ops[round % ops.len()];
            let mut arena = ConvexArena::new();
            let poly = cell.add_to(&mut arena).unwrap();
            let (kept, _) = a.merge_cells(&b, op, &mut arena, poly);
            let mut arena = ConvexArena::new();
            let poly = cell.add_to(&mut arena).unwrap();
            let plain = a.merge(&b, op, &mut arena, poly);
            assert_eq!(kept, plain, "round {round}");
            let mut used: Vec<u32> = kept
                .nodes()
                .iter()
                .filter_map(|n| match n {
                    Node::Split { plane, .. } => Some(*plane),
                    Node::Leaf(_) => None,
                })
                .collect();
            used.sort_unstable();
            used.dedup();
            let all: Vec<u32> = (0..kept.planes().len() as u32).collect();
            assert_eq!(used, all, "round {round}: a palette entry no split uses");
            let distinct: std::collections::HashSet<&Plane> = kept.planes().iter().collect();
            assert_eq!(distinct.len(), kept.planes().len(), "round {round}");
        }
    }
}
