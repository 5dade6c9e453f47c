//! Objects drawn at every displayed frame (`every_frame` in the scene,
//! seed 000 Fig. 4(d)): left out of the I-frames, depth-tested into every
//! method's frames.

use crate::interpolate::{Method, Options};

use super::interpolate::{marble, method, run_interpolation};
use super::util::root;

/// The windmill (blades two pixels wide turning 12° a frame before a
/// still wall), small, its blades drawn every frame or not.
fn windmill(every_frame: bool) -> String {
    let mesh = root().join("corpus/scenes/meshes/windmill.obj");
    std::fs::read_to_string(root().join("corpus/scenes/windmill.toml"))
        .unwrap()
        .replace("size = [256, 256]", "size = [96, 96]")
        .replace("frames = 16", "frames = 8")
        .replace("meshes/windmill.obj", &mesh.display().to_string())
        .replace(
            "rotation_degrees_per_frame = [0.0, 0.0, 12.0]",
            &format!("rotation_degrees_per_frame = [0.0, 0.0, 12.0]\nevery_frame = {every_frame}"),
        )
}

/// Interpolated by the image-space methods, the blades leave ghosts (a
/// blend of where they were in each I-frame) and holes; drawn at every displayed frame through the
/// Z-buffer bridge, every method's frames are the reference's up to
/// rounding: no ghost. Image-based is bridged with the depth its search
/// chose, scene-assisted with its own pass's, sample-and-hold and linear
/// blending with I-frame 0's. The I-frames, shown with the blades, stay
/// the reference.
#[test]
fn thin_object_rendered_every_frame_has_no_ghost() {
    let methods = vec![
        Method::SampleAndHold,
        Method::LinearBlend,
        Method::ImageBased,
        Method::SceneAssisted,
    ];
    let run = |every_frame| {
        let options = Options {
            methods: methods.clone(),
            ..Options::default()
        };
        run_interpolation(&marble(), &windmill(every_frame), options).map(|(report, _, _)| report)
    };
    let (Some(interpolated), Some(drawn)) = (run(false), run(true)) else {
        return;
    };
    assert_eq!(drawn.i_frame_psnr_min, 100.0);
    for &m in &methods {
        let (before, after) = (method(&interpolated, m), method(&drawn, m));
        // Scene-assisted rasterises the blades at the B-frame's time
        // already; what it shows of them is only as good as the I-frames'.
        assert!(
            m == Method::SceneAssisted || before.psnr_mean < 40.0,
            "{}: {} dB with the blades interpolated",
            m.name(),
            before.psnr_mean
        );
        assert!(
            after.ssim_min > 0.999 && after.psnr_mean > 60.0,
            "{}: SSIM {} (worst {}), {} dB with the blades drawn every frame",
            m.name(),
            after.ssim_mean,
            after.ssim_min,
            after.psnr_mean
        );
    }
    assert!(drawn.notes.iter().any(|n| n.contains("every_frame")));
}

/// With the blades drawn every frame, sample-and-hold, linear blending
/// and scene-assisted show the reference's frames (up to rounding), so
/// the eye following the motion sees what it sees in the reference:
/// their pursuit error is 0, as the reference's is. It was the blades'
/// contribution (0.006–0.008) when a method's first frame was taken from
/// the I-frame's colour target, drawn without them.
#[test]
fn pursuit_error_is_zero_for_the_reference_with_every_frame_objects() {
    let methods = vec![
        Method::SampleAndHold,
        Method::LinearBlend,
        Method::SceneAssisted,
    ];
    let options = Options {
        methods: methods.clone(),
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(&marble(), &windmill(true), options) else {
        return;
    };
    for &m in &methods {
        let measured = method(&report, m);
        assert!(
            measured.psnr_mean > 60.0,
            "{}: {} dB",
            m.name(),
            measured.psnr_mean
        );
        let pursuit = measured.pursuit_error.expect("a pursuit error");
        assert!(pursuit < 1e-4, "{}: pursuit error {pursuit}", m.name());
    }
}

/// The bridge carries each frame's depth: blades turning behind the wall
/// stay hidden in every method's frames (bridged with a far plane, or
/// with no depth, they would be drawn over it).
#[test]
fn every_frame_object_behind_a_surface_stays_hidden() {
    let methods = vec![
        Method::SampleAndHold,
        Method::ImageBased,
        Method::SceneAssisted,
    ];
    let scene = windmill(true).replace("position = [0.0, 0.0, 0.5]", "position = [0.0, 0.0, -1.5]");
    let options = Options {
        methods: methods.clone(),
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    for &m in &methods {
        let m = method(&report, m);
        assert!(
            m.psnr_mean > 60.0,
            "{}: {} dB",
            m.method.name(),
            m.psnr_mean
        );
    }
}
