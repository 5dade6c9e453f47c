//! Whole-frame reuse (`shadecache interpolate`): the I-frame pass, the
//! B-frame methods, the run and its report, on small scenes.

use shadecache::interpolate::bframe::Decision;
use shadecache::interpolate::report::{KeptFrame, Pictures, Report};
use shadecache::interpolate::{self, Method, Options};
use shadecache::profile::Quiet;
use shadecache::scene::Scene;

use crate::util::{root, temp_file};

/// Runs `shader_text` on `scene_text` with `options`; `None` (said on
/// stderr) without a GPU adapter outside CI.
pub(crate) fn run_interpolation(
    shader_text: &str,
    scene_text: &str,
    options: Options,
) -> Option<(Report, Pictures, Scene)> {
    crate::gpu::gpu()?;
    let (_dir, scene_path) = temp_file("scene.toml", scene_text.as_bytes());
    let scene = Scene::load(&scene_path).unwrap_or_else(|e| panic!("{}", e.render()));
    let shader = shadecache::front::parse(shadecache::diagnostic::SourceFile::new(
        "test.wgsl",
        shader_text,
    ))
    .unwrap_or_else(|e| panic!("{}", e.render()));
    let (report, pictures) =
        interpolate::interpolate(&shader, &scene, &scene_path, &options, &mut Quiet)
            .unwrap_or_else(|e| panic!("{}", e.render()));
    Some((report, pictures, scene))
}

fn marble() -> String {
    std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap()
}

/// A marble sphere over a marble floor; `effects`, `camera` and `sphere`
/// (TOML lines) set the motion.
fn sphere_over_floor(effects: &str, camera: &str, sphere: &str) -> String {
    format!(
        r#"
size = [96, 96]
frames = 8
effects = [{effects}]
[camera]
eye = [0.0, 1.2, 3.4]
target = [0.0, -0.3, 0.0]
{camera}
[[objects]]
mesh = {{ kind = "plane", size = 6.0, subdivisions = 4 }}
position = [0.0, -1.0, 0.0]
[[objects]]
mesh = {{ kind = "sphere", rings = 24, segments = 32 }}
scale = 0.8
{sphere}
[uniforms]
marble_frequency = 4.0
turbulence_amount = 6.0
light_color = [1.0, 1.0, 1.0]
"#
    )
}

fn method<'a>(report: &'a Report, method: Method) -> &'a interpolate::report::MethodReport {
    report
        .methods
        .iter()
        .find(|m| m.method == method)
        .unwrap_or_else(|| panic!("{} missing from the report", method.name()))
}

fn kept(pictures: &Pictures, method: Method) -> Vec<&KeptFrame> {
    pictures
        .kept
        .iter()
        .filter(|k| k.method == method)
        .collect()
}

/// Without motion every method's B-frames are the I-frames (up to one
/// rounding of the blend), the I-frames the reference, and the report says
/// the scene has none.
#[test]
fn static_scene_b_frames_equal_i_frames() {
    let scene = sphere_over_floor("", "", "");
    let options = Options {
        frames: Some(4),
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
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
    ] {
        let ends: Vec<&KeptFrame> = kept(&pictures, m)
            .into_iter()
            .filter(|k| k.alpha == 0.0 || (k.alpha == 1.0 && m.reads_later_frame()))
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
                assert!(
                    m == Method::ImageBased && decision != Decision::SameSurface as u32,
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

/// Flat shading by height above the backdrop, so that what a pixel shows
/// says which surface it is: the windmill's blades (z = 0.5) are bright,
/// the backdrop (z = −1) dark, striped so that it has detail.
const DEPTH_SHADED: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let stripes = 0.1 * step(0.5, fract(in.world_position.x * 4.0));
    return vec4<f32>(vec3<f32>(0.1 + 0.5 * (in.world_position.z + 1.0) + stripes), 1.0);
}
"#;

/// Brightness of [`DEPTH_SHADED`] above which a pixel shows a blade.
const BLADE: f32 = 0.8;

/// A two-bladed windmill turning 45° a frame in front of a backdrop: at
/// n = 4 the blades are where they were one interval before, so the
/// backdrop behind them is hidden in both I-frames and shown between them
/// (seed 000 §6's double misses). `depth` is the camera's convention.
fn windmill(depth: &str) -> String {
    let mesh = root().join("corpus/scenes/meshes/windmill.obj");
    format!(
        r#"
size = [96, 96]
frames = 8
effects = ["object-motion"]
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
depth = "{depth}"
[[objects]]
mesh = {{ kind = "plane", size = 6.0, subdivisions = 2 }}
position = [0.0, 0.0, -1.0]
rotation_degrees = [90.0, 0.0, 0.0]
[[objects]]
mesh = {{ kind = "obj", file = "{}" }}
position = [0.0, 0.0, 0.5]
rotation_degrees = [0.0, 0.0, 10.0]
rotation_degrees_per_frame = [0.0, 0.0, 45.0]
"#,
        mesh.display()
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

/// Closest-on-miss fills a double miss with the nearer of the two I-frames'
/// surfaces at the reprojected positions: behind the windmill's blades,
/// the blade (bright), not the backdrop the reference shows; with
/// reversed Z the same ("nearer" is the larger depth there).
#[test]
fn double_miss_closest_on_miss_takes_the_nearer_surface() {
    for depth in ["standard", "reversed"] {
        let Some(pictures) = windmill_frames(depth, vec![Method::SceneAssisted]) else {
            return;
        };
        let mut misses = 0;
        for frame in kept(&pictures, Method::SceneAssisted) {
            // The backdrop behind the blades' old places (the blades'
            // own pixels can miss too: at two pixels wide, a reprojected
            // point's nearest texel may fall beside the blade).
            let behind = double_misses(frame)
                .into_iter()
                .filter(|&p| frame.reference[p * 4] < BLADE);
            for p in behind {
                misses += 1;
                assert!(
                    frame.result[p * 4] > BLADE,
                    "{depth} Z, frame {}, pixel {p}: closest-on-miss shows {} (the reference {})",
                    frame.frame,
                    frame.result[p * 4],
                    frame.reference[p * 4]
                );
            }
        }
        assert!(misses > 20, "{depth} Z: only {misses} double misses");
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
/// shade-on-miss pass) and the fullscreen B-frame passes: valid under
/// naga with every flag (the instrumenting validates it) and Tint, no
/// derivative after a `discard` (naga writes it as a termination), and a
/// wgpu pipeline per pass of every plan.
#[test]
fn every_interpolation_pass_is_valid_and_builds() {
    let Some(gpu) = crate::gpu::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut files = vec![root().join("shaders/bframe.wgsl")];
    let mut built = 0;
    for path in crate::util::corpus() {
        let text = std::fs::read_to_string(root().join(&path)).unwrap();
        let (shader, analysis) = crate::util::analyzed(&path.display().to_string(), &text);
        let instrumented = match interpolate::iframe::instrument(
            &shader,
            &analysis,
            &shadecache::rewrite::Options::default(),
        ) {
            Ok(instrumented) => instrumented,
            Err(refusal) => {
                assert!(
                    !refusal.is_internal(),
                    "{}: {}",
                    path.display(),
                    refusal.reason
                );
                eprintln!("{}: refused: {}", path.display(), refusal.reason);
                continue;
            }
        };
        shadecache::rewrite::uniformity::check_kills(&instrumented.module)
            .unwrap_or_else(|err| panic!("{}: {err:?}", path.display()));
        let file = dir.path().join(format!(
            "{}.wgsl",
            path.file_stem().unwrap().to_string_lossy()
        ));
        std::fs::write(&file, &instrumented.text).unwrap();
        files.push(file);
        let mut plans = vec![instrumented.plan.clone()];
        for mode in [
            interpolate::iframe::SceneMode::ClosestOnMiss,
            interpolate::iframe::SceneMode::ShadeOnMiss,
        ] {
            match instrumented.scene_plan(mode) {
                Ok(plan) => plans.push(plan),
                Err(reason) => eprintln!("{}: no scene-assisted pass: {reason}", path.display()),
            }
        }
        for plan in plans {
            plan.check()
                .unwrap_or_else(|err| panic!("{}: {err}", path.display()));
            built += shadecache::runtime::build_passes(
                &gpu,
                &plan,
                |_| Some(instrumented.text.clone()),
                shadecache::runtime::PipelineOptions::default(),
            )
            .unwrap_or_else(|err| panic!("{}: {err}", path.display()));
        }
    }
    for result in crate::util::tint_validate(&files) {
        assert!(result.ok, "{}: {:?}", result.file, result.messages);
    }
    interpolate::bframe::BFrames::new(&gpu, (16, 16), &Method::ALL)
        .unwrap_or_else(|err| panic!("{err}"));
    assert!(built >= 30, "{built} pipelines");
}

/// Bad knobs and methods get a clear error and exit 1, before anything is
/// written.
#[test]
fn interpolate_bad_input_is_an_error() {
    let out = tempfile::tempdir().unwrap();
    let out_dir = out.path().join("report");
    let marble = "corpus/noise_marble.wgsl";
    let scene = "corpus/scenes/marble_sphere.toml";
    let out_arg = out_dir.display().to_string();
    for (args, says) in [
        (vec!["--frames-per-interval", "1"], "frames-per-interval"),
        (vec!["--iterations", "0"], "iterations"),
        (vec!["--method", "optical-flow"], "optical-flow"),
        (vec!["--screen-epsilon=-1"], "screen-epsilon"),
    ] {
        let mut full = vec!["interpolate", marble, "--scene", scene, "--out", &out_arg];
        full.extend(args.iter().copied());
        let output = crate::util::shadecache(&full);
        assert_eq!(output.status.code(), Some(1), "{args:?}");
        let err = crate::util::stderr(&output);
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!out_dir.exists(), "{args:?} wrote a report");
    }
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
