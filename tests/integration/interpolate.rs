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
