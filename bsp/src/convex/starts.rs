//! The records of where the next cut may start (paper 1 §3.3): the
//! landmarks and the extreme vertices of the parts of the last cut, kept
//! in the arena's scratch space from one cut to the next. How they are
//! found and used is in `landmarks` and `extremes`.

use crate::exact::{FILTER_EPSILON, Plane, Sign};

/// The descent steps from which a cut without landmarks leaves some: on
/// small polyhedra the descent from any vertex is short, and the landmarks
/// would cost more than they save.
pub(super) const LANDMARK_DESCENT: u32 = 4;

/// The most landmarks kept for one part.
pub(super) const MAX_LANDMARKS: usize = 4;

/// A few vertices of each part of the last cut, and those of the
/// polyhedron the current cut splits.
#[derive(Clone, Debug)]
pub(crate) struct Landmarks {
    /// The id of each part (`u32::MAX` for none): the lower and upper part
    /// of a two-sided cut, or the kept part and none.
    pub(super) parts: [u32; 2],
    /// The landmarks of each part.
    pub(super) vertices: [[u32; MAX_LANDMARKS]; 2],
    /// How many of `vertices` each part has.
    pub(super) counts: [usize; 2],
    /// The landmarks of the polyhedron being cut.
    pub(super) current: [u32; MAX_LANDMARKS],
    /// The side of each of `current`, where the `f64` filter tells it.
    pub(super) current_sides: [Option<Sign>; MAX_LANDMARKS],
    /// How many of `current` there are.
    pub(super) current_count: usize,
}

impl Default for Landmarks {
    fn default() -> Self {
        Self {
            parts: [u32::MAX; 2],
            vertices: [[u32::MAX; MAX_LANDMARKS]; 2],
            counts: [0; 2],
            current: [u32::MAX; MAX_LANDMARKS],
            current_sides: [None; MAX_LANDMARKS],
            current_count: 0,
        }
    }
}

impl Landmarks {
    /// Forgets every landmark.
    #[inline]
    pub(crate) fn forget(&mut self) {
        self.forget_parts();
        self.current_count = 0;
    }

    /// Makes the landmarks of the part with id `poly` current (none when
    /// `poly` is no part of the last cut) and forgets the parts: the cut
    /// records new ones once it is done. Returns how many there are.
    ///
    /// The parts are forgotten even when `poly` is neither: it may be one
    /// of them named by another of its half-edges, which the cut changes.
    #[inline]
    pub(super) fn take_for(&mut self, poly: u32) -> usize {
        if self.parts == [u32::MAX; 2] {
            // Nothing to forget (the common case of small polyhedra).
            self.current_count = 0;
            return 0;
        }
        // Forgotten parts have id `u32::MAX` and no landmarks.
        self.current_count = if self.parts[0] == poly {
            self.current = self.vertices[0];
            self.counts[0]
        } else if self.parts[1] == poly {
            self.current = self.vertices[1];
            self.counts[1]
        } else {
            0
        };
        self.forget_parts();
        self.current_count
    }

    /// Forgets the landmarks of the parts.
    #[inline]
    pub(super) fn forget_parts(&mut self) {
        self.parts = [u32::MAX; 2];
        self.counts = [0; 2];
    }

    /// Records part `k` (0 or 1) with id `part`: the current landmarks on
    /// a side for which `keep` holds, then `cap_vertex` if there is room.
    #[inline]
    pub(super) fn set_part(
        &mut self,
        k: usize,
        part: u32,
        keep: impl Fn(Option<Sign>) -> bool,
        cap_vertex: u32,
    ) {
        let slots = &mut self.vertices[k];
        let mut n = 0;
        let mut has_cap = false;
        let count = self.current_count;
        for (&v, &side) in self.current[..count].iter().zip(&self.current_sides) {
            slots[n] = v;
            has_cap |= v == cap_vertex;
            n += usize::from(keep(side));
        }
        if n < MAX_LANDMARKS && !has_cap {
            slots[n] = cap_vertex;
            n += 1;
        }
        self.parts[k] = part;
        self.counts[k] = n;
    }

    /// Whether the cut leaves landmarks: when it had some, or when its
    /// descent took `descent_steps ≥ LANDMARK_DESCENT`.
    #[inline]
    pub(super) fn worth_keeping(&self, descent_steps: u32) -> bool {
        self.current_count > 0 || descent_steps >= LANDMARK_DESCENT
    }
}

/// The number of fixed directions: `±u_i` for the axes of [`projections`].
pub(super) const DIRECTIONS: usize = 2 * HALF;

/// The number of directions up to sign.
pub(super) const HALF: usize = 3;

/// Every direction known.
pub(super) const ALL: u16 = (1 << DIRECTIONS) - 1;

/// The descent steps from which a cut without extremes records some.
pub(super) const EXTREME_DESCENT: u32 = 6;

/// The offsets of the point with homogeneous `f64` coordinates `p` along
/// the first `HALF` directions (direction `i + HALF` is the opposite of
/// `i`).
#[inline]
pub(super) fn projections(p: [f64; 4]) -> [f64; HALF] {
    let [x, y, z, w] = p;
    [x / w, y / w, z / w]
}

/// The direction closest to `n`, the normal of `approx`.
#[inline]
pub(super) fn closest_direction(approx: [f64; 4]) -> usize {
    let [a, b, c, _] = approx;
    let scores = [a, b, c];
    let (mut best, mut best_score) = (0, -1.0);
    for (i, &score) in scores.iter().enumerate() {
        if score.abs() > best_score {
            (best, best_score) = (i, score.abs());
        }
    }
    if scores[best] < 0.0 {
        best + HALF
    } else {
        best
    }
}

/// The extreme vertices of the polyhedron the current cut splits, or of
/// the one the last cut split, and which of them each part of that cut
/// kept.
#[derive(Clone, Debug)]
pub(crate) struct Extremes {
    /// The id of each part of the last cut (`u32::MAX` for none).
    pub(super) parts: [u32; 2],
    /// Which of `vertices` each part has kept (a bit per direction).
    pub(super) valid: [u16; 2],
    /// `e_i`.
    pub(super) vertices: [u32; DIRECTIONS],
    /// The homogeneous `f64` coordinates of the `e_i`, coordinate by
    /// coordinate (`X`, `Y`, `Z`, `W`), and the largest magnitude of the
    /// four of each.
    pub(super) approx: [[f64; DIRECTIONS]; 5],
    /// Whether the polyhedron being cut has extremes.
    pub(super) has_current: bool,
}

impl Default for Extremes {
    fn default() -> Self {
        Self {
            parts: [u32::MAX; 2],
            valid: [0; 2],
            vertices: [u32::MAX; DIRECTIONS],
            approx: [[0.0; DIRECTIONS]; 5],
            has_current: false,
        }
    }
}

impl Extremes {
    /// Forgets every extreme.
    #[inline]
    pub(crate) fn forget(&mut self) {
        self.parts = [u32::MAX; 2];
        self.has_current = false;
    }

    /// Whether the polyhedron being cut has extremes.
    #[cfg(test)]
    pub(crate) fn in_use(&self) -> bool {
        self.has_current
    }

    /// Whether the cut records extremes for its parts.
    #[inline]
    pub(super) fn worth_keeping(&self, descent_steps: u32) -> bool {
        self.has_current || descent_steps >= EXTREME_DESCENT
    }

    /// The directions whose `e_i` the filter places strictly below and
    /// strictly above `s` (a bit per direction). The error bound of the
    /// `f64` value `Σ t_k` of `T` is taken as `2^-50·M·Σ|s_k|`, `M` the
    /// largest magnitude of the point's coordinates, which bounds the
    /// `2^-50·Σ|t_k|` of [`FilteredDot`](crate::exact::FilteredDot).
    #[inline]
    pub(super) fn sides(&self, s: &Plane) -> (u16, u16) {
        let [a, b, c, d] = s.approx;
        let scale = ((a.abs() + b.abs()) + (c.abs() + d.abs())) * (FILTER_EPSILON * 1.01);
        let [xs, ys, zs, ws, ms] = &self.approx;
        let (mut below, mut above) = (0u16, 0u16);
        for i in 0..DIRECTIONS {
            let sum = (xs[i] * a + ys[i] * b) + (zs[i] * c + ws[i] * d);
            let bound = ms[i] * scale;
            below |= u16::from(sum < -bound) << i;
            above |= u16::from(sum > bound) << i;
        }
        (below, above)
    }

    /// The directions whose `e_i` the filter places strictly on side
    /// `side` of `s`: that mask of [`Extremes::sides`] alone, for a cut
    /// that keeps one part.
    #[inline]
    pub(super) fn strictly_on(&self, s: &Plane, side: Sign) -> u16 {
        let [a, b, c, d] = s.approx;
        let scale = ((a.abs() + b.abs()) + (c.abs() + d.abs())) * (FILTER_EPSILON * 1.01);
        let [xs, ys, zs, ws, ms] = &self.approx;
        let flip = if side == Sign::Negative { -1.0 } else { 1.0 };
        let mut mask = 0u16;
        for i in 0..DIRECTIONS {
            let sum = (xs[i] * a + ys[i] * b) + (zs[i] * c + ws[i] * d);
            // `sum < −bound` is `−sum > bound`: negating is exact.
            mask |= u16::from(flip * sum > ms[i] * scale) << i;
        }
        mask
    }

    /// Records `v`, with homogeneous `f64` coordinates `p`, as `e_i`.
    #[inline]
    pub(super) fn set(&mut self, i: usize, v: u32, p: [f64; 4]) {
        self.vertices[i] = v;
        let magnitude = p.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (k, &x) in p.iter().chain([magnitude].iter()).enumerate() {
            self.approx[k][i] = x;
        }
    }
}
