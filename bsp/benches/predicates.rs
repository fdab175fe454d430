//! Table 1 of paper 1: the exact predicates at the full bit budget, ns/op,
//! each beside the num-bigint version of the same operation.
//!
//! `cargo bench -p chisel_bsp --bench predicates`; `benches/table1.py`
//! turns the criterion results into the table of BENCHMARKS.md.

use std::hint::black_box;

use chisel_bsp::exact::{
    IntPoint, Plane, Point4, are_planes_parallel, classify_vertex, classify_vertex_exact,
    classify_vertex_filtered, intersect_3_planes, plane_from_points, plane_from_points_normalized,
};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

// The benchmark takes a part of the integration tests' shared support.
#[allow(dead_code)]
#[path = "../tests/it/common/bigint_reference.rs"]
mod big;
#[allow(dead_code)]
#[path = "../tests/it/common/inputs.rs"]
mod inputs;

/// Inputs per benchmark (one batch per criterion iteration): small enough
/// that vertices and planes stay in the L1 cache, as in a mesh cut.
const INPUTS: usize = 128;

struct Fixture {
    points: Vec<[IntPoint; 3]>,
    raw_points: Vec<[[i64; 3]; 3]>,
    planes: Vec<[Plane; 4]>,
    /// The fourth plane of each case, stored contiguously (L1-resident).
    targets: Vec<Plane>,
    big_planes: Vec<[big::BigPlane; 4]>,
    vertices: Vec<Point4>,
    big_vertices: Vec<big::BigVertex>,
    on_plane: Vec<(Point4, Plane)>,
}

fn fixture() -> Fixture {
    let mut rng = inputs::rng(2024);
    let mut f = Fixture {
        points: Vec::new(),
        raw_points: Vec::new(),
        planes: Vec::new(),
        targets: Vec::new(),
        big_planes: Vec::new(),
        vertices: Vec::new(),
        big_vertices: Vec::new(),
        on_plane: Vec::new(),
    };
    while f.vertices.len() < INPUTS {
        let raw = [0; 3].map(|_| inputs::point(&mut rng));
        let raw_planes = [0; 4].map(|_| inputs::plane(&mut rng));
        let planes = raw_planes.map(|(a, b, c, d)| Plane::new(a, b, c, d).unwrap());
        let Some(v) = intersect_3_planes(&planes[0], &planes[1], &planes[2]) else {
            continue;
        };
        let big_planes = raw_planes.map(|(a, b, c, d)| big::big_plane(a, b, c, d));
        f.big_vertices
            .push(big::intersect(&big_planes[0], &big_planes[1], &big_planes[2]).unwrap());
        f.vertices.push(v);
        f.on_plane.push((v, planes[0]));
        f.points.push(raw.map(|p| IntPoint::from_array(p).unwrap()));
        f.raw_points.push(raw);
        f.targets.push(planes[3]);
        f.planes.push(planes);
        f.big_planes.push(big_planes);
    }
    f
}

/// Times `op(i, batch)` over all inputs `i` in turn (sequential access, as in
/// a loop over a mesh's vertices); `batch` counts criterion's iterations so
/// that pairings can rotate and no branch pattern repeats. Criterion reports
/// time per batch; the throughput setting lets `benches/table1.py` divide it
/// into time per operation.
fn per_op<T>(c: &mut Criterion, group: &str, name: &str, op: impl Fn(usize, usize) -> T) {
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(INPUTS as u64));
    g.bench_function(name, |b| {
        let mut batch = 0;
        b.iter(|| {
            batch += 1;
            for i in 0..INPUTS {
                black_box(op(black_box(i), batch));
            }
        })
    });
    g.finish();
}

fn table1(c: &mut Criterion) {
    let f = fixture();

    per_op(c, "plane_from_points", "fixed", |i, _| {
        let [p, q, r] = f.points[i];
        plane_from_points(p, q, r)
    });
    per_op(c, "plane_from_points", "bigint", |i, _| {
        let [p, q, r] = f.raw_points[i];
        big::plane_from_points(p, q, r)
    });

    per_op(c, "plane_from_points_normalized", "fixed", |i, _| {
        let [p, q, r] = f.points[i];
        plane_from_points_normalized(p, q, r)
    });
    per_op(c, "plane_from_points_normalized", "bigint", |i, _| {
        let [p, q, r] = f.raw_points[i];
        big::plane_from_points(p, q, r).map(|pl| big::normalized(&pl))
    });

    per_op(c, "are_planes_parallel", "fixed", |i, _| {
        are_planes_parallel(&f.planes[i][0], &f.planes[i][1])
    });
    per_op(c, "are_planes_parallel", "bigint", |i, _| {
        big::parallel(&f.big_planes[i][0], &f.big_planes[i][1])
    });

    per_op(c, "intersect_3_planes", "fixed", |i, _| {
        let [p, q, r, _] = &f.planes[i];
        intersect_3_planes(p, q, r)
    });
    per_op(c, "intersect_3_planes", "bigint", |i, _| {
        let [p, q, r, _] = &f.big_planes[i];
        big::intersect(p, q, r)
    });

    per_op(c, "classify_vertex", "filtered", |i, batch| {
        classify_vertex(&f.vertices[i], &f.targets[(i + batch) % INPUTS])
    });
    per_op(c, "classify_vertex", "filter_only", |i, batch| {
        classify_vertex_filtered(&f.vertices[i], &f.targets[(i + batch) % INPUTS])
    });
    per_op(c, "classify_vertex", "exact", |i, batch| {
        classify_vertex_exact(&f.vertices[i], &f.targets[(i + batch) % INPUTS])
    });
    per_op(c, "classify_vertex", "bigint", |i, batch| {
        big::classify(&f.big_vertices[i], &f.big_planes[(i + batch) % INPUTS][3])
    });
    // Worst case for the filter: the vertex lies on the plane, so every
    // call falls through to the exact path.
    per_op(c, "classify_vertex", "filtered_on_plane", |i, _| {
        let (v, s) = &f.on_plane[i];
        classify_vertex(v, s)
    });
}

criterion_group!(benches, table1);
criterion_main!(benches);
