//! Shaders as engines write them: results carried in local variables,
//! costly work under material-flag branches and per-pixel branches, loop
//! results, several entry points in one module.

use crate::analysis::{Analysis, Candidate};
use crate::front::Shader;
use crate::profile::{Nodes, Options as ProfileOptions};
use crate::rewrite::{self, CacheFormat, CacheRead, Options, Variant};

use super::gpu::wgsl_sources;
use super::profile::run_shader;
use super::util::{analyzed, candidate, root};

fn corpus_shader(name: &str) -> (Shader, Analysis) {
    let path = root().join("corpus").join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    analyzed(name, &text)
}

/// The candidates whose text is `text`, in source order.
fn all_named<'a>(analysis: &'a Analysis, text: &str) -> Vec<&'a Candidate> {
    let mut found: Vec<&Candidate> = analysis
        .candidates
        .iter()
        .filter(|c| c.node.text == text)
        .collect();
    found.sort_by_key(|c| c.node.range.start);
    found
}

/// The WGSL of one pass file (`pass2`, `classify`...).
fn wgsl_of(rewritten: &rewrite::Rewritten, pass: &str) -> String {
    wgsl_sources(rewritten)
        .remove(&format!("{pass}.wgsl"))
        .unwrap_or_else(|| panic!("no {pass}.wgsl"))
}

/// A load of a local sees only the stores that reach it: `output_color`
/// read into the PBR input is the base colour times the texture, not the
/// lit colour stored into the same variable further down.
#[test]
fn values_through_locals_follow_reaching_definitions() {
    let (_, analysis) = corpus_shader("pbr_material_flags.wgsl");
    let loads = all_named(&analysis, "output_color");
    assert_eq!(loads.len(), 2, "{loads:#?}");
    let (early, returned) = (loads[0], loads[1]);
    assert!(early.ratio < 0.05, "early load P/T {}", early.ratio);
    assert!(
        returned.ratio > 0.95,
        "returned load P/T {}",
        returned.ratio
    );

    // A variable assigned in both arms of a branch: its value after the
    // branch needs both arms.
    let (_, terrain) = corpus_shader("terrain_slope_branch.wgsl");
    let albedo = candidate(&terrain, "albedo");
    let grass = candidate(&terrain, "fbm(in.world_position * 24.0)");
    assert!(
        albedo.cost > 1.8 * grass.cost,
        "{} {}",
        albedo.cost,
        grass.cost
    );
}

/// The value a loop leaves in a variable is a candidate; values inside the
/// loop stay rejected.
#[test]
fn a_loop_result_is_a_candidate() {
    let source = "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;\nstruct V { @builtin(position) position: vec4<f32>, @location(0) p: vec3<f32> }\n@vertex\nfn vs(@location(0) p: vec3<f32>) -> V {\n    return V(clip_from_world * vec4<f32>(p, 1.0), p);\n}\n@fragment\nfn fs(in: V) -> @location(0) vec4<f32> {\n    var sum = 0.0;\n    for (var i = 0; i < 8; i++) {\n        sum += sin(in.p.x * f32(i) + cos(in.p.y * f32(i)));\n    }\n    let shaded = sum * 0.125;\n    return vec4<f32>(shaded);\n}\n";
    let (shader, analysis) = analyzed("loop.wgsl", source);
    let sum = candidate(&analysis, "sum");
    assert!(sum.ratio > 0.9, "P/T {}", sum.ratio);
    assert!(analysis
        .rejected
        .iter()
        .any(|r| r.node.text.starts_with("sin(") && r.reason.as_str() == "in-loop"));
    for variant in Variant::CACHE {
        rewrite::rewrite(&shader, &analysis, sum, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
    }
}

/// The lit path under `if ((material.flags & UNLIT_BIT) == 0u)`: its
/// condition is uniform, so the node is cached like an unconditional one,
/// with "no value" where a draw does not take the branch. One-pass is
/// refused with the reason: the textures are sampled under flag branches,
/// and its miss branch is not uniform control flow.
#[test]
fn a_node_under_a_uniform_branch_is_cached() {
    let (shader, analysis) = corpus_shader("pbr_material_flags.wgsl");
    let lit = candidate(&analysis, "tone_mapping(apply_pbr_lighting(pbr_input))");
    for variant in [Variant::TwoPass, Variant::ThreePass] {
        let rewritten = rewrite::rewrite(&shader, &analysis, lit, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
        assert_eq!(rewritten.plan.node.path.as_deref(), Some("uniform-branch"));
        // Pass 2 computes the payload in both variants.
        let text = wgsl_of(&rewritten, "pass2");
        assert!(text.contains("cache_absent()"), "{text}");
        assert!(text.contains("& UNLIT_BIT"), "{text}");
    }
    let refused = rewrite::rewrite(
        &shader,
        &analysis,
        lit,
        Variant::OnePass,
        &Options::default(),
    )
    .unwrap_err();
    assert!(
        refused
            .reason
            .contains("implicit derivatives (textureSample)"),
        "{refused}"
    );
}

/// Grass or rock by the slope of each pixel: the grass detail exists only
/// where the branch is taken. Every variant is built, the payload returns
/// "no value" elsewhere, and the classify pass asks where the node exists.
#[test]
fn a_node_under_a_per_pixel_branch_is_cached_where_it_exists() {
    let (shader, analysis) = corpus_shader("terrain_slope_branch.wgsl");
    let grass = candidate(&analysis, "fbm(in.world_position * 24.0)");
    for variant in Variant::CACHE {
        let rewritten = rewrite::rewrite(&shader, &analysis, grass, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
        assert_eq!(
            rewritten.plan.node.path.as_deref(),
            Some("per-pixel-branch")
        );
        let classify = wgsl_of(&rewritten, "classify");
        assert!(classify.contains("fs_main_computes_node("), "{classify}");
        assert!(classify.contains("cache_classify_absent("), "{classify}");
    }
}

/// A module with a shadow pass and a main pass, as wgpu's `shadow` example
/// has: two vertex and two fragment entry points. The vertex entry point
/// is the one whose output struct the chosen fragment stage takes.
#[test]
fn vertex_entry_is_inferred_from_what_the_fragment_takes() {
    let source = "struct Globals { view_proj: mat4x4<f32>, num_lights: vec4<u32> }\n@group(0) @binding(0) var<uniform> u_globals: Globals;\nstruct Entity { world: mat4x4<f32>, color: vec4<f32> }\n@group(1) @binding(0) var<uniform> u_entity: Entity;\n@vertex\nfn vs_bake(@location(0) position: vec4<i32>) -> @builtin(position) vec4<f32> {\n    return u_globals.view_proj * u_entity.world * vec4<f32>(position);\n}\nstruct VertexOutput { @builtin(position) proj_position: vec4<f32>, @location(0) world_normal: vec3<f32>, @location(1) world_position: vec4<f32> }\n@vertex\nfn vs_main(@location(0) position: vec4<i32>, @location(1) normal: vec4<i32>) -> VertexOutput {\n    let w = u_entity.world;\n    let world_pos = u_entity.world * vec4<f32>(position);\n    var result: VertexOutput;\n    result.world_normal = mat3x3<f32>(w[0].xyz, w[1].xyz, w[2].xyz) * vec3<f32>(normal.xyz);\n    result.world_position = world_pos;\n    result.proj_position = u_globals.view_proj * world_pos;\n    return result;\n}\n@fragment\nfn fs_main(vertex: VertexOutput) -> @location(0) vec4<f32> {\n    let normal = normalize(vertex.world_normal);\n    var color = vec3<f32>(0.05);\n    for (var i = 0u; i < min(u_globals.num_lights.x, 10u); i += 1u) {\n        let light_dir = normalize(vec3<f32>(f32(i), 4.0, 2.0) - vertex.world_position.xyz);\n        color += max(0.0, dot(normal, light_dir)) * vec3<f32>(0.5);\n    }\n    return vec4<f32>(color, 1.0) * u_entity.color;\n}\n@fragment\nfn fs_main_without_storage(vertex: VertexOutput) -> @location(0) vec4<f32> {\n    return vec4<f32>(normalize(vertex.world_normal), 1.0);\n}\n";
    let shader =
        crate::front::parse(crate::diagnostic::SourceFile::new("shadow.wgsl", source)).unwrap();
    let analysis = crate::analysis::analyze(
        &shader,
        &crate::analysis::Options {
            entry: Some("fs_main".into()),
            ..Default::default()
        },
    )
    .unwrap();
    // The light loop's result.
    let color = candidate(&analysis, "color");
    for variant in Variant::CACHE {
        let rewritten = rewrite::rewrite(&shader, &analysis, color, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
        assert!(rewritten
            .plan
            .passes
            .iter()
            .filter(|p| p.draw == crate::plan::DrawKind::Geometry)
            .all(|pass| pass.vertex_entry == "vs_main"));
    }
    // Named explicitly, the shadow pass's vertex stage does not feed it.
    let named = Options {
        vertex_entry: Some("vs_bake".into()),
        ..Options::default()
    };
    let refused =
        rewrite::rewrite(&shader, &analysis, color, Variant::TwoPass, &named).unwrap_err();
    assert!(
        refused
            .reason
            .contains("`vs_bake` does not output what `fs_main` takes"),
        "{refused}"
    );

    // Two vertex stages that both return `VertexOutput`: which one draws
    // is not for the tool to guess.
    let twice = source.replace(
        "@fragment\nfn fs_main(",
        "@vertex\nfn vs_main_too(@location(0) position: vec4<i32>) -> VertexOutput {\n    var result: VertexOutput;\n    result.proj_position = u_globals.view_proj * vec4<f32>(position);\n    return result;\n}\n@fragment\nfn fs_main(",
    );
    let shader = crate::front::parse(crate::diagnostic::SourceFile::new(
        "shadow_twice.wgsl",
        twice,
    ))
    .unwrap();
    let analysis = crate::analysis::analyze(
        &shader,
        &crate::analysis::Options {
            entry: Some("fs_main".into()),
            ..Default::default()
        },
    )
    .unwrap();
    let color = candidate(&analysis, "color");
    let refused = rewrite::rewrite(
        &shader,
        &analysis,
        color,
        Variant::TwoPass,
        &Options::default(),
    )
    .unwrap_err();
    assert!(
        refused
            .reason
            .contains("several vertex entry points (`vs_main`, `vs_main_too`)"),
        "{refused}"
    );
}

/// Δn = 1 recomputes every pixel every frame: on the engine-style corpus
/// shaders, nodes through locals and under uniform and per-pixel branches
/// give the reference's image (differential test).
#[test]
fn engine_style_shaders_at_refresh_period_one_equal_the_reference() {
    let cases = [
        (
            "pbr_material_flags.wgsl",
            "pbr_flags_sphere.toml",
            vec![
                "tone_mapping(apply_pbr_lighting(pbr_input))",
                "output_color",
            ],
        ),
        (
            "terrain_slope_branch.wgsl",
            "slope_terrain.toml",
            vec!["fbm(in.world_position * 24.0)", "albedo"],
        ),
    ];
    for (shader_name, scene_name, texts) in cases {
        let (_, analysis) = corpus_shader(shader_name);
        let ids: Vec<String> = texts
            .iter()
            .map(|text| all_named(&analysis, text).last().unwrap().node.id.clone())
            .collect();
        let shader_text = std::fs::read_to_string(root().join("corpus").join(shader_name)).unwrap();
        let scene = std::fs::read_to_string(root().join("corpus/scenes").join(scene_name))
            .unwrap()
            .replace("size = [256, 256]", "size = [64, 64]");
        let options = ProfileOptions {
            nodes: Nodes::Ids(ids),
            refresh_periods: vec![1],
            refresh_quads: vec![1],
            cache_formats: vec![CacheFormat::Rgba32float],
            reconstructions: vec![CacheRead::Bilinear, CacheRead::NearestPacked],
            frames: Some(3),
            warmup: Some(1),
            variants: Variant::CACHE.to_vec(),
            ..ProfileOptions::default()
        };
        let Some((_, report, _)) = run_shader(&shader_text, &scene, options) else {
            return;
        };
        assert!(!report.results.is_empty(), "{shader_name}");
        for row in &report.results {
            assert!(
                row.max_abs_error <= 1.0 / 255.0 + 1e-9,
                "{shader_name} {} {} {}: {}",
                row.node,
                row.variant,
                row.reconstruction.as_str(),
                row.max_abs_error
            );
        }
    }
}

/// Pixels where a per-pixel branch does not compute the node are neither
/// hits nor misses: on a still scene without refresh, the grass detail is
/// reused wherever there is grass, although most of the terrain is rock.
#[test]
fn absent_pixels_are_not_counted_as_misses() {
    let (_, analysis) = corpus_shader("terrain_slope_branch.wgsl");
    let grass = candidate(&analysis, "fbm(in.world_position * 24.0)");
    let shader_text =
        std::fs::read_to_string(root().join("corpus/terrain_slope_branch.wgsl")).unwrap();
    let scene = std::fs::read_to_string(root().join("corpus/scenes/slope_terrain.toml"))
        .unwrap()
        .replace("size = [256, 256]", "size = [64, 64]")
        .replace("effects = [\"camera-motion\"]", "effects = []");
    let options = ProfileOptions {
        nodes: Nodes::Ids(vec![grass.node.id.clone()]),
        variants: vec![Variant::TwoPass],
        refresh_periods: vec![0],
        reconstructions: vec![CacheRead::Nearest],
        frames: Some(2),
        warmup: Some(2),
        ..ProfileOptions::default()
    };
    let Some((_, report, _)) = run_shader(&shader_text, &scene, options) else {
        return;
    };
    let row = &report.results[0];
    assert!(
        row.hit_rate > 0.95,
        "hit {} miss {}",
        row.hit_rate,
        row.miss_rate
    );
}

/// Text and UI shaders return from a `switch` on the content type (as
/// glyphon's does): a node in one case is absent where another case
/// returned. Every variant is built, the payload and the presence function
/// return "no value" and `false` in the other case, Δn = 1 gives the
/// reference's image, and on a still scene the node is reused wherever it
/// exists, though half the pixels return before it.
#[test]
fn a_node_after_returns_in_other_cases_is_absent_there() {
    let source = "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;\n@group(0) @binding(1) var atlas: texture_2d<f32>;\n@group(0) @binding(2) var atlas_sampler: sampler;\nstruct V { @builtin(position) position: vec4<f32>, @location(0) uv: vec2<f32>, @location(1) @interpolate(flat) content_type: u32 }\n@vertex\nfn vs(@location(0) p: vec3<f32>, @location(2) uv: vec2<f32>) -> V {\n    return V(clip_from_world * vec4<f32>(p, 1.0), uv, u32(p.x > 0.0));\n}\n@fragment\nfn fs(in: V) -> @location(0) vec4<f32> {\n    switch in.content_type {\n        case 0u: {\n            return textureSampleLevel(atlas, atlas_sampler, in.uv, 0.0);\n        }\n        case 1u: {\n            let coverage = textureSampleLevel(atlas, atlas_sampler, in.uv, 0.0).x * sin(in.uv.x * 40.0);\n            return vec4<f32>(coverage);\n        }\n        default: {}\n    }\n    return vec4<f32>(0.0);\n}\n";
    let (shader, analysis) = analyzed("text.wgsl", source);
    let coverage = candidate(
        &analysis,
        "textureSampleLevel(atlas, atlas_sampler, in.uv, 0.0).x * sin(in.uv.x * 40.0)",
    );
    for variant in Variant::CACHE {
        let rewritten =
            rewrite::rewrite(&shader, &analysis, coverage, variant, &Options::default())
                .unwrap_or_else(|r| panic!("{variant}: {r}"));
        assert_eq!(
            rewritten.plan.node.path.as_deref(),
            Some("per-pixel-branch")
        );
        let classify = wgsl_of(&rewritten, "classify");
        let presence = classify
            .split("fn fs_computes_node(")
            .nth(1)
            .expect("a presence function");
        let case_zero = presence.split("case 0u: {").nth(1).expect("case 0");
        let case_zero = &case_zero[..case_zero.find('}').unwrap()];
        assert!(case_zero.contains("return false;"), "{classify}");
    }

    let scene = r#"
size = [64, 64]
effects = []
[camera]
eye = [0.0, 2.0, 0.01]
[[objects]]
mesh = { kind = "plane", size = 2.0, subdivisions = 8 }
[textures.atlas]
generate = "checker"
size = 64
"#;
    let differential = ProfileOptions {
        nodes: Nodes::Ids(vec![coverage.node.id.clone()]),
        refresh_periods: vec![1],
        refresh_quads: vec![1],
        cache_formats: vec![CacheFormat::Rgba32float],
        frames: Some(2),
        warmup: Some(1),
        variants: Variant::CACHE.to_vec(),
        ..ProfileOptions::default()
    };
    let Some((_, report, _)) = run_shader(source, scene, differential) else {
        return;
    };
    for row in &report.results {
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{}: {}",
            row.variant,
            row.max_abs_error
        );
    }
    let still = ProfileOptions {
        nodes: Nodes::Ids(vec![coverage.node.id.clone()]),
        refresh_periods: vec![0],
        reconstructions: vec![CacheRead::Nearest],
        frames: Some(2),
        warmup: Some(2),
        variants: Variant::CACHE.to_vec(),
        ..ProfileOptions::default()
    };
    let Some((_, report, _)) = run_shader(source, scene, still) else {
        return;
    };
    for row in &report.results {
        assert!(row.hit_rate > 0.95, "{}: hit {}", row.variant, row.hit_rate);
    }
}

/// egui samples its texture in a helper (`sample_texture`): one-pass, which
/// computes the payload in its miss branch and hoists only the entry
/// point's own derivatives, refuses with the helper's name instead of
/// failing its own uniformity check; two- and three-pass are built.
#[test]
fn one_pass_refuses_a_payload_whose_helper_takes_derivatives() {
    let source = "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;\n@group(0) @binding(1) var r_tex_color: texture_2d<f32>;\n@group(0) @binding(2) var r_tex_sampler: sampler;\nstruct VertexOutput { @builtin(position) position: vec4<f32>, @location(0) tex_coord: vec2<f32>, @location(1) color: vec4<f32> }\n@vertex\nfn vs(@location(0) p: vec3<f32>, @location(2) uv: vec2<f32>) -> VertexOutput {\n    return VertexOutput(clip_from_world * vec4<f32>(p, 1.0), uv, vec4<f32>(1.0));\n}\nfn sample_texture(in: VertexOutput) -> vec4<f32> {\n    return textureSample(r_tex_color, r_tex_sampler, in.tex_coord);\n}\n@fragment\nfn fs(in: VertexOutput) -> @location(0) vec4<f32> {\n    let tex_gamma = sample_texture(in);\n    let out_color = in.color * tex_gamma;\n    return vec4<f32>(pow(out_color.rgb, vec3<f32>(2.2)), out_color.a);\n}\n";
    let (shader, analysis) = analyzed("egui.wgsl", source);
    let node = candidate(&analysis, "in.color * tex_gamma");
    let refused = rewrite::rewrite(
        &shader,
        &analysis,
        node,
        Variant::OnePass,
        &Options::default(),
    )
    .unwrap_err();
    assert!(
        refused
            .reason
            .contains("calls `sample_texture`, which takes implicit derivatives"),
        "{refused}"
    );
    for variant in [Variant::TwoPass, Variant::ThreePass] {
        rewrite::rewrite(&shader, &analysis, node, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
    }
}

/// `lit += f(..)` and then `lit += g(..)`, caching the second sum: in the
/// shade pass the first store is overwritten by the cached value, so it
/// and the call it stores are dropped together (keeping the store without
/// its call left a call result no statement computes: invalid IR).
#[test]
fn a_store_overwritten_by_the_cached_value_is_dropped_with_its_call() {
    let source = "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;\nstruct V { @builtin(position) position: vec4<f32>, @location(0) p: vec3<f32> }\n@vertex\nfn vs(@location(0) p: vec3<f32>) -> V {\n    return V(clip_from_world * vec4<f32>(p, 1.0), p);\n}\nfn shine(p: vec3<f32>) -> vec3<f32> {\n    return vec3<f32>(pow(max(sin(p.x * 9.0), 0.0), 12.0));\n}\n@fragment\nfn fs(in: V) -> @location(0) vec4<f32> {\n    var lit = vec3<f32>(0.1);\n    lit += shine(in.p);\n    let rim = pow(1.0 - abs(in.p.z), 4.0);\n    lit += vec3<f32>(rim * 0.25);\n    return vec4<f32>(lit * 0.5, 1.0);\n}\n";
    let (shader, analysis) = analyzed("overwritten.wgsl", source);
    let second = analysis
        .candidates
        .iter()
        .find(|c| c.node.text == "lit += vec3<f32>(rim * 0.25)")
        .unwrap_or_else(|| panic!("{:#?}", analysis.candidates));
    for variant in Variant::CACHE {
        let rewritten = rewrite::rewrite(&shader, &analysis, second, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
        // The shade keeps no call to `shine`: its value is in the cache.
        let shades: Vec<String> = wgsl_sources(&rewritten)
            .into_values()
            .filter_map(|text| {
                let body = text.split("fn fs_shade(").nth(1)?;
                Some(body.split("\nfn ").next().unwrap_or(body).to_string())
            })
            .collect();
        assert!(!shades.is_empty(), "{variant}: no shade function");
        for shade in shades {
            assert!(!shade.contains("shine("), "{variant}: {shade}");
        }
    }
}

/// A shader that binds all four of WebGPU's bind groups (view, light,
/// material, model) leaves none for the cache: its resources go after the
/// shader's last binding in the last group, every pass builds a pipeline,
/// and Δn = 1 still gives the reference's image.
#[test]
fn a_shader_using_all_four_bind_groups_gets_the_cache_after_its_last_binding() {
    let text = std::fs::read_to_string(root().join("corpus/tutorial_own_names.wgsl"))
        .unwrap()
        .replace(
            "@group(2) @binding(1)\nvar<uniform> object",
            "@group(3) @binding(0)\nvar<uniform> object",
        );
    assert!(text.contains("@group(3)"));
    let (shader, analysis) = analyzed("four_groups.wgsl", &text);
    let node = &analysis.candidates[0];
    for variant in Variant::CACHE {
        let rewritten = rewrite::rewrite(&shader, &analysis, node, variant, &Options::default())
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
        let bindings = &rewritten.plan.bindings;
        for resource in &bindings.cache {
            assert_eq!(resource.group, 3, "{resource:?}");
            assert!(resource.binding >= 1, "{resource:?}");
        }
        for twin in &bindings.previous {
            assert_eq!(twin.group, 3);
            assert!(bindings.cache.iter().all(|c| c.binding != twin.binding));
        }
        super::gpu::build_pipelines(&rewritten, &variant.to_string());
    }
    if let Some(report) =
        super::profile::assert_refresh_one_equals_reference(&shader, vec![node.node.id.clone()], 48)
    {
        assert_eq!(report.results.len(), Variant::CACHE.len());
    }
}

/// A forward pass and its shadow pass in one module, in the shape of
/// wgpu's `shadow` example (`corpus/multi/shadowed_lights.wgsl`): each
/// fragment stage pairs with the vertex stage that returns its struct,
/// the lights bound at one slot as storage for one and as a uniform array
/// of structs for the other, a depth texture array, integer positions.
/// Both profile on the default scene, and Δn = 1 gives the reference.
#[test]
fn a_shadow_and_forward_module_profiles_each_fragment_stage_without_a_scene() {
    let path = root().join("corpus/multi/shadowed_lights.wgsl");
    let shader = crate::front::load(&path).unwrap();
    for entry in ["fs_main", "fs_main_uniform_lights"] {
        let analysis = crate::analysis::analyze(
            &shader,
            &crate::analysis::Options {
                entry: Some(entry.into()),
                ..crate::analysis::Options::default()
            },
        )
        .unwrap();
        let node = &analysis.candidates[0];
        for variant in Variant::CACHE {
            let rewritten =
                rewrite::rewrite(&shader, &analysis, node, variant, &Options::default())
                    .unwrap_or_else(|r| panic!("{entry} {variant}: {r}"));
            assert!(rewritten
                .plan
                .passes
                .iter()
                .filter(|p| p.draw == crate::plan::DrawKind::Geometry)
                .all(|p| p.vertex_entry == "vs_main"));
            // One resource at the lights' slot: the one this stage reads.
            let at_slot: Vec<&str> = rewritten
                .plan
                .bindings
                .original
                .iter()
                .filter(|r| [r.group, r.binding] == [0, 1])
                .map(|r| r.kind.as_str())
                .collect();
            let expected = if entry == "fs_main" {
                "storage"
            } else {
                "uniform"
            };
            assert_eq!(at_slot, [expected], "{entry}");
            assert!(rewritten
                .plan
                .bindings
                .original
                .iter()
                .any(|r| r.kind == crate::plan::ResourceKind::DepthTextureArray));
        }
        let Some(_) = super::gpu::gpu() else { continue };
        let scene = crate::scene::Scene::default_for(&shader, Some(entry), None).unwrap();
        // Integer positions are fed the mesh's, rounded; the uniform
        // array's elements are written member by member.
        assert!(scene.defaulted.iter().all(|d| !d.contains("cannot")));
        let options = ProfileOptions {
            entry: Some(entry.into()),
            nodes: Nodes::Ids(vec![node.node.id.clone()]),
            refresh_periods: vec![1],
            refresh_quads: vec![1],
            cache_formats: vec![CacheFormat::Rgba32float],
            reconstructions: vec![CacheRead::Bilinear],
            frames: Some(2),
            warmup: Some(1),
            size: Some([48, 48]),
            variants: Variant::CACHE.to_vec(),
            ..ProfileOptions::default()
        };
        let (report, _) = crate::profile::profile(
            &shader,
            &scene,
            std::path::Path::new("default scene"),
            &options,
            &mut crate::profile::Quiet,
        )
        .unwrap_or_else(|e| panic!("{entry}: {}", e.render()));
        assert!(
            report
                .defaulted
                .iter()
                .any(|d| d.contains("`position` = the mesh's positions rounded")),
            "{:?}",
            report.defaulted
        );
        for row in &report.results {
            // Δn = 1 refreshes every drawn pixel.
            assert!(
                row.refresh_rate > 0.5,
                "{entry} {}: nothing drawn ({})",
                row.variant,
                row.refresh_rate
            );
            assert!(
                row.max_abs_error <= 1.0 / 255.0 + 1e-9,
                "{entry} {}: {}",
                row.variant,
                row.max_abs_error
            );
        }
    }
}

/// The candidates inside helper `function`, with text `text`.
fn in_helper<'a>(analysis: &'a Analysis, function: &str, text: &str) -> Vec<&'a Candidate> {
    analysis
        .candidates
        .iter()
        .filter(|c| c.node.function == function && c.node.text == text)
        .collect()
}

/// `fbm` is called four times from `fs_main`: its result expression is a
/// candidate once per call, each spanned in `fbm`'s source, named by its
/// call path, costed as that call (the inlined copy), and the call itself
/// is still a node of the entry point.
#[test]
fn helper_expressions_are_candidates_per_call_site() {
    let (_, analysis) = corpus_shader("helpers_nested.wgsl");
    let copies = in_helper(&analysis, "fbm", "total / 0.9375");
    assert_eq!(copies.len(), 4, "{copies:#?}");
    let mut calls: Vec<&str> = copies
        .iter()
        .map(|c| {
            assert_eq!(c.node.call_path.len(), 1);
            assert_eq!(c.node.call_path[0].function, "fbm");
            assert_eq!(c.node.span.start[0], 85, "the span is in `fbm`");
            c.node.call_path[0].text.as_str()
        })
        .collect();
    calls.sort();
    assert_eq!(
        calls,
        [
            "fbm(p * 0.5 + vec2<f32>(17.0, -3.0))",
            "fbm(p + vec2<f32>(5.2, 1.3))",
            "fbm(p)",
            "fbm(warped * 6.0)"
        ]
    );
    let ids: std::collections::BTreeSet<_> = copies.iter().map(|c| &c.node.id).collect();
    assert_eq!(ids.len(), 4);
    // Each copy costs what its call costs, less the argument.
    for copy in &copies {
        let call = &copy.node.call_path[0];
        let at_call = analysis
            .candidates
            .iter()
            .find(|c| c.node.call_path.is_empty() && c.node.range == call.range)
            .expect("the call is a node of the entry point");
        assert!(copy.cost > 0.9 * at_call.cost && copy.cost <= at_call.cost);
    }
    // Three levels down: `hash` inside `value_noise` inside `fbm`'s loop
    // is there, rejected as in-loop, with its whole path.
    let hash = analysis
        .rejected
        .iter()
        .find(|r| r.node.function == "hash")
        .unwrap();
    assert_eq!(hash.reason, crate::analysis::RejectReason::InLoop);
    let path: Vec<&str> = hash
        .node
        .call_path
        .iter()
        .map(|s| s.function.as_str())
        .collect();
    assert_eq!(path, ["fbm", "value_noise", "hash"]);
}

/// Caching a node inside a helper inlines the calls on its path only: the
/// payload of `fbm(warped * 6.0)`'s result has that call inlined and
/// still calls `fbm` for the other three, and the plan names the path.
#[test]
fn a_helper_node_is_rewritten_with_only_its_call_path_inlined() {
    let (shader, analysis) = corpus_shader("helpers_nested.wgsl");
    let node = in_helper(&analysis, "fbm", "total / 0.9375")
        .into_iter()
        .find(|c| c.node.call_path[0].text == "fbm(warped * 6.0)")
        .unwrap();
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        node,
        Variant::ThreePass,
        &Options::default(),
    )
    .unwrap();
    let payload_pass = &rewritten.passes[1].module;
    let payload = payload_pass
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some("fs_main_payload"))
        .unwrap()
        .1;
    let mut fbm_calls = 0;
    let mut loops = 0;
    crate::proc::each_statement(&payload.body, &mut |s| match *s {
        naga::Statement::Call { function, .. } => {
            fbm_calls +=
                usize::from(payload_pass.functions[function].name.as_deref() == Some("fbm"))
        }
        naga::Statement::Loop { .. } => loops += 1,
        _ => {}
    });
    // The payload needs `warped`, which calls `fbm` twice; the third call
    // is the inlined one (its octave loop), the fourth is not needed.
    assert_eq!(fbm_calls, 2);
    assert_eq!(loops, 1);
    assert_eq!(rewritten.plan.node.function.as_deref(), Some("fbm"));
    assert_eq!(rewritten.plan.node.call_path.len(), 1);
    assert_eq!(rewritten.plan.node.call_path[0].text, "fbm(warped * 6.0)");
}

/// Δn = 1 recomputes every pixel every frame: nodes inside helpers,
/// inlined along their call paths — `fbm`'s sum after its loop, the PBR
/// lighting's result and its tone map, and `blinn_phong`'s highlight after
/// the helper's early return — give the reference's image (differential
/// test on the default scene).
#[test]
fn helper_nodes_at_refresh_period_one_equal_the_reference() {
    let cases = [
        ("helpers_nested.wgsl", "fbm", "total / 0.9375"),
        (
            "pbr_material_flags.wgsl",
            "apply_pbr_lighting",
            "light_accum + ambient + material.emissive.rgb",
        ),
        (
            "pbr_material_flags.wgsl",
            "tone_mapping",
            "exposed / (vec3<f32>(1.0) + exposed)",
        ),
        (
            "tutorial_own_names.wgsl",
            "blinn_phong",
            "light.color * light.intensity * (diffuse + specular)",
        ),
    ];
    for (name, function, text) in cases {
        let (shader, analysis) = corpus_shader(name);
        let ids: Vec<String> = in_helper(&analysis, function, text)
            .iter()
            .map(|c| c.node.id.clone())
            .collect();
        assert!(!ids.is_empty(), "{name}: no `{text}` in `{function}`");
        if super::profile::assert_refresh_one_equals_reference(&shader, ids, 48).is_none() {
            return;
        }
    }
}
