//! Per-operation maps over vertex and face indices, cleared in `O(1)`.
//!
//! A cut touches a handful of the arena's elements; hashing them costs more
//! than the geometry. A [`StampMap`] is a dense array indexed by element id
//! whose entries count only when their stamp equals the current one, so
//! starting a new operation is a single increment, and lookups are one
//! comparison.

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
