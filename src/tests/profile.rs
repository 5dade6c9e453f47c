//! The profiler on lavapipe: small frames, few of them.

use crate::profile::{self, Nodes, Options, Quiet};
use crate::rewrite::{CacheFormat, CacheRead, Reconstruction, Variant};
use crate::scene::Scene;

use super::util::{marble_scene, root, temp_file};

pub(crate) fn run(
    scene_text: &str,
    options: Options,
) -> Option<(profile::Pictures, crate::report::Report, Scene)> {
    let marble = std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap();
    run_shader(&marble, scene_text, options)
}

/// Profiles `shader_text` on `scene_text`; `None` (said on stderr) without
/// a GPU adapter outside CI.
pub(crate) fn run_shader(
    shader_text: &str,
    scene_text: &str,
    options: Options,
) -> Option<(profile::Pictures, crate::report::Report, Scene)> {
    super::gpu::gpu()?;
    let (_dir, scene_path) = temp_file("scene.toml", scene_text.as_bytes());
    let scene = Scene::load(&scene_path).unwrap_or_else(|e| panic!("{}", e.render()));
    let shader = crate::front::parse(crate::diagnostic::SourceFile::new("test.wgsl", shader_text))
        .unwrap_or_else(|e| panic!("{}", e.render()));
    let (report, pictures) = profile::profile(&shader, &scene, &scene_path, &options, &mut Quiet)
        .unwrap_or_else(|e| panic!("{}", e.render()));
    Some((pictures, report, scene))
}

/// Δn = 1 on the default scene for `shader`'s nodes `ids` (rgba32float,
/// bilinear, two frames after one warm-up at `size`²): every row's largest
/// difference from the reference, which must be within one 8-bit step.
/// `None` without a GPU.
pub(crate) fn assert_refresh_one_equals_reference(
    shader: &crate::front::Shader,
    ids: Vec<String>,
    size: u32,
) -> Option<crate::report::Report> {
    super::gpu::gpu()?;
    let scene = Scene::default_for(shader, None, None).unwrap_or_else(|e| panic!("{}", e.render()));
    let options = Options {
        nodes: Nodes::Ids(ids),
        refresh_periods: vec![1],
        refresh_quads: vec![1],
        cache_formats: vec![crate::rewrite::CacheFormat::Rgba32float],
        reconstructions: vec![CacheRead::Bilinear],
        frames: Some(2),
        warmup: Some(1),
        size: Some([size, size]),
        variants: Variant::CACHE.to_vec(),
        ..Options::default()
    };
    let (report, _) = profile::profile(
        shader,
        &scene,
        std::path::Path::new("default scene"),
        &options,
        &mut Quiet,
    )
    .unwrap_or_else(|e| panic!("{}", e.render()));
    assert!(!report.results.is_empty());
    for row in &report.results {
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{} {}: {}",
            row.node,
            row.variant,
            row.max_abs_error
        );
    }
    Some(report)
}

/// The cache variants (lowres has its own tests, `lowres.rs`).
pub(crate) fn options(periods: &[u32], quads: &[u32]) -> Options {
    Options {
        nodes: Nodes::Ids(vec!["nb0c12cc4".into()]),
        variants: Variant::CACHE.to_vec(),
        refresh_periods: periods.to_vec(),
        refresh_quads: quads.to_vec(),
        ..Options::default()
    }
}

/// Static camera, static scene, refresh off: after the first frame every
/// covered pixel is reused and the image equals the reference within the
/// cache format's tolerance.
#[test]
fn static_scene_without_refresh_reuses_every_pixel() {
    let mut opts = options(&[0], &[4]);
    opts.reconstructions = CacheRead::ALL.to_vec();
    let Some((_, report, _)) = run(&marble_scene("", ""), opts) else {
        return;
    };
    assert_eq!(report.results.len(), Variant::CACHE.len() * 4);
    for row in &report.results {
        for (frame, stats) in row.frame_stats.iter().enumerate() {
            assert_eq!(
                stats.hit_rate, 1.0,
                "{} frame {frame}: {stats:?}",
                row.variant
            );
            assert_eq!(stats.miss_rate, 0.0);
            assert_eq!(stats.refresh_rate, 0.0);
        }
        // rgba16float holds the turbulence sum to 11 bits: at most one
        // step of the 8-bit output.
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{} {}",
            row.variant,
            row.max_abs_error
        );
        assert!(row.psnr > 45.0, "{} {}", row.variant, row.psnr);
    }
}

/// A camera cut resets the cache: a still sphere, no refresh, the camera
/// cutting at frame 3 to a view from 45° aside. Every variant reuses every
/// covered pixel before the cut, misses every one at the cut (the old
/// shot's values are never reprojected into the new one, although much of
/// the sphere is seen from both), and reuses every one again after.
#[test]
fn camera_cut_resets_the_cache() {
    let cut = "[[camera.cuts]]\nframe = 3\neye = [2.26, 0.3, 2.26]\n";
    let Some((_, report, _)) = run(&marble_scene("", cut), options(&[0], &[4])) else {
        return;
    };
    assert_eq!(report.results.len(), Variant::CACHE.len());
    for row in &report.results {
        let hits: Vec<f64> = row.frame_stats.iter().map(|s| s.hit_rate).collect();
        // The measured frames are 1 to 4, after one warm-up frame.
        assert_eq!(hits, [1.0, 1.0, 0.0, 1.0], "{}", row.variant);
    }
}

/// Δn = 1 recomputes every pixel every frame: each variant's image is the
/// reference's (differential test; an rgba32float cache so that three-pass,
/// which reads its payload back, loses nothing).
#[test]
fn refresh_period_one_equals_the_reference() {
    let mut opts = options(&[1], &[1]);
    opts.cache_formats = vec![CacheFormat::Rgba32float];
    opts.reconstructions = CacheRead::ALL.to_vec();
    let Some((_, report, _)) = run(
        &marble_scene("\"object-motion\", \"camera-motion\"", ""),
        opts,
    ) else {
        return;
    };
    assert_eq!(report.results.len(), Variant::CACHE.len() * 4);
    for row in &report.results {
        assert_eq!(row.hit_rate, 0.0, "{}", row.variant);
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{} {}",
            row.variant,
            row.max_abs_error
        );
        assert!(row.above_threshold == 0.0, "{}", row.variant);
    }
}

/// Over Δn consecutive frames of a static scene each pixel is refreshed
/// exactly once, so the mean refresh fraction is 1/Δn for any block size.
#[test]
fn refresh_fraction_is_one_over_the_period() {
    let mut opts = options(&[8], &[1, 2, 4]);
    opts.variants = vec![Variant::ThreePass];
    opts.frames = Some(8);
    let Some((_, report, _)) = run(&marble_scene("", ""), opts) else {
        return;
    };
    assert_eq!(report.results.len(), 3);
    for row in &report.results {
        assert!(
            (row.refresh_rate - 1.0 / 8.0).abs() < 0.002,
            "k = {}: refresh {}",
            row.refresh_quad,
            row.refresh_rate
        );
        assert!(((row.hit_rate + row.refresh_rate) - 1.0).abs() < 1e-9);
        // Per frame, the blocks due are a random share around 1/Δn.
        for stats in &row.frame_stats {
            assert!(
                stats.refresh_rate < 0.3,
                "k = {}: {:?}",
                row.refresh_quad,
                stats
            );
        }
    }
}

/// A cube sliding over a plane uncovers a band of the plane each frame:
/// those pixels, and only those (give or take a pixel at the edges, and the
/// cube's own newly seen sides), miss.
#[test]
fn sliding_cube_misses_exactly_at_the_disoccluded_band() {
    let scene_text = r#"
size = [128, 128]
frames = 1
warmup = 1
effects = ["object-motion", "disocclusion"]
[camera]
eye = [0.0, 40.0, 0.01]
target = [0.0, 0.0, 0.0]
fov_degrees = 8.0
near = 30.0
far = 50.0
[[objects]]
mesh = { kind = "plane", size = 8.0, subdivisions = 8 }
[[objects]]
mesh = { kind = "cube", size = 1.5 }
position = [-0.6, 0.75, 0.0]
translation_per_frame = [0.4, 0.0, 0.0]
[uniforms]
marble_frequency = 4.0
turbulence_amount = 6.0
light_color = [1.0, 1.0, 1.0]
"#;
    let mut opts = options(&[0], &[4]);
    opts.variants = vec![Variant::ThreePass];
    // Every reconstruction: the packed ones test the depth filtered from
    // the payload's fourth channel instead of last frame's depth buffer.
    opts.reconstructions = CacheRead::ALL.to_vec();
    let Some((pictures, report, scene)) = run(scene_text, opts) else {
        return;
    };
    assert_eq!(report.results.len(), 4);
    let (w, h) = (128usize, 128usize);

    // The cube's silhouette in frames 0 and 1, rasterised on the CPU at
    // pixel centres with the same matrices.
    let silhouette = |frame: u32| super::util::silhouette(&scene, 1, frame, w, h);
    let (before, now) = (silhouette(0), silhouette(1));
    let band: Vec<bool> = (0..w * h).map(|i| before[i] && !now[i]).collect();
    let near = |mask: &[bool], i: usize| super::util::near(mask, w, i);
    let band_interior = super::util::interior(&band, w);
    let band_pixels = band.iter().filter(|&&b| b).count();
    assert!(band_pixels > 100, "the band is {band_pixels} pixels");
    for (row, (_, classes)) in report.results.iter().zip(&pictures.results) {
        let miss = |i: usize| classes[i * 4] == 255 && classes[i * 4 + 2] == 0;
        let mut unmissed = 0;
        let mut stray = 0;
        for (i, &in_band) in band_interior.iter().enumerate() {
            if in_band && !miss(i) {
                unmissed += 1;
            }
            if miss(i) && !near(&band, i) && !near(&now, i) {
                stray += 1;
            }
        }
        let how = row.reconstruction.as_str();
        assert_eq!(
            unmissed, 0,
            "{how}: band pixels (one pixel in from its edge) that did not miss"
        );
        assert_eq!(stray, 0, "{how}: misses away from the band and the cube");
    }
}

/// With camera and object motion declared, the report says what each
/// causes alone; a deforming mesh, which the previous-frame uniforms cannot
/// describe, misses where a rigid one hits.
#[test]
fn misses_are_attributed_to_the_effects_that_cause_them() {
    let mut opts = options(&[0], &[4]);
    opts.variants = vec![Variant::TwoPass];
    // The light moves too, but moving it changes no geometry: alone, it
    // causes no miss — which the report shows only if each effect really
    // runs on its own.
    let scene = marble_scene(
        "\"object-motion\", \"camera-motion\", \"light-motion\"",
        "[light]\norbit_degrees_per_frame = 5.0\n",
    )
    .replace("[camera]\n", "[camera]\norbit_degrees_per_frame = 1.5\n");
    let Some((_, report, _)) = run(&scene, opts.clone()) else {
        return;
    };
    let effects: Vec<String> = report
        .miss_causes
        .iter()
        .map(|c| format!("{:?}", c.effect))
        .collect();
    assert_eq!(effects, ["ObjectMotion", "CameraMotion", "LightMotion"]);
    for cause in &report.miss_causes[..2] {
        assert!(cause.miss_rate > 0.0 && cause.miss_rate < 0.2, "{cause:?}");
    }
    assert_eq!(
        report.miss_causes[2].miss_rate, 0.0,
        "{:?}",
        report.miss_causes[2]
    );

    let rigid = marble_scene("", "");
    let deforming = marble_scene("\"deformation\"", "")
        .replace("rotation_degrees_per_frame", "deformation = { amplitude = 0.04, frequency = 8.0, speed = 0.5 }\nrotation_degrees_per_frame");
    let Some((_, still, _)) = run(&rigid, opts.clone()) else {
        return;
    };
    let Some((_, rippling, _)) = run(&deforming, opts) else {
        return;
    };
    assert_eq!(still.results[0].miss_rate, 0.0);
    assert!(
        rippling.results[0].miss_rate > 0.01,
        "{}",
        rippling.results[0].miss_rate
    );
    assert!(rippling.miss_causes[0].disocclusion_rate > 0.01);
}

/// A shader whose payload is not finite on part of the object: `PAYLOAD`
/// is replaced by the node's expression, `SHADE` by the colour from it.
fn non_finite_shader(payload: &str, shade: &str) -> String {
    format!(
        r#"
struct Frame {{
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}}
@group(0) @binding(0) var<uniform> frame: Frame;
struct VertexOutput {{
    @builtin(position) clip_position: vec4<f32>,
    @location(0) local: vec3<f32>,
}}
@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {{
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * (frame.world_from_local * vec4<f32>(position, 1.0));
    out.local = position;
    return out;
}}
@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {{
    let payload = {payload};
    let shade = {shade};
    return vec4<f32>(shade, 0.5 * shade, 0.2, 1.0);
}}
"#
    )
}

fn rotating_sphere() -> String {
    r#"
size = [128, 128]
frames = 6
warmup = 2
effects = ["object-motion"]
[camera]
eye = [0.0, 0.3, 3.2]
[[objects]]
mesh = { kind = "sphere", rings = 32, segments = 48 }
rotation_degrees_per_frame = [0.0, 2.0, 0.0]
"#
    .to_string()
}

fn non_finite_options(node_text: &str, shader: &str, format: CacheFormat) -> Options {
    let (_, analysis) = super::util::analyzed("test.wgsl", shader);
    let id = super::util::candidate(&analysis, node_text).node.id.clone();
    Options {
        nodes: Nodes::Ids(vec![id]),
        cache_formats: vec![format],
        // The scene's own two warm-up frames, not a refresh period's: the
        // sphere turns 2° a frame, and the share of the non-finite half in
        // view depends on how far it has turned (at 64°, nearly all).
        warmup: Some(2),
        variants: Variant::CACHE.to_vec(),
        ..Options::default()
    }
}

/// The same, with every reconstruction: the packed ones read payload and
/// depth together, and must keep non-finite payloads from spreading too.
fn non_finite_options_all(node_text: &str, shader: &str, format: CacheFormat) -> Options {
    Options {
        reconstructions: CacheRead::ALL.to_vec(),
        ..non_finite_options(node_text, shader, format)
    }
}

/// NaN payloads (sqrt of a negative) must not spread to the neighbours
/// whose bilinear footprint touches them, nor outlive a refresh: a
/// non-finite reconstruction is a miss, so the image stays the reference's.
#[test]
fn nan_payload_does_not_spread() {
    // NaN on the half x < 0, a gentle ramp on the other half.
    let node = "select(0.5 + (0.3 * in.local.y), sqrt(-1.0 - (in.local.y * in.local.y)), in.local.x < 0.0)";
    let shader = non_finite_shader(node, "clamp(payload, 0.0, 1.0)");
    let options = non_finite_options_all(node, &shader, CacheFormat::Rgba16float);
    let Some((_, report, _)) = run_shader(&shader, &rotating_sphere(), options) else {
        return;
    };
    assert_contained(&report, 0.1);
    for row in &report.results {
        assert!(
            row.hit_rate > 0.3,
            "{} {}: the finite half is reused: {}",
            row.variant,
            row.reconstruction.as_str(),
            row.hit_rate
        );
    }
}

/// Every variant with every reconstruction detects the non-finite
/// payloads (more than `detected` of the pixels read one back and miss),
/// and a bilinear read never spreads them: a NaN or ∞ read by a neighbour
/// would shade it far from the reference, so only the cache's ordinary
/// resampling error remains. (Nearest reads one texel, so a non-finite
/// value cannot reach a finite pixel; it may give a non-finite pixel its
/// finite neighbour's value, where the reference shows whatever clamp(NaN)
/// gives: not an error of the cache.)
fn assert_contained(report: &crate::report::Report, detected: f64) {
    assert_eq!(report.results.len(), Variant::CACHE.len() * 4);
    for row in &report.results {
        let what = format!("{} {}", row.variant, row.reconstruction.as_str());
        assert!(row.invalid_rate > detected, "{what}: {}", row.invalid_rate);
        let one_texel = matches!(
            row.reconstruction,
            Reconstruction::Nearest | Reconstruction::NearestPacked
        );
        assert!(
            one_texel || row.max_abs_error < 0.05,
            "{what}: {}",
            row.max_abs_error
        );
    }
}

/// Infinite payloads likewise: bilinear weights would turn them into
/// infinities and NaNs (0 · ∞) at the neighbours.
#[test]
fn inf_payload_does_not_spread() {
    // Infinite (exp overflows) on the side x > 0.5, a gentle ramp elsewhere.
    let node = "(0.3 + (0.2 * in.local.y)) * exp(select(0.0, 200.0, in.local.x > 0.5))";
    let shader = non_finite_shader(node, "select(clamp(payload, 0.0, 1.0), 0.9, payload > 1.0)");
    let options = non_finite_options_all(node, &shader, CacheFormat::Rgba32float);
    let Some((_, report, _)) = run_shader(&shader, &rotating_sphere(), options) else {
        return;
    };
    assert_contained(&report, 0.01);
}

/// A payload beyond the range of an rgba16float cache is written as NaN,
/// so reading it back is a miss and one- and two-pass recompute it: the
/// image stays correct, at the cost of the reuse of those pixels, which an
/// rgba32float cache keeps. Three-pass shades from the cache texel itself,
/// so an overflowing payload cannot be right there with rgba16float: it is
/// detected, and such a node needs an rgba32float cache.
#[test]
fn f16_overflow_is_recomputed_not_reused() {
    let node = "exp(in.local.x * 40.0)";
    let shader = non_finite_shader(node, "clamp(log(payload) / 40.0, 0.0, 1.0)");
    let half = non_finite_options(node, &shader, CacheFormat::Rgba16float);
    let full = non_finite_options(node, &shader, CacheFormat::Rgba32float);
    let Some((_, narrow, _)) = run_shader(&shader, &rotating_sphere(), half) else {
        return;
    };
    let Some((_, wide, _)) = run_shader(&shader, &rotating_sphere(), full) else {
        return;
    };
    for variant in Variant::CACHE {
        let narrow = narrow
            .results
            .iter()
            .find(|r| r.variant == variant)
            .unwrap();
        let wide = wide.results.iter().find(|r| r.variant == variant).unwrap();
        assert_eq!(wide.invalid_rate, 0.0, "{variant}");
        if matches!(variant, Variant::ThreePass | Variant::Deferred) {
            // Three-pass (and deferred, its passes in screen space) shades
            // from the cached value, so it cannot recompute: the analysis cannot bound exp() below 65504, and
            // the rewrite keeps this cache in rgba32float.
            assert_eq!(narrow.cache_format, CacheFormat::Rgba32float);
            assert_eq!(narrow.invalid_rate, 0.0);
            assert!(
                (narrow.max_abs_error - wide.max_abs_error).abs() <= 0.02,
                "{variant}: {} against {}",
                narrow.max_abs_error,
                wide.max_abs_error
            );
            continue;
        }
        // exp(40 x) exceeds 65504 where x > 0.28: a good part of the sphere.
        assert!(
            narrow.invalid_rate > 0.05,
            "{variant}: {}",
            narrow.invalid_rate
        );
        // One- and two-pass recompute the overflowing pixels: the f16 cache
        // is no worse than the f32 one (whose own error is the ordinary
        // resampling of a steep exponential). Blending the saturated
        // 65504s into their neighbours would be far worse.
        assert!(
            narrow.max_abs_error <= wide.max_abs_error + 0.02,
            "{variant}: rgba16float {} against rgba32float {}",
            narrow.max_abs_error,
            wide.max_abs_error
        );
    }
}

/// Errors are measured in the cache's steady state: by default the
/// warm-up is at least the longest refresh period, so each pixel has been
/// recomputed before the first measured frame. A shorter `warmup` given
/// explicitly is kept, and the report says its errors are a younger
/// cache's.
#[test]
fn the_warm_up_covers_the_longest_refresh_period() {
    let mut opts = options(&[4, 12], &[4]);
    opts.variants = vec![Variant::TwoPass];
    opts.frames = Some(1);
    let Some((_, report, scene)) = run(&marble_scene("\"object-motion\"", ""), opts.clone()) else {
        return;
    };
    assert_eq!(scene.warmup, 1);
    assert_eq!(report.warmup, 12);
    assert!(report.steady_state);
    // Three frames: the measured frame's cache is younger than a period.
    opts.warmup = Some(3);
    let (_, report, _) = run(&marble_scene("\"object-motion\"", ""), opts).unwrap();
    assert_eq!(report.warmup, 3);
    assert!(!report.steady_state);
}

/// The marble's colour reads `light_color`, a uniform: the shader alone
/// cannot bound it, but the scene gives its value, so the profiler knows
/// the colour stays within [0, 1.5] and its three-pass cache runs in
/// rgba16float. A light bright enough to overflow f16 widens it again.
#[test]
fn scene_uniform_values_bound_the_payload_range() {
    let colour = "n5c3eb6af"; // (ambient_light * albedo) + direct
    let three_pass = || Options {
        nodes: Nodes::Ids(vec![colour.into()]),
        variants: vec![Variant::ThreePass],
        frames: Some(2),
        ..Options::default()
    };
    let scene = marble_scene("\"object-motion\"", "");
    let Some((_, report, _)) = run(&scene, three_pass()) else {
        return;
    };
    let node = &report.nodes[0];
    assert!(node.fits_f16, "{:?}", node.range);
    assert!(node.range[1].is_some_and(|hi| hi < 1.5), "{:?}", node.range);
    assert_eq!(report.results[0].cache_format, CacheFormat::Rgba16float);

    let bright = scene.replace(
        "light_color = [1.0, 1.0, 1.0]",
        "light_color = [1.0e5, 1.0, 1.0]",
    );
    assert_ne!(bright, scene);
    let (_, report, _) = run(&bright, three_pass()).unwrap();
    assert!(!report.nodes[0].fits_f16, "{:?}", report.nodes[0].range);
    assert_eq!(report.results[0].cache_format, CacheFormat::Rgba32float);
}

/// A module whose vertex stage draws the mesh with one camera matrix and
/// passes the local position on, with `$fragment` after it.
macro_rules! with_camera_vertex {
    ($fragment:literal) => {
        concat!(
            r#"
struct Camera {
    clip_from_world: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> camera: Camera;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) local_position: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = camera.clip_from_world * vec4<f32>(position, 1.0);
    out.local_position = position;
    return out;
}
"#,
            $fragment
        )
    };
}

/// A camera looking away from the sphere: the measured frames cover no
/// pixels, and the report says so rather than give 100 dB for an empty
/// frame.
#[test]
fn empty_view_is_reported() {
    let scene = marble_scene("", "").replace(
        "eye = [0.0, 0.3, 3.2]",
        "eye = [0.0, 0.3, 3.2]\ntarget = [0.0, 0.3, 10.0]",
    );
    let Some((_, report, _)) = run(&scene, options(&[8], &[2])) else {
        return;
    };
    assert!(report.results.iter().all(|r| r.coverage == 0.0));
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("cover no pixels")),
        "{:?}",
        report.warnings
    );
    let choice = report.choice.unwrap();
    assert_eq!(choice.result, None);
}

/// An object the warm-up carries across the screen: the measured frames
/// show another view than frame 0, and the report says so.
#[test]
fn a_warmup_that_moves_the_scene_away_is_reported() {
    let scene = marble_scene("\"object-motion\"", "")
        .replace("warmup = 1", "warmup = 30")
        .replace(
            "rotation_degrees_per_frame = [0.0, 0.6, 0.0]",
            "rotation_degrees_per_frame = [0.0, 0.6, 0.0]\ntranslation_per_frame = [0.05, 0.0, 0.0]",
        );
    let Some((_, report, _)) = run(&scene, options(&[8], &[2])) else {
        return;
    };
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("warm-up frames moved object 0")),
        "{:?}",
        report.warnings
    );
    // A still scene has nothing to warn about.
    let Some((_, still, _)) = run(&marble_scene("", ""), options(&[8], &[2])) else {
        return;
    };
    assert!(still.warnings.is_empty(), "{:?}", still.warnings);
    assert!(still.results.iter().all(|r| r.coverage > 0.1));
}

/// A cheap node under a costly shade: whatever the cache saves, the shade
/// still runs, so the variant's time is far above its fixed cost.
const COSTLY_SHADE: &str = with_camera_vertex!(
    r#"
@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let base = sin(in.local_position.x * 3.0) + cos(in.local_position.y * 2.0);
    var shade = 0.0;
    for (var i = 0; i < 300; i++) {
        shade += sin(base * (1.0 + f32(i) * 0.01)) / 300.0;
    }
    return vec4<f32>(vec3<f32>(0.5 + 0.5 * shade), 1.0);
}
"#
);

/// The fixed cost of each pass is measured with the payload and the shade
/// made free, and the bound a variant's fixed costs allow is the
/// reference's time over them.
#[test]
fn fixed_cost_bound_is_the_reference_over_the_fixed_cost() {
    let shader = crate::front::parse(crate::diagnostic::SourceFile::new(
        "costly_shade.wgsl",
        COSTLY_SHADE,
    ))
    .unwrap();
    let base = crate::analysis::analyze(&shader, &Default::default())
        .unwrap()
        .candidates
        .iter()
        .find(|c| c.node.text == "sin(in.local_position.x * 3.0) + cos(in.local_position.y * 2.0)")
        .unwrap()
        .node
        .id
        .clone();
    if super::gpu::gpu().is_none() {
        return;
    }
    let scene = Scene::default_for(&shader, None, None).unwrap();
    let options = Options {
        nodes: Nodes::Ids(vec![base]),
        frames: Some(4),
        warmup: Some(4),
        size: Some([64, 64]),
        variants: Variant::CACHE.to_vec(),
        ..Options::default()
    };
    let (report, _) = profile::profile(
        &shader,
        &scene,
        std::path::Path::new("default scene"),
        &options,
        &mut Quiet,
    )
    .unwrap();
    assert_eq!(report.results.len(), Variant::CACHE.len());
    assert!(report.reference.fixed_ms > 0.0);
    for row in &report.results {
        let fixed: f64 = row.fixed_cost_ms.iter().map(|p| p.time_ms).sum();
        assert_eq!(row.fixed_cost_ms.len(), row.passes.len(), "{}", row.variant);
        assert!(fixed > 0.0);
        // The bound is the reference's time over the passes' fixed cost.
        // That the measured speed-up stays under it compares two timed
        // runs: docs/results.md measures it, no test asserts it.
        assert!((row.bound_with_fixed_costs - report.reference.time_ms / fixed).abs() < 1e-9);
    }
}

/// P/T is measured net of the payload pass's fixed cost, over the
/// reference, and nothing clamps it; the ideal speed-up follows from it.
/// (That it stays at most 1 for a node that is the whole colour is a
/// timing, measured in docs/results.md, not asserted here.)
#[test]
fn p_over_t_is_measured_net_of_the_fixed_cost() {
    let mut opts = options(&[8], &[2]);
    opts.nodes = Nodes::Top(1);
    opts.variants = vec![Variant::OnePass];
    let Some((_, report, _)) = run(&marble_scene("\"object-motion\"", ""), opts) else {
        return;
    };
    let node = &report.nodes[0];
    assert!(node.payload_fixed_ms > 0.0 && node.payload_ms > 0.0);
    // Net of the fixed cost, over the reference.
    let net = (node.payload_ms - node.payload_fixed_ms) / report.reference.time_ms;
    assert!((node.p_over_t - net).abs() < 1e-9);
    let row = &report.results[0];
    // Measured, P/T can exceed 1 / hit rate (the timings are noisy, and
    // nothing clamps P/T): the bound's denominator is kept positive.
    let expected = 1.0 / (1.0 - row.hit_rate * node.p_over_t).max(1e-6);
    assert!(
        (row.ideal_speedup - expected).abs() < 1e-9,
        "ideal {} against {expected} (hit rate {}, P/T {})",
        row.ideal_speedup,
        row.hit_rate,
        node.p_over_t
    );
}

/// The error is taken over the pixels the shader draws, with the whole
/// frame's figure beside it; the worst frame and the flicker are there
/// too. A still scene without refresh never flickers.
#[test]
fn error_over_covered_pixels() {
    let Some((_, report, _)) = run(
        &marble_scene("\"object-motion\", \"camera-motion\"", ""),
        options(&[4], &[2]),
    ) else {
        return;
    };
    for row in &report.results {
        assert!(row.psnr < 100.0, "{}: {}", row.variant, row.psnr);
        // The exact background only raises the whole-frame figure.
        assert!(row.psnr <= row.psnr_frame + 1e-9, "{row:?}");
        assert!(row.psnr_frame - row.psnr > 0.5, "{row:?}");
        assert!(row.worst_psnr <= row.psnr + 1e-9);
        assert!(row.flicker > 0.0 && row.flicker < 1.0);
    }
    let Some((_, still, _)) = run(&marble_scene("", ""), options(&[0], &[2])) else {
        return;
    };
    for row in &still.results {
        assert!(row.flicker < 1e-3, "{}: {}", row.variant, row.flicker);
    }
}

/// Frames are compared in linear float: a shader whose every covered value
/// is above 1 (an HDR target's highlights) has its cache error measured,
/// where 8-bit frames would clamp both the reference and the variant to
/// 255 and report them equal (PSNR 100, no error: what this test measured
/// before frames were read back as rgba16float).
#[test]
fn hdr_values_above_one_are_measured() {
    let marble = std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap();
    let bright = marble.replace(
        "return vec4<f32>(color, 1.0);",
        "return vec4<f32>((color * 4.0) + vec3<f32>(2.0), 1.0);",
    );
    assert_ne!(bright, marble);
    let Some((pictures, report, _)) = run_shader(
        &bright,
        &marble_scene("\"object-motion\"", ""),
        options(&[4], &[2]),
    ) else {
        return;
    };
    // The pictures are 8-bit: every covered pixel there is white.
    let (_, classes) = &pictures.results[0];
    for p in 0..pictures.reference.len() / 4 {
        if classes[p * 4 + 3] > 0 {
            assert_eq!(&pictures.reference[p * 4..p * 4 + 3], &[255, 255, 255]);
        }
    }
    for row in &report.results {
        assert!(row.psnr < 60.0, "{}: PSNR {}", row.variant, row.psnr);
        assert!(
            row.max_abs_error > 1.0 / 255.0,
            "{}: {}",
            row.variant,
            row.max_abs_error
        );
    }
}

/// A PCF shadow shader's depth texture gets a shadow map rendered from the
/// scene's light each frame: under a sphere lit from above, the floor is
/// in shadow, and beside it lit. With the far-plane map (`generate =
/// "far"`, what every depth texture got before) the same point is lit,
/// and the shader's shadows were never measured.
#[test]
fn shadow_map_is_rendered_from_the_light() {
    let shader = std::fs::read_to_string(root().join("corpus/shadow_pcf.wgsl")).unwrap();
    let scene = |pattern: &str| {
        format!(
            r#"
size = [96, 96]
frames = 1
warmup = 0
[camera]
eye = [0.0, 3.0, 3.0]
target = [0.0, 0.0, 0.0]
[light]
position = [0.0, 6.0, 0.1]
[[objects]]
mesh = {{ kind = "sphere", radius = 0.5 }}
position = [0.0, 1.0, 0.0]
[[objects]]
mesh = {{ kind = "plane", size = 4.0, subdivisions = 4 }}
[uniforms]
shadow_bias = 0.002
pcf_spread = 1.0
albedo = [0.8, 0.8, 0.8]
ambient = 0.05
light_color = [1.0, 1.0, 1.0]
[textures.shadow_map]
generate = "{pattern}"
"#
        )
    };
    let options = || Options {
        nodes: Nodes::Top(1),
        variants: vec![Variant::OnePass],
        refresh_periods: vec![8],
        ..Options::default()
    };
    let Some((shadowed, _, scene_read)) = run_shader(&shader, &scene("shadow-map"), options())
    else {
        return;
    };
    let Some((unshadowed, _, _)) = run_shader(&shader, &scene("far"), options()) else {
        return;
    };
    let state = scene_read.frame(0, 1.0);
    let luminance = |picture: &[u8], world: glam::Vec3| {
        let clip = state.clip_from_world * world.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let x = ((ndc.x * 0.5 + 0.5) * 96.0) as usize;
        let y = ((0.5 - ndc.y * 0.5) * 96.0) as usize;
        let at = (y * 96 + x) * 4;
        picture[at..at + 3]
            .iter()
            .map(|&c| f64::from(c))
            .sum::<f64>()
            / 3.0
    };
    let under = glam::Vec3::new(0.0, 0.0, 0.0);
    let beside = glam::Vec3::new(1.2, 0.0, -0.5);
    let (dark, lit) = (
        luminance(&shadowed.reference, under),
        luminance(&shadowed.reference, beside),
    );
    assert!(lit > 60.0, "the floor beside the sphere is lit: {lit}");
    assert!(dark < 0.5 * lit, "under the sphere {dark}, beside it {lit}");
    let far = luminance(&unshadowed.reference, under);
    assert!(
        far > 0.9 * lit,
        "with the far-plane map it is lit: {far} against {lit}"
    );
}

/// A mesh the application deforms on the CPU (a ripple written into the
/// vertex buffer each frame): the position input gets a previous-frame
/// twin, which the host fills from last frame's copy of the vertex buffer,
/// so the surface reprojects to where it was and hits. Measured on
/// lavapipe: 3.3% of the frame misses (the rim, where the ripple uncovers
/// surface) and PSNR is 37.8 dB; without the twin the position would be
/// this frame's seen through last frame's matrices, and 6.8% misses at
/// 34.8 dB.
#[test]
fn deformed_vertices_reproject_with_last_frames_vertex_buffer() {
    let scene = marble_scene("\"deformation\"", "").replace(
        "rotation_degrees_per_frame",
        "deformation = { amplitude = 0.04, frequency = 8.0, speed = 0.5 }\nrotation_degrees_per_frame",
    );
    let options = Options {
        nodes: Nodes::Ids(vec!["nb0c12cc4".into()]),
        variants: vec![Variant::ThreePass],
        refresh_periods: vec![0],
        refresh_quads: vec![1],
        ..Options::default()
    };
    let Some((_, report, _)) = run(&scene, options) else {
        return;
    };
    let row = &report.results[0];
    assert!(row.miss_rate < 0.05, "miss rate {}", row.miss_rate);
    assert!(row.psnr >= 36.5, "PSNR {} dB", row.psnr);
}

/// Adaptive refresh (`--adaptive-refresh`) under a light orbiting 4° a
/// frame, for the lit colour: a value that changed by 10% since it was
/// cached is refreshed again after Δn/4 frames (its age starts at ¾Δn), so
/// every cache variant follows the light more closely than with a fixed
/// Δn = 32 (on 128² here 32.2 against 25.8 dB), for twice the refreshes.
#[test]
fn adaptive_refresh_follows_a_changing_value() {
    let scene = marble_scene(
        "\"light-motion\"",
        "[light]\nposition = [3.0, 4.0, 2.5]\norbit_degrees_per_frame = 4.0",
    )
    .replace("rotation_degrees_per_frame = [0.0, 0.6, 0.0]\n", "");
    let options = Options {
        nodes: Nodes::Ids(vec!["n5c3eb6af".into()]),
        variants: Variant::CACHE.to_vec(),
        adaptive_refresh: vec![false, true],
        warmup: Some(32),
        frames: Some(4),
        ..Options::default()
    };
    let Some((_, report, _)) = run(&scene, options) else {
        return;
    };
    assert_eq!(report.results.len(), 2 * Variant::CACHE.len());
    for variant in Variant::CACHE {
        let row = |adaptive: bool| {
            report
                .results
                .iter()
                .find(|r| r.variant == variant && r.adaptive == adaptive)
                .unwrap()
        };
        let (fixed, adaptive) = (row(false), row(true));
        assert!(
            adaptive.psnr > fixed.psnr + 3.0,
            "{variant}: adaptive {} dB, fixed {} dB",
            adaptive.psnr,
            fixed.psnr
        );
        assert!(adaptive.refresh_rate > fixed.refresh_rate);
    }
}
