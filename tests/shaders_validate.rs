//! Every WGSL file under `shaders/` passes naga's parser and validator, the
//! way Bevy composes it: modules with `#define_import_path` are registered
//! with naga_oil's composer, and every other file is composed with every
//! combination of the shader defines it lists in a `// Defines: A, B.`
//! comment line. A shader error therefore fails `cargo test` on a machine
//! without a GPU.
//!
//! Shaders that import Bevy's shader library (`#import bevy_pbr::…`), directly
//! or through one of our modules (the splat passes' PBR shading), are
//! composed with that library, read from the Bevy crates' sources that this
//! build uses, and with the defines Bevy's mesh pipeline sets for a
//! forward-rendered mesh with positions and normals.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use naga::valid::Capabilities;
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderDefValue, ShaderLanguage,
    ShaderType,
};

fn shader_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders")
}

fn wgsl_files() -> Vec<(String, String)> {
    let mut files: Vec<(String, String)> = std::fs::read_dir(shader_dir())
        .expect("shaders/ is readable")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("shader is readable");
            (p.display().to_string(), text)
        })
        .collect();
    files.sort();
    files
}

/// Imports a module of Bevy's shader library.
fn imports_bevy(source: &str) -> bool {
    source.lines().any(|l| {
        let l = l.trim_start();
        [
            "#import bevy_pbr",
            "#import bevy_render",
            "#import bevy_core_pipeline",
        ]
        .iter()
        .any(|p| l.starts_with(p))
    })
}

/// The `#define_import_path` of a module.
fn import_path(source: &str) -> Option<&str> {
    source.lines().find_map(|l| {
        l.trim_start()
            .strip_prefix("#define_import_path")
            .map(str::trim)
    })
}

/// The files that import Bevy's shader library, directly or through a
/// module of ours that does.
fn needing_bevy(files: &[(String, String)]) -> Vec<String> {
    let mut paths: Vec<String> = Vec::new();
    let mut needing: Vec<String> = files
        .iter()
        .filter(|(_, s)| imports_bevy(s))
        .map(|(p, _)| p.clone())
        .collect();
    loop {
        paths.extend(
            files
                .iter()
                .filter(|(p, _)| needing.contains(p))
                .filter_map(|(_, s)| import_path(s))
                .map(|m| format!("#import {m}")),
        );
        let more: Vec<String> = files
            .iter()
            .filter(|(p, s)| {
                !needing.contains(p)
                    && s.lines()
                        .any(|l| paths.iter().any(|m| l.trim_start().starts_with(m.as_str())))
            })
            .map(|(p, _)| p.clone())
            .collect();
        if more.is_empty() {
            return needing;
        }
        needing.extend(more);
    }
}

fn is_module(source: &str) -> bool {
    source
        .lines()
        .any(|l| l.trim_start().starts_with("#define_import_path"))
}

/// The defines listed in `// Defines: A, B, C.` lines.
fn listed_defines(source: &str) -> Vec<String> {
    let mut defines = Vec::new();
    let mut in_list = false;
    for line in source.lines() {
        let Some(comment) = line.trim_start().strip_prefix("//") else {
            in_list = false;
            continue;
        };
        let comment = comment.trim();
        let rest = if let Some(rest) = comment.strip_prefix("Defines:") {
            in_list = true;
            rest
        } else if in_list {
            comment
        } else {
            continue;
        };
        for word in rest.split([',', ' ', '.', '(', ')']) {
            if !word.is_empty() && word.chars().all(|c| c.is_ascii_uppercase() || c == '_') {
                defines.push(word.to_owned());
            }
        }
        if comment.ends_with('.') {
            in_list = false;
        }
    }
    defines.sort();
    defines.dedup();
    defines
}

/// A composer holding our modules that do not need Bevy's library.
fn composer(files: &[(String, String)]) -> Composer {
    let composer = Composer::default()
        .with_capabilities(Capabilities::default() | Capabilities::EARLY_DEPTH_TEST);
    let bevy = needing_bevy(files);
    let own: Vec<&(String, String)> = files
        .iter()
        .filter(|(p, s)| is_module(s) && !bevy.contains(p))
        .collect();
    add_modules(composer, &own, &HashMap::new())
}

/// Adds `modules` (which may import each other) to `composer`.
fn add_modules(
    mut composer: Composer,
    modules: &[&(String, String)],
    shader_defs: &HashMap<String, ShaderDefValue>,
) -> Composer {
    // Modules may import each other: add until no more can be added.
    let mut pending: Vec<&(String, String)> = modules.to_vec();
    while !pending.is_empty() {
        let before = pending.len();
        let mut errors = Vec::new();
        pending.retain(|(path, source)| {
            match composer.add_composable_module(ComposableModuleDescriptor {
                source,
                file_path: path,
                language: ShaderLanguage::Wgsl,
                shader_defs: shader_defs.clone(),
                ..Default::default()
            }) {
                Ok(_) => false,
                Err(e) => {
                    errors.push(e.emit_to_string(&composer));
                    true
                }
            }
        });
        assert!(
            pending.len() < before,
            "shader modules do not compose:\n{}",
            errors.join("\n")
        );
    }
    composer
}

#[test]
fn every_wgsl_file_validates_with_every_define_combination() {
    let files = wgsl_files();
    assert!(
        files
            .iter()
            .any(|(p, _)| p.ends_with("quadric_common.wgsl")),
        "the quadric module is missing"
    );
    // Every module without Bevy composes (or `composer` fails).
    let mut composer = composer(&files);
    let bevy = needing_bevy(&files);
    let mut checked = 0;
    for (path, source) in files
        .iter()
        .filter(|(p, s)| !is_module(s) && !bevy.contains(p))
    {
        let defines = listed_defines(source);
        assert!(defines.len() <= 8, "{path}: too many defines to enumerate");
        for mask in 0u32..(1 << defines.len()) {
            let shader_defs: HashMap<String, ShaderDefValue> = defines
                .iter()
                .enumerate()
                .filter(|(i, _)| mask & (1 << i) != 0)
                .map(|(_, d)| (d.clone(), ShaderDefValue::Bool(true)))
                .collect();
            let result = composer.make_naga_module(NagaModuleDescriptor {
                source,
                file_path: path,
                shader_type: ShaderType::Wgsl,
                shader_defs: shader_defs.clone(),
                ..Default::default()
            });
            if let Err(e) = result {
                let mut names: Vec<_> = shader_defs.keys().collect();
                names.sort();
                panic!(
                    "{path} with defines {names:?} does not validate:\n{}",
                    e.emit_to_string(&composer)
                );
            }
            checked += 1;
        }
    }
    println!("{checked} shader variants without Bevy's library checked");
}

/// The version of `name` in `Cargo.lock`.
fn locked_version(name: &str) -> String {
    let lock = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.lock"))
        .expect("Cargo.lock is readable");
    let entry = format!("name = \"{name}\"\nversion = \"");
    let start = lock.find(&entry).map(|i| i + entry.len());
    let version = start.and_then(|i| lock[i..].split('"').next());
    version
        .unwrap_or_else(|| panic!("{name} is not in Cargo.lock"))
        .to_owned()
}

/// The WGSL modules (`#define_import_path`) of the Bevy crates whose shader
/// library materials import, from the crates' sources in Cargo's registry
/// (`$CARGO_HOME/registry/src/*/{crate}-{locked version}/src`).
fn bevy_shader_library() -> Vec<(String, String)> {
    let cargo_home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")))
        .expect("CARGO_HOME or HOME is set");
    let registry = cargo_home.join("registry").join("src");
    let indexes: Vec<PathBuf> = std::fs::read_dir(&registry)
        .unwrap_or_else(|e| panic!("{}: {e}", registry.display()))
        .flatten()
        .map(|e| e.path())
        .collect();
    let mut dirs: Vec<PathBuf> = ["bevy_pbr", "bevy_render", "bevy_core_pipeline"]
        .iter()
        .map(|name| {
            let dir = format!("{name}-{}", locked_version(name));
            indexes
                .iter()
                .map(|index| index.join(&dir).join("src"))
                .find(|src| src.is_dir())
                .unwrap_or_else(|| panic!("{dir} is not under {}", registry.display()))
        })
        .collect();
    dirs.sort();
    let mut files = Vec::new();
    let mut stack = dirs;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir)
            .expect("Bevy source is readable")
            .flatten()
        {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "wgsl") {
                let text = std::fs::read_to_string(&path).expect("shader is readable");
                if is_module(&text) {
                    files.push((path.display().to_string(), text));
                }
            }
        }
    }
    files.sort();
    files
}

/// The defines of Bevy 0.19's mesh pipeline for an opaque, forward-rendered
/// mesh with positions and normals under a perspective camera with one
/// shadowed directional light (`bevy_pbr/src/render/mesh.rs`, `light.rs`,
/// `material.rs`).
fn bevy_mesh_defines() -> HashMap<String, ShaderDefValue> {
    let mut defs: HashMap<String, ShaderDefValue> = [
        "MESH_PIPELINE",
        "VERTEX_OUTPUT_INSTANCE_INDEX",
        "VERTEX_POSITIONS",
        "VERTEX_NORMALS",
        "VIEW_PROJECTION_PERSPECTIVE",
        "SHADOW_FILTER_METHOD_GAUSSIAN",
        "TONEMAP_METHOD_TONY_MC_MAPFACE",
    ]
    .into_iter()
    .map(|d| (d.to_owned(), ShaderDefValue::Bool(true)))
    .collect();
    for (name, value) in [
        ("MAX_DIRECTIONAL_LIGHTS", 10),
        ("MAX_CASCADES_PER_LIGHT", 4),
        ("MAX_RECT_LIGHTS", 8),
        ("MATERIAL_BIND_GROUP", 3),
        ("AVAILABLE_STORAGE_BUFFER_BINDINGS", 8),
        ("TONEMAPPING_LUT_TEXTURE_BINDING_INDEX", 18),
        ("TONEMAPPING_LUT_SAMPLER_BINDING_INDEX", 19),
    ] {
        defs.insert(name.to_owned(), ShaderDefValue::UInt(value));
    }
    defs.insert(
        "SCREEN_SPACE_SPECULAR_TRANSMISSION_BLUR_TAPS".to_owned(),
        ShaderDefValue::Int(8),
    );
    defs
}

#[test]
fn material_shaders_validate_with_bevys_shader_library() {
    let files = wgsl_files();
    let bevy = needing_bevy(&files);
    let materials: Vec<_> = files
        .iter()
        .filter(|(p, s)| bevy.contains(p) && !is_module(s))
        .collect();
    for shader in ["terrain_triplanar.wgsl", "splat.wgsl", "global.wgsl"] {
        assert!(
            materials.iter().any(|(p, _)| p.ends_with(shader)),
            "{shader} is missing or does not import Bevy's PBR shading"
        );
    }
    let base = bevy_mesh_defines();
    let mut composer = Composer::default()
        .with_capabilities(Capabilities::default() | Capabilities::EARLY_DEPTH_TEST);
    // Bevy's modules import each other: add until no more can be added
    // (modules this configuration cannot compose stay out; a shader that
    // needs one fails below).
    let mut pending = bevy_shader_library();
    let mut left_out = Vec::new();
    loop {
        let before = pending.len();
        left_out.clear();
        pending.retain(|(path, source)| {
            match composer.add_composable_module(ComposableModuleDescriptor {
                source,
                file_path: path,
                language: ShaderLanguage::Wgsl,
                shader_defs: base.clone(),
                ..Default::default()
            }) {
                Ok(_) => false,
                Err(e) => {
                    left_out.push(format!("{path}: {}", e.emit_to_string(&composer)));
                    true
                }
            }
        });
        if pending.is_empty() || pending.len() == before {
            break;
        }
    }
    // Then ours, all of them (those with Bevy import those without).
    let own: Vec<&(String, String)> = files.iter().filter(|(_, s)| is_module(s)).collect();
    let mut composer = add_modules(composer, &own, &base);
    for (path, source) in materials {
        let defines = listed_defines(source);
        assert!(defines.len() <= 8, "{path}: too many defines to enumerate");
        for mask in 0u32..(1 << defines.len()) {
            let mut shader_defs = base.clone();
            for (i, d) in defines.iter().enumerate() {
                if mask & (1 << i) != 0 {
                    shader_defs.insert(d.clone(), ShaderDefValue::Bool(true));
                }
            }
            let result = composer.make_naga_module(NagaModuleDescriptor {
                source,
                file_path: path,
                shader_type: ShaderType::Wgsl,
                shader_defs,
                ..Default::default()
            });
            match result {
                Ok(module) if path.ends_with("terrain_triplanar.wgsl") => {
                    check_triplanar_uniform(&module);
                }
                Ok(_) => {}
                Err(e) => panic!(
                    "{path} (defines mask {mask:#b} of {defines:?}) does not validate:\n{}\n\
                     Bevy modules left out:\n{}",
                    e.emit_to_string(&composer),
                    left_out.join("\n")
                ),
            }
        }
    }
}

/// The WGSL `Triplanar` uniform has the `f32` fields of
/// `TriplanarExtension` (its `#[uniform(100)]` fields), in order, 4 bytes
/// apart, as the derived uniform lays them out.
fn check_triplanar_uniform(module: &naga::Module) {
    use bevy::reflect::structs::Struct;
    use bevy_chisel::terrain::TriplanarExtension;

    let extension = TriplanarExtension::new(Default::default(), Default::default());
    let rust: Vec<(String, u32)> = (0..extension.field_len())
        .filter(|&i| {
            extension
                .field_at(i)
                .is_some_and(|f| f.try_downcast_ref::<f32>().is_some())
        })
        .zip(0u32..)
        .map(|(i, k)| (extension.name_at(i).unwrap_or_default().to_owned(), 4 * k))
        .collect();
    let wgsl = module
        .types
        .iter()
        .find_map(|(_, t)| match (&t.name, &t.inner) {
            (Some(name), naga::TypeInner::Struct { members, .. }) if name == "Triplanar" => Some(
                members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect::<Vec<_>>(),
            ),
            _ => None,
        })
        .expect("struct Triplanar in terrain_triplanar.wgsl");
    assert_eq!(wgsl, rust, "WGSL Triplanar against TriplanarExtension");
}

#[test]
fn listed_defines_are_parsed_from_comments() {
    let source = "// Defines: A_B, EARLY_DEPTH_TEST,\n// OUTPUT_IDS (ids).\nfn f() {}\n";
    assert_eq!(
        listed_defines(source),
        vec!["A_B", "EARLY_DEPTH_TEST", "OUTPUT_IDS"]
    );
}

/// `(size, [(member, offset)])` of a `#[repr(C)]` struct: every field, in
/// declaration order.
macro_rules! rust_layout {
    ($t:ty: $($field:ident),+ $(,)?) => {
        (
            size_of::<$t>() as u32,
            vec![$((stringify!($field).to_owned(), std::mem::offset_of!($t, $field) as u32)),+],
        )
    };
}

/// The WGSL mirrors in `shaders/quadric_common.wgsl` have the members,
/// offsets and sizes of the Rust structs in `plugin/splat/gpu.rs`, as naga
/// lays them out (uniform and storage rules coincide for these structs).
#[test]
fn wgsl_structs_match_the_rust_layouts() {
    use bevy_chisel::splat::gpu::{PropUniform, QuadricRecord, SplatRecord, SplatViewUniform};

    let mut composer = composer(&wgsl_files());
    let source = "#import bevy_chisel::quadric::{Prop, Quadric, Splat, SplatView}\n\
        @group(0) @binding(0) var<uniform> layout_view: SplatView;\n\
        @group(0) @binding(1) var<uniform> layout_prop: Prop;\n\
        @group(0) @binding(2) var<storage, read> layout_quadrics: array<Quadric>;\n\
        @group(0) @binding(3) var<storage, read> layout_splats: array<Splat>;\n\
        @compute @workgroup_size(1)\n\
        fn main() {\n\
            let x = layout_view.flat_ratio + layout_prop.max_scale\n\
                + layout_quadrics[0].c[0].x + layout_splats[0].radius;\n\
        }\n";
    let module = composer
        .make_naga_module(NagaModuleDescriptor {
            source,
            file_path: "layout_check.wgsl",
            shader_type: ShaderType::Wgsl,
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("layout check: {}", e.emit_to_string(&composer)));
    let wgsl_layout = |name: &str| {
        let mangled = format!("{name}X_naga_oil_mod_X");
        module
            .types
            .iter()
            .find_map(|(_, t)| {
                let type_name = t.name.as_deref()?;
                let naga::TypeInner::Struct { members, span } = &t.inner else {
                    return None;
                };
                (type_name == name || type_name.starts_with(&mangled)).then(|| {
                    let members = members
                        .iter()
                        .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                        .collect::<Vec<_>>();
                    (*span, members)
                })
            })
            .unwrap_or_else(|| panic!("struct {name} is not in the composed module"))
    };
    let pairs = [
        (
            "SplatView",
            rust_layout!(SplatViewUniform: clip_from_world, camera_position, view_forward,
                flat_ratio, radius_tolerance, pad),
        ),
        (
            "Prop",
            rust_layout!(PropUniform: world_from_local, local_from_world, normal_from_local,
                bounds, product_count, max_scale, mirror_sign, metallic, perceptual_roughness,
                reflectance, pad),
        ),
        ("Quadric", rust_layout!(QuadricRecord: c)),
        (
            "Splat",
            rust_layout!(SplatRecord: position, radius, normal, normal_extent, quadric,
                clip_start, clip_count, pad),
        ),
    ];
    for (name, rust) in pairs {
        assert_eq!(
            wgsl_layout(name),
            rust,
            "WGSL {name} against its Rust mirror"
        );
    }
}
