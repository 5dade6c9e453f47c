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

/// A build script names a package by its crate (`.crate_package`): found
/// among the dependencies of the package being built (here this test's
/// own, whose graph has `shadecache_plan`) as that crate's `src/` (a
/// material importing from it is looked for there), and a crate not among
/// them fails the build with the way out, before the shader is composed.
#[test]
fn a_build_script_finds_a_wesl_package_by_its_crate() {
    use crate::build::Build;
    let dir = tempfile::tempdir().unwrap();
    let job = |material: &Path, packages: &Path, package: &str| {
        Build::new()
            .shader(material)
            .import_path(packages)
            .crate_package(package)
            .def(GROUP.0, GROUP.1)
            .vertex_shader(root().join(MESH))
            .variant(Variant::TwoPass)
            .out_dir(dir.path())
            .quiet()
            .run()
    };
    let (material, packages) = (root().join(MATERIAL), root().join(PACKAGES));
    let outputs =
        job(&material, &packages, "shadecache_plan").unwrap_or_else(|e| panic!("{:?}", e.errors));
    assert!(!outputs.files.is_empty(), "{outputs:?}");

    // Importing from the crate's package reads its `src/`.
    let (_copy, wesl) = shadecache_test_support::edited_wesl("lava_material.wesl", |text| {
        text.replacen("import ", "import shadecache_plan::probe::x;\nimport ", 1)
            .replacen(
                "fbm(in.world_position * 3.0, 6)",
                "fbm(in.world_position * 3.0, 6) + x",
                1,
            )
    });
    let err = job(
        &wesl.join("lava_material.wesl"),
        &wesl.join("packages"),
        "shadecache_plan",
    )
    .unwrap_err();
    let said = err.errors[0].render();
    assert!(
        said.contains("crates/shadecache-plan/src/probe.wesl`"),
        "{said}"
    );

    let err = job(&material, &packages, "engine_sky").unwrap_err();
    assert_eq!(err.errors.len(), 1, "{:?}", err.errors);
    let said = err.errors[0].render();
    assert!(
        said.contains("no crate `engine_sky`") && said.contains("engine_sky=DIR"),
        "{said}"
    );
}

/// A WESL composition's plan names the features its modules' `@if`s test
/// and the `constants::` they read, with the values composed with: the
/// fog's feature in an imported module, off unless given, and the
/// material's bind group as its number.
#[test]
fn a_wesl_variant_says_which_defs_its_composition_tests() {
    use crate::plan::{ShaderDef as PlanDef, ShaderDefValue};
    let def = |name: &str, value| PlanDef {
        name: name.into(),
        value,
    };
    let plain = load(&[]);
    assert!(
        plain.defs.contains(&def("FOG", ShaderDefValue::Unset)),
        "{:?}",
        plain.defs
    );
    assert!(plain
        .defs
        .contains(&def("MATERIAL_BIND_GROUP", ShaderDefValue::Int(2))));
    let fog = load(&[("FOG", ShaderDef::Bool(true))]);
    assert!(fog.defs.contains(&def("FOG", ShaderDefValue::Set)));
    let analysis = analysed(&fog);
    let rewritten = rewrite::rewrite(
        &fog,
        &analysis,
        &analysis.candidates[0],
        Variant::OnePass,
        &Options::default(),
    )
    .unwrap_or_else(|r| panic!("{r}"));
    assert_eq!(rewritten.plan.shader_defs, fog.defs);
}

/// Narrowing (`Composition::narrow_defs`, what a build script and
/// `rewrite` ask for): of the defs the sources test, a plan keeps those
/// whose flip changes what the entry points run. `WARM` picks the colour
/// the fragment returns; `DEBUG_UNUSED` only adds a function nothing
/// calls, so it is tested but changes no code, and is left out. Without
/// narrowing both are listed.
#[test]
fn a_plan_keeps_only_the_defs_that_change_the_code() {
    use crate::plan::ShaderDefValue;
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("helpers.wesl"),
        "@if(WARM) const TINT = vec4<f32>(1.0, 0.5, 0.2, 1.0);\n\
         @if(!WARM) const TINT = vec4<f32>(0.2, 0.5, 1.0, 1.0);\n\
         @if(DEBUG_UNUSED) fn unused() -> f32 { return 1.0; }\n",
    )
    .unwrap();
    let top = dir.path().join("material.wesl");
    std::fs::write(
        &top,
        "import package::helpers::TINT;\n\
         @fragment fn fs() -> @location(0) vec4<f32> { return TINT; }\n",
    )
    .unwrap();
    let names = |narrow_defs| {
        let composition = Composition {
            narrow_defs,
            ..Composition::default()
        };
        let shader = front::load_with(&top, &composition, None, None)
            .unwrap_or_else(|e| panic!("{}", e.render()));
        let defs: Vec<(String, ShaderDefValue)> =
            shader.defs.into_iter().map(|d| (d.name, d.value)).collect();
        defs
    };
    assert_eq!(
        names(false),
        [
            ("DEBUG_UNUSED".to_string(), ShaderDefValue::Unset),
            ("WARM".to_string(), ShaderDefValue::Unset)
        ]
    );
    assert_eq!(names(true), [("WARM".to_string(), ShaderDefValue::Unset)]);
}
