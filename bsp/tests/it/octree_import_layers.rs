//! Octree import of a layered heightfield in one pass: the same labelled
//! regions as importing the closed field and painting each band with one
//! convex column per square (deepest first) — exact volume per label equal
//! and every sampled point off the surfaces labelled alike — on random
//! fields with shallow, deep, repeated and redundant bands; typed errors
//! for malformed fields.

use std::collections::{BTreeMap, HashSet};

use chisel_bsp::Error;
use chisel_bsp::exact::IntPoint;
use chisel_bsp::octree::import_layers::LayeredHeightfield;
use chisel_bsp::octree::{Edit, Leaf, Octree, OctreeConfig, Tool};
use chisel_bsp::tree::Label;
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SIZE_LOG2: u8 = 8;

struct Field {
    corner: [i64; 2],
    samples: [u32; 2],
    spacing: i64,
    heights: Vec<i64>,
    bottom: i64,
    label: Label,
    bands: Vec<(i64, Label)>,
}

impl Field {
    fn layered(&self) -> LayeredHeightfield<'_> {
        LayeredHeightfield {
            corner: self.corner,
            samples: self.samples,
            spacing: self.spacing,
            heights: &self.heights,
            bottom: self.bottom,
            label: self.label,
            bands: &self.bands,
        }
    }

    fn at(&self, i: u32, j: u32, y: i64) -> [i64; 3] {
        [
            self.corner[0] + i64::from(i) * self.spacing,
            y,
            self.corner[1] + i64::from(j) * self.spacing,
        ]
    }

    fn top(&self, i: u32, j: u32) -> [i64; 3] {
        self.at(i, j, self.heights[(i + j * self.samples[0]) as usize])
    }

    /// The closed solid: top, bottom and walls.
    fn closed_mesh(&self) -> Vec<[IntPoint; 3]> {
        let [nx, nz] = self.samples;
        let mut out = Vec::new();
        let mut top_edges = HashSet::new();
        for j in 0..nz - 1 {
            for i in 0..nx - 1 {
                let (p00, p10) = (self.top(i, j), self.top(i + 1, j));
                let (p01, p11) = (self.top(i, j + 1), self.top(i + 1, j + 1));
                for t in [[p00, p01, p10], [p10, p01, p11]] {
                    top_edges.extend([(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]);
                    out.push(t);
                }
                let b = |i, j| self.at(i, j, self.bottom);
                out.push([b(i, j), b(i + 1, j), b(i, j + 1)]);
                out.push([b(i + 1, j), b(i + 1, j + 1), b(i, j + 1)]);
            }
        }
        let mut walls = Vec::new();
        for &(u, v) in &top_edges {
            if !top_edges.contains(&(v, u)) {
                let (ub, vb) = ([u[0], self.bottom, u[2]], [v[0], self.bottom, v[2]]);
                walls.push([v, u, ub]);
                walls.push([v, ub, vb]);
            }
        }
        out.extend(walls);
        out.iter()
            .map(|t| t.map(|c| IntPoint::from_array(c).unwrap()))
            .collect()
    }

    /// The reference: the closed solid imported, then every band painted
    /// with one convex column per square, deepest first.
    fn painted(&self) -> Octree {
        let mut octree = Octree::from_triangles(
            [0; 3],
            SIZE_LOG2,
            &self.closed_mesh(),
            self.label,
            OctreeConfig::default(),
        )
        .unwrap();
        let mut bands = self.bands.clone();
        bands.sort_by_key(|&(depth, _)| std::cmp::Reverse(depth));
        let [nx, nz] = self.samples;
        for (depth, label) in bands {
            for j in 0..nz - 1 {
                for i in 0..nx - 1 {
                    let corners = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
                    let high = corners
                        .iter()
                        .map(|&(a, b)| self.top(a, b)[1])
                        .max()
                        .unwrap()
                        + 1;
                    let mut points = Vec::new();
                    for (a, b) in corners {
                        let h = self.top(a, b)[1];
                        points.push(IntPoint::from_array(self.at(a, b, h - depth)).unwrap());
                        points.push(IntPoint::from_array(self.at(a, b, high)).unwrap());
                    }
                    let column = Tool::convex_hull(&points).unwrap();
                    octree.apply(&column, Edit::Paint(label)).unwrap();
                }
            }
        }
        octree
    }

    fn imported(&self) -> Octree {
        Octree::from_layered_heightfield(
            [0; 3],
            SIZE_LOG2,
            &self.layered(),
            OctreeConfig::default(),
        )
        .unwrap()
    }
}

fn random_field(rng: &mut ChaCha8Rng) -> Field {
    let samples = [rng.random_range(2..6u32), rng.random_range(2..6u32)];
    let spacing = rng.random_range(5..25i64);
    let bottom = rng.random_range(10..40i64);
    let rough = rng.random_range(1..60i64);
    let heights = (0..samples[0] * samples[1])
        .map(|_| bottom + 1 + rng.random_range(0..rough))
        .collect();
    let bands = (0..rng.random_range(0..5))
        .map(|_| (rng.random_range(1..70i64), rng.random_range(1..5u8)))
        .collect();
    Field {
        corner: [rng.random_range(0..20i64), rng.random_range(0..20i64)],
        samples,
        spacing,
        heights,
        bottom,
        label: rng.random_range(1..4u8),
        bands,
    }
}

/// Whether `point` lies on a splitting plane of a leaf holding it, or on
/// the border of such a leaf: there the label depends on which side
/// `label_at` takes.
fn on_a_surface(octree: &Octree, point: [i64; 3]) -> bool {
    let p = IntPoint::from_array(point).unwrap();
    octree.leaves().into_iter().any(|(key, leaf)| {
        let cell = octree.cell_box(key);
        let inside = (0..3).all(|a| cell.min[a] <= point[a] && point[a] <= cell.max[a]);
        let border = (0..3).any(|a| cell.min[a] == point[a] || point[a] == cell.max[a]);
        inside
            && (border
                || matches!(leaf, Leaf::Bsp(bsp) if bsp.planes().iter().any(|s| s.eval(p) == 0)))
    })
}

fn assert_same_regions(field: &Field, case: usize, rng: &mut ChaCha8Rng) {
    let (painted, imported) = (field.painted(), field.imported());
    let volumes = |o: &Octree| -> BTreeMap<Label, _> {
        o.exact_volumes()
            .into_iter()
            .filter(|(_, v)| !v.is_zero())
            .collect()
    };
    assert_eq!(
        volumes(&imported),
        volumes(&painted),
        "case {case}: volumes"
    );
    let [nx, nz] = field.samples;
    let far = field.at(nx - 1, nz - 1, 0);
    let top = field.heights.iter().max().unwrap() + 2;
    let mut compared = 0;
    for _ in 0..400 {
        let point = [
            rng.random_range(field.corner[0] - 2..=far[0] + 2),
            rng.random_range(field.bottom - 2..=top),
            rng.random_range(field.corner[1] - 2..=far[2] + 2),
        ];
        let (a, b) = (
            imported.label_at(point).unwrap(),
            painted.label_at(point).unwrap(),
        );
        if a != b {
            assert!(
                on_a_surface(&imported, point) || on_a_surface(&painted, point),
                "case {case}: {point:?} is {a:?} imported but {b:?} painted"
            );
        } else {
            compared += 1;
        }
    }
    assert!(compared > 300, "case {case}: only {compared} points agree");
}

#[test]
fn layered_import_labels_the_regions_painting_gives() {
    let mut rng = ChaCha8Rng::seed_from_u64(26);
    for case in 0..40 {
        let field = random_field(&mut rng);
        assert_same_regions(&field, case, &mut rng);
    }
}

#[test]
fn bands_reaching_below_the_bottom_and_repeated_depths_match() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let heights = vec![40, 45, 70, 41, 90, 52, 44, 60, 43];
    let field = Field {
        corner: [3, 5],
        samples: [3, 3],
        spacing: 30,
        heights,
        bottom: 20,
        label: 1,
        // Equal depths (the later wins), a band as deep as the base's own
        // label, and one below the bottom everywhere.
        bands: vec![(12, 2), (12, 3), (30, 1), (200, 4), (5, 2)],
    };
    assert_same_regions(&field, 0, &mut rng);
    let labels: Vec<Label> = field
        .imported()
        .exact_volumes()
        .into_iter()
        .filter(|(_, v)| !v.is_zero())
        .map(|(l, _)| l)
        .collect();
    assert_eq!(labels, vec![1, 2, 3, 4]);

    // A band of any depth: as deep as the grid allows, it holds what one
    // reaching below the bottom everywhere holds, and hides deeper ones.
    for (deepest, painted) in [
        (vec![(12, 2), (i64::MAX, 3)], vec![(12, 2), (6_000, 3)]),
        (
            vec![(12, 2), (i64::MAX, 3), (500, 4)],
            vec![(12, 2), (6_000, 3), (500, 4)],
        ),
    ] {
        let deep = Field {
            bands: deepest,
            ..field.clone_shape()
        };
        let reference = Field {
            bands: painted,
            ..field.clone_shape()
        };
        assert_eq!(
            deep.imported().exact_volumes(),
            reference.painted().exact_volumes(),
            "{:?}",
            deep.bands
        );
    }
}

impl Field {
    fn clone_shape(&self) -> Field {
        Field {
            corner: self.corner,
            samples: self.samples,
            spacing: self.spacing,
            heights: self.heights.clone(),
            bottom: self.bottom,
            label: self.label,
            bands: self.bands.clone(),
        }
    }
}

#[test]
fn malformed_fields_are_typed_errors() {
    let field = |heights: Vec<i64>, bands: Vec<(i64, Label)>, corner: [i64; 2]| Field {
        corner,
        samples: [2, 2],
        spacing: 10,
        heights,
        bottom: 5,
        label: 1,
        bands,
    };
    let build = |f: &Field| {
        Octree::from_layered_heightfield([0; 3], SIZE_LOG2, &f.layered(), OctreeConfig::default())
    };
    let at_bottom = field(vec![9, 5, 9, 9], vec![], [0, 0]);
    assert!(matches!(
        build(&at_bottom),
        Err(Error::InvalidHeightfield { .. })
    ));
    let flat_band = field(vec![9; 4], vec![(0, 2)], [0, 0]);
    assert!(matches!(
        build(&flat_band),
        Err(Error::InvalidHeightfield { .. })
    ));
    let short = field(vec![9; 3], vec![], [0, 0]);
    assert!(matches!(
        build(&short),
        Err(Error::InvalidHeightfield { .. })
    ));
    let outside = field(vec![9; 4], vec![], [250, 0]);
    assert!(matches!(build(&outside), Err(Error::OutsideOctree { .. })));
}
