//! Random convex operands for BSP tests and benchmarks.

use chisel_bsp::convex::{ConvexArena, CutOutcome, NO_TAG, PolyId};
use chisel_bsp::exact::{IntPoint, plane_from_points};
use chisel_bsp::octree::Tool;
use chisel_bsp::tools::{Pose, dodecahedron_corners};
use chisel_bsp::tree::{Bsp, Label};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

pub fn p(x: i64, y: i64, z: i64) -> IntPoint {
    IntPoint::new(x, y, z).expect("test points are in budget")
}

/// A box of half-size `r` around `centre`, cut `cuts` times by random planes
/// through points inside it, keeping the part below each.
pub fn random_convex(
    arena: &mut ConvexArena,
    rng: &mut ChaCha8Rng,
    centre: [i64; 3],
    r: i64,
    cuts: usize,
) -> PolyId {
    let c = centre;
    let mut poly = arena
        .add_box(
            p(c[0] - r, c[1] - r, c[2] - r),
            p(c[0] + r, c[1] + r, c[2] + r),
        )
        .expect("a box");
    let mut q = || {
        p(
            c[0] + rng.random_range(-r..r),
            c[1] + rng.random_range(-r..r),
            c[2] + rng.random_range(-r..r),
        )
    };
    for _ in 0..cuts {
        let Ok(s) = plane_from_points(q(), q(), q()) else {
            continue;
        };
        if let CutOutcome::Split { below, .. } = arena.cut(poly, &s.normalized(), NO_TAG, NO_TAG) {
            poly = below;
        }
    }
    poly
}

/// A random convex polyhedron centred within `spread` of the origin, with
/// half-size in `[min_r, max_r)`, as a linear BSP labelled `label`.
pub fn random_convex_bsp(
    rng: &mut ChaCha8Rng,
    label: Label,
    spread: i64,
    (min_r, max_r): (i64, i64),
    cuts: usize,
) -> Bsp {
    let mut arena = ConvexArena::new();
    let centre = [0; 3].map(|_| rng.random_range(-spread..spread));
    let r = rng.random_range(min_r..max_r);
    let poly = random_convex(&mut arena, rng, centre, r, cuts);
    Bsp::from_convex(&arena, poly, label)
}

/// A random turn: `a` about z after `b` about x, each drawn from
/// `[0, 6.3)` radians, in that order.
pub fn random_rotation(rng: &mut ChaCha8Rng) -> [[f64; 3]; 3] {
    let (a, b) = (rng.random_range(0.0..6.3f64), rng.random_range(0.0..6.3f64));
    let (ca, sa, cb, sb) = (a.cos(), a.sin(), b.cos(), b.sin());
    [
        [ca, -sa * cb, sa * sb],
        [sa, ca * cb, -ca * sb],
        [0.0, sb, cb],
    ]
}

/// The dodecahedron of [`dodecahedron_corners`]`(scale)`, turned by
/// `rotation` and centred at `at` (grid units).
pub fn placed_dodecahedron(scale: f64, rotation: [[f64; 3]; 3], at: [f64; 3]) -> Tool {
    let pose = Pose {
        rotation,
        translation: at,
    };
    Tool::placed(&dodecahedron_corners(scale), &pose).expect("a dodecahedron in budget")
}
