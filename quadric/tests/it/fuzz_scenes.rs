//! Property-based fuzzing of the scene reader (`Scene::from_ron`): the
//! bundled scenes damaged at random never panic, neither when read nor
//! when normalized (`Scene::dnf`), and an accepted scene has finite
//! quadrics. The case count is small in the normal run; `scripts/fuzz`
//! raises it (`PROPTEST_CASES`).

use chisel_quadric::Scene;
use proptest::prelude::*;

/// `PROPTEST_CASES` when set (long runs), else `default`.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn scenes() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    names.sort();
    names
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect()
}

/// Pieces of scene syntax and hostile numbers to splice in.
const PIECES: &[&str] = &[
    "1e300",
    "-1e300",
    "0",
    "-0",
    "nan",
    "inf",
    "1e-320",
    "(",
    ")",
    "[",
    "]",
    ",",
    ":",
    "Union",
    "Intersection",
    "Difference",
    "Complement",
    "Ref(\"a\")",
    "Sphere",
    "scale",
    "radius",
    "\"",
    "//",
    "/*",
    "Some(",
    "None",
    "(0, 0, 0)",
    "99999999999999999999",
];

#[derive(Clone, Debug)]
enum Edit {
    Delete(usize, usize),
    Insert(usize, usize),
    Repeat(usize, usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), 1..40usize).prop_map(|(a, n)| Edit::Delete(a, n)),
        (any::<usize>(), 0..PIECES.len()).prop_map(|(a, k)| Edit::Insert(a, k)),
        (any::<usize>(), 1..200usize).prop_map(|(a, n)| Edit::Repeat(a, n)),
    ]
}

/// The char boundary at or before byte `at % len`.
fn boundary(text: &str, at: usize) -> usize {
    let mut at = at % text.len().max(1);
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases(96)))]

    #[test]
    fn fuzz_damaged_scenes_never_panic(
        which in any::<usize>(),
        edits in proptest::collection::vec(edit(), 1..5),
    ) {
        let all = scenes();
        let mut text = all[which % all.len()].clone();
        for e in &edits {
            match *e {
                Edit::Delete(a, n) => {
                    let a = boundary(&text, a);
                    let b = boundary(&text, a + n).max(a);
                    text.replace_range(a..b, "");
                }
                Edit::Insert(a, k) => {
                    let a = boundary(&text, a);
                    text.insert_str(a, PIECES[k]);
                }
                Edit::Repeat(a, n) => {
                    let a = boundary(&text, a);
                    let b = boundary(&text, a + n).max(a);
                    let run = text[a..b].to_string();
                    text.insert_str(a, &run);
                }
            }
        }
        if let Ok(scene) = Scene::from_ron(&text)
            && let Ok(dnf) = scene.dnf()
        {
            prop_assert!(dnf
                .quadrics()
                .iter()
                .all(|q| q.quadric.coefficients().iter().all(|c| c.is_finite())));
        }
    }
}
