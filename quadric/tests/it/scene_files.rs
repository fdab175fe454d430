//! Scene files: the shipped scenes parse into the expected solids, and bad
//! files give errors that name the line and the problem.

use chisel_quadric::{Error, SampleOptions, Scene, SplatSet, SurfaceMaterial, sample};
use glam::DVec3;

fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/scenes")
        .join(name)
}

fn parse_error(text: &str) -> (usize, String) {
    match Scene::from_ron(text) {
        Err(Error::Scene { line, message, .. }) => (line, message),
        other => panic!("expected a scene error, got {other:?}"),
    }
}

#[test]
fn three_spheres_scene() {
    let scene = Scene::load(scene_path("three_spheres.quadric.ron")).unwrap();
    assert_eq!(scene.names, ["A", "B", "C"]);
    let dnf = scene.dnf().unwrap();
    assert_eq!(dnf.products().len(), 2);
    let inside = |p: DVec3| scene.dag.contains(scene.root, p).unwrap();
    assert!(inside(DVec3::ZERO)); // in the lens
    assert!(!inside(DVec3::new(-50.0, 0.0, 0.0))); // in A only
    assert!(inside(DVec3::new(0.0, 0.0, 50.0))); // in C
    assert_eq!(scene.color(2), Some([0.35, 0.75, 0.35]));
}

#[test]
fn classic_scene() {
    let scene = Scene::load(scene_path("classic.quadric.ron")).unwrap();
    assert_eq!(scene.dag.primitives().len(), 10); // 6 planes, sphere, 3 cylinders
    assert_eq!(scene.names[0], "cube[0]");
    let dnf = scene.dnf().unwrap();
    // One product: 6 planes, the sphere, and outside each cylinder.
    assert_eq!(dnf.products().len(), 1);
    assert_eq!(dnf.products()[0].len(), 10);
    let inside = |p: DVec3| scene.dag.contains(scene.root, p).unwrap();
    assert!(inside(DVec3::new(40.0, 40.0, 5.0)));
    assert!(!inside(DVec3::new(49.0, 49.0, 49.0))); // corner cut by the sphere
    assert!(!inside(DVec3::new(45.0, 0.0, 0.0))); // bored along x
    assert!(!inside(DVec3::new(0.0, 0.0, 0.0)));
}

#[test]
fn every_shape_parses() {
    let text = r#"
Scene(
    primitives: [
        (name: "h", shape: HalfSpace(normal: (0, 0, 1), offset: 2)),
        (name: "ec", shape: EllipticCylinder(radii: (1, 2))),
        (name: "k", shape: Cone(apex: (0, 0, 0), axis: (0, 0, 1), half_angle_deg: 30)),
        (name: "kc", shape: EllipticCone(radii: (1, 2))),
        (name: "p", shape: EllipticParaboloid(radii: (1, 1))),
        (name: "hp", shape: HyperbolicParaboloid(radii: (1, 1))),
        (name: "h1", shape: HyperboloidOneSheet(radii: (1, 1, 1))),
        (name: "h2", shape: HyperboloidTwoSheets(radii: (1, 1, 1))),
    ],
    root: Complement(Intersection([Ref("h"), Ref("ec"), Ref("k"), Ref("kc"), Ref("p"),
                                   Ref("hp"), Ref("h1"), Ref("h2")])),
)
"#;
    let scene = Scene::from_ron(text).unwrap();
    assert_eq!(scene.dag.primitives().len(), 8);
    let dnf = scene.dnf().unwrap();
    // ¬(h ∩ … ∩ h2) = ¬h ∪ … ∪ ¬h2: eight single-literal products.
    assert_eq!(dnf.products().len(), 8);
    assert!(dnf.products().iter().all(|p| p.len() == 1));
}

#[test]
fn shared_nodes_and_transforms() {
    let text = r#"
Scene(
    primitives: [
        (name: "e", shape: Ellipsoid(center: (0, 0, 0), radii: (1, 2, 3))),
        // A raw matrix: x² + y² + z² − 4, the sphere of radius 2, moved to x = 10.
        (name: "m", shape: Matrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -4]]),
         transform: (translate: (10, 0, 0))),
    ],
    nodes: [
        (name: "pair", node: Union([Ref("e"), Ref("m")])),
    ],
    root: Union([
        Ref("pair"),
        Transform((translate: (0, 100, 0), rotate: (0, 0, 90), scale: (2, 2, 2)), Ref("pair")),
    ]),
)
"#;
    let scene = Scene::from_ron(text).unwrap();
    let inside = |p: DVec3| scene.dag.contains(scene.root, p).unwrap();
    assert!(inside(DVec3::new(11.5, 0.0, 0.0)));
    assert!(!inside(DVec3::new(12.5, 0.0, 0.0)));
    // The copy: scaled by 2 (e's semi-axes 2, 4, 6), rotated 90° about z
    // (its long y-axis along world x), moved to y = 100.
    assert!(inside(DVec3::new(-3.5, 100.0, 0.0)));
    assert!(!inside(DVec3::new(0.0, 103.5, 0.0)));
    // m's copy: radius 4 around (0, 120, 0).
    assert!(inside(DVec3::new(0.0, 123.5, 0.0)));
    // "pair" is one shared node: two primitives, and the DNF has four
    // products (two instances of each).
    assert_eq!(scene.dag.primitives().len(), 2);
    assert_eq!(scene.dnf().unwrap().products().len(), 4);
}

#[test]
fn syntax_error_names_line() {
    let text = "Scene(\n    primitives: [\n        (name: \"A\", shape: Sphere(center: (0, 0, 0) radius: 1)),\n    ],\n    root: Ref(\"A\"),\n)\n";
    let (line, message) = parse_error(text);
    assert_eq!(line, 3, "{message}");
}

#[test]
fn unknown_shape_names_line_and_problem() {
    let text = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n    (name: \"B\", shape: Torus(r: 1)),\n  ],\n  root: Ref(\"A\"),\n)\n";
    let (line, message) = parse_error(text);
    assert_eq!(line, 4);
    assert!(message.contains("Torus"), "{message}");
}

#[test]
fn bad_value_names_line_and_problem() {
    let text = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n    (name: \"B\", shape: Sphere(center: (0, 0, 0), radius: -2)),\n  ],\n  root: Ref(\"A\"),\n)\n";
    let (line, message) = parse_error(text);
    assert_eq!(line, 4);
    assert!(message.contains("radius"), "{message}");
    let colour = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1),\n     color: (2, 0, 0)),\n  ],\n  root: Ref(\"A\"),\n)\n";
    let (line, message) = parse_error(colour);
    assert_eq!(line, 4);
    assert!(message.contains("colour"), "{message}");
}

#[test]
fn empty_operations_name_line() {
    let text = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n  ],\n  root: Union([\n    Ref(\"A\"),\n    Intersection([]),\n  ]),\n)\n";
    let (line, message) = parse_error(text);
    assert_eq!(line, 7);
    assert!(message.contains("Intersection"), "{message}");
    let diff = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n  ],\n  root: Difference([Ref(\"A\")]),\n)\n";
    let (line, message) = parse_error(diff);
    assert_eq!(line, 5);
    assert!(message.contains("Difference"), "{message}");
}

#[test]
fn name_errors_name_line() {
    let unknown = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n  ],\n  root: Union([Ref(\"A\"),\n    Ref(\"Z\")]),\n)\n";
    let (line, message) = parse_error(unknown);
    assert_eq!(line, 6);
    assert!(message.contains("\"Z\""), "{message}");
    let dup = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n    (name: \"A\", shape: Sphere(center: (1, 0, 0), radius: 1)),\n  ],\n  root: Ref(\"A\"),\n)\n";
    let (line, message) = parse_error(dup);
    assert_eq!(line, 3);
    assert!(message.contains("twice"), "{message}");
    let cycle = "Scene(\n  primitives: [],\n  nodes: [\n    (name: \"loop\", node: Complement(Ref(\"loop\"))),\n  ],\n  root: Ref(\"loop\"),\n)\n";
    let (line, message) = parse_error(cycle);
    assert_eq!(line, 4);
    assert!(message.contains("itself"), "{message}");
}

#[test]
fn degenerate_transforms_and_files() {
    let flat = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1),\n     transform: (scale: (1, 0, 1))),\n  ],\n  root: Ref(\"A\"),\n)\n";
    let (line, message) = parse_error(flat);
    assert_eq!(line, 4);
    assert!(message.contains("singular"), "{message}");
    let (_, message) = parse_error("");
    assert!(!message.is_empty());
    assert!(matches!(
        Scene::load(scene_path("no_such_scene.ron")),
        Err(Error::Scene { line: 0, .. })
    ));
}

#[test]
fn out_of_range_transforms_name_the_transform_and_value() {
    let scene = |transform: &str| {
        format!(
            "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1),\n     \
             transform: ({transform})),\n  ],\n  root: Ref(\"A\"),\n)\n"
        )
    };
    for (transform, part, value) in [
        ("scale: (1e300, 1, 1)", "scale", "1e300"),
        ("scale: (1, 1e-300, 1)", "scale", "1e-300"),
        ("scale: (1, 1, inf)", "scale", "inf"),
        ("translate: (0, -1e300, 0)", "translate", "-1e300"),
        ("rotate: (0, 0, 1e300)", "rotate", "1e300"),
        (
            "matrix: [[1e300, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]",
            "matrix row",
            "1e300",
        ),
    ] {
        let (line, message) = parse_error(&scene(transform));
        assert_eq!(line, 4, "{transform}: {message}");
        assert!(
            message.contains(&format!("transform {part} (")) && message.contains(value),
            "{transform}: {message}"
        );
        assert!(message.contains("out of range"), "{transform}: {message}");
        assert!(!message.contains("singular"), "{transform}: {message}");
    }
    // In range, large and small placements still load.
    assert!(Scene::from_ron(&scene("scale: (1e3, 1e3, 1e3), translate: (1e9, 0, 0)")).is_ok());
}

#[test]
fn shipped_scenes_carry_bounds_around_their_solids() {
    for name in ["three_spheres", "classic", "sharp8", "machine80"] {
        let scene = Scene::load(scene_path(&format!("{name}.quadric.ron"))).unwrap();
        let bounds = scene.bounds.unwrap_or_else(|| panic!("{name}: no bounds"));
        // No point of the solid on a coarse grid lies outside the sphere.
        let r = bounds.radius;
        let n = 24;
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    let t = |i: i32| 2.5 * r * (f64::from(i) / f64::from(n) - 0.5);
                    let p = bounds.centre + DVec3::new(t(i), t(j), t(k));
                    if bounds.signed_distance(p) > 0.0 {
                        assert!(
                            !scene.dag.contains(scene.root, p).unwrap(),
                            "{name}: solid at {p} outside its bounds"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn bounds_parse_and_bad_bounds_name_line() {
    let ok = "Scene(primitives: [(name: \"a\", shape: Sphere(center: (0, 0, 0), radius: 1))],\n\
              root: Ref(\"a\"), bounds: (1, 2, 3, 4))";
    let scene = Scene::from_ron(ok).unwrap();
    let b = scene.bounds.unwrap();
    assert_eq!((b.centre, b.radius), (DVec3::new(1.0, 2.0, 3.0), 4.0));
    let none = "Scene(primitives: [(name: \"a\", shape: Sphere(center: (0, 0, 0), radius: 1))], \
                root: Ref(\"a\"))";
    assert!(Scene::from_ron(none).unwrap().bounds.is_none());
    for (bad, what) in [
        ("(0, 0, 0, -5)", "positive radius"),
        ("(0, 0, 0, 0)", "positive radius"),
        ("(0, 0, 0)", ""),
        ("(0, 0, 0, 1, 2)", ""),
    ] {
        let text = format!(
            "Scene(\n primitives: [(name: \"a\", shape: Sphere(center: (0, 0, 0), radius: 1))],\n \
             root: Ref(\"a\"),\n bounds: {bad},\n)"
        );
        let (line, message) = parse_error(&text);
        assert_eq!(line, 4, "{bad}: {message}");
        assert!(message.contains(what), "{bad}: {message}");
    }
}

#[test]
fn metallic_and_roughness_are_per_primitive_and_optional() {
    let text = "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 10), metallic: 1, roughness: 0.25),\n    (name: \"B\", shape: Box(min: (0, 0, 0), max: (5, 5, 5)), roughness: 0.9),\n    (name: \"C\", shape: Sphere(center: (9, 0, 0), radius: 3)),\n  ],\n  root: Union([Ref(\"A\"), Ref(\"B\"), Ref(\"C\")]),\n  bounds: (0, 0, 0, 20),\n)\n";
    let scene = Scene::from_ron(text).unwrap();
    let materials: Vec<_> = scene.dag.primitives().iter().map(|p| p.material).collect();
    let a = SurfaceMaterial {
        metallic: Some(1.0),
        perceptual_roughness: Some(0.25),
    };
    let b = SurfaceMaterial {
        metallic: None,
        perceptual_roughness: Some(0.9),
    };
    // A, the six planes of B, C.
    assert_eq!(materials.len(), 8);
    assert_eq!(materials[0], a);
    assert!(materials[1..7].iter().all(|m| *m == b));
    assert_eq!(materials[7], SurfaceMaterial::default());
    // The splat set's quadric records carry them.
    let dnf = scene.dnf().unwrap();
    let options = SampleOptions::new(1.0, scene.bounds.unwrap()).unwrap();
    let samples = sample(&dnf, &options).unwrap();
    let set = SplatSet::new(&dnf, &scene.dag, &samples);
    for (record, q) in set.quadrics.iter().zip(dnf.quadrics()) {
        assert_eq!(record.material, materials[q.primitive]);
    }
    assert!(set.quadrics.iter().any(|q| q.material == a));
    assert!(set.quadrics.iter().any(|q| q.material == b));
}

#[test]
fn out_of_range_materials_are_typed_errors_naming_the_primitive() {
    for (field, value, shown) in [
        ("roughness", "1.5", "1.5"),
        ("roughness", "-0.25", "-0.25"),
        ("metallic", "NaN", "NaN"),
        ("metallic", "inf", "inf"),
    ] {
        let text = format!(
            "Scene(\n  primitives: [\n    (name: \"A\", shape: Sphere(center: (0, 0, 0), radius: 1)),\n    (name: \"shiny\", shape: Sphere(center: (1, 0, 0), radius: 1), {field}: {value}),\n  ],\n  root: Union([Ref(\"A\"), Ref(\"shiny\")]),\n)\n"
        );
        let error = Scene::from_ron(&text).expect_err("out of range");
        let Error::MaterialOutOfRange {
            primitive,
            field: f,
            line,
            ..
        } = &error
        else {
            panic!("{field}: {value}: expected MaterialOutOfRange, got {error:?}");
        };
        assert_eq!(primitive, "shiny");
        assert_eq!(*f, field);
        assert_eq!(*line, 4);
        let message = error.to_string();
        assert!(
            message.contains("\"shiny\"") && message.contains(field) && message.contains(shown),
            "{message}"
        );
    }
    // The same check guards DAGs built in code.
    let mut dag = chisel_quadric::CsgDag::new();
    let sphere = chisel_quadric::Quadric::sphere(DVec3::ZERO, 1.0).unwrap();
    let bad = SurfaceMaterial {
        metallic: Some(2.0),
        perceptual_roughness: None,
    };
    assert!(matches!(
        dag.try_primitive_with_material(sphere, [1.0; 3], bad),
        Err(Error::MaterialOutOfRange {
            field: "metallic",
            ..
        })
    ));
    assert!(dag.primitives().is_empty(), "nothing added");
}
