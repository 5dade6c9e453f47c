//! The harness the command's tests use: run the binary, `cargo tree`,
//! load shaders from text; the rest is the workspace's test support.

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;
pub use shadecache_test_support::{
    corpus, marble_scene, root, stderr, stdout, temp_file, tint_validate,
};

/// The GPU adapter a test that needs one draws on. Without one the test
/// fails, or with `SHADECACHE_SKIP_GPU_TESTS=1` is skipped (`None`, said
/// on the terminal).
pub fn adapter() -> Option<wgpu::AdapterInfo> {
    let adapter = shadecache_test_support::adapter();
    if adapter.is_none() {
        shadecache_test_support::no_adapter();
    }
    adapter
}

/// Whether a test that needs a GPU has none ([`adapter`]).
pub fn no_gpu() -> bool {
    adapter().is_none()
}

/// Runs `shadecache ARGS...` from the repository root with colour off.
pub fn shadecache<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_shadecache"))
        .args(args)
        .current_dir(root())
        .env("NO_COLOR", "1")
        .output()
        .expect("the shadecache binary runs")
}

/// The package names `cargo tree ARGS` lists from the root, in its order
/// (offline and locked: the build has fetched them).
pub fn cargo_tree(args: &[&str]) -> Vec<String> {
    let output = Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--locked"])
        .args(["--prefix", "none", "--format", "{p}"])
        .args(args)
        .current_dir(root())
        .output()
        .expect("cargo runs");
    assert!(output.status.success(), "{}", stderr(&output));
    // "name vX.Y.Z (...)" per line: the names.
    stdout(&output)
        .lines()
        .filter_map(|line| line.split_whitespace().next().map(str::to_owned))
        .collect()
}

/// `shadecache analyze PATH --format json`, which must succeed.
pub fn analyze_json(path: &Path) -> Value {
    use std::ffi::OsStr;
    let output = shadecache([
        OsStr::new("analyze"),
        path.as_os_str(),
        OsStr::new("--format"),
        OsStr::new("json"),
    ]);
    assert!(
        output.status.success(),
        "analyze {} failed:\n{}",
        path.display(),
        stderr(&output)
    );
    serde_json::from_slice(&output.stdout).expect("analyze prints JSON")
}

/// Parses, validates and analyses a shader given as text.
pub fn analyzed(
    name: &str,
    source: &str,
) -> (shadecache::front::Shader, shadecache::analysis::Analysis) {
    let shader = shadecache::front::parse(shadecache::diagnostic::SourceFile::new(name, source))
        .unwrap_or_else(|err| panic!("{name}: {err:?}"));
    let analysis = shadecache::analysis::analyze(&shader, &Default::default()).unwrap();
    (shader, analysis)
}

/// The candidate whose source text is `text`.
pub fn candidate<'a>(
    analysis: &'a shadecache::analysis::Analysis,
    text: &str,
) -> &'a shadecache::analysis::Candidate {
    analysis
        .candidates
        .iter()
        .find(|c| c.node.text == text)
        .unwrap_or_else(|| panic!("no candidate `{text}`"))
}

/// Runs `shadecache profile SHADER --scene <scene_text> --quiet`, which
/// must fail with exit status 1; returns its stderr.
pub fn profile_error(shader: &str, scene_text: &str) -> String {
    let (dir, path) = temp_file("scene.toml", scene_text.as_bytes());
    let out = dir.path().join("report");
    let output = shadecache([
        "profile".as_ref(),
        shader.as_ref(),
        "--scene".as_ref(),
        path.as_os_str(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ] as [&std::ffi::OsStr; 7]);
    assert!(!out.exists(), "a failed profile left {}", out.display());
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    err
}
