//! Rewrites checked across the corpus and every reconstruction: valid for
//! naga and Tint, built into wgpu pipelines, and only the passes that
//! reproject compute the previous position.

use super::util::{root, tint_validate};
use crate::analysis::{self, Analysis};
use crate::back::{self, Language};
use crate::front::{self, Shader};
use crate::plan::{CompareFunction, TargetKind};
use crate::rewrite::{self, CacheFormat, Options, Rewritten, Variant};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Every corpus shader × every candidate × every variant
/// ([`super::corpus_rewrites`]), written as WGSL: each pass re-parses and
/// validates with naga from its text and Tint accepts it; refusals carry a
/// reason and are never internal errors.
#[test]
fn every_emitted_module_validates_with_naga_and_tint() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut refusals: BTreeMap<String, usize> = BTreeMap::new();
    for rewrite in super::corpus_rewrites::corpus_rewrites() {
        match &rewrite.outcome {
            Ok(emitted) => {
                let out = dir.path().join(rewrite.label());
                std::fs::create_dir_all(&out).unwrap();
                for (name, text) in emitted.wgsl.iter().filter(|(n, _)| n.ends_with(".wgsl")) {
                    let file = out.join(name);
                    std::fs::write(&file, text).unwrap();
                    files.push(file);
                }
            }
            Err(reason) => {
                assert!(
                    !reason.contains("internal error"),
                    "{}: {reason}",
                    rewrite.label()
                );
                // Group by the kind of refusal (the reason up to its first
                // parenthesis or comma).
                let kind = reason.split([',', '(']).next().unwrap_or_default();
                *refusals
                    .entry(format!("{}: {}", rewrite.variant, kind.trim()))
                    .or_default() += 1;
            }
        }
    }
    assert!(files.len() > 1000, "{} files", files.len());
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let reparsed = front::parse(crate::diagnostic::SourceFile::new(
            file.display().to_string(),
            text,
        ));
        if let Err(err) = reparsed {
            panic!("{} does not re-validate:\n{}", file.display(), err.render());
        }
    }
    let relative: Vec<PathBuf> = files.clone();
    for result in tint_validate(&relative) {
        assert!(
            result.ok,
            "Tint rejects {}: {:#?}",
            result.file, result.messages
        );
    }
    // The reasons the corpus is refused for, so a new kind shows in review.
    let expected = [
        "two-pass: the shader may discard after the node is computed",
        "three-pass: the shader may discard after the node is computed",
        // pbr_material_flags.wgsl samples its textures under material-flag
        // branches.
        "one-pass: one-pass computes the payload only on a miss",
    ];
    for kind in refusals.keys() {
        assert!(
            expected.contains(&kind.as_str()),
            "a new kind of refusal: {kind}"
        );
    }
    eprintln!(
        "emitted {} pass modules; refused: {refusals:#?}",
        files.len()
    );
}

/// Passes that do not look the fragment up in last frame's cache (two-pass
/// pass 2, three-pass passes 2 and 3) draw with the vertex stage as the
/// original has it: no previous clip position computed or interpolated,
/// no previous-frame twin bound. The passes that do reproject keep both.
/// Over every corpus rewrite.
#[test]
fn only_passes_that_reproject_compute_the_previous_position() {
    let mut plain = 0;
    for rewrite in super::corpus_rewrites::corpus_rewrites() {
        let Ok(emitted) = &rewrite.outcome else {
            continue;
        };
        let plan = &emitted.plan;
        if plan.host_vertex.is_some() {
            continue;
        }
        let twins: Vec<[u32; 2]> = plan
            .bindings
            .previous
            .iter()
            .map(|t| [t.group, t.binding])
            .collect();
        for (index, pass) in plan.passes.iter().enumerate() {
            let binds_twin = pass.bindings.iter().any(|b| twins.contains(b));
            if pass.draw == crate::plan::DrawKind::Fullscreen {
                // The deferred variant's screen-space passes read last
                // frame's position from the G-buffer, never a twin.
                assert!(
                    !binds_twin,
                    "{} {} binds a twin",
                    rewrite.label(),
                    pass.name
                );
                continue;
            }
            // Lowres's samples and its upsampling both read the history.
            let reprojects = index == 0 || plan.variant == Variant::Lowres;
            let text = emitted
                .wgsl
                .iter()
                .find(|(name, _)| *name == pass.shader)
                .map(|(_, text)| text.as_str())
                .unwrap_or_else(|| panic!("{}: no {}", rewrite.label(), pass.shader));
            let label = format!("{} {}", rewrite.label(), pass.name);
            assert_eq!(
                text.contains("previous_clip_position"),
                reprojects,
                "{label}"
            );
            assert!(reprojects || !binds_twin, "{label} binds a twin");
            plain += usize::from(!reprojects);
        }
    }
    assert!(plain > 500, "{plain} passes checked");
}

/// Loads a corpus shader under its path relative to the repository root,
/// so plans and snapshots do not depend on where the checkout is.
fn load(path: &Path) -> (Shader, Analysis) {
    let text = std::fs::read_to_string(root().join(path)).unwrap();
    let shader = front::parse(crate::diagnostic::SourceFile::new(
        path.display().to_string(),
        text,
    ))
    .unwrap_or_else(|e| panic!("{}", e.render()));
    let analysis = analysis::analyze(&shader, &analysis::Options::default()).unwrap();
    (shader, analysis)
}

/// Writes a variant's WGSL passes under `out`; returns their paths.
fn write_wgsl(out: &Path, rewritten: &Rewritten) -> Vec<PathBuf> {
    back::write_variant(out, rewritten, Language::Wgsl)
        .unwrap()
        .into_iter()
        .filter(|f| f.extension().is_some_and(|e| e == "wgsl"))
        .collect()
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

/// Every reconstruction, with both cache formats, is written for the
/// noise shader's nodes and passes naga, Tint and (on a GPU) wgpu's
/// pipeline creation. Nearest reads one texel of depth and payload; the
/// packed reconstructions never read last frame's depth buffer (the depth
/// is in the payload's fourth channel), and refuse a four-component
/// payload, which leaves no channel for it.
#[test]
fn every_reconstruction_validates_and_builds() {
    let (shader, analysis) = load(Path::new("corpus/noise_marble.wgsl"));
    let gpu = super::gpu::gpu();
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut refused = 0;
    for reconstruction in rewrite::Reconstruction::ALL {
        for cache_format in [CacheFormat::Rgba16float, CacheFormat::Rgba32float] {
            let options = Options {
                cache_format,
                ..Options::default()
            };
            for candidate in analysis.candidates.iter().take(5) {
                for variant in Variant::ALL {
                    // Lowres's reconstruction is its upsampling's: nearest,
                    // bilinear or its own three. Adaptive refresh at
                    // rgba32float (lowres's third pass, the cache variants'
                    // lookup in the passes that compute the payload).
                    let mut options = options.clone();
                    let rgba32 = cache_format == CacheFormat::Rgba32float;
                    options.set_adaptive(variant, rgba32).unwrap();
                    let rewritten = options
                        .set_reconstruction(variant, reconstruction)
                        .and_then(|()| {
                            rewrite::rewrite(&shader, &analysis, candidate, variant, &options)
                        });
                    let rewritten = match rewritten {
                        Ok(rewritten) => rewritten,
                        // Lowres refuses the packed read-backs; the
                        // cache variants refuse the upsamplings.
                        Err(refusal)
                            if (variant.upsamples() && reconstruction.packs_depth())
                                || (!variant.upsamples() && reconstruction.upsamples()) =>
                        {
                            assert!(
                                refusal.reason.contains("upsamples lowres's samples")
                                    || refusal.reason.contains("rebuilds the payload"),
                                "{}",
                                refusal.reason
                            );
                            continue;
                        }
                        Err(refusal) => {
                            assert!(
                                reconstruction.packs_depth() && candidate.components == 4,
                                "{} {variant} {}: {}",
                                candidate.node.id,
                                reconstruction.as_str(),
                                refusal.reason
                            );
                            assert!(refusal.reason.contains("fourth channel"));
                            refused += 1;
                            continue;
                        }
                    };
                    assert_eq!(rewritten.plan.cache.reconstruction, reconstruction);
                    if variant.upsamples() {
                        let out = dir
                            .path()
                            .join(reconstruction.as_str())
                            .join(cache_format.as_str())
                            .join(&candidate.node.id)
                            .join(variant.as_str());
                        files.extend(write_wgsl(&out, &rewritten));
                        continue;
                    }
                    // A three-pass cache may be widened to rgba32float.
                    let filterable = rewritten.plan.cache.format == CacheFormat::Rgba16float;
                    let lookup = match (reconstruction, filterable) {
                        (rewrite::Reconstruction::Bilinear, true) => "cache_lookup",
                        (rewrite::Reconstruction::Bilinear, false) => "cache_lookup_loads",
                        (rewrite::Reconstruction::Nearest, _) => "cache_lookup_nearest",
                        (rewrite::Reconstruction::BilinearPacked, true) => "cache_lookup_packed",
                        (rewrite::Reconstruction::BilinearPacked, false) => {
                            "cache_lookup_loads_packed"
                        }
                        (rewrite::Reconstruction::NearestPacked, _) => {
                            "cache_lookup_nearest_packed"
                        }
                        (r, _) => panic!("{variant} ran with lowres's {r}"),
                    };
                    // Pass 1 of every variant reprojects (the deferred
                    // variant's pass 2, after its G-buffer pass).
                    let lookup_pass = usize::from(variant == Variant::Deferred);
                    let (_, text) = &wgsl(&rewritten)[lookup_pass];
                    assert!(text.contains(&format!("fn {lookup}(")), "{text}");
                    // Only bilinear gathers last frame's depths (every
                    // bilinear footprint gathers its four ages).
                    if reconstruction != rewrite::Reconstruction::Bilinear {
                        assert!(
                            !text.contains("textureGather(cache_previous_depth"),
                            "{text}"
                        );
                    }
                    if reconstruction.packs_depth() {
                        assert!(!text.contains("cache_previous_depth"), "{text}");
                        assert!(text.contains("fn cache_pack("), "{text}");
                    }
                    let out = dir
                        .path()
                        .join(reconstruction.as_str())
                        .join(cache_format.as_str())
                        .join(&candidate.node.id)
                        .join(variant.as_str());
                    files.extend(write_wgsl(&out, &rewritten));
                    if let Some(gpu) = &gpu {
                        let sources = super::gpu::wgsl_sources(&rewritten);
                        crate::runtime::build_passes(
                            gpu,
                            &rewritten.plan,
                            |name| sources.get(name).cloned(),
                            crate::runtime::PipelineOptions::default(),
                        )
                        .unwrap_or_else(|err| {
                            panic!(
                                "{} {variant} {}: {err}",
                                candidate.node.id,
                                reconstruction.as_str()
                            )
                        });
                    }
                }
            }
        }
    }
    // `vec4<f32>(color, 1.0)` is among the first five, for both packed
    // reconstructions, both formats and every cache variant. The
    // upsampling variants refuse the packed ones anyway (above).
    assert_eq!(refused, 2 * 2 * Variant::CACHE.len());
    for result in tint_validate(&files) {
        assert!(
            result.ok,
            "Tint rejects {}: {:#?}",
            result.file, result.messages
        );
    }
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
    let reference = crate::rewrite::plan::reference(
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

#[test]
fn uniformity_check_catches_derivatives_in_a_branch() {
    let source = "@group(0) @binding(0) var t: texture_2d<f32>;\n@group(0) @binding(1) var s: sampler;\n@fragment\nfn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {\n    var c = vec4<f32>(0.0);\n    if (uv.x > 0.5) {\n        c = textureSample(t, s, uv);\n    }\n    return c;\n}\n";
    let shader = front::parse(crate::diagnostic::SourceFile::new("branch.wgsl", source)).unwrap();
    let violation = rewrite::uniformity::check(&shader.module, &shader.info).unwrap_err();
    assert!(violation.what.contains("textureSample"), "{violation}");
    // The same sample before the branch is fine.
    let fine = source.replace(
        "    var c = vec4<f32>(0.0);\n    if (uv.x > 0.5) {\n        c = textureSample(t, s, uv);\n    }",
        "    var c = textureSample(t, s, uv);\n    if (uv.x > 0.5) {\n        c = c * 2.0;\n    }",
    );
    let shader = front::parse(crate::diagnostic::SourceFile::new("fine.wgsl", fine)).unwrap();
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
    let (shader, analysis) = super::util::analyzed("f16.wgsl", source);
    let wave = super::util::candidate(&analysis, "sin(in.uv.x * 30.0) * 0.5 + 0.5");
    let growth = super::util::candidate(&analysis, "exp(in.uv.y * 40.0)");
    assert!(wave.fits_f16);
    assert_eq!(wave.range, [Some(0.0), Some(1.0)]);
    assert!(!growth.fits_f16);

    let options = crate::rewrite::Options::default();
    assert_eq!(options.cache_format.as_str(), "rgba16float");
    let plan = |candidate, variant| {
        crate::rewrite::rewrite(&shader, &analysis, candidate, variant, &options)
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

/// A shader that fills a local struct member by member and hands a
/// pointer to it to a helper, in a loop (as Bevy's `apply_pbr_lighting`
/// fills `lighting_input` and calls `point_light(id, &lighting_input)`).
const LIGHTING_THROUGH_A_POINTER: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
}
@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (frame.world_from_local * vec4<f32>(normal, 0.0)).xyz;
    return out;
}

struct LightingInput {
    n: vec3<f32>,
    v: vec3<f32>,
    roughness: f32,
    diffuse: vec3<f32>,
}

fn light(input: ptr<function, LightingInput>, i: u32) -> vec3<f32> {
    let angle = f32(i) * 0.7;
    let l = normalize(vec3<f32>(cos(angle), 0.8, sin(angle)));
    let h = normalize(l + (*input).v);
    let shininess = 2.0 + 64.0 * (1.0 - (*input).roughness);
    let specular = pow(max(dot((*input).n, h), 0.0), shininess);
    return (*input).diffuse * max(dot((*input).n, l), 0.0) + vec3<f32>(specular);
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    var input: LightingInput;
    input.n = normalize(in.world_normal);
    input.v = normalize(frame.camera_position - in.world_position);
    input.roughness = 0.35;
    input.diffuse = vec3<f32>(0.6, 0.4, 0.2);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < 6u; i++) {
        sum += light(&input, i);
    }
    return vec4<f32>(sum * 0.3, 1.0);
}
"#;

/// Hard case: the payload calls a helper that reads a local through a
/// pointer. The payload slice keeps the stores into that local (its
/// members), which the helper reads; without them the payload pass drew
/// the helper reading an unwritten struct, a valid shader that lit
/// nothing (found on Bevy's `StandardMaterial`, whose point lights went
/// dark in the cache). At Δn = 1 every variant equals the reference.
#[test]
fn payload_keeps_what_a_call_reads_through_a_pointer() {
    let (shader, analysis) = super::util::analyzed("pointer.wgsl", LIGHTING_THROUGH_A_POINTER);
    let node = super::util::candidate(&analysis, "sum");
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        node,
        Variant::TwoPass,
        &Options::default(),
    )
    .unwrap_or_else(|r| panic!("{r}"));
    // The payload function, in the pass that computes it.
    let payloads: Vec<String> = rewritten
        .passes
        .iter()
        .map(|pass| back::wgsl_text(&pass.module, &pass.info).unwrap())
        .filter_map(|text| {
            let start = text.find("fn fs_main_payload(")?;
            let body = &text[start..];
            let end = body[1..].find("\nfn ").map_or(body.len(), |i| i + 1);
            Some(body[..end].to_string())
        })
        .collect();
    assert!(!payloads.is_empty());
    for payload in &payloads {
        for member in [".n = ", ".v = ", ".roughness = ", ".diffuse = "] {
            assert!(
                payload.contains(member),
                "the payload lost `{member}`:\n{payload}"
            );
        }
    }
    super::profile::assert_refresh_one_equals_reference(&shader, vec![node.node.id.clone()], 48);
}
