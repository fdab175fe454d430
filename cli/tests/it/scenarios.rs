//! The iterated CSG scenarios end to end, at small sizes: `--json` reports
//! parse and hold their invariants (volumes that only shrink under
//! subtraction, exact volumes where they are computable, watertight
//! results), a recorded sequence replays to the identical result, results
//! do not depend on the thread count, and malformed sequences are errors
//! naming their line, with exit code 3.

use crate::common;

use common::{box_obj, chisel, f, path, report, temp};
use serde_json::Value;

fn check_figures(r: &Value, steps: usize) {
    assert_eq!(r["steps"].as_u64(), Some(steps as u64), "{r}");
    assert_eq!(r["closed"].as_bool(), Some(true), "{r}");
    assert!(f(r, "triangles") > 0.0);
    assert!(f(r, "total_seconds") > 0.0);
    let (median, p99, max) = (f(r, "median_ms"), f(r, "p99_ms"), f(r, "max_ms"));
    assert!(0.0 < median && median <= p99 && p99 <= max, "{r}");
    assert!(f(r, "hull_median_ms") + f(r, "apply_median_ms") <= max);
    // Per-step CPU time of the thread that ran the step: each step's is at
    // most its wall time (read inside it), so every order statistic is too,
    // and the steps' sum is within the loop's total.
    let cpu = &r["cpu"];
    let slack = 1e-3;
    for key in ["median_ms", "p99_ms", "max_ms", "mean_ms"] {
        assert!(f(cpu, key) <= f(r, key) + slack, "{key}: {r}");
    }
    assert!(
        0.0 < f(cpu, "median_ms") && f(cpu, "median_ms") <= f(cpu, "p99_ms"),
        "{r}"
    );
    assert!(f(cpu, "p99_ms") <= f(cpu, "max_ms"), "{r}");
    assert!(f(cpu, "mean_ms") * steps as f64 <= f(r, "total_cpu_seconds") * 1e3 + slack);
    assert!(
        f(r, "total_cpu_seconds") <= f(r, "total_seconds") + 1e-6,
        "{r}"
    );
    assert!(f(r, "peak_memory_mib") > 0.0);
    let octree = &r["octree"];
    assert!(f(octree, "leaves") >= 1.0);
    assert!(f(octree, "bytes_per_bsp_node") > 0.0);
}

#[test]
fn mill_subtracts_and_replays_to_the_identical_result() {
    let ops = temp("mill.jsonl");
    let csv = temp("mill.csv");
    let steps = 12;
    let r = report(&[
        "mill",
        "--steps",
        &steps.to_string(),
        "--record",
        path(&ops),
        "--csv",
        path(&csv),
    ]);
    check_figures(&r, steps);
    // The block is 100 × 100 × 40 mm; the tool (radius 3 mm) cuts 10 mm
    // deep along a 1.5 mm-per-step row: at most the hull of the row's
    // circles, at least the disc at the start.
    let removed = 400_000.0 - f(&r, "volume_mm3");
    let row = 1.5 * steps as f64;
    assert!(
        removed > 10.0 * 27.0 && removed < 10.0 * (6.0 * row + 9.0 * std::f64::consts::PI),
        "{removed}"
    );
    let lines = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(lines.lines().count(), steps + 1);
    assert!(lines.starts_with("step,seconds,cpu_seconds,"));
    let recorded = std::fs::read_to_string(&ops).unwrap();
    assert_eq!(recorded.lines().count(), steps + 1);
    assert!(recorded.starts_with("{\"base\":{\"box\":[[0.0,0.0,0.0],[100.0,100.0,40.0]]}}\n"));

    let again = report(&["replay", path(&ops)]);
    check_figures(&again, steps);
    assert_eq!(again["volume_mm3"], r["volume_mm3"]);
    assert_eq!(again["mesh_hash"], r["mesh_hash"]);
    assert_eq!(again["triangles"], r["triangles"]);
}

#[test]
fn every_step_keeps_the_volume_bookkeeping_and_a_closed_surface() {
    for args in [
        vec!["mill", "--steps", "6"],
        vec!["cheese", "--count", "6", "--seed", "3"],
        vec!["sweep", "--samples", "2", "--max-bsp-nodes", "60"],
        vec!["cutter", "--path", "helix", "--sides", "24", "--steps", "4"],
        vec![
            "cutter", "--path", "spiral", "--sides", "12", "--steps", "4",
        ],
        vec![
            "cutter",
            "--path",
            "tilt",
            "--sides",
            "30",
            "--steps",
            "3",
            "--max-bsp-nodes",
            "40",
        ],
        vec!["fluted", "--steps", "3"],
        vec![
            "fluted",
            "--steps",
            "2",
            "--flutes",
            "4",
            "--substeps",
            "2",
            "--max-bsp-nodes",
            "40",
        ],
    ] {
        let mut args = args;
        args.push("--check");
        let r = report(&args);
        assert_eq!(r["checked"].as_bool(), Some(true), "{args:?}");
        // Mill, cheese, cutter and fluted subtract from a box, which at
        // these sizes leaves no edge contacts.
        if args[0] != "sweep" {
            assert_eq!(r["watertight"].as_bool(), Some(true), "{args:?}");
        }
    }
}

#[test]
fn replay_gives_exact_volumes_for_box_tools() {
    let ops = temp("boxes.jsonl");
    let cube = |x0: f64, y0: f64, z0: f64, x1: f64, y1: f64, z1: f64| {
        let mut points = Vec::new();
        for x in [x0, x1] {
            for y in [y0, y1] {
                for z in [z0, z1] {
                    points.push(format!("[{x},{y},{z}]"));
                }
            }
        }
        points.join(",")
    };
    // 10³ mm block; remove its upper half (500), add a 1 × 2 × 3 box beside
    // it (+6), then keep what lies in x ≤ 5 (250 of the block, 0 of the box).
    let text = format!(
        "{{\"base\": {{\"box\": [[0,0,0],[10,10,10]]}}}}\n\
         {{\"op\": \"subtract\", \"hull\": [{}]}}\n\
         {{\"op\": \"union\", \"hull\": [{}]}}\n",
        cube(-1.0, -1.0, 5.0, 11.0, 11.0, 11.0),
        cube(20.0, 0.0, 0.0, 21.0, 2.0, 3.0),
    );
    std::fs::write(&ops, &text).unwrap();
    let r = report(&["replay", path(&ops), "--check"]);
    check_figures(&r, 2);
    assert!((f(&r, "volume_mm3") - 506.0).abs() < 1e-9, "{r}");
    std::fs::write(
        &ops,
        format!(
            "{text}{{\"op\": \"intersect\", \"hull\": [{}]}}\n",
            cube(-1.0, -1.0, -1.0, 5.0, 11.0, 11.0)
        ),
    )
    .unwrap();
    let r = report(&["replay", path(&ops), "--check"]);
    assert!((f(&r, "volume_mm3") - 250.0).abs() < 1e-9, "{r}");
}

#[test]
fn cheese_is_the_same_on_any_thread_count() {
    let one = report(&["cheese", "--count", "25", "--seed", "9", "--threads", "1"]);
    let two = report(&["cheese", "--count", "25", "--seed", "9", "--threads", "2"]);
    check_figures(&one, 25);
    assert_eq!(one["threads"].as_u64(), Some(1));
    assert_eq!(two["threads"].as_u64(), Some(2));
    for key in ["volume_mm3", "mesh_hash", "triangles", "octree"] {
        assert_eq!(one[key], two[key], "{key}");
    }
    let volume = f(&one, "volume_mm3");
    // A dodecahedron of scale 5 mm (edge 2·5/φ) holds about 1,810 mm³.
    assert!(volume < 1e6 && volume > 1e6 - 25.0 * 1810.0, "{volume}");
    // Another seed carves elsewhere.
    let other = report(&["cheese", "--count", "25", "--seed", "10"]);
    assert_ne!(other["mesh_hash"], one["mesh_hash"]);
}

#[test]
fn sweep_unions_a_closed_solid() {
    let r = report(&["sweep", "--samples", "2"]);
    check_figures(&r, r["steps"].as_u64().unwrap() as usize);
    // More than the gear (> π · 8² · 6 mm³), less than its bounding
    // cylinder swept over the path's hull.
    let volume = f(&r, "volume_mm3");
    assert!(volume > std::f64::consts::PI * 64.0 * 6.0, "{volume}");
    assert!(volume < 100.0 * 100.0 * 100.0, "{volume}");
}

#[test]
fn malformed_sequences_name_the_line_and_exit_3() {
    let ops = temp("bad.jsonl");
    let base = "{\"base\": {\"box\": [[0,0,0],[10,10,10]]}}";
    let step = "{\"op\": \"subtract\", \"hull\": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]]}";
    for (text, needle) in [
        (
            format!("{base}\n{step}\n{{\"op\": \"drill\", \"hull\": []}}\n"),
            ":3:",
        ),
        (
            format!("{base}\n{step}\n{step}\n{{\"op\": \"subtract\"}}\n"),
            ":4:",
        ),
        (format!("{{\"base\": 7}}\n{step}\n"), ":1:"),
        (
            format!("{base}\n{{\"op\": \"union\", \"hull\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]]}}\n"),
            ":2:",
        ),
        (format!("{base}\n{step}\n{{oops\n"), ":3:"),
    ] {
        std::fs::write(&ops, &text).unwrap();
        let out = chisel().args(["replay", path(&ops)]).output().unwrap();
        assert_eq!(out.status.code(), Some(3), "{text}");
        let message = String::from_utf8(out.stderr).unwrap();
        assert!(
            message.starts_with("chisel: ") && message.contains(needle),
            "{message}"
        );
    }
    let out = chisel()
        .args(["replay", "no-such-file.jsonl"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let out = chisel().args(["sweep", "--samples", "1"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn boolean_of_two_boxes_has_the_exact_volumes() {
    let a = temp("a.obj");
    let b = temp("b.obj");
    std::fs::write(&a, box_obj([0.0; 3], [10.0; 3])).unwrap();
    std::fs::write(&b, box_obj([5.0, 0.0, 0.0], [15.0, 10.0, 10.0])).unwrap();
    for (op, volume, out) in [
        ("union", 1500.0, "u.glb"),
        ("intersection", 500.0, "i.ply"),
        ("difference", 500.0, "d.obj"),
    ] {
        let out = temp(out);
        let r = report(&["boolean", path(&a), path(&b), "--op", op, "-o", path(&out)]);
        assert!((f(&r, "a_volume_mm3") - 1000.0).abs() < 1e-9, "{r}");
        assert!((f(&r, "volume_mm3") - volume).abs() < 1e-9, "{op}: {r}");
        assert_eq!(r["watertight"].as_bool(), Some(true));
        assert_eq!(r["closed"].as_bool(), Some(true));
        // The written mesh reads back as the same solid.
        let again = report(&[
            "boolean",
            path(&out),
            path(&out),
            "--op",
            "union",
            "-o",
            path(&temp("x.obj")),
        ]);
        assert!(
            (f(&again, "volume_mm3") - volume).abs() < 1e-9,
            "{op}: {again}"
        );
    }
    // An open mesh (one face dropped) is refused with exit code 3.
    let open = temp("open.obj");
    let text = box_obj([0.0; 3], [1.0; 3]);
    std::fs::write(&open, text.lines().take(13).collect::<Vec<_>>().join("\n")).unwrap();
    let out = chisel()
        .args([
            "boolean",
            path(&open),
            path(&a),
            "--op",
            "union",
            "-o",
            path(&temp("y.obj")),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let message = String::from_utf8(out.stderr).unwrap();
    assert!(
        message.contains("open.obj") && message.contains("watertight"),
        "{message}"
    );
}

#[test]
fn scenarios_export_their_result_and_replay_a_mesh_base() {
    let glb = temp("mill.glb");
    let r = report(&["mill", "--steps", "4", "--export", path(&glb)]);
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    // A replay from an exported box with one box tool.
    let block = temp("block.obj");
    std::fs::write(&block, box_obj([0.0; 3], [10.0; 3])).unwrap();
    let ops = temp("mesh-base.jsonl");
    std::fs::write(
        &ops,
        "{\"base\": {\"mesh\": \"block.obj\"}}\n\
         {\"op\": \"subtract\", \"hull\": [[2,2,2],[4,2,2],[2,4,2],[4,4,2],[2,2,11],[4,2,11],[2,4,11],[4,4,11]]}\n",
    )
    .unwrap();
    let carved = report(&["replay", path(&ops)]);
    assert!(
        (f(&carved, "volume_mm3") - (1000.0 - 32.0)).abs() < 1e-9,
        "{carved}"
    );
    assert!(f(&r, "volume_mm3") < 400_000.0);
}
