//! Payload interpolation (`interpolate --method payload`): the cache's
//! payload interpolated between I-frames and shaded at each B-frame's
//! time.

use crate::interpolate::{Method, Options};

use super::interpolate::{marble, method, run_interpolation};
use super::util::root;

/// Seed 000 §6's limitation: where only the light moves, every warping
/// method carries the I-frames' shading along the (zero) flow, so the
/// highlight blends between its I-frame places; the payload (the
/// marble's albedo, which no light touches) interpolated and shaded at
/// the B-frame's time keeps it where it is. Its SSIM is above both
/// image-based's and sample-and-hold's, and its I-frames cost more than
/// image-based's by the payload pass.
#[test]
fn moving_light_payload_interpolation_beats_colour_warping() {
    let scene = std::fs::read_to_string(root().join("corpus/scenes/moving_light.toml"))
        .unwrap()
        .replace("size = [256, 256]", "size = [96, 96]")
        .replace("frames = 16", "frames = 8");
    let options = Options {
        methods: vec![Method::SampleAndHold, Method::ImageBased, Method::Payload],
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    let payload = method(&report, Method::Payload);
    for other in [Method::SampleAndHold, Method::ImageBased] {
        let other = method(&report, other);
        assert!(
            payload.ssim_mean > other.ssim_mean + 0.005,
            "payload SSIM {} against {}'s {}",
            payload.ssim_mean,
            other.method.name(),
            other.ssim_mean
        );
    }
    assert!(payload.ssim_min > 0.99, "{}", payload.ssim_min);
    assert_eq!(payload.added_latency_frames, 3.0);
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.contains("payload interpolates node") && n.contains("mix(vein_color")),
        "{:?}",
        report.notes
    );
}
