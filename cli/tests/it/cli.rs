//! The `chisel` binary end to end: real scenes in, summaries and files out,
//! bad input reported with exit code 3, a wrong command line with 2.

use crate::common;

use std::path::PathBuf;

use common::{chisel, temp};

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/scenes")
        .join(name)
}

#[test]
fn sample_reports_json_and_writes_ply() {
    let ply = temp("classic.ply");
    let out = chisel()
        .args(["sample", scene("classic.quadric.ron").to_str().unwrap()])
        .args(["--radius", "4", "--bounds", "0,0,0,90", "--json", "-o"])
        .arg(&ply)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = String::from_utf8(out.stdout).unwrap();
    let samples: usize = line
        .split("\"samples\":")
        .nth(1)
        .and_then(|rest| rest.split(',').next())
        .and_then(|n| n.parse().ok())
        .expect("a samples field");
    assert!(samples > 1000, "{line}");
    let text = std::fs::read_to_string(&ply).unwrap();
    assert!(text.starts_with("ply\n"));
    assert!(text.contains(&format!("element vertex {samples}\n")));
}

#[test]
fn trace_writes_an_image_with_the_object_in_it() {
    let png = temp("classic.png");
    let out = chisel()
        .args(["trace", scene("classic.quadric.ron").to_str().unwrap()])
        .args(["--bounds", "0,0,0,90", "--size", "64x48", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let report = String::from_utf8(out.stdout).unwrap();
    let hits: usize = report
        .split('(')
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("a surface pixel count");
    assert!(hits > 64 * 48 / 10 && hits < 64 * 48, "{report}");
}

#[test]
fn bad_input_is_a_clear_error_with_its_exit_code() {
    let bad = temp("bad.ron");
    std::fs::write(&bad, "Scene(primitives: [], root: Ref(\"x\"))").unwrap();
    for (code, args) in [
        (
            3,
            vec![
                "sample",
                "missing.ron",
                "--radius",
                "1",
                "--bounds",
                "0,0,0,1",
            ],
        ),
        (
            3,
            vec![
                "sample",
                bad.to_str().unwrap(),
                "--radius",
                "1",
                "--bounds",
                "0,0,0,1",
            ],
        ),
        (
            2,
            vec![
                "sample",
                scene("classic.quadric.ron").to_str().unwrap(),
                "--radius=-1",
                "--bounds",
                "0,0,0,90",
            ],
        ),
    ] {
        let out = chisel().args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(code), "{args:?}");
        let message = String::from_utf8(out.stderr).unwrap();
        assert!(
            message.starts_with("chisel: ") && message.len() > 20,
            "{message}"
        );
    }
    // Unparsable arguments are rejected by the parser (also exit code 2).
    let out = chisel()
        .args(["sample", "x.ron", "--radius", "1", "--bounds", "0,0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn sample_and_trace_default_to_the_scene_bounds() {
    // The shipped scenes carry `bounds`; the same run with and without the
    // equal `--bounds` gives the same samples.
    let run = |extra: &[&str]| {
        let out = chisel()
            .args([
                "sample",
                scene("three_spheres.quadric.ron").to_str().unwrap(),
            ])
            .args(["--radius", "6", "--json"])
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = String::from_utf8(out.stdout).unwrap();
        line.split("\"samples\":")
            .nth(1)
            .and_then(|rest| rest.split(',').next())
            .and_then(|n| n.parse::<usize>().ok())
            .expect("a samples field")
    };
    let from_scene = run(&[]);
    assert!(from_scene > 100);
    assert_eq!(from_scene, run(&["--bounds", "0,0,10,75"]));
    assert_ne!(from_scene, run(&["--bounds", "0,0,10,20"]));
    let png = temp("three_spheres.png");
    let out = chisel()
        .args([
            "trace",
            scene("three_spheres.quadric.ron").to_str().unwrap(),
        ])
        .args(["--size", "32x24", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn missing_bounds_is_a_clear_error() {
    let bare = temp("bare.ron");
    std::fs::write(
        &bare,
        "Scene(primitives: [(name: \"a\", shape: Sphere(center: (0, 0, 0), radius: 1))], \
         root: Ref(\"a\"))",
    )
    .unwrap();
    for (command, options) in [("sample", ["--radius", "0.1"]), ("trace", ["--fov", "30"])] {
        let out = chisel()
            .args([command, bare.to_str().unwrap()])
            .args(options)
            .arg("-o")
            .arg(temp("bare.out"))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{command}");
        let message = String::from_utf8(out.stderr).unwrap();
        assert!(
            message.contains("bounds: (x, y, z, r)") && message.contains("--bounds"),
            "{command}: {message}"
        );
    }
    // With --bounds the same scene samples.
    let out = chisel()
        .args(["sample", bare.to_str().unwrap(), "--radius", "0.1"])
        .args(["--bounds", "0,0,0,2"])
        .output()
        .unwrap();
    assert!(out.status.success());
}

#[test]
fn budget_prints_the_bit_widths() {
    let out = chisel().args(["budget", "--json"]).output().unwrap();
    assert!(out.status.success());
    let line = String::from_utf8(out.stdout).unwrap();
    assert!(line.contains("\"max_coord\":67108864") && line.contains("\"magnitude_bits\":252"));
}
