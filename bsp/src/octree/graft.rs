//! The axis-BSP of a cell with its children's BSPs in its leaves (paper 1
//! §3.8, Fig. 8, "combine A").
//!
//! Notation: `m` — the cell's centre. The tree splits by `x = m_x`, then
//! `y = m_y`, then `z = m_z`; below a plane is the lower half, so the leaf
//! reached by the bits `(x, y, z)` of child `i` holds child `i`'s BSP.

use crate::exact::Plane;
use crate::tree::{Bsp, Node, NodeId};

/// The eight `children` (ordered as [`super::CellKey::child`]) under the
/// axis planes through `mid`.
pub(crate) fn axis_graft(children: [&Bsp; 8], mid: [i64; 3]) -> Bsp {
    let mut planes: Vec<Plane> = (0..3)
        .map(|axis| {
            let mut n = [0i64; 3];
            n[axis] = 1;
            Plane::new(n[0], n[1], n[2], -(mid[axis] as i128))
                .expect("cell centres lie inside the coordinate range")
        })
        .collect();
    let mut nodes: Vec<Node> = Vec::new();
    graft(&mut planes, &mut nodes, &children, 0, 0);
    Bsp::from_parts(planes, nodes)
}

/// Appends the subtree for the children whose low bits are `bits` (axes
/// below `axis` already decided) and returns its root.
fn graft(
    planes: &mut Vec<Plane>,
    nodes: &mut Vec<Node>,
    children: &[&Bsp; 8],
    axis: usize,
    bits: usize,
) -> NodeId {
    if axis == 3 {
        return copy(planes, nodes, children[bits]);
    }
    let at = nodes.len() as NodeId;
    nodes.push(Node::Leaf(0));
    let below = graft(planes, nodes, children, axis + 1, bits);
    let above = graft(planes, nodes, children, axis + 1, bits | 1 << axis);
    nodes[at as usize] = Node::Split {
        plane: axis as u32,
        below,
        above,
    };
    at
}

/// Appends a copy of `bsp` (its own planes appended to the palette) and
/// returns its root.
fn copy(planes: &mut Vec<Plane>, nodes: &mut Vec<Node>, bsp: &Bsp) -> NodeId {
    let plane_base = planes.len() as u32;
    let node_base = nodes.len() as NodeId;
    planes.extend_from_slice(bsp.planes());
    nodes.extend(bsp.nodes().iter().map(|node| match *node {
        Node::Leaf(label) => Node::Leaf(label),
        Node::Split {
            plane,
            below,
            above,
        } => Node::Split {
            plane: plane + plane_base,
            below: below + node_base,
            above: above + node_base,
        },
    }));
    node_base
}
