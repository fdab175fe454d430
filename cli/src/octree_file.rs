//! Exact octree files (`.chisel`) for the commands: recognising them,
//! reading and writing them, and moving an octree into another cube
//! exactly.
//!
//! A `.chisel` file holds the octree itself with every plane as exact
//! integers (`chisel_bsp::octree::store`), on the commands' 1 µm grid. It
//! reads back bit-identically, so a result can be carved or combined again
//! with no re-import: a mesh export rounds vertices to floats, and a
//! rounded surface can come back self-intersecting.

use std::collections::BTreeSet;
use std::path::Path;

use chisel_bsp::convex::ConvexArena;
use chisel_bsp::octree::{CellBox, Edit, Leaf, Octree, Tool};
use chisel_bsp::tree::{EMPTY, Label, Node};

/// The extension of exact octree files.
pub const EXTENSION: &str = "chisel";

/// Whether `path` names an exact octree file (by its extension, any case).
#[must_use]
pub fn is_octree_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(EXTENSION))
}

/// Reads an octree file.
///
/// # Errors
/// A message naming the file: unreadable, not an octree file, damaged or
/// malformed.
pub fn read(path: &Path) -> Result<Octree, String> {
    Octree::load(path).map_err(|e| match e {
        chisel_bsp::Error::Io { message } => message,
        e => format!("{}: {e}", path.display()),
    })
}

/// Writes an octree file.
///
/// # Errors
/// A message naming the file.
pub fn write(path: &Path, octree: &Octree) -> Result<(), String> {
    crate::atomic::write_bytes(path, &octree.to_bytes())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// The box around every leaf cell that may hold material, or `None` when
/// the octree is empty.
#[must_use]
pub fn solid_bounds(octree: &Octree) -> Option<CellBox> {
    octree
        .leaves()
        .into_iter()
        .filter(|(_, leaf)| !matches!(leaf, Leaf::Uniform(EMPTY)))
        .map(|(key, _)| octree.cell_box(key))
        .reduce(|a, b| CellBox {
            min: [0, 1, 2].map(|i| a.min[i].min(b.min[i])),
            max: [0, 1, 2].map(|i| a.max[i].max(b.max[i])),
        })
}

/// Whether box `outer` holds box `inner`.
#[must_use]
pub fn holds(outer: &CellBox, inner: &CellBox) -> bool {
    (0..3).all(|a| outer.min[a] <= inner.min[a] && inner.max[a] <= outer.max[a])
}

/// The labels that `leaf` holds somewhere (empty included).
#[must_use]
pub fn leaf_labels(leaf: &Leaf) -> BTreeSet<Label> {
    match leaf {
        Leaf::Uniform(label) => BTreeSet::from([*label]),
        Leaf::Bsp(bsp) => bsp
            .nodes()
            .iter()
            .filter_map(|n| match n {
                Node::Leaf(label) => Some(*label),
                Node::Split { .. } => None,
            })
            .collect(),
    }
}

/// The tool holding exactly the parts of one leaf (box `cell`) whose label
/// `wanted` accepts, or `None` when there are none: the leaf's convex cells
/// inside its box are exact convex polyhedra.
///
/// # Errors
/// A message for geometry the kernel refuses (it cannot happen for the
/// leaves of a valid octree).
pub fn leaf_tool(
    leaf: &Leaf,
    cell: CellBox,
    wanted: impl Fn(Label) -> bool,
) -> Result<Option<Tool>, String> {
    match leaf {
        Leaf::Uniform(label) if wanted(*label) => {
            Tool::cuboid(cell).map(Some).map_err(|e| e.to_string())
        }
        Leaf::Uniform(_) => Ok(None),
        Leaf::Bsp(bsp) => {
            let mut arena = ConvexArena::new();
            let bounds = cell.add_to(&mut arena).map_err(|e| e.to_string())?;
            let pieces: Vec<Tool> = bsp
                .cells(&mut arena, bounds)
                .into_iter()
                .filter(|c| wanted(c.label))
                .map(|c| Tool::from_polyhedron(&arena, c.poly))
                .collect();
            if pieces.is_empty() {
                return Ok(None);
            }
            Tool::union(&pieces).map(Some).map_err(|e| e.to_string())
        }
    }
}

/// The same solid (every material) in the cube at `origin` with edge
/// `2^size_log2`, exactly: the octree itself when it already has that
/// cube, else every leaf's material added, label by label, to an empty
/// octree over the new cube. Material outside the new cube is cut off, so
/// callers pick a cube holding [`solid_bounds`].
///
/// # Errors
/// A message for a cube outside the exact range.
pub fn embed(octree: Octree, origin: [i64; 3], size_log2: u8) -> Result<Octree, String> {
    if octree.origin() == origin && octree.size_log2() == size_log2 {
        return Ok(octree);
    }
    let mut out =
        Octree::new(origin, size_log2, EMPTY, *octree.config()).map_err(|e| e.to_string())?;
    for (key, leaf) in octree.leaves() {
        for label in leaf_labels(leaf).into_iter().filter(|&l| l != EMPTY) {
            if let Some(tool) = leaf_tool(leaf, octree.cell_box(key), |l| l == label)? {
                out.apply(&tool, Edit::Add(label))
                    .map_err(|e| e.to_string())?;
            }
        }
    }
    Ok(out)
}
