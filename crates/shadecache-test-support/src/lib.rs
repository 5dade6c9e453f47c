//! What the workspace's tests share, in one place instead of a copy per
//! crate: the repository's paths and its corpus, a temporary file, the
//! Tint harness (Chrome's WGSL compiler, `tests/tint`), and what a test
//! that needs a GPU does on a machine without an adapter.
//!
//! It depends on none of the workspace's crates, so the library's own
//! tests can use it without a second copy of the library.

#![warn(missing_docs)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The environment variable that lets the tests needing a GPU adapter
/// skip where there is none.
pub const SKIP_GPU_TESTS: &str = "SHADECACHE_SKIP_GPU_TESTS";

/// The repository root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the repository root exists")
}

/// Every `corpus/*.wgsl`, sorted, as paths relative to the root.
pub fn corpus() -> Vec<PathBuf> {
    let root = root();
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("corpus"))
        .expect("corpus/ exists")
        .map(|entry| entry.expect("readable corpus entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "wgsl"))
        .map(|path| path.strip_prefix(&root).unwrap().to_path_buf())
        .collect();
    files.sort();
    assert!(files.len() >= 8, "the corpus has at least 8 shaders");
    files
}

/// A file in a fresh temporary directory, kept alive by the returned guard.
pub fn temp_file(name: &str, contents: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join(name);
    std::fs::write(&path, contents).expect("write the temporary file");
    (dir, path)
}

/// A process's standard output, as text.
pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A process's standard error, as text.
pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The GPU adapter wgpu opens on this machine (lavapipe counts), if any.
pub fn adapter() -> Option<wgpu::AdapterInfo> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .ok()
        .map(|adapter| adapter.get_info())
}

/// What a test that needs a GPU does where there is no adapter: fails
/// saying what to install (the README's test command runs with a Vulkan
/// driver, lavapipe on a CPU), unless `SHADECACHE_SKIP_GPU_TESTS=1` asks
/// to skip; then it returns, having said so on the terminal whatever the
/// test harness captures.
pub fn no_adapter() {
    if std::env::var_os(SKIP_GPU_TESTS).is_some_and(|v| v == "1") {
        // Written to the stream itself: libtest captures only the print
        // macros, and a skip must not pass unseen.
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED (no GPU adapter, {SKIP_GPU_TESTS}=1): {}",
            std::thread::current().name().unwrap_or("a test")
        );
        return;
    }
    panic!(
        "no GPU adapter: install a Vulkan driver (apt-get install mesa-vulkan-drivers libvulkan1 gives lavapipe), or set {SKIP_GPU_TESTS}=1 to skip the tests that need one"
    );
}

/// What Tint said about one file.
#[derive(Debug, serde::Deserialize)]
pub struct TintResult {
    /// The file, as given.
    pub file: String,
    /// Whether it compiled.
    pub ok: bool,
    /// Its errors and warnings.
    pub messages: Vec<TintMessage>,
}

/// One of Tint's messages.
#[derive(Debug, serde::Deserialize)]
pub struct TintMessage {
    /// `error`, `warning` or `info`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Where, 1-based.
    pub line: u64,
    /// Where, 1-based.
    pub column: u64,
    /// What.
    pub message: String,
}

/// The Tint harness (`tests/tint`), installed on first use: `npm ci`
/// installs the pinned `webgpu` package into `tests/tint/node_modules`
/// (ignored by git), once per test run however many tests ask at the same
/// time. Panics naming what is missing when node or npm are absent: a
/// missing validator must fail the test, not skip it.
fn tint_harness() -> PathBuf {
    static INSTALLED: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    let harness = root().join("tests/tint");
    let installed = || harness.join("node_modules/webgpu").is_dir();
    let outcome = INSTALLED.get_or_init(|| {
        if installed() {
            return Ok(());
        }
        for tool in ["node", "npm"] {
            if Command::new(tool).arg("--version").output().is_err() {
                return Err(format!(
                    "the Tint harness needs Node.js and npm, and `{tool}` is not on PATH: install them (Debian: apt-get install nodejs npm)"
                ));
            }
        }
        let output = Command::new("npm")
            .args(["ci", "--prefix", "tests/tint", "--no-audit", "--no-fund"])
            .current_dir(root())
            .output()
            .map_err(|err| format!("cannot run npm: {err}"))?;
        if !output.status.success() || !installed() {
            return Err(format!(
                "`npm ci --prefix tests/tint` failed (it needs the npm registry once):\n{}",
                stderr(&output)
            ));
        }
        Ok(())
    });
    if let Err(message) = outcome {
        panic!("{message}");
    }
    harness
}

/// Validates WGSL files with Tint (Chrome's compiler) through
/// `tests/tint/validate.mjs`, installing the harness on first use.
pub fn tint_validate(files: &[PathBuf]) -> Vec<TintResult> {
    let harness = tint_harness();
    let mut child = Command::new("node")
        .arg(harness.join("validate.mjs"))
        .arg("-")
        .current_dir(root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("node runs (install nodejs)");
    let list: String = files.iter().map(|f| format!("{}\n", f.display())).collect();
    child
        .stdin
        .take()
        .expect("stdin is piped")
        .write_all(list.as_bytes())
        .expect("write the file list");
    let output = child.wait_with_output().expect("node finishes");
    assert!(
        matches!(output.status.code(), Some(0) | Some(1)),
        "the Tint harness failed: {}",
        stderr(&output)
    );
    let results: Vec<TintResult> = stdout(&output)
        .lines()
        .map(|line| serde_json::from_str(line).expect("one JSON object per line"))
        .collect();
    assert_eq!(results.len(), files.len(), "one result per file");
    results
}

/// A scene for the marble shader: one sphere; `extra` adds TOML.
pub fn marble_scene(effects: &str, extra: &str) -> String {
    format!(
        r#"
size = [128, 128]
frames = 4
warmup = 1
effects = [{effects}]
[camera]
eye = [0.0, 0.3, 3.2]
[[objects]]
mesh = {{ kind = "sphere", rings = 32, segments = 48 }}
rotation_degrees_per_frame = [0.0, 0.6, 0.0]
[uniforms]
marble_frequency = 4.0
turbulence_amount = 6.0
light_color = [1.0, 1.0, 1.0]
{extra}
"#
    )
}

/// A marble sphere over a marble floor, for `corpus/noise_marble.wgsl`:
/// `settings` (TOML lines: size, frames, warm-up), `effects`, `camera`
/// and `sphere` (TOML lines) set the run and the motion.
pub fn sphere_over_floor(settings: &str, effects: &str, camera: &str, sphere: &str) -> String {
    format!(
        r#"
{settings}
effects = [{effects}]
[camera]
eye = [0.0, 1.2, 3.4]
target = [0.0, -0.3, 0.0]
{camera}
[[objects]]
mesh = {{ kind = "plane", size = 6.0, subdivisions = 4 }}
position = [0.0, -1.0, 0.0]
[[objects]]
mesh = {{ kind = "sphere", rings = 24, segments = 32 }}
scale = 0.8
{sphere}
[uniforms]
marble_frequency = 4.0
turbulence_amount = 6.0
light_color = [1.0, 1.0, 1.0]
"#
    )
}

/// A copy of `corpus/wesl` in a temporary folder, with `edit` applied to
/// the file at `file` (relative to `corpus/wesl`); the guard and the
/// copy's path.
pub fn edited_wesl(file: &str, edit: impl Fn(&str) -> String) -> (tempfile::TempDir, PathBuf) {
    fn copy(from: &Path, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for entry in std::fs::read_dir(from).unwrap() {
            let path = entry.unwrap().path();
            let target = to.join(path.file_name().unwrap());
            if path.is_dir() {
                copy(&path, &target);
            } else {
                std::fs::copy(&path, &target).unwrap();
            }
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let wesl = dir.path().join("wesl");
    copy(&root().join("corpus/wesl"), &wesl);
    let path = wesl.join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    let changed = edit(&text);
    assert_ne!(changed, text, "the edit changes {file}");
    std::fs::write(&path, changed).unwrap();
    (dir, wesl)
}
