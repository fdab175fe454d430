//! Per-operation maps over vertex and face indices, cleared in `O(1)`.
//!
//! A cut touches a handful of the arena's elements; hashing them costs more
//! than the geometry. A [`StampMap`] is a dense array indexed by element id
//! whose entries count only when their stamp equals the current one, so
//! starting a new operation is a single increment, and lookups are one
//! comparison.

use crate::exact::Sign;

/// A map from element index to `T`, valid for the current stamp only.
#[derive(Clone, Debug, Default)]
pub(crate) struct StampMap<T: Copy + Default> {
    stamp: u32,
    stamps: Vec<u32>,
    values: Vec<T>,
}

impl<T: Copy + Default> StampMap<T> {
    /// Forgets every entry.
    pub(crate) fn clear(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.fill(0);
            self.stamp = 1;
        }
    }

    /// The value at `i`, if set since the last [`StampMap::clear`].
    #[inline]
    pub(crate) fn get(&self, i: u32) -> Option<T> {
        let i = i as usize;
        (self.stamps.get(i) == Some(&self.stamp)).then(|| self.values[i])
    }

    /// Makes room for indices below `len` without reallocating later.
    pub(crate) fn reserve(&mut self, len: usize) {
        if len > self.stamps.len() {
            self.stamps.resize(len, 0);
            self.values.resize(len, T::default());
        }
    }

    /// Sets the value at `i`; returns true when `i` had no value yet.
    #[inline]
    pub(crate) fn insert(&mut self, i: u32, value: T) -> bool {
        let i = i as usize;
        if i >= self.stamps.len() {
            let len = (i + 1).max(2 * self.stamps.len());
            self.stamps.resize(len, 0);
            self.values.resize(len, T::default());
        }
        let fresh = self.stamps[i] != self.stamp;
        self.stamps[i] = self.stamp;
        self.values[i] = value;
        fresh
    }
}

/// The scratch space of the cutting operations, kept in the arena so that
/// cuts allocate nothing once it has grown to the arena's size.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// Side of each classified vertex.
    pub(crate) sides: StampMap<Sign>,
    /// Faces already queued by the march.
    pub(crate) faces: StampMap<bool>,
    /// Vertices already rotated around by the march.
    pub(crate) vertices: StampMap<bool>,
    /// Cap half-edge starting at each section vertex.
    pub(crate) cap_starts: StampMap<u32>,
    /// The half-edges of the face being split.
    pub(crate) face_loop: Vec<u32>,
}

impl Scratch {
    /// Makes room for `vertices` vertex and `faces` face indices.
    pub(crate) fn reserve(&mut self, vertices: usize, faces: usize) {
        self.sides.reserve(vertices);
        self.vertices.reserve(vertices);
        self.cap_starts.reserve(vertices);
        self.faces.reserve(faces);
    }

    /// Starts a new operation.
    pub(crate) fn clear(&mut self) {
        self.sides.clear();
        self.faces.clear();
        self.vertices.clear();
        self.cap_starts.clear();
    }
}
