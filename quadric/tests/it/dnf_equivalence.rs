//! DNF equivalence: on random points, the normal form classifies exactly as
//! the original DAG, for random DAGs with shared nodes, transforms,
//! complements and differences.

use crate::common;

use chisel_quadric::csg::{CsgDag, Dnf, NodeId};
use glam::DVec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Builds a random DAG of up to `ops` operations over `leaves` primitives;
/// operands are drawn from all earlier nodes, so nodes get shared.
fn random_dag(rng: &mut ChaCha8Rng, leaves: usize, ops: usize) -> (CsgDag, NodeId) {
    let mut dag = CsgDag::new();
    let mut ids: Vec<NodeId> = (0..leaves)
        .map(|_| dag.primitive(common::quadric(rng), [0.5; 3]))
        .collect();
    for _ in 0..ops {
        let pick = |rng: &mut ChaCha8Rng| ids[rng.random_range(0..ids.len())];
        let n = rng.random_range(1..=3);
        let operands: Vec<NodeId> = (0..n).map(|_| pick(rng)).collect();
        let id = match rng.random_range(0..5) {
            0 => dag.union(&operands),
            1 => dag.intersection(&operands),
            2 => {
                let base = pick(rng);
                dag.difference(base, &operands)
            }
            3 => dag.complement(operands[0]),
            _ => dag.transform(common::affine(rng), operands[0]),
        }
        .expect("operands are valid");
        ids.push(id);
    }
    let root = dag.last().expect("non-empty");
    (dag, root)
}

/// Points closer than this (relative) to a quadric surface are skipped:
/// the DAG and the DNF round differently there.
fn near_surface(dnf: &Dnf, p: DVec3) -> bool {
    dnf.quadrics().iter().any(|q| {
        let g = q.quadric.gradient(p).length();
        q.quadric.value(p).abs() <= 1e-7 * (g + q.quadric.max_abs_coefficient())
    })
}

#[test]
fn dnf_classifies_like_the_dag() {
    let mut rng = common::rng(21);
    let mut checked = 0usize;
    let mut inside = 0usize;
    for case in 0..300 {
        let leaves = rng.random_range(1..=6);
        let ops = rng.random_range(1..=10);
        let (dag, root) = random_dag(&mut rng, leaves, ops);
        let dnf = match Dnf::from_dag(&dag, root) {
            Ok(d) => d,
            Err(e) => panic!("case {case}: {e}"),
        };
        for _ in 0..200 {
            let p = common::point(&mut rng, 3.0);
            if near_surface(&dnf, p) {
                continue;
            }
            let by_dag = dag.contains(root, p).unwrap();
            assert_eq!(by_dag, dnf.contains(p), "case {case} at {p}");
            checked += 1;
            inside += usize::from(by_dag);
        }
    }
    // The test is only meaningful if both answers occur often.
    assert!(checked > 50_000, "{checked}");
    assert!(
        inside > checked / 20 && inside < checked * 19 / 20,
        "{inside} / {checked}"
    );
}

#[test]
fn products_are_sorted_and_consistent() {
    let mut rng = common::rng(22);
    for _ in 0..200 {
        let (dag, root) = random_dag(&mut rng, 4, 8);
        let dnf = Dnf::from_dag(&dag, root).unwrap();
        for product in dnf.products() {
            assert!(product.windows(2).all(|w| w[0].quadric < w[1].quadric));
            assert!(product.iter().all(|l| l.quadric < dnf.quadrics().len()));
        }
        for q in dnf.quadrics() {
            assert!(q.primitive < dag.primitives().len());
        }
    }
}

#[test]
fn normalization_is_deterministic() {
    let (dag, root) = random_dag(&mut common::rng(23), 5, 10);
    let first = Dnf::from_dag(&dag, root).unwrap();
    for _ in 0..3 {
        assert_eq!(Dnf::from_dag(&dag, root).unwrap(), first);
    }
}
