//! `shadecache rewrite` and the variants it emits.

use std::path::{Path, PathBuf};

use shadecache::analysis::{self, Analysis};
use shadecache::back::{self, Language};
use shadecache::front::{self, Shader};
use shadecache::plan::{CompareFunction, TargetKind};
use shadecache::rewrite::{self, CacheFormat, Options, Rewritten, Variant};

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

fn wgsl(rewritten: &Rewritten) -> Vec<(String, String)> {
    rewritten
        .passes
        .iter()
        .map(|pass| {
            let out = back::write(&pass.module, &pass.info, Language::Wgsl).unwrap();
            (
                pass.name.clone(),
                String::from_utf8(out[0].bytes.clone()).unwrap(),
            )
        })
        .collect()
}

/// A snapshot case, one file in `tests/snapshot-cases/`: a shader, its
/// nodes, the variants (all when absent) and the back ends (WGSL when
/// absent) whose output is kept, so a change in what is emitted shows in
/// review. A new case is a new file.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SnapshotCase {
    shader: String,
    nodes: Vec<String>,
    #[serde(default)]
    variants: Vec<Variant>,
    #[serde(default)]
    languages: Vec<String>,
}

/// Every pass (the classification pass included) and the plan of every
/// case's nodes × variants × back ends. The modules are compacted before
/// writing, so handle numbering does not churn. Snapshot names are
/// `shader__node__variant__pass` for WGSL and end in the back end's file
/// suffix for the others.
#[test]
fn snapshots_of_emitted_passes() {
    let dir = root().join("tests/snapshot-cases");
    let mut cases: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    cases.sort();
    assert!(!cases.is_empty());
    for case_path in cases {
        let case: SnapshotCase = toml::from_str(&std::fs::read_to_string(&case_path).unwrap())
            .unwrap_or_else(|e| panic!("{}: {e}", case_path.display()));
        let variants = if case.variants.is_empty() {
            Variant::ALL.to_vec()
        } else {
            case.variants.clone()
        };
        let languages: Vec<Language> = if case.languages.is_empty() {
            vec![Language::Wgsl]
        } else {
            case.languages
                .iter()
                .map(|l| match l.as_str() {
                    "wgsl" => Language::Wgsl,
                    "msl" => Language::Msl,
                    "hlsl" => Language::Hlsl,
                    "glsl" => Language::Glsl,
                    other => panic!("{}: no text back end `{other}`", case_path.display()),
                })
                .collect()
        };
        let (shader, analysis) = load(Path::new(&case.shader));
        let stem = Path::new(&case.shader)
            .file_stem()
            .unwrap()
            .to_str()
            .unwrap();
        for node in &case.nodes {
            let candidate = analysis
                .candidate(node)
                .unwrap_or_else(|| panic!("{}: `{node}` is no candidate", case_path.display()));
            for &variant in &variants {
                let rewritten =
                    rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default())
                        .unwrap_or_else(|r| panic!("{stem} {node} {variant}: {r}"));
                for &language in &languages {
                    for (file, bytes) in back::render_variant(&rewritten, language).unwrap() {
                        let text = String::from_utf8(bytes).unwrap();
                        let name = match language {
                            Language::Wgsl => file.trim_end_matches(".wgsl").to_string(),
                            _ => file,
                        };
                        insta::assert_snapshot!(format!("{stem}__{node}__{variant}__{name}"), text);
                    }
                }
                if languages.contains(&Language::Wgsl) {
                    let plan = serde_json::to_string_pretty(&rewritten.plan).unwrap();
                    insta::assert_snapshot!(format!("{stem}__{node}__{variant}__plan"), plan);
                }
            }
        }
    }
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
fn plans_describe_the_passes() {
    let (shader, analysis) = load(Path::new("corpus/noise_marble.wgsl"));
    let candidate = analysis.candidate("nb0c12cc4").unwrap();
    let plan = |variant| {
        rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default())
            .unwrap()
            .plan
    };
    let three = plan(Variant::ThreePass);
    let depth: Vec<(CompareFunction, bool)> = three
        .passes
        .iter()
        .map(|p| (p.depth.compare, p.depth.write))
        .collect();
    assert_eq!(
        depth,
        [
            (CompareFunction::Less, true),
            (CompareFunction::Less, true),
            (CompareFunction::Equal, false)
        ]
    );
    assert_eq!(
        three.passes.iter().map(|p| p.discards).collect::<Vec<_>>(),
        [true, false, false]
    );
    assert_eq!(three.passes[0].color_targets[0].target, TargetKind::Cache);
    assert_eq!(three.passes[2].color_targets[0].target, TargetKind::Color);
    // The uniform the vertex stage reads has a previous-frame twin.
    assert_eq!(three.bindings.previous.len(), 1);
    assert_eq!(three.bindings.previous[0].shadows.name, "frame");
    assert_eq!(three.bindings.previous[0].group, 1);
    let one = plan(Variant::OnePass);
    let targets: Vec<TargetKind> = one.passes[0]
        .color_targets
        .iter()
        .map(|t| t.target)
        .collect();
    assert_eq!(
        targets,
        [TargetKind::Color, TargetKind::Cache, TargetKind::Age]
    );
    assert_eq!(one.passes[0].color_targets[2].format.as_str(), "r16float");
    assert_eq!(one.vertex_layout.len(), 2);
    assert_eq!(one.vertex_layout[0].format.as_str(), "float32x3");
    assert_eq!(three.clear.depth, 1.0);

    // Reversed Z: nearer is `greater`, the far plane (and the clear) is 0,
    // which the host passes as CacheParams' far_depth.
    let reversed = rewrite::rewrite(
        &shader,
        &analysis,
        candidate,
        Variant::ThreePass,
        &Options {
            depth: rewrite::DepthConvention::Reversed,
            ..Options::default()
        },
    )
    .unwrap()
    .plan;
    let depth: Vec<CompareFunction> = reversed.passes.iter().map(|p| p.depth.compare).collect();
    assert_eq!(
        depth,
        [
            CompareFunction::Greater,
            CompareFunction::Greater,
            CompareFunction::Equal
        ]
    );
    assert_eq!(reversed.clear.depth, 0.0);
    let reference = shadecache::rewrite::plan::reference(
        &shader,
        &analysis,
        &Options {
            depth: rewrite::DepthConvention::Reversed,
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!(reference.passes[0].depth.compare, CompareFunction::Greater);
    assert_eq!(reference.clear.depth, 0.0);
    let far = three
        .cache
        .params
        .iter()
        .find(|f| f.name == "far_depth")
        .unwrap();
    assert_eq!(far.offset, 32);
}

#[test]
fn every_emitted_vertex_position_is_invariant() {
    let (shader, analysis) = load(Path::new("corpus/position_direct.wgsl"));
    let candidate = &analysis.candidates[0];
    for variant in Variant::ALL {
        let rewritten =
            rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default()).unwrap();
        for (pass, text) in wgsl(&rewritten) {
            // Every position, vertex output and fragment input alike.
            let positions = text.matches("@builtin(position)").count();
            let invariant = text.matches("@builtin(position) @invariant").count();
            assert!(positions >= 2, "{variant} {pass}:\n{text}");
            assert_eq!(positions, invariant, "{variant} {pass}:\n{text}");
        }
    }
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

#[test]
fn one_pass_hoists_derivatives_out_of_the_miss_branch() {
    // `textureSample` is in this node's slice: one-pass computes its
    // gradients before the branch and samples with textureSampleGrad.
    let (shader, analysis) = load(Path::new("corpus/implicit_derivative.wgsl"));
    let candidate = analysis.candidate("n9be52d42").unwrap();
    assert!(candidate.derivatives);
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        candidate,
        Variant::OnePass,
        &Options::default(),
    )
    .unwrap();
    let (_, text) = &wgsl(&rewritten)[0];
    assert!(text.contains("fn fs_main_gradients("), "{text}");
    assert!(text.contains("dpdx("), "{text}");
    assert!(text.contains("textureSampleGrad(albedo_texture"), "{text}");
    assert!(!text.contains("textureSample(albedo_texture"), "{text}");
    // The gradients are taken before the branch, the payload inside it.
    let gradients = text.find("= fs_main_gradients(").unwrap();
    let branch = text.find("if reuse").unwrap();
    let payload = text.find("= fs_main_payload(").unwrap();
    assert!(gradients < branch && branch < payload, "{text}");
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

#[test]
fn uniformity_check_catches_derivatives_in_a_branch() {
    let source = "@group(0) @binding(0) var t: texture_2d<f32>;\n@group(0) @binding(1) var s: sampler;\n@fragment\nfn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {\n    var c = vec4<f32>(0.0);\n    if (uv.x > 0.5) {\n        c = textureSample(t, s, uv);\n    }\n    return c;\n}\n";
    let shader = front::parse(shadecache::diagnostic::SourceFile::new(
        "branch.wgsl",
        source,
    ))
    .unwrap();
    let violation = rewrite::uniformity::check(&shader.module, &shader.info).unwrap_err();
    assert!(violation.what.contains("textureSample"), "{violation}");
    // The same sample before the branch is fine.
    let fine = source.replace(
        "    var c = vec4<f32>(0.0);\n    if (uv.x > 0.5) {\n        c = textureSample(t, s, uv);\n    }",
        "    var c = textureSample(t, s, uv);\n    if (uv.x > 0.5) {\n        c = c * 2.0;\n    }",
    );
    let shader = front::parse(shadecache::diagnostic::SourceFile::new("fine.wgsl", fine)).unwrap();
    rewrite::uniformity::check(&shader.module, &shader.info).unwrap();
}

/// The previous position is recomputed wherever the position comes from:
/// through helper functions (twinned too) and from an instance storage
/// buffer (twinned like a uniform).
#[test]
fn previous_position_follows_helpers_and_storage_buffers() {
    let (shader, analysis) = load(Path::new("corpus/helpers_nested.wgsl"));
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        &analysis.candidates[0],
        Variant::OnePass,
        &Options::default(),
    )
    .unwrap();
    let (_, text) = &wgsl(&rewritten)[0];
    assert!(text.contains("fn to_clip_previous("), "{text}");
    assert!(text.contains("fn to_world_previous("), "{text}");
    assert!(text.contains("previous_frame.clip_from_world"), "{text}");

    let (shader, analysis) = load(Path::new("corpus/instanced_storage.wgsl"));
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        &analysis.candidates[0],
        Variant::ThreePass,
        &Options::default(),
    )
    .unwrap();
    let shadowed: Vec<&str> = rewritten
        .plan
        .bindings
        .previous
        .iter()
        .map(|twin| twin.shadows.name.as_str())
        .collect();
    assert_eq!(shadowed, ["frame", "instances"]);
    let (_, text) = &wgsl(&rewritten)[0];
    assert!(text.contains("var<storage> previous_instances"), "{text}");
}

/// f16 overflow, detected statically: the analysis bounds each candidate
/// with interval arithmetic, and a three-pass rewrite of a node it cannot
/// bound below 65504 keeps its cache in rgba32float, saying why in the
/// plan. One- and two-pass keep rgba16float (they recompute an overflowing
/// payload: `f16_overflow_is_recomputed_not_reused`).
#[test]
fn f16_overflow_flagged_nodes_widen_the_three_pass_cache() {
    let source = "
struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs(@location(0) p: vec3<f32>) -> VertexOutput {
    return VertexOutput(vec4<f32>(p, 1.0), p.xy);
}

@fragment
fn fs(in: VertexOutput) -> @location(0) vec4<f32> {
    let wave = sin(in.uv.x * 30.0) * 0.5 + 0.5;
    let growth = exp(in.uv.y * 40.0);
    return vec4<f32>(wave, fract(growth), 0.0, 1.0);
}
";
    let (shader, analysis) = crate::util::analyzed("f16.wgsl", source);
    let wave = crate::util::candidate(&analysis, "sin(in.uv.x * 30.0) * 0.5 + 0.5");
    let growth = crate::util::candidate(&analysis, "exp(in.uv.y * 40.0)");
    assert!(wave.fits_f16);
    assert_eq!(wave.range, [Some(0.0), Some(1.0)]);
    assert!(!growth.fits_f16);

    let options = shadecache::rewrite::Options::default();
    assert_eq!(options.cache_format.as_str(), "rgba16float");
    let plan = |candidate, variant| {
        shadecache::rewrite::rewrite(&shader, &analysis, candidate, variant, &options)
            .unwrap()
            .plan
    };
    let widened = plan(growth, Variant::ThreePass);
    assert_eq!(widened.cache.format, CacheFormat::Rgba32float);
    assert!(widened
        .cache
        .format_note
        .as_deref()
        .unwrap()
        .contains("65504"));
    assert!(widened
        .passes
        .iter()
        .flat_map(|p| &p.color_targets)
        .filter(|t| t.target == TargetKind::Cache)
        .all(|t| t.format.as_str() == "rgba32float"));
    for (candidate, variant) in [
        (wave, Variant::ThreePass),
        (growth, Variant::TwoPass),
        (growth, Variant::OnePass),
    ] {
        let kept = plan(candidate, variant);
        assert_eq!(kept.cache.format, CacheFormat::Rgba16float, "{variant}");
        assert_eq!(kept.cache.format_note, None);
    }
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
