//! `chisel cheese`: many small dodecahedra subtracted from a cube, at
//! seeded random sizes, rotations and places.

use chisel_bsp::octree::CellBox;
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::sequence::{Base, Op, Sequence, Step, UNITS_PER_MM};

/// Block `[0,100]³` mm.
const BLOCK_MM: f64 = 100.0;
/// Scale (half the edge of the inscribed cube) uniform in [2, 5] mm.
const SCALE_MM: [f64; 2] = [2.0, 5.0];
/// Centres: x, y uniform in [0, 100], z in [60, 100] mm.
const XY_MM: [f64; 2] = [0.0, 100.0];
const Z_MM: [f64; 2] = [60.0, 100.0];

/// A uniformly random rotation (unit quaternion from three uniforms), as
/// a row-major matrix.
fn random_rotation(rng: &mut impl Rng) -> [[f64; 3]; 3] {
    let [u1, u2, u3]: [f64; 3] = [rng.random(), rng.random(), rng.random()];
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let [w, x, y, z] = [
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    ];
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// The scenario with `count` carves from RNG seed `seed` (ChaCha8).
///
/// # Errors
/// Never for in-range sizes; a message if a tool leaves the exact range.
pub fn sequence(count: usize, seed: u64) -> Result<Sequence, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let steps = (0..count)
        .map(|_| {
            let scale = rng.random_range(SCALE_MM[0]..=SCALE_MM[1]);
            let rotation = random_rotation(&mut rng);
            let centre = [
                rng.random_range(XY_MM[0]..=XY_MM[1]),
                rng.random_range(XY_MM[0]..=XY_MM[1]),
                rng.random_range(Z_MM[0]..=Z_MM[1]),
            ];
            let pose = Pose {
                rotation,
                translation: centre.map(|c| c * UNITS_PER_MM),
            };
            let hull = dodecahedron_corners(scale * UNITS_PER_MM)
                .into_iter()
                .map(|c| pose.place(c).map(|p| p.coords()).map_err(|e| e.to_string()))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Step {
                op: Op::Subtract,
                hull,
            })
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(Sequence {
        base: Base::Box(CellBox {
            min: [0; 3],
            max: [(BLOCK_MM * UNITS_PER_MM) as i64; 3],
        }),
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_are_orthonormal() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..100 {
            let r = random_rotation(&mut rng);
            for i in 0..3 {
                for j in 0..3 {
                    let dot: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((dot - want).abs() < 1e-12);
                }
            }
            let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
                - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
                + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
            assert!((det - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_carves() {
        let a = sequence(20, 3).unwrap();
        assert_eq!(a, sequence(20, 3).unwrap());
        assert_ne!(a, sequence(20, 4).unwrap());
        for s in &a.steps {
            assert_eq!(s.hull.len(), 20);
            // Circumradius √3 · scale ≤ 8.67 mm around a centre in the ranges.
            assert!(s.hull.iter().all(|p| p[2] > 50_000 && p[2] < 109_000));
        }
    }
}
