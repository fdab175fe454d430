//! A convex tool restricted to the facets of its intersection with a cell
//! (paper 1 §3.5, §3.8: the merge inserts `T` only where it meets `C`).
//!
//! Notation: `T` — a tool BSP that is a chain: every split has an empty
//! leaf on one side (its outer half-space `h_i⁺`) and the rest of the
//! chain on the other, ending in one solid leaf, so that
//! `T = ⋂ h_i⁻`; `C` — the closed integer box of an octree cell;
//! `P = C ∩ T`, cut exactly from `C` by every `h_i⁻` in chain order.
//!
//! [`super::restricted`] keeps the splits whose planes cut `C`. A tool
//! with many faces still crosses a small cell with many planes (the long
//! side faces of a swept cutter extend across every cell along its
//! length), although `P` has only a few facets. A convex polyhedron is
//! the intersection of its facet half-spaces, so
//! `P = C ∩ ⋂_{i ∈ F} h_i⁻` where `F` are the splits whose planes carry a
//! facet of `P`: the chain of the splits in `F` alone, in their order, has
//! the same regions inside `C` as `T`. The merge then cuts the cell's
//! regions by `|F|` planes instead of all of them, and leaves fewer
//! pieces for the boundary and the rebuild (§3.7). The result is exact;
//! only the pieces the surface is cut into differ, so a rebuilt leaf may
//! have another (equally valid) tree.

use crate::convex::{ConvexArena, KeptOutcome, NO_TAG, Part, PolyId};
use crate::exact::Plane;
use crate::tree::{Bsp, EMPTY, Label, Node, NodeId};

/// One split of a chain: its plane and the side of the solid.
#[derive(Clone, Copy)]
struct Link {
    plane: Plane,
    solid: Part,
}

/// `tool` restricted to the facets of its solid inside `cell` (a box
/// polyhedron of `arena`, cut up in place) when `tool` is a chain (see
/// the module doc); `None` for any other tree. An empty leaf when the
/// solid has no volume in `cell`, the solid leaf when it holds the cell.
pub(crate) fn facet_chain(tool: &Bsp, arena: &mut ConvexArena, cell: PolyId) -> Option<Bsp> {
    let (links, solid) = chain(tool)?;
    if solid == EMPTY {
        return Some(Bsp::uniform(EMPTY));
    }
    let mut poly = cell;
    // The link whose plane made each cap, by tag.
    for (i, link) in links.iter().enumerate() {
        let tag = i as u32;
        match arena.cut_keeping(poly, &link.plane, link.solid, tag) {
            KeptOutcome::Cut(kept) => poly = kept,
            KeptOutcome::Below if link.solid == Part::Below => {}
            KeptOutcome::Above if link.solid == Part::Above => {}
            // The cell lies in the closed outer half-space: the solid
            // has no volume in it.
            _ => return Some(Bsp::uniform(EMPTY)),
        }
    }
    let mut used = vec![false; links.len()];
    for face in arena.faces_of(poly) {
        let tag = arena.faces()[face as usize].tag;
        if tag != NO_TAG && (tag as usize) < links.len() {
            used[tag as usize] = true;
        }
    }
    let kept: Vec<Link> = links
        .iter()
        .zip(&used)
        .filter_map(|(link, &used)| used.then_some(*link))
        .collect();
    Some(chain_bsp(&kept, solid))
}

/// The links of `tool` in order and its solid label, when it is a chain
/// with only empty leaves beside it; the label [`EMPTY`] when its end is
/// empty (or a split has empty leaves on both sides, as the box
/// restriction leaves them where the box lies outside a plane): then it
/// has no solid at all.
fn chain(tool: &Bsp) -> Option<(Vec<Link>, Label)> {
    let nodes = tool.nodes();
    let mut links = Vec::new();
    let mut n: NodeId = 0;
    loop {
        match nodes[n as usize] {
            Node::Leaf(label) => return Some((links, label)),
            Node::Split {
                plane,
                below,
                above,
            } => {
                let empty = |m: NodeId| nodes[m as usize] == Node::Leaf(EMPTY);
                let (solid, next) = match (empty(below), empty(above)) {
                    (false, true) => (Part::Below, below),
                    (true, false) => (Part::Above, above),
                    (true, true) => return Some((links, EMPTY)),
                    (false, false) => return None,
                };
                links.push(Link {
                    plane: tool.planes()[plane as usize],
                    solid,
                });
                n = next;
            }
        }
    }
}

/// The chain of `links` (each plane once in the palette, in order) ending
/// in a leaf `solid`, nodes in preorder (a split, its lower subtree, its
/// upper one).
fn chain_bsp(links: &[Link], solid: Label) -> Bsp {
    let planes: Vec<Plane> = links.iter().map(|l| l.plane).collect();
    let mut nodes = Vec::with_capacity(2 * links.len() + 1);
    // Splits whose solid side is below have their empty leaf after the
    // rest of the chain: placed once the chain's end is reached.
    let mut pending_empty: Vec<usize> = Vec::new();
    for (i, link) in links.iter().enumerate() {
        let at = nodes.len();
        match link.solid {
            Part::Below => {
                nodes.push(Node::Split {
                    plane: i as u32,
                    below: (at + 1) as NodeId,
                    above: 0,
                });
                pending_empty.push(at);
            }
            Part::Above => {
                nodes.push(Node::Split {
                    plane: i as u32,
                    below: (at + 1) as NodeId,
                    above: (at + 2) as NodeId,
                });
                nodes.push(Node::Leaf(EMPTY));
            }
        }
    }
    nodes.push(Node::Leaf(solid));
    // The empty upper children, innermost split first (preorder: the
    // upper subtree of a split follows its whole lower subtree).
    for &at in pending_empty.iter().rev() {
        let leaf = nodes.len() as NodeId;
        nodes.push(Node::Leaf(EMPTY));
        if let Node::Split { above, .. } = &mut nodes[at] {
            *above = leaf;
        }
    }
    Bsp::from_parts(planes, nodes)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::octree::exact_volume::ExactVolume;
    use crate::octree::tool::random_hull;
    use crate::octree::tool::restricted;
    use crate::octree::{CellBox, Tool};
    use crate::tree::BooleanOp;

    fn random_box(rng: &mut ChaCha8Rng) -> CellBox {
        let edge = 1 << rng.random_range(1..7);
        let min = [0; 3].map(|_: i64| rng.random_range(-80..80));
        CellBox {
            min,
            max: min.map(|m| m + edge),
        }
    }

    /// The exact volume of each label of `a op b` inside `cell`.
    fn volumes(a: &Bsp, b: &Bsp, op: BooleanOp, cell: &CellBox) -> BTreeMap<Label, ExactVolume> {
        let mut arena = ConvexArena::new();
        let poly = cell.add_to(&mut arena).unwrap();
        let (_, cells) = a.merge_cells(b, op, &mut arena, poly);
        let mut out: BTreeMap<Label, ExactVolume> = BTreeMap::new();
        for c in cells {
            *out.entry(c.label).or_default() += &ExactVolume::of_polyhedron(&arena, c.poly);
        }
        out
    }

    /// The facet chain is a valid tree with at most the splits of the box
    /// restriction, and merging with it gives every label exactly the
    /// volume that merging with the whole tool gives, for every edit; its
    /// one-leaf forms mean a box outside or inside the tool.
    #[test]
    fn facet_chain_keeps_the_regions_in_the_cell() {
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        let (mut outside, mut inside, mut fewer) = (0, 0, 0);
        for round in 0..300 {
            let tool = random_hull(&mut rng, 0, 60, 8 + round % 40);
            let a = random_hull(&mut rng, 20, 60, 12).bsp().clone();
            let cell = random_box(&mut rng);
            let boxed = restricted(tool.bsp(), &cell);
            let mut arena = ConvexArena::new();
            let poly = cell.add_to(&mut arena).unwrap();
            let chain = facet_chain(&boxed, &mut arena, poly).expect("a hull is a chain");
            chain.validate().unwrap();
            assert!(chain.nodes().len() <= boxed.nodes().len());
            fewer += usize::from(chain.nodes().len() < boxed.nodes().len());
            match chain.nodes() {
                [Node::Leaf(EMPTY)] => outside += 1,
                [Node::Leaf(_)] => inside += 1,
                _ => {}
            }
            for op in [
                BooleanOp::Difference,
                BooleanOp::Union,
                BooleanOp::Intersection,
                BooleanOp::Paint(3),
            ] {
                assert_eq!(
                    volumes(&a, tool.bsp(), op, &cell),
                    volumes(&a, &chain, op, &cell),
                    "{op:?} in {cell:?}"
                );
            }
        }
        assert!(
            outside > 10 && inside > 0 && fewer > 20,
            "{outside} {inside} {fewer}"
        );
    }

    /// A tree that is not a chain is left to the box restriction.
    #[test]
    fn a_union_is_not_a_chain() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let one = random_hull(&mut rng, 0, 20, 12);
        let two = random_hull(&mut rng, 50, 20, 12);
        let union = Tool::union(&[one, two]).unwrap();
        let mut arena = ConvexArena::new();
        let cell = CellBox {
            min: [-64; 3],
            max: [64; 3],
        };
        let poly = cell.add_to(&mut arena).unwrap();
        assert!(facet_chain(union.bsp(), &mut arena, poly).is_none());
    }
}
