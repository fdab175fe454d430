//! The invariants of a [`SurfaceMesh`], checked exactly.
//!
//! Combinatorial: every corner names a vertex, polygons have at least three
//! original corners, `originals` starts at 0 and increases strictly, no two
//! consecutive corners are the same vertex. Geometric (exact): vertices are
//! pairwise distinct points; original corner `k` lies on the support plane
//! and on edge planes `k − 1` and `k`; every inserted corner lies strictly
//! inside its original edge (the test of [`super::tjunction`]), in order
//! along it.

use core::cmp::Ordering;

use super::SurfaceMesh;
use super::tjunction::strictly_inside_edge;
use super::weld::Welder;
use crate::exact::{Sign, classify_vertex, compare_offsets};

/// A broken invariant of a surface mesh: always a bug in the kernel, never
/// bad input.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("surface mesh invariant broken: {0}")]
pub struct MeshInvariantError(pub String);

macro_rules! ensure {
    ($cond:expr, $($msg:tt)*) => {
        if !$cond {
            return Err(MeshInvariantError(format!($($msg)*)));
        }
    };
}

impl SurfaceMesh {
    /// Checks every invariant (cost `O(corners)` exact classifications).
    ///
    /// # Errors
    /// The first broken invariant found.
    pub fn validate(&self) -> Result<(), MeshInvariantError> {
        let vertices = self.vertices();
        let mut welder = Welder::with_capacity(vertices.len());
        for (i, v) in vertices.iter().enumerate() {
            ensure!(
                welder.index(v) as usize == i,
                "vertex {i} is at the same position as an earlier vertex"
            );
        }
        for (f, p) in self.polygons().iter().enumerate() {
            let n = p.original_len();
            ensure!(n >= 3, "polygon {f} has {n} edge planes");
            ensure!(
                p.originals.len() == n,
                "polygon {f}: {} original corners for {n} edges",
                p.originals.len()
            );
            ensure!(
                p.originals.first() == Some(&0),
                "polygon {f}: the first corner is not original"
            );
            ensure!(
                p.originals.windows(2).all(|w| w[0] < w[1])
                    && p.originals.iter().all(|&o| (o as usize) < p.corners.len()),
                "polygon {f}: original corner positions {:?} are not increasing within {} corners",
                p.originals,
                p.corners.len()
            );
            ensure!(
                p.corners.iter().all(|&c| (c as usize) < vertices.len()),
                "polygon {f} names a vertex beyond {}",
                vertices.len()
            );
            let len = p.corners.len();
            ensure!(
                (0..len).all(|k| p.corners[k] != p.corners[(k + 1) % len]),
                "polygon {f} repeats a vertex in consecutive corners"
            );
            for k in 0..n {
                let c = &vertices[p.corners[p.originals[k] as usize] as usize];
                let on = [&p.plane, &p.edges[(k + n - 1) % n], &p.edges[k]]
                    .iter()
                    .all(|s| classify_vertex(c, s) == Sign::Zero);
                ensure!(on, "polygon {f}: corner {k} is not the meet of its planes");
                let previous = &p.edges[(k + n - 1) % n];
                let inserted = &p.corners[p.inserted_on_edge(k)];
                for (i, &w) in inserted.iter().enumerate() {
                    ensure!(
                        strictly_inside_edge(&vertices[w as usize], p, k),
                        "polygon {f}: inserted vertex {w} is not strictly inside edge {k}"
                    );
                    if i > 0 {
                        let order = compare_offsets(
                            &vertices[inserted[i - 1] as usize],
                            &vertices[w as usize],
                            previous,
                        );
                        ensure!(
                            order == Ordering::Greater,
                            "polygon {f}: inserted vertices on edge {k} are out of order"
                        );
                    }
                }
            }
        }
        Ok(())
    }
}
