//! Principal frames: the eigen basis is orthonormal and right-handed for
//! singular, repeated and nearly repeated eigenvalues; centres are right.

use crate::common;

use chisel_quadric::{PrincipalFrame, Quadric, SymmetricEigen};
use glam::{DMat3, DVec2, DVec3};
use rand::Rng;

fn assert_valid(a: DMat3) -> SymmetricEigen {
    let e = SymmetricEigen::new(a);
    let u = e.vectors;
    assert!(
        (u.transpose() * u).abs_diff_eq(DMat3::IDENTITY, 1e-13),
        "not orthonormal for {a:?}"
    );
    assert!((u.determinant() - 1.0).abs() < 1e-13);
    let scale = a
        .to_cols_array()
        .iter()
        .fold(1e-300_f64, |s, x| s.max(x.abs()));
    for i in 0..3 {
        let r = a * u.col(i) - u.col(i) * e.values[i];
        assert!(r.length() <= 1e-12 * scale, "residual {r} for {a:?}");
    }
    assert!(e.values.x <= e.values.y && e.values.y <= e.values.z);
    e
}

fn rotated_diagonal(rng: &mut rand_chacha::ChaCha8Rng, d: DVec3) -> DMat3 {
    let r = DMat3::from_quat(common::rotation(rng));
    r * DMat3::from_diagonal(d) * r.transpose()
}

#[test]
fn singular_and_repeated_spectra() {
    let mut rng = common::rng(41);
    let spectra = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),  // rank 1 (two parallel planes)
        DVec3::new(0.0, 1.0, 1.0),  // circular cylinder
        DVec3::new(0.0, 1.0, 4.0),  // elliptic cylinder
        DVec3::new(-1.0, 1.0, 1.0), // circular cone / hyperboloid
        DVec3::new(2.0, 2.0, 2.0),  // sphere: every basis is an eigenbasis
        DVec3::new(1.0, 1.0 + 1e-12, 2.0),
        DVec3::new(1.0, 1.0 + 1e-7, 1.0 - 1e-7),
        DVec3::new(-3.0, 0.0, 3.0),
        DVec3::new(1e-9, 1.0, 1e9),
    ];
    for d in spectra {
        for _ in 0..200 {
            let e = assert_valid(rotated_diagonal(&mut rng, d));
            let mut sorted = [d.x, d.y, d.z];
            sorted.sort_by(f64::total_cmp);
            let scale = d.abs().max_element().max(1.0);
            for (got, want) in [e.values.x, e.values.y, e.values.z].iter().zip(sorted) {
                assert!((got - want).abs() <= 1e-12 * scale, "{got} vs {want}");
            }
        }
    }
}

#[test]
fn random_symmetric_matrices() {
    let mut rng = common::rng(42);
    for _ in 0..5000 {
        let mut k = [0.0; 6];
        for x in &mut k {
            *x = rng.random_range(-10.0..10.0);
        }
        let a = DMat3::from_cols(
            DVec3::new(k[0], k[1], k[2]),
            DVec3::new(k[1], k[3], k[4]),
            DVec3::new(k[2], k[4], k[5]),
        );
        assert_valid(a);
    }
}

#[test]
fn frames_of_every_kind_are_orthonormal() {
    let mut rng = common::rng(43);
    for kind in 0..common::KINDS * 50 {
        let q = common::quadric_of_kind(&mut rng, kind);
        let f = PrincipalFrame::new(&q);
        assert!((f.axes.transpose() * f.axes).abs_diff_eq(DMat3::IDENTITY, 1e-13));
        assert!(f.centre.is_finite());
        let x = common::point(&mut rng, 2.0);
        assert!((f.to_world(f.to_local(x)) - x).length() < 1e-12);
    }
}

#[test]
fn centres_and_ranks() {
    let mut rng = common::rng(44);
    for _ in 0..100 {
        let m = common::rigid(&mut rng);
        let apex = m.transform_point3(DVec3::ZERO);
        let cone = Quadric::cone(DVec3::ZERO, DVec3::Z, 0.5)
            .unwrap()
            .transformed(&m)
            .unwrap();
        let f = PrincipalFrame::new(&cone);
        assert_eq!(f.rank(), 3);
        assert!((f.centre - apex).length() < 1e-10, "{} vs {apex}", f.centre);
        // A cylinder's centre is the point of its axis nearest the origin.
        let axis = m.transform_vector3(DVec3::Z);
        let cyl = Quadric::elliptic_cylinder(DVec2::new(1.0, 2.0))
            .unwrap()
            .transformed(&m)
            .unwrap();
        let f = PrincipalFrame::new(&cyl);
        assert_eq!(f.rank(), 2);
        let nearest = apex - axis * axis.dot(apex);
        assert!((f.centre - nearest).length() < 1e-10);
        // A plane has rank 0 and an orthonormal frame all the same.
        let plane = Quadric::half_space(axis, 1.0).unwrap();
        assert_eq!(PrincipalFrame::new(&plane).rank(), 0);
    }
}
