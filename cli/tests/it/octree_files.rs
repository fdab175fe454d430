//! Exact octree files (`.chisel`) end to end: a scenario's result exported
//! exactly and combined again with no re-import (`A ∩ A = A`, `A − A = ∅`,
//! checked exactly by differences of volume zero), a replay continuing from
//! a stored octree with the identical result, and damaged files reported
//! with exit code 3.

use crate::common;

use std::path::Path;

use common::{box_obj, chisel, f, path, report, temp};
use serde_json::Value;

fn boolean(a: &Path, b: &Path, op: &str, out: &Path) -> Value {
    report(&["boolean", path(a), path(b), "--op", op, "-o", path(out)])
}

/// Whether two octree files hold exactly the same solid: both
/// differences are empty, so their volume is exactly zero.
fn same_solid(a: &Path, b: &Path) -> bool {
    let scratch = temp("difference.chisel");
    f(&boolean(a, b, "difference", &scratch), "volume_mm3") == 0.0
        && f(&boolean(b, a, "difference", &scratch), "volume_mm3") == 0.0
}

#[test]
fn a_cheese_result_combines_with_itself_exactly() {
    let cheese = temp("c14.chisel");
    let r = report(&["cheese", "--count", "14", "--export", path(&cheese)]);
    let bytes = std::fs::read(&cheese).unwrap();
    assert_eq!(&bytes[..8], b"CHISELOC");

    let meet = temp("meet.chisel");
    let m = boolean(&cheese, &cheese, "intersection", &meet);
    // The file is the scenario's octree itself: the same volume, bit for
    // bit, as the scenario reported.
    assert_eq!(f(&m, "a_volume_mm3"), f(&r, "volume_mm3"), "{m}");
    assert_eq!(m["a_triangles"], Value::Null);
    assert_eq!(m["closed"].as_bool(), Some(true), "{m}");
    let relative = (f(&m, "volume_mm3") - f(&r, "volume_mm3")).abs() / f(&r, "volume_mm3");
    assert!(relative < 1e-12, "{m}");
    assert!(same_solid(&meet, &cheese), "A ∩ A = A exactly");

    let join = temp("join.chisel");
    boolean(&cheese, &cheese, "union", &join);
    assert!(same_solid(&join, &cheese), "A ∪ A = A exactly");

    let nothing = temp("nothing.obj");
    let d = boolean(&cheese, &cheese, "difference", &nothing);
    assert_eq!(f(&d, "volume_mm3"), 0.0, "{d}");
    assert_eq!(f(&d, "triangles"), 0.0, "{d}");
}

#[test]
fn a_replay_continues_from_a_stored_octree() {
    let stored = temp("c6.chisel");
    let r = report(&["cheese", "--count", "6", "--export", path(&stored)]);
    // No steps: the stored octree itself, so the same surface to the bit.
    let same = temp("same.jsonl");
    std::fs::write(&same, "{\"base\": {\"mesh\": \"c6.chisel\"}}\n").unwrap();
    let s = report(&["replay", path(&same)]);
    assert_eq!(s["mesh_hash"], r["mesh_hash"]);
    assert_eq!(f(&s, "volume_mm3"), f(&r, "volume_mm3"));

    // One box subtracted by a replay step, and by `boolean` from a mesh of
    // the same box: exactly the same solid.
    let step = temp("step.jsonl");
    std::fs::write(
        &step,
        "{\"base\": {\"mesh\": \"c6.chisel\"}}\n\
         {\"op\": \"subtract\", \"hull\": [[20,20,20],[60,20,20],[20,60,20],[60,60,20],\
         [20,20,110],[60,20,110],[20,60,110],[60,60,110]]}\n",
    )
    .unwrap();
    let replayed = temp("replayed.chisel");
    let p = report(&["replay", path(&step), "--export", path(&replayed)]);
    assert!(f(&p, "volume_mm3") < f(&r, "volume_mm3"));
    let block = temp("block.obj");
    std::fs::write(&block, box_obj([20.0; 3], [60.0, 60.0, 110.0])).unwrap();
    let combined = temp("combined.chisel");
    boolean(&stored, &block, "difference", &combined);
    assert!(same_solid(&replayed, &combined));

    // A step beyond the stored cube: the octree moves into a larger cube
    // exactly, and the new material is all there.
    let outside = temp("outside.jsonl");
    std::fs::write(
        &outside,
        "{\"base\": {\"mesh\": \"c6.chisel\"}}\n\
         {\"op\": \"union\", \"hull\": [[-50,0,0],[-40,0,0],[-50,10,0],[-40,10,0],\
         [-50,0,10],[-40,0,10],[-50,10,10],[-40,10,10]]}\n",
    )
    .unwrap();
    let o = report(&["replay", path(&outside)]);
    let added = f(&o, "volume_mm3") - f(&r, "volume_mm3");
    assert!((added - 1000.0).abs() < 1e-6, "{o}");
}

#[test]
fn damaged_octree_files_are_errors_with_exit_code_2() {
    let good = temp("good.chisel");
    report(&["mill", "--steps", "3", "--export", path(&good)]);
    let bytes = std::fs::read(&good).unwrap();
    let truncated = temp("truncated.chisel");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let mut flipped = bytes.clone();
    let middle = bytes.len() / 2;
    flipped[middle] ^= 1;
    let damaged = temp("damaged.chisel");
    std::fs::write(&damaged, &flipped).unwrap();
    let text = temp("text.chisel");
    std::fs::write(&text, "solid nothing\nendsolid\n").unwrap();
    for (file, expected) in [
        (&truncated, "truncated"),
        (&damaged, "damaged"),
        (&text, "not a chisel octree file"),
        (&temp("missing.chisel"), "missing.chisel"),
    ] {
        let out = chisel()
            .args(["boolean", path(file), path(&good), "--op", "union", "-o"])
            .arg(temp("never.obj"))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(3), "{}", file.display());
        let message = String::from_utf8_lossy(&out.stderr);
        assert!(message.contains(expected), "{message}");
    }
}

/// Two materials meeting inside a block: the interface between them is
/// reported once, so the surface as a whole has edges used once and never
/// reversed, yet every material's region (its own faces, and the
/// interface faces turned round for the material in front) is closed.
/// `boolean` and a replay `--check` must call such a surface closed.
#[test]
fn a_two_material_octree_is_closed() {
    use chisel_bsp::octree::{CellBox, Edit, Octree, OctreeConfig, Tool};
    let mut octree = Octree::from_box(
        [0; 3],
        17,
        CellBox {
            min: [0; 3],
            max: [100_000; 3],
        },
        1,
        OctreeConfig::default(),
    )
    .unwrap();
    // The upper part of the block becomes material 2, with faces on the
    // outside as well as an interface with material 1.
    let upper = Tool::cuboid(CellBox {
        min: [0, 0, 60_000],
        max: [100_000, 100_000, 100_000],
    })
    .unwrap();
    octree.apply(&upper, Edit::Paint(2)).unwrap();
    let two = temp("two-materials.chisel");
    octree.save(&two).unwrap();

    let out = temp("two-out.chisel");
    let m = boolean(&two, &two, "intersection", &out);
    assert_eq!(m["closed"].as_bool(), Some(true), "{m}");
    assert_eq!(f(&m, "volume_mm3"), 1e6, "{m}");

    let replay = temp("two.jsonl");
    std::fs::write(
        &replay,
        "{\"base\": {\"mesh\": \"two-materials.chisel\"}}\n\
         {\"op\": \"subtract\", \"hull\": [[20,20,50],[60,20,50],[20,60,50],[60,60,50],\
         [20,20,110],[60,20,110],[20,60,110],[60,60,110]]}\n",
    )
    .unwrap();
    let out = chisel()
        .args(["replay", path(&replay), "--check", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["closed"].as_bool(), Some(true), "{r}");
}
