//! `shadecache rewrite` and the variants it emits.

use std::path::Path;

use shadecache::analysis::{self, Analysis};
use shadecache::front::{self, Shader};
use shadecache::rewrite::Variant;

use crate::util::{root, shadecache, stderr, stdout};

/// Loads a corpus shader under its path relative to the repository root,
/// so plans and snapshots do not depend on where the checkout is.
fn load(path: &Path) -> (Shader, Analysis) {
    let text = std::fs::read_to_string(root().join(path)).unwrap();
    let shader = front::parse(shadecache::diagnostic::SourceFile::new(
        path.display().to_string(),
        text,
    ))
    .unwrap_or_else(|e| panic!("{}", e.render()));
    let analysis = analysis::analyze(&shader, &analysis::Options::default()).unwrap();
    (shader, analysis)
}

#[test]
fn rewrite_all_nodes_writes_every_candidate_and_variant() {
    let dir = tempfile::tempdir().unwrap();
    let output = shadecache([
        "rewrite".as_ref(),
        "corpus/noise_marble.wgsl".as_ref(),
        "--all-nodes".as_ref(),
        "--out".as_ref(),
        dir.path().as_os_str(),
    ] as [&std::ffi::OsStr; 5]);
    assert!(output.status.success(), "{}", stderr(&output));
    let (_, analysis) = load(Path::new("corpus/noise_marble.wgsl"));
    for candidate in &analysis.candidates {
        for variant in Variant::ALL {
            let out = dir.path().join(&candidate.node.id).join(variant.as_str());
            let plan: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.join("plan.json")).unwrap()).unwrap();
            let passes = plan["passes"].as_array().unwrap();
            let expected = match variant {
                Variant::OnePass => 1,
                Variant::TwoPass => 2,
                Variant::ThreePass => 3,
                Variant::Deferred => 4,
                Variant::Lowres => 2,
                // The G-buffer, the lattice, the samples, the upsampling.
                Variant::DeferredLowres => 4,
                Variant::Reference => unreachable!("not a rewrite"),
            };
            assert_eq!(passes.len(), expected);
            for pass in passes {
                assert!(out.join(pass["shader"].as_str().unwrap()).is_file());
            }
        }
    }
    assert!(stdout(&output).contains(&format!(
        "wrote {} variants",
        analysis.candidates.len() * Variant::ALL.len()
    )));
}

#[test]
fn other_languages_go_through_naga_back_ends() {
    for (emit, suffix) in [
        ("spv", "pass1.spv"),
        ("msl", "pass1.metal"),
        ("hlsl", "pass1.hlsl"),
        ("glsl", "pass1.frag.glsl"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let output = shadecache([
            "rewrite".as_ref(),
            "corpus/noise_marble.wgsl".as_ref(),
            "--node".as_ref(),
            "nb0c12cc4".as_ref(),
            "--variant".as_ref(),
            "three-pass".as_ref(),
            "--emit".as_ref(),
            emit.as_ref(),
            "--out".as_ref(),
            dir.path().as_os_str(),
        ] as [&std::ffi::OsStr; 10]);
        assert!(output.status.success(), "{emit}: {}", stderr(&output));
        let file = dir.path().join(suffix);
        assert!(
            std::fs::metadata(&file)
                .map(|m| m.len() > 100)
                .unwrap_or(false),
            "{emit}: no {suffix}"
        );
        // The plan names the files written.
        let plan: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("plan.json")).unwrap()).unwrap();
        for pass in plan["passes"]
            .as_array()
            .unwrap()
            .iter()
            .chain([&plan["classify"]])
        {
            let shader = pass["shader"].as_str().unwrap();
            assert!(
                dir.path().join(shader).is_file(),
                "{emit}: plan names {shader}"
            );
            for file in pass["stage_shaders"].as_array().into_iter().flatten() {
                assert!(
                    dir.path().join(file.as_str().unwrap()).is_file(),
                    "{emit}: {file}"
                );
            }
        }
    }
}

fn rewrite_fails(args: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let mut all: Vec<std::ffi::OsString> = vec!["rewrite".into()];
    all.extend(args.iter().map(Into::into));
    all.push("--out".into());
    all.push(dir.path().into());
    let output = shadecache(&all);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn unknown_node_id_is_an_error() {
    let err = rewrite_fails(&["corpus/noise_marble.wgsl", "--node", "n00000000"]);
    assert!(err.contains("unknown node id `n00000000`"), "{err}");
    assert!(
        err.contains("nb0c12cc4") || err.contains("candidates"),
        "{err}"
    );
}

#[test]
fn a_node_inside_a_loop_cannot_be_rewritten() {
    let (_, analysis) = load(Path::new("corpus/texture_loop.wgsl"));
    let in_loop = analysis
        .rejected
        .iter()
        .find(|r| r.reason == analysis::RejectReason::InLoop)
        .expect("texture_loop has nodes inside its loop");
    let err = rewrite_fails(&["corpus/texture_loop.wgsl", "--node", &in_loop.node.id]);
    assert!(err.contains("cannot be cached"), "{err}");
    assert!(err.contains("inside 1 loop"), "{err}");
    assert!(err.contains("corpus/texture_loop.wgsl:"), "{err}");
}

/// A payload that takes derivatives inside a loop cannot have them hoisted:
/// one-pass is refused with the reason, two- and three-pass are written.
#[test]
fn a_variant_refused_for_uniformity_says_why() {
    let source = "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;\n@group(0) @binding(1) var t: texture_2d<f32>;\n@group(0) @binding(2) var s: sampler;\nstruct V { @builtin(position) position: vec4<f32>, @location(0) uv: vec2<f32> }\n@vertex\nfn vs(@location(0) p: vec3<f32>, @location(2) uv: vec2<f32>) -> V {\n    return V(clip_from_world * vec4<f32>(p, 1.0), uv);\n}\n@fragment\nfn fs(in: V) -> @location(0) vec4<f32> {\n    var sum = vec4<f32>(0.0);\n    for (var i = 0; i < 4; i++) {\n        sum += textureSample(t, s, in.uv + vec2<f32>(f32(i) * 0.01, 0.0));\n    }\n    let blurred = sum * 0.25;\n    return blurred;\n}\n";
    let (_dir, path) = crate::util::temp_file("loop_sample.wgsl", source.as_bytes());
    let json = crate::util::analyze_json(&path);
    let id = json["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["text"] == "sum * 0.25")
        .expect("the blur is a candidate")["id"]
        .as_str()
        .unwrap()
        .to_string();
    let err = rewrite_fails(&[path.to_str().unwrap(), "--node", &id, "--variant", "all"]);
    assert!(err.contains("refused"), "{err}");
    assert!(err.contains(&id), "{err}");
    assert!(err.contains("one-pass"), "{err}");
    assert!(
        err.contains("implicit derivatives (textureSample) inside a loop"),
        "{err}"
    );
    assert!(!err.contains("two-pass:"), "two-pass is written: {err}");
    assert!(!err.contains("three-pass:"), "three-pass is written: {err}");
}

/// `--variant` takes a list as every other knob does: two of the three
/// variants are written, each in its own folder, the third not.
#[test]
fn variant_takes_a_list() {
    let dir = tempfile::tempdir().unwrap();
    let output = shadecache([
        "rewrite".as_ref(),
        "corpus/noise_marble.wgsl".as_ref(),
        "--node".as_ref(),
        "nb0c12cc4".as_ref(),
        "--variant".as_ref(),
        "two-pass,three-pass".as_ref(),
        "--out".as_ref(),
        dir.path().as_os_str(),
    ] as [&std::ffi::OsStr; 8]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(dir.path().join("two-pass/plan.json").is_file());
    assert!(dir.path().join("three-pass/plan.json").is_file());
    assert!(!dir.path().join("one-pass").exists());
}
