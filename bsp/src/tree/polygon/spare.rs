//! Spare edge and corner buffers of polygons, kept per thread.

use crate::exact::{Plane, Point4};
use crate::pool::{PerThread, Pool};

thread_local! {
    /// Edge buffers of dropped polygons and of boundary faces given to a
    /// mesh, for the next polygons built on the same thread: clipping and
    /// rebuilding drop about as many pieces as they create, so most splits
    /// allocate nothing.
    static SPARE_EDGES: Pool<Vec<Plane>> = const { Pool::new(MAX_SPARE) };
    /// Corner buffers of dropped polygons, kept apart from the edge buffers
    /// (a boundary face given to a mesh keeps its edge planes but hands
    /// back its corners).
    static SPARE_CORNERS: Pool<Vec<Point4>> = const { Pool::new(MAX_SPARE) };
}

/// Spare buffers of each kind kept per thread.
const MAX_SPARE: usize = 1024;

/// Hands `edges` and `corners` (either may be empty) to the spare buffers
/// of this thread. When the pool is full, or the thread is ending, the
/// buffers are simply freed.
#[inline(never)]
pub(crate) fn give_back_buffers(mut edges: Vec<Plane>, mut corners: Vec<Point4>) {
    if edges.capacity() != 0 {
        edges.clear();
        SPARE_EDGES.keep(edges);
    }
    if corners.capacity() != 0 {
        corners.clear();
        SPARE_CORNERS.keep(corners);
    }
}

/// Hands the edge buffers `buffers` yields to the spare buffers of this
/// thread while there is room, and stops asking for more when the pool is
/// full (what is left is the caller's to free).
pub(crate) fn give_back_edge_buffers(buffers: impl Iterator<Item = Vec<Plane>>) {
    SPARE_EDGES.keep_while_room(buffers.filter(|e| e.capacity() != 0).map(|mut e| {
        e.clear();
        e
    }));
}

/// Room for corners in new buffers, at least: most polygons have fewer,
/// so spare buffers usually fit the next polygon.
const MIN_CAPACITY: usize = 8;

/// Empty edge and corner buffers with room for `m` of each: spare ones
/// when they are large enough, else new ones (growing a spare buffer would
/// copy its stale contents).
pub(crate) fn spare_buffers(m: usize) -> (Vec<Plane>, Vec<Point4>) {
    let capacity = m.max(MIN_CAPACITY);
    (
        SPARE_EDGES
            .take()
            .filter(|e| e.capacity() >= m)
            .unwrap_or_else(|| Vec::with_capacity(capacity)),
        SPARE_CORNERS
            .take()
            .filter(|c| c.capacity() >= m)
            .unwrap_or_else(|| Vec::with_capacity(capacity)),
    )
}

/// An empty edge buffer with room for `m` planes: a spare one when it is
/// large enough, else a new one.
pub(crate) fn spare_edge_buffer(m: usize) -> Vec<Plane> {
    SPARE_EDGES
        .take()
        .filter(|e| e.capacity() >= m)
        .unwrap_or_else(|| Vec::with_capacity(m.max(MIN_CAPACITY)))
}
