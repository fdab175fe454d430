//! Adaptive subdivision of one basic region with the coverage guarantee
//! (paper 2, §4.2, Fig. 8b–c).
//!
//! Notation: `r` the splat radius (world), `d(v)` the quadric-relative CSG
//! distance of eq. 22 at the surface point above corner `v`, also bounded by
//! the bounding sphere (`max(d₂₂, |x − C| − R)`, still a valid eq.-22
//! distance for the solid clipped to the sphere), `δ₊` the region's maximum
//! distortion (§3.4). A world radius `ρ` maps to at least a path length
//! `ρ/δ₊` in the plane, since the heightfield stretches plane lengths by at
//! most `δ₊`; paths are straight inside polygons and arcs inside curved
//! triangles, whose radii are path lengths ([`Region`]).
//!
//! Per region:
//! 1. drop it if no point is in the plane's low-distortion region, the
//!    heightfield's domain or the bounding sphere;
//! 2. while `δ₊` exceeds [`DISTORTION_CAP`] (only where a bound reaches
//!    past the low-distortion region or to a singular point): drop the
//!    region if the distance at the centre of a ball around its patch
//!    exceeds the ball's radius, else subdivide;
//! 3. if every corner's disc of plane radius `|d(v)|/δ₊` reaches the
//!    region's cover radius and all signs agree: fill (negative) or drop
//!    (positive); a polygon whose distortion varies is first split, so
//!    that each part's grid follows its own `δ₊` (a density-aware fill),
//!    and the cells of rectangles and curved triangles are stretched along
//!    the axis the surface tilts least along ([`cell`]); a polygon is
//!    filled with a grid of cells, one sample at each cell centre moved
//!    into the region; a curved triangle with a grid of cells, one sample
//!    at the centre of each cell inside it, and on its border one sample
//!    at a point of the region per cell or per quarter of a cell, with
//!    radii from the cell's own distortion bound or from path lengths
//!    inside the region;
//! 4. if a corner is on the CSG surface and the region lies within plane
//!    distance `r/δ₊` of a point on the surface (a polygon's centroid,
//!    evaluated then, or else the corner of least reach), emit that one
//!    sample with the reduced radius `reach·δ₊` (§6.1);
//! 5. else halve the longest edge and recurse; unclassified regions smaller
//!    than `min_region_fraction·r` are dropped (the paper's threshold).
//!
//! The bounding sphere's term `|x − C| − R` is left out of `d(v)` in regions
//! whose surface lies inside the sphere (so a lone solid well inside its
//! bounds is filled whole). Corner classifications are handed down to the
//! children (a split adds one or two new corners), and every
//! [`CULL_EVERY`] levels the products farther than twice the region's
//! world radius are replaced by a constant lower bound of their distance
//! ([`CsgDistance::cull`]), so deep regions only evaluate the products
//! near them. The constants stay above the world radius, the largest
//! threshold the region's own tests compare a distance with (its cover
//! radius and its centroid's reach, times `δ₊`), so culling changes no
//! decision there.

use std::cell::{Cell, RefCell};

use glam::{DVec2, DVec3};

use crate::csg::{CsgDistance, OtherTerms};
use crate::sampling::cell;
use crate::sampling::curved::CurvedTriangle;
use crate::sampling::heightfield::Heightfield;
use crate::sampling::meeting::{FillGrid, MeetingRun};
use crate::sampling::polygon::Polygon;
use crate::sampling::regions::Region;
use crate::sampling::storage::{Bounds, Lift, LiftRef, Rounding};
use crate::sampling::{BoundingSphere, Sample, SampleBudget, SampleOptions, SamplingStats};

/// Regions whose distortion bound exceeds this are subdivided before they
/// are classified. It must be at least `√3`, the largest distortion inside
/// a low-distortion region (§4.1), so that every owned region gets
/// classified. Basic regions lie in their plane's low-distortion region,
/// but a polygon's bound is taken over its bounding box, which may reach
/// past a seam, and at a cone's apex the distortion is unbounded; larger
/// values classify such regions earlier.
pub const DISTORTION_CAP: f64 = 2.5;

/// Subdivision levels between two cullings of far products
/// ([`CsgDistance::cull`]); each level halves a region's area.
const CULL_EVERY: u32 = 2;

/// The density-aware fill splits a polygon whose distortion bound exceeds
/// its minimum by more than this factor...
const FILL_SPREAD: f64 = 1.1;

/// ... and whose grid has at least this many cells (the parts' seams cost
/// partial cells)...
const FILL_SPLIT_CELLS: f64 = 64.0;

/// ... at most this many times (halvings of its area).
const MAX_FILL_SPLITS: u32 = 8;

/// Recursion depth limit (a region then is `2⁻²⁵` of its basic region).
const MAX_DEPTH: u32 = 50;

/// Quarterings of a border cell in the fill of a curved triangle. Two
/// always suffice: a path inside the region is at most `1 + 1/√2` times
/// the distance of its ends ([`Warp::path_length`]), and the second
/// quartering halves a cell's half-diagonal (at most `r/δ₊`) twice.
///
/// [`Warp::path_length`]: crate::sampling::warp::Warp::path_length
const MAX_FILL_DEPTH: u32 = 2;

/// Everything one basic region's subdivision reads.
pub(crate) struct RegionJob<'a> {
    pub distance: &'a CsgDistance<'a>,
    pub patch: u32,
    pub heightfield: &'a Heightfield,
    pub sphere: BoundingSphere,
    pub options: &'a SampleOptions,
    /// The samples all regions may still emit.
    pub budget: &'a SampleBudget,
    /// The product nearest to the last query (see [`CsgDistance::relative_distance_hinted`]).
    pub hint: Cell<usize>,
    /// The other products of the normal form as seen from this literal.
    pub others: OtherTerms,
    /// Buffers of culled terms no longer in use ([`CsgDistance::cull_into`]).
    pub spare: RefCell<Vec<OtherTerms>>,
    /// How the samples are stored in `f32`.
    pub rounding: Rounding,
}

/// Where a region lies: its subdivision depth, whether its surface is
/// known to lie inside the bounding sphere, and whether it is a polygon
/// known to lie in the heightfield's domain and low-distortion region
/// (then so do the polygons it splits into, and they skip the test).
#[derive(Clone, Copy, Debug)]
struct Within {
    depth: u32,
    sphere: bool,
    owned: bool,
}

/// A region corner: not yet evaluated, outside the heightfield's domain, or
/// its surface point with the eq.-22 distance `d₂₂` (unclipped).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Corner {
    Unknown,
    OutsideDomain,
    Known(DVec3, f64),
}

impl RegionJob<'_> {
    /// Subdivides `region`, appending samples to `out`.
    pub(crate) fn run(&self, region: &Region, out: &mut Vec<Sample>, stats: &mut SamplingStats) {
        let within = Within {
            depth: 0,
            sphere: false,
            owned: false,
        };
        self.visit(
            region,
            [Corner::Unknown; 4],
            &self.others,
            within,
            out,
            stats,
        );
    }

    fn evaluate(&self, v: DVec2, others: &OtherTerms, stats: &mut SamplingStats) -> Corner {
        match self.heightfield.point(v) {
            Some(p) => {
                stats.distance_queries += 1;
                Corner::Known(p, self.relative_distance(p, others))
            }
            None => Corner::OutsideDomain,
        }
    }

    /// `others` restricted to the region's patch, every [`CULL_EVERY`] levels.
    fn culled(
        &self,
        region: &Region,
        delta: f64,
        depth: u32,
        others: &OtherTerms,
    ) -> Option<OtherTerms> {
        if !depth.is_multiple_of(CULL_EVERY) || others.literal_count() == 0 || !delta.is_finite() {
            return None;
        }
        let (anchor, reach) = region.anchor();
        let centre = self.heightfield.point(anchor)?;
        let mut out = self
            .spare
            .borrow_mut()
            .pop()
            .unwrap_or_else(OtherTerms::empty);
        if self
            .distance
            .cull_into(others, centre, reach * delta, &mut out)
        {
            Some(out)
        } else {
            self.spare.borrow_mut().push(out);
            None
        }
    }

    fn visit(
        &self,
        region: &Region,
        mut corners: [Corner; 4],
        others: &OtherTerms,
        mut within: Within,
        out: &mut Vec<Sample>,
        stats: &mut SamplingStats,
    ) {
        stats.regions += 1;
        let depth = within.depth;
        let hf = self.heightfield;
        let (lo, hi) = region.bounds();
        if self.budget.is_over() {
            return;
        }
        if !within.owned {
            let (foreign, owned) = hf.box_ownership(lo, hi);
            if foreign {
                return;
            }
            within.owned = owned && matches!(region, Region::Polygon(_));
        }
        // A box under a patch inside the sphere is not outside it (its
        // domain points are under that patch, and it has some: it is not
        // foreign).
        if !within.sphere && self.outside_sphere(lo, hi) {
            return;
        }
        within.sphere = within.sphere || self.inside_sphere(lo, hi);
        if depth >= MAX_DEPTH {
            stats.depth_limited += 1;
            return;
        }
        let r = self.options.radius;
        let verts = region.vertices();
        let (_, delta) = region.distortion_bounds(hf);
        if delta > DISTORTION_CAP && self.ball_is_off_surface(lo, hi, others, stats) {
            stats.discarded += 1;
            return;
        }
        if delta <= DISTORTION_CAP {
            for (c, v) in corners.iter_mut().zip(verts) {
                if *c == Corner::Unknown {
                    *c = self.evaluate(*v, others, stats);
                }
            }
            // Corner classifications; NaN where a corner is outside the domain.
            let mut ds = [f64::NAN; 4];
            for (d, c) in ds.iter_mut().zip(&corners[..verts.len()]) {
                if let Corner::Known(p, v) = c {
                    *d = self.clipped(*p, *v, within.sphere);
                }
            }
            let ds = &ds[..verts.len()];
            if ds.iter().all(|d| !d.is_nan()) {
                let cover = region.cover_radius();
                let negative = ds.iter().all(|d| *d < 0.0);
                let positive = ds.iter().all(|d| *d > 0.0);
                let reached = ds.iter().all(|d| d.abs() / delta >= cover);
                if reached && positive {
                    stats.discarded += 1;
                    return;
                }
                if positive && self.centre_is_off_surface(region, delta, others, stats) {
                    stats.discarded += 1;
                    return;
                }
                if reached && negative {
                    stats.filled += 1;
                    self.fill(region, delta, 0, out);
                    return;
                }
            }
            // One sample covers a small enough region.
            if let Some((uv, reach)) =
                self.single_sample(region, delta, ds, others, within.sphere, stats)
            {
                if self.budget.reserve(1.0) {
                    let (lo, hi) = region.bounds();
                    let cell = (lo - uv).abs().max((hi - uv).abs());
                    out.push(self.sample(uv, reach.max(f64::MIN_POSITIVE), cell));
                }
                return;
            }
        }
        if region.diameter() < self.options.min_region_fraction * r {
            stats.dropped_small += 1;
            return;
        }
        // Children reuse the parent's corners and share the new midpoint(s).
        let culled = if delta <= DISTORTION_CAP {
            self.culled(region, delta, depth, others)
        } else {
            None
        };
        let others = culled.as_ref().unwrap_or(others);
        // At most 4 parent corners and 2 new midpoints.
        let mut seen = [(DVec2::NAN, Corner::Unknown); 6];
        let mut count = verts.len();
        for (slot, (v, c)) in seen.iter_mut().zip(verts.iter().zip(corners)) {
            *slot = (*v, c);
        }
        for child in region.split() {
            let mut inherited = [Corner::Unknown; 4];
            for (slot, v) in inherited.iter_mut().zip(child.vertices()) {
                if let Some((_, c)) = seen[..count].iter().find(|(w, _)| w == v) {
                    *slot = *c;
                } else if delta <= DISTORTION_CAP && count < seen.len() {
                    let c = self.evaluate(*v, others, stats);
                    seen[count] = (*v, c);
                    count += 1;
                    *slot = c;
                }
            }
            let within = Within {
                depth: depth + 1,
                ..within
            };
            self.visit(&child, inherited, others, within, out, stats);
        }
        if let Some(buffer) = culled {
            self.spare.borrow_mut().push(buffer);
        }
    }

    /// Step 4: a point of the region on the CSG surface whose straight
    /// paths reach the whole region within `r` (world `reach·δ₊`), and that
    /// reach. A polygon's centroid reaches it in about half the path of a
    /// corner, so it is tried first (one distance query) where it would
    /// cover the region; else the surface corner of least reach.
    fn single_sample(
        &self,
        region: &Region,
        delta: f64,
        ds: &[f64],
        others: &OtherTerms,
        inside_sphere: bool,
        stats: &mut SamplingStats,
    ) -> Option<(DVec2, f64)> {
        // Both candidates need a corner on the surface.
        if !ds.iter().any(|d| *d < 0.0) {
            return None;
        }
        let r = self.options.radius;
        let corner = ds
            .iter()
            .enumerate()
            .filter(|(_, d)| **d < 0.0)
            .map(|(i, _)| (region.vertices()[i], region.reach(i) * delta))
            .filter(|(_, reach)| *reach <= r)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Region::Polygon(_) = region {
            let (anchor, reach) = region.anchor();
            let reach = reach * delta;
            let worth = corner.map_or(ds.iter().any(|d| *d < 0.0), |(_, c)| reach < 0.75 * c);
            if reach <= r
                && worth
                && let Some(p) = self.heightfield.point(anchor)
            {
                stats.distance_queries += 1;
                let d = self.relative_distance(p, others);
                if self.clipped(p, d, inside_sphere) < 0.0 {
                    return Some((anchor, reach));
                }
            }
        }
        corner
    }

    /// Whether the surface over the box `[lo, hi]` is off the CSG surface as
    /// a whole, judged from the centre of a ball around it (needs no
    /// distortion bound): eq. 22's positive case holds for every point of
    /// `Q` within `d` of any point.
    fn ball_is_off_surface(
        &self,
        lo: DVec2,
        hi: DVec2,
        others: &OtherTerms,
        stats: &mut SamplingStats,
    ) -> bool {
        let Some((centre, radius)) = self.heightfield.patch_ball(lo, hi) else {
            return true;
        };
        stats.distance_queries += 1;
        self.classify(centre, others) > radius
    }

    /// Whether a polygon whose corners are all off the surface is off it as
    /// a whole, judged from its centroid `c`: every point of the polygon is
    /// within the straight path `reach` of `c` (the polygon is convex), so
    /// its surface point within world distance `reach·δ₊` of the one above
    /// `c`, and eq. 22's positive case holds for all of them when
    /// `d(c) ≥ reach·δ₊`. Ends the strips of regions just off the surface
    /// beside an edge earlier than the corner discs can.
    fn centre_is_off_surface(
        &self,
        region: &Region,
        delta: f64,
        others: &OtherTerms,
        stats: &mut SamplingStats,
    ) -> bool {
        let Region::Polygon(_) = region else {
            return false;
        };
        let (anchor, reach) = region.anchor();
        let Some(p) = self.heightfield.point(anchor) else {
            return false;
        };
        stats.distance_queries += 1;
        self.classify(p, others) >= reach * delta
    }

    /// `max(d₂₂(p), |p − C| − R)`.
    fn classify(&self, p: DVec3, others: &OtherTerms) -> f64 {
        let d = self.relative_distance(p, others);
        self.clipped(p, d, false)
    }

    /// `d₂₂(p)` (eq. 22).
    fn relative_distance(&self, p: DVec3, others: &OtherTerms) -> f64 {
        let mut hint = self.hint.get();
        let d = self.distance.relative_distance_among(p, others, &mut hint);
        self.hint.set(hint);
        d
    }

    /// The distance `d` at `p` for the solid clipped to the bounding sphere,
    /// `max(d, |p − C| − R)`, or `d` itself in a region whose surface lies
    /// inside the sphere (there the clipping changes nothing, and `d` alone
    /// lets regions far from the solid's edges be filled whole).
    fn clipped(&self, p: DVec3, d: f64, inside_sphere: bool) -> f64 {
        if inside_sphere {
            d
        } else {
            d.max(self.sphere.signed_distance(p))
        }
    }

    /// Whether the surface over the box `[lo, hi]` lies inside the bounding
    /// sphere (its [`patch_ball`](Heightfield::patch_ball) does).
    fn inside_sphere(&self, lo: DVec2, hi: DVec2) -> bool {
        self.heightfield
            .patch_ball(lo, hi)
            .is_some_and(|(centre, radius)| {
                centre.distance(self.sphere.centre) + radius <= self.sphere.radius
            })
    }

    fn outside_sphere(&self, lo: DVec2, hi: DVec2) -> bool {
        let c = self.heightfield.project(self.sphere.centre);
        c.clamp(lo, hi).distance(c) > self.sphere.radius
    }

    /// Covers a region that lies wholly on the CSG surface (step 3), with
    /// the density-aware fill: while a polygon's own distortion bound `δ₊`
    /// (the smaller of its own and the one handed down, both valid on it)
    /// exceeds its minimum by more than [`FILL_SPREAD`] and its grid would
    /// have at least [`FILL_SPLIT_CELLS`] cells, it is split as in
    /// subdivision and each part filled with its own bound; then one grid
    /// whose cells follow the slopes ([`cell`]). Curved triangles are not
    /// split: their parts' border cells cost more than the bound saves.
    fn fill(&self, region: &Region, delta: f64, depth: u32, out: &mut Vec<Sample>) {
        let (low, own) = region.distortion_bounds(self.heightfield);
        let delta = own.min(delta);
        let slopes = self.slopes(region);
        if depth < MAX_FILL_SPLITS
            && matches!(region, Region::Polygon(_))
            && low.is_finite()
            && delta > FILL_SPREAD * low
            && self.grid_cells(region, delta, slopes) >= FILL_SPLIT_CELLS
        {
            for child in region.split() {
                self.fill(&child, delta, depth + 1, out);
            }
            return;
        }
        match region {
            Region::Polygon(p) => self.fill_polygon(p, delta, slopes, out),
            Region::Curved(c) => self.fill_curved(c, delta, slopes, out),
        }
    }

    /// Slope bounds for the shaped cells of a fill: over a rectangle, or at
    /// a curved triangle's vertices. A triangle's cells are square (its
    /// nearest-point samples are bounded by plane distance only).
    fn slopes(&self, region: &Region) -> DVec2 {
        match region {
            Region::Polygon(p) if p.is_rectangle() => {
                let (lo, hi) = p.bounds();
                self.heightfield.slope_bounds(lo, hi)
            }
            Region::Polygon(_) => DVec2::INFINITY,
            Region::Curved(c) => self.heightfield.slope_bounds_at(c.vertices()),
        }
    }

    /// The cells of the bounding-box grid of `region`.
    fn grid_cells(&self, region: &Region, delta: f64, slopes: DVec2) -> f64 {
        let (lo, hi) = region.bounds();
        let step = 2.0 * cell::half_size(self.options.radius, delta, slopes);
        let n = ((hi - lo) / step).ceil().max(DVec2::ONE);
        n.x * n.y
    }

    /// Covers a curved triangle: a grid of cells whose centre reaches the
    /// cell within `r` ([`cell`], slopes and `δ₊` bounded at the region's
    /// vertices). A cell inside the region (its four corners are: the
    /// region is convex in `w`, a cell is a box there) gets one sample at
    /// its centre, reaching the cell along straight paths inside the
    /// region. A cell on the region's border is handed to
    /// [`cover_box`](Self::cover_box).
    fn fill_curved(
        &self,
        region: &CurvedTriangle,
        delta: f64,
        slopes: DVec2,
        out: &mut Vec<Sample>,
    ) {
        let (lo, hi) = region.bounds();
        let size = hi - lo;
        let step = 2.0 * cell::half_size(self.options.radius, delta, slopes);
        let nx = (size.x / step.x).ceil().max(1.0);
        let ny = (size.y / step.y).ceil().max(1.0);
        // One sample per cell inside, up to 16 per border cell (two
        // quarterings): reserved before the grid is allocated.
        if !self
            .budget
            .reserve((nx + 1.0) * (ny + 1.0) + 32.0 * (nx + ny))
        {
            return;
        }
        let cell = DVec2::new(size.x / nx, size.y / ny);
        let radius = cell::reach(0.5 * cell, delta, slopes).min(self.options.radius);
        // The bounds of every inside cell, rounded once.
        let inside_bounds = Bounds::shared(&self.rounding, radius, 0.5 * cell);
        let lift = self.lift();
        // Cell counts are positive integers stored in f64, within the
        // sample budget just reserved.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let (nx, ny) = (nx as usize, ny as usize);
        let fill_grid = FillGrid {
            lo,
            hi,
            cell,
            nx,
            ny,
        };
        let grid = |i: usize, j: usize| fill_grid.point(i, j);
        out.reserve(nx * ny);
        let mut inside = vec![false; (nx + 1) * (ny + 1)];
        for j in 0..=ny {
            for i in 0..=nx {
                inside[j * (nx + 1) + i] = region.contains(grid(i, j));
            }
        }
        // The grid's columns increase along a row (see `MeetingRun`).
        let increasing = nx == 1 || grid(nx - 1, 0).x <= hi.x;
        for j in 0..ny {
            let run = if increasing {
                MeetingRun::of_row(region, &inside, j, fill_grid)
            } else {
                MeetingRun::UNKNOWN
            };
            for i in 0..nx {
                let (a, b) = (grid(i, j), grid(i + 1, j + 1));
                let k = j * (nx + 1) + i;
                let corners = [
                    inside[k],
                    inside[k + 1],
                    inside[k + nx + 1],
                    inside[k + nx + 2],
                ];
                if corners.iter().all(|c| *c) {
                    out.push(lift.sample(0.5 * (a + b), &inside_bounds));
                } else if corners.iter().any(|c| *c) || run.meets(i, region, a, b) {
                    self.cover_box(region, delta, a, b, 0, out);
                }
            }
        }
    }

    /// Covers the points of `region` in the box `[lo, hi]` (on its border;
    /// the caller has checked that they meet) with one sample at a point `q` of the region in the box: the box
    /// centre if it is inside, else the region's point nearest to it (in
    /// `w`) if that lies in the box, else some point of the region in the
    /// box. The radius bounds the world distance from `q` to every point of
    /// the region in the box by the smaller of two bounds: straight segments
    /// in the box, stretched by at most the box's distortion bound (exact at
    /// its corners, §3.4), or paths inside the region (`δ₊` times their
    /// length bound). Boxes whose radius would exceed `r` are quartered.
    fn cover_box(
        &self,
        region: &CurvedTriangle,
        delta: f64,
        lo: DVec2,
        hi: DVec2,
        depth: u32,
        out: &mut Vec<Sample>,
    ) {
        if depth > 0 && !region.meets_box(lo, hi) {
            return;
        }
        let centre = 0.5 * (lo + hi);
        let near = region.nearest_to(centre);
        let point = if near.cmpge(lo).all() && near.cmple(hi).all() {
            near
        } else if let Some(p) = region.point_in_box(lo, hi) {
            p
        } else {
            return;
        };
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        // One square root of the largest squared distance (`√` is monotone
        // and correctly rounded: the same as the largest distance).
        let far = corners
            .iter()
            .map(|c| c.distance_squared(point))
            .fold(0.0, f64::max)
            .sqrt();
        // The box is in the region's cell of the warp, where the distortion
        // is extreme at box corners (and unbounded where `r ≤ 0` at one).
        let (_, box_delta) = self.heightfield.distortion_bounds_at(&corners);
        let floor = lo.abs().min(hi.abs());
        let path = delta * region.warp().path_length(far, floor);
        let radius = (box_delta * far).min(path);
        if radius <= self.options.radius || depth >= MAX_FILL_DEPTH {
            let cell = (lo - point).abs().max((hi - point).abs());
            out.push(self.sample(point, radius.min(self.options.radius), cell));
            return;
        }
        let mid = centre;
        for (a, b) in [
            (lo, mid),
            (DVec2::new(mid.x, lo.y), DVec2::new(hi.x, mid.y)),
            (DVec2::new(lo.x, mid.y), DVec2::new(mid.x, hi.y)),
            (mid, hi),
        ] {
            self.cover_box(region, delta, a, b, depth + 1, out);
        }
    }

    /// Covers a polygon: a grid of cells whose centre reaches the cell
    /// within `r` ([`cell`]), one sample per cell at its centre moved into
    /// the polygon (its nearest point, the polygon being convex). In a
    /// rectangle the nearest point is the clamp, nearer along each axis to
    /// every point of the cell in the rectangle, so the shaped cell's reach
    /// holds; a triangle's cells are square (`slopes` infinite), whose reach
    /// needs only the plane distance, no farther than the half-diagonal.
    fn fill_polygon(&self, region: &Polygon, delta: f64, slopes: DVec2, out: &mut Vec<Sample>) {
        let (lo, hi) = region.bounds();
        let size = hi - lo;
        let step = 2.0 * cell::half_size(self.options.radius, delta, slopes);
        let nx = (size.x / step.x).ceil().max(1.0);
        let ny = (size.y / step.y).ceil().max(1.0);
        let cells = if nx.max(ny) > f64::from(u32::MAX) {
            f64::INFINITY
        } else {
            nx * ny
        };
        if !self.budget.reserve(cells) {
            return;
        }
        // Within the budget just reserved, so the cell count fits `usize`.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        out.reserve(cells as usize);
        let cell = DVec2::new(size.x / nx, size.y / ny);
        let half_cell = 0.5 * cell;
        let half_diagonal = 0.5 * cell.length();
        let radius = cell::reach(half_cell, delta, slopes).min(self.options.radius);
        // The bounds of a sample at its cell's centre (every cell of a
        // rectangle), rounded once.
        let centre_bounds = Bounds::shared(&self.rounding, radius, half_cell);
        let lift = self.lift();
        // Cell counts are positive integers stored in f64, within the
        // sample budget just reserved, each below 2^32.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let (nx, ny) = (nx as u32, ny as u32);
        let (rectangle, corners) = (region.is_rectangle(), region.vertices());
        for j in 0..ny {
            let y = f64::from(j) + 0.5;
            for i in 0..nx {
                let centre = lo + cell * DVec2::new(f64::from(i) + 0.5, y);
                // A rectangle's nearest point is the clamp to its corners
                // (`Polygon::closest_point`), inline.
                let p = if rectangle {
                    centre.clamp(corners[0], corners[2])
                } else {
                    region.closest_point(centre)
                };
                if p == centre {
                    out.push(lift.sample(p, &centre_bounds));
                } else if p.distance(centre) <= half_diagonal {
                    out.push(self.sample(p, radius, half_cell + (p - centre).abs()));
                }
            }
        }
    }

    /// The sample above plane point `uv` that covers the surface over the
    /// plane box `uv ± cell` within `radius`.
    fn sample(&self, uv: DVec2, radius: f64, cell: DVec2) -> Sample {
        LiftRef {
            heightfield: self.heightfield,
            patch: self.patch,
            rounding: &self.rounding,
        }
        .sample(uv, &Bounds::shared(&self.rounding, radius, cell))
    }

    /// A copy of what lifting a plane point to a sample reads, for a fill's
    /// loop (a local copy, which its stores to the output cannot alias).
    fn lift(&self) -> Lift {
        Lift {
            heightfield: *self.heightfield,
            patch: self.patch,
            rounding: self.rounding,
        }
    }
}
