//! The build-script API and the example crate that uses it.

use std::process::Command;

use crate::util::{cargo_tree, root};

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
