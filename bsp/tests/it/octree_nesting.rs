//! Nesting of a mesh's shells on import: shells must nest as a solid's
//! boundary (an outward shell inside no outward shell, a cavity directly
//! inside one), decided exactly by winding numbers. A shell nested in
//! another with the same orientation is refused with
//! [`Error::MisnestedShell`] (before: accepted, with a volume matching
//! neither the even-odd nor the nonzero reading).

use chisel_bsp::Error;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::{Octree, OctreeConfig};

type Tri = [IntPoint; 3];

fn p(x: i64, y: i64, z: i64) -> IntPoint {
    IntPoint::new(x, y, z).unwrap()
}

/// The box `lo..hi`, counter-clockwise seen from outside (outward); with
/// `cavity` every face reversed.
fn cuboid(lo: [i64; 3], hi: [i64; 3], cavity: bool) -> Vec<Tri> {
    let c = |i: usize, j: usize, k: usize| {
        let pick = |a: usize, bit: usize| if bit == 0 { lo[a] } else { hi[a] };
        p(pick(0, i), pick(1, j), pick(2, k))
    };
    let quads = [
        [c(0, 0, 0), c(0, 0, 1), c(0, 1, 1), c(0, 1, 0)],
        [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)],
        [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)],
        [c(0, 1, 0), c(0, 1, 1), c(1, 1, 1), c(1, 1, 0)],
        [c(0, 0, 0), c(0, 1, 0), c(1, 1, 0), c(1, 0, 0)],
        [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)],
    ];
    quads
        .iter()
        .flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]])
        .map(|[a, b, c]| if cavity { [a, c, b] } else { [a, b, c] })
        .collect()
}

fn volume(lo: [i64; 3], hi: [i64; 3]) -> f64 {
    (0..3).map(|a| (hi[a] - lo[a]) as f64).product()
}

fn import(shells: &[Vec<Tri>]) -> Result<Octree, Error> {
    let triangles: Vec<Tri> = shells.concat();
    let config = OctreeConfig {
        max_bsp_nodes: 150,
        max_depth: 8,
    };
    Octree::from_triangles([0; 3], 10, &triangles, 1, config)
}

fn assert_volume(octree: &Octree, expected: f64) {
    let got = octree.solid_volume();
    assert!(
        (got - expected).abs() <= 1e-9 * expected,
        "volume {got}, expected {expected}"
    );
}

const OUTER: ([i64; 3], [i64; 3]) = ([100; 3], [900; 3]);

#[test]
fn a_shell_inside_a_shell_of_the_same_orientation_is_refused() {
    let (lo, hi) = OUTER;
    let inner = ([300; 3], [600; 3]);
    let err = import(&[cuboid(lo, hi, false), cuboid(inner.0, inner.1, false)]).unwrap_err();
    match &err {
        Error::MisnestedShell {
            volume: v,
            winding,
            shell,
        } => {
            assert_eq!(*winding, 1);
            assert_eq!(*v, volume(inner.0, inner.1));
            assert!(shell.contains("[300, 300, 300]"), "{shell}");
        }
        other => panic!("expected a misnested shell, got {other:?}"),
    }
    let message = err.to_string();
    assert!(message.contains("Reverse the faces"), "{message}");
    // The same order of shells the other way round: the outer one is
    // found inside nothing, the inner one inside the outer.
    assert!(matches!(
        import(&[cuboid(inner.0, inner.1, false), cuboid(lo, hi, false)]),
        Err(Error::MisnestedShell { winding: 1, .. })
    ));
    // Reversed, the inner shell is a cavity: accepted, exact volume.
    let octree = import(&[cuboid(lo, hi, false), cuboid(inner.0, inner.1, true)]).unwrap();
    assert_volume(&octree, volume(lo, hi) - volume(inner.0, inner.1));
}

#[test]
fn islands_in_cavities_nest_and_cavities_in_cavities_do_not() {
    let (lo, hi) = OUTER;
    let (cavity, island) = (([200; 3], [800; 3]), ([300; 3], [700; 3]));
    let octree = import(&[
        cuboid(lo, hi, false),
        cuboid(cavity.0, cavity.1, true),
        cuboid(island.0, island.1, false),
    ])
    .unwrap();
    assert_volume(
        &octree,
        volume(lo, hi) - volume(cavity.0, cavity.1) + volume(island.0, island.1),
    );
    // A cavity inside a cavity: the space between them would be counted
    // -1 times, and the inner cavity lies inside the outer's box, so only
    // the winding number sees it.
    assert!(matches!(
        import(&[
            cuboid(lo, hi, false),
            cuboid(cavity.0, cavity.1, true),
            cuboid(island.0, island.1, true),
        ]),
        Err(Error::MisnestedShell { winding: 0, .. })
    ));
    // Two outward boxes side by side, one with a cavity.
    let beside = ([920, 100, 100], [1000, 200, 200]);
    let octree = import(&[
        cuboid(lo, hi, false),
        cuboid(cavity.0, cavity.1, true),
        cuboid(beside.0, beside.1, false),
    ])
    .unwrap();
    assert_volume(
        &octree,
        volume(lo, hi) - volume(cavity.0, cavity.1) + volume(beside.0, beside.1),
    );
}

/// Inner boxes placed so that the test rays run through the outer box's
/// edges, diagonals and corners (symmetric boxes put the points tested on
/// the faces' diagonals): the verdict never depends on such coincidences.
#[test]
fn the_verdict_is_exact_when_rays_run_through_edges_and_corners() {
    let (lo, hi) = OUTER;
    let ends = [100 + 1, 250, 400, 500, 700, 900 - 1];
    let mut cases = 0;
    for (i, &a) in ends.iter().enumerate() {
        for &b in &ends[i + 1..] {
            for &c in &ends[..3] {
                let inner_lo = [a, c, a];
                let inner_hi = [b, c + 150, b];
                for (cavity, first) in [(false, false), (true, false), (false, true), (true, true)]
                {
                    let (outer, inner) =
                        (cuboid(lo, hi, false), cuboid(inner_lo, inner_hi, cavity));
                    let shells = if first {
                        [inner, outer]
                    } else {
                        [outer, inner]
                    };
                    let result = import(&shells);
                    if cavity {
                        assert_volume(
                            &result.unwrap(),
                            volume(lo, hi) - volume(inner_lo, inner_hi),
                        );
                    } else {
                        assert!(
                            matches!(result, Err(Error::MisnestedShell { winding: 1, .. })),
                            "{inner_lo:?}..{inner_hi:?}: {result:?}"
                        );
                    }
                    cases += 1;
                }
            }
        }
    }
    assert_eq!(cases, 15 * 3 * 4);
}
