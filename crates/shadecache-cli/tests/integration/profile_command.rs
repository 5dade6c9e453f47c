//! `shadecache profile` as a user runs it: its errors, its report.json,
//! a sweep and its choice, the confirmatory run, every entry point.

use crate::util::*;
use shadecache::rewrite::Variant;

#[test]
fn a_missing_uniform_is_an_error_naming_it() {
    let scene = marble_scene("", "").replace("marble_frequency = 4.0\n", "");
    let err = crate::util::profile_error("corpus/noise_marble.wgsl", &scene);
    assert!(err.contains("`frame.marble_frequency`"), "{err}");
    assert!(err.contains("[uniforms]"), "{err}");
}

#[test]
fn a_bad_scene_file_points_at_the_error() {
    let err = crate::util::profile_error(
        "corpus/noise_marble.wgsl",
        "size = [128, 128]\nframes = \"many\"\n",
    );
    assert!(err.contains("scene.toml:2:"), "{err}");
}

#[test]
fn report_json_carries_the_documented_fields() {
    if crate::util::no_gpu() {
        return;
    }
    let scene = marble_scene("\"object-motion\"", "");
    let (_dir, path) = temp_file("scene.toml", scene.as_bytes());
    let out = tempfile::tempdir().unwrap();
    let output = shadecache([
        "profile".as_ref(),
        "corpus/noise_marble.wgsl".as_ref(),
        "--scene".as_ref(),
        path.as_os_str(),
        "--nodes".as_ref(),
        "top:2".as_ref(),
        "--frames".as_ref(),
        "2".as_ref(),
        "--out".as_ref(),
        out.path().as_os_str(),
        "--quiet".as_ref(),
    ] as [&std::ffi::OsStr; 11]);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap()).unwrap();
    let results = report["results"].as_array().unwrap();
    // The command's default measures every variant, lowres too.
    assert_eq!(results.len(), 2 * Variant::ALL.len());
    for row in results {
        for key in [
            "node",
            "variant",
            "speedup",
            "psnr",
            "ssim",
            "hit_rate",
            "miss_rate",
            "refresh_rate",
            "p_over_t",
            "ideal_speedup",
            "passes",
            "time_ms",
        ] {
            assert!(!row[key].is_null(), "{key} missing: {row}");
        }
        assert!(Variant::ALL
            .iter()
            .any(|v| v.as_str() == row["variant"].as_str().unwrap()));
        assert!(row["speedup"].as_f64().unwrap() > 0.0);
    }
    assert!(report["reference"]["time_ms"].as_f64().unwrap() > 0.0);
    let html = std::fs::read_to_string(out.path().join("report.html")).unwrap();
    assert!(html.contains("<svg") && html.contains("data:image/png;base64,"));
    assert!(html.contains("Which value to cache"));
    let maps = std::fs::read_dir(out.path().join("maps")).unwrap().count();
    assert_eq!(maps, 2 * Variant::ALL.len());
    assert!(out.path().join("images/difference.png").is_file());
    let trace: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("trace.json")).unwrap()).unwrap();
    assert!(
        trace.to_string().contains("pass1"),
        "the Chrome trace names the passes"
    );
    assert!(stdout_has(&output, "report: "));
}

fn stdout_has(output: &std::process::Output, text: &str) -> bool {
    String::from_utf8_lossy(&output.stdout).contains(text)
}

/// `--sweep` measures the pruned grid, says what it pruned, marks the
/// Pareto front of time against PSNR and SSIM, and `--max-error` writes
/// the fastest configuration within the budget as a valid rewrite.
#[test]
fn sweep_marks_the_pareto_front_and_writes_the_choice() {
    if crate::util::no_gpu() {
        return;
    }
    let scene = marble_scene("\"object-motion\"", "");
    let (_dir, path) = temp_file("scene.toml", scene.as_bytes());
    let out = tempfile::tempdir().unwrap();
    let output = shadecache(
        [
            "profile",
            "corpus/noise_marble.wgsl",
            "--scene",
            path.to_str().unwrap(),
            "--sweep",
            "--nodes",
            "top:1",
            "--variant",
            "two-pass",
            // Narrower than the sweep's own axes, to stay quick; the
            // format, reconstruction and ε axes keep their sweep values.
            "--refresh-period",
            "8,32",
            "--refresh-quad",
            "1,4",
            "--size",
            "48x48",
            "--frames",
            "2",
            "--warmup",
            "1",
            "--max-error",
            "psnr:10",
            "--out",
            out.path().to_str().unwrap(),
            "--quiet",
        ]
        .map(std::ffi::OsStr::new),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let report: shadecache::report::Report =
        serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap()).unwrap();

    // 2 Δn × 2 k × 4 reconstructions × 2 formats × 3 ε = 96 settings; the
    // planes through the base (Δn 32, k 4, bilinear, rgba16float, the
    // default ε) keep 4 + 24 − 1 = 27, and the base again with adaptive
    // refresh makes 28 configurations.
    let grid = report.grid.as_ref().expect("a sweep reports its grid");
    assert_eq!(grid.full, 96);
    assert_eq!(grid.measured, 28);
    assert_eq!(report.results.len(), 28);
    assert_eq!(report.results.iter().filter(|r| r.adaptive).count(), 1);
    let pruned: usize = grid.pruned.iter().map(|p| p.configurations).sum();
    assert_eq!(pruned, 96 - 27);
    assert!(grid.pruned.iter().all(|p| !p.reason.is_empty()));
    for format in ["rgba16float", "rgba32float"] {
        assert!(report
            .results
            .iter()
            .any(|r| r.cache_format.as_str() == format));
    }

    // The front: no row on it is beaten on both time and PSNR by another.
    let front: Vec<_> = report.results.iter().filter(|r| r.pareto_psnr).collect();
    assert!(!front.is_empty() || report.results.iter().all(|r| r.speedup <= 1.0));
    for a in &front {
        assert!(a.time_ms <= report.reference.time_ms);
        for b in &report.results {
            assert!(
                !(b.time_ms < a.time_ms && b.psnr > a.psnr),
                "a front row is dominated"
            );
        }
    }
    let html = std::fs::read_to_string(out.path().join("report.html")).unwrap();
    assert!(html.contains("Pareto front") && html.contains("SSIM against time"));

    // The choice: the fastest row within the budget whose speed-up
    // interval lies above 1×, if the confirmatory run repeats it; its
    // rewrite is on disk and valid.
    let choice = report.choice.as_ref().expect("a profile records a choice");
    assert!(choice.budget_given);
    let within = report
        .results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.psnr >= 10.0 && r.speedup_ci[0] > 1.0)
        .min_by(|a, b| a.1.time_ms.total_cmp(&b.1.time_ms))
        .map(|(i, _)| i);
    let chosen = choice.result;
    if let Some(i) = chosen {
        assert_eq!(Some(i), within);
        let plan: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.path().join("choice/plan.json")).unwrap())
                .unwrap();
        assert_eq!(plan["variant"], "two-pass");
        for entry in std::fs::read_dir(out.path().join("choice")).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "wgsl") {
                shadecache::front::load(&path)
                    .unwrap_or_else(|e| panic!("{}: {e:?}", path.display()));
            }
        }
        assert!(stdout_has(&output, "wrote its shaders and plan"));
    } else {
        // No choice only when nothing within the budget beats the original
        // beyond noise, or the confirmatory run did not repeat it.
        assert!(
            within.is_none()
                || choice
                    .confirmation
                    .as_ref()
                    .is_some_and(|c| c.speedup_ci[0] <= 1.0)
        );
        assert!(!out.path().join("choice").exists());
        assert!(stdout_has(&output, "keep the original"));
    }
}

/// The run's winner is measured again, against the original, before it is
/// recommended; what `choice/` holds is the configuration measured.
#[test]
fn confirmatory_run_repeats_the_winner() {
    if crate::util::no_gpu() {
        return;
    }
    let shader = root().join("tests/shaders/costly_smooth.wgsl");
    let out = tempfile::tempdir().unwrap();
    let output = shadecache([
        "profile".as_ref(),
        shader.as_os_str(),
        "--size".as_ref(),
        "64x64".as_ref(),
        "--frames".as_ref(),
        "6".as_ref(),
        "--warmup".as_ref(),
        "8".as_ref(),
        "--nodes".as_ref(),
        "top:1".as_ref(),
        "--variant".as_ref(),
        "one-pass".as_ref(),
        "--refresh-period".as_ref(),
        "16".as_ref(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        out.path().as_os_str(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: shadecache::report::Report =
        serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap()).unwrap();
    let choice = report.choice.as_ref().unwrap();
    assert!(!choice.budget_given);
    assert_eq!(choice.budget, shadecache::report::Budget::DEFAULT);
    let confirmation = choice
        .confirmation
        .as_ref()
        .expect("the run has a winner, and it was measured again");
    assert_eq!(confirmation.frames, report.frames);
    assert!(confirmation.speedup_ci[0] <= confirmation.speedup);
    assert!(confirmation.speedup <= confirmation.speedup_ci[1]);
    let row = &report.results[choice.result.or(choice.closest).unwrap()];
    assert!(row.speedup_ci[0] > 1.0 && row.ssim >= 0.95);
    if choice.result.is_some() {
        let plan: shadecache::plan::Plan =
            serde_json::from_slice(&std::fs::read(out.path().join("choice/plan.json")).unwrap())
                .unwrap();
        assert_eq!(plan.node.id, row.node);
        assert_eq!(plan.variant, row.variant);
        assert_eq!(plan.refresh.period, row.refresh_period);
        assert_eq!(plan.cache.format, row.cache_format);
        assert!(stdout(&output).contains("measured again"));
    }
}

/// A module with two fragment entry points (a lit pass and a wave pass
/// over one vertex stage), with no `--entry`: `profile` takes each in
/// turn into `OUT/<entry>/` and writes an index with a section per entry
/// point; `rewrite` writes each into `OUT/<entry>/`. Both used to stop and
/// ask for `--entry`.
#[test]
fn every_fragment_entry_point_is_profiled() {
    if crate::util::no_gpu() {
        return;
    }
    let source = "struct Frame { clip_from_world: mat4x4<f32>, world_from_local: mat4x4<f32>, light_position: vec3<f32> }
@group(0) @binding(0) var<uniform> frame: Frame;
struct VertexOut { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32>, @location(1) normal: vec3<f32> }
@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VertexOut {
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    return VertexOut(frame.clip_from_world * world, world.xyz, normal);
}
@fragment
fn fs_lit(in: VertexOut) -> @location(0) vec4<f32> {
    let l = normalize(frame.light_position - in.world);
    let diffuse = max(dot(normalize(in.normal), l), 0.0);
    let bands = 0.5 + 0.5 * sin(in.world * 9.0);
    return vec4<f32>(bands * diffuse + 0.1, 1.0);
}
@fragment
fn fs_waves(in: VertexOut) -> @location(0) vec4<f32> {
    let w = sin(in.world.x * 11.0) * cos(in.world.y * 7.0) + sin(in.world.z * 13.0);
    return vec4<f32>(vec3<f32>(0.5 + 0.25 * w), 1.0);
}
";
    let (dir, shader) = temp_file("two_passes.wgsl", source.as_bytes());
    let out = dir.path().join("report");
    let output = shadecache([
        "profile",
        shader.to_str().unwrap(),
        "--variant",
        "one-pass",
        "--nodes",
        "top:1",
        "--frames",
        "2",
        "--size",
        "48x48",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let summary = stdout(&output);
    for entry in ["fs_lit", "fs_waves"] {
        assert!(
            summary.contains(&format!("entry point `{entry}`:")),
            "{summary}"
        );
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join(entry).join("report.json")).unwrap())
                .unwrap();
        assert_eq!(report["entry"], entry);
        assert!(!report["results"].as_array().unwrap().is_empty());
    }
    let index: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let listed: Vec<&str> = index["entries"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["entry"].as_str().unwrap())
        .collect();
    assert_eq!(listed, ["fs_lit", "fs_waves"]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains("href=\"fs_lit/report.html\"")
            && html.contains("href=\"fs_waves/report.html\"")
    );

    let variants = dir.path().join("variants");
    let output = shadecache([
        "rewrite",
        shader.to_str().unwrap(),
        "--all-nodes",
        "--variant",
        "one-pass",
        "--out",
        variants.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(variants.join("fs_lit").is_dir() && variants.join("fs_waves").is_dir());
}

/// A knob is never silently ignored: lowres's given without lowres get a
/// note, and a read-back value that is lowres's names the flag that takes
/// it; a value the flag never takes is a usage error, not a run that
/// refuses its only configuration.
#[test]
fn flags_that_do_nothing_are_noted() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v");
    let output = shadecache([
        "rewrite",
        "corpus/noise_marble.wgsl",
        "--node",
        "n5c3eb6af",
        "--variant",
        "two-pass",
        "--sigma-normal",
        "0.5",
        "--reshade-unreliable",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains(
            "note: ignored --sigma-normal, --reshade-unreliable: lowres's knobs, and --variant asks for neither lowres nor deferred-lowres"
        ),
        "{}",
        stderr(&output)
    );
    // `--def NAME=false` where a module tests `#ifdef NAME`: warned.
    let output = shadecache([
        "analyze",
        "corpus/composed/ripple_material.wgsl",
        "--import-path",
        "corpus/composed/modules",
        "--def",
        "FOG=false",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("warning: --def FOG=false defines FOG, and `#ifdef FOG`"),
        "{}",
        stderr(&output)
    );
    // Usage errors, before anything runs.
    for (flag, value, says) in [
        (
            "--reconstruction",
            "spatial",
            "--lowres-reconstruction spatial",
        ),
        (
            "--lowres-reconstruction",
            "bilinear-packed",
            "invalid value 'bilinear-packed'",
        ),
    ] {
        let output = shadecache([
            "profile",
            "corpus/noise_marble.wgsl",
            "--variant",
            "lowres",
            flag,
            value,
        ]);
        assert_eq!(output.status.code(), Some(1), "{flag} {value}");
        assert!(stderr(&output).contains(says), "{}", stderr(&output));
    }
}
