//! Hostile input: parameters the commands accept in form but that would
//! take unbounded work, wrap, or silently break a guarantee. Each is
//! refused up front with a message naming the cause (and how to go on),
//! an exit code rather than an abort, and no output file.

mod common;

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
    let classic = scene("classic.ron");
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
    let classic = scene("classic.ron");
    let s = path(&classic);
    // Before: 18,672 samples at 1e8 and none at 1e10, both with exit 0.
    for r in ["0,0,0,1e8", "0,0,0,1e10", "0,0,0,1e300"] {
        refused(&["sample", s, "--radius", "2", "--bounds", r], "coverage");
    }
}

#[test]
fn oversized_counts_are_refused_by_the_parser() {
    let classic = scene("classic.ron");
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
