//! Splitting a leaf over the budget into its eight children from its
//! boundary faces (paper 1 §3.7–§3.8).
//!
//! Notation: `C` — the leaf's box, `m` its centre, `C_i` child `i`
//! ([`CellBox::child`]); `T` — the leaf's BSP; `F` — the exact boundary of
//! `T` inside `C`, with the faces on `C` marked
//! [`BoundaryFace::on_bounds`] (what the rebuild of `T` started from, or
//! [`Bsp::boundary`]); `L` / `O` — the labels behind / in front of a face.
//!
//! `F` is the whole surface inside `C`, so its pieces inside `C_i` are the
//! whole surface inside `C_i`: each face is clipped exactly by the three
//! planes `x_a = m_a` (plane-based polygons: no new plane, exact corners),
//! and `C_i`'s BSP is rebuilt from its inner pieces as
//! [`Bsp::simplified`] would rebuild `T` inside `C_i` — the same regions,
//! possibly other face pieces. The walls between siblings carry no
//! surface (the material is the same on both sides), except where a face
//! of `F` lies in a plane `x_a = m_a`: that face is on the box of the
//! child behind it, handed to it as a face on its bounds with label `L`,
//! and, for an interface (`O` not empty), on the box of the child in
//! front, handed to it reversed with label `O` — what extracting `T`'s
//! boundary inside each child box gives there. The pieces of the faces on
//! `C` are on the children's outer walls, marked as before. So each
//! child's pieces, once their border faces are resolved against the
//! regions across ([`super::Octree::cell_surface_from`]), give its exact
//! surface, and they are what splitting the child again starts from.
//!
//! A child with no inner piece holds one label: that of `T` at a point
//! strictly inside `C_i`, its centre pushed by `ε·(1, ε, ε²)` so that it
//! lies on no plane and the leaf reached is a region meeting `C_i`.

use super::cell::CellBox;
use crate::exact::{Plane, Sign};
use crate::tree::polygon::{Polygon, classify_polygon_corners};
use crate::tree::{BoundaryFace, Bsp, EMPTY, Label};

/// The pieces of `faces` (the exact boundary inside `cell`, faces on its
/// box marked) inside each child of `cell`, by child index: inner pieces
/// unmarked, pieces on the child's box marked [`BoundaryFace::on_bounds`]
/// (see the module notes for the faces lying between two children). The
/// pieces keep the order of `faces`.
pub(crate) fn split_faces(faces: Vec<BoundaryFace>, cell: &CellBox) -> [Vec<BoundaryFace>; 8] {
    let mid = cell.mid();
    let planes = [0, 1, 2].map(|axis| axis_plane(axis, mid[axis]));
    let mut out: [Vec<BoundaryFace>; 8] = Default::default();
    // Parts above a plane, waiting with their child bits so far, the axis
    // whose middle plane they lie in (if any) and the next axis.
    let mut waiting = Vec::new();
    let mut sides = Vec::new();
    for face in faces {
        let (label, outside, on_bounds) = (face.label, face.outside, face.on_bounds);
        // Depth first, below before above: the pieces in the order that
        // splitting all of them by one plane after the other gives. A
        // piece that is not split goes on in place.
        let mut first = Some((face.into_polygon(), 0usize, None::<usize>, 0usize));
        while let Some((mut piece, mut bits, mut lies_in, start)) =
            first.take().or_else(|| waiting.pop())
        {
            for (axis, plane) in planes.iter().enumerate().skip(start) {
                sides.clear();
                sides.resize(piece.vertices().len(), Sign::Zero);
                let (support, edges) = (&piece.support, &piece.edges);
                match classify_polygon_corners(support, edges, piece.vertices(), plane, &mut sides)
                {
                    (true, true) => {
                        let (below, above) = piece.split_straddling(&sides, plane);
                        waiting.push((above, bits | 1 << axis, lies_in, axis + 1));
                        piece = below;
                    }
                    (true, false) => {}
                    (false, true) => bits |= 1 << axis,
                    // In the plane: the child bit on this axis is the side
                    // behind the face, set below.
                    (false, false) => lies_in = Some(axis),
                }
            }
            let Some(axis) = lies_in else {
                out[bits].push(BoundaryFace::new(piece, label, outside, on_bounds));
                continue;
            };
            // The face points towards the side of the material in front.
            let faces_up = piece.support.normal()[axis] > 0;
            let (behind, in_front) = if faces_up {
                (bits, bits | 1 << axis)
            } else {
                (bits | 1 << axis, bits)
            };
            if outside != EMPTY {
                out[in_front].push(BoundaryFace::new(reversed(&piece), outside, EMPTY, true));
            }
            out[behind].push(BoundaryFace::new(piece, label, EMPTY, true));
        }
    }
    out
}

/// The BSP of `child` from its pieces (from [`split_faces`]): rebuilt from
/// the inner pieces, or one label — that of `parent` inside the child —
/// when there is none.
#[cfg(test)]
pub(crate) fn child_bsp(parent: &Bsp, pieces: &[BoundaryFace], child: &CellBox) -> Bsp {
    Bsp::rebuilt_from_boundary(pieces).unwrap_or_else(|| Bsp::uniform(label_inside(parent, child)))
}

/// [`child_bsp`] when it has at most `max_splits` splits, else `None`
/// (the rebuild is left unfinished as soon as it has more).
pub(crate) fn child_bsp_within(
    parent: &Bsp,
    pieces: &[BoundaryFace],
    child: &CellBox,
    max_splits: usize,
) -> Option<Bsp> {
    let rebuilt = Bsp::rebuilt_from_boundary_within(pieces, max_splits)?;
    Some(rebuilt.unwrap_or_else(|| Bsp::uniform(label_inside(parent, child))))
}

/// The label of `bsp` at the centre of `cell` pushed by `ε·(1, ε, ε²)`: a
/// point strictly inside `cell` on no plane.
fn label_inside(bsp: &Bsp, cell: &CellBox) -> Label {
    let twice = [0, 1, 2].map(|a| i128::from(cell.min[a]) + i128::from(cell.max[a]));
    bsp.label_near(twice, [1; 3], [0, 1, 2])
}

/// The same polygon facing the other way.
fn reversed(polygon: &Polygon) -> Polygon {
    Polygon::new(
        polygon.support.flipped(),
        polygon.edges.iter().rev().copied().collect(),
    )
}

/// The plane `x_axis = at`, positive side above.
fn axis_plane(axis: usize, at: i64) -> Plane {
    let mut n = [0i64; 3];
    n[axis] = 1;
    Plane::new(n[0], n[1], n[2], -i128::from(at)).expect("cell coordinates are in range")
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::convex::{ConvexArena, with_arena};
    use crate::tree::{Node, NodeId};

    /// The cell the tests split: centre 0, so that the middle planes are
    /// the coordinate planes.
    const CELL: CellBox = CellBox {
        min: [-64; 3],
        max: [64; 3],
    };

    /// A random plane through a random point of the cell: an axis plane at
    /// an even coordinate (often a middle plane of the cell) or of a
    /// random small normal.
    fn random_plane(rng: &mut ChaCha8Rng) -> ([i64; 3], Plane) {
        let mut x = [0; 3].map(|_| 2 * rng.random_range(-31..32));
        let n = if rng.random_bool(0.4) {
            let (mut n, axis) = ([0; 3], rng.random_range(0..3));
            n[axis] = if rng.random_bool(0.5) { 1 } else { -3 };
            if rng.random_bool(0.5) {
                x[axis] = 0;
            }
            n
        } else {
            [0; 3].map(|_| rng.random_range(-20i64..=20))
        };
        let d = -(0..3)
            .map(|i| i128::from(n[i]) * i128::from(x[i]))
            .sum::<i128>();
        (
            x,
            Plane::new(n[0], n[1], n[2], d).unwrap_or_else(|_| axis_plane(0, 0)),
        )
    }

    /// A random BSP: the leaf holding a random point split by a random
    /// plane, new leaves with random labels below `labels`.
    fn random_bsp(rng: &mut ChaCha8Rng, splits: usize, labels: Label) -> Bsp {
        let mut planes: Vec<Plane> = Vec::new();
        let mut nodes = vec![Node::Leaf(rng.random_range(0..labels))];
        while planes.len() < splits {
            let (x, plane) = random_plane(rng);
            let mut at = 0;
            while let Node::Split {
                plane,
                below,
                above,
            } = nodes[at]
            {
                let q = planes[plane as usize];
                let value = (0..3)
                    .map(|a| i128::from(q.normal()[a]) * i128::from(x[a]))
                    .sum::<i128>()
                    + q.offset();
                at = if value > 0 { above } else { below } as usize;
            }
            let below = nodes.len() as NodeId;
            nodes.push(Node::Leaf(rng.random_range(0..labels)));
            nodes.push(Node::Leaf(rng.random_range(0..labels)));
            nodes[at] = Node::Split {
                plane: planes.len() as u32,
                below,
                above: below + 1,
            };
            planes.push(plane);
        }
        Bsp::from_parts(planes, nodes)
    }

    /// Whether `a` and `b` have the same label everywhere inside `cell`:
    /// every cell of `a` there, cut by `b`, has only pieces of its label.
    fn same_regions(a: &Bsp, b: &Bsp, cell: &CellBox) -> bool {
        let mut arena = ConvexArena::new();
        let bounds = cell.add_to(&mut arena).unwrap();
        let cells = a.cells(&mut arena, bounds);
        cells.iter().all(|c| {
            b.cells(&mut arena, c.poly)
                .iter()
                .all(|piece| piece.label == c.label)
        })
    }

    /// The parent's rebuild and its faces inside `CELL`, as an edit
    /// hands them to the split.
    fn rebuilt_with_faces(bsp: &Bsp) -> (Bsp, Vec<BoundaryFace>) {
        with_arena(|arena| {
            let bounds = CELL.add_to(arena).unwrap();
            bsp.simplified_faces(arena, bounds)
        })
    }

    /// Each child rebuilt from its pieces has exactly the regions of the
    /// parent rebuilt inside the child's box, for random trees of several
    /// materials with many planes in the middle planes; so do the
    /// grandchildren split again from the children's pieces.
    #[test]
    fn children_from_pieces_have_the_regions_of_the_parent() {
        let mut rng = ChaCha8Rng::seed_from_u64(41);
        let (mut uniform, mut in_middle) = (0, 0);
        for round in 0..60 {
            let splits = rng.random_range(2..24);
            let (parent, faces) = rebuilt_with_faces(&random_bsp(&mut rng, splits, 4));
            let pieces = split_faces(faces, &CELL);
            for (i, pieces) in pieces.into_iter().enumerate() {
                let child = CELL.child(i);
                let bsp = child_bsp(&parent, &pieces, &child);
                assert!(
                    same_regions(&parent, &bsp, &child),
                    "round {round}, child {i}"
                );
                assert!(same_regions(&bsp, &parent, &child));
                uniform += usize::from(bsp.nodes().len() == 1);
                in_middle += pieces
                    .iter()
                    .filter(|f| f.on_bounds && !faces_out_of_child(f, &CELL, &child))
                    .count();
                let grandchildren = split_faces(pieces, &child);
                for (j, pieces) in grandchildren.into_iter().enumerate() {
                    let grandchild = child.child(j);
                    let small = child_bsp(&bsp, &pieces, &grandchild);
                    assert!(
                        same_regions(&parent, &small, &grandchild),
                        "round {round}, child {i}, {j}"
                    );
                }
            }
        }
        assert!(uniform > 20 && in_middle > 20, "{uniform} {in_middle}");
    }

    /// Whether a face on the box of `child` lies on the box of its parent
    /// `cell` (rather than in a middle plane).
    fn faces_out_of_child(face: &BoundaryFace, cell: &CellBox, child: &CellBox) -> bool {
        let n = face.plane.normal();
        (0..3).any(|a| {
            let at = if n[a] > 0 { child.max[a] } else { child.min[a] };
            let wall = if n[a] > 0 { cell.max[a] } else { cell.min[a] };
            n[a] != 0 && at == wall && i128::from(n[a]) * i128::from(at) + face.plane.offset() == 0
        })
    }

    /// A face in a middle plane between two materials goes to the child
    /// behind it with its label, and reversed to the child in front with
    /// the label in front; one on the empty side goes only behind.
    #[test]
    fn faces_in_a_middle_plane_go_to_both_children() {
        // Material 2 below z = 0, material 1 above it for x < 32, empty
        // above it for x > 32.
        let z = axis_plane(2, 0);
        let x = axis_plane(0, 32);
        let nodes = vec![
            Node::Split {
                plane: 0,
                below: 1,
                above: 2,
            },
            Node::Leaf(2),
            Node::Split {
                plane: 1,
                below: 3,
                above: 4,
            },
            Node::Leaf(1),
            Node::Leaf(EMPTY),
        ];
        let parent = Bsp::from_parts(vec![z, x], nodes);
        let (rebuilt, faces) = rebuilt_with_faces(&parent);
        let pieces = split_faces(faces, &CELL);
        for (i, pieces) in pieces.iter().enumerate() {
            let child = CELL.child(i);
            let upper_x = i & 1 == 1;
            let upper_z = i & 4 == 4;
            let middle: Vec<&BoundaryFace> = pieces
                .iter()
                .filter(|f| f.on_bounds && f.plane.normal()[2] != 0)
                .filter(|f| !faces_out_of_child(f, &CELL, &child))
                .collect();
            // Above x = 32 the face on z = 0 is between material 2 and
            // empty: the upper child has no piece of it.
            let expected: Vec<(Label, bool)> = match (upper_x, upper_z) {
                (false, false) => vec![(2, true)],
                (true, false) => vec![(2, true), (2, true)],
                (_, true) => vec![(1, false)],
            };
            let found: Vec<(Label, bool)> = middle
                .iter()
                .map(|f| (f.label, f.plane.normal()[2] > 0))
                .collect();
            assert_eq!(found, expected, "child {i}");
            assert!(middle.iter().all(|f| f.outside == EMPTY));
            let bsp = child_bsp(&rebuilt, pieces, &child);
            assert!(same_regions(&parent, &bsp, &child), "child {i}");
        }
    }

    /// Where the centre of a box lies on planes, the push goes to the same
    /// side of each: the region reached meets the box, never one of zero
    /// width between a plane and itself flipped.
    #[test]
    fn a_centre_on_planes_reads_a_region_inside() {
        let (x, flipped) = (axis_plane(0, 0), axis_plane(0, 0).flipped());
        let split = |plane, below, above| Node::Split {
            plane,
            below,
            above,
        };
        let cell = CellBox {
            min: [-1; 3],
            max: [1; 3],
        };
        // x > 0 is label 3 in both trees, x < 0 label 2, and the region
        // below both planes (none) label 1.
        let nodes = vec![
            split(0, 1, 2),
            split(1, 3, 4),
            Node::Leaf(3),
            Node::Leaf(1),
            Node::Leaf(2),
        ];
        let bsp = Bsp::from_parts(vec![x, flipped], nodes);
        assert_eq!(label_inside(&bsp, &cell), 3);
        let nodes = vec![
            split(0, 1, 2),
            split(1, 3, 4),
            Node::Leaf(2),
            Node::Leaf(1),
            Node::Leaf(3),
        ];
        let bsp = Bsp::from_parts(vec![flipped, x], nodes);
        assert_eq!(label_inside(&bsp, &cell), 3);
    }
}
