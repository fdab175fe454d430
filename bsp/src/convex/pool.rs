//! Reusable arena memory.
//!
//! - [`with_arena`]: each thread keeps the arenas it used, cleared but with
//!   their memory, so operations on many small cells do not allocate.
//!
//! (A dropped arena also hands its arrays to a small per-thread reserve
//! for [`ConvexArena::new`]: see `mesh.rs`.)

use super::mesh::ConvexArena;
use crate::pool::{PerThread, Pool};

thread_local! {
    static FREE: Pool<ConvexArena> = const { Pool::new(FREE_ARENAS) };
}

/// Arenas kept per thread for [`with_arena`]: more than its calls nest.
const FREE_ARENAS: usize = 16;

/// Runs `f` with an empty arena of this thread (nested calls get distinct
/// arenas), then keeps it for the next call.
pub fn with_arena<R>(f: impl FnOnce(&mut ConvexArena) -> R) -> R {
    let mut arena = FREE.take().unwrap_or_default();
    arena.clear();
    let out = f(&mut arena);
    FREE.keep(arena);
    out
}
