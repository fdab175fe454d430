//! BSP trees and the convex cells of their leaves: cells tile the bounds
//! exactly (volumes add up to the bounds' volume, exactly), each is a valid
//! strictly convex polyhedron, and a convex polyhedron turned into a linear
//! BSP comes back as exactly one labelled cell of the same volume.

use crate::common;

use chisel_bsp::convex::{ConvexArena, PolyId};
use chisel_bsp::tree::{Bsp, EMPTY};
use common::shapes::{self, p};
use common::volume::{Fraction, volume};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn a_uniform_bsp_has_one_cell_the_bounds() {
    let mut arena = ConvexArena::new();
    let bounds = arena.add_box(p(0, 0, 0), p(4, 5, 6)).unwrap();
    let bsp = Bsp::uniform(3);
    bsp.validate().unwrap();
    let cells = bsp.cells(&mut arena, bounds);
    assert_eq!(cells.len(), 1);
    assert_eq!((cells[0].poly, cells[0].label), (bounds, 3));
    assert_eq!(volume(&arena, cells[0].poly).num, 120.into());
}

#[test]
fn a_convex_polyhedron_round_trips_through_its_linear_bsp() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..20 {
        let mut source = ConvexArena::new();
        let poly = shapes::random_convex(&mut source, &mut rng, [0; 3], 1 << 16, 12);
        let expected = volume(&source, poly);
        let bsp = Bsp::from_convex(&source, poly, 7);
        bsp.validate().unwrap();

        let mut arena = ConvexArena::new();
        let h = 1 << 18;
        let bounds = arena.add_box(p(-h, -h, -h), p(h, h, h)).unwrap();
        let bounds_volume = volume(&arena, bounds);
        let cells = bsp.cells(&mut arena, bounds);

        let solid: Vec<_> = cells.iter().filter(|c| c.label != EMPTY).collect();
        assert_eq!(solid.len(), 1, "one solid cell");
        assert_eq!(solid[0].label, 7);
        assert_eq!(
            volume(&arena, solid[0].poly),
            expected,
            "same volume, exactly"
        );
        let mut total = Fraction::zero();
        for cell in &cells {
            arena.validate(cell.poly).unwrap();
            let v = volume(&arena, cell.poly);
            assert!(v.is_positive());
            total = total.add(&v);
        }
        assert_eq!(total, bounds_volume, "the cells tile the bounds exactly");
        // The solid cell has exactly the source's face planes.
        let planes = |a: &ConvexArena, q: PolyId| {
            let mut v: Vec<_> = a
                .faces_of(q)
                .iter()
                .map(|&f| {
                    let plane = a.face_plane(f);
                    (plane.normal(), plane.offset())
                })
                .collect();
            v.sort();
            v
        };
        assert_eq!(planes(&arena, solid[0].poly), planes(&source, poly));
    }
}
