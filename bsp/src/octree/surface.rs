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
//! octree, with no face between two cells of the same material.
//!
//! Meshed cell by cell, neighbouring cells cut their common walls
//! differently, so a border edge of one cell's mesh may pass through a
//! vertex of its neighbour's; [`super::seams`] seals each cell's mesh at
//! its neighbours' wall vertices, so that cell meshes meet edge to edge.

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
        self.resolve_borders_in(faces, cell, Descent::default())
    }

    /// [`Self::resolve_borders`] with the working memory `scratch`.
    fn resolve_borders_in<'a>(
        &'a self,
        faces: Vec<BoundaryFace>,
        cell: &CellBox,
        mut scratch: Descent<'a>,
    ) -> Vec<BoundaryFace> {
        let mut out = Vec::with_capacity(faces.len());
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
        let (start, start_box) = match facing.0 {
            Some((axis, positive)) => *scratch.starts[2 * axis + usize::from(positive)]
                .get_or_insert_with(|| self.first_split(facing, from)),
            None => (&self.root, root),
        };
        let Descent {
            stack,
            pieces,
            next,
            clip,
            nodes,
            starts: _,
        } = scratch;
        stack.push((start, start_box, polygon, *from));
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
/// visit when testing whether a piece is dropped whole; and per side of
/// the cell (`2·axis + positive`), once known, where every border face on
/// that side starts ([`Octree::first_split`]).
#[derive(Default)]
struct Descent<'a> {
    stack: Vec<(&'a OctNode, CellBox, Polygon, CellBox)>,
    pieces: Vec<(Polygon, CellBox, usize)>,
    next: Vec<(Polygon, CellBox, usize)>,
    clip: Vec<(NodeId, Polygon)>,
    nodes: Vec<NodeId>,
    starts: [Option<(&'a OctNode, CellBox)>; 6],
}

impl Octree {
    /// The octree node (with its box) where the descent of a border face
    /// with `facing` on the leaf box `from` first meets an inner cell
    /// whose axis planes may cut it, or a leaf: down from the root through
    /// the inner cells that hold `from`'s side whole. The descent depends
    /// only on the side (its range is `from` until the first split), so
    /// it is found once per side and every face on that side starts there.
    fn first_split(&self, facing: Facing, from: &CellBox) -> (&OctNode, CellBox) {
        let (mut node, mut cell) = (&self.root, self.root_box());
        while let OctNode::Inner(children) = node {
            let Some(i) = facing.child_holding(&cell, from) else {
                break;
            };
            node = &children[i];
            cell = cell.child(i);
        }
        (node, cell)
    }
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

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::octree::{Edit, OctreeConfig, Tool};
    use crate::tools::{Pose, dodecahedron_corners};

    const SIZE: i64 = 1 << 12;

    /// A dodecahedron of random size, rotation and place in the block.
    fn random_tool(rng: &mut ChaCha8Rng) -> Tool {
        let scale = rng.random_range(60.0..300.0);
        let a = rng.random_range(0.0..6.3f64);
        let (ca, sa) = (a.cos(), a.sin());
        let pose = Pose {
            rotation: [[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]],
            translation: [0, 1, 2].map(|_| rng.random_range(0.0..SIZE as f64)),
        };
        Tool::placed(&dodecahedron_corners(scale), &pose).unwrap()
    }

    /// Every leaf's border faces resolved with the descent of each side
    /// found once and with every face descending from the root give the
    /// same pieces, element for element, after random edits (materials
    /// 1 to 3, so that faces are kept towards smaller labels too).
    #[test]
    fn faces_start_where_the_descent_from_the_root_first_splits() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let config = OctreeConfig {
            max_bsp_nodes: 30,
            max_depth: 6,
        };
        let block = CellBox {
            min: [100; 3],
            max: [SIZE - 100; 3],
        };
        let mut octree = Octree::from_box([0; 3], 12, block, 1, config).unwrap();
        for i in 0..24 {
            let edit = match i % 4 {
                3 => Edit::Add(rng.random_range(2..=3)),
                _ => Edit::Subtract,
            };
            octree.apply(&random_tool(&mut rng), edit).unwrap();
        }
        let (mut borders, mut kept) = (0, 0);
        for (key, leaf) in octree.leaves() {
            let Leaf::Bsp(bsp) = leaf else { continue };
            let cell = octree.cell_box(key);
            let faces = with_arena(|arena| {
                let bounds = cell.add_to(arena).unwrap();
                bsp.boundary(arena, bounds)
            });
            borders += faces.iter().filter(|f| f.on_bounds).count();
            let cached = octree.resolve_borders(faces.clone(), &cell);
            let from_root = Descent {
                starts: [Some((&octree.root, octree.root_box())); 6],
                ..Descent::default()
            };
            let reference = octree.resolve_borders_in(faces, &cell, from_root);
            assert_eq!(cached.len(), reference.len(), "{key:?}");
            for (a, b) in cached.iter().zip(&reference) {
                assert_eq!(
                    (a.plane, &a.edges, a.label, a.outside, a.on_bounds),
                    (b.plane, &b.edges, b.label, b.outside, b.on_bounds),
                    "{key:?}"
                );
                assert!(
                    a.vertices
                        .iter()
                        .zip(&b.vertices)
                        .all(|(p, q)| { (p.xyz_digits, p.w_digits) == (q.xyz_digits, q.w_digits) })
                );
            }
            kept += cached.len();
        }
        assert!(
            borders > 500 && kept > 500,
            "{borders} border faces, {kept} kept"
        );
    }
}
