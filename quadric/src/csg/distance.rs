//! Conservative distances to a CSG surface in normal form (paper 2, §5, eqs. 19–22).
//!
//! Notation: `d(Q, p)` the conservative signed distance of eq. 12 (negative
//! inside); a literal `Lᵢⱼ` on the outside side uses `d(−Q, p) = −d(Q, p)`.
//!
//! - Eq. 19: `d(S, p) = minᵢ maxⱼ d(Lᵢⱼ, p)`, negative inside the solid.
//! - Eq. 22, relative to the literal `L_ab` (its quadric `Q_ab` being sampled):
//!   `d_ab(S, p) = max( −min_{i≠a} maxⱼ d(Lᵢⱼ, p),  max_{j≠b} d(L_aj, p) )`.
//!   Negative: `p` and every point of `Q_ab` within `|d_ab|` lie on the CSG
//!   surface; positive: none of them does. Empty minima are `+∞`, empty
//!   maxima `−∞`.
//! - Shared surfaces: for `p` on `Q_ab`, another product `i` that contains
//!   the same literal `L_ab` lies on the same side of `Q_ab` as product `a`,
//!   so it cannot make `p` interior and is left out of the minimum; one that
//!   contains the opposite literal `¬L_ab` is evaluated without it (its
//!   distance is 0 on `Q_ab` and says nothing). Without this, a surface
//!   shared by two products (a bore through two unioned parts) would have
//!   `d_ab = 0` and never be classified. A quadric and its exact negation
//!   count as one surface.

use std::collections::HashMap;

use glam::DVec3;

use crate::csg::dnf::{Dnf, Literal, Side};
use crate::distance::QuadricDistance;

/// The distance bounds of every quadric of a [`Dnf`], ready for eqs. 19 and 22.
#[derive(Clone, Debug)]
pub struct CsgDistance<'a> {
    dnf: &'a Dnf,
    quadrics: Vec<QuadricDistance>,
    /// Per quadric: the index of the first quadric with the same surface
    /// (the quadric itself or its exact negation) and whether it is negated.
    canonical: Vec<(usize, bool)>,
    /// Per literal ([`signed_index`]): the bounds with its side applied,
    /// `d(L, p)` directly (`d(−Q, p) = −d(Q, p)` for the outside side).
    signed: Vec<QuadricDistance>,
}

/// The index of literal `l` in [`CsgDistance::signed`].
fn signed_index(l: Literal) -> u32 {
    let q = u32::try_from(l.quadric).unwrap_or(u32::MAX / 2);
    2 * q + u32::from(l.side == Side::Outside)
}

impl<'a> CsgDistance<'a> {
    /// Prepares `dnf` (one eigen decomposition per quadric).
    #[must_use]
    pub fn new(dnf: &'a Dnf) -> Self {
        let quadrics: Vec<QuadricDistance> = dnf
            .quadrics()
            .iter()
            .map(|q| QuadricDistance::new(&q.quadric))
            .collect();
        let signed = quadrics.iter().flat_map(|q| [*q, q.complement()]).collect();
        let mut first: HashMap<[u64; 10], usize> = HashMap::new();
        let mut canonical = Vec::with_capacity(dnf.quadrics().len());
        for (i, q) in dnf.quadrics().iter().enumerate() {
            // `+ 0.0` turns −0 into +0, so that bit patterns compare as numbers.
            let key = q.quadric.coefficients().map(|c| (c + 0.0).to_bits());
            let negated = q.quadric.coefficients().map(|c| (0.0 - c).to_bits());
            if let Some(&j) = first.get(&negated) {
                canonical.push((j, true));
            } else {
                first.entry(key).or_insert(i);
                canonical.push((i, false));
            }
        }
        Self {
            dnf,
            quadrics,
            canonical,
            signed,
        }
    }

    /// A literal as `(canonical quadric, holds inside it)`: `Q < 0` and
    /// `−Q ≥ 0` give the same key up to the surface itself.
    fn literal_key(&self, l: Literal) -> (usize, bool) {
        let (q, negated) = self.canonical[l.quadric];
        (q, (l.side == Side::Inside) != negated)
    }

    /// The normal form these distances belong to.
    #[must_use]
    pub fn dnf(&self) -> &'a Dnf {
        self.dnf
    }

    /// `maxⱼ d(L_ij, p)` over the literals of product `i` except `skip`.
    fn product_distance(&self, i: usize, skip: Option<usize>, p: DVec3) -> f64 {
        self.product_distance_capped(i, skip, p, f64::INFINITY)
    }

    /// As [`product_distance`](Self::product_distance), but stops as soon as
    /// the running maximum reaches `cap` (the result is then `≥ cap`, which
    /// is all a surrounding minimum needs to know).
    fn product_distance_capped(&self, i: usize, skip: Option<usize>, p: DVec3, cap: f64) -> f64 {
        let mut max = f64::NEG_INFINITY;
        for (j, l) in self.dnf.products()[i].iter().enumerate() {
            if Some(j) == skip {
                continue;
            }
            let d = self.quadrics[l.quadric].distance(p);
            let d = match l.side {
                Side::Inside => d,
                Side::Outside => -d,
            };
            max = max.max(d);
            if max >= cap {
                break;
            }
        }
        max
    }

    /// `minᵢ maxⱼ d(L_ij, p)` over the products other than `skip`.
    fn union_distance(&self, skip: Option<usize>, p: DVec3) -> f64 {
        let mut hint = usize::MAX;
        self.union_distance_hinted(skip, None, p, &mut hint)
    }

    /// As [`union_distance`](Self::union_distance) for points on the
    /// surface of literal `on` (see the module notes on shared surfaces),
    /// evaluating product `hint` first (a good guess makes the others stop
    /// early) and storing the minimizing product in it.
    fn union_distance_hinted(
        &self,
        skip: Option<usize>,
        on: Option<Literal>,
        p: DVec3,
        hint: &mut usize,
    ) -> f64 {
        let n = self.dnf.products().len();
        let mut min = f64::INFINITY;
        let mut first = None;
        let hinted = (*hint < n && Some(*hint) != skip)
            .then(|| self.shared_literal(*hint, on))
            .flatten();
        if let Some(left_out) = hinted {
            min = self.product_distance(*hint, left_out, p);
            first = Some(*hint);
        }
        for i in 0..n {
            if Some(i) == skip || Some(i) == first {
                continue;
            }
            let Some(left_out) = self.shared_literal(i, on) else {
                continue;
            };
            let d = self.product_distance_capped(i, left_out, p, min);
            if d < min {
                min = d;
                *hint = i;
            }
        }
        min
    }

    /// How product `i` takes part for points on the surface of `on`:
    /// `None` to leave it out (it contains `on`), `Some(Some(j))` to
    /// evaluate it without its literal `j` (the opposite of `on`),
    /// `Some(None)` to evaluate it whole.
    fn shared_literal(&self, i: usize, on: Option<Literal>) -> Option<Option<usize>> {
        let Some(on) = on else {
            return Some(None);
        };
        let (surface, side) = self.literal_key(on);
        let product = &self.dnf.products()[i];
        let found = product
            .iter()
            .position(|l| self.literal_key(*l).0 == surface);
        match found {
            Some(j) if self.literal_key(product[j]).1 == side => None,
            Some(j) => Some(Some(j)),
            None => Some(None),
        }
    }

    /// The conservative signed distance to the CSG surface, eq. 19: negative
    /// inside the solid, `+∞` for an empty solid.
    #[must_use]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.union_distance(None, p)
    }

    /// The quadric-relative distance `d_ab(S, p)` of eq. 22 for literal `b` of
    /// product `a`, meant for points `p` on that literal's quadric.
    ///
    /// Precondition: `a < products().len()` and `b < products()[a].len()`
    /// (panics otherwise; indices come from iterating the [`Dnf`]).
    #[must_use]
    pub fn relative_distance(&self, a: usize, b: usize, p: DVec3) -> f64 {
        let mut hint = usize::MAX;
        self.relative_distance_hinted(a, b, p, &mut hint)
    }

    /// [`relative_distance`](Self::relative_distance) with a hint: the
    /// product of the other terms evaluated first, updated to the nearest
    /// one. Queries at nearby points that share a hint skip most literals of
    /// far products; the result is the same for every hint.
    ///
    /// Preconditions as [`relative_distance`](Self::relative_distance).
    #[must_use]
    pub fn relative_distance_hinted(&self, a: usize, b: usize, p: DVec3, hint: &mut usize) -> f64 {
        let own = self.product_distance(a, Some(b), p);
        let on = self.dnf.products()[a][b];
        let others = self.union_distance_hinted(Some(a), Some(on), p, hint);
        (-others).max(own)
    }

    /// The other products as seen from literal `b` of product `a` (see the
    /// module notes on shared surfaces), and that literal's own product,
    /// for [`relative_distance_among`](Self::relative_distance_among).
    ///
    /// Preconditions as [`relative_distance`](Self::relative_distance).
    #[must_use]
    pub fn other_terms(&self, a: usize, b: usize) -> OtherTerms {
        let on = Some(self.dnf.products()[a][b]);
        let mut literals = Vec::new();
        let term = |product: usize, left_out: Option<usize>, literals: &mut Vec<u32>| {
            let start = index_u32(literals.len());
            for (j, l) in self.dnf.products()[product].iter().enumerate() {
                if Some(j) != left_out {
                    literals.push(signed_index(*l));
                }
            }
            Term {
                product: index_u32(product),
                start,
                end: index_u32(literals.len()),
                floor: f64::NEG_INFINITY,
            }
        };
        let own = term(a, Some(b), &mut literals);
        let terms = (0..self.dnf.products().len())
            .filter(|&i| i != a)
            .filter_map(|i| self.shared_literal(i, on).map(|left_out| (i, left_out)))
            .map(|(i, left_out)| term(i, left_out, &mut literals))
            .collect();
        OtherTerms {
            literals,
            terms,
            own,
            floor: f64::INFINITY,
        }
    }

    /// `max(floor, maxⱼ d(Lⱼ, p))` over the literals of `term`, stopping
    /// as soon as the running maximum reaches `cap` (the result is then
    /// `≥ cap`, all that a surrounding minimum needs to know).
    #[inline]
    fn term_distance(&self, literals: &[u32], term: &Term, p: DVec3, cap: f64) -> f64 {
        let mut max = term.floor;
        if max >= cap {
            return max;
        }
        for &k in &literals[term.start as usize..term.end as usize] {
            // A compare, not `f64::max`: distances are never NaN.
            let d = self.signed[k as usize].distance(p);
            if d > max {
                max = d;
                if max >= cap {
                    break;
                }
            }
        }
        max
    }

    /// Eq. 22 for the literal `others` was made for (by
    /// [`other_terms`](Self::other_terms), possibly
    /// [`cull`](Self::cull)ed). `hint` as in
    /// [`relative_distance_hinted`](Self::relative_distance_hinted): the
    /// product evaluated first, updated to the nearest one; the result is
    /// the same for every hint.
    #[must_use]
    pub fn relative_distance_among(&self, p: DVec3, others: &OtherTerms, hint: &mut usize) -> f64 {
        let literals = &others.literals;
        let mut min = others.floor;
        let first = others
            .terms
            .iter()
            .position(|t| t.product as usize == *hint);
        if let Some(k) = first {
            min = min.min(self.term_distance(literals, &others.terms[k], p, f64::INFINITY));
        }
        for (k, term) in others.terms.iter().enumerate() {
            if Some(k) == first {
                continue;
            }
            let d = self.term_distance(literals, term, p, min);
            if d < min {
                min = d;
                *hint = term.product as usize;
            }
        }
        // The own product only matters where it exceeds `−min`.
        let own = self.term_distance(literals, &others.own, p, f64::INFINITY);
        (-min).max(own)
    }

    /// `others` for points within distance `radius` of `centre`. With `D`
    /// the distance of a product or literal at `centre` (each conservative,
    /// so the sign holds and `|D| − radius` bounds the true distance
    /// anywhere in the ball):
    /// - a product (also the own one) with `D > 2·radius` becomes the
    ///   constant `D − radius`;
    /// - a literal of a remaining product with `D < −2·radius` becomes the
    ///   constant `D + radius`, folded into its product's floor.
    ///
    /// Each replacement keeps the sign and shrinks the magnitude of the
    /// value it replaces, and so does every `min`/`max` of eq. 22 above it:
    /// the result stays a conservative eq.-22 distance in the ball. Each
    /// constant also keeps a magnitude above `radius`, so where the exact
    /// value would reach `radius` in magnitude the culled one does too: a
    /// caller that only compares the sign, and magnitudes with thresholds
    /// up to `radius`, decides as without culling. `None` when nothing can
    /// be dropped.
    #[must_use]
    pub fn cull(&self, others: &OtherTerms, centre: DVec3, radius: f64) -> Option<OtherTerms> {
        let mut out = OtherTerms::empty();
        self.cull_into(others, centre, radius, &mut out)
            .then_some(out)
    }

    /// [`cull`](Self::cull) into `out`, reusing its buffers (a subdivision
    /// culls at every other level): `true` when something was dropped,
    /// and `out` then holds the culled terms (else its content is
    /// unspecified).
    pub fn cull_into(
        &self,
        others: &OtherTerms,
        centre: DVec3,
        radius: f64,
        out: &mut OtherTerms,
    ) -> bool {
        let far = 2.0 * radius;
        let mut literals = std::mem::take(&mut out.literals);
        literals.clear();
        let mut changed = false;
        let mut floor = others.floor;
        // The term culled, or `Err(constant)` when it became one.
        let mut cull_term = |term: &Term, literals: &mut Vec<u32>| -> Result<Term, f64> {
            let start = literals.len();
            let mut total = term.floor;
            let mut term_floor = term.floor;
            for &k in &others.literals[term.start as usize..term.end as usize] {
                let d = self.signed[k as usize].distance(centre);
                total = total.max(d);
                if d < -far {
                    term_floor = term_floor.max(d + radius);
                } else {
                    literals.push(k);
                }
            }
            if total > far {
                literals.truncate(start);
                changed = true;
                return Err(total - radius);
            }
            changed |= literals.len() - start < (term.end - term.start) as usize;
            Ok(Term {
                product: term.product,
                start: index_u32(start),
                end: index_u32(literals.len()),
                floor: term_floor,
            })
        };
        let own = match cull_term(&others.own, &mut literals) {
            Ok(t) => t,
            Err(constant) => Term {
                product: others.own.product,
                start: 0,
                end: 0,
                floor: constant,
            },
        };
        let mut terms = std::mem::take(&mut out.terms);
        terms.clear();
        for term in &others.terms {
            match cull_term(term, &mut literals) {
                Ok(t) => terms.push(t),
                Err(constant) => floor = floor.min(constant),
            }
        }
        *out = OtherTerms {
            literals,
            terms,
            own,
            floor,
        };
        changed
    }
}

/// Indices into normal forms fit in `u32` (the product limit is far lower).
fn index_u32(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

/// One product of [`OtherTerms`]: its literals still evaluated (a range of
/// [`OtherTerms::literals`]) and a constant lower bound standing for those
/// dropped by [`CsgDistance::cull`].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Term {
    product: u32,
    start: u32,
    end: u32,
    floor: f64,
}

/// The products of the normal form as seen from one literal `L_ab`: the
/// other products, each with the literal to leave out (module notes), and
/// the own product without `L_ab`; plus a constant lower bound for the
/// products dropped by [`CsgDistance::cull`].
#[derive(Clone, Debug, PartialEq)]
pub struct OtherTerms {
    /// Literals still evaluated, as indices of [`CsgDistance`]'s signed bounds.
    literals: Vec<u32>,
    /// The other products still evaluated.
    terms: Vec<Term>,
    /// The own product without the sampled literal.
    own: Term,
    /// `min` over the dropped products' constants (`+∞` if none).
    floor: f64,
}

impl OtherTerms {
    /// No terms at all (`+∞` everywhere), a buffer for
    /// [`CsgDistance::cull_into`].
    #[must_use]
    pub fn empty() -> Self {
        Self {
            literals: Vec::new(),
            terms: Vec::new(),
            own: Term {
                product: 0,
                start: 0,
                end: 0,
                floor: f64::NEG_INFINITY,
            },
            floor: f64::INFINITY,
        }
    }

    /// The bytes of the largest `OtherTerms` of `dnf`, the one
    /// [`CsgDistance::other_terms`] builds when no product is left out:
    /// an index per literal of the normal form and an entry per product.
    #[must_use]
    pub fn bytes_for(dnf: &Dnf) -> u64 {
        let literals: usize = dnf.products().iter().map(Vec::len).sum();
        let bytes = literals
            .saturating_mul(std::mem::size_of::<u32>())
            .saturating_add(
                dnf.products()
                    .len()
                    .saturating_mul(std::mem::size_of::<Term>()),
            );
        u64::try_from(bytes).unwrap_or(u64::MAX)
    }

    /// The number of other products still evaluated.
    #[must_use]
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// `true` when no product is evaluated any more.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The number of literal distances one query evaluates at most.
    #[must_use]
    pub fn literal_count(&self) -> usize {
        self.literals.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Quadric;
    use crate::csg::CsgDag;

    #[test]
    fn three_spheres_relative_distance() {
        // (A ∩ B) ∪ C with A, B overlapping and C far away.
        let mut dag = CsgDag::new();
        let s = |x: f64| Quadric::sphere(DVec3::new(x, 0.0, 0.0), 1.0).unwrap();
        let a = dag.primitive(s(0.0), [1.0; 3]);
        let b = dag.primitive(s(1.0), [1.0; 3]);
        let c = dag.primitive(s(10.0), [1.0; 3]);
        let ab = dag.intersection(&[a, b]).unwrap();
        let root = dag.union(&[ab, c]).unwrap();
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        let d = CsgDistance::new(&dnf);
        // Products are sorted: [C], [A, B].
        assert_eq!(dnf.products()[1].len(), 2);
        // On A at (1, 0, 0): inside B (its centre), far from C → on the surface.
        let on_a_in_b = d.relative_distance(1, 0, DVec3::new(1.0, 0.0, 0.0));
        assert!(on_a_in_b < 0.0 && (on_a_in_b + 1.0).abs() < 1e-9);
        // On A at (−1, 0, 0): outside B by 1 → cut away.
        let on_a_out_b = d.relative_distance(1, 0, DVec3::new(-1.0, 0.0, 0.0));
        assert!(on_a_out_b > 0.0 && (on_a_out_b - 1.0).abs() < 1e-9);
        // On C at (11, 0, 0): the only literal of its product, and A ∩ B is
        // at least max(d_A, d_B) = 10 away.
        let on_c = d.relative_distance(0, 0, DVec3::new(11.0, 0.0, 0.0));
        assert!((on_c + 10.0).abs() < 1e-9);
        // Eq. 19 at (1, 0, 0): on A's surface and inside B, so 0 from A ∩ B.
        assert!(d.distance(DVec3::new(1.0, 0.0, 0.0)).abs() < 1e-9);
        // Eq. 19 at (5, 0, 0): 4 outside both A and C, 3 outside B → max 4.
        assert!((d.distance(DVec3::new(5.0, 0.0, 0.0)) - 4.0).abs() < 1e-9);
    }

    #[test]
    fn shared_surfaces_are_classified() {
        // Two unioned boxes whose top faces share the plane z = 1 over x ∈ [1, 2].
        let mut dag = CsgDag::new();
        let a = dag
            .cuboid(DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0), [1.0; 3])
            .unwrap();
        let b = dag
            .cuboid(
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(3.0, 1.0, 1.0),
                [1.0; 3],
            )
            .unwrap();
        let root = dag.union(&[a, b]).unwrap();
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        let d = CsgDistance::new(&dnf);
        let top = Quadric::half_space(DVec3::Z, 1.0).unwrap();
        let p = DVec3::new(1.5, 0.5, 1.0);
        for (i, product) in dnf.products().iter().enumerate() {
            let j = product
                .iter()
                .position(|l| dnf.quadrics()[l.quadric].quadric == top)
                .unwrap();
            // On the surface, with a radius of 0.5 (the nearest other face).
            assert!((d.relative_distance(i, j, p) + 0.5).abs() < 1e-9);
        }
        // A slab on each side of z = 0: the shared plane is interior.
        let mut dag = CsgDag::new();
        let below = dag
            .cuboid(-DVec3::ONE, DVec3::new(1.0, 1.0, 0.0), [1.0; 3])
            .unwrap();
        let above = dag
            .cuboid(DVec3::new(-1.0, -1.0, 0.0), DVec3::ONE, [1.0; 3])
            .unwrap();
        let root = dag.union(&[below, above]).unwrap();
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        let d = CsgDistance::new(&dnf);
        let floor = Quadric::half_space(DVec3::Z, 0.0).unwrap();
        for (i, product) in dnf.products().iter().enumerate() {
            let Some(j) = product.iter().position(|l| {
                let q = dnf.quadrics()[l.quadric].quadric;
                q == floor || q == floor.complement()
            }) else {
                continue;
            };
            assert!(d.relative_distance(i, j, DVec3::new(0.2, 0.1, 0.0)) > 0.5);
        }
    }

    #[test]
    fn culled_terms_stay_conservative() {
        // A plate with four bores and a boss: planes and cylinders, many
        // literals per product, some far from any given ball.
        let mut dag = CsgDag::new();
        let plate = dag
            .cuboid(
                DVec3::new(-6.0, -4.0, 0.0),
                DVec3::new(6.0, 4.0, 1.0),
                [1.0; 3],
            )
            .unwrap();
        let mut bores = Vec::new();
        for (x, y) in [(-4.0, -2.0), (4.0, -2.0), (-4.0, 2.0), (4.0, 2.0)] {
            let q = Quadric::cylinder(DVec3::new(x, y, 0.0), DVec3::Z, 0.5).unwrap();
            bores.push(dag.primitive(q, [1.0; 3]));
        }
        let boss = dag
            .cuboid(
                DVec3::new(-1.0, -1.0, 0.5),
                DVec3::new(1.0, 1.0, 3.0),
                [1.0; 3],
            )
            .unwrap();
        let drilled = dag.difference(plate, &bores).unwrap();
        let root = dag.union(&[drilled, boss]).unwrap();
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        let d = CsgDistance::new(&dnf);
        let mut culled_any = false;
        for (a, product) in dnf.products().iter().enumerate() {
            for b in 0..product.len() {
                let others = d.other_terms(a, b);
                for (k, centre) in [
                    DVec3::new(-4.0, -2.0, 1.0),
                    DVec3::new(0.3, 0.2, 3.0),
                    DVec3::new(5.5, 3.5, 0.5),
                ]
                .into_iter()
                .enumerate()
                {
                    let radius = 0.1 + 0.2 * f64::from(u8::try_from(k).unwrap());
                    let Some(culled) = d.cull(&others, centre, radius) else {
                        continue;
                    };
                    culled_any |= culled.literal_count() < others.literal_count();
                    // Culling again inside a smaller ball keeps it conservative.
                    let again = d
                        .cull(&culled, centre, 0.5 * radius)
                        .unwrap_or(culled.clone());
                    for i in 0..200 {
                        let t = f64::from(i);
                        let dir = DVec3::new((t * 1.3).sin(), (t * 0.7).cos(), (t * 2.1).sin());
                        let p = centre + dir.normalize() * 0.5 * radius * ((t * 0.37).sin().abs());
                        let (mut h1, mut h2, mut h3) = (usize::MAX, usize::MAX, 0);
                        let full = d.relative_distance_among(p, &others, &mut h1);
                        assert_eq!(full, d.relative_distance(a, b, p));
                        for weak in [
                            d.relative_distance_among(p, &culled, &mut h2),
                            d.relative_distance_among(p, &again, &mut h3),
                        ] {
                            assert!(
                                weak.signum() == full.signum() && weak.abs() <= full.abs(),
                                "product {a} literal {b} at {p}: {weak} vs {full}"
                            );
                        }
                    }
                }
            }
        }
        assert!(culled_any, "some literals were culled");
    }
}
