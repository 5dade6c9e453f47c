//! The build-script API and the example crate that uses it.

use std::process::Command;

use shadecache::build::{Build, Nodes};
use shadecache::rewrite::Variant;

use crate::util::{cargo_tree, root};

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
    // two-pass: 2 passes, classify, plan; three-pass: 3 passes, classify, plan.
    assert_eq!(outputs.files.len(), 4 + 2 * 5);
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
    let (_a, first) = crate::util::temp_file(
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
    let (_dir, path) = crate::util::temp_file("deep.wgsl", source.as_bytes());
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

/// `examples/build-script` builds from the checkout and runs: its
/// `build.rs` rewrites a corpus shader into OUT_DIR and its `main.rs`
/// includes the WGSL and the plan.
#[test]
fn build_script_example_builds_and_runs() {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    let output = Command::new(env!("CARGO"))
        .args(["run", "--quiet", "--locked", "--manifest-path"])
        .arg(root().join("examples/build-script/Cargo.toml"))
        // Share the repository's target directory so shadecache and its
        // dependencies are not compiled again.
        .env("CARGO_TARGET_DIR", target)
        .output()
        .expect("cargo runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("(three-pass) with 3 passes"), "{stdout}");
    assert!(
        stdout.contains("pass3: 2 entry points; depth equal (write false)"),
        "{stdout}"
    );
    assert!(stdout.contains("last frame's `frame`"), "{stdout}");
}

/// What a build script compiles: the library's default features (read,
/// analyse, rewrite, write back) bring naga and naga_oil and nothing that
/// runs a GPU or serves only the command line; the `profile` feature
/// brings the GPU stack (so the check can fail).
#[test]
fn build_script_feature_set_has_no_gpu_dependencies() {
    let tree = |features: &[&str]| {
        let mut args = vec!["-p", "shadecache", "-e", "normal"];
        args.extend(features);
        cargo_tree(&args)
            .into_iter()
            .collect::<std::collections::BTreeSet<_>>()
    };
    let lean = tree(&["--no-default-features"]);
    assert_eq!(
        lean,
        tree(&[]),
        "the default features are the build script's"
    );
    assert!(
        lean.contains("naga") && lean.contains("naga_oil"),
        "{lean:?}"
    );
    for gpu in [
        "wgpu",
        "wgpu-core",
        "wgpu-profiler",
        "shadecache-host",
        "clap",
        "indicatif",
        "gltf",
        "tobj",
        "image",
        "pollster",
    ] {
        assert!(
            !lean.contains(gpu),
            "{gpu} in the build script's tree: {lean:?}"
        );
    }
    let full = tree(&["--features", "profile"]);
    assert!(full.contains("wgpu") && full.contains("image"), "{full:?}");
}

/// The packages `cargo build`, `cargo run` and `cargo test` compile at the
/// workspace root (its default members, dev-dependencies and build
/// scripts included): the toolchain, its command and the crates
/// applications link, and nothing of Bevy, which compiles only when its
/// crates are named (`-p shadecache-bevy`, or `--workspace`).
#[test]
fn default_members_compile_no_bevy() {
    let packages = |selection: &[&str]| {
        let mut args = vec!["-e", "normal,build,dev"];
        args.extend(selection);
        cargo_tree(&args)
            .into_iter()
            .collect::<std::collections::BTreeSet<_>>()
    };
    let default = packages(&[]);
    for member in [
        "shadecache",
        "shadecache-cli",
        "shadecache-host",
        "shadecache-plan",
    ] {
        assert!(default.contains(member), "{member} not built: {default:?}");
    }
    let bevy: Vec<&String> = default
        .iter()
        .filter(|name| name.starts_with("bevy") || name.starts_with("shadecache-bevy"))
        .collect();
    assert!(bevy.is_empty(), "the default members compile {bevy:?}");
    // The whole workspace does compile Bevy: the check can fail.
    assert!(packages(&["--workspace"]).contains("bevy"));
}
