//! The harness every test uses: run the binary, validate with Tint, load
//! shaders from text.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use serde_json::Value;
use shadecache::scene::Scene;

/// The repository root (this crate is `crates/shadecache-cli`).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `corpus/*.wgsl`, sorted, as paths relative to the root.
pub fn corpus() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("corpus"))
        .expect("corpus/ exists")
        .map(|entry| entry.expect("readable corpus entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "wgsl"))
        .map(|path| path.strip_prefix(root()).unwrap().to_path_buf())
        .collect();
    files.sort();
    assert!(files.len() >= 8, "the corpus has at least 8 shaders");
    files
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

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
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

/// A file in a fresh temporary directory, kept alive by the returned guard.
pub fn temp_file(name: &str, contents: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join(name);
    std::fs::write(&path, contents).expect("write the temporary file");
    (dir, path)
}

/// What Tint said about one file.
#[derive(Debug, serde::Deserialize)]
pub struct TintResult {
    pub file: String,
    pub ok: bool,
    pub messages: Vec<TintMessage>,
}

#[derive(Debug, serde::Deserialize)]
pub struct TintMessage {
    #[serde(rename = "type")]
    pub kind: String,
    pub line: u64,
    pub column: u64,
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

/// Whether a pixel of `mask` lies within one pixel (8-neighbourhood) of
/// `i`.
pub fn near(mask: &[bool], w: usize, i: usize) -> bool {
    let h = mask.len() / w;
    let (x, y) = ((i % w) as i64, (i / w) as i64);
    (-1..=1).any(|dy| {
        (-1..=1).any(|dx| {
            let (nx, ny) = (x + dx, y + dy);
            nx >= 0
                && ny >= 0
                && nx < w as i64
                && ny < h as i64
                && mask[(ny as usize) * w + nx as usize]
        })
    })
}

/// Which pixels object `object` (all its instances) covers in frame
/// `frame`, rasterised on the CPU at pixel centres with the scene's own
/// matrices (`w × h`, row-major, y down).
pub fn silhouette(scene: &Scene, object: usize, frame: u32, w: usize, h: usize) -> Vec<bool> {
    let state = scene.frame(frame, w as f32 / h as f32);
    // A skinned object's outline is its pose's.
    let rest = scene.objects[object]
        .mesh
        .build(Path::new("."))
        .unwrap()
        .skinned(scene.objects[object].skin.as_ref());
    let mesh = scene.posed(object, &rest, &state).unwrap_or(rest);
    let instances: Vec<Vec<glam::Vec2>> = state.instances[object]
        .iter()
        .map(|instance| {
            let clip = state.clip_from_world * state.objects[object] * *instance;
            mesh.positions
                .iter()
                .map(|p| {
                    let c = clip * p.extend(1.0);
                    glam::Vec2::new(c.x / c.w, c.y / c.w)
                })
                .collect()
        })
        .collect();
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let p = glam::Vec2::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0);
            instances.iter().any(|points| {
                mesh.indices.chunks(3).any(|t| {
                    let [a, b, c] = [
                        points[t[0] as usize],
                        points[t[1] as usize],
                        points[t[2] as usize],
                    ];
                    let side = |u: glam::Vec2, v: glam::Vec2| (v - u).perp_dot(p - u);
                    let (s0, s1, s2) = (side(a, b), side(b, c), side(c, a));
                    (s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0) || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0)
                })
            })
        })
        .collect()
}

/// The pixels of `mask` whose whole 8-neighbourhood is in `mask`: one
/// pixel in from its edge, where rasterisation rounding cannot matter.
pub fn interior(mask: &[bool], w: usize) -> Vec<bool> {
    let outside: Vec<bool> = mask.iter().map(|m| !m).collect();
    (0..mask.len()).map(|i| !near(&outside, w, i)).collect()
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
    let (_dir, path) = temp_file("scene.toml", scene_text.as_bytes());
    let output = shadecache([
        "profile".as_ref(),
        shader.as_ref(),
        "--scene".as_ref(),
        path.as_os_str(),
        "--quiet".as_ref(),
    ] as [&std::ffi::OsStr; 5]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    err
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

/// Where object `object` of `scene` moved between frames 0 and 1 at
/// `w`×`h`: the pixels it newly covers (its leading band, two pixels in
/// from the band's edges) and those it uncovers (one pixel in), from its
/// silhouettes.
pub fn moved_bands(scene: &Scene, object: usize, w: usize, h: usize) -> (Vec<usize>, Vec<usize>) {
    let (before, now) = (
        silhouette(scene, object, 0, w, h),
        silhouette(scene, object, 1, w, h),
    );
    let leading: Vec<bool> = (0..w * h).map(|i| now[i] && !before[i]).collect();
    let leading = interior(&interior(&leading, w), w);
    let trailing: Vec<bool> = (0..w * h).map(|i| before[i] && !now[i]).collect();
    let trailing = interior(&trailing, w);
    (
        (0..w * h).filter(|&i| leading[i]).collect(),
        (0..w * h).filter(|&i| trailing[i]).collect(),
    )
}

/// Whether pixel `i` of a classification map (RGBA8) is a hit.
pub fn is_hit(classes: &[u8], i: usize) -> bool {
    classes[i * 4..i * 4 + 3] == shadecache::measure::metrics::HIT
}
