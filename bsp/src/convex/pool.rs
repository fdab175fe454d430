//! Reusable arenas: each thread keeps the arenas it used, cleared but with
//! their memory, so operations on many small cells do not allocate.

use std::cell::RefCell;

use super::mesh::ConvexArena;

thread_local! {
    static FREE: RefCell<Vec<ConvexArena>> = const { RefCell::new(Vec::new()) };
}

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
