//! One-dimensional CSG along a ray (paper 2, §7.2; Roth 1982).
//!
//! Notation: a *set* is a sorted list of disjoint open intervals of the ray
//! parameter `t`; each end remembers the literal that bounds it (quadric
//! index and the sign that turns `∇Q` into the solid's outward normal). A
//! literal `Q < 0` gives the line's inside spans; `Q ≥ 0` their complement;
//! a product intersects its literals' sets; the solid is the union of the
//! products' sets.

use crate::csg::{Dnf, Literal, Side};
use crate::ray::Ray;

/// The literal bounding an interval end: quadric index and outward sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// The ray parameter.
    pub t: f64,
    /// Index into [`Dnf::quadrics`] (`u32::MAX` for an infinite end).
    pub quadric: u32,
    /// `+1` when the solid's outward normal is `∇Q`, `−1` when it is `−∇Q`.
    pub sign: f64,
}

/// An open interval `(entry, exit)` of the ray parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub entry: Bound,
    /// Upper end.
    pub exit: Bound,
}

const FREE: u32 = u32::MAX;

fn bound(t: f64, quadric: u32, sign: f64) -> Bound {
    Bound { t, quadric, sign }
}

/// The set of `t` where `literal` holds along `ray`.
fn literal_set(dnf: &Dnf, literal: Literal, ray: &Ray) -> Vec<Interval> {
    let q = u32::try_from(literal.quadric).unwrap_or(FREE);
    let hits = dnf.quadrics()[literal.quadric].quadric.intersect_line(ray);
    let spans = hits.spans();
    match literal.side {
        Side::Inside => spans
            .iter()
            .filter(|s| s.entry < s.exit)
            .map(|s| Interval {
                entry: bound(s.entry, q, 1.0),
                exit: bound(s.exit, q, 1.0),
            })
            .collect(),
        Side::Outside => {
            let mut out = Vec::with_capacity(3);
            let mut start = bound(f64::NEG_INFINITY, FREE, -1.0);
            for s in spans.iter().filter(|s| s.entry < s.exit) {
                if start.t < s.entry {
                    out.push(Interval {
                        entry: start,
                        exit: bound(s.entry, q, -1.0),
                    });
                }
                start = bound(s.exit, q, -1.0);
            }
            if start.t < f64::INFINITY {
                out.push(Interval {
                    entry: start,
                    exit: bound(f64::INFINITY, FREE, -1.0),
                });
            }
            out
        }
    }
}

/// The intersection of two sets.
fn intersect(a: &[Interval], b: &[Interval]) -> Vec<Interval> {
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let entry = if a[i].entry.t >= b[j].entry.t {
            a[i].entry
        } else {
            b[j].entry
        };
        let exit = if a[i].exit.t <= b[j].exit.t {
            a[i].exit
        } else {
            b[j].exit
        };
        if entry.t < exit.t {
            out.push(Interval { entry, exit });
        }
        if a[i].exit.t <= b[j].exit.t {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// The set of `t` where the solid of `dnf` contains `ray.at(t)`, as sorted,
/// merged intervals.
#[must_use]
pub fn solid_intervals(dnf: &Dnf, ray: &Ray) -> Vec<Interval> {
    let everything = Interval {
        entry: bound(f64::NEG_INFINITY, FREE, 1.0),
        exit: bound(f64::INFINITY, FREE, 1.0),
    };
    let mut all: Vec<Interval> = Vec::new();
    for product in dnf.products() {
        let mut set = vec![everything];
        for &literal in product {
            set = intersect(&set, &literal_set(dnf, literal, ray));
            if set.is_empty() {
                break;
            }
        }
        all.extend(set);
    }
    all.sort_by(|a, b| a.entry.t.total_cmp(&b.entry.t));
    let mut merged: Vec<Interval> = Vec::with_capacity(all.len());
    for iv in all {
        match merged.last_mut() {
            Some(last) if iv.entry.t <= last.exit.t => {
                if iv.exit.t > last.exit.t {
                    last.exit = iv.exit;
                }
            }
            _ => merged.push(iv),
        }
    }
    merged
}
