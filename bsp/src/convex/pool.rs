//! Reusable arena memory.
//!
//! - [`with_arena`]: each thread keeps the arenas it used, cleared but with
//!   their memory, so operations on many small cells do not allocate.
//! - A dropped arena hands its arrays to a small per-thread reserve, and
//!   [`ConvexArena::new`] takes them back (cleared): code that builds a
//!   fresh arena per operation does not regrow its arrays, nor fault in new
//!   pages, every time.

use super::mesh::{ConvexArena, Face, HalfEdge, Vertex};
use super::scratch::Scratch;
use crate::exact::{Plane, Point4};
use crate::pool::{PerThread, Pool};

thread_local! {
    static FREE: Pool<ConvexArena> = const { Pool::new(FREE_ARENAS) };
    static SPARE: Pool<Arrays> = const { Pool::new(SPARE_ARRAYS) };
}

/// Arenas kept per thread for [`with_arena`]: more than its calls nest.
const FREE_ARENAS: usize = 16;

/// Arrays kept per thread for reuse: enough for a few arenas alive at once.
const SPARE_ARRAYS: usize = 4;

/// Runs `f` with an empty arena of this thread (nested calls get distinct
/// arenas), then keeps it for the next call.
pub fn with_arena<R>(f: impl FnOnce(&mut ConvexArena) -> R) -> R {
    let mut arena = FREE.take().unwrap_or_default();
    arena.clear();
    let out = f(&mut arena);
    FREE.keep(arena);
    out
}

/// The arrays of a dropped arena, emptied, with their capacity.
pub(super) struct Arrays {
    pub(super) vertices: Vec<Vertex>,
    pub(super) points: Vec<Point4>,
    pub(super) half_edges: Vec<HalfEdge>,
    pub(super) faces: Vec<Face>,
    pub(super) planes: Vec<Plane>,
    pub(super) scratch: Option<Box<Scratch>>,
}

/// Arrays of an earlier arena of this thread, if any are kept.
pub(super) fn take_spare() -> Option<Arrays> {
    SPARE.take()
}

/// Keeps `arrays` for a later arena of this thread (cleared here), unless
/// enough are kept already or the thread is shutting down.
pub(super) fn keep_spare(mut arrays: Arrays) {
    arrays.vertices.clear();
    arrays.points.clear();
    arrays.half_edges.clear();
    arrays.faces.clear();
    arrays.planes.clear();
    SPARE.keep(arrays);
}
