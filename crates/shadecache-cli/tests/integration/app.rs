//! `examples/app`: a wgpu application whose build script rewrites its own
//! shader and whose render loop runs the variant with the host crate. It
//! builds from the checkout and runs headless on lavapipe; its cached
//! frames are compared with its original frames.

use std::path::Path;
use std::process::Command;

use crate::util::{cargo_tree, root};

/// Runs the app with `args`; its stdout.
fn run_app(args: &[&str], out: &Path) -> String {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    let output = Command::new(env!("CARGO"))
        .args(["run", "--quiet", "--locked", "--manifest-path"])
        .arg(root().join("examples/app/Cargo.toml"))
        .arg("--")
        .args(args)
        .arg("--out")
        .arg(out)
        // Share the repository's target directory so shadecache and its
        // dependencies are not compiled again.
        .env("CARGO_TARGET_DIR", target)
        .output()
        .expect("cargo runs");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    stdout
}

/// The numbers of the app's steady-state line: mean PSNR, worst PSNR,
/// max error.
fn steady_state(stdout: &str) -> [f64; 3] {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("steady state"))
        .unwrap_or_else(|| panic!("no steady-state line:\n{stdout}"));
    let numbers: Vec<f64> = line
        .split([' ', ','])
        .filter_map(|word| word.parse().ok())
        .collect();
    match numbers[..] {
        [mean, worst, max_error] => [mean, worst, max_error],
        _ => panic!("{line}"),
    }
}

/// With Δn = 1 every pixel is computed every frame: each cached frame is
/// the original frame, up to the f16 cache's rounding (below one step of
/// an 8-bit display).
#[test]
fn example_app_at_refresh_period_one_equals_its_original_frames() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let stdout = run_app(
        &[
            "--compare",
            "--refresh-period",
            "1",
            "--frames",
            "4",
            "--size",
            "96",
        ],
        out.path(),
    );
    for line in stdout.lines().filter(|l| l.starts_with("frame")) {
        let error: f64 = line.rsplit(' ').next().unwrap().parse().unwrap();
        assert!(error <= 1.0 / 255.0, "{line}");
    }
    let [_, _, max_error] = steady_state(&stdout);
    assert!(max_error <= 1.0 / 255.0, "{stdout}");
    for name in ["original_000.png", "cached_000.png"] {
        assert!(out.path().join(name).is_file(), "{name}");
    }
    assert!(stdout.contains("GPU ms per frame: original"), "{stdout}");
}

/// In the steady state the app's error stays within what `profile`
/// measures for the same node and knobs on the same scene
/// (`examples/app/scene.toml`): the profiler and the app run the variant
/// through the same host crate.
#[test]
fn example_app_error_stays_within_what_profile_measured() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let app = run_app(&["--compare", "--frames", "8", "--size", "96"], out.path());
    let [mean, worst, _] = steady_state(&app);
    let profile = crate::util::shadecache([
        "profile",
        root()
            .join("examples/app/shaders/planet.wgsl")
            .to_str()
            .unwrap(),
        "--scene",
        root().join("examples/app/scene.toml").to_str().unwrap(),
        "--nodes",
        "nf50106c5",
        "--variant",
        "three-pass",
        "--refresh-period",
        "16",
        "--cache-format",
        "rgba16float",
        "--frames",
        "8",
        "--size",
        "96x96",
        "--quiet",
        "--out",
        out.path().join("profile").to_str().unwrap(),
    ]);
    assert!(
        profile.status.success(),
        "{}",
        crate::util::stderr(&profile)
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.path().join("profile/report.json")).unwrap(),
    )
    .unwrap();
    let row = &report["results"][0];
    let (psnr, worst_psnr) = (
        row["psnr"].as_f64().unwrap(),
        row["worst_psnr"].as_f64().unwrap(),
    );
    // The same scene drawn by two programs: within half a decibel.
    assert!(
        mean >= psnr - 0.5,
        "app {mean} dB, profile {psnr} dB\n{app}"
    );
    assert!(
        worst >= worst_psnr - 0.5,
        "app {worst} dB, profile {worst_psnr} dB\n{app}"
    );
    assert!(mean < 90.0, "the app's cache reuses nothing: {app}");
}

/// The host crate's test fixtures are what the toolchain writes today, so
/// the host is tested on current plans.
#[test]
fn host_crate_fixtures_are_what_rewrite_writes() {
    let fixtures = root().join("crates/shadecache-host/tests/fixtures");
    for (shader, node, variants) in [
        (
            "square",
            "nf0aaf62f",
            ["three-pass", "one-pass", "deferred"].as_slice(),
        ),
        ("gbuffer", "nf0aaf62f", ["three-pass"].as_slice()),
    ] {
        let out = tempfile::tempdir().unwrap();
        let source = format!("crates/shadecache-host/tests/fixtures/{shader}.wgsl");
        let list = variants.join(",");
        let output = crate::util::shadecache([
            "rewrite",
            &source,
            "--node",
            node,
            "--variant",
            &list,
            "--refresh-period",
            "64",
            "--out",
            out.path().to_str().unwrap(),
        ]);
        assert!(output.status.success(), "{}", crate::util::stderr(&output));
        for &variant in variants {
            // One variant is written into the folder itself.
            let written = match variants.len() {
                1 => out.path().to_path_buf(),
                _ => out.path().join(variant),
            };
            for entry in std::fs::read_dir(written).unwrap() {
                let path = entry.unwrap().path();
                let name = path.file_name().unwrap();
                // The list of what the run wrote, for the next run to clear.
                if name == ".shadecache-out" {
                    continue;
                }
                let text = std::fs::read_to_string(&path).unwrap();
                let fixture = fixtures.join(shader).join(variant).join(name);
                assert!(
                    std::fs::read_to_string(&fixture).is_ok_and(|f| f == text),
                    "{}: the fixture is stale; write it again with `shadecache rewrite {source} --node {node} --variant {list} --refresh-period 64`",
                    fixture.display()
                );
            }
        }
    }
}

/// The crates in `cargo tree -p PACKAGE -e normal EXTRA...`.
fn tree(package: &str, extra: &[&str]) -> Vec<String> {
    let mut args = vec!["-p", package, "-e", "normal"];
    args.extend(extra);
    cargo_tree(&args)
}

/// An application links the host crate without the toolchain: its
/// dependencies are wgpu, serde and the plan schema (and pollster, to wait
/// on wgpu), and none of the toolchain's, except what wgpu itself brings
/// (its WGSL front end reports with codespan-reporting).
#[test]
fn host_crate_depends_on_wgpu_serde_and_the_plan_only() {
    let mut direct = tree("shadecache-host", &["--depth", "1"]).split_off(1);
    direct.sort();
    assert_eq!(direct, ["pollster", "serde", "shadecache-plan", "wgpu"]);
    let crates = tree("shadecache-host", &[]);
    let through_wgpu = tree("wgpu", &[]);
    for toolchain in [
        "clap",
        "petgraph",
        "codespan-reporting",
        "toml",
        "image",
        "indicatif",
        "wgpu-profiler",
        "naga_oil",
        "shadecache",
    ] {
        let pulled = crates.iter().any(|c| c == toolchain);
        let by_wgpu = through_wgpu.iter().any(|c| c == toolchain);
        assert!(!pulled || by_wgpu, "the host crate pulls in {toolchain}");
    }
}

/// The app runs its lowres variant (the albedo shaded at a sixteenth of
/// the pixels, upsampled spatio-temporally) through the host crate as it
/// runs three-pass: the build script wrote it beside three-pass, the app
/// makes it from its own layouts and records it into its own encoder,
/// with the samples' targets at 24×24 its own size. The frames after 16
/// warm-up frames are close to the original's (the planet turns and its
/// north twists against its south, so the history is reprojected).
#[test]
fn lowres_runs_in_the_host_crate() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let stdout = run_app(
        &[
            "--compare",
            "--variant",
            "lowres",
            "--frames",
            "4",
            "--size",
            "96",
        ],
        out.path(),
    );
    assert!(stdout.contains("variant: lowres"), "{stdout}");
    let [mean, worst, _] = steady_state(&stdout);
    assert!(mean > 30.0 && worst > 28.0, "{stdout}");
    assert!(stdout.contains("GPU ms per frame: original"), "{stdout}");
}

/// Run as it ships, the app lets the host crate's governor choose each
/// frame between its original pipeline and the variant, times every frame
/// without waiting for it, watches the cached frames' error against a
/// budget, and says what the governor decided.
#[test]
fn example_app_runs_the_governor_by_default() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let stdout = run_app(&["--frames", "300", "--size", "96"], out.path());
    assert!(
        stdout.contains("300 frames, governed, error budget 35 dB"),
        "{stdout}"
    );
    assert!(stdout.contains("governor: cache"), "{stdout}");
    // The error watch ran: the cache starts on, and its first warm
    // frame is watched.
    assert!(stdout.contains("error watch: "), "{stdout}");
    let timed: u32 = stdout
        .split(" over ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no timed frames in {stdout}"));
    assert!(timed >= 200, "{timed} of 300 frames timed\n{stdout}");
}
