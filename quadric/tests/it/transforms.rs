//! Transforms: `Q' = M⁻ᵀ Q M⁻¹` keeps values (`Q'(Mx) = Q(x)`), composes,
//! and maps normals by `M⁻ᵀ`.

use crate::common;

use chisel_quadric::{Error, Quadric};
use glam::{DMat3, DMat4, DVec3};

fn tolerance(q: &Quadric, x: DVec3) -> f64 {
    1e-10 * q.max_abs_coefficient() * (1.0 + x.length_squared())
}

#[test]
fn transformed_value_at_transformed_point_equals_original() {
    let mut rng = common::rng(11);
    for kind in 0..common::KINDS * 20 {
        let q = common::quadric_of_kind(&mut rng, kind);
        let m = common::affine(&mut rng);
        let qm = q.transformed(&m).unwrap();
        for _ in 0..20 {
            let x = common::point(&mut rng, 3.0);
            let (before, after) = (q.value(x), qm.value(m.transform_point3(x)));
            assert!(
                (before - after).abs() <= tolerance(&q, x),
                "kind {kind}: Q(x) = {before}, Q'(Mx) = {after}"
            );
        }
    }
}

#[test]
fn transforms_compose_and_invert() {
    let mut rng = common::rng(12);
    for kind in 0..common::KINDS * 10 {
        let q = common::quadric_of_kind(&mut rng, kind);
        let (m1, m2) = (common::affine(&mut rng), common::affine(&mut rng));
        let stepwise = q.transformed(&m1).unwrap().transformed(&m2).unwrap();
        let at_once = q.transformed(&(m2 * m1)).unwrap();
        let back = q
            .transformed(&m1)
            .unwrap()
            .transformed(&m1.inverse())
            .unwrap();
        let s = q.max_abs_coefficient();
        for (a, b) in stepwise.coefficients().iter().zip(at_once.coefficients()) {
            assert!((a - b).abs() <= 1e-9 * s.max(stepwise.max_abs_coefficient()));
        }
        for (a, b) in back.coefficients().iter().zip(q.coefficients()) {
            assert!((a - b).abs() <= 1e-9 * s, "{back:?} vs {q:?}");
        }
    }
}

#[test]
fn normals_map_by_inverse_transpose() {
    let mut rng = common::rng(13);
    for _ in 0..200 {
        let q = common::quadric(&mut rng);
        let m = common::affine(&mut rng);
        let qm = q.transformed(&m).unwrap();
        let x = common::point(&mut rng, 2.0);
        let (Some(n), Some(nm)) = (q.normal(x), qm.normal(m.transform_point3(x))) else {
            continue;
        };
        let expect = (DMat3::from_mat4(m).inverse().transpose() * n).normalize();
        assert!((nm - expect).length() < 1e-8, "{nm} vs {expect}");
    }
}

#[test]
fn sign_is_kept_under_reflection() {
    // A mirror (negative determinant) must not swap inside and outside.
    let q = Quadric::sphere(DVec3::new(1.0, 0.0, 0.0), 0.5).unwrap();
    let mirror = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0));
    let qm = q.transformed(&mirror).unwrap();
    assert!(qm.value(DVec3::new(-1.0, 0.0, 0.0)) < 0.0);
    assert!(qm.value(DVec3::new(1.0, 0.0, 0.0)) > 0.0);
}

#[test]
fn bad_transforms_are_errors() {
    let q = Quadric::sphere(DVec3::ZERO, 1.0).unwrap();
    assert_eq!(
        q.transformed(&DMat4::from_scale(DVec3::new(1.0, 1.0, 1e-20))),
        Err(Error::SingularTransform)
    );
    let mut p = DMat4::IDENTITY;
    p.w_axis.w = 2.0;
    assert_eq!(q.transformed(&p), Err(Error::NotAffine));
}
