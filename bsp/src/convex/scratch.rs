//! Per-operation maps over vertex and face indices, cleared in `O(1)`.
//!
//! A cut touches a handful of the arena's elements; hashing them costs more
//! than the geometry. A [`StampMap`] is a dense array indexed by element id
//! whose entries count only when their stamp equals the current one, so
//! starting a new operation is a single increment, and lookups are one
//! comparison.

use super::extremes::Extremes;
use super::landmarks::Landmarks;
use super::ring::RingFace;
use super::survey::FaceInfo;
use crate::exact::Sign;

/// A map from element index to `T`, valid for the current stamp only. Each
/// entry keeps its stamp beside its value, so a lookup touches one slot.
#[derive(Clone, Debug, Default)]
pub(crate) struct StampMap<T: Copy + Default> {
    stamp: u32,
    entries: Vec<(u32, T)>,
}

impl<T: Copy + Default> StampMap<T> {
    /// Forgets every entry.
    pub(crate) fn clear(&mut self) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.entries.fill((0, T::default()));
            self.stamp = 1;
        }
    }

    /// The value at `i`, if set since the last [`StampMap::clear`].
    #[inline]
    pub(crate) fn get(&self, i: u32) -> Option<T> {
        match self.entries.get(i as usize) {
            Some(&(stamp, value)) if stamp == self.stamp => Some(value),
            _ => None,
        }
    }

    /// The number of entries set since the last [`StampMap::clear`] (a
    /// scan of every slot: for statistics, not for the cuts).
    pub(crate) fn count(&self) -> usize {
        self.entries
            .iter()
            .filter(|(stamp, _)| *stamp == self.stamp)
            .count()
    }

    /// Makes room for indices below `len` without reallocating later.
    pub(crate) fn reserve(&mut self, len: usize) {
        if len > self.entries.len() {
            self.entries.resize(len, (0, T::default()));
        }
    }

    /// Sets the value at `i`; returns true when `i` had no value yet.
    #[inline]
    pub(crate) fn insert(&mut self, i: u32, value: T) -> bool {
        let stamp = self.stamp;
        match self.entries.get_mut(i as usize) {
            Some(entry) => {
                let fresh = entry.0 != stamp;
                *entry = (stamp, value);
                fresh
            }
            None => self.grow_and_insert(i as usize, value),
        }
    }

    /// [`StampMap::insert`] beyond the entries: grows them (at least
    /// doubling), then inserts.
    #[cold]
    #[inline(never)]
    fn grow_and_insert(&mut self, i: usize, value: T) -> bool {
        let len = (i + 1).max(2 * self.entries.len());
        self.entries.resize(len, (0, T::default()));
        self.entries[i] = (self.stamp, value);
        true
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
    /// The march's queue of faces to visit, each with the crossing
    /// half-edge it is entered by (or `u32::MAX`).
    pub(crate) queue: Vec<(u32, u32)>,
    /// The faces that meet the section, with what the split needs to know
    /// about each.
    pub(crate) relevant: Vec<(u32, FaceInfo)>,
    /// The vertices on the cutting plane of the face the march visits.
    pub(crate) on_plane: Vec<u32>,
    /// The half-edges lying in the cutting plane, on faces of the lower
    /// and of the upper part.
    pub(crate) section: [Vec<u32>; 2],
    /// The faces of a generic section in the order the section crosses
    /// them (`ring`).
    pub(crate) ring: Vec<RingFace>,
    /// Ring positions in the order of their faces, then the cap half-edge
    /// leaving each new vertex (`ring_both`).
    pub(crate) order: Vec<u32>,
    /// Where the next cut of a part of the last cut starts (kept from one
    /// operation to the next, unlike the rest).
    pub(crate) landmarks: Landmarks,
    /// The extreme vertices of the parts of the last cut in fixed
    /// directions (kept from one operation to the next, like `landmarks`).
    pub(crate) extremes: Extremes,
    /// The side whose chain the march should walk on the face it starts
    /// from, when the start vertex tells (an extreme vertex lies near the
    /// small part).
    pub(crate) chain: Option<Sign>,
    /// The steps the edge descents of the operation took.
    pub(crate) descent_steps: u32,
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
        self.descent_steps = 0;
        self.chain = None;
    }
}
