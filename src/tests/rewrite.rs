//! Rewrites checked across the corpus and every reconstruction: valid for
//! naga and Tint, built into wgpu pipelines, and only the passes that
//! reproject compute the previous position.

use super::util::{root, tint_validate};
use crate::analysis::{self, Analysis};
use crate::back::{self, Language};
use crate::front::{self, Shader};
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
                            if (variant == Variant::Lowres && reconstruction.packs_depth())
                                || (variant != Variant::Lowres && reconstruction.upsamples()) =>
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
                    if variant == Variant::Lowres {
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
    // reconstructions, both formats and every variant.
    // Lowres refuses the packed ones anyway (above).
    assert_eq!(refused, 2 * 2 * (Variant::ALL.len() - 1));
    for result in tint_validate(&files) {
        assert!(
            result.ok,
            "Tint rejects {}: {:#?}",
            result.file, result.messages
        );
    }
}
