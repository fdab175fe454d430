//! Normalization of a CSG DAG to disjunctive normal form (paper 2, §5, eqs. 17–18).
//!
//! Notation: `S = ⋃ᵢ ⋂ⱼ Lᵢⱼ`, a union of *products* `i`, each an
//! intersection of *literals* `Lᵢⱼ = (quadric index, side)`; side
//! [`Side::Inside`] means `Q < 0`, [`Side::Outside`] means "not inside"
//! (`Q ≥ 0`, the complement `−Q`). An empty union is the empty set; an empty
//! product is all of space.
//!
//! Rewriting rules, applied top-down with a polarity (`+` or `−`, for an odd
//! number of enclosing complements) and an accumulated transform `M`:
//! - `∪⁺` and `∩⁻` concatenate the children's products (De Morgan);
//! - `∩⁺` and `∪⁻` take the cross product of the children's products;
//! - `a − b₁ − … ` is `a ∩ ¬b₁ ∩ …`;
//! - complement flips the polarity; transform multiplies `M` by its matrix;
//! - a leaf becomes the literal `(M⁻ᵀ Q M⁻¹, +: Inside / −: Outside)`.
//!
//! Shared DAG nodes are expanded once per path (each path is a distinct
//! instance of the primitive, §5). Identical transformed quadrics share one
//! index. Products are kept sorted and simplified: duplicate literals and
//! products are removed, products containing both sides of one quadric are
//! dropped (empty), and products that contain another product are absorbed.

use std::collections::HashMap;

use glam::{DMat4, DVec3};

use crate::csg::dag::{CsgDag, Node, NodeId};
use crate::error::{Error, Result};
use crate::quadric::Quadric;

/// Default limit on the number of products during normalization.
pub const MAX_PRODUCTS: usize = 1 << 16;

/// Absorption is quadratic in the product count; it runs below this size.
const ABSORB_LIMIT: usize = 4096;

/// Which side of a quadric a literal asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Side {
    /// `Q(x) < 0`.
    Inside,
    /// Not inside: `Q(x) ≥ 0`.
    Outside,
}

impl Side {
    /// The other side.
    #[must_use]
    pub fn flip(self) -> Self {
        match self {
            Side::Inside => Side::Outside,
            Side::Outside => Side::Inside,
        }
    }

    /// Whether a quadric value `q` is on this side.
    #[must_use]
    pub fn holds(self, q: f64) -> bool {
        (q < 0.0) == (self == Side::Inside)
    }
}

/// One factor of a product: a quadric (index into [`Dnf::quadrics`]) and a side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Literal {
    /// Index into [`Dnf::quadrics`].
    pub quadric: usize,
    /// Which side of it.
    pub side: Side,
}

/// A quadric of the normal form: a primitive with all transforms applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DnfQuadric {
    /// The transformed quadric (`Q < 0` inside).
    pub quadric: Quadric,
    /// The index of the source primitive in [`CsgDag::primitives`] (for its colour).
    pub primitive: usize,
}

/// A CSG solid in disjunctive normal form: a union of intersections of literals.
#[derive(Clone, Debug, PartialEq)]
pub struct Dnf {
    quadrics: Vec<DnfQuadric>,
    products: Vec<Vec<Literal>>,
}

type Product = Vec<Literal>;

impl Dnf {
    /// Normalizes the solid of `root` in `dag`, with at most [`MAX_PRODUCTS`] products.
    ///
    /// Errors: [`Error::UnknownNode`], [`Error::DnfTooLarge`], and transform
    /// errors if an accumulated transform degenerates numerically.
    pub fn from_dag(dag: &CsgDag, root: NodeId) -> Result<Self> {
        Self::from_dag_with_limit(dag, root, MAX_PRODUCTS)
    }

    /// As [`from_dag`](Self::from_dag) with a custom product limit.
    pub fn from_dag_with_limit(dag: &CsgDag, root: NodeId, limit: usize) -> Result<Self> {
        dag.node(root)?;
        let mut builder = Builder {
            dag,
            limit,
            quadrics: Vec::new(),
            index: HashMap::new(),
        };
        let products = builder.normalize(root, DMat4::IDENTITY, true)?;
        Ok(Self {
            quadrics: builder.quadrics,
            products,
        })
    }

    /// The distinct transformed quadrics that the literals refer to.
    #[must_use]
    pub fn quadrics(&self) -> &[DnfQuadric] {
        &self.quadrics
    }

    /// The products (intersection terms), each a sorted list of literals.
    #[must_use]
    pub fn products(&self) -> &[Vec<Literal>] {
        &self.products
    }

    /// `true` when the solid is empty (no products).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.products.is_empty()
    }

    /// The quadric of `literal` with its side applied: `Q` for inside, `−Q` for
    /// outside, so that the literal holds (up to the surface) where the
    /// result is negative.
    #[must_use]
    pub fn literal_quadric(&self, literal: Literal) -> Quadric {
        let q = self.quadrics[literal.quadric].quadric;
        match literal.side {
            Side::Inside => q,
            Side::Outside => q.complement(),
        }
    }

    /// Whether `point` is inside the solid.
    #[must_use]
    pub fn contains(&self, point: DVec3) -> bool {
        let values: Vec<f64> = self
            .quadrics
            .iter()
            .map(|q| q.quadric.value(point))
            .collect();
        self.products
            .iter()
            .any(|p| p.iter().all(|l| l.side.holds(values[l.quadric])))
    }
}

struct Builder<'a> {
    dag: &'a CsgDag,
    limit: usize,
    quadrics: Vec<DnfQuadric>,
    index: HashMap<[u64; 10], usize>,
}

impl Builder<'_> {
    fn normalize(&mut self, id: NodeId, m: DMat4, positive: bool) -> Result<Vec<Product>> {
        let node = self.dag.node(id)?.clone();
        let products = match node {
            Node::Primitive(i) => {
                let q = self.leaf(i, &m)?;
                let side = if positive {
                    Side::Inside
                } else {
                    Side::Outside
                };
                vec![vec![Literal { quadric: q, side }]]
            }
            Node::Union(children) => self.combine(&children, &m, positive, positive)?,
            Node::Intersection(children) => self.combine(&children, &m, positive, !positive)?,
            Node::Difference { base, subtracted } => {
                // base ∩ ¬s₁ ∩ … ; negated: ¬base ∪ s₁ ∪ …
                let mut parts = vec![self.normalize(base, m, positive)?];
                for s in subtracted {
                    parts.push(self.normalize(s, m, !positive)?);
                }
                if positive {
                    self.cross_all(parts)?
                } else {
                    self.concat(parts)?
                }
            }
            Node::Complement(child) => self.normalize(child, m, !positive)?,
            Node::Transform { transform, child } => {
                self.normalize(child, m * transform.matrix, positive)?
            }
        };
        Ok(products)
    }

    /// Children combined by concatenation (`union_like`) or cross product.
    fn combine(
        &mut self,
        children: &[NodeId],
        m: &DMat4,
        positive: bool,
        union_like: bool,
    ) -> Result<Vec<Product>> {
        let mut parts = Vec::with_capacity(children.len());
        for &c in children {
            parts.push(self.normalize(c, *m, positive)?);
        }
        if union_like {
            self.concat(parts)
        } else {
            self.cross_all(parts)
        }
    }

    fn leaf(&mut self, primitive: usize, m: &DMat4) -> Result<usize> {
        let source = self.dag.primitives()[primitive].quadric;
        let quadric = if *m == DMat4::IDENTITY {
            source
        } else {
            source.transformed(m)?
        };
        let key = quadric.coefficients().map(f64::to_bits);
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        self.quadrics.push(DnfQuadric { quadric, primitive });
        self.index.insert(key, self.quadrics.len() - 1);
        Ok(self.quadrics.len() - 1)
    }

    fn concat(&self, parts: Vec<Vec<Product>>) -> Result<Vec<Product>> {
        let total: usize = parts.iter().map(Vec::len).sum();
        if total > self.limit {
            return Err(Error::DnfTooLarge { limit: self.limit });
        }
        Ok(simplify(parts.into_iter().flatten().collect()))
    }

    fn cross_all(&self, parts: Vec<Vec<Product>>) -> Result<Vec<Product>> {
        let mut acc: Vec<Product> = vec![Vec::new()];
        for part in parts {
            if acc.len().saturating_mul(part.len()) > self.limit {
                return Err(Error::DnfTooLarge { limit: self.limit });
            }
            let mut next = Vec::with_capacity(acc.len() * part.len());
            for a in &acc {
                for b in &part {
                    if let Some(p) = merge(a, b) {
                        next.push(p);
                    }
                }
            }
            acc = simplify(next);
        }
        Ok(acc)
    }
}

/// The conjunction of two sorted products, or `None` if it is contradictory.
fn merge(a: &[Literal], b: &[Literal]) -> Option<Product> {
    let mut p: Product = a.iter().chain(b).copied().collect();
    p.sort_unstable();
    p.dedup();
    let contradictory = p.windows(2).any(|w| w[0].quadric == w[1].quadric);
    (!contradictory).then_some(p)
}

/// Sorts and deduplicates products and removes absorbed ones (`P ⊂ P'` ⇒ drop `P'`).
fn simplify(mut products: Vec<Product>) -> Vec<Product> {
    products.sort_unstable_by(|a, b| a.len().cmp(&b.len()).then_with(|| a.cmp(b)));
    products.dedup();
    if products.len() > ABSORB_LIMIT {
        return products;
    }
    let mut kept: Vec<Product> = Vec::with_capacity(products.len());
    for p in products {
        // Shorter products come first, so only they can absorb `p`.
        if !kept.iter().any(|k| is_subset(k, &p)) {
            kept.push(p);
        }
    }
    kept
}

/// Whether sorted `small` is a subset of sorted `big`.
fn is_subset(small: &[Literal], big: &[Literal]) -> bool {
    let mut it = big.iter();
    small.iter().all(|s| it.any(|b| b == s))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(dag: &mut CsgDag, x: f64) -> NodeId {
        dag.primitive(
            Quadric::sphere(DVec3::new(x, 0.0, 0.0), 1.0).unwrap(),
            [1.0; 3],
        )
    }

    #[test]
    fn three_spheres_has_two_products() {
        let mut dag = CsgDag::new();
        let (a, b, c) = (
            sphere(&mut dag, 0.0),
            sphere(&mut dag, 1.0),
            sphere(&mut dag, 5.0),
        );
        let ab = dag.intersection(&[a, b]).unwrap();
        let root = dag.union(&[ab, c]).unwrap();
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        assert_eq!(dnf.quadrics().len(), 3);
        let inside = |q| Literal {
            quadric: q,
            side: Side::Inside,
        };
        assert_eq!(
            dnf.products(),
            &[vec![inside(2)], vec![inside(0), inside(1)]]
        );
    }

    #[test]
    fn contradictions_and_absorption() {
        let mut dag = CsgDag::new();
        let a = sphere(&mut dag, 0.0);
        let b = sphere(&mut dag, 1.0);
        let not_a = dag.complement(a).unwrap();
        let empty = dag.intersection(&[a, not_a]).unwrap();
        assert!(Dnf::from_dag(&dag, empty).unwrap().is_empty());
        let everything = dag.complement(empty).unwrap();
        let all = Dnf::from_dag(&dag, everything).unwrap();
        assert_eq!(all.products().len(), 2); // ¬A ∪ A, both single literals
        let ab = dag.intersection(&[a, b]).unwrap();
        let absorbed = dag.union(&[a, ab]).unwrap();
        assert_eq!(Dnf::from_dag(&dag, absorbed).unwrap().products().len(), 1);
    }

    #[test]
    fn limit_is_enforced() {
        let mut dag = CsgDag::new();
        let mut factors = Vec::new();
        for i in 0..8 {
            let p = sphere(&mut dag, f64::from(i));
            let q = sphere(&mut dag, f64::from(i) + 0.5);
            factors.push(dag.union(&[p, q]).unwrap());
        }
        let root = dag.intersection(&factors).unwrap();
        assert_eq!(
            Dnf::from_dag_with_limit(&dag, root, 100),
            Err(Error::DnfTooLarge { limit: 100 })
        );
        assert_eq!(Dnf::from_dag(&dag, root).unwrap().products().len(), 256);
    }
}
