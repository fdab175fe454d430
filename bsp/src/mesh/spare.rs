//! Spare index buffers: the corner and original-corner lists of dropped
//! mesh polygons, kept per thread for the next polygons welded there (a
//! game re-meshes a few cells after every edit, each mesh about as large as
//! the last), so that most polygons allocate nothing.

use std::cell::RefCell;

thread_local! {
    /// Emptied index buffers of dropped polygons.
    static SPARE: RefCell<Vec<Vec<u32>>> = const { RefCell::new(Vec::new()) };
}

/// Spare index buffers kept per thread.
const MAX_SPARE: usize = 2048;

/// Room for indices in new buffers, at least: most polygons have fewer
/// corners, so spare buffers usually fit the next polygon.
const MIN_CAPACITY: usize = 8;

/// An empty index buffer with room for `m` indices: a spare one when it is
/// large enough, else a new one.
pub(super) fn index_buffer(m: usize) -> Vec<u32> {
    SPARE
        .try_with(|spare| spare.try_borrow_mut().ok().and_then(|mut s| s.pop()))
        .ok()
        .flatten()
        .filter(|b| b.capacity() >= m)
        .unwrap_or_else(|| Vec::with_capacity(m.max(MIN_CAPACITY)))
}

/// Hands the index buffers `buffers` yields to the spare buffers of this
/// thread while there is room, and stops asking for more when the pool is
/// full (what is left is the caller's to free).
pub(super) fn give_back(buffers: impl Iterator<Item = Vec<u32>>) {
    let _ = SPARE.try_with(|spare| {
        if let Ok(mut spare) = spare.try_borrow_mut() {
            for mut buffer in buffers {
                if spare.len() >= MAX_SPARE {
                    break;
                }
                if buffer.capacity() != 0 {
                    buffer.clear();
                    spare.push(buffer);
                }
            }
        }
    });
}
