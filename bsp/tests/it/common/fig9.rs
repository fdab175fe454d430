//! The planes of paper 1's Figure 9 setting, shared by the `cut` benchmark
//! and the `fig9_cuts` instruction-count bench: planes tangent to the
//! sphere of radius `0.95 R` inscribed in the box `[-R, R]³`, with integer
//! normals of length about 2^10 in random directions, outward.

use chisel_bsp::exact::Plane;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Half the edge of the box the cell starts from.
pub const R: i64 = 1 << 20;

/// An integer vector of length about `scale` in a uniformly random
/// direction.
pub fn random_direction(rng: &mut ChaCha8Rng, scale: f64) -> [i64; 3] {
    loop {
        let v = [0; 3].map(|_| rng.random_range(-1.0..1.0f64));
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if (0.1..=1.0).contains(&n) {
            return v.map(|c| (c / n * scale).round() as i64);
        }
    }
}

/// `count` planes tangent to the sphere of radius `0.95 R` in random
/// directions drawn from `seed`, outward.
pub fn tangent_planes(count: usize, seed: u64) -> Vec<Plane> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let radius = 0.95 * R as f64;
    (0..count)
        .map(|_| {
            let n = random_direction(&mut rng, 1024.0);
            let len = ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) as f64).sqrt();
            Plane::new(n[0], n[1], n[2], -(radius * len).round() as i128).expect("in budget")
        })
        .collect()
}
