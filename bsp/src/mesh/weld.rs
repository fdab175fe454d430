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
//!
//! Up to [`SCAN_MAX`] vertices (the surface of one octree cell) no cells
//! are kept: each new point is compared with every vertex so far, first
//! by its ordered position (within [`MARGIN`] ulps per axis, which every
//! equal point is), then exactly. Both ways find the one equal vertex, if
//! any, so the indices are the same.

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

/// Vertices up to which every new point is compared with every vertex
/// (see the module docs): cheaper than hashing cells for a few dozen.
/// At most 64, the bits of the mask [`Welder`] scans with.
pub const SCAN_MAX: usize = 64;

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
    /// The vertex after each in its cell, or [`END`] (empty while the
    /// vertices are scanned).
    next: Vec<u32>,
    /// The ordered position of each vertex ([`ordered_bits`] per axis).
    ordered: Vec<[i64; 3]>,
    /// The ordered x of each vertex up to [`SCAN_MAX`] of them.
    xs: Vec<i64>,
}

impl Welder {
    /// An empty welder with room for about `n` vertices.
    #[must_use]
    pub fn with_capacity(n: usize) -> Self {
        Self {
            vertices: Vec::with_capacity(n),
            cells: HashMap::default(),
            next: Vec::new(),
            ordered: Vec::with_capacity(n),
            xs: Vec::with_capacity(n.min(SCAN_MAX + 1)),
        }
    }

    /// A welder holding `vertices` (indices `0..len`), which must be
    /// distinct points (as [`Self::into_vertices`] gives them), with room
    /// for about `more` further ones: what indexing them one by one would
    /// give, without comparing them with each other.
    #[must_use]
    pub fn from_distinct(mut vertices: Vec<Point4>, more: usize) -> Self {
        let n = vertices.len() + more;
        vertices.reserve(more);
        let mut ordered = Vec::with_capacity(n);
        ordered.extend(vertices.iter().map(|v| v.to_f64().map(ordered_bits)));
        let mut welder = Self {
            vertices,
            cells: HashMap::default(),
            next: Vec::new(),
            xs: Vec::with_capacity(n.min(SCAN_MAX + 1)),
            ordered,
        };
        if welder.vertices.len() < SCAN_MAX {
            welder.xs.extend(welder.ordered.iter().map(|o| o[0]));
        } else {
            welder.next.reserve(n);
            for v in 0..welder.vertices.len() {
                welder.next.push(END);
                welder.file(v as u32);
            }
        }
        welder
    }

    /// The index of `p`: that of an earlier equal point, or a new one.
    pub fn index(&mut self, p: &Point4) -> u32 {
        let ordered = p.to_f64().map(ordered_bits);
        if self.vertices.len() < SCAN_MAX {
            return self.scan(p, ordered);
        }
        self.search(p, ordered)
    }

    /// [`Self::index`] up to [`SCAN_MAX`] vertices: `p`, at `ordered`,
    /// compared with every vertex; the cells are filled when the vertices
    /// grow past.
    fn scan(&mut self, p: &Point4, ordered: [i64; 3]) -> u32 {
        // Newest first (a corner mostly recurs in the next faces), each
        // vertex near along x (`|x − c| ≤ MARGIN` as one wrapping
        // subtraction and one unsigned comparison) checked on y and z,
        // then exactly.
        let near =
            |o: i64, c: i64| (o.wrapping_sub(c).wrapping_add(MARGIN) as u64) <= 2 * MARGIN as u64;
        let mut end = self.xs.len();
        while let Some(i) = self.xs[..end].iter().rposition(|&x| near(x, ordered[0])) {
            let o = self.ordered[i];
            if near(o[1], ordered[1]) && near(o[2], ordered[2]) && same_point(&self.vertices[i], p)
            {
                return i as u32;
            }
            end = i;
        }
        let index = self.vertices.len() as u32;
        self.vertices.push(*p);
        self.ordered.push(ordered);
        self.xs.push(ordered[0]);
        if self.vertices.len() == SCAN_MAX {
            let room = self.vertices.capacity();
            self.cells.reserve(room);
            self.next.reserve(room);
            for v in 0..self.vertices.len() {
                self.next.push(END);
                self.file(v as u32);
            }
        }
        index
    }

    /// Files vertex `v` (its [`Self::next`] entry pushed, [`END`]) at the
    /// end of its cell's list.
    fn file(&mut self, v: u32) {
        let key = self.ordered[v as usize].map(|o| o >> CELL_SHIFT);
        match self.cells.entry(CellKey(key)) {
            Entry::Occupied(mut cell) => {
                let (_, last) = cell.get_mut();
                self.next[*last as usize] = v;
                *last = v;
            }
            Entry::Vacant(cell) => {
                cell.insert((v, v));
            }
        }
    }

    /// [`Self::index`] above [`SCAN_MAX`] vertices: `p`, at `ordered`,
    /// looked up in its cells.
    fn search(&mut self, p: &Point4, ordered: [i64; 3]) -> u32 {
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
        self.ordered.push(ordered);
        self.next.push(END);
        self.file(index);
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

    /// A xorshift generator of integers in `[−range, range)`, from `seed`.
    fn integers(seed: u64) -> impl FnMut(i64) -> i64 {
        let mut state = seed;
        move |range| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % (2 * range as u64)) as i64 - range
        }
    }

    /// Meets of plane triples through a few hundred points, each point
    /// reached several times in random order: the welder gives every
    /// point the index of its first appearance, as comparing it exactly
    /// with every earlier vertex does, below and above [`SCAN_MAX`].
    #[test]
    fn scanning_and_cells_give_first_appearance_indices() {
        let mut next = integers(0x9e37_79b9_7f4a_7c15);
        // Points (i/3, j/7, k/11) reached through planes 3a·x + 7b·y +
        // 11c·z + d = 0 with d = −(a·i + b·j + c·k).
        let targets: Vec<[i64; 3]> = (0..300).map(|_| [0; 3].map(|_| next(1000))).collect();
        let mut points = Vec::new();
        for round in 0..3 {
            for (t, &[i, j, k]) in targets.iter().enumerate() {
                if (t + round) % 2 == 1 {
                    continue;
                }
                let mut plane = || {
                    let (a, b, c) = (next(1 << 20), next(1 << 20), next(1 << 20));
                    Plane::new(3 * a, 7 * b, 11 * c, -i128::from(a * i + b * j + c * k))
                };
                let (Ok(p), Ok(q), Ok(r)) = (plane(), plane(), plane()) else {
                    continue;
                };
                if let Some(v) = intersect_3_planes(&p, &q, &r) {
                    points.push(v);
                }
            }
        }
        for count in [SCAN_MAX / 2, points.len()] {
            let mut welder = Welder::default();
            let mut reference: Vec<Point4> = Vec::new();
            for p in &points[..count] {
                let expected = reference
                    .iter()
                    .position(|q| q.same_position(p))
                    .unwrap_or_else(|| {
                        reference.push(*p);
                        reference.len() - 1
                    });
                assert_eq!(welder.index(p) as usize, expected);
            }
        }
        assert!(points.len() > 3 * SCAN_MAX);
        // A welder started from distinct vertices, below, at and above
        // the scan limit, then indexing the rest: the same indices as one
        // that indexed them all.
        let mut whole = Welder::default();
        let indices: Vec<u32> = points.iter().map(|p| whole.index(p)).collect();
        let distinct = whole.into_vertices();
        for split in [SCAN_MAX / 2, SCAN_MAX, 2 * SCAN_MAX] {
            let mut welder = Welder::from_distinct(distinct[..split].to_vec(), 8);
            for (p, &index) in points.iter().zip(&indices) {
                assert_eq!(welder.index(p), index);
            }
            assert_eq!(welder.into_vertices().len(), distinct.len());
        }
    }

    /// The point `(1/3, 1/7, 1/11)` as the meet of many different plane
    /// triples: all weld to one vertex, even where the rounded `f64`s differ.
    #[test]
    fn equal_points_from_different_planes_weld_to_one_vertex() {
        let mut welder = Welder::default();
        let mut bit_patterns = std::collections::HashSet::new();
        let mut next = integers(0x2545_f491_4f6c_dd1d);
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
