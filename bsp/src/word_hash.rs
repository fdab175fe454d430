//! A fast hasher for the crate's internal hash maps.

use core::hash::Hasher;

/// A multiply–rotate hash of a few words (as in `rustc-hash`): the keys
/// (welding cells, directed edges, plane coefficients) are not adversarial,
/// and lookups only need a good spread.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct WordHasher(u64);

impl Hasher for WordHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.0 = self.0.wrapping_add(x).wrapping_mul(0xF135_7AEA_2E62_A9C5);
    }

    #[inline]
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }

    #[inline]
    fn write_i128(&mut self, x: i128) {
        self.write_u64(x as u64);
        self.write_u64((x >> 64) as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0.rotate_left(26)
    }
}

/// A hash map keyed through [`WordHasher`].
pub(crate) type WordMap<K, V> =
    std::collections::HashMap<K, V, core::hash::BuildHasherDefault<WordHasher>>;

/// A hash set keyed through [`WordHasher`].
pub(crate) type WordSet<T> =
    std::collections::HashSet<T, core::hash::BuildHasherDefault<WordHasher>>;
