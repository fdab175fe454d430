//! Reusable arena memory.
//!
//! - [`with_arena`]: each thread keeps the arenas it used, cleared but with
//!   their memory, so operations on many small cells do not allocate.
//! - A dropped arena hands its arrays to a small per-thread reserve, and
//!   [`ConvexArena::new`] takes them back (cleared): code that builds a
//!   fresh arena per operation does not regrow its arrays, nor fault in new
//!   pages, every time.

use std::cell::RefCell;

use super::mesh::{ConvexArena, Face, HalfEdge, Vertex};
use super::scratch::Scratch;
use crate::exact::{Plane, Point4};

thread_local! {
    static FREE: RefCell<Vec<ConvexArena>> = const { RefCell::new(Vec::new()) };
    static SPARE: RefCell<Vec<Arrays>> = const { RefCell::new(Vec::new()) };
}

/// Arrays kept per thread for reuse: enough for a few arenas alive at once.
const SPARE_ARRAYS: usize = 4;

/// Runs `f` with an empty arena of this thread (nested calls get distinct
/// arenas), then keeps it for the next call.
pub fn with_arena<R>(f: impl FnOnce(&mut ConvexArena) -> R) -> R {
    let mut arena = FREE
        .with(|free| free.borrow_mut().pop())
        .unwrap_or_default();
    arena.clear();
    let out = f(&mut arena);
    FREE.with(|free| free.borrow_mut().push(arena));
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
    SPARE
        .try_with(|spare| spare.borrow_mut().pop())
        .ok()
        .flatten()
}

/// Keeps `arrays` for a later arena of this thread (cleared here), unless
/// enough are kept already or the thread is shutting down.
pub(super) fn keep_spare(mut arrays: Arrays) {
    arrays.vertices.clear();
    arrays.points.clear();
    arrays.half_edges.clear();
    arrays.faces.clear();
    arrays.planes.clear();
    let _ = SPARE.try_with(|spare| {
        if let Ok(mut spare) = spare.try_borrow_mut()
            && spare.len() < SPARE_ARRAYS
        {
            spare.push(arrays);
        }
    });
}
