//! Whole-frame reuse (`shadecache interpolate`): the I-frame pass, the
//! B-frame methods, the run and its report, on small scenes.

use crate::interpolate::bframe::Decision;
use crate::interpolate::report::{KeptFrame, Pictures, Report};
use crate::interpolate::{self, Method, Options};
use crate::profile::Quiet;
use crate::scene::Scene;

use super::util::{root, temp_file};

/// Runs `shader_text` on `scene_text` with `options`; `None` (said on
/// stderr) without a GPU adapter outside CI.
pub(crate) fn run_interpolation(
    shader_text: &str,
    scene_text: &str,
    options: Options,
) -> Option<(Report, Pictures, Scene)> {
    super::gpu::gpu()?;
    let (_dir, scene_path) = temp_file("scene.toml", scene_text.as_bytes());
    let scene = Scene::load(&scene_path).unwrap_or_else(|e| panic!("{}", e.render()));
    let shader = crate::front::parse(crate::diagnostic::SourceFile::new("test.wgsl", shader_text))
        .unwrap_or_else(|e| panic!("{}", e.render()));
    let (report, pictures) =
        interpolate::interpolate(&shader, &scene, &scene_path, &options, &mut Quiet)
            .unwrap_or_else(|e| panic!("{}", e.render()));
    Some((report, pictures, scene))
}

pub(crate) fn marble() -> String {
    std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap()
}

/// A marble sphere over a marble floor; `effects`, `camera` and `sphere`
/// (TOML lines) set the motion.
pub(crate) fn sphere_over_floor(effects: &str, camera: &str, sphere: &str) -> String {
    super::util::sphere_over_floor("size = [96, 96]\nframes = 8", effects, camera, sphere)
}

pub(crate) fn method(report: &Report, method: Method) -> &interpolate::report::MethodReport {
    report
        .methods
        .iter()
        .find(|m| m.method == method)
        .unwrap_or_else(|| panic!("{} missing from the report", method.name()))
}

pub(crate) fn kept(pictures: &Pictures, method: Method) -> Vec<&KeptFrame> {
    pictures
        .kept
        .iter()
        .filter(|k| k.method == method)
        .collect()
}

/// Without motion every method's B-frames are the I-frames (up to one
/// rounding of the blend), the I-frames the reference, and the report says
/// the scene has none; with latest-frame initialisation too.
#[test]
fn static_scene_b_frames_equal_i_frames() {
    for latest_frame_init in [false, true] {
        static_scene_with(latest_frame_init);
    }
}

fn static_scene_with(latest_frame_init: bool) {
    let scene = sphere_over_floor("", "", "");
    let options = Options {
        frames: Some(4),
        latest_frame_init,
        // The morph blurs what it may, moving or not, unless told to
        // blur only what moves.
        blur_min_speed: Some(0.15),
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    assert_eq!(
        report.parameters.options.latest_frame_init,
        latest_frame_init
    );
    assert!(
        report.notes.iter().any(|n| n.contains("no motion")),
        "{:?}",
        report.notes
    );
    assert_eq!(report.i_frame_psnr_min, 100.0);
    for m in &report.methods {
        assert!(
            m.psnr_mean >= 70.0 && m.ssim_min >= 0.9999,
            "{}: PSNR {} SSIM {}",
            m.method.name(),
            m.psnr_mean,
            m.ssim_min
        );
    }
    assert_eq!(
        method(&report, Method::ImageBased).double_miss_rate,
        Some(0.0)
    );
}

/// A B-frame at α = 0 is I-frame 0 and at α = 1 I-frame 1, for every
/// method that reads both (half-velocity reads I-frame 0's colour only:
/// α = 0), under camera and object motion (differential test: a blend
/// weighted the wrong way round, or a reprojection off by a pixel, fails
/// it). Image-based's pixels where the searches did not agree on one
/// surface are the exception, bounded to 1% of the frame: beside a
/// silhouette the search into the other I-frame may converge within ε1
/// onto the nearer object, which §5.2's case 2 takes, and where neither
/// converges (a double miss) the smaller residual decides.
#[test]
fn alpha_zero_and_one_are_the_i_frames() {
    let scene = sphere_over_floor(
        "\"object-motion\", \"camera-motion\"",
        "orbit_degrees_per_frame = 1.5",
        "rotation_degrees_per_frame = [0.0, 3.0, 0.0]\ntranslation_per_frame = [0.02, 0.0, 0.0]",
    );
    let options = Options {
        frames: Some(4),
        endpoints: true,
        ..Options::default()
    };
    let Some((report, pictures, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    assert_eq!(
        report.i_frame_psnr_min, 100.0,
        "the I-frame is the reference"
    );
    for m in [
        Method::LinearBlend,
        Method::ImageBased,
        Method::SceneAssisted,
        Method::SceneAssistedShadeOnMiss,
        Method::HalfVelocity,
        Method::SampleAndHold,
        Method::Payload,
    ] {
        let ends: Vec<&KeptFrame> = kept(&pictures, m)
            .into_iter()
            .filter(|k| {
                let waits = method(&report, m).added_latency_frames > 0.0;
                k.alpha == 0.0 || (k.alpha == 1.0 && waits)
            })
            .collect();
        assert!(!ends.is_empty(), "{}: no end points kept", m.name());
        for end in ends {
            let mut off_edge = 0;
            for (p, &decision) in end.decisions.iter().enumerate() {
                let error = (0..3)
                    .map(|c| (end.reference[p * 4 + c] - end.result[p * 4 + c]).abs())
                    .fold(0.0f32, f32::max);
                if error <= 1.0 / 255.0 {
                    continue;
                }
                // Payload interpolation reads its payloads through
                // image-based's search and decisions.
                let searched = matches!(m, Method::ImageBased | Method::Payload);
                assert!(
                    searched && decision != Decision::SameSurface as u32,
                    "{} at α = {}, pixel {p} (decision {decision}): error {error}",
                    m.name(),
                    end.alpha,
                );
                off_edge += 1;
            }
            assert!(
                off_edge * 100 <= end.decisions.len(),
                "{} at α = {}: {off_edge} pixels differ from the I-frame",
                m.name(),
                end.alpha
            );
        }
    }
}

/// A module whose vertex stage draws each object with the scene's camera
/// and model matrices and passes its world and local positions on, with
/// `$fragment` after it.
macro_rules! with_frame_vertex {
    ($fragment:literal) => {
        concat!(
            r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) local_position: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.local_position = position;
    return out;
}
"#,
            $fragment
        )
    };
}

/// Flat shading by height above the backdrop, so that what a pixel shows
/// says which surface it is: the windmill's blades (z = 0.5) are bright,
/// the backdrop (z = −1) dark, striped so that it has detail.
const DEPTH_SHADED: &str = with_frame_vertex!(
    r#"
@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let stripes = 0.1 * step(0.5, fract(in.world_position.x * 4.0));
    return vec4<f32>(vec3<f32>(0.1 + 0.5 * (in.world_position.z + 1.0) + stripes), 1.0);
}
"#
);

/// Brightness of [`DEPTH_SHADED`] above which a pixel shows a blade.
const BLADE: f32 = 0.8;

/// A two-bladed windmill turning 45° a frame in front of a backdrop: at
/// n = 4 the blades are where they were one interval before, so the
/// backdrop behind them is hidden in both I-frames and shown between them
/// (seed 000 §6's double misses). `depth` is the camera's convention.
fn windmill(depth: &str) -> String {
    let mesh = root().join("corpus/scenes/meshes/windmill.obj");
    before_wall(
        depth,
        0.0,
        &format!(
            r#"[[objects]]
mesh = {{ kind = "obj", file = "{}" }}
position = [0.0, 0.0, 0.5]
rotation_degrees = [0.0, 0.0, 10.0]
rotation_degrees_per_frame = [0.0, 0.0, 45.0]
"#,
            mesh.display()
        ),
    )
}

/// The windmill's B-frames of `methods`, kept whole.
fn windmill_frames(depth: &str, methods: Vec<Method>) -> Option<Pictures> {
    let options = Options {
        frames: Some(4),
        methods,
        keep_frames: true,
        ..Options::default()
    };
    run_interpolation(DEPTH_SHADED, &windmill(depth), options).map(|(_, pictures, _)| pictures)
}

/// The pixels of scene-assisted (closest-on-miss) B-frames where neither
/// I-frame showed the surface, by kept frame.
fn double_misses(frame: &KeptFrame) -> Vec<usize> {
    (0..frame.decisions.len())
        .filter(|&p| frame.decisions[p] == Decision::DoubleMiss as u32)
        .collect()
}

/// Two windmills on one hub, the back one (z = 0.5) turning 45° a frame,
/// the front one (z = 0.8, brighter under [`DEPTH_SHADED`]) 22.5° from a
/// quarter turn: at n = 4 the back one's blades lie level in every
/// I-frame, the front one's in every other. So the backdrop behind the
/// level blades is hidden by the back windmill in one I-frame and by the
/// front one in the other, and shown between them: a double miss whose
/// two candidates are different surfaces.
fn two_windmills(depth: &str) -> String {
    let mesh = root().join("corpus/scenes/meshes/windmill.obj");
    let mesh = mesh.display();
    before_wall(
        depth,
        0.0,
        &format!(
            r#"[[objects]]
mesh = {{ kind = "obj", file = "{mesh}" }}
position = [0.0, 0.0, 0.5]
rotation_degrees_per_frame = [0.0, 0.0, 45.0]
[[objects]]
mesh = {{ kind = "obj", file = "{mesh}" }}
position = [0.0, 0.0, 0.8]
rotation_degrees = [0.0, 0.0, 90.0]
rotation_degrees_per_frame = [0.0, 0.0, 22.5]
"#
        ),
    )
}

/// Brightness of [`DEPTH_SHADED`] above which a pixel shows the front
/// windmill (z = 0.8: 1.0 to 1.1; the back one 0.85 to 0.95).
const FRONT_BLADE: f32 = 0.975;

/// Closest-on-miss fills a double miss with the nearer of the two I-frames'
/// surfaces at the reprojected positions: behind the level blades, where
/// one I-frame shows the back windmill and the other the front one, the
/// front one's colour; with reversed Z the same ("nearer" is the larger
/// depth there). Checked: with the comparison the wrong way round, or
/// not turned round for reversed Z, the back windmill's colour shows and
/// the test fails. (Behind one windmill both candidates would be the same
/// blade, and the test could not tell the nearer from the farther.)
#[test]
fn double_miss_closest_on_miss_takes_the_nearer_surface() {
    for depth in ["standard", "reversed"] {
        let options = Options {
            methods: vec![Method::SceneAssisted],
            frames: Some(8),
            keep_frames: true,
            ..Options::default()
        };
        let Some((_, pictures, _)) =
            run_interpolation(DEPTH_SHADED, &two_windmills(depth), options)
        else {
            return;
        };
        let (mut front, mut back) = (0, 0);
        for frame in kept(&pictures, Method::SceneAssisted) {
            // The backdrop, hidden in both I-frames, filled with a blade
            // (not a sample straddling a blade's edge).
            for p in double_misses(frame) {
                let shown = frame.result[p * 4];
                if frame.reference[p * 4] >= BLADE || shown < BLADE {
                    continue;
                }
                if shown > FRONT_BLADE {
                    front += 1;
                } else {
                    back += 1;
                }
            }
        }
        assert!(
            front > 20,
            "{depth} Z: {front} double misses show the front windmill"
        );
        assert!(
            back * 10 <= front,
            "{depth} Z: {back} double misses show the back windmill, {front} the front one"
        );
    }
}

/// Shade-on-miss shades the double misses with the original fragment
/// stage: there (and everywhere the I-frames agree) it is the reference.
#[test]
fn double_miss_shade_on_miss_equals_the_reference() {
    let Some(pictures) = windmill_frames(
        "standard",
        vec![Method::SceneAssisted, Method::SceneAssistedShadeOnMiss],
    ) else {
        return;
    };
    let closest = kept(&pictures, Method::SceneAssisted);
    let shaded = kept(&pictures, Method::SceneAssistedShadeOnMiss);
    assert_eq!(closest.len(), shaded.len());
    let mut misses = 0;
    for (closest, shaded) in closest.iter().zip(&shaded) {
        assert_eq!(closest.frame, shaded.frame);
        for p in double_misses(closest) {
            misses += 1;
            let error = (0..3)
                .map(|c| (shaded.reference[p * 4 + c] - shaded.result[p * 4 + c]).abs())
                .fold(0.0f32, f32::max);
            assert!(
                error <= 1.0 / 255.0,
                "frame {}, pixel {p}: shade-on-miss is {error} off the reference",
                shaded.frame
            );
        }
    }
    assert!(misses > 20, "only {misses} double misses");
}

/// Image-based's correspondence errors over `frames` displayed frames of
/// `scene` drawn with `shader`; `None` only without a GPU adapter.
fn image_based_correspondence(
    shader: &str,
    scene: &str,
    frames: u32,
) -> Option<interpolate::report::CorrespondenceError> {
    let options = Options {
        methods: vec![Method::ImageBased],
        frames: Some(frames),
        ..Options::default()
    };
    let (report, _, _) = run_interpolation(shader, scene, options)?;
    let error = method(&report, Method::ImageBased)
        .correspondence_error_px
        .clone();
    Some(error.expect("image-based's correspondences are measured"))
}

/// E_lin (000 Fig. 11): I-frame 0's points carried linearly along their
/// exact flow against where they are at each B-frame's time. A square
/// sliding at constant velocity moves linearly: no error but at its
/// silhouette, where a pixel's point may lie on the other surface.
#[test]
fn linear_motion_error_is_zero_for_constant_velocity() {
    let Some(error) =
        image_based_correspondence(SLIDING_SHADED, &sliding_square(square_speed(2.0)), 8)
    else {
        return;
    };
    let linear = error.linear.unwrap();
    assert!(
        linear.interior_mean < 0.02 && linear.p95 < 0.05,
        "{linear:?}"
    );
    assert!(linear.ranges[0] > 0.99, "{linear:?}");
    // The correspondences the search used, either direction, against the
    // exact points in the I-frame each reads: found exactly, where the
    // forward search alone misses what I-frame 0 does not show (the
    // uncovered band behind the square).
    let (used, forward) = (error.used.unwrap(), error.total.unwrap());
    assert!(
        used.mean < 0.01 && used.mean < forward.mean / 2.0,
        "used {used:?}, forward {forward:?}"
    );
}

/// The windmill's blades turn 45° a frame: their points move on circles,
/// and the chord the linear assumption takes falls off them by pixels
/// (against under 0.02 px for the sliding square above). The report gives
/// E_lin's spread, its silhouettes apart.
#[test]
fn nonlinear_motion_error_reported() {
    let Some(error) = image_based_correspondence(DEPTH_SHADED, &windmill("standard"), 4) else {
        return;
    };
    let linear = error.linear.unwrap();
    // Most of the frame is the still wall (no error); the blades, a few
    // per cent of it, are pixels off.
    assert!(linear.mean > 0.2, "{linear:?}");
    assert!(linear.ranges[1..].iter().sum::<f64>() > 0.02, "{linear:?}");
    let total = error.total.unwrap();
    assert!(total.mean > 0.0 && total.p95 >= total.mean, "{total:?}");
}

/// Half-velocity's direction test (003 slide 31): in a tail, where the
/// earlier frame's velocity would be carried on, a direction that
/// disagrees with the later frame's by more than `min_cosine` holds the
/// pixel, showing I-frame 0 there (no worse than 30 fps). A square slides
/// right over a wall sliding left: behind the square the velocity turns
/// round, from the square's to the wall's. Accepting every direction
/// (cosine −1) holds none.
#[test]
fn direction_change_holds_the_earlier_frame() {
    let run = |min_cosine: f32| {
        let options = Options {
            methods: vec![Method::HalfVelocity],
            frames_per_interval: 2,
            frames: Some(6),
            min_cosine,
            moving_objects: false,
            keep_frames: true,
            ..Options::default()
        };
        let scene =
            squares_before_wall(-square_speed(2.0), &[(0.8, [-0.6, 0.0], square_speed(4.0))]);
        run_interpolation(SLIDING_SHADED, &scene, options).map(|(_, pictures, _)| pictures)
    };
    let Some(tested) = run(0.5) else {
        return;
    };
    let held = |frame: &KeptFrame| -> Vec<usize> {
        (0..frame.decisions.len())
            .filter(|&p| frame.decisions[p] == Decision::OneDirection as u32)
            .collect()
    };
    let mut checked = 0;
    for frame in kept(&tested, Method::HalfVelocity) {
        let start = frame.frame - (frame.alpha * 2.0).round() as u32;
        let Some(iframe) = tested.iframes.iter().find(|i| i.frame == start) else {
            continue;
        };
        for p in held(frame) {
            for c in 0..3 {
                let (shown, there) = (frame.result[p * 4 + c], iframe.color[p * 4 + c]);
                assert!(
                    (shown - there).abs() <= 1e-3,
                    "frame {}, pixel {p}: held at {shown}, I-frame 0 shows {there}",
                    frame.frame
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 20, "{checked} held pixels checked");
    let accepting = run(-1.0).unwrap();
    let none: usize = kept(&accepting, Method::HalfVelocity)
        .iter()
        .map(|f| held(f).len())
        .sum();
    assert_eq!(none, 0);
}

/// Reverse reprojection with reshading (seed 000's main baseline, Figs.
/// 7–10): where I-frame 0 does not show the point (what the baseline
/// without reshading marks a miss), the original fragment stage shades it
/// at the B-frame's time, so those pixels are the reference's; elsewhere
/// the two agree.
#[test]
fn reshade_on_miss_equals_reference_at_misses() {
    let Some(pictures) = windmill_frames(
        "standard",
        vec![
            Method::ReverseReprojection,
            Method::ReverseReprojectionReshade,
        ],
    ) else {
        return;
    };
    let plain = kept(&pictures, Method::ReverseReprojection);
    let shaded = kept(&pictures, Method::ReverseReprojectionReshade);
    assert_eq!(plain.len(), shaded.len());
    let (mut misses, mut worse) = (0, 0usize);
    for (plain, shaded) in plain.iter().zip(&shaded) {
        assert_eq!(plain.frame, shaded.frame);
        for p in double_misses(plain) {
            misses += 1;
            let error = error_at(shaded, p);
            assert!(
                error <= 1.0 / 255.0,
                "frame {}, pixel {p}: the reshaded miss is {error} off the reference",
                shaded.frame
            );
            if error_at(plain, p) > 0.05 {
                worse += 1;
            }
        }
    }
    assert!(misses > 20, "only {misses} misses");
    assert!(
        worse > 10,
        "the plain baseline was wrong at only {worse} of them"
    );
    let Some((report, _, _)) = run_interpolation(
        DEPTH_SHADED,
        &windmill("standard"),
        Options {
            frames: Some(4),
            methods: vec![Method::ReverseReprojectionReshade],
            ..Options::default()
        },
    ) else {
        return;
    };
    assert_eq!(
        method(&report, Method::ReverseReprojectionReshade).added_latency_frames,
        0.0
    );
}

/// Reversed Z (near at depth 1) changes what "nearer", "far" and the
/// relative depth tests mean in every B-frame pass: each method's B-frames
/// are as good as with standard depth, on a scene with occlusion and
/// disocclusion.
#[test]
fn reversed_z_interpolation() {
    let run = |depth: &str| {
        let scene = sphere_over_floor(
            "\"object-motion\", \"camera-motion\"",
            &format!("orbit_degrees_per_frame = 1.5\ndepth = \"{depth}\""),
            "rotation_degrees_per_frame = [0.0, 3.0, 0.0]\ntranslation_per_frame = [0.04, 0.0, 0.0]",
        );
        let options = Options {
            frames: Some(8),
            ..Options::default()
        };
        run_interpolation(&marble(), &scene, options).map(|(report, _, _)| report)
    };
    let (Some(standard), Some(reversed)) = (run("standard"), run("reversed")) else {
        return;
    };
    assert_eq!(reversed.i_frame_psnr_min, 100.0);
    for m in &standard.methods {
        let r = method(&reversed, m.method);
        assert!(
            (r.ssim_mean - m.ssim_mean).abs() <= 0.005,
            "{}: SSIM {} with reversed Z, {} with standard",
            m.method.name(),
            r.ssim_mean,
            m.ssim_mean
        );
    }
    let misses = |report: &Report| method(report, Method::ImageBased).double_miss_rate.unwrap();
    assert!(
        (misses(&reversed) - misses(&standard)).abs() <= 0.01,
        "double misses: {} reversed, {} standard",
        misses(&reversed),
        misses(&standard)
    );
}

/// Every corpus shader's I-frame module (the I-frame pass, the
/// scene-assisted pass and the original fragment stage for its
/// shade-on-miss pass), its payload interpolation's payload and shade
/// passes, and the fullscreen B-frame passes: valid under
/// naga with every flag (the instrumenting validates it) and Tint, no
/// derivative after a `discard` (naga writes it as a termination), and a
/// wgpu pipeline per pass of every plan.
#[test]
fn every_interpolation_pass_is_valid_and_builds() {
    let Some(gpu) = super::gpu::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut files = vec![
        root().join("shaders/bframe.wgsl"),
        root().join("shaders/morph.wgsl"),
        root().join("shaders/bridge.wgsl"),
    ];
    let mut built = 0;
    // A refusal is the shader's limit, never the toolchain's failure.
    let refused = |path: &std::path::Path, what: &str, refusal: &crate::rewrite::Refusal| {
        assert!(
            !refusal.is_internal(),
            "{}: {}",
            path.display(),
            refusal.reason
        );
        eprintln!("{}: {what} refused: {}", path.display(), refusal.reason);
    };
    // Each plan checked and each of its passes built as a wgpu pipeline.
    let build = |path: &std::path::Path,
                 plan: &crate::plan::Plan,
                 source: &dyn Fn(&str) -> Option<String>| {
        plan.check()
            .unwrap_or_else(|err| panic!("{}: {err}", path.display()));
        crate::runtime::build_passes(
            &gpu,
            plan,
            source,
            crate::runtime::PipelineOptions::default(),
        )
        .unwrap_or_else(|err| panic!("{}: {err}", path.display()))
    };
    for path in super::util::corpus() {
        let text = std::fs::read_to_string(root().join(&path)).unwrap();
        let (shader, analysis) = super::util::analyzed(&path.display().to_string(), &text);
        let instrumented = match interpolate::iframe::instrument(
            &shader,
            &analysis,
            &crate::rewrite::Options::default(),
            gpu.device.limits().max_vertex_attributes,
        ) {
            Ok(instrumented) => instrumented,
            Err(refusal) => {
                refused(&path, "the I-frame pass", &refusal);
                continue;
            }
        };
        crate::rewrite::uniformity::check_kills(&instrumented.module)
            .unwrap_or_else(|err| panic!("{}: {err:?}", path.display()));
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let file = dir.path().join(format!("{stem}.wgsl"));
        std::fs::write(&file, &instrumented.text).unwrap();
        files.push(file);
        let mut plans = vec![instrumented.plan.clone()];
        for mode in [
            interpolate::iframe::SceneMode::ClosestOnMiss,
            interpolate::iframe::SceneMode::ShadeOnMiss,
            interpolate::iframe::SceneMode::ReverseReprojectionReshade,
            // Offsets into an rgba16float target, whatever the user's
            // colour format.
            interpolate::iframe::SceneMode::Correspondence,
            interpolate::iframe::SceneMode::MovingObjects,
        ] {
            match instrumented.scene_plan(mode) {
                Ok(plan) => plans.push(plan),
                Err(reason) => eprintln!("{}: no scene-assisted pass: {reason}", path.display()),
            }
        }
        for plan in plans {
            built += build(&path, &plan, &|_| Some(instrumented.text.clone()));
        }
        // Payload interpolation's payload and shade passes, where the
        // shader has a node that reads no per-frame input.
        let Ok(candidate) = interpolate::payload::choose(&analysis) else {
            continue;
        };
        let options = crate::rewrite::Options::default();
        let reference = crate::rewrite::plan::reference(&shader, &analysis, &options).unwrap();
        let passes =
            match interpolate::payload::passes(&shader, &analysis, candidate, &options, &reference)
            {
                Ok(passes) => passes,
                Err(refusal) => {
                    refused(&path, "payload", &refusal);
                    continue;
                }
            };
        for (name, text) in &passes.sources {
            let file = dir.path().join(format!("{stem}_{name}"));
            std::fs::write(&file, text).unwrap();
            files.push(file);
        }
        for plan in [&passes.iframe, &passes.shade] {
            built += build(&path, plan, &|name| passes.sources.get(name).cloned());
        }
    }
    for result in super::util::tint_validate(&files) {
        assert!(result.ok, "{}: {:?}", result.file, result.messages);
    }
    for latest in [None, Some(1), Some(4)] {
        interpolate::bframe::BFrames::new(&gpu, (16, 16), &Method::ALL, (3, latest))
            .unwrap_or_else(|err| panic!("{err}"));
    }
    // The morph's passes, with and without the speed gate, at the
    // smallest and the paper's grid, in both orders of blur.
    let paper = interpolate::morph::BlurOrder::Paper;
    let warp_blurred = interpolate::morph::BlurOrder::WarpBlurred;
    for (grid, blur_gated_by_speed, blur_order) in [(2, false, paper), (8, true, warp_blurred)] {
        let setup = interpolate::morph::MorphSetup {
            size: [32, 16],
            grid,
            blur_level: 2,
            blur_gated_by_speed,
            blur_order,
        };
        interpolate::morph::Morph::new(&gpu, setup).unwrap_or_else(|err| panic!("{err}"));
    }
    assert!(built >= 30, "{built} pipelines");
}

/// Seed 000's globe (Fig. 3): turning and moving at once, its silhouette
/// leaves a search started at the pixel, which dual initialisation
/// (each direction also started from the other I-frame's velocity, eqs.
/// 16–17) brings back: fewer pixels far from the reference, fewer double
/// misses.
#[test]
fn dual_init_fixes_rotating_translating_silhouette() {
    let scene = std::fs::read_to_string(root().join("corpus/scenes/globe.toml")).unwrap();
    let run = |dual_init: bool| {
        let options = Options {
            methods: vec![Method::ImageBased],
            size: Some([128, 128]),
            frames: Some(8),
            dual_init,
            keep_frames: true,
            ..Options::default()
        };
        run_interpolation(&marble(), &scene, options)
    };
    let (Some((dual, dual_frames, _)), Some((plain, plain_frames, _))) = (run(true), run(false))
    else {
        return;
    };
    // Pixels more than 0.1 off the reference, over every B-frame.
    let far_off = |pictures: &Pictures| -> usize {
        kept(pictures, Method::ImageBased)
            .iter()
            .map(|k| {
                (0..k.decisions.len())
                    .filter(|&p| {
                        (0..3).any(|c| (k.reference[p * 4 + c] - k.result[p * 4 + c]).abs() > 0.1)
                    })
                    .count()
            })
            .sum()
    };
    let (with, without) = (far_off(&dual_frames), far_off(&plain_frames));
    assert!(
        with * 4 < without * 3,
        "{with} pixels far off with dual initialisation, {without} without"
    );
    let misses = |report: &Report| method(report, Method::ImageBased).double_miss_rate.unwrap();
    assert!(misses(&dual) < misses(&plain));
}

/// The I-frame's flows are where the scene's own matrices put each
/// pixel's surface point at the previous and the next I-frame: every
/// covered pixel away from silhouettes is taken back to its object's
/// space through its depth and this frame's matrices (on the CPU), moved
/// to the other I-frames' and projected, for camera orbits, object turns
/// and moves of several speeds and n = 2 and 4 (property test over the
/// cases).
#[test]
fn flows_match_cpu_projection() {
    let cases = [
        ("1.5", "[0.0, 3.0, 0.0]", "[0.02, 0.0, 0.0]", 4),
        ("0.0", "[5.0, 0.0, 2.0]", "[0.0, 0.03, -0.05]", 2),
        ("-3.0", "[0.0, -8.0, 0.0]", "[-0.06, 0.0, 0.02]", 4),
    ];
    for (orbit, turn, moves, n) in cases {
        let scene_text = sphere_over_floor(
            "\"object-motion\", \"camera-motion\"",
            &format!("orbit_degrees_per_frame = {orbit}"),
            &format!("rotation_degrees_per_frame = {turn}\ntranslation_per_frame = {moves}"),
        );
        let options = Options {
            methods: vec![Method::SampleAndHold],
            frames_per_interval: n,
            frames: Some(2 * n),
            keep_frames: true,
            ..Options::default()
        };
        let Some((report, pictures, scene)) = run_interpolation(&marble(), &scene_text, options)
        else {
            return;
        };
        let [w, h] = report.size.map(|v| v as usize);
        let aspect = w as f32 / h as f32;
        assert!(!pictures.iframes.is_empty());
        let mut checked = 0;
        for iframe in &pictures.iframes {
            let now = scene.frame(iframe.frame, aspect);
            let sphere = super::util::silhouette(&scene, 1, iframe.frame, w, h);
            let floor = super::util::silhouette(&scene, 0, iframe.frame, w, h);
            let sphere_inside = super::util::interior(&sphere, w);
            let floor_inside = super::util::interior(&floor, w);
            for p in 0..w * h {
                let object = if sphere_inside[p] {
                    1
                } else if floor_inside[p] && !super::util::near(&sphere, w, p) {
                    0
                } else {
                    continue;
                };
                let (x, y) = ((p % w) as f32 + 0.5, (p / w) as f32 + 0.5);
                let z = iframe.depth[p];
                let ndc = glam::Vec3::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0, z);
                let world = now.clip_from_world.inverse().project_point3(ndc);
                let local = now.objects[object].inverse().transform_point3(world);
                for (other, flow) in [
                    (iframe.frame - n, &iframe.flow_previous),
                    (iframe.frame + n, &iframe.flow_next),
                ] {
                    let then = scene.frame(other, aspect);
                    let clip = then.clip_from_world * then.objects[object] * local.extend(1.0);
                    let moved = clip.truncate() / clip.w;
                    let expected = glam::Vec3::new(
                        (moved.x * 0.5 + 0.5) * w as f32 - x,
                        (0.5 - 0.5 * moved.y) * h as f32 - y,
                        moved.z - z,
                    );
                    let got = glam::Vec3::new(flow[p * 4], flow[p * 4 + 1], flow[p * 4 + 2]);
                    // Valid, and 2 on what moves in the world (the
                    // sphere), 1 on what is still (the floor).
                    let valid = if scene.moves(object) { 2.0 } else { 1.0 };
                    assert_eq!(
                        flow[p * 4 + 3],
                        valid,
                        "pixel {p} of frame {}",
                        iframe.frame
                    );
                    let off = (got - expected).abs();
                    assert!(
                        off.x <= 0.02 + 2e-3 * expected.x.abs()
                            && off.y <= 0.02 + 2e-3 * expected.y.abs()
                            && off.z <= 1e-4 + 2e-3 * expected.z.abs(),
                        "orbit {orbit}, frame {} → {other}, pixel ({x}, {y}) of object {object}: flow {got}, the scene's matrices say {expected}",
                        iframe.frame
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked} flows checked");
    }
}

/// Flat shading by height, like [`DEPTH_SHADED`], with stripes in the
/// object's own space on what stands in front of the wall only: the wall
/// is one flat colour, the square (bright) carries its stripes along.
pub(crate) const SLIDING_SHADED: &str = with_frame_vertex!(
    r#"
@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let stripes = 0.2 * step(0.5, fract(in.local_position.x * 6.0));
    let front = in.world_position.z > -0.5;
    return vec4<f32>(vec3<f32>(select(0.1, 0.6 + stripes, front)), 1.0);
}
"#
);

/// Brightness of [`SLIDING_SHADED`] above which a pixel shows the square.
pub(crate) const SQUARE: f32 = 0.4;

/// Squares before a wall, the camera still: each `(size, [x, y], speed)`,
/// moving `speed` world units a frame along x, the wall `wall_speed`.
pub(crate) fn squares_before_wall(wall_speed: f32, squares: &[(f32, [f32; 2], f32)]) -> String {
    let objects: String = squares
        .iter()
        .map(|(size, [x, y], speed)| {
            format!(
                r#"[[objects]]
mesh = {{ kind = "plane", size = {size}, subdivisions = 2 }}
position = [{x}, {y}, 0.0]
rotation_degrees = [90.0, 0.0, 0.0]
translation_per_frame = [{speed}, 0.0, 0.0]
"#
            )
        })
        .collect();
    before_wall("standard", wall_speed, &objects)
}

/// A 96² scene of `objects` (TOML) before a wall one unit behind the
/// origin moving `wall_speed` world units a frame along x, the camera
/// still three units in front with depth convention `depth`.
pub(crate) fn before_wall(depth: &str, wall_speed: f32, objects: &str) -> String {
    format!(
        r#"
size = [96, 96]
frames = 8
effects = ["object-motion"]
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
depth = "{depth}"
[light]
position = [0.0, 0.0, 10.0]
[[objects]]
mesh = {{ kind = "plane", size = 6.0, subdivisions = 2 }}
position = [0.0, 0.0, -1.0]
rotation_degrees = [90.0, 0.0, 0.0]
translation_per_frame = [{wall_speed}, 0.0, 0.0]
{objects}"#
    )
}

/// A square sliding to the right before a wall, the camera still, `speed`
/// world units a frame: a constant velocity.
fn sliding_square(speed: f32) -> String {
    squares_before_wall(0.0, &[(0.8, [-0.6, 0.0], speed)])
}

/// World units a frame that move the sliding square `pixels` pixels at
/// 96² (the camera 3 units away, 45° field of view).
pub(crate) fn square_speed(pixels: f32) -> f32 {
    pixels * 2.0 * 3.0 * 22.5f32.to_radians().tan() / 96.0
}

/// Half-velocity's B-frames of the sliding square (n = 2, α = ½) moving
/// `pixels` a frame, with velocity merging or without, and the scene. The
/// square is treated as the rest of the scene (no moving-object offsets
/// or removal): what is checked is the velocity alone.
fn half_velocity_frames(velocity_merge: bool, pixels: f32) -> Option<(Pictures, Scene)> {
    half_velocity_frames_with(velocity_merge, false, pixels)
}

fn half_velocity_frames_with(
    velocity_merge: bool,
    moving_objects: bool,
    pixels: f32,
) -> Option<(Pictures, Scene)> {
    let options = Options {
        methods: vec![Method::HalfVelocity],
        frames_per_interval: 2,
        frames: Some(6),
        velocity_merge,
        moving_objects,
        keep_frames: true,
        ..Options::default()
    };
    run_interpolation(
        SLIDING_SHADED,
        &sliding_square(square_speed(pixels)),
        options,
    )
    .map(|(_, pictures, scene)| (pictures, scene))
}

/// Largest channel difference at pixel `p` of a kept B-frame.
pub(crate) fn error_at(frame: &KeptFrame, p: usize) -> f32 {
    (0..3)
        .map(|c| (frame.reference[p * 4 + c] - frame.result[p * 4 + c]).abs())
        .fold(0.0f32, f32::max)
}

/// At constant velocity, seed 003's middle frame from the earlier frame
/// and the merged velocity is the true middle frame: away from the
/// square's outline at the three times (where rasterisation and the
/// bilinear kernel mix it with the wall) no pixel is more than a
/// resampling error off, the wall the square uncovers (its tail, which the
/// later frame's velocity leaves behind, and which the merge fills with
/// the wall beside it: exact for a flat wall) included. The square moves
/// two pixels a frame, so the half-way samples fall on texel centres.
#[test]
fn half_velocity_constant_motion_is_exact() {
    let Some((pictures, scene)) = half_velocity_frames(true, 2.0) else {
        return;
    };
    let frames = kept(&pictures, Method::HalfVelocity);
    assert!(!frames.is_empty());
    for frame in frames {
        // The square's outline at the B-frame's time and at the two
        // I-frames' (n = 2: a frame before and after).
        let outline: Vec<bool> = {
            let masks: Vec<Vec<bool>> = [frame.frame - 1, frame.frame, frame.frame + 1]
                .iter()
                .map(|&f| super::util::silhouette(&scene, 1, f, 96, 96))
                .collect();
            (0..96 * 96)
                .map(|p| {
                    masks
                        .iter()
                        .any(|m| super::util::near(m, 96, p) && !super::util::interior(m, 96)[p])
                })
                .collect()
        };
        let mut worst = 0.0f32;
        for p in (0..96 * 96).filter(|&p| !outline[p]) {
            worst = worst.max(error_at(frame, p));
        }
        assert!(worst <= 0.02, "frame {}: worst error {worst}", frame.frame);
    }
}

/// Velocity merging takes the earlier frame's velocity where its surface
/// is the nearer (003 slide 31): the tail the square leaves behind is
/// the wall again. With the later frame's velocity alone the tail shows
/// the square where the reference shows the wall (a ghost half the
/// displacement wide).
#[test]
fn velocity_merge_prefers_nearer_surface() {
    let (Some((merged, scene)), Some((current, _))) = (
        half_velocity_frames(true, 4.0),
        half_velocity_frames(false, 4.0),
    ) else {
        return;
    };
    let ghosts = |pictures: &Pictures| -> usize {
        kept(pictures, Method::HalfVelocity)
            .iter()
            .map(|frame| {
                // Where the square was a frame ago and no longer is.
                let now = super::util::silhouette(&scene, 1, frame.frame, 96, 96);
                let before = super::util::silhouette(&scene, 1, frame.frame - 1, 96, 96);
                let inside_before = super::util::interior(&before, 96);
                (0..96 * 96)
                    .filter(|&p| inside_before[p] && !super::util::near(&now, 96, p))
                    .filter(|&p| frame.result[p * 4] > SQUARE && frame.reference[p * 4] < SQUARE)
                    .count()
            })
            .sum()
    };
    let (with, without) = (ghosts(&merged), ghosts(&current));
    assert!(without >= 20, "{without} ghost pixels without merging");
    assert!(
        with * 10 <= without,
        "{with} ghost pixels with merging, {without} without"
    );
}

/// Where a surface is visible in one I-frame only (the wall the square
/// uncovers or covers), image-based takes it from that one (§5.2): on
/// those pixels it is far closer to the reference than linear blending,
/// which ghosts there.
#[test]
fn disoccluded_in_one_frame_taken_from_the_other() {
    let options = Options {
        methods: vec![Method::ImageBased, Method::LinearBlend],
        frames: Some(8),
        keep_frames: true,
        ..Options::default()
    };
    let Some((_, pictures, _)) = run_interpolation(SLIDING_SHADED, &sliding_square(0.04), options)
    else {
        return;
    };
    let image_based = kept(&pictures, Method::ImageBased);
    let blend = kept(&pictures, Method::LinearBlend);
    let (mut ours, mut theirs, mut count) = (0.0f64, 0.0f64, 0);
    for (frame, blended) in image_based.iter().zip(&blend) {
        assert_eq!(frame.frame, blended.frame);
        for p in 0..frame.decisions.len() {
            if frame.decisions[p] == Decision::OneDirection as u32 {
                ours += f64::from(error_at(frame, p));
                theirs += f64::from(error_at(blended, p));
                count += 1;
            }
        }
    }
    assert!(count >= 50, "{count} pixels seen in one I-frame only");
    assert!(
        ours * 4.0 <= theirs,
        "mean error {} image-based, {} linear blend, over {count} pixels",
        ours / count as f64,
        theirs / count as f64
    );
}

/// Seed 000's documented failure (§6, Fig. 4): the image-based search
/// cannot follow blades two pixels wide turning fast, while the
/// scene-assisted B-frame, which rasterises them, can. Measured on the
/// blades' pixels and bounded: finite, and the rest of the frame good.
#[test]
fn thin_fast_geometry() {
    let mesh = root().join("corpus/scenes/meshes/windmill.obj");
    let scene = std::fs::read_to_string(root().join("corpus/scenes/windmill.toml"))
        .unwrap()
        .replace("meshes/windmill.obj", &mesh.display().to_string());
    let options = Options {
        methods: vec![Method::ImageBased, Method::SceneAssisted],
        size: Some([128, 128]),
        frames: Some(8),
        keep_frames: true,
        ..Options::default()
    };
    let Some((report, pictures, scene)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    let on_blades = |method: Method| -> (f64, f64) {
        let (mut blades, mut rest, mut nb, mut nr) = (0.0f64, 0.0f64, 0, 0);
        for frame in kept(&pictures, method) {
            let blade = super::util::silhouette(&scene, 1, frame.frame, 128, 128);
            for p in 0..blade.len() {
                let error = error_at(frame, p);
                assert!(error.is_finite(), "{}: not finite at {p}", method.name());
                if blade[p] {
                    blades += f64::from(error);
                    nb += 1;
                } else if !super::util::near(&blade, 128, p) {
                    rest += f64::from(error);
                    nr += 1;
                }
            }
        }
        (blades / nb as f64, rest / nr as f64)
    };
    let (image_blades, image_rest) = on_blades(Method::ImageBased);
    let (scene_blades, _) = on_blades(Method::SceneAssisted);
    eprintln!(
        "mean error on the blades: image-based {image_blades:.4}, scene-assisted {scene_blades:.4}; elsewhere image-based {image_rest:.4}"
    );
    assert!(
        image_blades > 3.0 * scene_blades,
        "image-based follows the blades ({image_blades} against {scene_blades}): the documented failure is gone, update docs/results-interpolation.md"
    );
    assert!(image_blades < 0.5, "image-based's blades: {image_blades}");
    assert!(
        image_rest < 0.02,
        "image-based off the blades: {image_rest}"
    );
    assert!(method(&report, Method::ImageBased).ssim_mean > 0.9);
}

/// `--motion-blur` (000 §9): each method's frames around every I-frame
/// averaged and compared with the reference's composite. Without motion
/// every composite is the I-frame's; with motion the bidirectional
/// methods' composites are closer to the reference's than
/// sample-and-hold's, which repeats one frame.
#[test]
fn motion_blur_composites_b_frames_around_each_i_frame() {
    let run = |effects: &str, camera: &str, sphere: &str| {
        let options = Options {
            frames: Some(12),
            motion_blur: true,
            // A still picture stays the I-frame under the morph too.
            blur_min_speed: Some(0.15),
            ..Options::default()
        };
        run_interpolation(
            &marble(),
            &sphere_over_floor(effects, camera, sphere),
            options,
        )
        .map(|(report, _, _)| report)
    };
    let Some(still) = run("", "", "") else {
        return;
    };
    for m in &still.methods {
        let ssim = m.motion_blur_ssim.expect("motion blur measured");
        assert!(ssim >= 0.9999, "{}: {ssim}", m.method.name());
    }
    let Some(moving) = run(
        "\"object-motion\", \"camera-motion\"",
        "orbit_degrees_per_frame = 1.5",
        "rotation_degrees_per_frame = [0.0, 3.0, 0.0]\ntranslation_per_frame = [0.04, 0.0, 0.0]",
    ) else {
        return;
    };
    let blur = |m: Method| method(&moving, m).motion_blur_ssim.unwrap();
    for m in [
        Method::ImageBased,
        Method::SceneAssisted,
        Method::LinearBlend,
    ] {
        assert!(
            blur(m) > blur(Method::SampleAndHold),
            "{}: {} against sample-and-hold's {}",
            m.name(),
            blur(m),
            blur(Method::SampleAndHold)
        );
    }
    assert_eq!(blur(Method::Reference), 1.0);
}

/// 000 Fig. 11: image-based's correspondences against the exact ones the
/// scene-assisted pass computes. For a square sliding at constant speed
/// (a translation: the search converges in one step) they are the exact
/// ones up to the flows' precision wherever I-frame 0 shows the point;
/// for the turning, moving globe they are pixels off (the silhouettes).
#[test]
fn correspondence_error_is_measured_against_scene_assisted() {
    let run = |shader: &str, scene: &str| {
        let options = Options {
            methods: vec![Method::ImageBased],
            size: Some([96, 96]),
            frames: Some(8),
            ..Options::default()
        };
        run_interpolation(shader, scene, options).map(|(report, _, _)| {
            method(&report, Method::ImageBased)
                .correspondence_error_px
                .clone()
                .expect("measured")
        })
    };
    let Some(sliding) = run(SLIDING_SHADED, &sliding_square(0.04)) else {
        return;
    };
    let globe = std::fs::read_to_string(root().join("corpus/scenes/globe.toml")).unwrap();
    let Some(turning) = run(&marble(), &globe) else {
        return;
    };
    eprintln!("sliding {sliding:?}, globe {turning:?}");
    assert!(sliding.hit < 0.1, "{sliding:?}");
    assert!(sliding.hit <= sliding.all);
    assert!(
        turning.all > 10.0 * sliding.hit,
        "{turning:?} against {sliding:?}"
    );
}

/// Two starts of one search direction can both converge, on different
/// surfaces: at a moving sphere's rim the start at p finds the floor
/// point the sphere hides at the B-frame's time, the dual start the
/// sphere. Both are fixed points with residuals under ε1; the nearer is
/// kept. Taking the smaller residual instead (the paper's rule for the
/// starts) shrinks the sphere by its rim: 13% of the pixels along its
/// outline far off, against 3%.
#[test]
fn converged_starts_on_two_surfaces_keep_the_nearer() {
    let Some((outline, far_off)) = rim_far_off(false) else {
        return;
    };
    assert!(outline > 500, "{outline} outline pixels");
    assert!(
        far_off * 100 <= outline * 6,
        "{far_off} of {outline} outline pixels far off: the sphere lost its rim"
    );
}

/// `--paper`: seed 000's selection as it states it, the smaller residual
/// of two converged starts, with dual and latest-frame initialisation. On
/// the same rim it keeps the floor behind the sphere where the default
/// keeps the sphere: the rim's pixels far off at least twice as often.
#[test]
fn paper_configuration_keeps_smaller_residual() {
    let (Some((outline, paper)), Some((_, default))) = (rim_far_off(true), rim_far_off(false))
    else {
        return;
    };
    assert!(
        paper >= 2 * default && paper * 100 >= outline * 8,
        "{paper} of {outline} outline pixels far off with the smaller residual, {default} with the nearer surface"
    );
}

/// A sphere moving and turning over the floor, the camera orbiting: its
/// outline's pixels at each image-based B-frame's time, and how many are
/// more than 0.1 off the reference, with the smaller-residual selection
/// (and the paper's initialisations) or the default.
fn rim_far_off(paper: bool) -> Option<(usize, usize)> {
    let scene_text = sphere_over_floor(
        "\"object-motion\", \"camera-motion\"",
        "orbit_degrees_per_frame = 1.0",
        "position = [-0.5, -0.2, 0.0]\nrotation_degrees_per_frame = [0.0, 4.0, 0.0]\ntranslation_per_frame = [0.035, 0.0, 0.0]",
    );
    let options = Options {
        methods: vec![Method::ImageBased],
        size: Some([128, 128]),
        frames: Some(8),
        keep_frames: true,
        smaller_residual: paper,
        latest_frame_init: paper,
        ..Options::default()
    };
    let (_, pictures, scene) = run_interpolation(&marble(), &scene_text, options)?;
    let (mut outline, mut far_off) = (0, 0);
    for frame in kept(&pictures, Method::ImageBased) {
        let sphere = super::util::silhouette(&scene, 1, frame.frame, 128, 128);
        let outside: Vec<bool> = sphere.iter().map(|s| !s).collect();
        for p in (0..sphere.len()).filter(|&p| sphere[p] && super::util::near(&outside, 128, p)) {
            outline += 1;
            far_off += usize::from(error_at(frame, p) > 0.1);
        }
    }
    Some((outline, far_off))
}

/// Two squares crossing before a wall in opposite directions, the camera
/// still, `speed` world units a frame each.
fn crossing_squares(speed: f32) -> String {
    squares_before_wall(
        0.0,
        &[(0.5, [-0.6, 0.4], speed), (0.5, [0.6, -0.4], -speed)],
    )
}

/// Seed 003's moving objects (slides 33–47): drawn at the B-frame's time
/// they are where they are, and where they have left the earlier frame
/// shows the wall synthesised around them, not the objects again. With
/// the later frame's velocity alone (no merging, which hides the tails
/// another way) and without the moving objects, each square leaves a
/// ghost half its displacement wide; with them, none.
#[test]
fn moving_objects_leave_no_tail() {
    let run = |moving_objects: bool| {
        let options = Options {
            methods: vec![Method::HalfVelocity],
            frames_per_interval: 2,
            frames: Some(6),
            velocity_merge: false,
            moving_objects,
            keep_frames: true,
            ..Options::default()
        };
        run_interpolation(
            SLIDING_SHADED,
            &crossing_squares(square_speed(4.0)),
            options,
        )
    };
    let (Some((_, with, scene)), Some((_, without, _))) = (run(true), run(false)) else {
        return;
    };
    // Pixels showing a square where the reference shows the wall, and
    // the squares' pixels more than a resampling error off, away from
    // the squares' outlines at the three times.
    let count = |pictures: &Pictures| -> (usize, usize) {
        let (mut ghosts, mut off) = (0, 0);
        for frame in kept(pictures, Method::HalfVelocity) {
            let times = [frame.frame - 1, frame.frame, frame.frame + 1];
            let masks: Vec<Vec<bool>> = [1, 2]
                .iter()
                .flat_map(|&o| times.map(|f| super::util::silhouette(&scene, o, f, 96, 96)))
                .collect();
            let outline = |p: usize| {
                masks
                    .iter()
                    .any(|m| super::util::near(m, 96, p) && !super::util::interior(m, 96)[p])
            };
            for p in (0..96 * 96).filter(|&p| !outline(p)) {
                if frame.result[p * 4] > SQUARE && frame.reference[p * 4] < SQUARE {
                    ghosts += 1;
                }
                if frame.reference[p * 4] > SQUARE && error_at(frame, p) > 0.02 {
                    off += 1;
                }
            }
        }
        (ghosts, off)
    };
    let ((ghosts, off), (ghosts_without, _)) = (count(&with), count(&without));
    assert!(
        ghosts_without >= 40,
        "{ghosts_without} ghost pixels without the moving objects"
    );
    assert_eq!(ghosts, 0, "ghost pixels with the moving objects");
    assert_eq!(off, 0, "square pixels off with the moving objects");
}

/// Character removal's rules (003 slide 46), on a synthetic mask: a
/// masked pixel with an unmasked neighbour `delta` away takes their mean;
/// one with none is left as it was, still masked; each pass reaches
/// `delta` further in, so the fill grows from the mask's edge.
#[test]
fn character_removal_fills_from_unmasked_neighbours() {
    use crate::interpolate::bframe::{BFrameParams, BFrames};
    use wgpu::util::DeviceExt;
    let Some(gpu) = super::gpu::gpu() else {
        return;
    };
    // 32 × 32: colour x/32 in red, y/32 in green; a moving object (flow w
    // = 2) over columns 8–23 of every row.
    let (w, h) = (32u32, 32u32);
    let texture = |label, format, bytes: &[u8]| {
        gpu.device.create_texture_with_data(
            &gpu.queue,
            &wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytes,
        )
    };
    let half = |v: f32| half::f16::from_f32(v).to_le_bytes();
    let masked = |x: u32| (8..24).contains(&x);
    let mut color = Vec::new();
    let mut flow = Vec::new();
    for y in 0..h {
        for x in 0..w {
            for v in [x as f32 / 32.0, y as f32 / 32.0, 0.0, 1.0] {
                color.extend(half(v));
            }
            let valid = if masked(x) { 2.0 } else { 1.0 };
            for v in [0.0, 0.0, 0.0, valid] {
                flow.extend(half(v));
            }
        }
    }
    let color = texture("colour", wgpu::TextureFormat::Rgba16Float, &color);
    let flow = texture("flow", wgpu::TextureFormat::Rgba16Float, &flow);
    let bframes = BFrames::new(&gpu, (w, h), &[Method::HalfVelocity], (3, None)).unwrap();
    let params = BFrameParams {
        viewport: [w as f32, h as f32],
        alpha: 0.5,
        screen_epsilon: 1.0,
        depth_epsilon: 0.01,
        far_depth: 1.0,
        dual_init: true,
        smaller_residual: false,
        velocity_merge: true,
        moving_objects: true,
        min_cosine: 0.5,
        previous_alpha: None,
        inpaint_delta: 1,
    };
    // At quarter resolution (16 × 16, pixel i reading column 2i): columns
    // 4–11 masked. One pass fills 4 and 11 from 3 and 12.
    let removal = |passes: u32| -> Vec<f32> {
        bframes.remove_moving_objects(&gpu, (&color, &flow), &params, passes, None);
        let bytes = crate::runtime::read_texture(&gpu, bframes.removed(), 8).unwrap();
        crate::measure::metrics::linear_from_f16(&bytes)
    };
    let at = |pixels: &[f32], x: usize, y: usize| -> [f32; 4] {
        let i = (y * 16 + x) * 4;
        [pixels[i], pixels[i + 1], pixels[i + 2], pixels[i + 3]]
    };
    let close = |a: f32, b: f32| (a - b).abs() < 2e-3;
    let one = removal(1);
    let y = 5;
    let row = 2.0 * y as f32 / 32.0;
    for x in 0..16 {
        let [r, g, _, state] = at(&one, x, y);
        let source = 2.0 * x as f32 / 32.0;
        match x {
            // Unmasked: unchanged, never masked.
            0..=3 | 12..=15 => assert!(close(r, source) && state == 0.0, "x {x}: {r} {state}"),
            // The edge: the mean of the unmasked neighbours, left and
            // right of it (3 and 12 in the full frame's 6 and 24) and
            // above and below (masked too).
            4 => assert!(
                close(r, 6.0 / 32.0) && close(g, row) && state == 0.5,
                "x 4: {r} {g} {state}"
            ),
            11 => assert!(close(r, 24.0 / 32.0) && state == 0.5, "x 11: {r} {state}"),
            // Inside: no unmasked neighbour, left as it was, still masked.
            _ => assert!(close(r, source) && state == 1.0, "x {x}: {r} {state}"),
        }
    }
    // Three passes: columns 4–6 and 9–11 filled, each from the one
    // filled before; 7 and 8 still masked.
    let three = removal(3);
    for x in [4, 5, 6, 9, 10, 11] {
        assert_eq!(at(&three, x, y)[3], 0.5, "x {x} after three passes");
    }
    assert!(close(at(&three, 5, y)[0], 6.0 / 32.0), "x 5 takes 4's fill");
    for x in [7, 8] {
        assert_eq!(at(&three, x, y)[3], 1.0, "x {x} after three passes");
    }
}

/// A small square in front of a wall, the two moving apart (the square 5
/// pixels a frame to the right, the wall 3 to the left, 32 pixels apart
/// over an interval of n = 4). Where the square has moved past what
/// either I-frame shows at a pixel, neither the start at p nor the dual
/// start finds it; latest-frame initialisation (000 eqs. 18–19) starts
/// from the offsets the B-frame before found around the pixel, the
/// nearest surface's (§5.3: "particularly helpful near depth
/// discontinuities"), and finds it: half as many pixels along the
/// square's outline far off (192 against 384; from the centre tap alone,
/// no better than without). On the bundled scenes it measures worse on
/// average, which is why it is off by default.
#[test]
fn latest_frame_init_helps_at_discontinuities() {
    // The wall is 4 units from the camera, the square 3.
    let scene_text = squares_before_wall(
        -square_speed(3.0) * 4.0 / 3.0,
        &[(0.4, [-0.6, 0.0], square_speed(5.0))],
    );
    let run = |latest_frame_init: bool| {
        let options = Options {
            methods: vec![Method::ImageBased],
            frames: Some(8),
            latest_frame_init,
            keep_frames: true,
            ..Options::default()
        };
        run_interpolation(SLIDING_SHADED, &scene_text, options)
    };
    let (Some((_, with, scene)), Some((_, without, _))) = (run(true), run(false)) else {
        return;
    };
    // Pixels more than 0.1 off, next to or on the square at the
    // B-frame's time.
    let far_off = |pictures: &Pictures| -> usize {
        kept(pictures, Method::ImageBased)
            .iter()
            .map(|frame| {
                let square = super::util::silhouette(&scene, 1, frame.frame, 96, 96);
                (0..96 * 96)
                    .filter(|&p| super::util::near(&square, 96, p) && error_at(frame, p) > 0.1)
                    .count()
            })
            .sum()
    };
    let (with, without) = (far_off(&with), far_off(&without));
    assert!(without >= 100, "{without} pixels far off without");
    assert!(
        with * 3 <= without * 2,
        "{with} pixels far off along the outline with latest-frame initialisation, {without} without"
    );
}

/// Instanced as the wgpu tutorial draws: each instance's model matrix as
/// four per-instance vertex inputs, shaded by stripes in the object's
/// own space (the colour moves with the surface, whatever the view).
const TUTORIAL_INSTANCED: &str = r#"
struct Camera {
    view_proj: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> camera: Camera;

struct InstanceInput {
    @location(5) model_matrix_0: vec4<f32>,
    @location(6) model_matrix_1: vec4<f32>,
    @location(7) model_matrix_2: vec4<f32>,
    @location(8) model_matrix_3: vec4<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) local: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, instance: InstanceInput) -> VertexOutput {
    let model = mat4x4<f32>(
        instance.model_matrix_0,
        instance.model_matrix_1,
        instance.model_matrix_2,
        instance.model_matrix_3,
    );
    var out: VertexOutput;
    out.clip_position = camera.view_proj * model * vec4<f32>(position, 1.0);
    out.local = position;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let stripes = step(vec3<f32>(0.5), fract(in.local * 4.0));
    return vec4<f32>(0.2 + 0.6 * stripes, 1.0);
}
"#;

/// The per-instance inputs the position reads get a twin per other
/// I-frame, filled with that I-frame's values: the scene-assisted
/// B-frames of orbiting, spinning instances land where the reference
/// draws them. Were the twins fed this frame's values, every instance
/// would stay put between the I-frames.
#[test]
fn per_instance_positions_are_twinned_per_i_frame() {
    let scene_text = r#"
size = [96, 96]
frames = 8
effects = ["object-motion"]
[camera]
eye = [0.0, 3.0, 4.5]
target = [0.0, 0.0, 0.0]
[[objects]]
mesh = { kind = "cube", size = 0.7 }
[objects.instances]
count = 4
layout = "grid"
spacing = 1.5
orbit_degrees_per_frame = 4.0
spin_degrees_per_frame = [0.0, 6.0, 0.0]
[roles]
"camera.view_proj" = "clip_from_world"
"#;
    let options = Options {
        methods: vec![
            Method::SceneAssisted,
            Method::ImageBased,
            Method::LinearBlend,
            Method::SampleAndHold,
        ],
        frames: Some(8),
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(TUTORIAL_INSTANCED, scene_text, options) else {
        return;
    };
    let ssim = |m: Method| method(&report, m).ssim_mean;
    let (scene, image, blend, hold) = (
        ssim(Method::SceneAssisted),
        ssim(Method::ImageBased),
        ssim(Method::LinearBlend),
        ssim(Method::SampleAndHold),
    );
    eprintln!(
        "scene-assisted {scene:.4}, image-based {image:.4}, linear blend {blend:.4}, sample-and-hold {hold:.4}"
    );
    assert!(hold < 0.9, "sample-and-hold {hold}: the scene barely moves");
    assert!(scene > 0.97, "scene-assisted {scene}");
    assert!(
        image > blend + 0.05,
        "image-based {image}, linear blend {blend}"
    );
}
