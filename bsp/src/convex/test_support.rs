//! What the convex module's tests share: the box polyhedra start from,
//! random planes around it, and element-for-element comparison of arenas.

use super::{ConvexArena, PolyId};
use crate::exact::{IntPoint, Plane};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Half the edge of the box the polyhedra start from.
pub(crate) const R: i64 = 1 << 20;

/// The cube `[-R, R]³`.
pub(crate) fn cube(arena: &mut ConvexArena) -> PolyId {
    let corner = |c| IntPoint::new(c, c, c).expect("in budget");
    arena.add_box(corner(-R), corner(R)).expect("a box")
}

/// A plane with a normal of length about `scale` in a random direction, at
/// a distance from the origin (outward) drawn from `radii` times `R`: with
/// radii near 1, chains of cuts keeping the part below build large round
/// polyhedra.
pub(crate) fn random_plane(rng: &mut ChaCha8Rng, scale: f64, radii: std::ops::Range<f64>) -> Plane {
    loop {
        let v = [0; 3].map(|_| rng.random_range(-1.0..1.0f64));
        let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if !(0.1..=1.0).contains(&len) {
            continue;
        }
        let n = v.map(|c| (c / len * scale).round() as i64);
        let norm = ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) as f64).sqrt();
        let radius = rng.random_range(radii.clone()) * R as f64;
        let d = -(radius * norm).round() as i128;
        return Plane::new(n[0], n[1], n[2], d).expect("in budget");
    }
}

/// [`random_plane`] with a normal of about 2^10, tangent to a sphere of
/// radius `0.8 R … 0.99 R`.
pub(crate) fn tangent_plane(rng: &mut ChaCha8Rng) -> Plane {
    random_plane(rng, 1024.0, 0.8..0.99)
}

/// Element-for-element equality of two arenas.
pub(crate) fn assert_same_arena(a: &ConvexArena, b: &ConvexArena) {
    assert_eq!(a.half_edges, b.half_edges);
    assert_eq!(a.faces.len(), b.faces.len());
    for (x, y) in a.faces.iter().zip(&b.faces) {
        assert_eq!((x.half_edge, x.tag), (y.half_edge, y.tag));
        assert_eq!(a.planes[x.plane as usize], b.planes[y.plane as usize]);
    }
    assert_eq!(a.vertices.len(), b.vertices.len());
    for v in 0..a.vertices.len() as u32 {
        assert_eq!(a.vertex_half_edge(v), b.vertex_half_edge(v));
        let (p, q) = (a.point(v), b.point(v));
        assert_eq!((p.xyz_digits, p.w_digits), (q.xyz_digits, q.w_digits));
    }
}
