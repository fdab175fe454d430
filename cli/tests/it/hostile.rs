//! Hostile input: parameters the commands accept in form but that would
//! take unbounded work, wrap, or silently break a guarantee. Each is
//! refused up front with a message naming the cause (and how to go on),
//! an exit code rather than an abort, and no output file.

use crate::common;

use std::path::PathBuf;

use common::{chisel, path, temp};

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/scenes")
        .join(name)
}

/// Runs chisel with `args`; asserts it exits with a code (no signal, no
/// panic) other than success, and that standard error holds `wanted`.
fn refused(args: &[&str], wanted: &str) {
    let out = chisel().args(args).output().unwrap();
    let message = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.code().is_some_and(|c| c != 0) && !message.contains("panicked"),
        "{args:?}: {:?} {message}",
        out.status
    );
    assert!(message.contains(wanted), "{args:?}: {message}");
}

#[test]
fn a_tiny_splat_radius_is_refused_before_allocating() {
    let classic = scene("classic.quadric.ron");
    let s = path(&classic);
    // Before: an allocation of 8e17 bytes, and an add overflow in the
    // subdivision at 1e-300.
    refused(
        &["sample", s, "--radius", "1e-9", "--bounds", "0,0,0,90"],
        "coverage",
    );
    refused(
        &["sample", s, "--radius", "1e-300", "--bounds", "0,0,0,90"],
        "coverage",
    );
    // Within the bounds ratio, the sample limit decides, and says how to
    // raise it.
    refused(
        &[
            "sample",
            s,
            "--radius",
            "2",
            "--bounds",
            "0,0,0,90",
            "--max-samples",
            "1000",
        ],
        "--max-samples",
    );
}

#[test]
fn huge_bounds_fail_instead_of_dropping_coverage() {
    let classic = scene("classic.quadric.ron");
    let s = path(&classic);
    // Before: 18,672 samples at 1e8 and none at 1e10, both with exit 0.
    for r in ["0,0,0,1e8", "0,0,0,1e10", "0,0,0,1e300"] {
        refused(&["sample", s, "--radius", "2", "--bounds", r], "coverage");
    }
}

#[test]
fn oversized_counts_are_refused_by_the_parser() {
    let classic = scene("classic.quadric.ron");
    let out = temp("huge.png");
    refused(
        &[
            "trace",
            path(&classic),
            "--size",
            "100000x100000",
            "-o",
            path(&out),
        ],
        "limit",
    );
    assert!(!out.exists());
    refused(
        &["trace", path(&classic), "--size", "0x10", "-o", path(&out)],
        "pixel",
    );
    // Before: 2^64 − 1 steps wrapped to 0 and succeeded.
    refused(&["mill", "--steps", "18446744073709551615"], "1000000");
    refused(&["cheese", "--count", "1000000000000"], "1000000");
    refused(&["sweep", "--samples", "0"], "1000000");
    // Before: 6 GB for one carve.
    refused(&["cheese", "--count", "1", "--max-bsp-nodes", "1"], "8");
}

/// Runs chisel with `args` under a file size limit of 1 KiB (the signal it
/// would raise ignored, so a write past it fails as a full disk does).
fn with_small_disk(args: &[&str]) -> std::process::Output {
    let mut command = std::process::Command::new("sh");
    command
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 1; exec \"$@\"")
        .arg("sh")
        .arg(env!("CARGO_BIN_EXE_chisel"))
        .args(args);
    command.output().unwrap()
}

#[test]
fn a_failed_write_leaves_the_existing_file_as_it_was() {
    let folder = temp("small-disk");
    std::fs::create_dir_all(&folder).unwrap();
    let keep = b"an existing file that must survive\n";
    for name in ["out.obj", "out.chisel", "out.ply", "steps.csv", "ops.jsonl"] {
        std::fs::write(folder.join(name), keep).unwrap();
    }
    let at = |name: &str| folder.join(name).to_str().unwrap().to_owned();
    for args in [
        vec![
            "cheese".to_owned(),
            "--count".into(),
            "3".into(),
            "--export".into(),
            at("out.obj"),
        ],
        vec![
            "cheese".into(),
            "--count".into(),
            "3".into(),
            "--export".into(),
            at("out.chisel"),
        ],
        vec![
            "cheese".into(),
            "--count".into(),
            "300".into(),
            "--csv".into(),
            at("steps.csv"),
        ],
        vec![
            "cheese".into(),
            "--count".into(),
            "30".into(),
            "--record".into(),
            at("ops.jsonl"),
        ],
        vec![
            "sample".into(),
            path(&scene("classic.quadric.ron")).into(),
            "--radius".into(),
            "2".into(),
            "-o".into(),
            at("out.ply"),
        ],
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = with_small_disk(&args);
        let message = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(5), "{args:?}: {message}");
        assert!(message.contains("File too large"), "{args:?}: {message}");
    }
    let classic = scene("classic.quadric.ron");
    let out = with_small_disk(&["trace", path(&classic), "-o", &at("out.png")]);
    assert_eq!(out.status.code(), Some(5));
    assert!(!String::from_utf8_lossy(&out.stdout).contains("wrote"));
    assert!(!folder.join("out.png").exists());
    for name in ["out.obj", "out.chisel", "out.ply", "steps.csv", "ops.jsonl"] {
        assert_eq!(std::fs::read(folder.join(name)).unwrap(), keep, "{name}");
    }
    // No temporary file is left behind.
    let left: Vec<_> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// `boolean -o` naming one of its inputs, on a full disk: the input is
/// kept as it was (before: replaced by a partial file).
#[test]
fn a_failed_boolean_write_keeps_the_input_it_names() {
    let folder = temp("small-disk-boolean");
    std::fs::create_dir_all(&folder).unwrap();
    let a = folder.join("a.obj");
    let b = folder.join("b.obj");
    let a_text = common::box_obj([0.0; 3], [10.0; 3]);
    std::fs::write(&a, &a_text).unwrap();
    std::fs::write(&b, common::box_obj([5.0, 3.0, 7.0], [15.0, 13.0, 17.0])).unwrap();
    let args = [
        "boolean",
        path(&a),
        path(&b),
        "--op",
        "union",
        "-o",
        path(&a),
    ];
    let out = with_small_disk(&args);
    let message = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(5), "{message}");
    assert_eq!(std::fs::read_to_string(&a).unwrap(), a_text);
    // With room to write, the same command replaces it.
    let out = chisel().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_ne!(std::fs::read_to_string(&a).unwrap(), a_text);
}

/// An OBJ box with every face reversed, alone or beside an outward box,
/// is refused as inside out (before: accepted, with a union depending on
/// the other operand).
#[test]
fn inside_out_meshes_are_refused() {
    let outward = common::box_obj([0.0; 3], [10.0; 3]);
    let reversed: String = outward
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(f) => {
                let mut v: Vec<&str> = f.split(' ').collect();
                v.reverse();
                format!("f {}\n", v.join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect();
    let inverted = temp("inverted.obj");
    std::fs::write(&inverted, &reversed).unwrap();
    let good = temp("good.obj");
    std::fs::write(&good, &outward).unwrap();
    let out = temp("inverted-out.obj");
    refused(
        &[
            "boolean",
            path(&inverted),
            path(&good),
            "--op",
            "union",
            "-o",
            path(&out),
        ],
        "inside out",
    );
    // A reversed small box beside a large outward one: positive in all,
    // but the reversed shell is no cavity.
    let mut both = common::box_obj([0.0; 3], [100.0; 3]);
    for l in reversed.lines() {
        if let Some(p) = l.strip_prefix("v ") {
            let c: Vec<f64> = p
                .split(' ')
                .map(|x| x.parse::<f64>().unwrap() + 200.0)
                .collect();
            both.push_str(&format!("v {} {} {}\n", c[0], c[1], c[2]));
        }
    }
    for l in reversed.lines() {
        if let Some(f) = l.strip_prefix("f ") {
            let idx: Vec<String> = f
                .split(' ')
                .map(|i| (i.parse::<u32>().unwrap() + 8).to_string())
                .collect();
            both.push_str(&format!("f {}\n", idx.join(" ")));
        }
    }
    let two = temp("two-shells.obj");
    std::fs::write(&two, both).unwrap();
    refused(
        &[
            "boolean",
            path(&two),
            path(&good),
            "--op",
            "union",
            "-o",
            path(&out),
        ],
        "inside out",
    );
    assert!(!out.exists());
}

/// Arguments are checked before any work, messages name the real cause
/// (with the input value and unit), and each kind of failure has its exit
/// code: 2 command line, 3 input data, 5 a failed write.
#[test]
fn late_checks_and_causes() {
    let code = |args: &[&str]| {
        let out = chisel().args(args).output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    // The output's extension before the (missing) inputs are read, and
    // before a long scenario runs.
    let (c, m) = code(&[
        "boolean", "nope.obj", "nope.obj", "--op", "union", "-o", "x.xyz",
    ]);
    assert_eq!(c, Some(2), "{m}");
    assert!(m.contains(".xyz"), "{m}");
    // It names every format the output can take, the octree file too.
    assert!(m.contains(".chisel"), "{m}");
    let (c, m) = code(&["mill", "--steps", "1000000", "--export", "x.xyz"]);
    assert_eq!(c, Some(2), "{m}");
    let (c, m) = code(&[
        "cheese",
        "--count",
        "1000000",
        "--csv",
        "/no/such/folder/x.csv",
    ]);
    assert_eq!(c, Some(2), "{m}");
    assert!(m.contains("does not exist"), "{m}");
    // A coordinate beyond the grid: the input value and the range in the
    // input's unit, not a saturated grid value.
    let far = temp("far.obj");
    std::fs::write(
        &far,
        "v 0 0 0\nv 1e300 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let out = temp("far-out.obj");
    let (c, m) = code(&[
        "boolean",
        path(&far),
        path(&far),
        "--op",
        "union",
        "-o",
        path(&out),
    ]);
    assert_eq!(c, Some(3), "{m}");
    assert!(
        m.contains("vertex 2") && m.contains("x=1e300") && m.contains("67108.864"),
        "{m}"
    );
    assert!(!m.contains("9223372036854775807"), "{m}");
    // Camera arguments name themselves.
    let classic = scene("classic.quadric.ron");
    let png = temp("camera.png");
    for (option, value) in [("--fov", "0"), ("--eye", "1e300,0,0")] {
        let (c, m) = code(&["trace", path(&classic), option, value, "-o", path(&png)]);
        assert_eq!(c, Some(2), "{m}");
        assert!(m.contains(option) && !m.contains("cone"), "{m}");
    }
    // Vertex numbers in messages count from 1 in every format.
    let nan = temp("nan.obj");
    std::fs::write(&nan, "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let (c, m) = code(&[
        "boolean",
        path(&nan),
        path(&nan),
        "--op",
        "union",
        "-o",
        path(&out),
    ]);
    assert_eq!(c, Some(3), "{m}");
    assert!(m.contains("vertex 2 has a NaN"), "{m}");
}

/// A scene of `n` unions of two spheres under one intersection: `2ⁿ`
/// products in normal form.
fn crossed_unions(n: usize) -> String {
    let mut primitives = String::new();
    let mut factors = Vec::new();
    for i in 0..n {
        let offset = 0.1 * (i + 1) as f64;
        primitives.push_str(&format!(
            "(name: \"a{i}\", shape: Sphere(center: ({offset}, 0, 0), radius: 50)),\n\
             (name: \"b{i}\", shape: Sphere(center: (0, {offset}, 0), radius: 50)),\n"
        ));
        factors.push(format!("Union([Ref(\"a{i}\"), Ref(\"b{i}\")])"));
    }
    format!(
        "Scene(primitives: [{primitives}], root: Intersection([{}]), bounds: (0, 0, 0, 60))",
        factors.join(", ")
    )
}

#[test]
fn a_normal_form_too_large_to_sample_is_refused() {
    // Before: 32,768 products (under the 65,536 limit) grew past 5 GB and
    // aborted; now refused up front, naming the option that raises the limit.
    let file = temp("crossed15.quadric.ron");
    std::fs::write(&file, crossed_unions(15)).unwrap();
    let out = temp("crossed15.ply");
    let args = ["sample", path(&file), "--radius", "2", "-o", path(&out)];
    refused(&args, "--max-memory-mb");
    let status = chisel().args(args).output().unwrap().status;
    assert_eq!(status.code(), Some(3));
    assert!(!out.exists());
    // The limit applies to any scene, and the option sets it.
    let classic = scene("classic.quadric.ron");
    refused(
        &[
            "sample",
            path(&classic),
            "--radius",
            "2",
            "--max-memory-mb",
            "0",
        ],
        "limit of 0 MiB",
    );
}
