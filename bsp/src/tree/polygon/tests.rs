//! Splits of polygons against a fresh computation of every part.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::classify::classify_corners;
use super::{Polygon, meet};
use crate::exact::{IntPoint, Plane, Point4, Sign};

/// Whether two vertices have the same digits and `f64`s.
fn same_digits(a: &Point4, b: &Point4) -> bool {
    a.xyz_digits == b.xyz_digits
        && a.w_digits == b.w_digits
        && a.approx.map(f64::to_bits) == b.approx.map(f64::to_bits)
}

fn random_point(rng: &mut ChaCha8Rng) -> IntPoint {
    let mut c = || rng.random_range(-1000..=1000);
    IntPoint::new(c(), c(), c()).expect("in budget")
}

/// A plane with a small random normal through `x`.
fn plane_through(rng: &mut ChaCha8Rng, x: IntPoint) -> Option<Plane> {
    let n = [0; 3].map(|_| rng.random_range(-20i64..=20));
    let d = -(0..3)
        .map(|i| i128::from(n[i]) * i128::from(x.coords()[i]))
        .sum::<i128>();
    (n != [0; 3]).then(|| Plane::new(n[0], n[1], n[2], d).expect("small coefficients"))
}

/// The parts of `triangle` after `rounds` splits by random planes, every
/// `corner_every`-th through one of its `corners` (so corners land on
/// the plane), and the planes used with their flips.
fn split_repeatedly(
    rng: &mut ChaCha8Rng,
    triangle: Polygon,
    corners: [IntPoint; 3],
    rounds: usize,
    corner_every: usize,
) -> (Vec<Polygon>, Vec<Plane>) {
    let mut pieces = vec![triangle];
    let mut planes = Vec::new();
    for round in 0..rounds {
        let x = if round % corner_every == 0 {
            corners[rng.random_range(0..3)]
        } else {
            random_point(rng)
        };
        let Some(plane) = plane_through(rng, x) else {
            continue;
        };
        planes.extend([plane, plane.flipped()]);
        pieces = pieces
            .into_iter()
            .flat_map(|piece| {
                let (below, above) = piece.split(&plane);
                below.into_iter().chain(above)
            })
            .collect();
    }
    (pieces, planes)
}

/// Every corner of every part, after repeated splits by random planes
/// (some through corners, so corners land on the plane), has exactly
/// the digits of a fresh meet of its planes: the corners a split takes
/// over from the original or from the other part are the right ones.
#[test]
fn split_parts_keep_exact_corners() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut checked = 0;
    for _ in 0..300 {
        let corners = [0; 3].map(|_| random_point(&mut rng));
        let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
            continue;
        };
        let (pieces, _) = split_repeatedly(&mut rng, triangle, corners, 6, 3);
        for piece in &pieces {
            let n = piece.edges.len();
            assert_eq!(piece.vertices().len(), n);
            for k in 0..n {
                let fresh = meet(
                    &piece.support,
                    &piece.edges[(k + n - 1) % n],
                    &piece.edges[k],
                );
                assert!(
                    same_digits(&piece.vertices()[k], &fresh),
                    "corner {k} of {n}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 3000, "only {checked} corners checked");
}

/// [`Polygon::parts_of`] a polygon read in place gives the parts
/// [`Polygon::split_known`] gives, plane for plane and corner for
/// corner, for every choice of wanted parts, for the parts of repeated
/// splits cut by random planes (some through corners).
#[test]
fn parts_of_agree_with_split_known() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let same = |a: &Option<Polygon>, b: &Option<Polygon>| match (a, b) {
        (Some(a), Some(b)) => {
            a.support == b.support
                && a.edges == b.edges
                && a.corners.len() == b.corners.len()
                && a.corners
                    .iter()
                    .zip(&b.corners)
                    .all(|(x, y)| same_digits(x, y))
        }
        (None, None) => true,
        _ => false,
    };
    let mut checked = 0;
    for _ in 0..200 {
        let corners = [0; 3].map(|_| random_point(&mut rng));
        let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
            continue;
        };
        let (pieces, _) = split_repeatedly(&mut rng, triangle, corners, 4, 2);
        for piece in &pieces {
            let x = if rng.random_range(0..3) == 0 {
                corners[rng.random_range(0..3)]
            } else {
                random_point(&mut rng)
            };
            let Some(p) = plane_through(&mut rng, x) else {
                continue;
            };
            let mut sides = vec![Sign::Zero; piece.vertices().len()];
            if piece.whole_side(&p, &mut sides).is_some() {
                continue;
            }
            for wanted in [[true, true], [true, false], [false, true], [false, false]] {
                let direct = Polygon::parts_of(
                    &piece.support,
                    |k| &piece.edges[k],
                    |k| &piece.corners[k],
                    &sides,
                    &p,
                    wanted,
                );
                let split = piece.clone().split_known(&sides, &p, wanted);
                assert!(same(&direct.0, &split.0) && same(&direct.1, &split.1));
                checked += 1;
            }
        }
    }
    assert!(checked > 500, "only {checked} splits checked");
}

/// [`Polygon::whole_side`], [`Polygon::side_of_plane`] and
/// [`Polygon::reaches_side`] agree with classifying every corner in full, for the parts of repeated splits
/// against the splitting planes (on which the parts have corners, found
/// without arithmetic) and their flips.
#[test]
fn whole_side_agrees_with_full_classification() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let (mut checked, mut touching) = (0, 0);
    for _ in 0..200 {
        let corners = [0; 3].map(|_| random_point(&mut rng));
        let Some(triangle) = Polygon::triangle(corners).expect("in budget") else {
            continue;
        };
        let (pieces, planes) = split_repeatedly(&mut rng, triangle, corners, 5, 2);
        for piece in &pieces {
            let n = piece.vertices().len();
            let (mut sides, mut exact) = (vec![Sign::Zero; n], vec![Sign::Zero; n]);
            for p in &planes {
                // Every corner classified in full, as the reference.
                let (below, above) = classify_corners(piece.vertices(), p, &mut exact);
                let expected = piece.side_from_corners(below, above, p);
                assert_eq!(piece.whole_side(p, &mut sides), expected);
                assert_eq!(sides, exact);
                assert_eq!(piece.side_of_plane(p), expected);
                for above in [false, true] {
                    let reaches = expected.is_none_or(|side| side == above);
                    assert_eq!(piece.reaches_side(p, above), reaches);
                }
                touching += usize::from(exact.contains(&Sign::Zero));
                checked += 1;
            }
        }
    }
    assert!(
        checked > 2000 && touching > 500,
        "{checked} checked, {touching} touching"
    );
}
