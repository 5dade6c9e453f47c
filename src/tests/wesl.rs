//! A WESL-composed material, analysed, rewritten and built.

use super::gpu::{build_pipelines, write_wgsl};
use super::util::{root, tint_validate};
use crate::analysis::{self, Analysis};
use crate::front::compose::{Composition, ShaderDef};
use crate::front::{self, Shader};
use crate::rewrite::{self, Options, Variant};
use std::path::Path;

const MATERIAL: &str = "corpus/wesl/lava_material.wesl";
const PACKAGES: &str = "corpus/wesl/packages";
/// The engine's vertex stage: the module `engine_pbr::render::mesh`,
/// whose `package::render::…` imports resolve only when its package is
/// known to be the folder above `render/` (as Bevy's crates lay out
/// theirs).
const MESH: &str = "corpus/wesl/packages/engine_pbr/render/mesh.wesl";
/// The material's bind group, which it reads as `constants::`.
const GROUP: (&str, ShaderDef) = ("MATERIAL_BIND_GROUP", ShaderDef::Int(2));

/// The material composes through wesl with its engine's vertex module:
/// imported names read `module__item` (naga writes them with one
/// underscore), `@if(FOG)` follows `--def FOG`, `constants::` takes a
/// numeric def, the object-space crust is a candidate, and every variant
/// of the top nodes and of the crust is emitted valid under naga (in the
/// rewrite) and Tint and builds a wgpu render pipeline.
#[test]
fn wesl_composed_material_analyses_and_rewrites() {
    let plain = load(&[]);
    let fog = load(&[("FOG", ShaderDef::Bool(true))]);
    assert!(
        plain
            .file
            .text
            .contains("fn pbr_functions_apply_pbr_lighting("),
        "{}",
        plain.file.text
    );
    assert!(plain.file.text.contains("fn noise_fbm("));
    assert!(plain.module.entry_points.iter().any(|e| e.name == "vertex"));
    let mixes_fog = |s: &Shader| s.file.text.contains("vec3<f32>(0.6f, 0.65f, 0.7f)");
    assert!(!mixes_fog(&plain) && mixes_fog(&fog));
    assert!(
        plain
            .file
            .text
            .contains("@group(2) @binding(1) \nvar<uniform> material"),
        "{}",
        plain.file.text
    );

    let analysis = analysed(&fog);
    let crust = analysis
        .candidates
        .iter()
        .find(|c| {
            c.node
                .text
                .starts_with("noise_fbm((in.world_position * 3f), 6i)")
        })
        .expect("the crust's six octaves are a candidate");
    let mut nodes: Vec<_> = analysis.candidates.iter().take(3).collect();
    nodes.push(crust);

    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    let mut pipelines = 0;
    for candidate in nodes {
        for variant in Variant::CACHE {
            let rewritten =
                rewrite::rewrite(&fog, &analysis, candidate, variant, &Options::default())
                    .unwrap_or_else(|r| panic!("{} {variant}: {r}", candidate.node.id));
            let what = format!("{} {variant}", candidate.node.id);
            pipelines += build_pipelines(&rewritten, &what).unwrap_or(0);
            files.extend(write_wgsl(
                dir.path(),
                &format!("{}-{variant}", candidate.node.id),
                &rewritten,
            ));
        }
    }
    assert!(files.len() >= 4 * Variant::CACHE.len());
    eprintln!("{} passes, {pipelines} pipelines", files.len());
    for result in tint_validate(&files) {
        assert!(result.ok, "{}: {:?}", result.file, result.messages);
    }
}

fn composition(root: &Path, defs: &[(&str, ShaderDef)]) -> Composition {
    Composition {
        import_paths: vec![root.join(PACKAGES)],
        defs: std::iter::once(&GROUP)
            .chain(defs)
            .map(|(n, v)| (n.to_string(), *v))
            .collect(),
        ..Composition::default()
    }
}

fn load(defs: &[(&str, ShaderDef)]) -> Shader {
    front::load_with(
        &root().join(MATERIAL),
        &composition(&root(), defs),
        Some(&root().join(MESH)),
        None,
    )
    .unwrap_or_else(|e| panic!("{}", e.render()))
}

fn analysed(shader: &Shader) -> Analysis {
    analysis::analyze(shader, &analysis::Options::default())
        .unwrap_or_else(|e| panic!("{}", e.render()))
}
