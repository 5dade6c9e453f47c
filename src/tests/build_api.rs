//! The build-script API (`crate::build`): what it writes and what
//! it refuses.

use super::util::root;
use crate::build::{Build, Nodes};
use crate::rewrite::Variant;

#[test]
fn build_writes_the_chosen_variants() {
    let dir = tempfile::tempdir().unwrap();
    let outputs = Build::new()
        .shader(root().join("corpus/noise_marble.wgsl"))
        .node("nb0c12cc4")
        .variant(Variant::TwoPass)
        .shader(root().join("corpus/shadow_pcf.wgsl"))
        .nodes(Nodes::Top(2))
        .variant(Variant::ThreePass)
        .out_dir(dir.path())
        .quiet()
        .run()
        .unwrap();
    let marble = dir.path().join("noise_marble/nb0c12cc4/two-pass");
    assert!(marble.join("pass1.wgsl").is_file());
    assert!(marble.join("pass2.wgsl").is_file());
    assert!(marble.join("plan.json").is_file());
    assert!(!dir.path().join("noise_marble/nb0c12cc4/one-pass").exists());
    let shadow_variants = std::fs::read_dir(dir.path().join("shadow_pcf"))
        .unwrap()
        .count();
    assert_eq!(shadow_variants, 2);
    // two-pass: 2 passes, classify, plan; three-pass: 3 passes, classify,
    // plan; and the module naming them.
    assert_eq!(outputs.files.len(), 4 + 2 * 5 + 1);
    assert_eq!(outputs.variants.len(), 3);

    // The module naming them: each shader's first node's variants under
    // the shader's own name, every file included by its path.
    let module = std::fs::read_to_string(dir.path().join("variants.rs")).unwrap();
    assert!(module.contains("pub mod noise_marble {"), "{module}");
    assert!(
        module.contains("pub const NODE: &str = \"nb0c12cc4\";"),
        "{module}"
    );
    assert!(module.contains("pub use self::nb0c12cc4::*;"), "{module}");
    assert!(module.contains("pub mod two_pass {"), "{module}");
    assert_eq!(
        module.matches("pub mod three_pass {").count(),
        2,
        "{module}"
    );
    assert_eq!(module.matches("include_str!(").count(), 14, "{module}");
    for included in module.split("include_str!(\"").skip(1) {
        let path = &included[..included.find('"').unwrap()];
        assert!(std::path::Path::new(path).is_file(), "{path}");
    }
    assert!(syn_like_balanced(&module), "{module}");
}

/// Whether braces, brackets and parentheses balance outside strings: the
/// module is Rust a game includes, checked for its shape here; the Bevy
/// example compiles one.
fn syn_like_balanced(text: &str) -> bool {
    let (mut depth, mut in_string, mut escaped) = (0i64, false, false);
    for c in text.chars() {
        match (in_string, escaped, c) {
            (true, true, _) => escaped = false,
            (true, false, '\\') => escaped = true,
            (true, false, '"') => in_string = false,
            (true, false, _) => {}
            (false, _, '"') => in_string = true,
            (false, _, '{' | '[' | '(') => depth += 1,
            (false, _, '}' | ']' | ')') => depth -= 1,
            _ => {}
        }
        if depth < 0 {
            return false;
        }
    }
    depth == 0 && !in_string
}

/// `composed` gives each shader as `run` reads it, in order, without
/// writing anything: what a test profiles to measure the variants a build
/// writes. A shader that cannot be read is an error, as for `run`.
#[test]
fn build_composes_the_shaders_it_rewrites() {
    let shaders = Build::new()
        .shader(root().join("corpus/noise_marble.wgsl"))
        .node("nb0c12cc4")
        .shader(root().join("corpus/shadow_pcf.wgsl"))
        .quiet()
        .composed()
        .unwrap_or_else(|e| panic!("{:?}", e.errors));
    assert_eq!(shaders.len(), 2);
    assert!(shaders[0].file.path.ends_with("noise_marble.wgsl"));
    assert!(shaders[1].file.path.ends_with("shadow_pcf.wgsl"));
    for shader in &shaders {
        assert!(shader
            .module
            .entry_points
            .iter()
            .any(|e| e.stage == naga::ShaderStage::Fragment));
    }
    let err = Build::new()
        .shader(root().join("corpus/no_such_shader.wgsl"))
        .composed()
        .unwrap_err();
    assert!(
        err.errors[0].render().contains("no_such_shader.wgsl"),
        "{:?}",
        err.errors
    );
}

#[test]
fn build_fails_short_on_a_bad_node() {
    let dir = tempfile::tempdir().unwrap();
    let err = Build::new()
        .shader(root().join("corpus/noise_marble.wgsl"))
        .node("n00000000")
        .out_dir(dir.path())
        .quiet()
        .run()
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "shadecache: 1 error rewriting shaders (quiet: their diagnostics are in BuildError::errors)"
    );
    assert!(err.errors[0]
        .render()
        .contains("unknown node id `n00000000`"));
    // Nothing half-written.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn build_fails_on_a_missing_shader_and_on_settings_without_a_shader() {
    let dir = tempfile::tempdir().unwrap();
    let err = Build::new()
        .shader(root().join("corpus/missing.wgsl"))
        .out_dir(dir.path())
        .quiet()
        .run()
        .unwrap_err();
    assert!(err.errors[0].render().contains("no such file"));
    let err = Build::new()
        .node("nb0c12cc4")
        .out_dir(dir.path())
        .quiet()
        .run()
        .unwrap_err();
    assert!(err.errors[0].render().contains("before any shader"));
}

/// Two shaders with one file stem would write one folder: an error, unless
/// one is given its own name; the reference is not a variant to write.
#[test]
fn build_refuses_colliding_stems_and_the_reference_variant() {
    let dir = tempfile::tempdir().unwrap();
    let (_a, first) = super::util::temp_file(
        "marble.wgsl",
        &std::fs::read(root().join("corpus/noise_marble.wgsl")).unwrap(),
    );
    let twice = || {
        Build::new()
            .shader(root().join("corpus/noise_marble.wgsl"))
            .node("nb0c12cc4")
            .variant(Variant::OnePass)
            .out_dir(dir.path())
            .quiet()
    };
    let renamed = first.with_file_name("noise_marble.wgsl");
    std::fs::copy(&first, &renamed).unwrap();
    let err = twice()
        .shader(&renamed)
        .node("nb0c12cc4")
        .variant(Variant::OnePass)
        .run()
        .unwrap_err();
    assert!(
        err.errors[0]
            .render()
            .contains("would both be written to `noise_marble/`"),
        "{}",
        err.errors[0].render()
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    twice()
        .shader(&renamed)
        .name("marble_copy")
        .node("nb0c12cc4")
        .variant(Variant::OnePass)
        .run()
        .unwrap();
    assert!(dir
        .path()
        .join("marble_copy/nb0c12cc4/one-pass/pass1.wgsl")
        .is_file());
    assert!(dir
        .path()
        .join("noise_marble/nb0c12cc4/one-pass/pass1.wgsl")
        .is_file());

    let err = Build::new()
        .shader(root().join("corpus/noise_marble.wgsl"))
        .variant(Variant::Reference)
        .out_dir(dir.path())
        .quiet()
        .run()
        .unwrap_err();
    assert!(err.errors[0].render().contains("Variant::Reference"));
}

/// A sum deep enough to overflow a build script's main thread in a debug
/// build is rewritten: the build runs on a thread with a large stack.
#[test]
fn build_handles_deep_expressions() {
    let terms: Vec<String> = (0..3000)
        .map(|i| format!("sin(p.x * {i}.0 + p.y)"))
        .collect();
    let source = format!(
        "@fragment\nfn fs(@location(0) p: vec2<f32>) -> @location(0) vec4<f32> {{\n    let s = {};\n    return vec4<f32>(s);\n}}\n",
        terms.join(" + ")
    );
    let (_dir, path) = super::util::temp_file("deep.wgsl", source.as_bytes());
    let out = tempfile::tempdir().unwrap();
    // Run from a thread with a small stack, as a build script's would be.
    let outputs = std::thread::Builder::new()
        .stack_size(2 * 1024 * 1024)
        .spawn(move || {
            Build::new()
                .shader(&path)
                .variant(Variant::OnePass)
                .out_dir(out.path())
                .quiet()
                .run()
                .map(|o| o.files.len())
        })
        .unwrap()
        .join()
        .unwrap()
        .unwrap();
    assert!(outputs > 0);
}
