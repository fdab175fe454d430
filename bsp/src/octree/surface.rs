//! The surface of an octree (paper 1 §3.4 across cells).
//!
//! Notation: a *border face* is a face of a leaf's solid lying on the
//! leaf's box; the *region across* it is what lies in front of it — a part
//! of a neighbouring leaf, or the outside of the root cube (empty).
//!
//! Inside a leaf the surface is its BSP's boundary ([`Bsp::boundary`]), or
//! after an edit the boundary its rebuild started from
//! ([`Octree::cell_surface_from`]: the same exact surface, cut into pieces
//! by the merged tree's planes rather than the rebuilt tree's).
//! A border face is clipped exactly against the region across: descending
//! from the root, it is split by the axis planes of each inner cell it
//! reaches (a face lying in such a plane goes to the side it faces), then
//! against the neighbour's BSP — unless, followed down that BSP whole (to
//! both sides of each plane it straddles), it reaches no leaf with a
//! smaller label (`Bsp::drops_whole`): then nothing of it would be kept,
//! and it is dropped uncut, as most border faces are. Pieces are kept
//! where the label across is smaller — empty, or a material with a
//! smaller label (an interface is reported once) — so the union of all
//! cells' surfaces is the boundary of every material region of the
//! octree, with no face between two cells of the same material. T-junctions between cells remain; the mesh stage
//! removes them.

use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::tree::{Leaf, OctNode, Octree};
use crate::convex::with_arena;
use crate::exact::Plane;
use crate::tree::polygon::Polygon;
use crate::tree::{BoundaryFace, Bsp, EMPTY, Label, NodeId};

impl Octree {
    /// The surface pieces of leaf cell `key` (empty when `key` is not a
    /// leaf): the faces between materials inside it, and its border faces
    /// where the region across has a smaller label. Every piece has
    /// [`BoundaryFace::on_bounds`] false: border faces are resolved.
    #[must_use]
    pub fn cell_surface(&self, key: CellKey) -> Vec<BoundaryFace> {
        let Some(leaf) = self.leaf(key) else {
            return Vec::new();
        };
        if matches!(leaf, Leaf::Uniform(EMPTY)) {
            return Vec::new();
        }
        // The leaf's own BSP, borrowed (a uniform leaf's is one node).
        let uniform;
        let bsp: &Bsp = match leaf {
            Leaf::Bsp(bsp) => bsp,
            Leaf::Uniform(label) => {
                uniform = Bsp::uniform(*label);
                &uniform
            }
        };
        let cell = self.cell_box(key);
        let faces = with_arena(|arena| match cell.add_to(arena) {
            Ok(bounds) => bsp.boundary(arena, bounds),
            Err(_) => Vec::new(),
        });
        self.resolve_borders(faces, &cell)
    }

    /// The surface pieces of leaf cell `key` from its boundary `faces`
    /// inside the cell (as [`Octree::apply_with_faces`] hands them back):
    /// the border faces ([`BoundaryFace::on_bounds`]) are clipped against
    /// the regions across, the others kept. The same exact surface as
    /// [`Octree::cell_surface`] (empty when `key` is not a leaf), possibly
    /// in different pieces.
    #[must_use]
    pub fn cell_surface_from(&self, key: CellKey, faces: Vec<BoundaryFace>) -> Vec<BoundaryFace> {
        if self.leaf(key).is_none() {
            return Vec::new();
        }
        self.resolve_borders(faces, &self.cell_box(key))
    }

    /// The boundary `faces` of a leaf inside `cell`, with its border faces
    /// clipped against the regions across and the others kept.
    fn resolve_borders(&self, faces: Vec<BoundaryFace>, cell: &CellBox) -> Vec<BoundaryFace> {
        let mut out = Vec::with_capacity(faces.len());
        let mut scratch = Descent::default();
        for face in faces {
            if face.on_bounds {
                let label = face.label;
                self.clip_across(face.into_polygon(), label, cell, &mut scratch, &mut out);
            } else {
                out.push(face);
            }
        }
        out
    }

    /// The surface of every leaf, in leaf order (cells run in parallel).
    #[must_use]
    pub fn surface(&self) -> Vec<BoundaryFace> {
        let keys: Vec<CellKey> = self.leaves().into_iter().map(|(k, _)| k).collect();
        keys.par_iter()
            .map(|&key| self.cell_surface(key))
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect()
    }

    /// Clips a border face of solid `label` on the box `from` (the leaf it
    /// belongs to) against the region across it.
    ///
    /// Descending, a piece is split by an axis plane only where that plane
    /// crosses the box range known to hold the piece (`from`'s, narrowed by
    /// earlier splits): elsewhere the split would return the piece whole,
    /// to the same side, so the pieces and their order are those of
    /// splitting at every axis plane.
    fn clip_across<'a>(
        &'a self,
        polygon: Polygon,
        label: Label,
        from: &CellBox,
        scratch: &mut Descent<'a>,
        out: &mut Vec<BoundaryFace>,
    ) {
        let mut emit = |piece: Polygon, other: Label| {
            if other < label {
                out.push(BoundaryFace::new(piece, label, other, false));
            }
        };
        let root = self.root_box();
        if faces_out_of(&polygon.support, &root) {
            emit(polygon, EMPTY);
            return;
        }
        let facing = Facing::of(&polygon.support, from);
        let Descent {
            stack,
            pieces,
            next,
            clip,
            nodes,
        } = scratch;
        stack.push((&self.root, root, polygon, *from));
        while let Some((mut node, mut cell, polygon, range)) = stack.pop() {
            // Down through the inner cells that no axis plane cuts the piece
            // in (most of the way from the root): the piece goes on whole,
            // as the split below would hand it on.
            while let OctNode::Inner(children) = node {
                let Some(i) = facing.child_holding(&cell, &range) else {
                    break;
                };
                node = &children[i];
                cell = cell.child(i);
            }
            match node {
                OctNode::Leaf(Leaf::Uniform(other)) => emit(polygon, *other),
                OctNode::Leaf(Leaf::Bsp(bsp)) => {
                    // Mostly the neighbour's solid covers the piece: then
                    // it is dropped without being cut up.
                    if !bsp.drops_whole(&polygon, label, nodes) {
                        bsp.clip_polygon(0, polygon, label, clip, &mut emit);
                    }
                }
                OctNode::Inner(children) => {
                    let mid = cell.mid();
                    pieces.push((polygon, range, 0usize));
                    for (axis, &m) in mid.iter().enumerate() {
                        for (piece, range, bits) in pieces.drain(..) {
                            match facing.side(axis, m, &range) {
                                Some(false) => next.push((piece, range, bits)),
                                Some(true) => next.push((piece, range, bits | 1 << axis)),
                                None => {
                                    let (below, above) = piece.split(&axis_plane(axis, m));
                                    let (mut rb, mut ra) = (range, range);
                                    rb.max[axis] = rb.max[axis].min(m);
                                    ra.min[axis] = ra.min[axis].max(m);
                                    next.extend(below.map(|p| (p, rb, bits)));
                                    next.extend(above.map(|p| (p, ra, bits | 1 << axis)));
                                }
                            }
                        }
                        std::mem::swap(pieces, next);
                    }
                    for (piece, range, i) in pieces.drain(..) {
                        stack.push((&children[i], cell.child(i), piece, range));
                    }
                }
            }
        }
    }
}

/// Working memory of [`Octree::clip_across`], reused across the border
/// faces of a cell: the cells still to visit with their piece and the box
/// range known to hold it, the pieces of one inner cell, axis by axis, and
/// the pieces still to clip in a neighbour's BSP, and its nodes still to
/// visit when testing whether a piece is dropped whole.
#[derive(Default)]
struct Descent<'a> {
    stack: Vec<(&'a OctNode, CellBox, Polygon, CellBox)>,
    pieces: Vec<(Polygon, CellBox, usize)>,
    next: Vec<(Polygon, CellBox, usize)>,
    clip: Vec<(NodeId, Polygon)>,
    nodes: Vec<NodeId>,
}

/// The one axis a normal `n` has a non-zero component on, if only one.
#[inline]
fn single_axis(n: [i64; 3]) -> Option<usize> {
    match (n[0] != 0, n[1] != 0, n[2] != 0) {
        (true, false, false) => Some(0),
        (false, true, false) => Some(1),
        (false, false, true) => Some(2),
        _ => None,
    }
}

/// The plane `x_axis = at`, positive side above.
fn axis_plane(axis: usize, at: i64) -> Plane {
    let mut n = [0i64; 3];
    n[axis] = 1;
    Plane::new(n[0], n[1], n[2], -i128::from(at)).expect("cell coordinates are in range")
}

/// Where a border face lies: the axis its plane is normal to and whether
/// it faces the positive direction, or nothing known (every axis plane
/// then splits exactly).
#[derive(Clone, Copy)]
struct Facing(Option<(usize, bool)>);

impl Facing {
    /// The facing of a face with support `plane` lying on the box `from`.
    fn of(plane: &Plane, from: &CellBox) -> Self {
        let n = plane.normal();
        let Some(axis) = single_axis(n) else {
            return Self(None);
        };
        let positive = n[axis] > 0;
        // n_a·x + d = 0 must be the box's own face on that side.
        let at = if positive {
            from.max[axis]
        } else {
            from.min[axis]
        };
        let on_box = i128::from(n[axis]) * i128::from(at) + plane.offset() == 0;
        Self(on_box.then_some((axis, positive)))
    }

    /// The child of the inner cell `cell` that a piece of the face within
    /// `range` goes to whole, or `None` when an axis plane of the cell may
    /// cut it.
    #[inline]
    fn child_holding(self, cell: &CellBox, range: &CellBox) -> Option<usize> {
        let mid = cell.mid();
        let mut i = 0;
        for (axis, &m) in mid.iter().enumerate() {
            if self.side(axis, m, range)? {
                i |= 1 << axis;
            }
        }
        Some(i)
    }

    /// The side of the plane `x_axis = m` (`true` above) that a piece of
    /// the face within `range` goes to whole, or `None` when the plane may
    /// cut it.
    fn side(self, axis: usize, m: i64, range: &CellBox) -> Option<bool> {
        let (a, positive) = self.0?;
        if axis == a {
            // The face lies in x_a = its box side: in the plane it goes to
            // the side it faces.
            let c = if positive { range.max[a] } else { range.min[a] };
            return Some(if c == m { positive } else { c > m });
        }
        if range.max[axis] <= m {
            Some(false)
        } else if range.min[axis] >= m {
            Some(true)
        } else {
            None
        }
    }
}

/// Whether a plane is one of the faces of `cube`, oriented outward.
fn faces_out_of(plane: &Plane, cube: &CellBox) -> bool {
    let n = plane.normal();
    let Some(axis) = single_axis(n) else {
        return false;
    };
    // n_a·x + d = 0 is the side x = c exactly when n_a·c + d = 0.
    let na = n[axis];
    let side = if na > 0 {
        cube.max[axis]
    } else {
        cube.min[axis]
    };
    i128::from(na) * i128::from(side) + plane.offset() == 0
}
