//! Octree-embedded BSPs (paper 1 §3.8): a persistent octree whose leaves
//! hold a small BSP or one label, so that the cost of an edit depends on
//! the tool, not on how much has been edited before.
//!
//! Notation: a *cell* is an octree node's axis-aligned box, named by its
//! [`CellKey`]; a *leaf* holds a [`Leaf`]; the *budget* is the maximal
//! number of inner BSP nodes per leaf ([`OctreeConfig::max_bsp_nodes`]).
//!
//! - [`cell`] — cell keys and integer boxes.
//! - [`tree`] — the persistent octree: construction, leaves, statistics.
//! - [`tool`] — convex tools (and unions of them) with their bounds.
//! - [`apply`] — applying a tool to the cells it overlaps, in parallel;
//!   [`Octree::apply_with_faces`] also hands back the boundary faces the
//!   rebuild of each replaced leaf extracted, for re-meshing without
//!   cutting that leaf again ([`Octree::cell_surface_from`]).
//! - `leaf` — leaves within the budget: splitting those over it and
//!   combining children under it (also [`Octree::from_bsp`]).
//! - [`import`] — an octree from a closed triangle mesh (§3.9);
//!   [`import_layers`] — from a heightfield with material bands by depth,
//!   every band labelled in the same pass.
//! - [`measure`] — material volumes for reports; [`exact_volume`] — the
//!   same, exactly, as rationals; [`volume_change`] — what an edit changed
//!   of each material, exactly, from the cells it names.
//! - [`components`] — connected components of the solid (cells sharing
//!   faces of positive area) and what anchors them.
//! - [`debris`] — after an edit, finding the solid no anchor holds and
//!   taking it out as pieces of their own (`relabel` empties or keeps
//!   chosen cells); [`chunk_debris`] — the same across octrees side by
//!   side (the chunks of a world), a piece over several chunks found as
//!   one.
//! - [`surface`] — the surface of a cell or of the whole octree, with the
//!   faces on cell borders kept only where the neighbour across is empty.
//! - [`seams`] — sealed cell meshes that meet their neighbours' edge to
//!   edge, kept up to date across edits ([`SeamedMesher`]); [`shading`] —
//!   the surface around their border vertices, shared between neighbours
//!   for smooth normals that agree across cell borders; [`outside_shading`]
//!   — the same across the cubes of neighbouring octrees.
//! - [`hash`] — a state hash of an octree's content, updated per edit
//!   from the cells it changed ([`StateHash`]).
//! - [`store`] — octree files: exact, versioned and checked
//!   ([`Octree::to_bytes`], [`Octree::from_bytes`]).
//!
//! ## Example
//!
//! ```
//! use chisel_bsp::mesh::SurfaceMesh;
//! use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
//! use chisel_bsp::tools::{Pose, dodecahedron_corners};
//!
//! // A 100 mm block on a 1 µm grid, in a cube of edge 2^17.
//! let block = CellBox { min: [0; 3], max: [100_000; 3] };
//! let mut octree = Octree::from_box([0; 3], 17, block, 1, OctreeConfig::default())?;
//! let undo = octree.clone();
//! let at = Pose::at([50_000.0, 50_000.0, 100_000.0]);
//! let tool = Tool::placed(&dodecahedron_corners(3_000.0), &at)?;
//! let changes = octree.apply(&tool, Edit::Subtract)?;
//! for key in &changes.changed {
//!     let triangles = SurfaceMesh::from_faces(&octree.cell_surface(*key)).triangles();
//!     assert!(!triangles.is_empty());
//! }
//! assert!(octree.solid_volume() < undo.solid_volume());
//! # Ok::<(), chisel_bsp::Error>(())
//! ```

pub mod apply;
pub mod cell;
pub mod chunk_debris;
pub mod components;
pub mod debris;
pub mod exact_volume;
mod graft;
pub mod hash;
pub mod import;
pub mod import_layers;
mod leaf;
pub mod measure;
mod mesh_check;
pub mod outside_shading;
mod relabel;
pub mod seams;
pub mod shading;
mod split;
pub mod store;
pub mod surface;
pub mod tool;
pub mod tree;
pub mod volume_change;

pub use apply::{Changes, Edit};
pub use cell::{CellBox, CellKey};
pub use chunk_debris::{
    ChunkOctree, ChunkPart, ChunkedDetached, ChunkedPiece, DebrisLimits, detach_across_chunks,
    detach_across_chunks_with_open_sides,
};
pub use components::{Anchors, Component, CubeSide, SolidCell};
pub use debris::{Carved, DebrisCell, DebrisConfig, DebrisPiece, Detached};
pub use exact_volume::ExactVolume;
pub use hash::StateHash;
pub use leaf::CellFaces;
pub use outside_shading::PointWedges;
pub use seams::SeamedMesher;
pub use shading::ShadedCell;
pub use tool::Tool;
pub use tree::{Leaf, Octree, OctreeConfig, OctreeStats};
