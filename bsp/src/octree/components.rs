//! Connected components of an octree's solid (paper 1 §3.4 across the
//! cells of §3.8).
//!
//! Notation: a *solid cell* `(k, n)` ([`SolidCell`]) is the convex cell of
//! BSP leaf `n` inside octree leaf `k` (`n = 0` for a uniform leaf) with a
//! non-empty label: the nodes of the graph. Two solid cells are *adjacent*
//! when they share a face of positive area, whatever their materials;
//! touching along an edge or at a point does not connect. A *wall* is a
//! side of a leaf's box; an *anchor* is a side of the root cube or a
//! marked box ([`Anchors`]).
//!
//! Inside a leaf, each cut face of a cell is clipped down the subtree on
//! its other side (its tag), as boundary extraction clips it (§3.4): the
//! pieces that reach solid leaves name the neighbours. A face on a wall is
//! cut to the wall of each leaf across it and clipped down that leaf's BSP,
//! as the octree's surface resolves border faces. A polygon is split only
//! where it straddles a plane, so every piece has positive area: the
//! adjacency is exact, on integers only.

use super::cell::{CellBox, CellKey};
use super::exact_volume::ExactVolume;
use super::tree::{Leaf, OctNode, Octree};
use crate::convex::{ConvexArena, KeptOutcome, NO_TAG, Part, PolyId};
use crate::exact::Plane;
use crate::tree::boundary::cell_face;
use crate::tree::polygon::Polygon;
use crate::tree::{Bsp, EMPTY, Label, Node, NodeId};
use crate::word_hash::{WordMap, WordSet};

/// One convex solid cell of an octree: BSP leaf `node` of leaf cell `key`
/// (`0` for a uniform leaf).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SolidCell {
    /// The octree leaf holding it.
    pub key: CellKey,
    /// The BSP leaf node it is the cell of (`0` in a uniform leaf).
    pub node: NodeId,
}

/// A side of the root cube.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CubeSide {
    /// The axis it is normal to: 0 = x, 1 = y, 2 = z.
    pub axis: usize,
    /// The upper side (`max`) rather than the lower one (`min`).
    pub upper: bool,
}

impl CubeSide {
    /// The bottom, `y = min`: y is up in Bevy.
    pub const BOTTOM: CubeSide = CubeSide {
        axis: 1,
        upper: false,
    };

    /// The four vertical sides (x and z, lower and upper): the sides a
    /// chunk of a horizontal grid shares with its neighbours.
    pub const HORIZONTAL: [CubeSide; 4] = [
        CubeSide {
            axis: 0,
            upper: false,
        },
        CubeSide {
            axis: 0,
            upper: true,
        },
        CubeSide {
            axis: 2,
            upper: false,
        },
        CubeSide {
            axis: 2,
            upper: true,
        },
    ];
}

/// What holds solid in place: a component is anchored when one of its
/// cells has a face of positive area on one of `sides`, or shares volume
/// with one of `boxes`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Anchors {
    /// Sides of the root cube that hold what rests on them (default: the
    /// bottom, [`CubeSide::BOTTOM`]).
    pub sides: Vec<CubeSide>,
    /// Boxes in grid units that hold what has volume inside them.
    pub boxes: Vec<CellBox>,
}

impl Default for Anchors {
    fn default() -> Self {
        Self {
            sides: vec![CubeSide::BOTTOM],
            boxes: Vec::new(),
        }
    }
}

impl Anchors {
    /// A lower bound on the gap (largest per-axis distance) between `cell`
    /// and the nearest anchor, for ordering a search towards the anchors;
    /// `0` when there are none.
    fn gap(&self, root: &CellBox, cell: &CellBox) -> i64 {
        let sides = self.sides.iter().map(|s| {
            if s.upper {
                root.max[s.axis] - cell.max[s.axis]
            } else {
                cell.min[s.axis] - root.min[s.axis]
            }
        });
        let boxes = self.boxes.iter().map(|b| {
            (0..3)
                .map(|a| (b.min[a] - cell.max[a]).max(cell.min[a] - b.max[a]).max(0))
                .max()
                .unwrap_or(0)
        });
        sides.chain(boxes).min().unwrap_or(0)
    }
}

/// A connected component of the solid.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Component {
    /// Its cells, sorted.
    pub cells: Vec<SolidCell>,
    /// Whether it touches an anchor.
    pub anchored: bool,
}

impl Octree {
    /// Every connected component of the solid, in the order of their
    /// first cells (leaf order, then BSP node). This walks the whole
    /// octree; [`Octree::detach_unanchored`] searches locally.
    #[must_use]
    pub fn solid_components(&self, anchors: &Anchors) -> Vec<Component> {
        let mut graph = SolidGraph::new(self, anchors);
        let mut seen: WordSet<SolidCell> = WordSet::default();
        let mut out = Vec::new();
        let mut next = Vec::new();
        for (key, _) in self.leaves() {
            for start in graph.solid_cells(key) {
                if !seen.insert(start) {
                    continue;
                }
                let (mut cells, mut stack, mut anchored) = (vec![start], vec![start], false);
                while let Some(cell) = stack.pop() {
                    next.clear();
                    anchored |= graph.expand(cell, &mut next);
                    for &n in &next {
                        if seen.insert(n) {
                            cells.push(n);
                            stack.push(n);
                        }
                    }
                }
                cells.sort_unstable();
                out.push(Component { cells, anchored });
            }
        }
        out
    }

    /// The leaves across the wall of `cell` normal to `axis` (its upper
    /// side when `upper`) whose walls share an area with it, sorted.
    pub(crate) fn leaves_across(&self, cell: &CellBox, axis: usize, upper: bool) -> Vec<CellKey> {
        let c = if upper {
            cell.max[axis]
        } else {
            cell.min[axis]
        };
        let mut out = Vec::new();
        let mut stack = vec![(CellKey::ROOT, &self.root, self.root_box())];
        while let Some((key, node, b)) = stack.pop() {
            let shares_area = (0..3)
                .filter(|&x| x != axis)
                .all(|x| b.min[x] < cell.max[x] && cell.min[x] < b.max[x]);
            if !shares_area {
                continue;
            }
            match node {
                OctNode::Leaf(_) => {
                    let across = if upper { b.min[axis] } else { b.max[axis] };
                    if across == c {
                        out.push(key);
                    }
                }
                OctNode::Inner(children) => {
                    let holds = if upper {
                        b.min[axis] <= c && c < b.max[axis]
                    } else {
                        b.min[axis] < c && c <= b.max[axis]
                    };
                    if holds {
                        for (i, child) in children.iter().enumerate() {
                            stack.push((key.child(i), child, b.child(i)));
                        }
                    }
                }
            }
        }
        out.sort_unstable();
        out
    }
}

/// The solid cells of one leaf, cut once and kept while a search runs.
pub(crate) struct LeafCells<'a> {
    pub(crate) leaf: &'a Leaf,
    pub(crate) cell: CellBox,
    pub(crate) arena: ConvexArena,
    /// `(node, label, polyhedron)` of each solid cell, sorted by node.
    pub(crate) solid: Vec<(NodeId, Label, PolyId)>,
}

impl LeafCells<'_> {
    /// The label and polyhedron of the cell of BSP leaf `node`.
    pub(crate) fn find(&self, node: NodeId) -> Option<(Label, PolyId)> {
        let i = self.solid.binary_search_by_key(&node, |c| c.0).ok()?;
        Some((self.solid[i].1, self.solid[i].2))
    }

    /// The exact volume of the cell of `poly`.
    pub(crate) fn volume(&self, poly: PolyId) -> ExactVolume {
        match self.leaf {
            Leaf::Uniform(_) => ExactVolume::of_box(&self.cell),
            Leaf::Bsp(_) => ExactVolume::of_polyhedron(&self.arena, poly),
        }
    }
}

/// The adjacency graph of an octree's solid cells, built as a search
/// reaches them.
pub(crate) struct SolidGraph<'a> {
    octree: &'a Octree,
    anchors: &'a Anchors,
    root: CellBox,
    leaves: WordMap<CellKey, LeafCells<'a>>,
    /// [`Octree::leaves_across`] by leaf and wall.
    across: WordMap<(CellKey, usize, bool), Vec<CellKey>>,
    /// Sides of the root cube that lead into a neighbouring octree: the
    /// faces on them are collected in `border`, not followed.
    through: Vec<CubeSide>,
    /// The faces on `through` sides that [`SolidGraph::expand`] met since
    /// they were last taken.
    pub(crate) border: Vec<(CubeSide, Polygon)>,
    /// Root sides that are noted, not followed and not anchors (see
    /// [`SolidGraph::noting`]).
    noted: Vec<CubeSide>,
    /// The `noted` sides the cell [`SolidGraph::expand`] last expanded
    /// touches.
    pub(crate) touched: Vec<CubeSide>,
}

impl<'a> SolidGraph<'a> {
    pub(crate) fn new(octree: &'a Octree, anchors: &'a Anchors) -> Self {
        Self {
            octree,
            anchors,
            root: octree.root_box(),
            leaves: WordMap::default(),
            across: WordMap::default(),
            through: Vec::new(),
            border: Vec::new(),
            noted: Vec::new(),
            touched: Vec::new(),
        }
    }

    /// The same graph, with the faces on the root sides `through` handed
    /// back in [`SolidGraph::border`] (they lead into a neighbouring
    /// octree, see `chunks.rs`).
    pub(crate) fn passing(mut self, through: Vec<CubeSide>) -> Self {
        self.through = through;
        self
    }

    /// The same graph, noting in [`SolidGraph::touched`] which of the root
    /// sides `noted` the expanded cell touches (they are neither anchors
    /// nor followed).
    pub(crate) fn noting(mut self, noted: Vec<CubeSide>) -> Self {
        self.noted = noted;
        self
    }

    /// The cells of leaf `key`, cut on first use; `None` when `key` is not
    /// a leaf.
    pub(crate) fn leaf_cells(&mut self, key: CellKey) -> Option<&LeafCells<'a>> {
        if !self.leaves.contains_key(&key) {
            let leaf = self.octree.leaf(key)?;
            let cell = self.octree.cell_box(key);
            let mut arena = ConvexArena::new();
            let solid = match leaf {
                Leaf::Uniform(EMPTY) => Vec::new(),
                Leaf::Uniform(label) => vec![(0, *label, cell.add_to(&mut arena).ok()?)],
                Leaf::Bsp(bsp) => {
                    let bounds = cell.add_to(&mut arena).ok()?;
                    let mut solid: Vec<(NodeId, Label, PolyId)> = bsp
                        .cells(&mut arena, bounds)
                        .into_iter()
                        .filter(|c| c.label != EMPTY)
                        .map(|c| (c.leaf, c.label, c.poly))
                        .collect();
                    solid.sort_unstable_by_key(|c| c.0);
                    solid
                }
            };
            let cells = LeafCells {
                leaf,
                cell,
                arena,
                solid,
            };
            self.leaves.insert(key, cells);
        }
        self.leaves.get(&key)
    }

    /// The solid cells of leaf `key` (none when it is not a leaf).
    pub(crate) fn solid_cells(&mut self, key: CellKey) -> Vec<SolidCell> {
        self.leaf_cells(key).map_or_else(Vec::new, |cells| {
            cells
                .solid
                .iter()
                .map(|&(node, _, _)| SolidCell { key, node })
                .collect()
        })
    }

    /// How far the leaf `key` is from the anchors, at least.
    pub(crate) fn gap(&self, key: CellKey) -> i64 {
        self.anchors.gap(&self.root, &self.octree.cell_box(key))
    }

    /// Appends the solid cells adjacent to `cell` to `out` (sorted, each
    /// once) and tells whether `cell` touches an anchor. Its faces on the
    /// `through` sides go to `border`, the `noted` sides it touches to
    /// `touched`.
    pub(crate) fn expand(&mut self, cell: SolidCell, out: &mut Vec<SolidCell>) -> bool {
        let start = out.len();
        self.touched.clear();
        if self.leaf_cells(cell.key).is_none() {
            return false;
        }
        let Self {
            octree,
            anchors,
            root,
            leaves,
            across,
            through,
            border,
            noted,
            touched,
        } = self;
        let Some(cells) = leaves.get(&cell.key) else {
            return false;
        };
        let Some((_, poly)) = cells.find(cell.node) else {
            return false;
        };
        let arena = &cells.arena;
        let mut anchored = anchors
            .boxes
            .iter()
            .any(|b| shares_volume_with_box(cells, poly, b));
        for f in arena.faces_of(poly) {
            let tag = arena.faces()[f as usize].tag;
            if tag != NO_TAG {
                if let Leaf::Bsp(bsp) = cells.leaf {
                    clip_to_solid_leaves(bsp, tag, cell_face(arena, f), &mut |node| {
                        out.push(SolidCell {
                            key: cell.key,
                            node,
                        });
                    });
                }
                continue;
            }
            let Some((axis, upper)) = wall_of(arena.face_plane(f)) else {
                continue;
            };
            let on_root = if upper {
                cells.cell.max[axis] == root.max[axis]
            } else {
                cells.cell.min[axis] == root.min[axis]
            };
            if on_root {
                let side = CubeSide { axis, upper };
                anchored |= anchors.sides.contains(&side);
                if noted.contains(&side) && !touched.contains(&side) {
                    touched.push(side);
                }
                if through.contains(&side) {
                    border.push((side, cell_face(arena, f)));
                }
                continue;
            }
            let keys = across
                .entry((cell.key, axis, upper))
                .or_insert_with(|| octree.leaves_across(&cells.cell, axis, upper));
            let face = cell_face(arena, f);
            reach_across(octree, keys, &cells.cell, axis, &face, &mut |n| out.push(n));
        }
        out[start..].sort_unstable();
        let mut kept = start;
        for i in start..out.len() {
            if kept == start || out[kept - 1] != out[i] {
                out[kept] = out[i];
                kept += 1;
            }
        }
        out.truncate(kept);
        anchored
    }
}

/// Calls `emit` with every solid cell of `octree` in the leaves `keys`
/// (those across the wall of the box `cell` normal to `axis`, as
/// [`Octree::leaves_across`] lists them) that the face `face` on that wall
/// reaches with positive area. `cell` may be a leaf of another octree
/// whose cube touches this one's there (a neighbouring chunk).
pub(crate) fn reach_across(
    octree: &Octree,
    keys: &[CellKey],
    cell: &CellBox,
    axis: usize,
    face: &Polygon,
    emit: &mut impl FnMut(SolidCell),
) {
    for &key in keys {
        let wall = octree.cell_box(key);
        let Some(piece) = clip_to_wall(face.clone(), cell, &wall, axis) else {
            continue;
        };
        match octree.leaf(key) {
            Some(Leaf::Uniform(label)) if *label != EMPTY => emit(SolidCell { key, node: 0 }),
            Some(Leaf::Bsp(bsp)) => {
                clip_to_solid_leaves(bsp, 0, piece, &mut |node| emit(SolidCell { key, node }));
            }
            _ => {}
        }
    }
}

/// Clips `polygon` down the subtree of `bsp` at `start`, calling `emit`
/// with every solid leaf a piece of positive area reaches (a piece lying
/// in a node's plane goes to the side it faces). Parts towards empty
/// leaves are not built.
fn clip_to_solid_leaves(bsp: &Bsp, start: NodeId, polygon: Polygon, emit: &mut impl FnMut(NodeId)) {
    let nodes = bsp.nodes();
    let empty = |n: NodeId| nodes[n as usize] == Node::Leaf(EMPTY);
    let mut stack = vec![(start, polygon)];
    while let Some((n, polygon)) = stack.pop() {
        match nodes[n as usize] {
            Node::Leaf(label) => {
                if label != EMPTY {
                    emit(n);
                }
            }
            Node::Split {
                plane,
                below,
                above,
            } => {
                let wanted = [!empty(below), !empty(above)];
                if wanted == [false, false] {
                    continue;
                }
                let (b, a) = polygon.split_wanted(&bsp.planes()[plane as usize], wanted);
                stack.extend(a.map(|a| (above, a)));
                stack.extend(b.map(|b| (below, b)));
            }
        }
    }
}

/// The wall a face on a leaf's box lies on: its axis, and whether it is
/// the upper side.
fn wall_of(plane: &Plane) -> Option<(usize, bool)> {
    let n = plane.normal();
    let axis = (0..3).find(|&a| n[a] != 0)?;
    let single = (0..3).all(|a| a == axis || n[a] == 0);
    single.then_some((axis, n[axis] > 0))
}

/// The plane `x_axis = at`, positive side above.
fn axis_plane(axis: usize, at: i64) -> Option<Plane> {
    let mut n = [0i64; 3];
    n[axis] = 1;
    Plane::new(n[0], n[1], n[2], -i128::from(at)).ok()
}

/// The part of `polygon` (on a wall of `cell` normal to `axis`) on the
/// wall of the box `other` across it, if it has positive area.
fn clip_to_wall(polygon: Polygon, cell: &CellBox, other: &CellBox, axis: usize) -> Option<Polygon> {
    let mut polygon = polygon;
    for x in (0..3).filter(|&x| x != axis) {
        if other.min[x] > cell.min[x] {
            polygon = polygon
                .split_wanted(&axis_plane(x, other.min[x])?, [false, true])
                .1?;
        }
        if other.max[x] < cell.max[x] {
            polygon = polygon
                .split_wanted(&axis_plane(x, other.max[x])?, [true, false])
                .0?;
        }
    }
    Some(polygon)
}

/// Whether the cell `poly` of `cells` shares volume with the box `anchor`:
/// the cell cut down to the box keeps a part.
fn shares_volume_with_box(cells: &LeafCells<'_>, poly: PolyId, anchor: &CellBox) -> bool {
    if !cells.cell.overlaps(anchor) {
        return false;
    }
    let inside =
        (0..3).all(|a| anchor.min[a] <= cells.cell.min[a] && cells.cell.max[a] <= anchor.max[a]);
    if inside || matches!(cells.leaf, Leaf::Uniform(_)) {
        return true;
    }
    let (mut arena, mut poly) = cells.arena.extract(poly);
    for a in 0..3 {
        for upper in [false, true] {
            // The outward plane of the box's side: its inside is below.
            let mut n = [0i64; 3];
            let d = if upper {
                if cells.cell.max[a] <= anchor.max[a] {
                    continue;
                }
                n[a] = 1;
                -i128::from(anchor.max[a])
            } else {
                if cells.cell.min[a] >= anchor.min[a] {
                    continue;
                }
                n[a] = -1;
                i128::from(anchor.min[a])
            };
            let Ok(side) = Plane::new(n[0], n[1], n[2], d) else {
                return false;
            };
            match arena.cut_keeping(poly, &side, Part::Below, NO_TAG) {
                KeptOutcome::Cut(kept) => poly = kept,
                KeptOutcome::Below => {}
                KeptOutcome::Above => return false,
            }
        }
    }
    true
}
