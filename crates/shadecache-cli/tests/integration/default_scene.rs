//! Profiling without a scene: the default scene, its roles inferred from
//! the shader's own names, every other binding defaulted and listed, and
//! `scene init` writing the same scene out.

use std::ffi::OsStr;
use std::path::Path;

use serde_json::Value;

use crate::util::{profile_error, shadecache, stderr, stdout, temp_file};

const TUTORIAL: &str = "corpus/tutorial_own_names.wgsl";

/// `shadecache profile TUTORIAL` at 32×32 for two frames, with `--scene`
/// when given; the report.
fn profile(scene: Option<&Path>, out: &Path) -> (Value, String) {
    let mut args: Vec<&OsStr> = vec![
        "profile".as_ref(),
        TUTORIAL.as_ref(),
        "--nodes".as_ref(),
        "top:1".as_ref(),
        "--variant".as_ref(),
        "two-pass".as_ref(),
        "--frames".as_ref(),
        "2".as_ref(),
        "--size".as_ref(),
        "32x32".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
    ];
    if let Some(scene) = scene {
        args.extend(["--scene".as_ref(), scene.as_os_str()]);
    }
    let output = shadecache(args);
    assert!(output.status.success(), "{}", stderr(&output));
    let report = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    (report, stdout(&output))
}

/// `shadecache profile SHADER` with no scene: the top node, one `variant`,
/// `frames` frames at `size`², into `out`.
fn profile_small(
    shader: &Path,
    variant: &str,
    frames: u32,
    size: u32,
    out: &Path,
) -> std::process::Output {
    shadecache([
        OsStr::new("profile"),
        shader.as_os_str(),
        OsStr::new("--variant"),
        OsStr::new(variant),
        OsStr::new("--nodes"),
        OsStr::new("top:1"),
        OsStr::new("--frames"),
        OsStr::new(&frames.to_string()),
        OsStr::new("--size"),
        OsStr::new(&format!("{size}x{size}")),
        OsStr::new("--quiet"),
        OsStr::new("--out"),
        out.as_os_str(),
    ])
}

/// The default scene finds the tutorial's `camera.view_proj` and
/// `object.model` from its vertex stage: camera motion moves what is drawn
/// (misses; with identity matrices it would move nothing), and every
/// value it had to invent is listed.
#[test]
fn profile_without_a_scene_infers_roles_and_lists_defaults() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let (report, summary) = profile(None, out.path());
    let defaulted: Vec<&str> = report["defaulted"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(
        defaulted.contains(
            &"uniform `light.intensity` = 1.0 (a f32, a scale, intensity or distance, by its name: 1)"
        )
            && defaulted.contains(&"texture `t_normal` = generated \"flat-normal\""),
        "{defaulted:?}"
    );
    // Roles are not defaults.
    assert!(
        !defaulted
            .iter()
            .any(|d| d.contains("view_proj") || d.contains("light.position")),
        "{defaulted:?}"
    );
    assert!(summary.contains("defaulted"), "{summary}");
    let camera = report["miss_causes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["effect"] == "camera-motion")
        .expect("a camera-motion miss cause");
    assert!(camera["miss_rate"].as_f64().unwrap() > 0.001, "{camera}");
}

/// The file `scene init` writes is the default scene: profiled, it gives
/// the same images (same hits, same error) as no scene.
#[test]
fn a_scene_init_file_profiles_as_no_scene() {
    let output = shadecache(["scene", "init", TUTORIAL]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(
        text.contains("\"camera.view_proj\" = \"clip_from_world\""),
        "{text}"
    );
    assert!(text.contains("# inferred: applied last"), "{text}");
    assert!(text.contains("# defaulted:"), "{text}");
    if crate::util::no_gpu() {
        return;
    }
    let (_dir, path) = temp_file("scene.toml", text.as_bytes());
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (with_file, _) = profile(Some(&path), a.path());
    let (without, _) = profile(None, b.path());
    let row = |report: &Value| {
        let r = &report["results"][0];
        (
            r["node"].clone(),
            r["psnr"].clone(),
            r["hit_rate"].clone(),
            r["miss_rate"].clone(),
        )
    };
    assert_eq!(row(&with_file), row(&without));
}

/// A scene for the tutorial shader with `roles` under [roles]; the line of
/// the first role.
fn with_roles(roles: &str) -> (String, usize) {
    let text = format!(
        "[[objects]]\nmesh = {{ kind = \"sphere\" }}\n[roles]\n{roles}\n[uniforms]\nintensity = 1.0\ncolor = [1.0, 1.0, 1.0]\nshininess = 0.5\ntint = [1.0, 1.0, 1.0, 1.0]\n[textures.t_diffuse]\ngenerate = \"checker\"\n[textures.t_normal]\ngenerate = \"flat-normal\"\n"
    );
    (text, 4)
}

#[test]
fn an_unknown_role_is_an_error_at_its_line() {
    let (scene, line) = with_roles("\"camera.view_proj\" = \"view_projection\"");
    let err = profile_error(TUTORIAL, &scene);
    assert!(err.contains("unknown role `view_projection`"), "{err}");
    assert!(err.contains("clip_from_world"), "{err}");
    assert!(err.contains(&format!("scene.toml:{line}:")), "{err}");
}

#[test]
fn a_role_naming_a_missing_member_is_an_error() {
    let (scene, line) = with_roles("\"camera.viewproj\" = \"clip_from_world\"");
    let err = profile_error(TUTORIAL, &scene);
    assert!(
        err.contains("`camera.viewproj`, which the shader does not have"),
        "{err}"
    );
    assert!(err.contains("`camera.view_proj`"), "{err}");
    assert!(err.contains(&format!("scene.toml:{line}:")), "{err}");
}

#[test]
fn a_role_on_a_member_of_the_wrong_type_is_an_error() {
    let (scene, line) = with_roles("\"camera.view_pos\" = \"clip_from_world\"");
    let err = profile_error(TUTORIAL, &scene);
    assert!(
        err.contains("`camera.view_pos` is vec4<f32> and cannot take role `clip_from_world`"),
        "{err}"
    );
    assert!(err.contains(&format!("scene.toml:{line}:")), "{err}");
}

#[test]
fn a_member_given_a_role_and_a_value_is_an_error() {
    let (scene, line) = with_roles("\"light.intensity\" = \"time\"");
    let err = profile_error(TUTORIAL, &scene);
    assert!(err.contains("`light.intensity` is given twice"), "{err}");
    assert!(err.contains(&format!("scene.toml:{line}:")), "{err}");
}

/// A float vertex input whose name and location say nothing the mesh
/// has: named, exit 1 (a constant would draw something else than the
/// shader's author meant).
#[test]
fn a_vertex_input_the_mesh_cannot_feed_is_an_error() {
    let shader = "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;
struct V { @builtin(position) position: vec4<f32>, @location(0) weight: f32 }
@vertex
fn vs(@location(0) position: vec3<f32>, @location(5) wind_gust: f32) -> V {
    return V(clip_from_world * vec4<f32>(position, 1.0), wind_gust);
}
@fragment
fn fs(in: V) -> @location(0) vec4<f32> {
    return vec4<f32>(sin(in.weight * 40.0));
}
";
    let (dir, path) = temp_file("gusty.wgsl", shader.as_bytes());
    // A scene that says nothing of it: an error at the input. (The
    // default scene gives such an input a constant, listed as defaulted.)
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, "[[objects]]\nmesh = { kind = \"sphere\" }\n").unwrap();
    let output = shadecache([
        "profile".as_ref(),
        path.as_os_str(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--quiet".as_ref(),
    ] as [&OsStr; 5]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot feed vertex input @location(5) `wind_gust` (float32)"),
        "{err}"
    );
    // At the input's declaration.
    let column = shader.lines().nth(3).unwrap().find("wind_gust").unwrap() + 1;
    assert!(err.contains(&format!("gusty.wgsl:4:{column}")), "{err}");
}

/// A float vertex input the mesh has nothing for (a text renderer's
/// per-glyph `depth`; here `layer`).
const LAYERED: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(3) layer: f32,
}

struct VertexOutput {
    @builtin(position) clip: vec4<f32>,
    @location(0) layer: f32,
    @location(1) local: vec3<f32>,
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    var out: VertexOutput;
    // The constant sizes the sphere: 0.25 draws it whole, anything that
    // ignores the constant (zero) draws nothing.
    let placed = in.position * in.layer * 4.0;
    out.clip = frame.clip_from_world * frame.world_from_local * vec4<f32>(placed, 1.0);
    out.layer = in.layer;
    out.local = in.position;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    var bands = 0.0;
    for (var i = 0; i < 8; i++) {
        bands += sin(in.local.x * 3.0 * f32(i + 1)) * 0.1;
    }
    return vec4<f32>(bands, in.layer, 0.0, 1.0);
}
"#;

/// Without a constant for it the profile stops at the input, saying how
/// to give one; with `[vertex_inputs]` in the scene the input is that
/// constant (the sphere it sizes covers the frame) and the shader
/// profiles.
#[test]
fn a_vertex_input_the_mesh_cannot_feed_takes_the_scenes_constant() {
    let (_shader_dir, shader) = temp_file("layered.wgsl", LAYERED.as_bytes());
    let shader = shader.to_str().unwrap();
    let sphere =
        "frames = 2\nwarmup = 1\nsize = [32, 32]\n\n[[objects]]\nmesh = { kind = \"sphere\" }\n";
    let err = profile_error(shader, sphere);
    assert!(err.contains("`layer`"), "{err}");
    assert!(err.contains("[vertex_inputs]"), "{err}");
    if crate::util::no_gpu() {
        return;
    }
    let scene = format!("{sphere}\n[vertex_inputs]\nlayer = 0.25\n");
    let (_scene_dir, scene) = temp_file("scene.toml", scene.as_bytes());
    let out = tempfile::tempdir().unwrap();
    let output = shadecache([
        "profile".as_ref(),
        shader.as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--variant".as_ref(),
        "two-pass".as_ref(),
        "--nodes".as_ref(),
        "top:1".as_ref(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        out.path().as_os_str(),
    ] as [&OsStr; 11]);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("report.json")).unwrap())
            .unwrap();
    assert!(report["results"][0]["coverage"].as_f64().unwrap() > 0.1);
}

/// Bevy's lights as a uniform array (`array<PointLight, 256u>`, its
/// build without storage buffers): longer than a scene writes member by
/// member.
const LIGHT_ARRAY: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}
struct PointLight {
    position_radius: vec4<f32>,
    color: vec4<f32>,
}
struct PointLights {
    data: array<PointLight, 256u>,
}
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> point_lights: PointLights;

struct VertexOutput {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.clip = frame.clip_from_world * frame.world_from_local * vec4<f32>(position, 1.0);
    out.local = position;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    var lit = vec3<f32>(0.1);
    for (var i = 0u; i < 4u; i++) {
        let light = point_lights.data[i];
        let d = length(light.position_radius.xyz - in.local);
        lit += light.color.rgb / (1.0 + d * d) + vec3<f32>(sin(in.local.x * f32(i + 3u)) * 0.05);
    }
    return vec4<f32>(lit, 1.0);
}
"#;

/// A uniform array longer than a scene writes member by member is zero
/// (no lights), listed as defaulted; a scene that tries to set it is told
/// to leave it out.
#[test]
fn a_long_uniform_array_is_zero_and_listed_as_defaulted() {
    let (_dir, shader) = temp_file("lights.wgsl", LIGHT_ARRAY.as_bytes());
    let err = profile_error(
        shader.to_str().unwrap(),
        "[[objects]]\nmesh = { kind = \"sphere\" }\n\n[uniforms]\ndata = 1.0\n",
    );
    assert!(err.contains("`point_lights.data`"), "{err}");
    assert!(err.contains("leave it out"), "{err}");
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let output = profile_small(&shader, "two-pass", 2, 32, out.path());
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(
        text.contains("uniform `point_lights.data` = zero"),
        "{text}"
    );
}

/// A shader whose expensive value is scaled to nearly nothing draws a
/// black sphere: every variant matches it (SSIM 1.0000), which says
/// nothing about the shader. The reference check says so first, in the
/// terminal and the report, and the answer recommends nothing on it,
/// though variants within the budget were measured.
#[test]
fn degenerate_reference_is_reported_and_never_recommended() {
    if crate::util::no_gpu() {
        return;
    }
    let source = "struct Frame { clip_from_world: mat4x4<f32>, world_from_local: mat4x4<f32> }
@group(0) @binding(0) var<uniform> frame: Frame;
struct VertexOut { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32> }
@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOut {
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    return VertexOut(frame.clip_from_world * world, world.xyz);
}
fn wave(p: vec3<f32>) -> f32 {
    return sin(p.x * 7.0) * cos(p.y * 5.0) + sin(p.y * 13.0 + p.z * 3.0) * 0.5;
}
@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let shade = vec3<f32>(wave(in.world), wave(in.world.yzx), wave(in.world.zxy)) * 0.5 + 0.5;
    return vec4<f32>(shade * 0.001, 1.0);
}
";
    let (dir, shader) = temp_file("black.wgsl", source.as_bytes());
    let out = dir.path().join("report");
    let output = profile_small(&shader, "one-pass", 3, 48, &out);
    assert!(output.status.success(), "{}", stderr(&output));
    let summary = stdout(&output);
    // Said first: right after the run's line, before any figure.
    let lines: Vec<&str> = summary.lines().collect();
    assert!(
        lines[1].contains("reference check: DEGENERATE (nearly-black)"),
        "{summary}"
    );
    assert!(
        lines[2].contains("Likely cause: an unlit input"),
        "{summary}"
    );
    let report: Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let check = &report["reference_check"];
    assert_eq!(check["problems"][0]["kind"], "nearly-black", "{check}");
    assert!(check["coverage"].as_f64().unwrap() > 0.2, "{check}");
    // The variant matched the black frames, and is not recommended.
    assert!(report["results"][0]["ssim"].as_f64().unwrap() > 0.99);
    assert!(report["choice"]["result"].is_null(), "{}", report["choice"]);
    assert!(report["choice"]["closest"].is_null());
    let reason = report["choice"]["reason"].as_str().unwrap();
    assert!(reason.contains("the reference is degenerate"), "{reason}");
    assert!(!out.join("choice").exists());
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let top = html
        .find("Degenerate reference")
        .expect("the report says so");
    assert!(top < html.find("Which value to cache").unwrap());

    // The same shader, lit, passes its check.
    let lit = source.replace("shade * 0.001", "shade");
    std::fs::write(&shader, lit).unwrap();
    let output = profile_small(&shader, "one-pass", 3, 48, &out);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("reference check: passes"),
        "{}",
        stdout(&output)
    );
}

/// wgpu's cube example reads a `texture_2d<u32>` with `textureLoad`: the
/// runtime makes it an `rgba8uint` texture of the scene's texels, the
/// default scene fills it with small whole numbers (the example divides
/// them by 255 and scales them up), and the profile runs on a reference
/// that passes its check. It stopped at "uint-texture bindings are not
/// supported".
#[test]
fn uint_texture_binding_profiles() {
    if crate::util::no_gpu() {
        return;
    }
    let source = "struct VertexOutput { @location(0) tex_coord: vec2<f32>, @builtin(position) position: vec4<f32> };
@group(0) @binding(0) var<uniform> transform: mat4x4<f32>;
@vertex
fn vs_main(@location(0) position: vec4<f32>, @location(1) tex_coord: vec2<f32>) -> VertexOutput {
    var result: VertexOutput;
    result.tex_coord = tex_coord;
    result.position = transform * position;
    return result;
}
@group(0) @binding(1) var r_color: texture_2d<u32>;
@fragment
fn fs_main(vertex: VertexOutput) -> @location(0) vec4<f32> {
    let tex = textureLoad(r_color, vec2<i32>(vertex.tex_coord * 256.0), 0);
    let v = f32(tex.x) / 255.0;
    return vec4<f32>(1.0 - (v * 5.0), 1.0 - (v * 15.0), 1.0 - (v * 50.0), 1.0);
}
";
    let (dir, shader) = temp_file("cube.wgsl", source.as_bytes());
    let out = dir.path().join("report");
    let output = profile_small(&shader, "one-pass", 2, 48, &out);
    assert!(output.status.success(), "{}", stderr(&output));
    let report: Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert!(
        report["defaulted"]
            .as_array()
            .unwrap()
            .iter()
            .any(|d| d == "texture `r_color` = generated \"cells\""),
        "{}",
        report["defaulted"]
    );
    let check = &report["reference_check"];
    assert!(check["problems"].as_array().unwrap().is_empty(), "{check}");
    // The cells vary the colour over the surface.
    assert!(
        check["luminance_spread"].as_f64().unwrap() > 0.01,
        "{check}"
    );
}
