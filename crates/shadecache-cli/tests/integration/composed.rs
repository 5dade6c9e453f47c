//! Shaders split and composed as engines write them: a fragment-only
//! material module and the mesh pipeline's vertex module
//! (`corpus/split/`), and a material composed from naga_oil modules
//! (`corpus/composed/`).

use std::ffi::OsStr;

use shadecache::analysis::{self, Analysis};
use shadecache::front::compose::{Composition, ShaderDef};
use shadecache::front::{self, Shader};
use shadecache::rewrite::{self, Options, Variant};

use crate::gpu::write_wgsl;
use crate::util::{root, shadecache, stderr, temp_file, tint_validate};

const FRAGMENT: &str = "corpus/split/toon_material.wgsl";
const VERTEX: &str = "corpus/split/mesh.wgsl";

fn analysed(shader: &Shader) -> Analysis {
    analysis::analyze(shader, &analysis::Options::default())
        .unwrap_or_else(|e| panic!("{}", e.render()))
}

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
        for variant in Variant::CACHE {
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
                let geometry = planned.draw == shadecache::plan::DrawKind::Geometry;
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
                .filter(|p| p.draw == shadecache::plan::DrawKind::Geometry)
                .all(|p| p.vertex_entry.is_empty()));
            files.extend(write_wgsl(
                dir.path(),
                &format!("{}-{variant}", candidate.node.id),
                &rewritten,
            ));
            emitted += 1;
        }
    }
    assert_eq!(emitted, 4 * Variant::CACHE.len());
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
            .filter(|p| p.draw == shadecache::plan::DrawKind::Geometry)
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
        crate::gpu::build_pipelines(&rewritten, &variant.to_string());
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
    if let Some(report) = crate::profile::assert_refresh_one_equals_reference(&shader, ids, 64) {
        assert_eq!(report.results.len(), 2 * Variant::CACHE.len());
    }
}

#[test]
fn vertex_naming_a_module_without_a_vertex_entry_point_is_an_error() {
    let output = shadecache([
        "rewrite",
        FRAGMENT,
        "--vertex",
        FRAGMENT,
        "--all-nodes",
        "--out",
        "/nonexistent/never-written",
    ]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains("has no vertex entry point: --vertex takes the module"),
        "{err}"
    );
    assert!(err.contains("toon_material.wgsl:1:1"), "{err}");
}

#[test]
fn a_binding_the_two_modules_declare_differently_is_an_error() {
    let vertex = std::fs::read_to_string(root().join(VERTEX))
        .unwrap()
        .replace(
            "@group(0) @binding(0) var<uniform> view: View;",
            "@group(0) @binding(0) var<uniform> view: mat4x4<f32>;",
        )
        .replace("view.clip_from_world", "view");
    let (_dir, path) = temp_file("mesh.wgsl", vertex.as_bytes());
    let output = shadecache([
        "rewrite".as_ref(),
        FRAGMENT.as_ref(),
        "--vertex".as_ref(),
        path.as_os_str(),
        "--all-nodes".as_ref(),
        "--out".as_ref(),
        "/nonexistent/never-written".as_ref(),
    ] as [&OsStr; 7]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(err.contains("group 0 binding 0 is `view` in the vertex module and `view` in the fragment module, of different types"), "{err}");
    assert!(err.contains("mesh.wgsl:1:1"), "{err}");
}

/// A fragment-only module profiled with no `--vertex` file is drawn by a
/// vertex stage made from its inputs' names and types (the world position,
/// the normal and the uv from the mesh), said in the report's filled-in
/// inputs; it used to be refused. `--vertex` still gives the real one.
#[test]
fn fragment_only_module_gets_a_generated_vertex_stage() {
    if crate::gpu::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], dir: &str| {
        let report = out.path().join(dir);
        let mut args = vec![
            "profile",
            FRAGMENT,
            "--quiet",
            "--nodes",
            "top:1",
            "--variant",
            "one-pass",
            "--frames",
            "2",
            "--size",
            "48x48",
            "--out",
            report.to_str().unwrap(),
        ];
        args.extend(extra);
        let output = shadecache(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(report.join("report.json")).unwrap()).unwrap();
        json
    };
    let generated = run(&[], "generated");
    let defaulted: Vec<&str> = generated["defaulted"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_str().unwrap())
        .collect();
    for line in [
        "vertex stage generated: @location(0) `world_position` = the world position",
        "vertex stage generated: @location(1) `world_normal` = the mesh's normal in world space",
        "vertex stage generated: @location(2) `uv` = the mesh's texture coordinate",
    ] {
        assert!(defaulted.contains(&line), "{defaulted:?}");
    }
    let check = &generated["reference_check"];
    assert!(check["problems"].as_array().unwrap().is_empty(), "{check}");
    // Camera and object motion reach it: the generated stage reads the
    // simulated matrices.
    assert!(check["changed_share"].as_f64().unwrap() > 0.05, "{check}");

    // The joined module is valid WGSL to Tint as well as naga.
    let shader = front::load(&root().join(FRAGMENT)).unwrap();
    let fragment = analysis::fragment_entry(&shader, None).unwrap();
    let (joined, _) = front::vertex::generate(&shader, fragment).unwrap();
    let text = shadecache::back::wgsl_text(&joined.module, &joined.info).unwrap();
    let (_dir, path) = temp_file("joined.wgsl", text.as_bytes());
    for result in tint_validate(&[path]) {
        assert!(result.ok, "{result:?}\n{text}");
    }

    let given = run(&["--vertex", VERTEX], "given");
    assert!(given["defaulted"]
        .as_array()
        .unwrap()
        .iter()
        .all(|d| !d.as_str().unwrap().starts_with("vertex stage generated")));
}

const COMPOSED: &str = "corpus/composed/ripple_material.wgsl";
const MODULES: &str = "corpus/composed/modules";

fn composition(defs: &[(&str, ShaderDef)]) -> Composition {
    Composition {
        import_paths: vec![root().join(MODULES)],
        defs: defs.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        ..Composition::default()
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

#[test]
fn an_import_that_does_not_resolve_is_an_error_at_the_import() {
    let output = shadecache(["analyze", COMPOSED]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains("`#import engine::view` does not resolve"),
        "{err}"
    );
    assert!(err.contains("ripple_material.wgsl:6:9"), "{err}");
}

#[test]
fn an_error_in_an_imported_module_points_into_it() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["view.wgsl", "lighting.wgsl"] {
        let text = std::fs::read_to_string(root().join(MODULES).join(name)).unwrap();
        let text = text.replace(
            "let distance = length(to_light);",
            "let distance = length(to_light;",
        );
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let output = shadecache([
        "analyze".as_ref(),
        COMPOSED.as_ref(),
        "--import-path".as_ref(),
        dir.path().as_os_str(),
    ] as [&OsStr; 4]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    let line = std::fs::read_to_string(dir.path().join("lighting.wgsl"))
        .unwrap()
        .lines()
        .position(|l| l.contains("length(to_light;"))
        .unwrap()
        + 1;
    assert!(err.contains(&format!("lighting.wgsl:{line}:")), "{err}");
}
