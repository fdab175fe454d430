//! Terrains outside the ECS: building from heightfields and meshes, ray
//! casts, and terrain files (bit-identical round trips, typed errors).

use bevy::math::Ray3d;
use bevy::prelude::*;
use bevy_chisel::bsp::octree::store::checksum;
use bevy_chisel::bsp::octree::{Edit, Octree};
use bevy_chisel::bsp::tools::Quantization;
use bevy_chisel::terrain::{
    CarveTool, HeightLayer, Heightfield, Terrain, TerrainError, file::FORMAT_VERSION,
};

fn mm() -> Quantization {
    Quantization::new(0.001, [0.0; 3]).expect("valid unit")
}

fn same_structure(a: &Octree, b: &Octree) -> bool {
    let (la, lb) = (a.leaves(), b.leaves());
    la.len() == lb.len()
        && la
            .iter()
            .zip(&lb)
            .all(|((ka, a), (kb, b))| ka == kb && a.to_bsp() == b.to_bsp())
}

/// A 4 m × 4 m slab of rock (1) with dirt (2) down to 1 m under the surface
/// and grass (3) down to 0.2 m, on a gentle slope.
fn hill() -> Terrain {
    let size = UVec2::new(5, 5);
    let heights = (0..25)
        .map(|k| 0.1 * (k % 5) as f32 + 0.05 * (k / 5) as f32)
        .collect();
    let field = Heightfield {
        size,
        heights,
        spacing: 1.0,
        corner: Vec3::new(-2.0, 0.0, -2.0),
        bottom: -3.0,
        label: 1,
        layers: Vec::new(),
    }
    .with_layers([
        HeightLayer {
            depth: 1.0,
            label: 2,
        },
        HeightLayer {
            depth: 0.2,
            label: 3,
        },
    ]);
    Terrain::from_heightfield(mm(), &field)
        .expect("valid heightfield")
        .with_labels([4, 5])
}

fn label_at(terrain: &Terrain, p: Vec3) -> Option<u8> {
    let g = terrain
        .quantization()
        .to_grid_f32(p.to_array())
        .expect("in range");
    terrain.octree().label_at(g.coords()).expect("in range")
}

#[test]
fn heightfield_layers_follow_the_surface() {
    let terrain = hill();
    // At (0, 0) the surface is at 0.1·2 + 0.05·2 = 0.3.
    assert_eq!(label_at(&terrain, Vec3::new(0.0, 0.35, 0.0)), Some(0));
    assert_eq!(label_at(&terrain, Vec3::new(0.0, 0.25, 0.0)), Some(3));
    assert_eq!(label_at(&terrain, Vec3::new(0.0, -0.3, 0.0)), Some(2));
    assert_eq!(label_at(&terrain, Vec3::new(0.0, -1.0, 0.0)), Some(1));
    assert_eq!(label_at(&terrain, Vec3::new(0.0, -3.1, 0.0)), Some(0));
    let volumes = terrain.octree().volumes();
    // Grass: 0.2 m under 16 m² (in mm³).
    let grass = volumes.get(&3).copied().unwrap_or(0.0) * 1e-9;
    assert!((grass - 0.2 * 16.0).abs() < 1e-6, "grass {grass} m³");
    let total: f64 = volumes.values().sum::<f64>() * 1e-9;
    // Mean height 0.2 + 0.1 = 0.3 above a bottom at −3.
    assert!((total - 3.3 * 16.0).abs() < 1e-6, "total {total} m³");
}

#[test]
fn heightfield_errors_are_typed() {
    let field = Heightfield {
        size: UVec2::new(3, 2),
        heights: vec![0.0; 5],
        spacing: 1.0,
        corner: Vec3::ZERO,
        bottom: -1.0,
        label: 1,
        layers: Vec::new(),
    };
    assert!(matches!(
        Terrain::from_heightfield(mm(), &field),
        Err(TerrainError::InvalidHeightfield { .. })
    ));
    let below = Heightfield {
        heights: vec![0.0; 6],
        bottom: 0.5,
        ..field
    };
    assert!(matches!(
        Terrain::from_heightfield(mm(), &below),
        Err(TerrainError::InvalidHeightfield { .. })
    ));
}

#[test]
fn meshes_import_when_closed_and_fail_clearly_when_open() {
    let cube = Mesh::from(Cuboid::new(2.0, 1.0, 3.0));
    let terrain = Terrain::from_mesh(mm(), &cube, 4).expect("a cuboid is closed");
    let volume = terrain.octree().solid_volume() * 1e-9;
    assert!((volume - 6.0).abs() < 1e-9, "volume {volume}");
    let open = Mesh::from(Plane3d::default().mesh().size(2.0, 2.0));
    match Terrain::from_mesh(mm(), &open, 4) {
        Err(TerrainError::Kernel(bevy_chisel::bsp::Error::NotWatertight { .. })) => {}
        other => panic!("expected NotWatertight, got {:?}", other.err()),
    }
}

#[test]
fn ray_casts_hit_the_surface_and_see_craters() {
    let mut terrain = Terrain::from_box(
        mm(),
        Vec3::new(-2.0, -2.0, -2.0),
        Vec3::new(2.0, 0.0, 2.0),
        1,
    )
    .expect("valid box");
    let down = Ray3d::new(Vec3::new(0.3, 5.0, 0.2), Dir3::NEG_Y);
    let hit = terrain.ray_cast(down, 100.0).expect("hits the top");
    assert!((hit.point.y - 0.0).abs() < 1e-4, "{hit:?}");
    assert!((hit.distance - 5.0).abs() < 1e-4);
    assert!(hit.normal.abs_diff_eq(Vec3::Y, 1e-6), "{hit:?}");
    assert_eq!(hit.label, 1);
    assert!(terrain.ray_cast(down, 4.0).is_none(), "too short");
    let miss = Ray3d::new(Vec3::new(3.0, 5.0, 0.0), Dir3::NEG_Y);
    assert!(terrain.ray_cast(miss, 100.0).is_none());

    // A crater of radius 1 at the surface: the ray now goes deeper.
    let tool = CarveTool::dodecahedron(1.0, Vec3::new(0.3, 0.0, 0.2));
    let grid = tool.to_grid(terrain.quantization()).expect("on the grid");
    terrain
        .apply_now(&grid, Edit::Subtract)
        .expect("valid carve");
    let hit = terrain
        .ray_cast(down, 100.0)
        .expect("hits the crater floor");
    assert!(hit.point.y < -0.7 && hit.point.y > -1.01, "{hit:?}");
    assert_eq!(label_at(&terrain, hit.point + Vec3::Y * 0.002), Some(0));
    assert_eq!(label_at(&terrain, hit.point - Vec3::Y * 0.002), Some(1));
    // Sideways through the crater wall.
    let side = Ray3d::new(Vec3::new(-5.0, -0.5, 0.2), Dir3::X);
    let hit = terrain.ray_cast(side, 100.0).expect("hits the side");
    assert!((hit.point.x + 2.0).abs() < 1e-4);
    assert!(hit.normal.abs_diff_eq(Vec3::NEG_X, 1e-6));
}

#[test]
fn files_round_trip_bit_identically() {
    let mut terrain = hill();
    let q = *terrain.quantization();
    for (k, edit) in [Edit::Subtract, Edit::Add(4), Edit::Paint(5), Edit::Subtract]
        .into_iter()
        .enumerate()
    {
        let at = Vec3::new(-1.0 + 0.6 * k as f32, 0.2, 0.3);
        let grid = CarveTool::dodecahedron(0.7, at)
            .to_grid(&q)
            .expect("on the grid");
        terrain.apply_now(&grid, edit).expect("valid carve");
    }
    let bytes = terrain.to_bytes();
    let loaded = Terrain::from_bytes(&bytes).expect("loads");
    assert!(same_structure(terrain.octree(), loaded.octree()));
    assert_eq!(loaded.journal(), terrain.journal());
    assert_eq!(loaded.base(), terrain.base());
    assert_eq!(loaded.to_bytes(), bytes);
    assert_eq!(loaded.undo_depth(), 4);
    // The labels the journal used are known again after loading.
    assert_eq!(loaded.labels(), terrain.labels());
    assert_eq!(loaded.octree().volumes(), terrain.octree().volumes());

    let dir = std::env::temp_dir().join(format!("chisel-terrain-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("hill.chisel");
    terrain.save(&path).expect("saves");
    let from_file = Terrain::load(&path).expect("loads");
    assert!(same_structure(terrain.octree(), from_file.octree()));
    let _ = std::fs::remove_dir_all(&dir);

    // The undo history came along: undoing the saved terrain and the
    // loaded one step by step gives the same octrees, down to the one
    // before the first carve.
    let mut loaded = loaded;
    for _ in 0..4 {
        assert_eq!(terrain.undo_now(), loaded.undo_now());
        assert!(same_structure(terrain.octree(), loaded.octree()));
        assert_eq!(terrain.to_bytes(), loaded.to_bytes());
    }
    assert!(same_structure(loaded.octree(), hill().octree()));
    assert_eq!(loaded.undo_now(), Err(TerrainError::NothingToUndo));
}

#[test]
fn undo_steps_are_kept_up_to_the_saved_limit_and_share_cells() {
    let slab = Terrain::from_box(
        mm(),
        Vec3::new(-4.0, -2.0, -4.0),
        Vec3::new(4.0, 0.0, 4.0),
        1,
    )
    .expect("valid box");
    let mut terrain = slab.with_max_undo(2);
    let q = *terrain.quantization();
    let carve = |terrain: &mut Terrain, x: f32, z: f32| {
        let grid = CarveTool::dodecahedron(0.3, Vec3::new(x, 0.0, z))
            .to_grid(&q)
            .expect("on the grid");
        terrain
            .apply_now(&grid, Edit::Subtract)
            .expect("valid carve");
    };
    // Enough craters that the octree splits into cells.
    for k in 0..16 {
        let (x, z) = ((k % 4) as f32, (k / 4) as f32);
        carve(&mut terrain, -3.0 + 2.0 * x, -3.0 + 2.0 * z);
    }
    assert_eq!(terrain.undo_depth(), 2);
    let bytes = terrain.to_bytes();
    // The octree before each undo step shares the cells that step did not
    // change with the next one, in the file too: far less than three
    // separate octree files.
    assert!(terrain.octree().stats().leaves > 8);
    let at = bytes
        .windows(8)
        .position(|w| w == b"CHISELOC")
        .expect("an octree snapshot");
    let mut length = [0; 8];
    length.copy_from_slice(&bytes[at - 8..at]);
    let snapshots = u64::from_le_bytes(length) as usize;
    let mut steps = Terrain::from_bytes(&bytes).expect("loads");
    let mut separate = steps.octree().to_bytes().len();
    while steps.undo_now().is_ok() {
        separate += steps.octree().to_bytes().len();
    }
    assert!(10 * snapshots < 7 * separate, "{snapshots} vs {separate}");

    let mut loaded = Terrain::from_bytes(&bytes).expect("loads");
    assert_eq!(loaded.undo_depth(), 2);
    carve(&mut loaded, 0.0, 0.0);
    assert_eq!(loaded.undo_depth(), 2, "the limit came along");
    assert_eq!(loaded.journal().len(), 17);
}

#[test]
fn damaged_files_give_typed_errors() {
    let mut terrain = hill();
    let q = *terrain.quantization();
    let grid = CarveTool::dodecahedron(0.7, Vec3::new(0.0, 0.3, 0.0))
        .to_grid(&q)
        .expect("on the grid");
    terrain
        .apply_now(&grid, Edit::Subtract)
        .expect("valid carve");
    let bytes = terrain.to_bytes();

    let mut magic = bytes.clone();
    magic[0] = b'X';
    assert_eq!(
        Terrain::from_bytes(&magic).err(),
        Some(TerrainError::BadMagic)
    );

    let mut version = bytes.clone();
    version[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    assert_eq!(
        Terrain::from_bytes(&version).err(),
        Some(TerrainError::UnsupportedVersion {
            found: FORMAT_VERSION + 1,
            supported: FORMAT_VERSION
        })
    );

    assert!(matches!(
        Terrain::from_bytes(&bytes[..10]),
        Err(TerrainError::Truncated { .. })
    ));
    assert!(matches!(
        Terrain::from_bytes(&bytes[..bytes.len() - 3]),
        Err(TerrainError::Corrupt { .. })
    ));
    let mut flipped = bytes.clone();
    let middle = bytes.len() / 2;
    flipped[middle] ^= 0x10;
    assert!(matches!(
        Terrain::from_bytes(&flipped),
        Err(TerrainError::Corrupt { .. })
    ));
    match Terrain::load("/nonexistent/terrain.chisel") {
        Err(TerrainError::Io { message }) => {
            assert!(message.contains("/nonexistent/terrain.chisel"), "{message}");
        }
        other => panic!("expected Io, got {:?}", other.err()),
    }
    // A bad file's error names it.
    let path = std::env::temp_dir().join(format!("bevy_chisel-bad-{}.chisel", std::process::id()));
    std::fs::write(&path, &magic).expect("writes");
    let error = Terrain::load(&path).err().expect("a bad file");
    assert_eq!(error.in_file(), &TerrainError::BadMagic);
    assert!(
        error.to_string().starts_with(&path.display().to_string()),
        "{error}"
    );
    let _ = std::fs::remove_file(&path);

    // Damage inside the octree snapshot behind a valid outer checksum is
    // found by the kernel's own checks.
    let snapshot = bytes
        .windows(8)
        .position(|w| w == b"CHISELOC")
        .expect("an octree snapshot");
    let mut inner = bytes.clone();
    inner[snapshot + 30] ^= 0x40;
    let end = inner.len() - 8;
    let sum = checksum(&inner[..end]);
    inner[end..].copy_from_slice(&sum.to_le_bytes());
    match Terrain::from_bytes(&inner) {
        Err(TerrainError::Corrupt { reason }) => {
            assert!(reason.starts_with("octree snapshot:"), "{reason}");
        }
        other => panic!("expected Corrupt, got {:?}", other.err()),
    }
}

#[test]
fn an_unknown_material_is_refused_and_changes_nothing() {
    let mut terrain = hill();
    let bytes = terrain.to_bytes();
    let grid = CarveTool::dodecahedron(0.7, Vec3::new(0.0, 0.2, 0.0))
        .to_grid(terrain.quantization())
        .expect("on the grid");
    for edit in [Edit::Add(6), Edit::Paint(200)] {
        let error = terrain.apply_now(&grid, edit).expect_err("unknown label");
        assert!(
            matches!(error, TerrainError::UnknownLabel { known: ref k, .. } if k == &[1, 2, 3, 4, 5]),
            "{error:?}"
        );
        assert!(error.to_string().contains("with_labels"), "{error}");
    }
    assert_eq!(terrain.to_bytes(), bytes, "a refused carve left a trace");
    // Declared, the same label is accepted.
    let mut terrain = terrain.with_labels([6]);
    terrain
        .apply_now(&grid, Edit::Add(6))
        .expect("declared label");
    assert_eq!(terrain.journal().len(), 1);
}

/// Damage anywhere in a terrain file, behind a valid outer checksum (which
/// would otherwise catch it): reading never panics, and what reads passes
/// the kernel's checks, saves and reads back to the same state, and can
/// still be carved and undone. Half the cases damage the records before the octree
/// snapshot (grid, base, journal, undo steps), half the snapshot; one in
/// four cuts the file short instead. `CHISEL_FUZZ_CASES` sets the number
/// of damaged files (default 400; `scripts/fuzz` runs 20,000).
#[test]
fn damaged_terrain_files_read_or_fail_typed_never_panic() {
    let mut terrain = hill();
    let q = *terrain.quantization();
    let grid = |radius: f32, at: Vec3| {
        CarveTool::dodecahedron(radius, at)
            .to_grid(&q)
            .expect("on the grid")
    };
    terrain
        .apply_now(&grid(0.7, Vec3::new(0.0, 0.3, 0.0)), Edit::Subtract)
        .expect("valid carve");
    terrain
        .apply_now(&grid(0.5, Vec3::new(1.0, 0.4, 0.5)), Edit::Add(2))
        .expect("valid carve");
    let bytes = terrain.to_bytes();
    let snapshot = bytes
        .windows(8)
        .position(|w| w == b"CHISELOC")
        .expect("an octree snapshot");
    let cases: u64 = std::env::var("CHISEL_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(400);
    let mut state = 0x5eed_u64;
    let mut next = move || {
        // SplitMix64: the same cases on every run.
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let tool = grid(0.4, Vec3::new(-1.0, 0.3, -1.0));
    let (mut read, mut refused) = (0u64, 0u64);
    for case in 0..cases {
        let body = bytes.len() - 8;
        let (lo, hi) = if case % 2 == 0 {
            (12, snapshot)
        } else {
            (snapshot, body)
        };
        let mut damaged = bytes.clone();
        let mut what = Vec::new();
        if case % 4 == 3 {
            let cut = lo + (next() as usize) % (hi - lo);
            damaged.truncate(cut);
            damaged.extend_from_slice(&[0; 8]);
            what.push(format!("cut at {cut}"));
        } else {
            for _ in 0..1 + next() % 3 {
                let at = lo + (next() as usize) % (hi - lo);
                let value = next() as u8;
                damaged[at] = if damaged[at] == value { !value } else { value };
                what.push(format!("byte {at} = {}", damaged[at]));
            }
        }
        let end = damaged.len() - 8;
        let sum = checksum(&damaged[..end]);
        damaged[end..].copy_from_slice(&sum.to_le_bytes());
        let outcome = std::panic::catch_unwind(|| Terrain::from_bytes(&damaged));
        match outcome {
            Err(_) => panic!("case {case}: reading panicked ({what:?})"),
            Ok(Err(_)) => refused += 1,
            Ok(Ok(mut loaded)) => {
                read += 1;
                let again = Terrain::from_bytes(&loaded.to_bytes()).map(|t| t.state_hash());
                assert_eq!(again, Ok(loaded.state_hash()), "case {case}: {what:?}");
                let used = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    let _ = loaded.apply_now(&tool, Edit::Subtract);
                    // The loaded undo steps, down to the base.
                    while loaded.undo_now().is_ok() {}
                }));
                assert!(
                    used.is_ok(),
                    "case {case}: carving or undoing panicked ({what:?})"
                );
            }
        }
    }
    println!("{cases} damaged files: {read} read, {refused} refused with a typed error");
    assert!(refused > cases / 4, "most damage is found");
}
