//! # bevy_chisel — exact, local solid modelling for Bevy
//!
//! `bevy_chisel` brings two kernels into Bevy:
//!
//! - [`chisel_bsp`] (re-exported as [`bsp`]): exact integer plane geometry,
//!   the foundation of destructible octree-BSP terrain whose carves never
//!   fail, never crack and are bit-identical on every machine.
//! - [`chisel_quadric`] (re-exported as [`quadric`]): quadric CSG trees for
//!   level-design props drawn pixel-exact by splat ray tracing.
//!
//! The [`splat`] module draws quadric CSG props: a [`splat::QuadricProp`]
//! component (a scene file or an in-memory scene), sampled on the async
//! compute pool, rendered by a splat pass with per-fragment ray tracing,
//! clipping and depth writes, or by a global ray-tracing pass for
//! comparison ([`splat::ChiselSplatPlugin`]).
//!
//! The [`terrain`] module is destructible terrain: a [`terrain::Terrain`]
//! component owning an octree of exact BSPs, carved by [`terrain::Carve`]
//! messages on the async compute pool, re-meshed only in the cells that
//! changed, with undo, ray casts and versioned files
//! ([`terrain::TerrainPlugin`]).
//!
//! The [`presentation`] module runs any app either in a window or, where
//! there is no display, headless on an offscreen target with PNG
//! screenshots — the examples and the render tests use it. The [`viewer`]
//! module holds what the examples share: an orbit camera, text overlays and
//! carving the terrain under the mouse cursor.
//!
//! The [`net`] module (feature `net`) replicates carves from one
//! authoritative server to its clients: integer carves in sequence order,
//! state hashes and snapshots, never meshes.

#![warn(missing_docs)]

#[cfg(feature = "net")]
pub mod net;
pub mod presentation;
pub mod splat;
pub mod terrain;
pub mod viewer;

pub use chisel_bsp as bsp;
pub use chisel_quadric as quadric;
