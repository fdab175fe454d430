//! Adaptive sampling of a CSG surface with a coverage guarantee (paper 2, §3.2, §3.4, §4).
//!
//! Guarantee: with splat radius `r`, every point of the CSG surface inside
//! the bounding sphere has a sample on the same quadric within distance `r`
//! (up to the paper's threshold: unclassified regions smaller than
//! `min_region_fraction · r` are dropped), and every sample lies on the CSG
//! surface.
//!
//! Pipeline, per literal `L_ab` of the normal form (each product's copy of a
//! quadric is its own surface instance, §5):
//! 1. the quadric's local form and up to six heightfields
//!    ([`heightfield`], §3.2);
//! 2. each heightfield's domain box, cut into basic regions ([`basic`],
//!    §4.1: rectangles, triangles, and elliptic, hyperbolic or parabolic
//!    triangles, whose curved sides follow the ownership conics exactly:
//!    [`warp`], [`curved`]);
//! 3. each basic region subdivided and classified with the quadric-relative
//!    CSG distance (eq. 22) and distortion bounds (§3.4), filled with samples
//!    where it lies on the surface (`subdivide`, §4.2).
//!
//! Basic regions run in parallel (rayon); the output order is the order of
//! the basic regions, so it does not depend on the number of threads.
//! [`partial`] keeps the samples per basic region, so that after an edit
//! only the regions it can change are sampled again.
//!
//! ```
//! use chisel_quadric::{BoundingSphere, CsgDag, Dnf, Quadric, SampleOptions, sample};
//! use glam::DVec3;
//!
//! // A unit ball minus a half-space: a hemisphere with a flat face.
//! let mut dag = CsgDag::new();
//! let ball = dag.primitive(Quadric::sphere(DVec3::ZERO, 1.0)?, [0.8; 3]);
//! let cut = dag.primitive(Quadric::half_space(DVec3::Z, 0.0)?, [0.3; 3]);
//! let root = dag.difference(ball, &[cut])?;
//! let dnf = Dnf::from_dag(&dag, root)?;
//! let options = SampleOptions::new(0.05, BoundingSphere::new(DVec3::ZERO, 1.5)?)?;
//! let set = sample(&dnf, &options)?;
//! // Every sample is on the sphere (z ≥ 0) or on the disc z = 0.
//! // Positions are stored in `f32`: on the surface up to its rounding.
//! for s in &set.samples {
//!     let p = s.position.as_dvec3();
//!     assert!(((p.length() - 1.0).abs() < 1e-7 && p.z >= -1e-7)
//!         || (p.z.abs() < 1e-7 && p.length() <= 1.0 + 1e-7));
//! }
//! # Ok::<(), chisel_quadric::Error>(())
//! ```

pub mod basic;
pub mod cell;
mod cost;
pub mod curved;
pub mod heightfield;
mod meeting;
pub mod partial;
pub mod polygon;
pub mod regions;
pub mod separable;
pub mod storage;
mod subdivide;
pub mod warp;

use glam::{DVec2, DVec3, Vec2, Vec3};
use rayon::prelude::*;

use crate::csg::{CsgDistance, Dnf, Side};
use crate::error::{Error, Result, positive};
pub(crate) use cost::Job;
pub use cost::{DEFAULT_MAX_MEMORY, SamplingCost, sampling_cost};
use cost::{cost_of, quadric_regions};
use heightfield::Heightfield;
use regions::RegionKind;
pub use storage::outward_normal;
pub use subdivide::DISTORTION_CAP;
use subdivide::RegionJob;

/// The sphere outside which no surface is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre.
    pub centre: DVec3,
    /// Radius (positive).
    pub radius: f64,
}

impl BoundingSphere {
    /// A sphere with finite `centre` and positive `radius`.
    ///
    /// Errors: [`Error::NonFinite`], [`Error::NonPositive`].
    pub fn new(centre: DVec3, radius: f64) -> Result<Self> {
        if !centre.is_finite() {
            return Err(Error::NonFinite {
                what: "bounding sphere centre",
            });
        }
        positive(radius, "bounding sphere radius")?;
        Ok(Self { centre, radius })
    }

    /// `|p − centre| − radius`: negative inside.
    #[must_use]
    #[inline]
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        (p - self.centre).length() - self.radius
    }
}

/// Parameters of [`sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleOptions {
    /// The splat radius `r`: every surface point gets a sample within `r`.
    pub radius: f64,
    /// Only the surface inside this sphere is sampled.
    pub bounds: BoundingSphere,
    /// Unclassified regions smaller than this fraction of `r` (plane
    /// diameter) are dropped (§4.2; the paper suggests `0.1`).
    pub min_region_fraction: f64,
    /// The most samples [`sample`] may emit ([`DEFAULT_MAX_SAMPLES`] by
    /// default); a grid fill that would pass it is not allocated, and the
    /// call fails with [`Error::TooManySamples`].
    pub max_samples: u64,
    /// The most bytes [`sample`] may allocate for its tables before the
    /// first sample ([`SamplingCost::bytes`], [`DEFAULT_MAX_MEMORY`] by
    /// default); a normal form that needs more fails with
    /// [`Error::SamplingTooLarge`] before anything is allocated.
    pub max_memory: u64,
}

/// The default [`SampleOptions::max_samples`]: 10 million samples, about
/// 1 GB while sampling.
pub const DEFAULT_MAX_SAMPLES: u64 = 10_000_000;

/// The largest ratio of bounding-sphere radius to splat radius that
/// [`sample`] accepts: beyond it, basic regions would need more than the
/// subdivision limit of halvings to come down to the splat radius.
pub const MAX_BOUNDS_RATIO: f64 = (1u64 << 24) as f64;

/// The largest coordinate magnitude of the bounding sphere's box
/// (`|Cᵢ| + R`) that [`sample`] accepts: samples are stored in `f32`
/// ([`Sample`], at most about `3.4·10³⁸`), with room for the rounding.
pub const MAX_COORDINATE: f64 = 1e37;

impl SampleOptions {
    /// Options with splat radius `radius` inside `bounds` and the default
    /// threshold `0.1`.
    ///
    /// Errors: [`Error::NonPositive`] / [`Error::NonFinite`] for the radius.
    pub fn new(radius: f64, bounds: BoundingSphere) -> Result<Self> {
        positive(radius, "splat radius")?;
        Ok(Self {
            radius,
            bounds,
            min_region_fraction: 0.1,
            max_samples: DEFAULT_MAX_SAMPLES,
            max_memory: DEFAULT_MAX_MEMORY,
        })
    }
}

/// One surface sample, in `f32` (28 bytes: the output of a sampling run
/// is written once, so its size is the run's page faults).
///
/// The position is the computed (`f64`) one rounded to the nearest `f32`,
/// in the frame of the normal form (the prop's local frame); its plane
/// point on its patch ([`SampleSet::uv_of`]) and its normal
/// ([`SampleSet::normal_of`]) are derived from it where they are read. The covering bounds [`radius`](Self::radius) and
/// [`cell`](Self::cell) are widened by that rounding and rounded up to
/// `f32` ([`storage`]), so the coverage guarantee holds for the stored
/// sample, and every bound derived from them stays conservative. The
/// literal, product and quadric it lies on are those of its patch
/// ([`SampleSet::patch_of`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The point on the quadric and on the CSG surface (within the
    /// rounding to `f32`).
    pub position: Vec3,
    /// Index into [`SampleSet::patches`]: the heightfield of the literal
    /// it was sampled for.
    pub patch: u32,
    /// The radius it must cover, `≤ r` (reduced where regions are small,
    /// §6.1) plus the rounding of [`position`](Self::position), rounded up.
    pub radius: f32,
    /// Half size of the box around its plane point
    /// ([`SampleSet::uv_of`], plane coordinates of its patch) that holds the plane points of every surface point the
    /// sample is there to cover (its fill cell, or its region), plus the
    /// gap between the computed plane point and the one derived from the
    /// stored position, rounded up: the renderer bounds its splat by the
    /// surface over that box. `+∞` where only [`radius`](Self::radius)
    /// bounds them.
    pub cell: Vec2,
}

/// `x` as the nearest `f32` at least `x` (`+∞` beyond the `f32` range,
/// NaN for NaN): a stored bound that is never smaller than the computed one.
#[must_use]
#[inline]
pub fn f32_at_least(x: f64) -> f32 {
    // The rounding is the point; it is corrected upward below.
    #[allow(clippy::cast_possible_truncation)]
    let y = x as f32;
    if f64::from(y) >= x || x.is_nan() {
        y
    } else if y >= 0.0 {
        // The next `f32` up of a non-negative finite one (`f32::MAX`
        // steps to `+∞`): one more in its bits.
        f32::from_bits(y.to_bits() + 1)
    } else {
        y.next_up()
    }
}

/// A heightfield of one literal, as referenced by [`Sample::patch`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// Product of the literal.
    pub product: u32,
    /// Literal within the product.
    pub literal: u32,
    /// Index into [`Dnf::quadrics`].
    pub quadric: u32,
    /// The heightfield.
    pub heightfield: Heightfield,
}

/// Counters of one sampling run (paper 2, Table 2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SamplingStats {
    /// Basic regions built (§4.1).
    pub basic_regions: u64,
    /// Basic regions by kind ([`RegionKind::index`]): triangles,
    /// rectangles, elliptic, hyperbolic and parabolic triangles.
    pub kinds: [u64; RegionKind::COUNT],
    /// Samples emitted by the basic regions of each kind.
    pub kind_samples: [u64; RegionKind::COUNT],
    /// Regions visited during subdivision.
    pub regions: u64,
    /// Evaluations of the eq.-22 distance.
    pub distance_queries: u64,
    /// Regions filled with samples as a whole.
    pub filled: u64,
    /// Regions proven off the CSG surface.
    pub discarded: u64,
    /// Unclassified regions dropped at the size threshold (§4.2).
    pub dropped_small: u64,
    /// Regions still unclassified at the subdivision depth limit (then
    /// [`sample`] fails: the coverage guarantee would not hold).
    pub depth_limited: u64,
}

/// The samples [`sample`] may still emit, shared by the parallel regions.
/// Grid fills reserve their cell count before allocating: the sum of the
/// reservations is the same in any order, so whether the limit is passed
/// does not depend on the thread count.
pub(crate) struct SampleBudget {
    limit: u64,
    reserved: std::sync::atomic::AtomicU64,
    over: std::sync::atomic::AtomicBool,
}

impl SampleBudget {
    fn new(limit: u64) -> Self {
        Self {
            limit,
            reserved: 0.into(),
            over: false.into(),
        }
    }

    /// Reserves `n` samples (any non-negative number, also huge or
    /// infinite); `false`, and the budget marked over, when that passes
    /// the limit.
    pub(crate) fn reserve(&self, n: f64) -> bool {
        use std::sync::atomic::Ordering::Relaxed;
        // `n` is a cell count: a non-negative integer in `f64`.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let fits = n.is_finite() && n <= self.limit as f64 && {
            let n = n as u64;
            self.reserved.fetch_add(n, Relaxed).saturating_add(n) <= self.limit
        };
        if !fits {
            self.over.store(true, Relaxed);
        }
        fits
    }

    /// Whether the limit was passed.
    pub(crate) fn is_over(&self) -> bool {
        self.over.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn reached(&self) -> u64 {
        self.reserved.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl SamplingStats {
    fn add(&mut self, other: &Self) {
        self.basic_regions += other.basic_regions;
        for (a, b) in self.kinds.iter_mut().zip(other.kinds) {
            *a += b;
        }
        for (a, b) in self.kind_samples.iter_mut().zip(other.kind_samples) {
            *a += b;
        }
        self.regions += other.regions;
        self.distance_queries += other.distance_queries;
        self.filled += other.filled;
        self.discarded += other.discarded;
        self.dropped_small += other.dropped_small;
        self.depth_limited += other.depth_limited;
    }
}

/// The result of [`sample`].
#[derive(Clone, Debug, PartialEq)]
pub struct SampleSet {
    /// The samples, in a deterministic order.
    pub samples: Vec<Sample>,
    /// The heightfields the samples refer to.
    pub patches: Vec<Patch>,
    /// Counters.
    pub stats: SamplingStats,
    /// The options used.
    pub options: SampleOptions,
}

impl SampleSet {
    /// The patch of sample `s` (its literal, product, quadric and
    /// heightfield).
    ///
    /// # Panics
    /// If `s` is not a sample of this set (its patch index out of range).
    #[must_use]
    #[inline]
    pub fn patch_of(&self, s: &Sample) -> &Patch {
        &self.patches[s.patch as usize]
    }

    /// The solid's outward unit normal at sample `s` (zero at a singular
    /// point): [`outward_normal`] of its literal's quadric at its stored
    /// position, in `f64`. `dnf` is the normal form the set was sampled
    /// from.
    ///
    /// # Panics
    /// If `s` is not a sample of this set, or `dnf` not its normal form
    /// (an index out of range).
    #[must_use]
    #[inline]
    pub fn normal_of(&self, dnf: &Dnf, s: &Sample) -> DVec3 {
        let patch = self.patch_of(s);
        let literal = dnf.products()[patch.product as usize][patch.literal as usize];
        let sign = match literal.side {
            Side::Inside => 1.0,
            Side::Outside => -1.0,
        };
        outward_normal(
            &dnf.quadrics()[literal.quadric].quadric,
            sign,
            s.position.as_dvec3(),
        )
    }

    /// The plane point of sample `s` on its patch: the projection of its
    /// stored position ([`Heightfield::project`], in `f64`), the centre of
    /// the box that [`Sample::cell`] bounds.
    ///
    /// # Panics
    /// If `s` is not a sample of this set (its patch index out of range).
    #[must_use]
    #[inline]
    pub fn uv_of(&self, s: &Sample) -> DVec2 {
        self.patch_of(s).heightfield.project(s.position.as_dvec3())
    }
}

/// Samples the surface of `dnf` inside `options.bounds` with radius
/// `options.radius`, in parallel on the current rayon pool.
///
/// An empty normal form gives no samples. Errors: [`Error::NonPositive`] /
/// [`Error::NonFinite`] for invalid options; [`Error::SamplingTooLarge`]
/// (checked first, before anything per literal is allocated: see
/// [`sampling_cost`]), [`Error::TooManySamples`] and
/// [`Error::CoverageNotReached`] for the limits.
pub fn sample(dnf: &Dnf, options: &SampleOptions) -> Result<SampleSet> {
    let run = SamplingRun::new(dnf, options)?;
    // Each fold accumulator takes the samples of a contiguous run of jobs
    // in job order, and the accumulators are collected in order, so their
    // concatenation is the sequential order for any thread count; one
    // pool of one thread runs the jobs in order into one buffer, which
    // becomes the result without a copy (rayon would still split the jobs
    // in two accumulators, and the second would be copied: a third of a
    // single-quadric run's page faults).
    let results: Vec<Vec<Sample>> = if rayon::current_num_threads() == 1 {
        let mut out = Vec::new();
        for job in &run.jobs {
            run.run(job, &|_, _, _| true, &mut out);
        }
        vec![out]
    } else {
        run.jobs
            .par_iter()
            .fold(Vec::new, |mut out: Vec<Sample>, job| {
                run.run(job, &|_, _, _| true, &mut out);
                out
            })
            .collect()
    };
    let total: usize = results.iter().map(Vec::len).sum();
    let runs = run.finish(Vec::new());
    runs.check_limits(options, total)?;
    // The first run's buffer grows in place (a large block is remapped,
    // not copied); only the others are copied.
    let mut results = results.into_iter();
    let mut samples = results.next().unwrap_or_default();
    samples.reserve_exact(total - samples.len());
    for s in results {
        samples.extend(s);
    }
    Ok(SampleSet {
        samples,
        patches: runs.patches,
        stats: runs.stats,
        options: *options,
    })
}

/// Which basic-region jobs [`sample_regions`] runs: called with each job's
/// patch, job and basic region, `true` to run it.
pub(crate) type JobSelection<'a> = dyn Fn(&Patch, &Job, &regions::Region) -> bool + Sync + 'a;

/// The basic-region jobs of one sampling run, in output order (the hook of
/// [`partial`], which keeps samples per region).
pub(crate) struct RegionRuns {
    /// The heightfields of the literals, as [`SampleSet::patches`].
    pub patches: Vec<Patch>,
    /// One job per basic region of every patch.
    pub jobs: Vec<Job>,
    /// Per job: its samples, or `None` where the selection left it out.
    pub samples: Vec<Option<Vec<Sample>>>,
    /// Counters of the jobs that ran.
    pub stats: SamplingStats,
    budget_over: bool,
    budget_reached: u64,
}

impl RegionRuns {
    /// Samples of the jobs that ran.
    pub(crate) fn sample_count(&self) -> usize {
        self.samples.iter().flatten().map(Vec::len).sum()
    }

    /// [`Error::TooManySamples`] when the budget was passed or `total`
    /// exceeds it, [`Error::CoverageNotReached`] when a region stayed
    /// unclassified.
    pub(crate) fn check_limits(&self, options: &SampleOptions, total: usize) -> Result<()> {
        if self.budget_over || total as u64 > options.max_samples {
            return Err(Error::TooManySamples {
                limit: options.max_samples,
                reached: self.budget_reached.max(total as u64),
            });
        }
        let depth_limited = self.stats.depth_limited;
        if depth_limited > 0 {
            return Err(Error::CoverageNotReached {
                reason: format!(
                    "{depth_limited} region(s) were still unclassified after the subdivision \
                     limit; give bounds closer around the solid or a larger radius"
                ),
            });
        }
        Ok(())
    }
}

/// The jobs of [`sample`] for `dnf`, running those `select` picks (in
/// parallel), each region's samples apart; the limits are left to the
/// caller ([`RegionRuns::check_limits`]).
pub(crate) fn sample_regions(
    dnf: &Dnf,
    options: &SampleOptions,
    select: &JobSelection<'_>,
) -> Result<RegionRuns> {
    let run = SamplingRun::new(dnf, options)?;
    let samples: Vec<Option<Vec<Sample>>> = run
        .jobs
        .par_iter()
        .map(|job| {
            let mut out = Vec::new();
            run.run(job, select, &mut out).then_some(out)
        })
        .collect();
    Ok(run.finish(samples))
}

/// One sampling run of a normal form: its checked options, region tables,
/// patches and jobs, shared by the jobs while they run.
struct SamplingRun<'a> {
    dnf: &'a Dnf,
    options: &'a SampleOptions,
    sphere: BoundingSphere,
    tables: Vec<cost::QuadricRegions>,
    distance: CsgDistance<'a>,
    budget: SampleBudget,
    patches: Vec<Patch>,
    jobs: Vec<Job>,
    /// Counters are sums, the same in any order: one shared total.
    totals: std::sync::Mutex<SamplingStats>,
}

impl<'a> SamplingRun<'a> {
    /// Checks the options and the memory the run needs, and lays out its
    /// jobs: one per basic region of every literal's heightfields.
    fn new(dnf: &'a Dnf, options: &'a SampleOptions) -> Result<Self> {
        positive(options.radius, "splat radius")?;
        BoundingSphere::new(options.bounds.centre, options.bounds.radius)?;
        if !options.min_region_fraction.is_finite() || options.min_region_fraction < 0.0 {
            return Err(Error::NonPositive {
                what: "minimum region fraction",
                value: options.min_region_fraction,
            });
        }
        let ratio = options.bounds.radius / options.radius;
        if ratio > MAX_BOUNDS_RATIO {
            return Err(Error::CoverageNotReached {
                reason: format!(
                    "the bounding sphere's radius {:e} is {ratio:.3e} splat radii ({:e}), more than \
                     2^24; give bounds closer around the solid or a larger radius",
                    options.bounds.radius, options.radius
                ),
            });
        }
        let reach = (options.bounds.centre.abs() + options.bounds.radius).max_element();
        if reach > MAX_COORDINATE {
            return Err(Error::CoverageNotReached {
                reason: format!(
                    "the bounding sphere reaches {reach:e}, beyond {MAX_COORDINATE:e}: samples \
                     are stored in f32; give bounds closer around the solid, in a frame nearer \
                     the origin"
                ),
            });
        }
        let sphere = options.bounds;
        let tables = quadric_regions(dnf, sphere);
        let cost = cost_of(dnf, &tables);
        if cost.bytes > options.max_memory {
            return Err(Error::SamplingTooLarge {
                products: dnf.products().len() as u64,
                literals: cost.literals,
                regions: cost.regions,
                needed: cost.bytes,
                limit: options.max_memory,
            });
        }
        let budget = SampleBudget::new(options.max_samples);
        let distance = CsgDistance::new(dnf);
        let capacity = |n: u64| usize::try_from(n).unwrap_or(0);
        let mut patches = Vec::with_capacity(capacity(cost.patches));
        let mut jobs: Vec<Job> = Vec::with_capacity(capacity(cost.regions));
        for (a, product) in dnf.products().iter().enumerate() {
            for (b, literal) in product.iter().enumerate() {
                for (k, (hf, regions)) in tables[literal.quadric].iter().enumerate() {
                    let patch = index_u32(patches.len());
                    patches.push(Patch {
                        product: index_u32(a),
                        literal: index_u32(b),
                        quadric: index_u32(literal.quadric),
                        heightfield: *hf,
                    });
                    jobs.extend((0..regions.len()).map(|r| Job {
                        patch,
                        heightfield: index_u32(k),
                        region: index_u32(r),
                    }));
                }
            }
        }
        Ok(Self {
            dnf,
            options,
            sphere,
            tables,
            distance,
            budget,
            patches,
            jobs,
            totals: std::sync::Mutex::new(SamplingStats::default()),
        })
    }

    /// Runs `job` when `select` picks it, appending its samples to `out`;
    /// tells whether it ran.
    fn run(&self, job: &Job, select: &JobSelection<'_>, out: &mut Vec<Sample>) -> bool {
        let patch = &self.patches[job.patch as usize];
        let literal = self.dnf.products()[patch.product as usize][patch.literal as usize];
        let (region, kind) =
            &self.tables[literal.quadric][job.heightfield as usize].1[job.region as usize];
        if !select(patch, job, region) {
            return false;
        }
        let region_job = RegionJob {
            distance: &self.distance,
            patch: job.patch,
            heightfield: &patch.heightfield,
            sphere: self.sphere,
            options: self.options,
            budget: &self.budget,
            hint: std::cell::Cell::new(usize::MAX),
            others: self
                .distance
                .other_terms(patch.product as usize, patch.literal as usize),
            spare: std::cell::RefCell::new(Vec::new()),
            rounding: storage::Rounding::new(&self.sphere, &patch.heightfield),
        };
        let mut stats = SamplingStats {
            basic_regions: 1,
            ..SamplingStats::default()
        };
        stats.kinds[kind.index()] = 1;
        let before = out.len();
        region_job.run(region, out, &mut stats);
        stats.kind_samples[kind.index()] = (out.len() - before) as u64;
        self.totals
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .add(&stats);
        true
    }

    /// The run's patches, jobs and counters with `samples` (per job, or
    /// none for [`sample`], which keeps them in runs).
    fn finish(self, samples: Vec<Option<Vec<Sample>>>) -> RegionRuns {
        RegionRuns {
            patches: self.patches,
            jobs: self.jobs,
            samples,
            stats: self
                .totals
                .into_inner()
                .unwrap_or_else(std::sync::PoisonError::into_inner),
            budget_over: self.budget.is_over(),
            budget_reached: self.budget.reached(),
        }
    }
}

/// Indices into normal forms fit in `u32` (the product limit is far lower).
fn index_u32(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::f32_at_least;

    /// The least `f32` at or above `x`: never below it, and its
    /// predecessor is.
    #[test]
    fn f32_at_least_is_the_nearest_f32_not_below() {
        for x in [
            0.1,
            1.0 / 3.0,
            2.5,
            1e-40,
            1e-300,
            123_456_789.123,
            f64::from(f32::MAX),
            -0.1,
            -1e-300,
        ] {
            let y = f32_at_least(x);
            assert!(f64::from(y) >= x, "{x}: {y}");
            assert!(f64::from(y.next_down()) < x, "{x}: {y}");
        }
        assert_eq!(f32_at_least(0.0), 0.0);
        assert_eq!(f32_at_least(0.25), 0.25);
        assert_eq!(f32_at_least(f64::from(f32::MAX) * 1.0001), f32::INFINITY);
        assert_eq!(f32_at_least(f64::INFINITY), f32::INFINITY);
        assert!(f32_at_least(f64::NAN).is_nan());
    }
}
