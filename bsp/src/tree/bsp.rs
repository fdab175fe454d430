//! The BSP structure: a node array over a plane palette.

use crate::convex::{ConvexArena, PolyId};
use crate::exact::Plane;

/// A material label of a leaf; [`EMPTY`] is no material.
pub type Label = u8;

/// The label of empty space.
pub const EMPTY: Label = 0;

/// Index of a node in [`Bsp::nodes`].
pub type NodeId = u32;

/// One node of a [`Bsp`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    /// A region of one material.
    Leaf(Label),
    /// A split by `planes[plane]`.
    Split {
        /// Index into [`Bsp::planes`].
        plane: u32,
        /// The subtree below the plane (`n·x + d < 0`).
        below: NodeId,
        /// The subtree above the plane.
        above: NodeId,
    },
}

/// A BSP tree with labelled leaves; node `0` is the root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bsp {
    planes: Vec<Plane>,
    nodes: Vec<Node>,
}

/// A structural defect found by [`Bsp::validate`]: always a bug.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("BSP invariant broken: {0}")]
pub struct BspInvariantError(pub String);

impl Bsp {
    /// All of space with one label.
    #[must_use]
    pub fn uniform(label: Label) -> Self {
        Self {
            planes: Vec::new(),
            nodes: vec![Node::Leaf(label)],
        }
    }

    /// The convex polyhedron `poly` as a linear BSP: one split per face,
    /// each with empty space above, and `label` below the last.
    #[must_use]
    pub fn from_convex(arena: &ConvexArena, poly: PolyId, label: Label) -> Self {
        let faces = arena.faces_of(poly);
        Self::convex(faces.iter().map(|&f| *arena.face_plane(f)), label)
    }

    /// The linear tree of [`Bsp::from_convex`] for a convex polyhedron
    /// with face planes `planes` (positive outside), in that order.
    pub(crate) fn convex(planes: impl ExactSizeIterator<Item = Plane>, label: Label) -> Self {
        let mut bsp = Self {
            planes: Vec::with_capacity(planes.len()),
            nodes: Vec::with_capacity(2 * planes.len() + 1),
        };
        for (k, plane) in planes.enumerate() {
            let node = bsp.nodes.len() as NodeId;
            bsp.planes.push(plane);
            bsp.nodes.push(Node::Split {
                plane: k as u32,
                below: node + 2,
                above: node + 1,
            });
            bsp.nodes.push(Node::Leaf(EMPTY));
        }
        bsp.nodes.push(Node::Leaf(label));
        bsp
    }

    /// A tree from a builder's parts, root first.
    pub(crate) fn from_parts(planes: Vec<Plane>, nodes: Vec<Node>) -> Self {
        Self { planes, nodes }
    }

    /// The same tree with every leaf label mapped by `f`.
    #[must_use]
    pub fn relabeled(&self, f: impl Fn(Label) -> Label) -> Bsp {
        let nodes = self
            .nodes
            .iter()
            .map(|n| match *n {
                Node::Leaf(l) => Node::Leaf(f(l)),
                split => split,
            })
            .collect();
        Bsp::from_parts(self.planes.clone(), nodes)
    }

    /// A tree from stored parts (a saved file, a network message), checked:
    /// the nodes must form one tree rooted at node 0 over in-range plane
    /// indices. Planes are checked when they are made ([`Plane::new`]).
    ///
    /// # Errors
    /// The first defect found; nothing is built.
    pub fn from_stored_parts(
        planes: Vec<Plane>,
        nodes: Vec<Node>,
    ) -> Result<Self, BspInvariantError> {
        if nodes.is_empty() {
            return Err(BspInvariantError("a tree needs at least its root".into()));
        }
        let bsp = Self { planes, nodes };
        bsp.validate()?;
        Ok(bsp)
    }

    /// The node array.
    #[must_use]
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The plane palette.
    #[must_use]
    pub fn planes(&self) -> &[Plane] {
        &self.planes
    }

    /// Checks that every node is reachable from the root exactly once (the
    /// nodes form a tree) and every index is in range.
    ///
    /// # Errors
    /// The first defect found.
    pub fn validate(&self) -> Result<(), BspInvariantError> {
        let mut seen = vec![false; self.nodes.len()];
        let mut stack = vec![0 as NodeId];
        while let Some(n) = stack.pop() {
            let Some(node) = self.nodes.get(n as usize) else {
                return Err(BspInvariantError(format!("node {n} out of range")));
            };
            if std::mem::replace(&mut seen[n as usize], true) {
                return Err(BspInvariantError(format!("node {n} reached twice")));
            }
            if let Node::Split {
                plane,
                below,
                above,
            } = *node
            {
                if plane as usize >= self.planes.len() {
                    return Err(BspInvariantError(format!("node {n} names plane {plane}")));
                }
                stack.extend([below, above]);
            }
        }
        match seen.iter().position(|&s| !s) {
            Some(n) => Err(BspInvariantError(format!("node {n} is unreachable"))),
            None => Ok(()),
        }
    }
}
