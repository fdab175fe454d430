//! Partial re-sampling after an edit (paper 2, §8: "a partial update …
//! computing regions that might have been invalidated and only recompute
//! the affected samples").
//!
//! Notation: a job is one basic region `R` of heightfield `k` of literal
//! `L_ab` ([`sample`](crate::sample) runs one per region); `B(c, ρ)` the
//! ball around the surface over `R` (`Heightfield::patch_ball`); `Q → Q'`
//! a quadric of the normal form before and after the edit; `d` the
//! conservative distance of eq. 12, `|d(Q, x)| ≤` the true distance from
//! `x` to the surface `Q = 0`, with the sign of `Q(x)`.
//!
//! Invalidation rule. An edit that keeps the normal form's products and
//! changes the coefficients of some quadrics re-runs a job when its literal
//! is on a changed quadric, or when the surface over `R` cannot be shown
//! clear of the edit: the ball `B` of `R`'s bounding box is clear, or each
//! of the box's four quarters is (recursively, a few times). A ball is
//! clear when for every changed `Q → Q'`
//!
//! `|d(Q, c)| > ρ  and  |d(Q', c)| > ρ  and  sign Q(c) = sign Q'(c)`,
//!
//! (neither surface meets `B`, and every point of `B` is on the same side
//! of both), or every product holding `Q` has a literal `L` on an unchanged
//! quadric with `d(L, c) > ρ` (`d(L, ·) = ±d(Q_L, ·)` by the literal's side,
//! positive where it is false): the product is false on all of `B` before
//! and after, whatever `Q`.
//!
//! In a clear ball the solid, and with it the CSG surface, is the same
//! before and after. A kept job's old samples lie on the surface over `R`,
//! inside the clear balls, and cover it (§4.2 covers each basic region by
//! its own samples), so they stay valid and complete. Jobs of unchanged
//! literals have the same heightfields and basic regions before and after
//! (they depend only on the quadric and the bounding sphere), so jobs are
//! matched by `(a, b, k, region index)`.
//!
//! Carves ([`Scene::carved`](crate::Scene::carved)). An edit that keeps
//! every quadric and appends literals on new quadrics to products (a
//! carve adds "outside `T`" to every product: `S' = ⋃ₐ (Pₐ ∩ Eₐ)`, `Eₐ`
//! the literals appended to product `a`) keeps the jobs of the old
//! literals, with the same heightfields, basic regions and keys, and adds
//! the new literals' jobs, which all run. An old job is re-run unless the
//! surface over `R` is shown clear of the edit, with the same balls and
//! quarterings as above; a ball is clear when every appended literal `L`
//! holds on all of it:
//!
//! `d(L, c) < −ρ`
//!
//! (`d(L, ·)` positive where `L` is false, as above: for "outside `T`",
//! every point of `B` is outside `T`). Then every `Eₐ` is true on `B`, so
//! `S' ∩ B = S ∩ B`: the solid, and with it the CSG surface, is the same in
//! the ball, and the old job's samples stay valid and complete by the
//! argument above. A small dent re-runs the old jobs whose surface comes
//! near the tool, and the tool's own jobs, which find the CSG surface only
//! where the tool cuts the solid.
//!
//! An appended literal's job (`L` of product `a`, region `R`) samples the
//! CSG surface on `L`'s quadric where the rest of product `a` holds. When
//! some old literal `K` of product `a` is false on every ball of `R` (the
//! same balls and quarterings, `d(K, c) > ρ`), no surface point over `R`
//! is in product `a`: a full sampling finds nothing there, and the job is
//! left empty without running (counted in `regions_empty`). A dent then
//! runs only the tool's jobs of products that reach it.
//!
//! Edits that change the products otherwise, the options, or make a
//! changed or added quadric coincide with another one (a shared surface,
//! eq. 22's notes) fall back to a full sampling.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use crate::csg::{Dnf, Literal, Side};
use crate::distance::QuadricDistance;
use crate::error::Result;
use crate::quadric::Quadric;
use crate::sampling::heightfield::Heightfield;
use crate::sampling::regions::Region;
use crate::sampling::{
    Job, Patch, Sample, SampleOptions, SampleSet, SamplingStats, sample_regions,
};

/// Relative padding of a job's ball radius `ρ` against rounding in
/// `Heightfield::patch_ball`
/// and in the distance bound.
const BALL_PADDING: f64 = 1e-6;

/// How often [`is_clear`] quarters a basic region's box at most (up to
/// `4⁴ = 256` balls per region, each a few distance bounds: far less than
/// sampling the region).
const MAX_QUARTERINGS: u32 = 4;

/// A sampling kept per basic region, so that a later edit re-samples only
/// the regions the edit can change ([`RegionSamples::resample`]).
///
/// ```
/// use chisel_quadric::sampling::partial::RegionSamples;
/// use chisel_quadric::{BoundingSphere, SampleOptions, Scene, sample};
/// use glam::{DVec2, DVec3};
///
/// let scene = |x: f64| {
///     Scene::from_ron(&format!(
///         r#"Scene(primitives: [
///             (name: "a", shape: Sphere(center: (0, 0, 0), radius: 10)),
///             (name: "b", shape: Sphere(center: ({x}, 0, 0), radius: 2)),
///         ], root: Union([Ref("a"), Ref("b")]))"#
///     ))
/// };
/// let options = SampleOptions::new(1.0, BoundingSphere::new(DVec3::ZERO, 30.0)?)?;
/// let before = RegionSamples::sample(&scene(20.0)?.dnf()?, &options)?;
/// // Move the small sphere: the big one's regions far from both places are kept.
/// let after_dnf = scene(22.0)?.dnf()?;
/// let (after, report) = before.resample(&after_dnf)?;
/// assert!(!report.full && report.regions_kept > 0);
/// assert_eq!(after.to_sample_set().samples.len(), sample(&after_dnf, &options)?.samples.len());
/// # Ok::<(), chisel_quadric::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct RegionSamples {
    options: SampleOptions,
    /// The normal form's quadrics when sampled.
    quadrics: Vec<Quadric>,
    /// The normal form's products when sampled.
    products: Vec<Vec<Literal>>,
    patches: Vec<Patch>,
    jobs: Vec<Job>,
    /// Per job, its samples.
    samples: Vec<Vec<Sample>>,
    stats: SamplingStats,
}

/// What [`RegionSamples::resample`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ResampleReport {
    /// The quadrics of the normal form whose coefficients changed.
    pub changed_quadrics: Vec<usize>,
    /// The literals appended to products (a carve, see the module notes).
    pub appended_literals: Vec<Literal>,
    /// Basic regions sampled again.
    pub regions_resampled: usize,
    /// Basic regions whose samples were kept.
    pub regions_kept: usize,
    /// Basic regions of appended literals proven empty without sampling
    /// (their product is false on all of the surface over them).
    pub regions_empty: usize,
    /// Samples kept from before.
    pub samples_kept: usize,
    /// `true` when the edit needed a full sampling (see the module notes).
    pub full: bool,
}

/// A job's identity across samplings: product `a`, literal `b`, heightfield
/// `k` and basic region index.
type JobKey = (u32, u32, u32, u32);

fn job_key(patches: &[Patch], job: &Job) -> JobKey {
    let patch = &patches[job.patch as usize];
    (patch.product, patch.literal, job.heightfield, job.region)
}

/// What an edit changed, for the invalidation rule.
enum Change {
    /// A quadric's coefficients.
    Coefficients(CoefficientChange),
    /// A literal appended to products (a carve), as a signed bound
    /// positive where the literal is false.
    Appended(QuadricDistance),
}

impl Change {
    /// Whether the solid may differ somewhere in the ball `(centre,
    /// radius)` because of this change (the module notes).
    fn may_differ_in(&self, centre: DVec3, radius: f64) -> bool {
        match self {
            Self::Coefficients(change) => change.may_differ_in(centre, radius),
            Self::Appended(literal) => {
                let reach = radius * (1.0 + BALL_PADDING);
                // NaN fails the comparison: such a ball is re-sampled.
                let holds_on_ball = literal.distance(centre) < -reach;
                !holds_on_ball
            }
        }
    }
}

/// A changed quadric's distance bounds, before and after, and the
/// literals that can switch off the products it takes part in.
struct CoefficientChange {
    before: QuadricDistance,
    after: QuadricDistance,
    /// Per product holding the quadric: its literals on unchanged
    /// quadrics, as signed bounds (positive where the literal is false).
    guards: Vec<Vec<QuadricDistance>>,
}

/// The signed bound of `literal` of `dnf`, positive where it is false.
fn literal_distance(dnf: &Dnf, literal: Literal) -> QuadricDistance {
    let d = QuadricDistance::new(&dnf.quadrics()[literal.quadric].quadric);
    match literal.side {
        Side::Inside => d,
        Side::Outside => d.complement(),
    }
}

impl CoefficientChange {
    /// Whether the literals of this quadric may differ somewhere in the
    /// ball `(centre, radius)` (the invalidation rule).
    fn may_differ_in(&self, centre: DVec3, radius: f64) -> bool {
        let reach = radius * (1.0 + BALL_PADDING);
        let d0 = self.before.distance(centre);
        let d1 = self.after.distance(centre);
        // NaN fails every comparison: such a ball is re-sampled.
        let clear = d0.abs() > reach && d1.abs() > reach && (d0 > 0.0) == (d1 > 0.0);
        let switched_off = || {
            self.guards
                .iter()
                .all(|product| product.iter().any(|l| l.distance(centre) > reach))
        };
        !(clear || switched_off())
    }
}

/// Whether `clear` holds for the ball around the surface over the plane
/// box `[lo, hi]` of `heightfield`, or else for each of its four quarters'
/// (recursively, down to [`MAX_QUARTERINGS`]). The surface over a box lies
/// in the union of its quarters' balls, which hug a curved or tilted patch
/// far closer than the one ball around a large basic region. With the
/// invalidation rule as `clear`: no change can alter the solid near the
/// surface over the box.
fn is_clear(
    heightfield: &Heightfield,
    clear: &dyn Fn(DVec3, f64) -> bool,
    lo: DVec2,
    hi: DVec2,
    depth: u32,
) -> bool {
    // No ball: no surface point over the box at all.
    let Some((centre, radius)) = heightfield.patch_ball(lo, hi) else {
        return true;
    };
    if clear(centre, radius) {
        return true;
    }
    if depth >= MAX_QUARTERINGS {
        return false;
    }
    let mid = 0.5 * (lo + hi);
    [
        (lo, mid),
        (DVec2::new(mid.x, lo.y), DVec2::new(hi.x, mid.y)),
        (DVec2::new(lo.x, mid.y), DVec2::new(mid.x, hi.y)),
        (mid, hi),
    ]
    .into_iter()
    .all(|(a, b)| is_clear(heightfield, clear, a, b, depth + 1))
}

impl RegionSamples {
    /// Samples `dnf` in full, as [`sample`](crate::sample) does, keeping
    /// the samples per basic region.
    ///
    /// Errors: those of [`sample`](crate::sample).
    pub fn sample(dnf: &Dnf, options: &SampleOptions) -> Result<Self> {
        let runs = sample_regions(dnf, options, &|_, _, _| true)?;
        runs.check_limits(options, runs.sample_count())?;
        Ok(Self {
            options: *options,
            quadrics: dnf.quadrics().iter().map(|q| q.quadric).collect(),
            products: dnf.products().to_vec(),
            patches: runs.patches,
            jobs: runs.jobs,
            samples: runs
                .samples
                .into_iter()
                .map(Option::unwrap_or_default)
                .collect(),
            stats: runs.stats,
        })
    }

    /// The samples of the edited normal form `dnf`, with the same options:
    /// only the basic regions the edit may change are sampled again (see
    /// the module notes); the others keep their samples. The result is a
    /// valid sampling of `dnf` with the coverage guarantee, and its
    /// re-sampled regions are exactly those of [`RegionSamples::sample`]
    /// on `dnf`.
    ///
    /// Errors: those of [`sample`](crate::sample); `self` is unchanged.
    pub fn resample(&self, dnf: &Dnf) -> Result<(Self, ResampleReport)> {
        let (changed, appended) = if let Some(appended) = self.appended_literals(dnf) {
            (Vec::new(), appended)
        } else if let Some(changed) = self.changed_quadrics(dnf) {
            (changed, Vec::new())
        } else {
            let full = Self::sample(dnf, &self.options)?;
            let report = ResampleReport {
                changed_quadrics: (0..dnf.quadrics().len()).collect(),
                regions_resampled: full.jobs.len(),
                full: true,
                ..ResampleReport::default()
            };
            return Ok((full, report));
        };
        let mut changes: Vec<Change> = changed
            .iter()
            .map(|&q| {
                Change::Coefficients(CoefficientChange {
                    before: QuadricDistance::new(&self.quadrics[q]),
                    after: QuadricDistance::new(&dnf.quadrics()[q].quadric),
                    guards: dnf
                        .products()
                        .iter()
                        .filter(|product| product.iter().any(|l| l.quadric == q))
                        .map(|product| {
                            product
                                .iter()
                                .filter(|l| !changed.contains(&l.quadric))
                                .map(|&l| literal_distance(dnf, l))
                                .collect()
                        })
                        .collect(),
                })
            })
            .collect();
        changes.extend(
            appended
                .iter()
                .map(|&l| Change::Appended(literal_distance(dnf, l))),
        );
        let old: HashMap<JobKey, usize> = self
            .jobs
            .iter()
            .enumerate()
            .map(|(i, job)| (job_key(&self.patches, job), i))
            .collect();
        let is_changed = |q: u32| changed.contains(&(q as usize));
        let unchanged_in =
            |centre: DVec3, radius: f64| !changes.iter().any(|c| c.may_differ_in(centre, radius));
        let first_new = self.quadrics.len();
        let guards = self.product_guards(dnf, &appended);
        let select = |patch: &Patch, job: &Job, region: &Region| -> bool {
            if is_changed(patch.quadric) {
                return true;
            }
            let key = (patch.product, patch.literal, job.heightfield, job.region);
            let (lo, hi) = region.bounds();
            if !old.contains_key(&key) {
                // An appended literal's job is empty where its product is
                // false on the surface over the region (module notes).
                let Some(guards) = guards.get(patch.product as usize) else {
                    return true;
                };
                let product_off = |centre: DVec3, radius: f64| {
                    let reach = radius * (1.0 + BALL_PADDING);
                    guards.iter().any(|l| l.distance(centre) > reach)
                };
                return (patch.quadric as usize) < first_new
                    || !is_clear(&patch.heightfield, &product_off, lo, hi, 0);
            }
            !is_clear(&patch.heightfield, &unchanged_in, lo, hi, 0)
        };
        let mut runs = sample_regions(dnf, &self.options, &select)?;
        let slots = std::mem::take(&mut runs.samples);
        let mut report = ResampleReport {
            changed_quadrics: changed,
            appended_literals: appended,
            ..ResampleReport::default()
        };
        let mut samples = Vec::with_capacity(runs.jobs.len());
        for (job, slot) in runs.jobs.iter().zip(slots) {
            if let Some(fresh) = slot {
                report.regions_resampled += 1;
                samples.push(fresh);
                continue;
            }
            let key = job_key(&runs.patches, job);
            let Some(&i) = old.get(&key) else {
                report.regions_empty += 1;
                samples.push(Vec::new());
                continue;
            };
            let kept = {
                // The same literal and heightfield; only its patch index may
                // have moved (a changed quadric's literals can have another
                // number of heightfields).
                self.samples[i]
                    .iter()
                    .map(|s| Sample {
                        patch: job.patch,
                        ..*s
                    })
                    .collect::<Vec<_>>()
            };
            report.regions_kept += 1;
            report.samples_kept += kept.len();
            samples.push(kept);
        }
        let total = samples.iter().map(Vec::len).sum();
        runs.check_limits(&self.options, total)?;
        Ok((
            Self {
                options: self.options,
                quadrics: dnf.quadrics().iter().map(|q| q.quadric).collect(),
                products: dnf.products().to_vec(),
                patches: runs.patches,
                jobs: runs.jobs,
                samples,
                stats: runs.stats,
            },
            report,
        ))
    }

    /// Per product, the bounds of its literals on the sampled normal
    /// form's quadrics, positive where the literal is false; empty when
    /// nothing was `appended`.
    fn product_guards(&self, dnf: &Dnf, appended: &[Literal]) -> Vec<Vec<QuadricDistance>> {
        if appended.is_empty() {
            return Vec::new();
        }
        let first_new = self.quadrics.len();
        let bounds: Vec<QuadricDistance> = self.quadrics.iter().map(QuadricDistance::new).collect();
        dnf.products()
            .iter()
            .map(|product| {
                product
                    .iter()
                    .filter(|l| l.quadric < first_new)
                    .map(|l| match l.side {
                        Side::Inside => bounds[l.quadric],
                        Side::Outside => bounds[l.quadric].complement(),
                    })
                    .collect()
            })
            .collect()
    }

    /// The distinct literals appended to products when `dnf` is a carve of
    /// the sampled normal form (module notes): the same quadrics followed
    /// by new ones, each product the old one followed by literals on new
    /// quadrics only, at least one. `None` otherwise, or when a new quadric
    /// coincides with another one or its negation.
    fn appended_literals(&self, dnf: &Dnf) -> Option<Vec<Literal>> {
        let old = self.quadrics.len();
        let new = dnf.quadrics();
        if new.len() <= old || dnf.products().len() != self.products.len() {
            return None;
        }
        let bits = |q: &Quadric| q.coefficients().map(|c| (c + 0.0).to_bits());
        let negated = |q: &Quadric| q.coefficients().map(|c| (0.0 - c).to_bits());
        if self
            .quadrics
            .iter()
            .zip(new)
            .any(|(a, b)| bits(a) != bits(&b.quadric))
        {
            return None;
        }
        let mut appended: Vec<Literal> = Vec::new();
        for (before, after) in self.products.iter().zip(dnf.products()) {
            let tail = after.strip_prefix(before.as_slice())?;
            if tail.iter().any(|l| l.quadric < old) {
                return None;
            }
            appended.extend_from_slice(tail);
        }
        appended.sort_unstable();
        appended.dedup();
        if appended.is_empty() {
            return None;
        }
        for (i, q) in new.iter().enumerate().skip(old) {
            let coincides = new.iter().enumerate().any(|(j, other)| {
                j != i
                    && (bits(&other.quadric) == bits(&q.quadric)
                        || bits(&other.quadric) == negated(&q.quadric))
            });
            if coincides {
                return None;
            }
        }
        Some(appended)
    }

    /// The quadrics whose coefficients differ in `dnf`, or `None` when the
    /// edit needs a full sampling: other products, another quadric count,
    /// or a changed quadric equal to another one or to its negation.
    fn changed_quadrics(&self, dnf: &Dnf) -> Option<Vec<usize>> {
        if dnf.products() != self.products.as_slice() || dnf.quadrics().len() != self.quadrics.len()
        {
            return None;
        }
        let bits = |q: &Quadric| q.coefficients().map(|c| (c + 0.0).to_bits());
        let negated = |q: &Quadric| q.coefficients().map(|c| (0.0 - c).to_bits());
        let changed: Vec<usize> = self
            .quadrics
            .iter()
            .zip(dnf.quadrics())
            .enumerate()
            .filter(|(_, (a, b))| bits(a) != bits(&b.quadric))
            .map(|(i, _)| i)
            .collect();
        for &c in &changed {
            for q in [&self.quadrics[c], &dnf.quadrics()[c].quadric] {
                let coincides =
                    |other: &Quadric| bits(other) == bits(q) || bits(other) == negated(q);
                let others_before = self.quadrics.iter().enumerate();
                let others_after = dnf.quadrics().iter().map(|d| &d.quadric).enumerate();
                if others_before
                    .chain(others_after)
                    .any(|(i, other)| i != c && coincides(other))
                {
                    return None;
                }
            }
        }
        Some(changed)
    }

    /// The samples as one [`SampleSet`], in the order of
    /// [`sample`](crate::sample) (after [`RegionSamples::sample`], equal to
    /// its result). The counters are those of the regions the last run
    /// sampled.
    #[must_use]
    pub fn to_sample_set(&self) -> SampleSet {
        SampleSet {
            samples: self.samples.iter().flatten().copied().collect(),
            patches: self.patches.clone(),
            stats: self.stats,
            options: self.options,
        }
    }

    /// The options sampled with.
    #[must_use]
    pub fn options(&self) -> &SampleOptions {
        &self.options
    }

    /// Number of basic regions (jobs).
    #[must_use]
    pub fn region_count(&self) -> usize {
        self.jobs.len()
    }

    /// Each basic region's samples, as `((product, literal, heightfield,
    /// region index), samples)`, in output order.
    pub fn regions(&self) -> impl Iterator<Item = ((u32, u32, u32, u32), &[Sample])> {
        self.jobs
            .iter()
            .zip(&self.samples)
            .map(|(job, s)| (job_key(&self.patches, job), s.as_slice()))
    }
}
