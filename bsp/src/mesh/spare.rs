//! Spare index buffers: the corner and original-corner lists of dropped
//! mesh polygons, kept per thread for the next polygons welded there (a
//! game re-meshes a few cells after every edit, each mesh about as large as
//! the last), so that most polygons allocate nothing.

use crate::pool::{PerThread, Pool};

thread_local! {
    /// Emptied index buffers of dropped polygons.
    static SPARE: Pool<Vec<u32>> = const { Pool::new(MAX_SPARE) };
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
        .take()
        .filter(|b| b.capacity() >= m)
        .unwrap_or_else(|| Vec::with_capacity(m.max(MIN_CAPACITY)))
}

/// Hands the index buffers `buffers` yields to the spare buffers of this
/// thread while there is room, and stops asking for more when the pool is
/// full (what is left is the caller's to free).
pub(super) fn give_back(buffers: impl Iterator<Item = Vec<u32>>) {
    SPARE.keep_while_room(buffers.filter(|b| b.capacity() != 0).map(|mut b| {
        b.clear();
        b
    }));
}
