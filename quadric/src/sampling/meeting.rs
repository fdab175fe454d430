//! The cells of one row of a curved triangle's fill grid that meet the
//! region (paper 2, §4.2: the fill of a curved triangle,
//! `subdivide::RegionJob::fill_curved`).
//!
//! Notation: `w` the warped coordinates of the triangle's cell
//! ([`Warp`](crate::sampling::warp::Warp)), where the region is a
//! triangle and a grid cell a box; a row is the grid's cells between two
//! grid lines `y = const`.

use glam::DVec2;

use crate::sampling::curved::CurvedTriangle;

/// The grid of a curved triangle's fill: `nx × ny` cells of size `cell`
/// over `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FillGrid {
    pub lo: DVec2,
    pub hi: DVec2,
    pub cell: DVec2,
    pub nx: usize,
    pub ny: usize,
}

impl FillGrid {
    /// Grid point `(i, j)`, `i ≤ nx`, `j ≤ ny`; the last ones are the
    /// bounds' ends exactly, so that the grid spans them.
    #[inline]
    pub(crate) fn point(&self, i: usize, j: usize) -> DVec2 {
        #[allow(clippy::cast_precision_loss)]
        let (x, y) = (i as f64, j as f64);
        DVec2::new(
            if i == self.nx {
                self.hi.x
            } else {
                self.lo.x + self.cell.x * x
            },
            if j == self.ny {
                self.hi.y
            } else {
                self.lo.y + self.cell.y * y
            },
        )
    }
}

/// The cells `first..=last` of one row of a curved triangle's fill grid
/// that [`CurvedTriangle::meets_box`] accepts, where known.
///
/// They are a run: in the warped coordinates `w` the region is a triangle
/// and a cell a box, and along a row (a fixed `y` range, the columns
/// increasing) the boxes' `w` ranges move one way (each axis of the warp
/// is monotone on the region's side of 0, and so is every rounded
/// operation). So each comparison of the test (a bounding-box side, or a
/// side of the triangle against the box corner farthest inside it) holds
/// on a prefix or a suffix of the row, and all of them on a run. When the
/// test accepts the row's first and last cells with a corner in the
/// region, the run holds every cell between them, and walking outwards
/// from them until the test fails finds its ends: the cells it would
/// accept, with a few calls instead of one per cell without a corner
/// inside.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeetingRun {
    known: bool,
    first: usize,
    last: usize,
}

impl MeetingRun {
    /// A row whose run is not known: the test is asked per cell.
    pub(crate) const UNKNOWN: Self = Self {
        known: false,
        first: 0,
        last: 0,
    };

    /// The run of row `j` of `grid`, with corner flags `inside`
    /// (`nx + 1` per grid row).
    #[inline(never)]
    pub(crate) fn of_row(
        region: &CurvedTriangle,
        inside: &[bool],
        j: usize,
        grid: FillGrid,
    ) -> Self {
        let FillGrid { nx, .. } = grid;
        let grid = |i: usize, j: usize| grid.point(i, j);
        let cornered = |i: usize| {
            let k = j * (nx + 1) + i;
            inside[k] || inside[k + 1] || inside[k + nx + 1] || inside[k + nx + 2]
        };
        let meets = |i: usize| region.meets_box(grid(i, j), grid(i + 1, j + 1));
        // The first and last cells with a corner in the region: beside the
        // first and last such grid points of the two grid rows.
        let rows = &inside[j * (nx + 1)..(j + 2) * (nx + 1)];
        let (below, above) = rows.split_at(nx + 1);
        let lowest = |row: &[bool]| row.iter().position(|&c| c);
        let highest = |row: &[bool]| row.iter().rposition(|&c| c);
        let (Some(left), Some(right)) = (
            lowest(below).into_iter().chain(lowest(above)).min(),
            highest(below).into_iter().chain(highest(above)).max(),
        ) else {
            return Self::UNKNOWN;
        };
        // A grid point `p` is a corner of cells `p − 1` and `p`.
        let (mut first, mut last) = (left.saturating_sub(1), right.min(nx - 1));
        debug_assert!(cornered(first) && cornered(last));
        if !meets(first) || (last != first && !meets(last)) {
            return Self::UNKNOWN;
        }
        while first > 0 && meets(first - 1) {
            first -= 1;
        }
        while last + 1 < nx && meets(last + 1) {
            last += 1;
        }
        Self {
            known: true,
            first,
            last,
        }
    }

    /// Whether the test accepts cell `i`, the box `[lo, hi]` (asked where
    /// the run is not known).
    #[inline(never)]
    pub(crate) fn meets(self, i: usize, region: &CurvedTriangle, lo: DVec2, hi: DVec2) -> bool {
        if self.known {
            let meets = self.first <= i && i <= self.last;
            debug_assert_eq!(
                meets,
                region.meets_box(lo, hi),
                "the run of cells meeting the region"
            );
            meets
        } else {
            region.meets_box(lo, hi)
        }
    }
}
