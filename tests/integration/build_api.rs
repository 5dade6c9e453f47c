//! The build-script API and the example crate that uses it.

use std::process::Command;

use shadecache::build::{Build, Nodes};
use shadecache::rewrite::Variant;

use crate::util::root;

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
        "shadecache: 1 error rewriting shaders (see the diagnostics above)"
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
