//! The lowres variant: the payload shaded at 1/s × 1/s of the pixels on
//! a jittered lattice and rebuilt at full resolution (seed 001).

use crate::profile::Options;
use crate::rewrite::{CacheFormat, Upsampler, Variant};

use super::profile::{options, run};
use super::util::marble_scene;

/// Lowres alone, with `reconstructions`, rgba32float, after `warmup`
/// frames.
fn lowres(reconstructions: &[Upsampler], warmup: u32, frames: u32) -> Options {
    let mut opts = options(&[32], &[4]);
    opts.variants = vec![Variant::Lowres];
    opts.lowres_reconstructions = reconstructions.to_vec();
    opts.cache_formats = vec![CacheFormat::Rgba32float];
    opts.warmup = Some(warmup);
    opts.frames = Some(frames);
    opts
}

/// A static scene: after s² = 16 frames every pixel has been shaded on
/// its own once, and the spatio-temporal reconstruction shows its own
/// samples: within 0.02 of the reference everywhere, silhouettes included
/// (61.6 dB, the deferred lowres's figure too, on the same 39 pixels).
/// Not to the bit: near the silhouette the pixels' filtered temporal
/// gradient stays above CACHE_STILL, so their exact history is not kept
/// and they show eq. 7's blend. A sample's gradient is taken against last
/// frame's result at its pixel, which where that was such a blend measures
/// the blend's error rather than a change of the shading, and the loop
/// sustains itself: with the `still` condition dropped from the rule that
/// keeps an exact history the frame is the reference to the bit (100 dB),
/// but a light that changes is then kept for s² frames
/// (`history_rejected_on_shading_change` and
/// `moving_shadow_edge_does_not_ghost` fail). This runs the whole variant
/// through the host crate, as an application does: the samples at 32×32
/// with the projection jittered onto each frame's lattice, the
/// upsampling, the history. Checked: without the exact-sample rule of `cache_upsample`
/// (the paper's blend alone, which averages the other phases' interpolated
/// values in for ever) it is 58.6 dB.
#[test]
fn static_scene_lowres_converges_to_full_resolution() {
    static_marble_converges(Variant::Lowres, (128, 128), (0.02, 61.0));
}

/// At a size the lattice does not divide (130 × 126 at s = 4: 33 × 32
/// samples, the last column and row of cells cut short), the forward
/// samples pass's projection is scaled as well as moved (`cache_jitter`),
/// so each sample still lands on its pixel's centre and those past the
/// window shade outside it; the deferred one reads its lattice pixel from
/// the G-buffer, clamped to the frame. Every pixel, those of the short
/// cells included, is shaded on its own within s² frames: 60.1 dB for
/// both. What is left is at the sphere's silhouette (6 pixels 3 to 6
/// steps of 8 bits off, 0.033 at most, the same in both, so of the
/// upsampling they share), not at the short cells. Checked: with the
/// forward projection moved but not scaled (m = 1, the samples drifting
/// off their pixels towards the window's far edges), 51.7 dB. The
/// deferred clamp is not what this shows: without it the converged
/// frame is the same here (its guard is against reading past the
/// G-buffer, which WGSL's robust loads already make harmless).
#[test]
fn lowres_converges_at_a_size_the_lattice_does_not_divide() {
    for variant in [Variant::Lowres, Variant::DeferredLowres] {
        static_marble_converges(variant, (130, 126), (0.04, 58.0));
    }
}

/// The still marble (turbulence 1) at `size` through `variant`'s
/// spatio-temporal reconstruction after s² + 1 frames: its largest
/// difference from the reference below `bounds.0`, its PSNR above
/// `bounds.1` dB, and its passes those of the variant.
fn static_marble_converges(variant: Variant, (width, height): (u32, u32), bounds: (f64, f64)) {
    let scene = marble_scene("", "")
        .replace("turbulence_amount = 6.0", "turbulence_amount = 1.0")
        .replace("size = [128, 128]", &format!("size = [{width}, {height}]"));
    let options = Options {
        variants: vec![variant],
        ..lowres(&[Upsampler::SpatioTemporal], 17, 3)
    };
    let Some((_, report, _)) = run(&scene, options) else {
        return;
    };
    assert_eq!(report.results.len(), 1);
    let row = &report.results[0];
    assert_eq!((row.variant, row.refresh_period), (variant, 16));
    // The deferred lowres's G-buffer, lattice, samples and upsampling;
    // the forward one's samples and upsampling.
    let passes = if variant == Variant::DeferredLowres {
        4
    } else {
        2
    };
    assert_eq!(row.passes.len(), passes, "{variant}: {:?}", row.passes);
    assert!(
        row.max_abs_error < bounds.0 && row.psnr > bounds.1,
        "{variant} at {width}×{height}: largest difference {} after 16 frames (PSNR {} dB)",
        row.max_abs_error,
        row.psnr
    );
}

/// Before the lattice has covered the window, only a sixteenth of the
/// pixels are shaded: the spatial upsampling interpolates the rest, so
/// the frame is not yet the reference (the convergence above is the
/// history's doing, not an artefact of a full-resolution shading).
#[test]
fn lowres_first_frame_is_upsampled_not_shaded() {
    let Some((_, report, _)) = run(&marble_scene("", ""), lowres(&[Upsampler::Spatial], 0, 1))
    else {
        return;
    };
    let row = &report.results[0];
    assert!(row.max_abs_error > 4.0 / 255.0, "{}", row.max_abs_error);
    assert!(row.psnr > 20.0, "{}", row.psnr);
}

/// A flat colour per object (which side of x = 0 it stands on), dimmed
/// until a light switches on at `time` 0.5, lit by the up-facing normal,
/// through a loop that makes it worth caching: the same value at every
/// pixel of an object, so that any error of an upsampling is a neighbour's
/// colour bleeding in, or a stale one.
const FLAT: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
}
@group(0) @binding(0) var<uniform> frame: Frame;
struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}
struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_normal: vec3<f32>,
}
@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * frame.world_from_local * vec4<f32>(in.position, 1.0);
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    return out;
}
@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let albedo = select(vec3<f32>(0.8, 0.2, 0.1), vec3<f32>(0.1, 0.3, 0.9), frame.world_from_local[3].x > 0.0);
    let lit = albedo * select(0.2, 1.0, frame.time >= 0.5) * max(normalize(in.world_normal).y, 0.0);
    var c = lit;
    for (var i = 0; i < 32; i++) {
        c = sqrt((c * c) + vec3<f32>(1e-6));
    }
    return vec4<f32>(c, 1.0);
}
"#;

/// Two coplanar planes side by side, each its own draw and colour, seen
/// from above at an angle: their edge has one depth and one normal, only
/// the draw tells the sides apart. `effects` and `settings` (TOML lines)
/// add motion and the frame counts.
fn two_planes(settings: &str, effects: &str) -> String {
    format!(
        r#"
size = [128, 128]
{settings}
effects = [{effects}]
[camera]
eye = [0.0, 3.0, 3.0]
target = [0.0, 0.0, 0.0]
[[objects]]
mesh = {{ kind = "plane", size = 3.0, subdivisions = 2 }}
position = [-1.5, 0.0, 0.0]
[[objects]]
mesh = {{ kind = "plane", size = 3.0, subdivisions = 2 }}
position = [1.5, 0.0, 0.0]
"#
    )
}

fn lowres_top(reconstructions: &[Upsampler], warmup: u32, frames: u32) -> Options {
    Options {
        nodes: crate::profile::Nodes::Top(1),
        ..lowres(reconstructions, warmup, frames)
    }
}

/// A material edge on one plane (two draws, coplanar): the spatial
/// upsampling weighs each sample by its draw (ours: eq. 2 has normal and
/// depth terms only, which cannot tell these sides apart), so no pixel
/// takes the other side's colour; bilinear upsampling, without weights,
/// bleeds across, which shows the scene tests what it should.
#[test]
fn material_edge_does_not_bleed() {
    let Some((_, report, _)) = super::profile::run_shader(
        FLAT,
        &two_planes("frames = 1\nwarmup = 0", ""),
        lowres_top(&[Upsampler::Spatial, Upsampler::Bilinear], 0, 1),
    ) else {
        return;
    };
    let error = |r: Upsampler| {
        report
            .results
            .iter()
            .find(|row| row.reconstruction == r.into())
            .unwrap()
            .max_abs_error
    };
    assert!(
        error(Upsampler::Spatial) < 0.01,
        "spatial: {}",
        error(Upsampler::Spatial)
    );
    assert!(
        error(Upsampler::Bilinear) > 0.1,
        "bilinear: {}",
        error(Upsampler::Bilinear)
    );
}

/// The light switches on: the samples' temporal gradient is 0.8 where
/// they meet the dim history, the history is dropped, and from the frame
/// of the switch on no stale (dim) value is shown: every frame is within
/// 0.02 of the reference. The temporal reconstruction, which trusts its
/// history, still shows dim pixels frames later. Checked: with eq. 8's
/// filtered confidence alone (no drop on a change of half or more) the
/// error is 0.69, 0.63, 0.12, 0.08, 0.05 over the five frames from the
/// switch.
#[test]
fn history_rejected_on_shading_change() {
    // `time` advances 0.02 a frame: after 20 warm-up frames the history
    // is settled, and the light comes on at frame 25, measured frame 5.
    let scene = two_planes(
        "frames = 10\nwarmup = 20\nseconds_per_frame = 0.02",
        "\"time\"",
    );
    let Some((_, report, _)) = super::profile::run_shader(
        FLAT,
        &scene,
        lowres_top(&[Upsampler::SpatioTemporal, Upsampler::Temporal], 20, 10),
    ) else {
        return;
    };
    let row = |r: Upsampler| {
        report
            .results
            .iter()
            .find(|row| row.reconstruction == r.into())
            .unwrap()
    };
    // Frame 25 (time 0.5) is measured frame 5.
    let switched = 5;
    let adaptive = row(Upsampler::SpatioTemporal);
    for (frame, stats) in adaptive.frame_stats.iter().enumerate() {
        assert!(
            stats.max_abs_error < 0.02,
            "frame {frame}: {}",
            stats.max_abs_error
        );
    }
    let temporal = row(Upsampler::Temporal);
    assert!(
        temporal.frame_stats[switched + 2].max_abs_error > 0.1,
        "temporal: {}",
        temporal.frame_stats[switched + 2].max_abs_error
    );
}

/// The mean absolute difference (over RGB, in [0, 1]) of two RGBA8
/// pictures at `pixels`.
fn mean_error(a: &[u8], b: &[u8], pixels: &[usize]) -> f64 {
    let sum: f64 = pixels
        .iter()
        .flat_map(|&i| (0..3).map(move |c| i * 4 + c))
        .map(|k| f64::from(a[k].abs_diff(b[k])) / 255.0)
        .sum();
    sum / (3 * pixels.len().max(1)) as f64
}

/// The marble sphere sliding over the marble floor, with `settings`.
fn sliding_sphere(settings: &str) -> String {
    super::util::sphere_over_floor(
        settings,
        "\"object-motion\"",
        "",
        "position = [-1.2, 0.0, 0.0]\ntranslation_per_frame = [0.12, 0.0, 0.0]",
    )
}

/// Where the sphere slid off the floor last frame, the floor is
/// disoccluded: its history is the sphere's, so it gets no temporal
/// weight (eq. 7 with hw = 0) and the spatio-temporal frame there is the
/// spatial upsampling's (1.02× its error), not a ghost of the sphere.
/// Checked: with the history weighed on a miss (and its gradient not set
/// to 1 there), the revealed band's error is 1.56× the spatial one.
#[test]
fn disocclusion_falls_back_to_spatial() {
    let (warmup, frames) = (16, 2);
    let Some((pictures, report, scene)) = run(
        &sliding_sphere("size = [128, 128]\nframes = 2\nwarmup = 16"),
        lowres(
            &[Upsampler::Spatial, Upsampler::SpatioTemporal],
            warmup,
            frames,
        ),
    ) else {
        return;
    };
    let last = warmup + frames - 1;
    let (w, h) = (128, 128);
    let before = super::util::silhouette(&scene, 1, last - 1, w, h);
    let now = super::util::silhouette(&scene, 1, last, w, h);
    let revealed: Vec<bool> = (0..w * h).map(|i| before[i] && !now[i]).collect();
    let revealed: Vec<usize> = super::util::interior(&revealed, w)
        .iter()
        .enumerate()
        .filter_map(|(i, &m)| m.then_some(i))
        .collect();
    assert!(revealed.len() > 20, "{} revealed pixels", revealed.len());
    let error = |r: Upsampler| {
        let index = report
            .results
            .iter()
            .position(|row| row.reconstruction == r.into())
            .unwrap();
        mean_error(&pictures.results[index].0, &pictures.reference, &revealed)
    };
    let (spatial, adaptive) = (error(Upsampler::Spatial), error(Upsampler::SpatioTemporal));
    assert!(
        adaptive <= spatial * 1.2,
        "revealed floor: spatio-temporal {adaptive}, spatial {spatial}"
    );
}

/// A blue ball crossing a red floor fast (5 pixels a frame, [`FLAT`]
/// colours): the floor it uncovers over the last three frames has the
/// ball's colour in its history, and spatio-temporal shows the floor
/// there (within 0.02 on average), no blue trail. Checked: with the
/// history weighed whatever its gradient and its depth test, the trail
/// is 0.04 off on average (0 with them).
#[test]
fn fast_motion_no_ghosting() {
    let scene = r#"
size = [128, 128]
frames = 3
warmup = 16
effects = ["object-motion"]
[camera]
eye = [0.0, 1.2, 3.4]
target = [0.0, -0.3, 0.0]
[[objects]]
mesh = { kind = "plane", size = 8.0, subdivisions = 4 }
position = [-2.5, -1.0, 0.0]
[[objects]]
mesh = { kind = "sphere", rings = 24, segments = 32 }
scale = 0.6
position = [-1.6, -0.4, 0.0]
translation_per_frame = [0.12, 0.0, 0.0]
"#;
    let (warmup, frames) = (16, 3);
    let Some((pictures, report, scene)) = super::profile::run_shader(
        FLAT,
        scene,
        lowres_top(&[Upsampler::SpatioTemporal], warmup, frames),
    ) else {
        return;
    };
    let last = warmup + frames - 1;
    let (w, h) = (128, 128);
    let now = super::util::silhouette(&scene, 1, last, w, h);
    let mut trail = vec![false; w * h];
    for back in 1..=3 {
        let before = super::util::silhouette(&scene, 1, last - back, w, h);
        for i in 0..w * h {
            trail[i] |= before[i] && !now[i];
        }
    }
    let trail: Vec<usize> = super::util::interior(&trail, w)
        .iter()
        .enumerate()
        .filter_map(|(i, &m)| m.then_some(i))
        .collect();
    assert!(trail.len() > 100, "{} trail pixels", trail.len());
    assert_eq!(report.results.len(), 1);
    let error = mean_error(&pictures.results[0].0, &pictures.reference, &trail);
    assert!(error < 0.02, "the trail is {error} off on average");
}

/// The marble's veins are finer than the 4×4 lattice: spatial upsampling
/// of a still picture changes from frame to frame as the lattice steps
/// through its offsets (flicker), and spatio-temporal settles on the
/// shaded samples: its flicker is below a tenth of the spatial one's.
/// Checked: without its history (wf = 0, no exact samples kept) it
/// flickers more than the spatial upsampling.
#[test]
fn thin_feature_flicker_bounded() {
    let Some((_, report, _)) = run(
        &marble_scene("", ""),
        lowres(&[Upsampler::Spatial, Upsampler::SpatioTemporal], 17, 6),
    ) else {
        return;
    };
    let flicker = |r: Upsampler| {
        report
            .results
            .iter()
            .find(|row| row.reconstruction == r.into())
            .unwrap()
            .flicker
    };
    let (spatial, adaptive) = (
        flicker(Upsampler::Spatial),
        flicker(Upsampler::SpatioTemporal),
    );
    assert!(spatial > 0.0, "spatial flicker {spatial}");
    assert!(
        adaptive < 0.1 * spatial,
        "flicker: spatio-temporal {adaptive}, spatial {spatial}"
    );
}

/// Adaptive refresh (`--reshade-unreliable`): the pixels the upsampling
/// cannot vouch for (the floor the sliding sphere reveals: no history,
/// no own sample, few samples of its surface near the edge) are shaded
/// at full resolution in a third pass, so the revealed band is closer to
/// the reference than the spatial guess leaves it, for a third pass that
/// costs what those few pixels cost. Checked: with the third pass's
/// pixels not discarded from the second (nothing re-shaded), the two
/// errors are equal.
#[test]
fn lowres_reshades_unreliable_pixels() {
    let (warmup, frames) = (16, 2);
    let mut options = lowres(&[Upsampler::SpatioTemporal], warmup, frames);
    options.adaptive_refresh = vec![false, true];
    let Some((pictures, report, scene)) = run(
        &sliding_sphere("size = [128, 128]\nframes = 2\nwarmup = 16"),
        options,
    ) else {
        return;
    };
    assert_eq!(report.results.len(), 2);
    let last = warmup + frames - 1;
    let (w, h) = (128, 128);
    let before = super::util::silhouette(&scene, 1, last - 1, w, h);
    let now = super::util::silhouette(&scene, 1, last, w, h);
    let revealed: Vec<usize> = (0..w * h).filter(|&i| before[i] && !now[i]).collect();
    let error = |reshade: bool| {
        let index = report
            .results
            .iter()
            .position(|row| row.adaptive == reshade)
            .unwrap();
        assert_eq!(
            report.results[index].passes.len(),
            if reshade { 3 } else { 2 }
        );
        mean_error(&pictures.results[index].0, &pictures.reference, &revealed)
    };
    let (guessed, reshaded) = (error(false), error(true));
    assert!(
        reshaded < 0.8 * guessed,
        "revealed band: re-shaded {reshaded}, upsampled {guessed}"
    );
}

/// The paper's temporal baseline (`--fill-holes`, §5: temporal
/// amortisation "with second-pass hole filling"): every pixel the history
/// misses and this frame did not shade (the floor the sliding sphere
/// reveals) is shaded at full resolution in a third pass, so the revealed
/// band is the reference's, where the temporal reconstruction without it
/// shows the spatial guess. Spatio-temporal is not changed by it.
#[test]
fn temporal_baseline_fills_every_hole() {
    let (warmup, frames) = (16, 2);
    let run_with = |reconstruction, fill_holes| {
        let mut options = lowres(&[reconstruction], warmup, frames);
        options.upsampling.fill_holes = fill_holes;
        run(
            &sliding_sphere("size = [128, 128]\nframes = 2\nwarmup = 16"),
            options,
        )
    };
    let Some((guessed, report, scene)) = run_with(Upsampler::Temporal, false) else {
        return;
    };
    assert_eq!(report.results[0].passes.len(), 2);
    let (filled, report, _) = run_with(Upsampler::Temporal, true).unwrap();
    assert_eq!(report.results[0].passes.len(), 3);
    let (_, report, _) = run_with(Upsampler::SpatioTemporal, true).unwrap();
    assert_eq!(
        report.results[0].passes.len(),
        2,
        "spatio-temporal fills no hole"
    );
    let last = warmup + frames - 1;
    let (w, h) = (128, 128);
    let before = super::util::silhouette(&scene, 1, last - 1, w, h);
    let now = super::util::silhouette(&scene, 1, last, w, h);
    let revealed: Vec<usize> = (0..w * h).filter(|&i| before[i] && !now[i]).collect();
    assert!(revealed.len() > 50, "{} revealed pixels", revealed.len());
    let error = |pictures: &crate::report::images::Pictures| {
        mean_error(&pictures.results[0].0, &pictures.reference, &revealed)
    };
    let (guess, fill) = (error(&guessed), error(&filled));
    eprintln!("revealed band: {guess} upsampled, {fill} with its holes filled");
    assert!(fill < 0.0005, "revealed band with its holes filled: {fill}");
    assert!(
        guess > 4.0 * fill.max(0.001),
        "upsampled {guess}, filled {fill}"
    );
}

/// [`FLAT`] coloured by depth instead of by object: red in front of
/// z = 0, blue behind it.
const BY_DEPTH: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> frame: Frame;
struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}
struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_normal: vec3<f32>,
    @location(1) world_position: vec3<f32>,
}
@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    var out: VertexOutput;
    let world = frame.world_from_local * vec4<f32>(in.position, 1.0);
    out.clip_position = frame.clip_from_world * world;
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    out.world_position = world.xyz;
    return out;
}
@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let albedo = select(vec3<f32>(0.1, 0.3, 0.9), vec3<f32>(0.8, 0.2, 0.1), in.world_position.z > 0.0);
    var c = albedo * max(normalize(in.world_normal).z, 0.0);
    for (var i = 0; i < 32; i++) {
        c = sqrt((c * c) + vec3<f32>(1e-6));
    }
    return vec4<f32>(c, 1.0);
}
"#;

/// An OBJ of two squares facing +z in one mesh: a small one (z = 0.5) a
/// unit in front of a large one (z = −0.5); the folder it is in, and its
/// path.
fn two_squares() -> (tempfile::TempDir, std::path::PathBuf) {
    let meshes = tempfile::tempdir().unwrap();
    let obj = meshes.path().join("squares.obj");
    std::fs::write(
        &obj,
        "v -1.5 -1.5 -0.5\nv 1.5 -1.5 -0.5\nv 1.5 1.5 -0.5\nv -1.5 1.5 -0.5\n\
         v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\nvn 0 0 1\n\
         f 1//1 2//1 3//1\nf 1//1 3//1 4//1\nf 5//1 6//1 7//1\nf 5//1 7//1 8//1\n",
    )
    .unwrap();
    (meshes, obj)
}

/// One mesh, one draw: a small square a unit in front of a large one,
/// both facing the camera. Around the small square's outline the samples
/// of both squares have one normal and one draw id, and only eq. 2's
/// depth weight (σz, 3% of the depth) tells them apart: the spatial
/// upsampling does not bleed the back square's colour onto the front one
/// or the reverse. With the depth weight made flat (σz = 100) it does,
/// which shows the scene tests what it should.
#[test]
fn depth_edge_does_not_bleed() {
    let (_meshes, obj) = two_squares();
    let scene = format!(
        r#"
size = [128, 128]
frames = 1
warmup = 0
effects = []
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
[[objects]]
mesh = {{ kind = "obj", file = "{}" }}
"#,
        obj.display()
    );
    let error = |sigma_depth: f32| {
        let mut options = lowres_top(&[Upsampler::Spatial], 0, 1);
        options.upsampling.sigma_depth = sigma_depth;
        let (_, report, _) = super::profile::run_shader(BY_DEPTH, &scene, options)?;
        Some(report.results[0].max_abs_error)
    };
    let Some(weighted) = error(0.03) else {
        return;
    };
    assert!(weighted < 0.01, "with σz = 0.03: {weighted}");
    let flat = error(100.0).unwrap();
    assert!(flat > 0.1, "with σz = 100: {flat}");
}

/// Hard case 15 of the design note (seed 001's σz is "3% of the
/// difference between the near and far frustum plane", §3.1):
/// `--depth-tolerance range` takes σz of the scene camera's far − near.
/// With the far plane at 100 the squares of [`depth_edge_does_not_bleed`],
/// a unit apart, differ by 1% of the range, within σz: the upsampling
/// bleeds one onto the other, where σz of the depth (ours: 1/2.5 apart)
/// keeps them apart. Reversed Z changes nothing (the weight reads the
/// view depth). With an infinite far plane the range is undefined and σz
/// is of the depth again.
#[test]
fn depth_tolerance_of_the_range_follows_the_camera_planes() {
    let (_meshes, obj) = two_squares();
    let error = |tolerance: crate::rewrite::DepthTolerance, camera: &str| {
        let scene = format!(
            "size = [128, 128]\nframes = 1\nwarmup = 0\neffects = []\n[camera]\neye = [0.0, 0.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\n{camera}\n[[objects]]\nmesh = {{ kind = \"obj\", file = \"{}\" }}\n",
            obj.display()
        );
        let mut options = lowres_top(&[Upsampler::Spatial], 0, 1);
        options.upsampling.depth_tolerance = tolerance;
        let (_, report, _) = super::profile::run_shader(BY_DEPTH, &scene, options)?;
        Some(report.results[0].max_abs_error)
    };
    use crate::rewrite::DepthTolerance::{OfDepth, OfRange};
    let Some(of_depth) = error(OfDepth, "far = 100.0") else {
        return;
    };
    assert!(of_depth < 0.01, "σz of the depth: {of_depth}");
    let of_range = error(OfRange, "far = 100.0").unwrap();
    assert!(of_range > 0.1, "σz of the range 99.9: {of_range}");
    let reversed = error(OfRange, "far = 100.0\ndepth = \"reversed\"").unwrap();
    assert!(reversed > 0.1, "σz of the range, reversed Z: {reversed}");
    let infinite = error(OfRange, "far = \"infinity\"").unwrap();
    assert!(infinite < 0.01, "σz of an infinite range: {infinite}");
}

/// Hard case 19 of the design note (seed 001: texture LOD in the
/// payload): the samples pass rasterises at 1/s × 1/s, so its derivatives
/// are s times the full resolution's and an implicit-LOD sample reads
/// log2 s mip levels coarser. With the bias of −log2 s the samples read
/// about the full resolution's level: on a still plane with a mipmapped
/// noise texture (minified about five times in the reference), the
/// spatio-temporal reconstruction comes within 37 dB of the reference,
/// and without the bias it stays at a copy two mip levels blurrier,
/// 13 dB further. Without mip levels the bias changes nothing.
#[test]
fn lod_bias_matches_the_reference() {
    let shader =
        std::fs::read_to_string(super::util::root().join("corpus/implicit_derivative.wgsl"))
            .unwrap();
    let scene = |mipmaps: bool| {
        format!(
            r#"
size = [128, 128]
effects = []
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
[light]
position = [0.0, 0.0, 4.0]
[[objects]]
mesh = {{ kind = "plane", size = 2.4, subdivisions = 1 }}
rotation_degrees = [70.0, 0.0, 0.0]
[uniforms]
uv_scale = 2.0
stripe_frequency = 0.0
light_color = [1.0, 1.0, 1.0]
[textures.albedo_texture]
generate = "noise"
size = 256
mipmaps = {mipmaps}
"#
        )
    };
    let psnr = |lod_bias: bool, mipmaps: bool| {
        let mut options = lowres_top(&[Upsampler::SpatioTemporal], 17, 3);
        options.upsampling.lod_bias = lod_bias;
        let (_, report, _) = super::profile::run_shader(&shader, &scene(mipmaps), options)?;
        Some(report.results[0].psnr)
    };
    let Some(biased) = psnr(true, true) else {
        return;
    };
    let unbiased = psnr(false, true).unwrap();
    eprintln!(
        "lowres on a mipmapped texture: {biased:.1} dB with the LOD bias, {unbiased:.1} dB without"
    );
    assert!(biased > 33.0, "with the bias: {biased} dB");
    assert!(
        unbiased < biased - 10.0,
        "without the bias: {unbiased} dB (with: {biased})"
    );
    let (one_level_biased, one_level) = (psnr(true, false).unwrap(), psnr(false, false).unwrap());
    assert!(
        (one_level_biased - one_level).abs() < 0.01,
        "one mip level: {one_level_biased} dB biased, {one_level} dB not"
    );
}

/// A floor whose colour is a smooth pattern under a pole's thin shadow
/// sweeping it (`time`): the band is 5 pixels wide at 128² and moves 3
/// pixels a frame, so within the four samples around a pixel (2s = 8
/// pixels across) one edge darkens what it reaches and the other
/// brightens what it leaves.
const SHADOW_SWEEP: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    time: f32,
}
@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) world_normal: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) uv: vec2<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * frame.world_from_local * vec4<f32>(position, 1.0);
    out.uv = uv;
    out.world_normal = (frame.world_from_local * vec4<f32>(normal, 0.0)).xyz;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let pattern = 0.6 + (0.25 * (sin(in.uv.x * 9.0) * sin(in.uv.y * 7.0)));
    let across = fract(in.uv.x - (1.8 * frame.time)) - 0.5;
    let shadow = 1.0 - (0.75 * (1.0 - smoothstep(0.015, 0.025, abs(across))));
    let lit = pattern * shadow;
    return vec4<f32>(vec3<f32>(lit), 1.0);
}
"#;

/// Seed 001's temporal gradient filtered as the paper filters it, the
/// absolute values blind to the geometry (`--gradient-filter paper`),
/// against ours, the signed values weighted by geometry: under a thin
/// shadow sweeping a still floor the band's two edges change the shading
/// in opposite directions within the samples around a pixel. Averaged
/// signed, they cancel and read as confidence: the history keeps the
/// band where it was, a ghost of the shadow on floor the reference shows
/// lit. With the paper's filter the history there is dropped.
#[test]
fn moving_shadow_edge_does_not_ghost() {
    let (_, analysis) = super::util::analyzed("shadow_sweep.wgsl", SHADOW_SWEEP);
    let lit = super::util::candidate(&analysis, "pattern * shadow");
    let scene = r#"
size = [128, 128]
effects = ["time"]
[camera]
eye = [0.0, 0.0, 2.4]
target = [0.0, 0.0, 0.0]
[[objects]]
mesh = { kind = "plane", size = 2.0, subdivisions = 1 }
rotation_degrees = [90.0, 0.0, 0.0]
"#;
    // The last frame's pixels the variant shows darker than the reference
    // by a tenth or more, away from the shadow (more than 8 pixels, the
    // samples' footprint, from any pixel of its core in the row, where the
    // spatial upsampling alone blurs it): where the shadow was.
    let ghosts = |gradient_filter| {
        let mut options = lowres(&[Upsampler::SpatioTemporal], 20, 12);
        options.nodes = crate::profile::Nodes::Ids(vec![lit.node.id.clone()]);
        options.upsampling.gradient_filter = gradient_filter;
        let (pictures, report, _) = super::profile::run_shader(SHADOW_SWEEP, scene, options)?;
        let (result, _) = &pictures.results[0];
        let (reference, width) = (&pictures.reference, 128usize);
        let mut count = 0;
        for (r, v) in reference.chunks(width * 4).zip(result.chunks(width * 4)) {
            let core: Vec<usize> = (0..width).filter(|&x| r[x * 4] < 50).collect();
            for x in 0..width {
                let away = core.iter().all(|&c| c.abs_diff(x) > 8);
                if away && v[x * 4] + 25 < r[x * 4] {
                    count += 1;
                }
            }
        }
        Some((count, report.results[0].psnr))
    };
    let Some((ours, ours_psnr)) = ghosts(crate::rewrite::GradientFilter::Ours) else {
        return;
    };
    let (paper, paper_psnr) = ghosts(crate::rewrite::GradientFilter::Paper).unwrap();
    eprintln!(
        "a thin shadow sweeping: {paper} ghost pixels ({paper_psnr:.1} dB) with the paper's gradient filter, {ours} ({ours_psnr:.1} dB) with ours"
    );
    assert!(
        ours > 100,
        "ours left {ours} ghost pixels: the case does not ghost"
    );
    assert!(
        paper * 4 < ours,
        "the paper's filter left {paper} ghost pixels, ours {ours}"
    );
}

/// Deferred lowres alone (the paper's pipeline), as [`lowres`].
fn deferred_lowres(reconstructions: &[Upsampler], warmup: u32, frames: u32) -> Options {
    Options {
        variants: vec![Variant::DeferredLowres],
        ..lowres(reconstructions, warmup, frames)
    }
}

/// Deferred lowres on the static marble converges as the forward lowres
/// does (above): after s² = 16 frames every pixel has been shaded once,
/// here from the G-buffer, which keeps the full-resolution raster's
/// varyings bit for bit. What is left (0.016 at most, 61.6 dB) is the
/// forward lowres's, on the same pixels near the silhouette: their exact
/// history is not kept while their filtered gradient, taken against last
/// frame's blend there, stays above CACHE_STILL (above). Not misses: with
/// a sample whose lookup misses given a gradient of 0 instead of 1, the
/// same 39 pixels.
/// Checked: with the samples read at the low-resolution pixel's own
/// G-buffer texel instead of the lattice pixel's (no
/// `cache_lattice_pixel`), 0.069 and 36.9 dB.
#[test]
fn static_scene_deferred_lowres_converges_to_full_resolution() {
    static_marble_converges(Variant::DeferredLowres, (128, 128), (0.02, 61.0));
}

/// Two draws, two colours, side by side: the deferred lowres's samples
/// pass runs at 1/s × 1/s, where the frame's stencil of draw ordinals
/// cannot be tested, so the lattice pass marks a stencil of that size
/// from the ordinals the G-buffer keeps. Each draw's samples are then
/// shaded with its own bind groups only where it is visible: the first
/// frame's spatial upsampling shows each plane in its own colour. Checked:
/// with every draw keeping every lattice pixel (the lattice's discard
/// removed), the last draw shades all the samples, and where the first
/// plane's samples take the second's colour it is 0.16 off.
#[test]
fn deferred_lowres_shades_each_draw_at_its_own_samples() {
    let Some((_, report, _)) = super::profile::run_shader(
        FLAT,
        &two_planes("frames = 1\nwarmup = 0", ""),
        Options {
            nodes: crate::profile::Nodes::Top(1),
            ..deferred_lowres(&[Upsampler::Spatial], 0, 1)
        },
    ) else {
        return;
    };
    let row = &report.results[0];
    assert_eq!(row.variant, Variant::DeferredLowres);
    assert_eq!(row.passes.len(), 4, "{:?}", row.passes);
    assert!(row.max_abs_error < 0.01, "{}", row.max_abs_error);
}

/// A contact point (the paper's material ids, `--material-ids`): two
/// coplanar planes meet at x = 0, each its own draw and colour, and the
/// camera pans across the edge 1.5 pixels a frame. Next to the edge, on
/// the side the scene moves into, a pixel of one plane reprojects onto
/// where the other was, at the same depth: the depth test finds the other
/// plane's history and the temporal reconstruction shows its colour
/// (0.071 off on average over the four pixels next to the edge). With
/// `material_ids` the history keeps the draw's id and misses where its
/// lookup reads a texel of another draw; those pixels take the
/// draw-weighted spatial value (0.004). Checked: with the id test
/// removed, 0.071 with the flag too.
#[test]
fn contact_point_history_misses_by_material() {
    let scene = r#"
size = [128, 128]
frames = 3
warmup = 20
effects = ["camera-motion"]
[camera]
eye = [-1.6, 3.0, 3.0]
target = [-1.6, 0.0, 0.0]
pan_per_frame = [0.07, 0.0, 0.0]
[[objects]]
mesh = { kind = "plane", size = 3.0, subdivisions = 2 }
position = [-1.5, 0.0, 0.0]
[[objects]]
mesh = { kind = "plane", size = 3.0, subdivisions = 2 }
position = [1.5, 0.0, 0.0]
"#;
    // Lit from the first frame: no stale dim history to wash out.
    let lit = FLAT.replace("select(0.2, 1.0, frame.time >= 0.5)", "1.0");
    let run_with = |material_ids| {
        let mut options = lowres_top(&[Upsampler::Temporal], 20, 3);
        options.upsampling.material_ids = material_ids;
        super::profile::run_shader(&lit, scene, options)
    };
    let Some((by_depth, _, _)) = run_with(false) else {
        return;
    };
    let (by_material, _, _) = run_with(true).unwrap();
    // The four pixels of the right-hand plane next to the edge in the last
    // frame, where the scene moved in from the left-hand plane: where the
    // reference's colour changes along a row between two lit pixels (not
    // at the planes' outline against the background).
    let reference = &by_depth.reference;
    let w = 128;
    let at = |x: usize, y: usize| &reference[(y * w + x) * 4..(y * w + x) * 4 + 3];
    let mut near_edge = Vec::new();
    for y in 0..w {
        for x in 0..w - 5 {
            let (a, b) = (at(x, y), at(x + 1, y));
            let lit = a.iter().chain(b).all(|&c| c > 8);
            if lit && a.iter().zip(b).any(|(p, q)| p.abs_diff(*q) > 40) {
                near_edge.extend((x + 1..x + 5).map(|x| y * w + x));
            }
        }
    }
    assert!(
        near_edge.len() > 100,
        "{} pixels near the edge",
        near_edge.len()
    );
    let error = |pictures: &crate::report::images::Pictures| {
        mean_error(&pictures.results[0].0, &pictures.reference, &near_edge)
    };
    let (depth_only, with_ids) = (error(&by_depth), error(&by_material));
    eprintln!("near the edge: {depth_only} by depth alone, {with_ids} with material ids");
    assert!(with_ids < 0.01, "with material ids: {with_ids}");
    assert!(
        depth_only > 4.0 * with_ids.max(0.005),
        "by depth alone: {depth_only}"
    );
}
