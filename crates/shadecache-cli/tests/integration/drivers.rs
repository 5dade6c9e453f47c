//! What a GPU driver does to a measured run: a crash or a hang is a
//! diagnostic naming the shader, the step, the adapter and driver (exit
//! code 3), never a bare signal; shaders that crashed an old driver
//! profile on a current one; every report names the driver's version.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

use crate::util::{root, stderr, stdout};

/// `shadecache ARGS...` from the root with `env` set, colour off.
fn shadecache_with(env: &[(&str, &str)], args: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_shadecache"));
    command.args(args).current_dir(root()).env("NO_COLOR", "1");
    for (name, value) in env {
        command.env(name, value);
    }
    command.output().expect("the shadecache binary runs")
}

/// `profile SHADER --nodes top:1 --quiet --out OUT EXTRA...`.
fn profile(shader: &str, out: &std::path::Path, extra: &[&str]) -> Vec<String> {
    ["profile", shader, "--nodes", "top:1", "--quiet", "--out"]
        .iter()
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .chain(extra.iter().map(|s| s.to_string()))
        .collect()
}

/// The smallest profile: one node, one variant, one frame.
fn tiny_profile(shader: &str, out: &std::path::Path) -> Vec<String> {
    profile(
        shader,
        out,
        &[
            "--size",
            "16x16",
            "--frames",
            "1",
            "--warmup",
            "0",
            "--variant",
            "one-pass",
        ],
    )
}

fn args(list: &[String]) -> Vec<&str> {
    list.iter().map(String::as_str).collect()
}

/// The run ends by a signal in the middle of the reference's first frame
/// (the test-only hook aborts the measured run as a crashing driver
/// would): the command says what it was drawing, on which adapter and
/// driver, and exits with 3, not with the signal.
#[test]
fn a_driver_crash_is_a_diagnostic_not_a_signal() {
    let Some(gpu) = crate::util::adapter() else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let output = shadecache_with(
        &[("SHADECACHE_TEST_ABORT_WHILE_DRAWING", "reference")],
        &args(&tiny_profile("corpus/noise_marble.wgsl", out.path())),
    );
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(3), "{err}");
    for part in [
        "the measured run was ended by signal 6 (SIGABRT",
        "while drawing a frame of reference (its passes",
        "shader: corpus/noise_marble.wgsl",
        &format!("adapter and driver: {}", gpu.name),
        gpu.driver_info.as_str(),
        // The default scene's neutral values, which a crash may owe to.
        "the scene gave a neutral value to: uniform `frame.",
    ] {
        assert!(err.contains(part), "`{part}` not in:\n{err}");
    }
}

/// A fragment shader that loops for minutes: with a five-second bound
/// (room for its pipelines to compile on a loaded machine) the run is
/// ended and said to have run past it, with exit code 3.
#[test]
fn a_runaway_frame_is_a_diagnostic() {
    let Some(gpu) = crate::util::adapter() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let shader = dir.path().join("runaway.wgsl");
    std::fs::write(
        &shader,
        "struct Frame { clip_from_world: mat4x4<f32>, }
@group(0) @binding(0) var<uniform> frame: Frame;
struct V { @builtin(position) position: vec4<f32>, @location(0) p: vec3<f32> }
@vertex
fn vs(@location(0) p: vec3<f32>) -> V {
    return V(frame.clip_from_world * vec4<f32>(p, 1.0), p);
}
@fragment
fn fs(in: V) -> @location(0) vec4<f32> {
    var acc = in.p.x;
    for (var i = 0u; i < 2000000000u; i++) {
        acc = sin(acc * 1.0001 + in.p.y);
    }
    return vec4<f32>(acc, in.p.z, 0.0, 1.0);
}
",
    )
    .unwrap();
    let out = dir.path().join("report");
    let started = std::time::Instant::now();
    let output = shadecache_with(
        &[("SHADECACHE_GPU_TIMEOUT", "5")],
        &args(&tiny_profile(&shader.display().to_string(), &out)),
    );
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(3), "{err}");
    for part in [
        "one GPU step ran past 5 s, so the measured run was ended: drawing a frame of reference",
        "runaway.wgsl",
        &format!("adapter and driver: {}", gpu.name),
        "SHADECACHE_GPU_TIMEOUT=SECONDS",
    ] {
        assert!(err.contains(part), "`{part}` not in:\n{err}");
    }
    // Ended, not waited for: 2·10⁹ iterations a pixel take minutes.
    assert!(
        started.elapsed() < std::time::Duration::from_secs(60),
        "the run was not ended: {:?}",
        started.elapsed()
    );
}

/// The 77-line reduction of Bevy's PBR shader that crashed Mesa 22.3.6's
/// lavapipe profiles on the driver the project requires (Mesa 24 or
/// newer).
#[test]
fn lavapipe_22_reproducer_profiles() {
    let Some(_gpu) = crate::util::adapter() else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let output = shadecache_with(
        &[],
        &args(&profile(
            "tests/drivers/lavapipe-22.3.6-crash.wgsl",
            out.path(),
            &[
                "--size",
                "8x8",
                "--frames",
                "1",
                "--warmup",
                "0",
                "--variant",
                "two-pass",
            ],
        )),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(out.path().join("report.json").is_file());
}

/// The folder of a crate of the workspace's dependency graph, found as
/// the library finds a WESL package's (`cargo metadata`, with the network
/// where offline cannot list every platform's packages).
fn package_dir(name: &str) -> PathBuf {
    use shadecache::front::crate_package::{source_dir, Lookup};
    let root = root();
    let src = source_dir(name, &Lookup::command_line(&root)).unwrap_or_else(|err| panic!("{err}"));
    src.parent()
        .expect("`src/` is in the crate's folder")
        .to_path_buf()
}

/// Bevy's PBR shader as the naga_oil crate ships it (its example, composed
/// from 17 modules) profiles with the default scene: the command that
/// died by SIGSEGV on Mesa 22.3.6.
#[test]
fn bevy_pbr_profiles() {
    let Some(_gpu) = crate::util::adapter() else {
        return;
    };
    let example = package_dir("naga_oil").join("examples/bevy_pbr_wgsl");
    let out = tempfile::tempdir().unwrap();
    let import_path = example.display().to_string();
    let output = shadecache_with(
        &[],
        &args(&profile(
            &example.join("pbr.wgsl").display().to_string(),
            out.path(),
            &[
                "--import-path",
                &import_path,
                "--def",
                "VERTEX_UVS",
                "--size",
                "64x64",
                "--frames",
                "4",
            ],
        )),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let report = report_json(out.path());
    assert!(
        !report["results"].as_array().unwrap().is_empty(),
        "no configuration measured: {report}"
    );
}

/// report.json of a report folder.
fn report_json(out: &std::path::Path) -> Value {
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

/// A run's summary line and its page name `version`; its report.json's
/// `pointer` field contains it.
fn names_the_driver(output: &Output, out: &std::path::Path, pointer: &str, version: &str) {
    assert!(output.status.success(), "{}", stderr(output));
    let first = stdout(output)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    assert!(first.contains(version), "{first}");
    let driver = report_json(out)
        .pointer(pointer)
        .cloned()
        .unwrap_or_default();
    assert!(
        driver.as_str().unwrap_or_default().contains(version),
        "{driver}"
    );
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(page.contains(version), "the page does not name {version}");
}

/// A figure belongs to its driver: `profile`'s and `interpolate`'s
/// summaries, report.json and the pages name the adapter's driver with
/// its version.
#[test]
fn reports_name_the_driver_version() {
    let Some(gpu) = crate::util::adapter() else {
        return;
    };
    let version = gpu.driver_info.clone();
    assert!(!version.is_empty(), "the adapter names no driver version");

    let out = tempfile::tempdir().unwrap();
    let output = shadecache_with(
        &[],
        &args(&tiny_profile("corpus/noise_marble.wgsl", out.path())),
    );
    names_the_driver(&output, out.path(), "/device/driver", &version);

    let out = tempfile::tempdir().unwrap();
    let output = shadecache_with(
        &[],
        &[
            "interpolate",
            "corpus/noise_marble.wgsl",
            "--scene",
            "corpus/scenes/walking_floor.toml",
            "--method",
            "sample-and-hold",
            "--size",
            "32x32",
            "--frames",
            "5",
            "--quiet",
            "--out",
            &out.path().display().to_string(),
        ],
    );
    names_the_driver(&output, out.path(), "/driver", &version);
}
