//! Booleans by grafting copies of `B` into the cells of `A` (paper 1 §3.5,
//! the merge as the paper states it).
//!
//! Notation: `A`, `B` — the operands; `f(a, b)` — the label function
//! ([`BooleanOp::apply`]); `C` — the convex cell of the current recursion,
//! cut exactly from the bounds; `f(a, B)` — `B` with every leaf label `b`
//! replaced by `f(a, b)`, the *image* of `B` under label `a`.
//!
//! The merge recurses on `A` only. At an inner node it cuts `C` by the
//! node's plane: a proper cut recurses into both children, otherwise only
//! into the child that holds `C`, dropping the plane. At a leaf of `A` with
//! label `a` it stops and inserts `f(a, B)`: a single leaf when `f(a, ·)`
//! takes one value on all of `B`'s labels, else a copy of `B`'s nodes with
//! shifted indices and mapped labels. `B` is never cut, so its planes may
//! not cut their cells — unlike [`Bsp::merge`], which prunes `B` cell by
//! cell, this result keeps them, and the redundancy removal that follows
//! (§3.7, [`Bsp::simplified`]) drops them. The regions, and so the exact
//! volumes of every material, are those of [`Bsp::merge`].
//!
//! What makes the output nodes cheap:
//! - `B`'s planes enter the output palette once, before `A`'s (with the
//!   first image that is a tree, even if no cell gets a copy), and each
//!   image `f(a, B)` is built once per label `a`; a copy is then a
//!   block copy of the image and an index offset added to its splits.
//! - A subtree of `A` whose leaves all map to the same single leaf yields
//!   that leaf without a cut (cutting would only make splits that all
//!   collapse into it); it is found in one pass over `A` beforehand, which
//!   also tells which children of a split cut their cell further.
//! - Only the pieces such children need are built: both
//!   ([`ConvexArena::cut`]), one ([`ConvexArena::cut_keeping`]), or none —
//!   then the cell's vertices are only classified against the plane.
//! - A split whose two children are equal leaves collapses into the leaf.
//!
//! The cells form a stack: everything a recursion adds to the arena is
//! discarded when it returns, so the arena stays as small as one
//! root-to-leaf path.

use super::bsp::{Bsp, EMPTY, Label, Node, NodeId};
use super::cells::{self, Survey};
use super::merge::BooleanOp;
use crate::convex::{ConvexArena, CutOutcome, KeptOutcome, NO_TAG, Part, PolyId};
use crate::exact::Plane;

/// Marks an `A` plane not yet in the output palette.
const UNSEEN: u32 = u32::MAX;

/// What `f(a, ·)` makes of `B`.
enum Image {
    /// The same label everywhere: one leaf.
    Leaf(Label),
    /// `B`'s nodes with mapped labels and output plane indices; child
    /// indices still relative to `B`'s root.
    Tree(Vec<Node>),
}

/// What a node of `A` yields, known before cutting.
#[derive(Clone, Copy)]
enum Step {
    /// One leaf, whatever the cell: a leaf of `A` whose image is a leaf, or
    /// a subtree all of whose leaves yield the same one.
    Leaf(Label),
    /// A leaf of `A` whose image `images[k]` is a tree.
    Graft(usize),
    /// A split of `A` to cut the cell by.
    Cut {
        plane: u32,
        below: NodeId,
        above: NodeId,
    },
}

/// Which children of a split its cell reaches, with the pieces of a
/// proper cut that are built (those of children that cut further).
enum Reach {
    Both(Option<PolyId>, Option<PolyId>),
    Below,
    Above,
}

/// Builds the grafted tree.
struct Grafter<'a> {
    a: &'a Bsp,
    b: &'a Bsp,
    op: BooleanOp,
    arena: &'a mut ConvexArena,
    planes: Vec<Plane>,
    /// The output palette index of each of `A`'s planes once used.
    a_planes: Vec<u32>,
    /// Where `B`'s planes start in the output palette, once copied.
    b_planes: Option<u32>,
    /// Which labels `B`'s leaves carry.
    b_labels: [bool; 256],
    /// The images built so far, by label of `A`.
    images: Vec<(Label, Image)>,
    /// What each node of `A` yields.
    plan: Vec<Step>,
    /// The vertices of a cell whose pieces no child needs.
    survey: Survey,
    nodes: Vec<Node>,
}

impl Grafter<'_> {
    /// The single label `f(a, ·)` gives all of `B`'s labels, if it does.
    fn uniform_image(&self, a: Label) -> Option<Label> {
        let mut image = None;
        for b in 0..=Label::MAX {
            if self.b_labels[b as usize] {
                let l = self.op.apply(a, b);
                match image {
                    None => image = Some(l),
                    Some(seen) if seen != l => return None,
                    Some(_) => {}
                }
            }
        }
        image
    }

    /// The index in [`Grafter::images`] of `f(a, B)`, built on first use.
    fn image(&mut self, a: Label) -> usize {
        if let Some(k) = self.images.iter().position(|(l, _)| *l == a) {
            return k;
        }
        let image = match self.uniform_image(a) {
            Some(label) => Image::Leaf(label),
            None => {
                let base = *self.b_planes.get_or_insert_with(|| {
                    let base = self.planes.len() as u32;
                    self.planes.extend_from_slice(self.b.planes());
                    base
                });
                let (op, b_nodes) = (self.op, self.b.nodes());
                Image::Tree(
                    b_nodes
                        .iter()
                        .map(|n| match *n {
                            Node::Leaf(b) => Node::Leaf(op.apply(a, b)),
                            Node::Split {
                                plane,
                                below,
                                above,
                            } => Node::Split {
                                plane: base + plane,
                                below,
                                above,
                            },
                        })
                        .collect(),
                )
            }
        };
        self.images.push((a, image));
        self.images.len() - 1
    }

    /// Fills [`Grafter::plan`] for `A`'s subtree `n` and returns its step;
    /// builds the image of every leaf label on the way.
    fn plan_a(&mut self, n: NodeId) -> Step {
        let step = match self.a.nodes()[n as usize] {
            Node::Leaf(a) => {
                let k = self.image(a);
                match self.images[k].1 {
                    Image::Leaf(label) => Step::Leaf(label),
                    Image::Tree(_) => Step::Graft(k),
                }
            }
            Node::Split {
                plane,
                below,
                above,
            } => match (self.plan_a(below), self.plan_a(above)) {
                (Step::Leaf(x), Step::Leaf(y)) if x == y => Step::Leaf(x),
                _ => Step::Cut {
                    plane,
                    below,
                    above,
                },
            },
        };
        self.plan[n as usize] = step;
        step
    }

    /// Appends the merge of `A`'s subtree `n` restricted to `cell`; returns
    /// its node. `cell` is used up; it is given exactly when the step is a
    /// cut.
    fn graft_a(&mut self, n: NodeId, cell: Option<PolyId>) -> NodeId {
        match (self.plan[n as usize], cell) {
            (Step::Leaf(label), _) => self.push(Node::Leaf(label)),
            (Step::Graft(k), _) => self.graft_b(k),
            (
                Step::Cut {
                    plane,
                    below,
                    above,
                },
                Some(cell),
            ) => self.cut_a(plane, (below, above), cell),
            (Step::Cut { .. }, None) => unreachable!("a cut step always gets its cell"),
        }
    }

    /// Cuts `cell` by `A`'s plane `plane` and recurses into the children it
    /// reaches; a split node only when the cut is proper. Only the pieces
    /// that children cut further are built.
    fn cut_a(&mut self, plane: u32, (below, above): (NodeId, NodeId), cell: PolyId) -> NodeId {
        let mark = self.arena.mark();
        let s = &self.a.planes()[plane as usize];
        let cuts = |n: NodeId| matches!(self.plan[n as usize], Step::Cut { .. });
        let pieces = match (cuts(below), cuts(above)) {
            (true, true) => match self.arena.cut(cell, s, NO_TAG, NO_TAG) {
                CutOutcome::Split {
                    below: cb,
                    above: ca,
                } => Reach::Both(Some(cb), Some(ca)),
                CutOutcome::Below => Reach::Below,
                CutOutcome::Above => Reach::Above,
            },
            // Only which children the cell reaches matters.
            (false, false) => {
                self.survey.survey(self.arena, cell);
                match self.survey.reach(self.arena, s) {
                    cells::Reach::Both => Reach::Both(None, None),
                    cells::Reach::Below => Reach::Below,
                    cells::Reach::Above => Reach::Above,
                }
            }
            (cuts_below, _) => {
                let keep = if cuts_below { Part::Below } else { Part::Above };
                match self.arena.cut_keeping(cell, s, keep, NO_TAG) {
                    KeptOutcome::Cut(piece) if cuts_below => Reach::Both(Some(piece), None),
                    KeptOutcome::Cut(piece) => Reach::Both(None, Some(piece)),
                    KeptOutcome::Below => Reach::Below,
                    KeptOutcome::Above => Reach::Above,
                }
            }
        };
        let node = match pieces {
            Reach::Below => self.graft_a(below, Some(cell)),
            Reach::Above => self.graft_a(above, Some(cell)),
            Reach::Both(cb, ca) => {
                let node = self.push(Node::Leaf(EMPTY));
                let b = self.graft_a(below, cb);
                let a = self.graft_a(above, ca);
                match (self.nodes[b as usize], self.nodes[a as usize]) {
                    // Equal leaves on both sides: the plane separates nothing.
                    (Node::Leaf(x), Node::Leaf(y)) if x == y => {
                        self.nodes.truncate(node as usize);
                        self.push(Node::Leaf(x))
                    }
                    _ => {
                        let plane = self.a_plane(plane);
                        self.nodes[node as usize] = Node::Split {
                            plane,
                            below: b,
                            above: a,
                        };
                        node
                    }
                }
            }
        };
        // The cell and all its pieces are dead now.
        self.arena.release_to(mark);
        node
    }

    /// Appends the image `images[k]` for a leaf of `A`; returns its root.
    fn graft_b(&mut self, k: usize) -> NodeId {
        let root = self.nodes.len() as NodeId;
        match &self.images[k].1 {
            Image::Leaf(label) => self.nodes.push(Node::Leaf(*label)),
            Image::Tree(tree) => {
                // A copy, then the child indices of its splits shifted.
                self.nodes.extend_from_slice(tree);
                for node in &mut self.nodes[root as usize..] {
                    if let Node::Split { below, above, .. } = node {
                        *below += root;
                        *above += root;
                    }
                }
            }
        }
        root
    }

    /// The output palette index of `A`'s plane `plane`, added on first use.
    fn a_plane(&mut self, plane: u32) -> u32 {
        let index = &mut self.a_planes[plane as usize];
        if *index == UNSEEN {
            *index = self.planes.len() as u32;
            self.planes.push(self.a.planes()[plane as usize]);
        }
        *index
    }

    fn push(&mut self, node: Node) -> NodeId {
        self.nodes.push(node);
        self.nodes.len() as NodeId - 1
    }
}

impl Bsp {
    /// `self op other` inside the convex polyhedron `bounds` of `arena`
    /// (used up as by [`Bsp::merge`]; outside `bounds` the result is
    /// empty), by the paper's merge: `self` is cut cell by cell, `other` is
    /// copied whole (labels mapped) into every cell of a leaf of `self`
    /// whose label does not decide the result alone.
    ///
    /// Exact: the result's regions inside `bounds` are those of
    /// [`Bsp::merge`], but `other`'s planes are kept where they do not cut
    /// their cells, so the tree is larger; [`Bsp::simplified`] removes them.
    /// Equal planes of the operands get separate palette entries.
    ///
    /// # Panics
    /// When the result could have more nodes or planes than `u32` counts
    /// (checked before any cut: `arena` is then unchanged).
    #[must_use]
    pub fn merge_grafted(
        &self,
        other: &Bsp,
        op: BooleanOp,
        arena: &mut ConvexArena,
        bounds: PolyId,
    ) -> Bsp {
        let mut b_labels = [false; 256];
        for n in other.nodes() {
            if let Node::Leaf(b) = *n {
                b_labels[b as usize] = true;
            }
        }
        let mut grafter = Grafter {
            a: self,
            b: other,
            op,
            arena,
            planes: Vec::with_capacity(self.planes().len() + other.planes().len()),
            a_planes: vec![UNSEEN; self.planes().len()],
            b_planes: None,
            b_labels,
            images: Vec::new(),
            plan: vec![Step::Leaf(EMPTY); self.nodes().len()],
            survey: Survey::default(),
            nodes: Vec::new(),
        };
        grafter.plan_a(0);
        // At most every leaf of `A` gets a whole copy of `B`.
        let copies = grafter
            .plan
            .iter()
            .filter(|s| matches!(s, Step::Graft(_)))
            .count();
        let most = copies
            .checked_mul(other.nodes().len())
            .and_then(|n| n.checked_add(self.nodes().len()))
            .filter(|&n| NodeId::try_from(n).is_ok())
            .filter(|_| u32::try_from(self.planes().len() + other.planes().len()).is_ok());
        let Some(most) = most else {
            panic!(
                "a grafted merge of {copies} copies of {} nodes is too large",
                other.nodes().len()
            );
        };
        grafter.nodes.reserve(most);
        // Nodes are appended in depth-first order, so the first one is the
        // root (a collapsed split is replaced in place).
        let root = grafter.graft_a(0, Some(bounds));
        debug_assert_eq!(root, 0);
        Bsp::from_parts(grafter.planes, grafter.nodes)
    }
}
