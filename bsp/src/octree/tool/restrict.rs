//! A tool's BSP restricted to an integer box: the splits whose plane
//! cuts the box, the others replaced by the child holding the box.
//!
//! Notation: `T` — the tool's BSP; `B = [lo, hi]` — a closed integer box
//! (an octree cell, paper 1 §3.8); `n·x + d` — a plane of `T`;
//! `[n·x + d]_B` — its range over `B`, from the box corners.
//!
//! A split whose plane has `max_B(n·x + d) ≤ 0` holds the whole box on its
//! closed lower side, and so every three-dimensional convex cell inside the
//! box: cutting such a cell by the plane is never proper, and the merge
//! (§3.5) goes on into the lower child without a node, a palette entry or
//! a change to the arena ([`crate::tree::Bsp::merge_cells`]). The same holds
//! above for `min_B ≥ 0`. Dropping these splits before the merge therefore
//! changes nothing in its result, and spares one vertex classification of
//! every cell reaching them per plane. When no split is left, the box lies
//! in one region of `T`.

use super::contact::{box_range, dot};
use crate::exact::Plane;
use crate::octree::CellBox;
use crate::tree::{Bsp, EMPTY, Node, NodeId};

/// `tool` restricted to the closed box `cell` (see the module doc): the
/// same regions on the box, with only the splits whose planes cut it.
pub(crate) fn restricted(tool: &Bsp, cell: &CellBox) -> Bsp {
    let mut out = Restrict {
        tool,
        cell,
        planes: Vec::new(),
        palette: vec![u32::MAX; tool.planes().len()],
        nodes: Vec::new(),
    };
    out.node(0);
    Bsp::from_parts(out.planes, out.nodes)
}

/// Whether a corner or the centre of the closed box `cell` lies strictly
/// inside a solid region of `tool`: strictly on one side of every plane on
/// its way down, at a non-empty leaf. A small ball around it then lies in
/// that region, so the solid has volume in the box. `false` decides
/// nothing.
pub(crate) fn solid_at_a_corner(tool: &Bsp, cell: &CellBox) -> bool {
    let (lo, hi) = (cell.min, cell.max);
    let corners = (0..8).map(|i| [0, 1, 2].map(|a| if (i >> a) & 1 == 1 { hi[a] } else { lo[a] }));
    std::iter::once(cell.mid())
        .chain(corners)
        .any(|p| strictly_in_solid(tool, p))
}

/// Whether the point `p` lies strictly inside a solid region of `tool`.
fn strictly_in_solid(tool: &Bsp, p: [i64; 3]) -> bool {
    let mut n = 0;
    loop {
        match tool.nodes()[n as usize] {
            Node::Leaf(label) => return label != EMPTY,
            Node::Split {
                plane,
                below,
                above,
            } => {
                let s = &tool.planes()[plane as usize];
                n = match (dot(s.normal(), p) + s.offset()).signum() {
                    -1 => below,
                    1 => above,
                    _ => return false,
                };
            }
        }
    }
}

/// The restricted tree under construction.
struct Restrict<'a> {
    tool: &'a Bsp,
    cell: &'a CellBox,
    planes: Vec<Plane>,
    /// The output palette index of each plane of `tool` once used.
    palette: Vec<u32>,
    nodes: Vec<Node>,
}

impl Restrict<'_> {
    /// Appends the restriction of `tool`'s subtree `n`; returns its node.
    ///
    /// Nodes are appended in preorder (a split, then its lower subtree,
    /// then its upper one), with an explicit stack instead of recursion:
    /// the tool of a large hull is a chain as deep as its face count.
    fn node(&mut self, n: NodeId) -> NodeId {
        let root = self.nodes.len() as NodeId;
        // Tool subtrees still to restrict, each with the output split
        // (and which of its children) that it becomes.
        let mut stack: Vec<(NodeId, Option<(usize, bool)>)> = vec![(n, None)];
        while let Some((n, parent)) = stack.pop() {
            let id = self.nodes.len();
            let node = self.restrict_one(n);
            self.nodes.push(node);
            if let Some((at, above_side)) = parent
                && let Node::Split { below, above, .. } = &mut self.nodes[at]
            {
                *(if above_side { above } else { below }) = id as NodeId;
            }
            if let Node::Split { below, above, .. } = node {
                // The lower subtree first: pushed last.
                stack.push((above, Some((id, true))));
                stack.push((below, Some((id, false))));
            }
        }
        root
    }

    /// The first node of `tool`'s subtree `n` kept in the box: a leaf, or
    /// a split whose plane cuts the box (with the tool's child nodes, for
    /// [`Self::node`] to replace), following the child holding the box
    /// past the others.
    fn restrict_one(&mut self, mut n: NodeId) -> Node {
        loop {
            match self.tool.nodes()[n as usize] {
                Node::Leaf(label) => return Node::Leaf(label),
                Node::Split {
                    plane,
                    below,
                    above,
                } => {
                    let s = &self.tool.planes()[plane as usize];
                    let (min, max) = box_range(s.normal(), self.cell.min, self.cell.max);
                    let (min, max) = (min + s.offset(), max + s.offset());
                    if max <= 0 {
                        n = below;
                    } else if min >= 0 {
                        n = above;
                    } else {
                        let index = &mut self.palette[plane as usize];
                        if *index == u32::MAX {
                            *index = self.planes.len() as u32;
                            self.planes.push(*s);
                        }
                        return Node::Split {
                            plane: *index,
                            below,
                            above,
                        };
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::convex::ConvexArena;
    use crate::octree::tool::random_hull;
    use crate::tree::BooleanOp;

    /// A point's exact homogeneous coordinates, for comparisons.
    fn exact(p: &crate::exact::Point4) -> ([crate::exact::I256; 3], crate::exact::I192) {
        (p.xyz(), p.w())
    }

    fn random_box(rng: &mut ChaCha8Rng) -> CellBox {
        let edge = 1 << rng.random_range(1..7);
        let min = [0; 3].map(|_: i64| rng.random_range(-80..80));
        CellBox {
            min,
            max: min.map(|m| m + edge),
        }
    }

    /// Merging with the restricted tool gives the same tree, the same
    /// cells (labels, leaves, vertices) and the same rebuilt tree and faces
    /// as merging with the whole tool; a one-leaf restriction is the label
    /// of every cell of the tool in the box; a solid corner means solid
    /// volume in the box.
    #[test]
    fn restriction_changes_no_merge() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        let (mut one_region, mut cut) = (0, 0);
        for _ in 0..300 {
            let tool = random_hull(&mut rng, 0, 60, 12);
            let a = random_hull(&mut rng, 20, 60, 12).bsp().clone();
            let cell = random_box(&mut rng);
            let small = restricted(tool.bsp(), &cell);
            small.validate().unwrap();
            for op in [BooleanOp::Difference, BooleanOp::Union, BooleanOp::Paint(3)] {
                let mut merged = Vec::new();
                for b in [tool.bsp(), &small] {
                    let mut arena = ConvexArena::new();
                    let poly = cell.add_to(&mut arena).unwrap();
                    let (bsp, cells) = a.merge_cells(b, op, &mut arena, poly);
                    let shapes: Vec<_> = cells
                        .iter()
                        .map(|c| {
                            let v: Vec<_> = arena
                                .vertices_of(c.poly)
                                .into_iter()
                                .map(|v| exact(arena.point(v)))
                                .collect();
                            (c.leaf, c.label, v)
                        })
                        .collect();
                    let mut arena = ConvexArena::new();
                    let poly = cell.add_to(&mut arena).unwrap();
                    let (rebuilt, faces) = a.merge_simplified_faces(b, op, &mut arena, poly);
                    let faces: Vec<_> = faces
                        .into_iter()
                        .map(|f| {
                            let corners: Vec<_> = f.vertices.iter().map(exact).collect();
                            (f.plane, corners, f.label, f.outside, f.on_bounds)
                        })
                        .collect();
                    merged.push((bsp, shapes, rebuilt, faces));
                }
                assert!(merged[0] == merged[1], "{op:?} in {cell:?}");
            }
            let mut arena = ConvexArena::new();
            let poly = cell.add_to(&mut arena).unwrap();
            let labels: Vec<_> = tool
                .bsp()
                .cells(&mut arena, poly)
                .iter()
                .map(|c| c.label)
                .collect();
            if let [Node::Leaf(l)] = small.nodes() {
                one_region += 1;
                assert!(labels.iter().all(|x| x == l));
            } else {
                cut += 1;
            }
            if solid_at_a_corner(&small, &cell) {
                assert!(labels.iter().any(|&x| x != EMPTY));
            }
        }
        // Both kinds of boxes were met.
        assert!(one_region > 20 && cut > 20, "{one_region} {cut}");
    }
}
