//! The deferred variant: one geometry pass into a G-buffer, the lookup,
//! the misses and the shading in screen space, per draw (docs/rewrite.md).

use crate::profile::{Nodes, Options};
use crate::rewrite::{self, CacheFormat, CacheRead, Variant};

use super::profile::{options, run_shader};
use super::util::{analyzed, interior, root, silhouette};

/// The marble shader with its colour tinted by the object's height, read
/// in the fragment stage from the per-object uniform (its model matrix),
/// as engines read a per-object tint or material: a screen-space pass
/// that shades one draw's pixels with another draw's bind groups tints
/// them wrong.
fn tinted_marble() -> String {
    let marble = std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap();
    let tinted = marble.replace(
        "return vec4<f32>(color, 1.0);",
        "return vec4<f32>(color * (0.5 + 0.3 * frame.world_from_local[3].y), 1.0);",
    );
    assert_ne!(tinted, marble, "the marble shader's return changed");
    tinted
}

/// Profiles [`tinted_marble`]'s turbulence (the node the marble tests
/// cache) on `scene` with `options`.
fn run_tinted(
    scene: &str,
    mut options: Options,
) -> Option<(
    crate::profile::Pictures,
    crate::report::Report,
    crate::scene::Scene,
)> {
    let source = tinted_marble();
    let (_, analysis) = analyzed("tinted_marble.wgsl", &source);
    let turbulence =
        super::util::candidate(&analysis, "s4 + (0.0625 * abs(gradient_noise(p * 16.0)))");
    options.nodes = Nodes::Ids(vec![turbulence.node.id.clone()]);
    run_shader(&source, scene, options)
}

/// Two objects with their own model matrices (a marble sphere over a
/// marble floor, [`tinted_marble`] tinting each by its height), so that a
/// screen-space pass shading one draw's pixels with another draw's bind
/// groups would show; `effects`, `camera` and `sphere` (TOML lines) set
/// the motion.
fn sphere_over_floor(effects: &str, camera: &str, sphere: &str) -> String {
    super::util::sphere_over_floor(
        "size = [128, 128]\nframes = 3\nwarmup = 1",
        effects,
        camera,
        sphere,
    )
}

/// Δn = 1 recomputes every pixel every frame: the deferred variant's
/// image is the reference's, for every reconstruction, with a moving
/// camera and a moving object (differential test). The screen-space passes
/// rebuild the fragment inputs bit for bit from the G-buffer and shade each
/// pixel with its own draw's bind groups (the stencil's ordinal): a lossy
/// G-buffer puts the marble in the wrong place, and a draw shading
/// another's pixels tints them with the other object's height (checked:
/// with the screen-space passes' stencil test set to `always`, so that
/// every draw shades every pixel, this and the next two tests fail).
#[test]
fn deferred_refresh_period_one_equals_the_reference() {
    let mut opts = options(&[1], &[1]);
    opts.variants = vec![Variant::Deferred];
    opts.cache_formats = vec![CacheFormat::Rgba32float];
    opts.reconstructions = CacheRead::ALL.to_vec();
    let scene = sphere_over_floor(
        "\"object-motion\", \"camera-motion\"",
        "orbit_degrees_per_frame = 1.0",
        "rotation_degrees_per_frame = [0.0, 2.0, 0.0]\ntranslation_per_frame = [0.05, 0.0, 0.0]",
    );
    let Some((_, report, _)) = run_tinted(&scene, opts) else {
        return;
    };
    assert_eq!(report.results.len(), 4);
    for row in &report.results {
        let what = row.reconstruction.as_str();
        assert_eq!(row.hit_rate, 0.0, "{what}");
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{what}: {}",
            row.max_abs_error
        );
        assert_eq!(row.above_threshold, 0.0, "{what}");
    }
}

/// A static scene with refresh off: after the first frame every covered
/// pixel of both draws is reused, and the image is the reference's within
/// the cache format's step. The values shown age frame after frame, which
/// they do only if the miss pass runs nowhere: it writes age 0 where it
/// runs (checked: without the lookup's stencil mark, the miss pass
/// recomputes every pixel, the oldest value shown is 0 frames old and
/// this fails).
#[test]
fn deferred_static_scene_reuses_every_pixel() {
    let mut opts = options(&[0], &[4]);
    opts.variants = vec![Variant::Deferred];
    opts.reconstructions = CacheRead::ALL.to_vec();
    let Some((_, report, _)) = run_tinted(&sphere_over_floor("", "", ""), opts) else {
        return;
    };
    assert_eq!(report.results.len(), 4);
    for row in &report.results {
        let what = row.reconstruction.as_str();
        for (frame, stats) in row.frame_stats.iter().enumerate() {
            assert_eq!(stats.hit_rate, 1.0, "{what} frame {frame}: {stats:?}");
            assert_eq!(stats.miss_rate, 0.0, "{what} frame {frame}");
        }
        assert!(row.max_age >= 2, "{what}: oldest value {}", row.max_age);
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{what}: {}",
            row.max_abs_error
        );
    }
}

/// `fwidth` and `dpdx`/`dpdy` in the screen-space passes are taken of the
/// inputs rebuilt from the G-buffer, across the screen's 2×2 quads. On a
/// plane seen in perspective (every varying the same function across its
/// triangles, its outline the only edge), inside
/// the plane a quad's pixels hold one surface's values, as the original's
/// quad does, and the image equals the reference (Δn = 1, rgba32float:
/// within one 8-bit step). At the silhouette a quad straddles the plane
/// and the background (or the plane's far side), where the original
/// extrapolated its own triangle with helper invocations: the faceted
/// normal and the grid's filter width differ there, and the test bounds
/// that (measured: the interior exactly equal, 28 of the 395 outline
/// pixels more than one step off). Fails when the derivatives see
/// anything but the G-buffer's exact values (a lossy G-buffer changes the
/// interior too) or are taken after the screen pass discards.
#[test]
fn deferred_derivatives_match_in_the_interior() {
    let source = std::fs::read_to_string(root().join("corpus/derivatives_fwidth.wgsl")).unwrap();
    let scene = r#"
size = [128, 128]
frames = 1
warmup = 1
effects = ["object-motion"]
[camera]
eye = [0.0, 1.2, 3.0]
target = [0.0, 0.0, 0.0]
[[objects]]
mesh = { kind = "plane", size = 2.4, subdivisions = 4 }
rotation_degrees = [50.0, 20.0, 0.0]
rotation_degrees_per_frame = [0.0, 0.5, 0.0]
[uniforms]
grid_scale = 12.0
line_width = 1.2
light_color = [1.0, 0.97, 0.92]
"#;
    let (_, analysis) = analyzed("derivatives_fwidth.wgsl", &source);
    // The top candidate: the lit colour, whose payload takes the faceted
    // normal from dpdx/dpdy and the grid's filter width from fwidth.
    let node = analysis.candidates[0].node.id.clone();
    let opts = Options {
        nodes: Nodes::Ids(vec![node]),
        variants: vec![Variant::Deferred],
        refresh_periods: vec![1],
        refresh_quads: vec![1],
        cache_formats: vec![CacheFormat::Rgba32float],
        reconstructions: vec![CacheRead::Bilinear],
        ..Options::default()
    };
    let Some((pictures, report, scene)) = run_shader(&source, scene, opts) else {
        return;
    };
    let (w, h) = (128, 128);
    let covered = silhouette(&scene, 0, 1, w, h);
    let inside = interior(&covered, w);
    let image = &pictures.results[0].0;
    let reference = &pictures.reference;
    let difference = |i: usize| {
        (0..3)
            .map(|c| image[i * 4 + c].abs_diff(reference[i * 4 + c]))
            .max()
            .unwrap_or(0)
    };
    let interior_worst = (0..w * h)
        .filter(|&i| inside[i])
        .map(difference)
        .max()
        .unwrap_or(0);
    assert!(
        interior_worst <= 1,
        "inside the plane the deferred image is the reference's: worst {interior_worst}/255"
    );
    let edge: Vec<usize> = (0..w * h).filter(|&i| covered[i] && !inside[i]).collect();
    let off = edge.iter().filter(|&&i| difference(i) > 1).count();
    let share = off as f64 / edge.len() as f64;
    eprintln!(
        "interior worst {interior_worst}/255; silhouette: {off} of {} differ",
        edge.len()
    );
    assert!(
        !edge.is_empty() && share < 0.25,
        "at the silhouette ({} pixels) {off} differ from the reference",
        edge.len()
    );
    assert!(report.results[0].psnr > 30.0, "{}", report.results[0].psnr);
}

/// Inputs beyond what eight colour targets of four words hold cannot go
/// through a G-buffer: the variant is refused, naming the words it would
/// need, and the other variants of the same shader are built.
#[test]
fn deferred_g_buffer_too_large_is_refused() {
    let source = r#"
struct Globals { view_projection: mat4x4<f32>, time: f32 }
@group(0) @binding(0) var<uniform> globals: Globals;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) a: vec4<f32>,
    @location(1) b: vec4<f32>,
    @location(2) c: vec4<f32>,
    @location(3) d: vec4<f32>,
    @location(4) e: vec4<f32>,
    @location(5) f: vec4<f32>,
    @location(6) g: vec4<f32>,
    @location(7) h: vec4<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> Varyings {
    let p = vec4<f32>(position, 1.0);
    return Varyings(globals.view_projection * p, p, p * 2.0, p * 3.0, p * 4.0, p * 5.0, p * 6.0, p * 7.0, p * 8.0);
}

@fragment
fn fs_main(in: Varyings) -> @location(0) vec4<f32> {
    let wave = sin(in.a * globals.time) + cos(in.b) + sin(in.c) + cos(in.d);
    let more = sin(in.e) + cos(in.f) + sin(in.g) + cos(in.h);
    return wave * more;
}
"#;
    let (shader, analysis) = analyzed("wide.wgsl", source);
    let candidate = analysis
        .candidates
        .iter()
        .find(|c| c.node.text.starts_with("sin(in.e)"))
        .unwrap_or_else(|| {
            panic!(
                "{:?}",
                analysis
                    .candidates
                    .iter()
                    .map(|c| &c.node.text)
                    .collect::<Vec<_>>()
            )
        });
    let options = rewrite::Options::default();
    let refusal = rewrite::rewrite(&shader, &analysis, candidate, Variant::Deferred, &options)
        .expect_err("eight vec4 varyings and the previous position exceed a G-buffer");
    assert!(!refusal.is_internal(), "{refusal}");
    assert!(
        refusal.reason.contains("35 words") && refusal.reason.contains("in.h.w"),
        "{refusal}"
    );
    for variant in [Variant::OnePass, Variant::TwoPass, Variant::ThreePass] {
        rewrite::rewrite(&shader, &analysis, candidate, variant, &options)
            .unwrap_or_else(|r| panic!("{variant}: {r}"));
    }
}

/// An alpha-tested leaf in front of another: the fragment stage discards
/// where the leaf texture is transparent, so which pixels the front leaf
/// covers, and so what the back leaf shows through its holes, is decided
/// by shading. The deferred geometry pass runs the payload and the shade
/// for their discards alone, so its depth and stencil hold the pixels the
/// original covers: at Δn = 1 the image is the reference's, for nodes
/// computed before the discard and after it (checked: without the
/// geometry pass's discards the front leaf's depth hides the back leaf
/// through its holes, and this fails).
#[test]
fn deferred_alpha_tested_cutout_equals_the_reference() {
    let source = std::fs::read_to_string(root().join("corpus/discard_cutout.wgsl")).unwrap();
    let scene = r#"
size = [128, 128]
frames = 2
warmup = 1
effects = ["object-motion"]
[camera]
eye = [0.0, 1.6, 2.2]
target = [0.0, 0.0, 0.0]
[[objects]]
mesh = { kind = "plane", size = 1.6, subdivisions = 16 }
rotation_degrees_per_frame = [0.0, 0.4, 0.0]
[[objects]]
mesh = { kind = "plane", size = 2.4, subdivisions = 4 }
position = [0.0, -0.4, 0.0]
[uniforms]
alpha_threshold = 0.5
translucency = 0.3
light_color = [1.0, 0.97, 0.92]
[textures.leaf_texture]
generate = "noise"
size = 256
"#;
    let (_, analysis) = analyzed("discard_cutout.wgsl", &source);
    let ids: Vec<String> = analysis
        .candidates
        .iter()
        .take(3)
        .map(|c| c.node.id.clone())
        .collect();
    let opts = Options {
        nodes: Nodes::Ids(ids),
        variants: vec![Variant::Deferred],
        refresh_periods: vec![1],
        refresh_quads: vec![1],
        cache_formats: vec![CacheFormat::Rgba32float],
        reconstructions: vec![CacheRead::Bilinear],
        ..Options::default()
    };
    let Some((_, report, _)) = run_shader(&source, scene, opts) else {
        return;
    };
    assert_eq!(report.results.len(), 3, "every node is built");
    for row in &report.results {
        assert!(row.coverage > 0.2, "{}: {}", row.node, row.coverage);
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{}: {}",
            row.node,
            row.max_abs_error
        );
    }
}
