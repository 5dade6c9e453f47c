//! Shaders composed from several modules (naga_oil imports, a separate
//! vertex module, a fragment-only module): rewritten, built, and at
//! Δn = 1 equal to the reference.

use super::gpu::write_wgsl;
use super::util::{root, tint_validate};
use crate::analysis::{self, Analysis};
use crate::front::compose::{Composition, ShaderDef};
use crate::front::{self, Shader};
use crate::rewrite::{self, Options, Variant};

const FRAGMENT: &str = "corpus/split/toon_material.wgsl";
const VERTEX: &str = "corpus/split/mesh.wgsl";
const COMPOSED: &str = "corpus/composed/ripple_material.wgsl";
const MODULES: &str = "corpus/composed/modules";

/// Without its vertex module, every variant of every node is still
/// emitted: fragment passes that take the previous clip position at the
/// first location the fragment stage leaves free, and a plan that says
/// what the host's vertex stage must output. Every pass validates under
/// naga (in the rewrite) and Tint.
#[test]
fn a_fragment_only_module_emits_fragment_passes_and_says_what_the_vertex_stage_must_output() {
    let shader = front::load(&root().join(FRAGMENT)).unwrap();
    let analysis = analysed(&shader);
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut emitted = 0;
    for candidate in analysis.candidates.iter().take(4) {
        // Lowres jitters the vertex stage, which a fragment-only module
        // does not have: refused, saying what to give.
        let refusal = rewrite::rewrite(
            &shader,
            &analysis,
            candidate,
            Variant::Lowres,
            &Options::default(),
        )
        .expect_err("lowres needs the vertex stage");
        assert!(
            refusal.reason.contains("--vertex FILE"),
            "{}",
            refusal.reason
        );
        // Deferred lowres shades its samples from the G-buffer, with no
        // jitter: it takes the module as the deferred variant does.
        for variant in Variant::CACHE.into_iter().chain([Variant::DeferredLowres]) {
            let rewritten =
                rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default())
                    .unwrap_or_else(|r| panic!("{} {variant}: {r}", candidate.node.id));
            let host = rewritten.plan.host_vertex.as_ref().expect("host_vertex");
            // The fragment stage reads locations 0, 1 and 2.
            assert_eq!(host.previous_clip_position_location, 3);
            assert!(
                host.requirement
                    .contains("@location(3) previous_clip_position"),
                "{}",
                host.requirement
            );
            // The deferred variant's screen-space passes bring their own
            // vertex stage, a triangle over the screen.
            let plan_passes = rewritten.plan.passes.iter().chain(&rewritten.plan.classify);
            for (pass, planned) in rewritten
                .passes
                .iter()
                .chain([&rewritten.classify])
                .zip(plan_passes)
            {
                let geometry = planned.draw == crate::plan::DrawKind::Geometry;
                assert!(
                    !geometry
                        || pass
                            .module
                            .entry_points
                            .iter()
                            .all(|ep| ep.stage == naga::ShaderStage::Fragment)
                );
            }
            assert!(rewritten
                .plan
                .passes
                .iter()
                .filter(|p| p.draw == crate::plan::DrawKind::Geometry)
                .all(|p| p.vertex_entry.is_empty()));
            files.extend(write_wgsl(
                dir.path(),
                &format!("{}-{variant}", candidate.node.id),
                &rewritten,
            ));
            emitted += 1;
        }
    }
    assert_eq!(emitted, 4 * (Variant::CACHE.len() + 1));
    for result in tint_validate(&files) {
        assert!(result.ok, "{}: {:?}", result.file, result.messages);
    }
}

/// `--vertex FILE` merges the vertex module on IR: one `view` uniform for
/// the binding both declare, the vertex stage instrumented as if it were
/// the module's own, and every pass builds a wgpu pipeline.
#[test]
fn a_separate_vertex_module_is_merged_on_ir() {
    let shader = front::load_with(
        &root().join(FRAGMENT),
        &Composition::default(),
        Some(&root().join(VERTEX)),
        None,
    )
    .unwrap();
    let module = &shader.module;
    let stages: Vec<_> = module
        .entry_points
        .iter()
        .map(|ep| (ep.name.as_str(), ep.stage))
        .collect();
    assert_eq!(
        stages,
        [
            ("fragment", naga::ShaderStage::Fragment),
            ("vertex", naga::ShaderStage::Vertex)
        ]
    );
    let views = module
        .global_variables
        .iter()
        .filter(|(_, g)| {
            g.binding
                == Some(naga::ResourceBinding {
                    group: 0,
                    binding: 0,
                })
        })
        .count();
    assert_eq!(views, 1);
    let analysis = analysed(&shader);
    let candidate = &analysis.candidates[0];
    for variant in Variant::CACHE {
        let rewritten =
            rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default())
                .unwrap_or_else(|r| panic!("{variant}: {r}"));
        assert!(rewritten.plan.host_vertex.is_none());
        assert!(rewritten
            .plan
            .passes
            .iter()
            .filter(|p| p.draw == crate::plan::DrawKind::Geometry)
            .all(|p| p.vertex_entry == "vertex"));
        // The previous position comes from twins of the vertex module's
        // uniforms.
        assert!(
            rewritten
                .plan
                .bindings
                .previous
                .iter()
                .any(|t| t.shadows.name == "mesh"),
            "{:?}",
            rewritten.plan.bindings.previous
        );
        super::gpu::build_pipelines(&rewritten, &variant.to_string());
    }
}

/// Δn = 1 recomputes every pixel: the composed module's variants give the
/// reference's image (differential test, on the default scene).
#[test]
fn a_composed_module_at_refresh_period_one_equals_the_reference() {
    let shader = front::load_with(
        &root().join(FRAGMENT),
        &Composition::default(),
        Some(&root().join(VERTEX)),
        None,
    )
    .unwrap();
    let analysis = analysed(&shader);
    let ids = analysis
        .candidates
        .iter()
        .take(2)
        .map(|c| c.node.id.clone())
        .collect();
    if let Some(report) = super::profile::assert_refresh_one_equals_reference(&shader, ids, 64) {
        assert_eq!(report.results.len(), 2 * Variant::CACHE.len());
    }
}

/// `#import`s resolve under the import path and `#ifdef`s follow the
/// defs: the lighting helper of another module is part of the costly
/// node, the fog exists only with `FOG`, and every variant of the top
/// nodes is emitted and valid under Tint.
#[test]
fn a_module_with_imports_is_composed_through_naga_oil() {
    let plain = front::load_with(&root().join(COMPOSED), &composition(&[]), None, None)
        .unwrap_or_else(|e| panic!("{}", e.render()));
    let fog = front::load_with(
        &root().join(COMPOSED),
        &composition(&[("FOG", ShaderDef::Bool(true))]),
        None,
        None,
    )
    .unwrap_or_else(|e| panic!("{}", e.render()));
    let plain_analysis = analysed(&plain);
    let fog_analysis = analysed(&fog);
    // Imported names read as module__item (naga writes them back with one
    // underscore).
    assert!(
        plain.file.text.contains("fn lighting_point_light("),
        "{}",
        plain.file.text
    );
    assert!(plain_analysis
        .candidates
        .iter()
        .any(|c| c.node.text.starts_with("lighting_point_light(")));
    let has_fog = |a: &Analysis| a.candidates.iter().any(|c| c.node.text.starts_with("mix("));
    assert!(!has_fog(&plain_analysis) && has_fog(&fog_analysis));

    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for candidate in fog_analysis.candidates.iter().take(3) {
        for variant in Variant::CACHE {
            let rewritten =
                rewrite::rewrite(&fog, &fog_analysis, candidate, variant, &Options::default())
                    .unwrap_or_else(|r| panic!("{} {variant}: {r}", candidate.node.id));
            files.extend(write_wgsl(
                dir.path(),
                &format!("{}-{variant}", candidate.node.id),
                &rewritten,
            ));
        }
    }
    for result in tint_validate(&files) {
        assert!(result.ok, "{}: {:?}", result.file, result.messages);
    }
}

fn analysed(shader: &Shader) -> Analysis {
    analysis::analyze(shader, &analysis::Options::default())
        .unwrap_or_else(|e| panic!("{}", e.render()))
}

fn composition(defs: &[(&str, ShaderDef)]) -> Composition {
    Composition {
        import_paths: vec![root().join(MODULES)],
        defs: defs.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        ..Composition::default()
    }
}

/// A variant says which defs its composition tests, and with what value,
/// in its plan: those of the shader (`FOG`) and of the modules it imports
/// (`SOFT_SPECULAR`), set or not; a def no source tests is not named. An
/// engine that composes per draw state draws through the passes only
/// where it composes with the same values.
#[test]
fn a_variant_says_which_defs_its_composition_tests() {
    use crate::plan::{ShaderDef as PlanDef, ShaderDefValue};
    let fog = front::load_with(
        &root().join(COMPOSED),
        &composition(&[
            ("FOG", ShaderDef::Bool(true)),
            ("UNTESTED", ShaderDef::UInt(3)),
        ]),
        None,
        None,
    )
    .unwrap_or_else(|e| panic!("{}", e.render()));
    let def = |name: &str, value| PlanDef {
        name: name.into(),
        value,
    };
    let expected = vec![
        def("FOG", ShaderDefValue::Set),
        def("SOFT_SPECULAR", ShaderDefValue::Unset),
    ];
    assert_eq!(fog.defs, expected);
    let analysis = analysed(&fog);
    let rewritten = rewrite::rewrite(
        &fog,
        &analysis,
        &analysis.candidates[0],
        Variant::OnePass,
        &Options::default(),
    )
    .unwrap_or_else(|r| panic!("{r}"));
    assert_eq!(rewritten.plan.shader_defs, expected);
    let json = serde_json::to_string(&rewritten.plan).unwrap();
    assert!(
        json.contains(r#""shader_defs":[{"name":"FOG","value":"set"},{"name":"SOFT_SPECULAR","value":"unset"}]"#),
        "{json}"
    );
}
