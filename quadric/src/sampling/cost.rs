//! The memory [`sample`](crate::sample) needs before its first sample,
//! counted up front so that a normal form too large to sample is refused
//! instead of exhausting memory.
//!
//! Sampling runs one job per basic region of every heightfield of every
//! literal instance `L_ab` (§5: each product's copy of a quadric is its own
//! surface). The heightfields and basic regions depend only on the quadric
//! and the bounding sphere, so they are built once per distinct quadric
//! ([`QuadricRegions`]); the counts follow from them without allocating
//! anything per literal. A scene of `n` unions of two primitives under an
//! intersection has `2ⁿ` products of `n` literals each, and so `n · 2ⁿ`
//! literal instances: the tables grow with the normal form, not with the
//! scene file.

use glam::DVec2;

use crate::csg::{Dnf, OtherTerms};
use crate::sampling::basic::basic_regions;
use crate::sampling::heightfield::{Heightfield, LocalForm};
use crate::sampling::regions::{Region, RegionKind};
use crate::sampling::{BoundingSphere, Patch, Sample};

/// The default [`SampleOptions::max_memory`](crate::SampleOptions::max_memory):
/// 1 GiB for the tables counted by [`sampling_cost`].
pub const DEFAULT_MAX_MEMORY: u64 = 1 << 30;

/// Culled copies of the eq.-22 table a thread holds at once, counted with
/// the full table (the subdivision keeps the copies along its recursion;
/// culling shrinks each one, so two full tables is the usual peak).
/// Each worker thread holds its own; they are small beside the regions,
/// and counting one thread's keeps the verdict the same on any number of
/// threads, as the results are.
const TABLE_COPIES: u64 = 2;

/// What [`sample`](crate::sample) allocates for a normal form before its
/// first sample, from [`sampling_cost`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SamplingCost {
    /// Literal instances sampled: the literals of all products together.
    pub literals: u64,
    /// Their heightfields ([`SampleSet::patches`](crate::SampleSet::patches)).
    pub patches: u64,
    /// Their basic regions, one parallel job each.
    pub regions: u64,
    /// Estimated bytes: the patches, one job and one result slot per
    /// region, and the eq.-22 distance tables of one worker thread (the
    /// same on any number of threads).
    /// Samples are not counted; [`SampleOptions::max_samples`](crate::SampleOptions::max_samples)
    /// limits them.
    pub bytes: u64,
}

/// The heightfields of one quadric and the basic regions of each, inside
/// the bounding sphere's box.
pub(crate) type QuadricRegions = Vec<(Heightfield, Vec<(Region, RegionKind)>)>;

/// One job of the sampler: basic region `region` of heightfield
/// `heightfield` of the quadric of patch `patch`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Job {
    pub patch: u32,
    pub heightfield: u32,
    pub region: u32,
}

/// The heightfields and basic regions of every quadric that a literal of
/// `dnf` uses (none for the others).
pub(crate) fn quadric_regions(dnf: &Dnf, sphere: BoundingSphere) -> Vec<QuadricRegions> {
    let mut used = vec![false; dnf.quadrics().len()];
    for literal in dnf.products().iter().flatten() {
        used[literal.quadric] = true;
    }
    dnf.quadrics()
        .iter()
        .zip(used)
        .map(|(q, used)| {
            if !used {
                return Vec::new();
            }
            LocalForm::new(&q.quadric)
                .heightfields()
                .into_iter()
                .map(|hf| {
                    let c = hf.project(sphere.centre);
                    let lo = c - DVec2::splat(sphere.radius);
                    let hi = c + DVec2::splat(sphere.radius);
                    (hf, basic_regions(&hf, lo, hi))
                })
                .collect()
        })
        .collect()
}

/// The counts and bytes of [`SamplingCost`] for `dnf` with the regions of
/// [`quadric_regions`].
pub(crate) fn cost_of(dnf: &Dnf, regions: &[QuadricRegions]) -> SamplingCost {
    let mut cost = SamplingCost::default();
    for literal in dnf.products().iter().flatten() {
        let quadric = &regions[literal.quadric];
        cost.literals += 1;
        cost.patches += quadric.len() as u64;
        cost.regions += quadric.iter().map(|(_, r)| r.len() as u64).sum::<u64>();
    }
    let size = |bytes: usize| bytes as u64;
    let per_region = size(std::mem::size_of::<Job>()) + size(std::mem::size_of::<Vec<Sample>>());
    let table = OtherTerms::bytes_for(dnf);
    cost.bytes = cost
        .patches
        .saturating_mul(size(std::mem::size_of::<Patch>()))
        .saturating_add(cost.regions.saturating_mul(per_region))
        .saturating_add(table.saturating_mul(TABLE_COPIES));
    cost
}

/// What [`sample`](crate::sample) would allocate for `dnf` inside `sphere`
/// before its first sample; `sample` refuses
/// with [`Error::SamplingTooLarge`](crate::Error::SamplingTooLarge) when
/// [`SamplingCost::bytes`] passes [`SampleOptions::max_memory`](crate::SampleOptions::max_memory).
///
/// Builds the heightfields and basic regions of each distinct quadric
/// once; nothing per literal instance.
#[must_use]
pub fn sampling_cost(dnf: &Dnf, sphere: BoundingSphere) -> SamplingCost {
    cost_of(dnf, &quadric_regions(dnf, sphere))
}
