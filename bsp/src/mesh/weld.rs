//! Welding equal exact vertices into one index.
//!
//! Two corners are the same vertex exactly when [`Point4::same_position`]
//! says so. The same point reached from different plane triples has
//! different homogeneous coordinates `(X, Y, Z, W)`, and its `f64` position
//! `fl(fl(X) / fl(W))` is then *not* always bit-identical (each of the three
//! roundings may go another way), so the `f64` bits alone cannot be the key.
//! They are close, though: each coordinate is within `(1 + u)²/(1 − u) − 1
//! < 3.01·u` (`u = 2^-53`) relative of the exact value, i.e. within 4 units
//! in the last place (ulps) of it, and two roundings of one point are within
//! 8 ulps of each other (never crossing zero: a zero coordinate has `X = 0`
//! and rounds to exactly `0.0`; a non-zero one is at least `2^-168`, far
//! from subnormals).
//!
//! Hence the key: map each coordinate to its position on the ordered line
//! of `f64`s (an integer that grows by one per ulp) and drop the low
//! [`CELL_SHIFT`] bits. Equal points get keys that differ by at most one
//! per axis, and a different key only when the position lies within
//! [`MARGIN`] ulps of a cell border, where the neighbouring cell is searched
//! too. Candidates are then confirmed exactly.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::hash::{BuildHasherDefault, Hash, Hasher};

use crate::exact::Point4;
use crate::word_hash::WordHasher;

/// Low bits dropped from the ordered `f64` position: cells are `2^12` ulps
/// wide per axis, so that a point lies within [`MARGIN`] of a border (and
/// a neighbouring cell is searched too) on under 2% of the axes, while
/// distinct vertices of a mesh are still far apart in ulps and rarely
/// share a cell.
pub const CELL_SHIFT: u32 = 12;

/// Ulps from a cell border within which the neighbouring cell is searched:
/// above the 8 ulps that two roundings of one point can differ by, with a
/// wide safety factor.
pub const MARGIN: i64 = 32;

/// The position of `x` on the ordered integer line of `f64`s: monotone,
/// one step per ulp, `+0.0` and `−0.0` both at 0.
#[must_use]
#[inline]
pub fn ordered_bits(x: f64) -> i64 {
    let magnitude = (x.to_bits() & !(1u64 << 63)) as i64;
    if x.is_sign_negative() {
        -magnitude
    } else {
        magnitude
    }
}

/// Whether `a` and `b` are the same point: identical homogeneous
/// coordinates (the common case, a corner shared by neighbouring faces),
/// else the exact cross-multiplied comparison.
#[inline]
fn same_point(a: &Point4, b: &Point4) -> bool {
    (a.xyz_digits == b.xyz_digits && a.w_digits == b.w_digits) || a.same_position(b)
}

/// The key of a cell: its three coordinates, hashed as three words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct CellKey([i64; 3]);

impl Hash for CellKey {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        for v in self.0 {
            state.write_i64(v);
        }
    }
}

/// Marks the end of a cell's list of vertices.
const END: u32 = u32::MAX;

/// Assigns indices to exact points, one per distinct position, in order of
/// first appearance.
#[derive(Debug, Default)]
pub struct Welder {
    vertices: Vec<Point4>,
    /// The first and last vertex of each cell; the others are linked by
    /// [`Self::next`], in order of first appearance.
    cells: HashMap<CellKey, (u32, u32), BuildHasherDefault<WordHasher>>,
    /// The vertex after each in its cell, or [`END`].
    next: Vec<u32>,
}

impl Welder {
    /// An empty welder with room for about `n` vertices.
    #[must_use]
    pub fn with_capacity(n: usize) -> Self {
        Self {
            vertices: Vec::with_capacity(n),
            cells: HashMap::with_capacity_and_hasher(n, BuildHasherDefault::default()),
            next: Vec::with_capacity(n),
        }
    }

    /// The index of `p`: that of an earlier equal point, or a new one.
    pub fn index(&mut self, p: &Point4) -> u32 {
        let ordered = p.to_f64().map(ordered_bits);
        let key = ordered.map(|o| o >> CELL_SHIFT);
        // Per axis the cell itself and, near a border, its neighbour.
        let choices = |axis: usize| -> [Option<i64>; 2] {
            let (o, k) = (ordered[axis], key[axis]);
            let low = o - (k << CELL_SHIFT);
            let high = ((k + 1) << CELL_SHIFT) - o;
            let neighbour = if low < MARGIN {
                Some(k - 1)
            } else if high <= MARGIN {
                Some(k + 1)
            } else {
                None
            };
            [Some(k), neighbour]
        };
        let (cx, cy, cz) = (choices(0), choices(1), choices(2));
        for x in cx.iter().flatten() {
            for y in cy.iter().flatten() {
                for z in cz.iter().flatten() {
                    let Some(&(first, _)) = self.cells.get(&CellKey([*x, *y, *z])) else {
                        continue;
                    };
                    let mut i = first;
                    while i != END {
                        if same_point(&self.vertices[i as usize], p) {
                            return i;
                        }
                        i = self.next[i as usize];
                    }
                }
            }
        }
        let index = self.vertices.len() as u32;
        self.vertices.push(*p);
        self.next.push(END);
        match self.cells.entry(CellKey(key)) {
            Entry::Occupied(mut cell) => {
                let (_, last) = cell.get_mut();
                self.next[*last as usize] = index;
                *last = index;
            }
            Entry::Vacant(cell) => {
                cell.insert((index, index));
            }
        }
        index
    }

    /// The distinct vertices, by index.
    #[must_use]
    pub fn into_vertices(self) -> Vec<Point4> {
        self.vertices
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::{Plane, intersect_3_planes};

    #[test]
    fn ordered_bits_is_monotone_across_zero() {
        let xs = [-1.0, -f64::MIN_POSITIVE, -0.0, 0.0, f64::MIN_POSITIVE, 1.0];
        for w in xs.windows(2) {
            assert!(ordered_bits(w[0]) <= ordered_bits(w[1]));
        }
        assert_eq!(
            ordered_bits(1.0) + 1,
            ordered_bits(f64::from_bits(1.0f64.to_bits() + 1))
        );
    }

    /// The point `(1/3, 1/7, 1/11)` as the meet of many different plane
    /// triples: all weld to one vertex, even where the rounded `f64`s differ.
    #[test]
    fn equal_points_from_different_planes_weld_to_one_vertex() {
        let mut welder = Welder::default();
        let mut bit_patterns = std::collections::HashSet::new();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move |range: i64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % (2 * range as u64)) as i64 - range
        };
        let mut count = 0;
        while count < 400 {
            // a·x + b·y + c·z + d = 0 through (1/3, 1/7, 1/11): a = 3a',
            // b = 7b', c = 11c', d = −(a' + b' + c').
            let mut plane = || {
                let (a, b, c) = (next(1 << 40), next(1 << 40), next(1 << 40));
                Plane::new(3 * a, 7 * b, 11 * c, -((a + b + c) as i128))
            };
            let (Ok(p), Ok(q), Ok(r)) = (plane(), plane(), plane()) else {
                continue;
            };
            let Some(v) = intersect_3_planes(&p, &q, &r) else {
                continue;
            };
            count += 1;
            bit_patterns.insert(v.to_f64().map(f64::to_bits));
            assert_eq!(welder.index(&v), 0);
        }
        assert!(
            bit_patterns.len() > 1,
            "the same point rounds to different f64s, so bits alone are no key"
        );
    }
}
