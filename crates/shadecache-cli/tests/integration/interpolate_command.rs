//! `shadecache interpolate` as a user runs it: bad input, the default
//! scene.

use crate::util::*;

/// Bad knobs and methods get a clear error and exit 1, before anything is
/// written.
#[test]
fn interpolate_bad_input_is_an_error() {
    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().join("report");
    let marble = "corpus/noise_marble.wgsl";
    let scene = "corpus/scenes/marble_sphere.toml";
    let out_arg = out_dir.display().to_string();
    for (args, says) in [
        (vec!["--frames-per-interval", "1"], "frames-per-interval"),
        (vec!["--iterations", "0"], "iterations"),
        (vec!["--method", "optical-flow"], "optical-flow"),
        (vec!["--screen-epsilon=-1"], "screen-epsilon"),
        (vec!["--inpaint-passes", "0"], "inpaint-passes"),
        (vec!["--latest-radius", "0"], "latest-radius"),
        (vec!["--method", "morph", "--grid", "12"], "power of two"),
        (
            vec!["--method", "payload", "--node", "n00000000"],
            "unknown node id `n00000000`",
        ),
        (
            vec!["--method", "morph", "--size", "100x100"],
            "does not divide the 100×100 frame",
        ),
        (vec!["--method", "morph", "--gamma", "0"], "gamma"),
        (
            vec!["--method", "morph", "--gamma", "1e30"],
            "--gamma is a display's",
        ),
        (
            vec!["--pursuit-substeps", "1000000"],
            "--pursuit-substeps must be from 1 to 1024",
        ),
        (
            vec![
                "--method",
                "morph",
                "--tracking",
                "70,90",
                "--tracking",
                "1,2",
            ],
            "tracking",
        ),
        (vec!["--method", "morph", "--tracking", "90,70"], "tracking"),
        (vec!["--method", "morph", "--blur-level", "0"], "blur-level"),
        (
            vec!["--method", "morph", "--frames-per-interval", "1"],
            "frames-per-interval",
        ),
    ] {
        let mut full = vec!["interpolate", marble, "--scene", scene, "--out", &out_arg];
        full.extend(args.iter().copied());
        let output = crate::util::shadecache(&full);
        assert_eq!(output.status.code(), Some(1), "{args:?}");
        let err = crate::util::stderr(&output);
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!out_dir.exists(), "{args:?} wrote a report");
    }
    // A shader whose flows cannot be made (the fragment stage moves its
    // own depth): refused with the reason, before anything is written.
    let (_dir, shader) = temp_file(
        "depth.wgsl",
        br#"
struct Frame { clip_from_world: mat4x4<f32> }
@group(0) @binding(0) var<uniform> frame: Frame;
@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return frame.clip_from_world * vec4<f32>(position, 1.0);
}
struct Out { @location(0) color: vec4<f32>, @builtin(frag_depth) depth: f32 }
@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> Out {
    return Out(vec4<f32>(1.0), p.z * 0.5);
}
"#,
    );
    let shader = shader.display().to_string();
    let output = crate::util::shadecache([
        "interpolate",
        &shader,
        "--method",
        "morph",
        "--out",
        &out_arg,
    ]);
    assert_eq!(output.status.code(), Some(1));
    let err = crate::util::stderr(&output);
    assert!(err.contains("frag_depth"), "{err}");
    assert!(!out_dir.exists());
}

/// With no scene, `interpolate` renders the motion a game has (the camera
/// orbiting at 1° a frame, a small sphere crossing in front), said in the
/// report: holding the I-frame then loses visibly to the scene-assisted
/// pass. On the profile's default scene, which barely moves, every
/// method tied with sample-and-hold (SSIM 0.9987 at 64², here 0.986).
#[test]
fn default_interpolation_scene_moves() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let output = crate::util::shadecache([
        "interpolate",
        "corpus/noise_marble.wgsl",
        "--method",
        "sample-and-hold,scene-assisted",
        "--size",
        "64x64",
        "--frames",
        "8",
        "--quiet",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", crate::util::stderr(&output));
    assert!(crate::util::stdout(&output).contains("scene: default scene with a game's motion"));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap()).unwrap();
    assert!(report["scene_description"]
        .as_str()
        .unwrap()
        .contains("orbits at 1° a frame"));
    let ssim = |name: &str| {
        report["methods"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["method"] == name)
            .unwrap_or_else(|| panic!("{name} in {report}"))["ssim_mean"]
            .as_f64()
            .unwrap()
    };
    let (hold, assisted) = (ssim("sample-and-hold"), ssim("scene-assisted"));
    assert!(hold < 0.995, "sample-and-hold {hold}");
    assert!(
        assisted > hold + 0.005,
        "scene-assisted {assisted}, hold {hold}"
    );
}

/// The morph at the largest frame side: its search pyramid pads the frame
/// by a tile, past the largest texture, so the size is an error naming
/// the largest it takes, before the GPU is touched (it was a panic in
/// wgpu's texture validation). The comma form of the ramps parses.
#[test]
fn morph_at_the_largest_size_is_an_error_or_runs() {
    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().join("report");
    for method in ["morph", "morph-past", "morph-warp", "all"] {
        let output = crate::util::shadecache([
            "interpolate",
            "corpus/noise_marble.wgsl",
            "--scene",
            "corpus/scenes/walking_floor.toml",
            "--size",
            "8192x8",
            "--frames",
            "4",
            "--method",
            method,
            "--tracking",
            "70,90",
            "--distortion-blur",
            "0.25,1",
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        let err = crate::util::stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{method}: {err}");
        assert!(
            err.contains("the morph at --grid 8 takes frames up to 8184 pixels a side, not 8192×8"),
            "{method}: {err}"
        );
        assert!(!err.contains("panicked"), "{method}: {err}");
        assert!(!out_dir.exists());
    }
}

/// `--blur-order paper` runs the morph in the paper's order, the report
/// records it with the edge error and the paper's break-even figure of
/// each extrapolator, and the summary says whether it breaks even.
#[test]
fn blur_order_paper_is_recorded_with_the_break_even_figure() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let output = crate::util::shadecache([
        "interpolate",
        "corpus/noise_marble.wgsl",
        "--scene",
        "corpus/scenes/walking_floor.toml",
        "--method",
        "morph",
        "--blur-order",
        "paper",
        "--size",
        "64x64",
        "--frames-per-interval",
        "3",
        "--frames",
        "6",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", crate::util::stderr(&output));
    let stdout = crate::util::stdout(&output);
    assert!(
        stdout.contains("break even (seed 004's test: below 1)")
            || stdout.contains("breaks even (seed 004's test: below 1)"),
        "{stdout}"
    );
    assert!(stdout.contains("within 12 px of a motion edge"), "{stdout}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.path().join("report.json")).unwrap()).unwrap();
    assert_eq!(report["parameters"]["blur_order"], "paper", "{report}");
    let morph = &report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["method"] == "morph")
        .unwrap_or_else(|| panic!("morph in {report}"));
    assert!(
        morph["extrapolated_frame_ratio"].as_f64().unwrap() > 0.0,
        "{morph}"
    );
    assert!(morph["edge_psnr"].as_f64().unwrap() > 10.0, "{morph}");
}
