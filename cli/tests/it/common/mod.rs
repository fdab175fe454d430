//! Shared by the command-line tests: running `chisel`, its `--json`
//! reports, scratch files, and a box as OBJ text.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// The `chisel` binary under test.
pub fn chisel() -> Command {
    Command::new(env!("CARGO_BIN_EXE_chisel"))
}

/// A scratch path, in a folder of this process and of the test file that
/// asks (its caller's file name), so that files of the same name in two
/// test modules never meet.
#[track_caller]
pub fn temp(name: &str) -> PathBuf {
    let module = Path::new(std::panic::Location::caller().file())
        .file_stem()
        .map_or_else(|| "tests".into(), |s| s.to_string_lossy().into_owned());
    let dir = std::env::temp_dir()
        .join(format!("chisel-cli-tests-{}", std::process::id()))
        .join(module);
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// `p` as a command-line argument.
pub fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs chisel with `args` and `--json`; the parsed one-line report.
pub fn report(args: &[&str]) -> Value {
    let out = chisel().args(args).arg("--json").output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().count(), 1, "{text}");
    serde_json::from_str(&text).unwrap()
}

/// The number `key` of a report.
pub fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number `{key}` in {v}"))
}

/// An axis-aligned box as OBJ text (outward, counter-clockwise faces).
pub fn box_obj(min: [f64; 3], max: [f64; 3]) -> String {
    let mut text = String::new();
    for k in 0..8 {
        let c = |a: usize| if k >> a & 1 == 1 { max[a] } else { min[a] };
        text.push_str(&format!("v {} {} {}\n", c(0), c(1), c(2)));
    }
    // Corner k has bit a set when it is at max along axis a (1-based).
    for face in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ] {
        text.push_str(&format!(
            "f {} {} {} {}\n",
            face[0], face[1], face[2], face[3]
        ));
    }
    text
}
