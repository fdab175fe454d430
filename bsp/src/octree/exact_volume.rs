//! Exact volumes as rationals (paper 1 §3.2 vertices, §3.8 cells).
//!
//! Notation: a vertex is `p = X / W` (`X ∈ ℤ³`, `W > 0`, [`Point4`]);
//! `O` is an integer point near the polyhedron, `X' = X − W·O`; `L` is the
//! least common multiple of the polyhedron's `W`s and `Y = X'·(L / W)`, so
//! that `p − O = Y / L` with one denominator for every vertex. A face with
//! corners `p_0 … p_{m−1}` (counter-clockwise from outside) adds the fan
//! `Σ_k det(Y_0, Y_k, Y_{k+1})`; the volume is that sum over all faces
//! divided by `6·L³` (the divergence theorem with tetrahedra from `O`).
//!
//! A cell whose vertices are all integer points (`W = 1`, as axis-aligned
//! cuts give) is summed in `i128`: with `|p − O| ≤ 2^28` a determinant is
//! below `2^87` and far fewer than `2^40` of them are added.
//! The octree's volume adds the cells' reduced fractions pairwise, so the
//! denominators grow with the depth of the sum rather than its length.

use core::cmp::Ordering;
use core::fmt;
use core::ops::{Add, AddAssign, Sub};
use std::collections::BTreeMap;

use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Signed, ToPrimitive, Zero};
use rayon::prelude::*;

use super::cell::{CellBox, CellKey};
use super::tree::{Leaf, Octree};
use crate::convex::{ConvexArena, PolyId};
use crate::exact::Point4;
use crate::tree::{EMPTY, Label};

/// A volume in cubic grid units as an exact reduced fraction
/// `numerator / denominator` (denominator positive).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ExactVolume {
    num: BigInt,
    den: BigInt,
}

impl Default for ExactVolume {
    fn default() -> Self {
        Self::zero()
    }
}

impl ExactVolume {
    /// No volume.
    #[must_use]
    pub fn zero() -> Self {
        Self {
            num: BigInt::zero(),
            den: BigInt::one(),
        }
    }

    /// A whole number of cubic grid units.
    #[must_use]
    pub fn from_integer(v: i128) -> Self {
        Self {
            num: BigInt::from(v),
            den: BigInt::one(),
        }
    }

    /// `num / den`, reduced; `None` when `den` is zero.
    #[must_use]
    pub fn from_fraction(num: BigInt, den: BigInt) -> Option<Self> {
        if den.is_zero() {
            return None;
        }
        let (num, den) = if den.is_negative() {
            (-num, -den)
        } else {
            (num, den)
        };
        let g = num.gcd(&den);
        Some(if g.is_one() || g.is_zero() {
            Self { num, den }
        } else {
            Self {
                num: num / &g,
                den: den / g,
            }
        })
    }

    /// The numerator of the reduced fraction.
    #[must_use]
    pub fn numerator(&self) -> &BigInt {
        &self.num
    }

    /// The denominator of the reduced fraction (positive).
    #[must_use]
    pub fn denominator(&self) -> &BigInt {
        &self.den
    }

    /// Whether the volume is zero.
    #[must_use]
    pub fn is_zero(&self) -> bool {
        self.num.is_zero()
    }

    /// The nearest `f64`, within a few units in the last place (for
    /// messages and physics; comparisons should stay exact).
    #[must_use]
    pub fn to_f64(&self) -> f64 {
        if self.num.is_zero() {
            return 0.0;
        }
        // q = num / den scaled to about 62 bits, then scaled back.
        let e = self.num.bits() as i64 - self.den.bits() as i64;
        let q: BigInt = if e <= 62 {
            (&self.num << (62 - e) as usize) / &self.den
        } else {
            &self.num / (&self.den << (e - 62) as usize)
        };
        q.to_f64().unwrap_or(f64::NAN) * 2f64.powi((e - 62) as i32)
    }

    /// Whether the volume is more than `limit` cubic grid units.
    #[must_use]
    pub fn exceeds(&self, limit: u128) -> bool {
        self.num > BigInt::from(limit) * &self.den
    }

    /// The exact volume of the convex polyhedron `poly` of `arena`.
    #[must_use]
    pub fn of_polyhedron(arena: &ConvexArena, poly: PolyId) -> Self {
        let ids = arena.vertices_of(poly);
        let points: Vec<&Point4> = ids.iter().map(|&v| arena.point(v)).collect();
        let Some(first) = points.first() else {
            return Self::zero();
        };
        let origin = first.to_f64().map(|c| c.round() as i64);
        let mut index: Vec<(u32, usize)> = ids.iter().enumerate().map(|(i, &v)| (v, i)).collect();
        index.sort_unstable();
        let at = |v: u32| index[index.binary_search_by_key(&v, |e| e.0).unwrap_or(0)].1;
        let faces: Vec<Vec<usize>> = arena
            .faces_of(poly)
            .into_iter()
            .map(|f| {
                arena
                    .face_loop(f)
                    .map(|h| at(arena.half_edges()[h as usize].origin))
                    .collect()
            })
            .collect();
        if let Some(small) = integer_offsets(&points, origin) {
            let mut sum = 0i128;
            for face in &faces {
                for k in 1..face.len().saturating_sub(1) {
                    sum += det_i128(&small[face[0]], &small[face[k]], &small[face[k + 1]]);
                }
            }
            return Self::from_fraction(BigInt::from(sum), BigInt::from(6)).unwrap_or_default();
        }
        let big: Vec<([BigInt; 3], BigInt)> = points.iter().map(|p| to_big(p)).collect();
        let l = big.iter().fold(BigInt::one(), |l, (_, w)| l.lcm(w));
        let y: Vec<[BigInt; 3]> = big
            .into_iter()
            .map(|(x, w)| {
                let scale = &l / &w;
                [0, 1, 2].map(|a| (&x[a] - &w * origin[a]) * &scale)
            })
            .collect();
        let mut sum = BigInt::zero();
        for face in &faces {
            for k in 1..face.len().saturating_sub(1) {
                sum += det_big(&y[face[0]], &y[face[k]], &y[face[k + 1]]);
            }
        }
        let den = BigInt::from(6) * &l * &l * &l;
        Self::from_fraction(sum, den).unwrap_or_default()
    }

    /// The volume of an integer box.
    #[must_use]
    pub fn of_box(cell: &CellBox) -> Self {
        let edge = |a: usize| i128::from(cell.max[a] - cell.min[a]);
        Self::from_integer(edge(0) * edge(1) * edge(2))
    }

    /// The sum of `parts`, added pairwise.
    #[must_use]
    pub fn sum_balanced(mut parts: Vec<ExactVolume>) -> ExactVolume {
        while parts.len() > 1 {
            let mut next = Vec::with_capacity(parts.len().div_ceil(2));
            let mut it = parts.into_iter();
            while let Some(a) = it.next() {
                next.push(match it.next() {
                    Some(b) => a + b,
                    None => a,
                });
            }
            parts = next;
        }
        parts.pop().unwrap_or_default()
    }
}

impl Add for ExactVolume {
    type Output = ExactVolume;
    fn add(self, other: ExactVolume) -> ExactVolume {
        &self + &other
    }
}

impl Add for &ExactVolume {
    type Output = ExactVolume;
    fn add(self, other: &ExactVolume) -> ExactVolume {
        if self.den == other.den {
            return ExactVolume::from_fraction(&self.num + &other.num, self.den.clone())
                .unwrap_or_default();
        }
        ExactVolume::from_fraction(
            &self.num * &other.den + &other.num * &self.den,
            &self.den * &other.den,
        )
        .unwrap_or_default()
    }
}

impl AddAssign<&ExactVolume> for ExactVolume {
    fn add_assign(&mut self, other: &ExactVolume) {
        *self = &*self + other;
    }
}

impl Sub for &ExactVolume {
    type Output = ExactVolume;
    fn sub(self, other: &ExactVolume) -> ExactVolume {
        let neg = ExactVolume {
            num: -other.num.clone(),
            den: other.den.clone(),
        };
        self + &neg
    }
}

impl std::iter::Sum for ExactVolume {
    fn sum<I: Iterator<Item = ExactVolume>>(iter: I) -> Self {
        Self::sum_balanced(iter.collect())
    }
}

impl PartialOrd for ExactVolume {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for ExactVolume {
    fn cmp(&self, other: &Self) -> Ordering {
        (&self.num * &other.den).cmp(&(&other.num * &self.den))
    }
}

impl fmt::Display for ExactVolume {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.den.is_one() {
            write!(f, "{}", self.num)
        } else {
            write!(f, "{}/{}", self.num, self.den)
        }
    }
}

impl Octree {
    /// The exact volume of every non-empty material, in cubic grid units
    /// (leaves run in parallel; the result does not depend on the order).
    #[must_use]
    pub fn exact_volumes(&self) -> BTreeMap<Label, ExactVolume> {
        self.exact_volumes_of(&self.leaves())
    }

    /// The exact volume of every non-empty material of `leaves`, each
    /// measured inside its cell (the octree's leaves, or the parts of them
    /// in smaller cells).
    pub(super) fn exact_volumes_of(
        &self,
        leaves: &[(CellKey, &Leaf)],
    ) -> BTreeMap<Label, ExactVolume> {
        let per_leaf: Vec<Vec<(Label, ExactVolume)>> = leaves
            .par_iter()
            .map(|&(key, leaf)| leaf_volumes(leaf, &self.cell_box(key)))
            .collect();
        let mut parts: BTreeMap<Label, Vec<ExactVolume>> = BTreeMap::new();
        for (label, v) in per_leaf.into_iter().flatten() {
            parts.entry(label).or_default().push(v);
        }
        parts
            .into_iter()
            .map(|(label, parts)| (label, ExactVolume::sum_balanced(parts)))
            .collect()
    }

    /// The exact volume of all material together, in cubic grid units.
    #[must_use]
    pub fn exact_solid_volume(&self) -> ExactVolume {
        ExactVolume::sum_balanced(self.exact_volumes().into_values().collect())
    }
}

/// The exact volume per label of one leaf inside `cell` (the part of the
/// leaf's regions in `cell`, when `cell` lies inside the leaf's own).
fn leaf_volumes(leaf: &Leaf, cell: &CellBox) -> Vec<(Label, ExactVolume)> {
    match leaf {
        Leaf::Uniform(EMPTY) => Vec::new(),
        Leaf::Uniform(label) => vec![(*label, ExactVolume::of_box(cell))],
        Leaf::Bsp(bsp) => {
            let mut arena = ConvexArena::new();
            let Ok(bounds) = cell.add_to(&mut arena) else {
                return Vec::new();
            };
            let mut per_label: BTreeMap<Label, Vec<ExactVolume>> = BTreeMap::new();
            for c in bsp.cells(&mut arena, bounds) {
                if c.label != EMPTY {
                    per_label
                        .entry(c.label)
                        .or_default()
                        .push(ExactVolume::of_polyhedron(&arena, c.poly));
                }
            }
            per_label
                .into_iter()
                .map(|(label, parts)| (label, ExactVolume::sum_balanced(parts)))
                .collect()
        }
    }
}

/// `p − origin` for every point when all are integer points (`W = 1`,
/// coordinates within `i64`), else `None`.
fn integer_offsets(points: &[&Point4], origin: [i64; 3]) -> Option<Vec<[i64; 3]>> {
    points
        .iter()
        .map(|p| {
            let small = p.w_digits == [1, 0, 0] && p.xyz_digits.iter().all(|d| d[1..] == [0; 3]);
            small.then(|| [0, 1, 2].map(|a| p.xyz_digits[a][0] - origin[a]))
        })
        .collect()
}

fn det_i128(a: &[i64; 3], b: &[i64; 3], c: &[i64; 3]) -> i128 {
    let m = |x: i64, y: i64| i128::from(x) * i128::from(y);
    i128::from(a[0]) * (m(b[1], c[2]) - m(b[2], c[1]))
        - i128::from(a[1]) * (m(b[0], c[2]) - m(b[2], c[0]))
        + i128::from(a[2]) * (m(b[0], c[1]) - m(b[1], c[0]))
}

fn det_big(a: &[BigInt; 3], b: &[BigInt; 3], c: &[BigInt; 3]) -> BigInt {
    &a[0] * (&b[1] * &c[2] - &b[2] * &c[1]) - &a[1] * (&b[0] * &c[2] - &b[2] * &c[0])
        + &a[2] * (&b[0] * &c[1] - &b[1] * &c[0])
}

/// `(X, W)` of a vertex as big integers, from its balanced digits.
fn to_big(p: &Point4) -> ([BigInt; 3], BigInt) {
    let digits = |d: &[i64]| {
        d.iter()
            .rev()
            .fold(BigInt::zero(), |acc, &x| (acc << 64) + BigInt::from(x))
    };
    (
        [0, 1, 2].map(|a| digits(&p.xyz_digits[a])),
        digits(&p.w_digits),
    )
}
