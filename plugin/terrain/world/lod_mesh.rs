//! Coarse meshes of a chunk, one per level of detail, with their errors:
//! the source sampled at a coarser lattice (a chunk nobody carved), or the
//! chunk's exact surface simplified by vertex clustering (an edited
//! chunk); both with skirts down to the floor along the chunk's sides.
//!
//! Notation: `s` — the sample spacing, `E` — the chunk edge, `n = E / s`
//! squares per chunk side, `K = log2 n` the coarsest level; `k` a level
//! in `1..=K`, `m = 2^k`; `h(i, j)` — the source's grid height of sample
//! `(i, j)`; `C_k` — the coarse surface of level `k`; `e_k` — its error,
//! in grid units.
//!
//! **Unedited chunk, level `k`**: the samples `(m·I, m·J)`, squares of
//! side `m·s` split along the same diagonal as the source's (from
//! `(I+1, J)` to `(I, J+1)`). Every coarse edge then runs along edges of
//! the exact surface, so `C_k − exact` is linear on each exact triangle
//! and `e_k = max |h(i, j) − C_k(i, j)|` over the chunk's samples: the
//! exact largest vertical distance (computed in integers, scaled by `m`).
//!
//! **Edited chunk, level `k`**: vertex clustering of the chunk's exact
//! surface (welded, T-junctions split; side walls and floor left out) on cubes of edge
//! `c_k = s·2^(k−1)` aligned with the chunk's cube. A cluster's vertex is
//! the mean of its members, which lies in its cube, so every coarse vertex
//! is within the cube diagonal `√3·c_k` of an exact vertex, and every
//! point of a coarse triangle (the same convex combination of its
//! corners) within `e_k = √3·c_k` of a point of the exact triangle it
//! came from. Vertices on a side of the chunk are clustered apart from the
//! rest (per side), so the coarse border stays in the side's plane.
//!
//! The border of an edited chunk is kept exact: vertices on a side are not
//! clustered.
//!
//! **Skirts**: every border edge (in a side's plane, used by one coarse
//! triangle) hangs a vertical strip facing out of the chunk, `2·D_side + 1`
//! grid units deep (`skirt_depths`): `D_side` bounds how far any level's
//! border lies from the exact one along that side (unedited chunks
//! interpolate the side's samples; edited ones keep the exact border, and
//! a carve that changes a border edits both chunks on it). Two chunks'
//! borders on a shared side are thus at most `2·D_side` apart, and the
//! higher one's strip (or a full-detail chunk's wall, down to the floor)
//! closes the gap: no crack between two levels.

use std::collections::HashMap;

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use chisel_bsp::mesh::SurfaceMesh;
use chisel_bsp::octree::Octree;
use chisel_bsp::tree::{EMPTY, Label};

use super::super::error::TerrainError;
use super::ChunkCoord;
use super::source::{WorldLayout, WorldSource};
use crate::terrain::base::TerrainBase;

/// One level of a chunk's coarse meshes.
#[derive(Clone, Debug)]
pub struct LevelMesh {
    /// The level (1 is the finest coarse level).
    pub level: u8,
    /// The geometric error bound `e_k`, in world units (see the module
    /// docs for what it bounds in each case).
    pub error: f32,
    /// One mesh per material, in the world's local frame, skirts
    /// included.
    pub meshes: Vec<(Label, Mesh)>,
    /// Triangles, skirts included.
    pub triangles: usize,
    /// Bytes of vertex and index data.
    pub bytes: usize,
}

/// What a chunk's coarse meshes were made from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LodBasis {
    /// The source (the chunk is not edited).
    Source,
    /// The exact solid of the edited chunk with this state hash.
    Edited(u64),
}

/// A chunk's coarse meshes of every level, finest first.
#[derive(Clone, Debug)]
pub struct LodPyramid {
    /// What they were made from.
    pub basis: LodBasis,
    /// Levels `1..=K`, at index `k − 1`.
    pub levels: Vec<LevelMesh>,
}

impl LodPyramid {
    /// The errors of the levels, in world units, finest first.
    #[must_use]
    pub fn errors(&self) -> Vec<f32> {
        self.levels.iter().map(|l| l.error).collect()
    }
}

/// The coarsest level a chunk of `layout` has (`K = chunk_log2 −
/// spacing_log2`).
#[must_use]
pub fn coarsest_level(layout: &WorldLayout) -> u8 {
    layout.chunk_log2.saturating_sub(layout.spacing_log2)
}

/// The material on top of an unedited chunk: the shallowest band's, or
/// the solid's.
fn surface_label(layout: &WorldLayout) -> Label {
    layout
        .layers
        .iter()
        .min_by_key(|&&(depth, _)| depth)
        .map_or(layout.label, |&(_, label)| label)
}

/// The coarse meshes of unedited chunk `coord`, every level.
///
/// # Errors
/// As [`WorldLayout::chunk_base`] (a bad source sample).
pub fn source_pyramid(
    layout: &WorldLayout,
    source: &dyn WorldSource,
    coord: ChunkCoord,
) -> Result<LodPyramid, TerrainError> {
    let TerrainBase::Heightfield { field, .. } = layout.chunk_base(source, coord)? else {
        unreachable!("a world chunk's base is a heightfield");
    };
    let side = field.samples[0] as usize;
    let n = side - 1;
    let origin = layout.chunk_origin(coord);
    let label = surface_label(layout);
    let box_ = ChunkBox::of(layout, coord);
    let skirt = skirt_depths(layout, &field.heights);
    let levels = (1..=coarsest_level(layout))
        .map(|k| {
            let m = 1usize << k;
            let h = |i: usize, j: usize| field.heights[i + j * side];
            let error = heightfield_error(&h, n, m);
            let coarse = n / m;
            let mut mesh = MeshBuilder::default();
            let at = |i: usize, j: usize| {
                layout.quantization.to_world(
                    [
                        origin[0] + (i * m) as i64 * field.spacing,
                        h(i * m, j * m),
                        origin[2] + (j * m) as i64 * field.spacing,
                    ]
                    .map(|c| c as f64),
                )
            };
            let vertex = |i: usize, j: usize| (i + j * (coarse + 1)) as u32;
            let points: Vec<[f64; 3]> = (0..=coarse)
                .flat_map(|j| (0..=coarse).map(move |i| (i, j)))
                .map(|(i, j)| at(i, j))
                .collect();
            let mut triangles = Vec::with_capacity(2 * coarse * coarse);
            for j in 0..coarse {
                for i in 0..coarse {
                    let (v00, v10) = (vertex(i, j), vertex(i + 1, j));
                    let (v01, v11) = (vertex(i, j + 1), vertex(i + 1, j + 1));
                    triangles.push([v00, v01, v10]);
                    triangles.push([v10, v01, v11]);
                }
            }
            mesh.surface(&points, &triangles);
            let edges: Vec<(u32, u32, u8)> = boundary_on_sides(&triangles, &points, &box_)
                .into_iter()
                .map(|(a, b, side, _)| (a, b, side))
                .collect();
            mesh.strips(&points, &edges, &skirt);
            level_mesh(k, error * layout.quantization.unit(), vec![(label, mesh)])
        })
        .collect();
    Ok(LodPyramid {
        basis: LodBasis::Source,
        levels,
    })
}

/// `e_k` of a heightfield of `n × n` squares at level step `m`, in grid
/// units: the largest `|h − C_k|` over the samples, computed exactly as
/// `m·h − m·C_k` in integers.
fn heightfield_error(h: &impl Fn(usize, usize) -> i64, n: usize, m: usize) -> f64 {
    let mi = m as i128;
    let mut worst = 0i128;
    for j in 0..=n {
        for i in 0..=n {
            // The coarse square holding (i, j), and (u, v)·m inside it.
            let (ci, cj) = ((i / m).min(n / m - 1), (j / m).min(n / m - 1));
            let (u, v) = ((i - ci * m) as i128, (j - cj * m) as i128);
            let c = |a: usize, b: usize| i128::from(h((ci + a) * m, (cj + b) * m));
            let (h00, h10, h01, h11) = (c(0, 0), c(1, 0), c(0, 1), c(1, 1));
            // m·C: the triangle (00, 01, 10) where u + v <= m, else
            // (10, 01, 11).
            let scaled = if u + v <= mi {
                h00 * mi + u * (h10 - h00) + v * (h01 - h00)
            } else {
                h11 * mi + (mi - u) * (h01 - h11) + (mi - v) * (h10 - h11)
            };
            worst = worst.max((i128::from(h(i, j)) * mi - scaled).abs());
        }
    }
    worst as f64 / m as f64
}

/// The coarse meshes of an edited chunk, every level, by vertex clustering
/// of its exact surface.
///
/// # Errors
/// As [`WorldLayout::chunk_base`] (the source's samples give the skirts).
pub fn edited_pyramid(
    layout: &WorldLayout,
    source: &dyn WorldSource,
    coord: ChunkCoord,
    octree: &Octree,
    state_hash: u64,
) -> Result<LodPyramid, TerrainError> {
    let TerrainBase::Heightfield { field, .. } = layout.chunk_base(source, coord)? else {
        unreachable!("a world chunk's base is a heightfield");
    };
    let skirt = skirt_depths(layout, &field.heights);
    let q = &layout.quantization;
    // Every exact triangle of the surface, in the world's local frame,
    // with its material: the whole chunk's surface welded, with no
    // T-junction between cells (a vertex in the middle of a neighbour's
    // edge would open a gap once clustered).
    let surface = SurfaceMesh::from_face_vec(octree.surface());
    let positions: Vec<[f64; 3]> = (0..surface.vertices().len() as u32)
        .map(|v| q.to_world(surface.position(v)))
        .collect();
    let exact: Vec<(Label, [[f64; 3]; 3])> = surface
        .polygons()
        .iter()
        .filter(|p| p.outside == EMPTY)
        .flat_map(|p| {
            p.triangulate()
                .into_iter()
                .map(|t| (p.label, t.map(|v| positions[v as usize])))
        })
        .collect();
    let box_ = ChunkBox::of(layout, coord);
    let exact: Vec<(Label, [[f64; 3]; 3])> = exact
        .into_iter()
        .filter(|(_, t)| !box_.is_wall(t))
        .collect();
    let unit = q.unit();
    let levels = (1..=coarsest_level(layout))
        .map(|k| {
            let cell = (layout.spacing() << (k - 1)) as f64 * unit;
            let meshes = cluster(&exact, &box_, cell, &skirt);
            level_mesh(k, 3f64.sqrt() * cell, meshes)
        })
        .collect();
    Ok(LodPyramid {
        basis: LodBasis::Edited(state_hash),
        levels,
    })
}

/// The skirt depth of each side (`-x`, `+x`, `-z`, `+z`), in world units:
/// `2·D + 1` grid units, `D` the largest vertical distance, over every
/// level, between the side's samples and their level's interpolation
/// along the side. It depends only on the side's samples, which the two
/// chunks sharing the side read alike, so both hang the same depth, and
/// any two levels' borders there (or a level's and the exact one) are
/// at most `2·D` apart.
fn skirt_depths(layout: &WorldLayout, heights: &[i64]) -> [f64; 4] {
    let side = (1usize << coarsest_level(layout)) + 1;
    let line = |s: usize| -> Vec<i64> {
        (0..side)
            .map(|t| match s {
                0 => heights[t * side],
                1 => heights[side - 1 + t * side],
                2 => heights[t],
                _ => heights[t + (side - 1) * side],
            })
            .collect()
    };
    [0, 1, 2, 3].map(|s| {
        let h = line(s);
        let mut worst = 0i128;
        for k in 1..=coarsest_level(layout) {
            let m = 1usize << k;
            for (t, &ht) in h.iter().enumerate() {
                let c = (t / m).min((side - 1) / m - 1) * m;
                let (a, b) = (i128::from(h[c]), i128::from(h[c + m]));
                let u = (t - c) as i128;
                let scaled = a * m as i128 + u * (b - a);
                worst = worst.max((i128::from(ht) * m as i128 - scaled).abs() / m as i128 + 1);
            }
        }
        (2 * worst + 1) as f64 * layout.quantization.unit()
    })
}

/// Vertex clustering of `exact` on cubes of edge `cell` (world units),
/// one mesh per material, with skirts.
fn cluster(
    exact: &[(Label, [[f64; 3]; 3])],
    box_: &ChunkBox,
    cell: f64,
    skirt: &[f64; 4],
) -> Vec<(Label, MeshBuilder)> {
    let cells = ((box_.max[0] - box_.min[0]) / cell).round().max(1.0) as i64;
    // Cluster key: the cube, or for a vertex on a side the vertex itself
    // (the border stays exact).
    let key = |p: [f64; 3]| {
        let sides = box_.sides_of(p);
        if sides != 0 {
            return (p.map(|c| c.to_bits() as i64), 0x10 | sides);
        }
        let c = |a: usize| (((p[a] - box_.min[a]) / cell).floor() as i64).clamp(0, cells - 1);
        ([c(0), c(1), c(2)], 0)
    };
    let mut ids: HashMap<([i64; 3], u8), u32> = HashMap::new();
    let mut sums: Vec<([f64; 3], u32, [f64; 3])> = Vec::new();
    let mut triangles: Vec<(Label, [u32; 3])> = Vec::with_capacity(exact.len() / 4);
    for (label, t) in exact {
        let v = t.map(|p| {
            let next = sums.len() as u32;
            let id = *ids.entry(key(p)).or_insert(next);
            if id == next {
                sums.push(([0.0; 3], 0, p));
            }
            let s = &mut sums[id as usize];
            for (sum, c) in s.0.iter_mut().zip(p) {
                *sum += c;
            }
            s.1 += 1;
            id
        });
        triangles.push((*label, v));
    }
    // Each exact vertex is counted once per triangle around it: the mean
    // is weighted by valence, still a convex combination of members.
    // Border vertices keep their exact position.
    let points: Vec<[f64; 3]> = sums
        .iter()
        .map(|(s, count, first)| {
            if box_.sides_of(*first) != 0 {
                *first
            } else {
                s.map(|c| c / f64::from(*count))
            }
        })
        .collect();
    triangles.retain(|(_, [a, b, c])| a != b && b != c && c != a);
    // The same triangle (up to rotation) from several exact ones: once.
    let canonical = |t: [u32; 3]| {
        let r = (0..3).min_by_key(|&r| t[r]).unwrap_or(0);
        [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
    };
    triangles.sort_by_key(|&(label, t)| (label, canonical(t)));
    triangles.dedup_by_key(|(label, t)| (*label, canonical(*t)));
    let mut labels: Vec<Label> = triangles.iter().map(|t| t.0).collect();
    labels.dedup();
    let all: Vec<[u32; 3]> = triangles.iter().map(|t| t.1).collect();
    // Border edges over all materials; each strip takes its triangle's.
    let borders = boundary_on_sides(&all, &points, box_);
    labels
        .into_iter()
        .map(|label| {
            let mine: Vec<[u32; 3]> = triangles
                .iter()
                .filter(|t| t.0 == label)
                .map(|t| t.1)
                .collect();
            let mut mesh = MeshBuilder::default();
            mesh.surface(&points, &mine);
            let edges: Vec<(u32, u32, u8)> = borders
                .iter()
                .filter(|&&(_, _, _, t)| triangles[t].0 == label)
                .map(|&(a, b, side, _)| (a, b, side))
                .collect();
            mesh.strips(&points, &edges, skirt);
            (label, mesh)
        })
        .collect()
}

/// A chunk's cube in the world's local frame.
struct ChunkBox {
    min: [f64; 3],
    max: [f64; 3],
    /// Distance within which a point counts as on a side.
    tolerance: f64,
}

/// The four sides, as bits: `-x`, `+x`, `-z`, `+z`.
const SIDES: [(usize, bool); 4] = [(0, false), (0, true), (2, false), (2, true)];

impl ChunkBox {
    fn of(layout: &WorldLayout, coord: ChunkCoord) -> Self {
        let q = &layout.quantization;
        let o = layout.chunk_origin(coord).map(|c| c as f64);
        let e = layout.chunk_edge() as f64;
        let min = q.to_world(o);
        let max = q.to_world([o[0] + e, o[1] + e, o[2] + e]);
        Self {
            min,
            max,
            tolerance: 1e-6 * (max[0] - min[0]).abs().max(1.0),
        }
    }

    fn plane(&self, side: usize) -> f64 {
        let (axis, upper) = SIDES[side];
        if upper {
            self.max[axis]
        } else {
            self.min[axis]
        }
    }

    /// The sides `p` lies on, as bits.
    fn sides_of(&self, p: [f64; 3]) -> u8 {
        let mut bits = 0;
        for (s, &(axis, _)) in SIDES.iter().enumerate() {
            if (p[axis] - self.plane(s)).abs() <= self.tolerance {
                bits |= 1 << s;
            }
        }
        bits
    }

    /// Whether triangle `t` lies in a side's plane or on the floor (the
    /// chunk's walls and bottom, hidden in the world).
    fn is_wall(&self, t: &[[f64; 3]; 3]) -> bool {
        let sides = t.iter().fold(0xF, |bits, &p| bits & self.sides_of(p));
        let floor = t
            .iter()
            .all(|p| (p[1] - self.min[1]).abs() <= self.tolerance);
        sides != 0 || floor
    }

    /// The unit vector out of the chunk through side `side`.
    fn outward(side: u8) -> [f64; 3] {
        let (axis, upper) = SIDES[side as usize];
        let mut n = [0.0; 3];
        n[axis] = if upper { 1.0 } else { -1.0 };
        n
    }
}

/// Triangles with smooth normals, then skirt strips shaded as the
/// surface they hang from.
#[derive(Default)]
struct MeshBuilder {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
    /// The render vertex of each point the surface uses.
    surface_vertex: HashMap<u32, u32>,
}

impl MeshBuilder {
    /// The triangles over `points` (only the points they use), each
    /// vertex with the area-weighted mean normal of its triangles.
    fn surface(&mut self, points: &[[f64; 3]], triangles: &[[u32; 3]]) {
        let mut slot: HashMap<u32, u32> = HashMap::new();
        let mut normals: Vec<[f64; 3]> = Vec::new();
        let base = self.positions.len() as u32;
        for t in triangles {
            let [a, b, c] = t.map(|v| points[v as usize]);
            let n = cross(sub(b, a), sub(c, a));
            for &v in t {
                let next = slot.len() as u32;
                let s = *slot.entry(v).or_insert(next);
                if s == next {
                    self.positions.push(points[v as usize].map(|c| c as f32));
                    normals.push([0.0; 3]);
                }
                for a in 0..3 {
                    normals[s as usize][a] += n[a];
                }
                self.indices.push(base + s);
            }
        }
        self.surface_vertex
            .extend(slot.into_iter().map(|(v, s)| (v, base + s)));
        self.normals.extend(normals.into_iter().map(|n| {
            let len = dot(n, n).sqrt();
            if len > 0.0 {
                n.map(|c| (c / len) as f32)
            } else {
                [0.0, 1.0, 0.0]
            }
        }));
    }

    /// A strip from each edge `(a, b, side)` hanging `depth[side]` down,
    /// facing out of the chunk through `side`. Where a strip shows, it
    /// fills the step down to a neighbour's lower border: each of its
    /// vertices takes the smooth normal of the surface point it hangs
    /// from (the side's outward normal where the surface has none), so
    /// the step shades as the ground beside it rather than as a wall.
    fn strips(&mut self, points: &[[f64; 3]], edges: &[(u32, u32, u8)], depth: &[f64; 4]) {
        for &(a, b, side) in edges {
            let (pa, pb) = (points[a as usize], points[b as usize]);
            let d = depth[usize::from(side)];
            let (fa, fb) = ([pa[0], pa[1] - d, pa[2]], [pb[0], pb[1] - d, pb[2]]);
            let out = ChunkBox::outward(side).map(|c| c as f32);
            let [na, nb] = [a, b].map(|v| {
                self.surface_vertex
                    .get(&v)
                    .map_or(out, |&r| self.normals[r as usize])
            });
            let out = ChunkBox::outward(side);
            self.strip_triangle([(pa, na), (fa, na), (pb, nb)], out);
            self.strip_triangle([(pb, nb), (fa, na), (fb, nb)], out);
        }
    }

    /// A triangle of `(position, normal)` corners, wound counter-clockwise
    /// seen from `out`; skipped when degenerate.
    fn strip_triangle(&mut self, t: [([f64; 3], [f32; 3]); 3], out: [f64; 3]) {
        let n = cross(sub(t[1].0, t[0].0), sub(t[2].0, t[0].0));
        if dot(n, n) == 0.0 {
            return;
        }
        let t = if dot(n, out) < 0.0 {
            [t[0], t[2], t[1]]
        } else {
            t
        };
        let base = self.positions.len() as u32;
        for (p, normal) in t {
            self.positions.push(p.map(|c| c as f32));
            self.normals.push(normal);
        }
        self.indices.extend([base, base + 1, base + 2]);
    }
}

/// The edges used by exactly one of `triangles` whose ends lie on one
/// side of the chunk, as `(a, b, side, triangle index)`.
fn boundary_on_sides(
    triangles: &[[u32; 3]],
    points: &[[f64; 3]],
    box_: &ChunkBox,
) -> Vec<(u32, u32, u8, usize)> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut out = Vec::new();
    for (index, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if uses.get(&(a.min(b), a.max(b))) != Some(&1) {
                continue;
            }
            let common = box_.sides_of(points[a as usize]) & box_.sides_of(points[b as usize]);
            if let Some(side) = (0..4u8).find(|s| common & (1 << s) != 0) {
                out.push((a, b, side, index));
            }
        }
    }
    out
}

/// Level `level`'s meshes as Bevy meshes, with their counts.
fn level_mesh(level: u8, error: f64, meshes: Vec<(Label, MeshBuilder)>) -> LevelMesh {
    let triangles = meshes.iter().map(|(_, m)| m.indices.len() / 3).sum();
    let bytes = meshes
        .iter()
        .map(|(_, m)| m.positions.len() * 24 + m.indices.len() * 4)
        .sum();
    let meshes = meshes
        .into_iter()
        .filter(|(_, m)| !m.indices.is_empty())
        .map(|(label, m)| {
            let mesh = Mesh::new(
                PrimitiveTopology::TriangleList,
                RenderAssetUsages::default(),
            )
            .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, m.positions)
            .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, m.normals)
            .with_inserted_indices(Indices::U32(m.indices));
            (label, mesh)
        })
        .collect();
    LevelMesh {
        level,
        error: error as f32,
        meshes,
        triangles,
        bytes,
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
