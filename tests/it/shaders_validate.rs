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
        assert!(defines.len() <= 11, "{path}: too many defines to enumerate");
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

/// The shadow-map variant of the splat pass (`SHADOW_DEPTH`, the shadow
/// pipeline's only define) needs none of Bevy's shader library and binds
/// nothing in groups 0 and 1, which the shadow pipeline leaves empty: it
/// composes from our own modules alone, its fragment stage writes depth
/// and no colour, and every global it uses is in group 2 or 3.
#[test]
fn the_shadow_variant_needs_no_bevy_bindings() {
    let files = wgsl_files();
    let mut composer = composer(&files);
    let (path, source) = files
        .iter()
        .find(|(p, _)| p.ends_with("splat.wgsl"))
        .expect("splat.wgsl");
    let module = composer
        .make_naga_module(NagaModuleDescriptor {
            source,
            file_path: path,
            shader_type: ShaderType::Wgsl,
            shader_defs: HashMap::from([("SHADOW_DEPTH".to_owned(), ShaderDefValue::Bool(true))]),
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("shadow variant: {}", e.emit_to_string(&composer)));
    let info =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), Capabilities::default())
            .validate(&module)
            .expect("the shadow variant validates");
    let fragment = module
        .entry_points
        .iter()
        .position(|e| e.stage == naga::ShaderStage::Fragment)
        .expect("a fragment stage");
    let result = module.entry_points[fragment]
        .function
        .result
        .as_ref()
        .expect("the fragment stage returns its depth");
    assert_eq!(
        result.binding,
        Some(naga::Binding::BuiltIn(naga::BuiltIn::FragDepth)),
        "depth only"
    );
    for (index, entry) in module.entry_points.iter().enumerate() {
        let used = info.get_entry_point(index);
        for (handle, global) in module.global_variables.iter() {
            if let Some(binding) = &global.binding
                && !used[handle].is_empty()
            {
                assert!(
                    binding.group >= 2,
                    "{} uses {:?} at group {}",
                    entry.name,
                    global.name,
                    binding.group
                );
            }
        }
    }
}

#[test]
fn listed_defines_are_parsed_from_comments() {
    let source = "// Defines: A_B, EARLY_DEPTH_TEST,\n// OUTPUT_IDS (ids).\nfn f() {}\n";
    assert_eq!(
        listed_defines(source),
        vec!["A_B", "EARLY_DEPTH_TEST", "OUTPUT_IDS"]
    );
}

/// One Rust GPU struct as its mirror must see it: its `#[repr(C)]` size and
/// field offsets, the bytes `encase` writes for a value of it (in its
/// address space) and the bytes it writes for each field alone.
struct RustMirror {
    size: u32,
    /// `(field, repr(C) offset, encase bytes of the field alone)`, in
    /// declaration order.
    fields: Vec<(String, u32, Vec<u8>)>,
    /// The whole value as `encase` writes it.
    encased: Vec<u8>,
    /// Two copies as a storage array (for array element types), else empty.
    encased_pair: Vec<u8>,
}

/// The [`RustMirror`] of a struct literal with one distinct value per field
/// (the literal names every field, so a new field fails to compile here).
/// `uniform` or `storage`: the address space the shaders read it in.
macro_rules! rust_mirror {
    ($space:ident, $t:ident { $($field:ident: $value:expr),+ $(,)? }) => {{
        use bevy::render::render_resource::encase;
        let value = $t { $($field: $value),+ };
        let field_bytes = |write: &dyn Fn(&mut encase::StorageBuffer<Vec<u8>>)| {
            let mut buffer = encase::StorageBuffer::new(Vec::new());
            write(&mut buffer);
            buffer.into_inner()
        };
        let fields = vec![$((
            stringify!($field).to_owned(),
            std::mem::offset_of!($t, $field) as u32,
            field_bytes(&|b| b.write(&value.$field).expect("encase writes the field")),
        )),+];
        let (encased, encased_pair) = rust_mirror!(@encase $space, value);
        RustMirror { size: size_of::<$t>() as u32, fields, encased, encased_pair }
    }};
    (@encase uniform, $value:ident) => {{
        let mut buffer = encase::UniformBuffer::new(Vec::new());
        buffer.write(&$value).expect("encase writes the uniform");
        (buffer.into_inner(), Vec::new())
    }};
    (@encase storage, $value:ident) => {{
        let mut one = encase::StorageBuffer::new(Vec::new());
        one.write(&$value).expect("encase writes the record");
        let mut pair = encase::StorageBuffer::new(Vec::new());
        pair.write(&vec![$value, $value]).expect("encase writes the array");
        (one.into_inner(), pair.into_inner())
    }};
}

/// `[start, start + 1, start + 2, start + 3]`.
fn vec4_from(start: f32) -> bevy::math::Vec4 {
    bevy::math::Vec4::new(start, start + 1.0, start + 2.0, start + 3.0)
}

/// A matrix of 16 consecutive values from `start`.
fn mat4_from(start: f32) -> bevy::math::Mat4 {
    bevy::math::Mat4::from_cols_array(&std::array::from_fn(|i| start + i as f32))
}

/// A struct of a composed naga module: `(span, [(member, offset)])`.
type WgslLayout = (u32, Vec<(String, u32)>);

/// Whether `name` in a composed module is the item `item` (naga_oil
/// mangles the names of imported items).
fn is_item(name: &str, item: &str) -> bool {
    name == item || name.starts_with(&format!("{item}X_naga_oil_mod_X"))
}

/// The WGSL mirrors in `shaders/quadric_common.wgsl` have the members,
/// offsets and sizes of the Rust structs in `plugin/splat/gpu.rs`, as naga
/// lays them out: the `#[repr(C)]` offsets agree, and so do the bytes
/// `encase` uploads (each field's bytes sit at naga's offset of its member,
/// the whole value fills naga's span, an array element naga's stride). The
/// flag constants agree with the kernel's.
#[test]
fn wgsl_structs_match_the_rust_layouts() {
    use bevy::math::{UVec2, Vec3};
    use bevy_chisel::splat::gpu::{PropUniform, QuadricRecord, SplatRecord, SplatViewUniform};

    let mut composer = composer(&wgsl_files());
    let source = "#import bevy_chisel::quadric::{\n\
            INDEX_MASK, OUTSIDE_FLAG, Prop, Quadric, Splat, SplatView,\n\
        }\n\
        @group(0) @binding(0) var<uniform> layout_view: SplatView;\n\
        @group(0) @binding(1) var<uniform> layout_prop: Prop;\n\
        @group(0) @binding(2) var<storage, read> layout_quadrics: array<Quadric>;\n\
        @group(0) @binding(3) var<storage, read> layout_splats: array<Splat>;\n\
        @group(0) @binding(4) var<storage, read_write> layout_flags: u32;\n\
        @compute @workgroup_size(1)\n\
        fn main() {\n\
            let x = layout_view.flat_ratio + layout_prop.max_scale\n\
                + layout_quadrics[0].c[0].x + layout_splats[0].radius;\n\
            layout_flags = OUTSIDE_FLAG | INDEX_MASK;\n\
        }\n";
    let module = composer
        .make_naga_module(NagaModuleDescriptor {
            source,
            file_path: "layout_check.wgsl",
            shader_type: ShaderType::Wgsl,
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("layout check: {}", e.emit_to_string(&composer)));
    let wgsl_struct = |name: &str| -> (naga::Handle<naga::Type>, WgslLayout) {
        module
            .types
            .iter()
            .find_map(|(handle, t)| {
                let naga::TypeInner::Struct { members, span } = &t.inner else {
                    return None;
                };
                is_item(t.name.as_deref()?, name).then(|| {
                    let members = members
                        .iter()
                        .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                        .collect();
                    (handle, (*span, members))
                })
            })
            .unwrap_or_else(|| panic!("struct {name} is not in the composed module"))
    };
    let array_stride = |element: naga::Handle<naga::Type>| {
        module
            .types
            .iter()
            .find_map(|(_, t)| match t.inner {
                naga::TypeInner::Array { base, stride, .. } if base == element => Some(stride),
                _ => None,
            })
            .expect("the element type has an array in the composed module")
    };
    let mirrors = [
        (
            "SplatView",
            rust_mirror!(
                uniform,
                SplatViewUniform {
                    clip_from_world: mat4_from(1.0),
                    camera_position: vec4_from(17.0),
                    view_forward: vec4_from(21.0),
                    flat_ratio: 25.0,
                    radius_tolerance: 26.0,
                    pad: UVec2::new(27, 28),
                }
            ),
        ),
        (
            "Prop",
            rust_mirror!(
                uniform,
                PropUniform {
                    world_from_local: mat4_from(1.0),
                    local_from_world: mat4_from(17.0),
                    normal_from_local: mat4_from(33.0),
                    bounds: vec4_from(49.0),
                    product_count: 53,
                    max_scale: 54.0,
                    mirror_sign: 55.0,
                    metallic: 56.0,
                    perceptual_roughness: 57.0,
                    reflectance: 58.0,
                    pad: UVec2::new(59, 60),
                }
            ),
        ),
        (
            "Quadric",
            rust_mirror!(
                storage,
                QuadricRecord {
                    c: [
                        vec4_from(1.0),
                        vec4_from(5.0),
                        vec4_from(9.0),
                        vec4_from(13.0)
                    ],
                }
            ),
        ),
        (
            "Splat",
            rust_mirror!(
                storage,
                SplatRecord {
                    position: Vec3::new(1.0, 2.0, 3.0),
                    radius: 4.0,
                    normal: Vec3::new(5.0, 6.0, 7.0),
                    normal_extent: 8.0,
                    tangent: Vec3::new(9.0, 10.0, 11.0),
                    normal_turn: 12.0,
                    tangent_extent: bevy::math::Vec2::new(13.0, 14.0),
                    quadric: 15,
                    clip_start: 16,
                    clip_count: 17,
                    pad: [18, 19, 20],
                }
            ),
        ),
    ];
    for (name, rust) in mirrors {
        let (handle, (span, members)) = wgsl_struct(name);
        let repr_c: Vec<(String, u32)> = rust
            .fields
            .iter()
            .map(|(field, offset, _)| (field.clone(), *offset))
            .collect();
        assert_eq!(
            (span, &members),
            (rust.size, &repr_c),
            "WGSL {name} against the #[repr(C)] layout of its Rust mirror"
        );
        assert_eq!(rust.encased.len(), span as usize, "encase size of {name}");
        for ((member, offset), (_, _, bytes)) in members.iter().zip(&rust.fields) {
            let at = *offset as usize;
            assert_eq!(
                rust.encased.get(at..at + bytes.len()),
                Some(&bytes[..]),
                "encase bytes of {name}.{member} at naga's offset {offset}"
            );
        }
        if !rust.encased_pair.is_empty() {
            let stride = array_stride(handle) as usize;
            assert_eq!(rust.encased_pair.len(), 2 * stride, "array of {name}");
            assert_eq!(rust.encased_pair[stride..], rust.encased[..], "{name} [1]");
        }
    }
    for (name, kernel) in [
        ("OUTSIDE_FLAG", chisel_quadric::OUTSIDE_FLAG),
        ("INDEX_MASK", chisel_quadric::INDEX_MASK),
    ] {
        let value = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref().is_some_and(|n| is_item(n, name)))
            .map(|(_, c)| &module.global_expressions[c.init])
            .unwrap_or_else(|| panic!("constant {name} is not in the composed module"));
        assert!(
            matches!(value, naga::Expression::Literal(naga::Literal::U32(v)) if *v == kernel),
            "WGSL {name} is {value:?}, the kernel's is {kernel:#x}"
        );
    }
}
