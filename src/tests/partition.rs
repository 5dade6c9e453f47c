//! Partitioned rendering (`interpolate --partition`, seed 000 §7): each
//! I-frame drawn in n parts, one per displayed frame.

use crate::interpolate::{Method, Options};

use super::interpolate::{marble, method, run_interpolation};

/// Four marble spheres in a row, the nearest first in draw order (so a
/// later part draws farther surfaces behind what an earlier one drew),
/// over a floor drawn last, the camera orbiting.
fn spheres_in_a_row() -> String {
    let mut scene = String::from(
        r#"
size = [96, 96]
frames = 8
effects = ["camera-motion"]
[camera]
eye = [0.0, 1.0, 3.6]
target = [0.0, -0.2, 0.0]
orbit_degrees_per_frame = 1.5
"#,
    );
    for (i, z) in [1.2, 0.4, -0.4, -1.2].iter().enumerate() {
        scene.push_str(&format!(
            "[[objects]]\nmesh = {{ kind = \"sphere\", rings = 16, segments = 24 }}\nscale = 0.45\nposition = [{x}, -0.4, {z}]\n",
            x = 0.35 * i as f32 - 0.5,
        ));
    }
    scene.push_str(
        r#"[[objects]]
mesh = { kind = "plane", size = 6.0, subdivisions = 4 }
position = [0.0, -1.0, 0.0]
[uniforms]
marble_frequency = 4.0
turbulence_amount = 6.0
light_color = [1.0, 1.0, 1.0]
"#,
    );
    scene
}

fn run(partition: bool) -> Option<crate::interpolate::report::Report> {
    let options = Options {
        methods: vec![Method::SampleAndHold, Method::ImageBased],
        partition,
        ..Options::default()
    };
    run_interpolation(&marble(), &spheres_in_a_row(), options).map(|(report, _, _)| report)
}

/// Hard case 20 of the design notes: the I-frame drawn in parts, each
/// loading the colour and depth the one before left, is the I-frame drawn
/// at once, bit for bit, although the parts cut draws in two and draw
/// farther surfaces after nearer ones: every I-frame equals the reference
/// at its time (which is drawn at once), and every B-frame is what it is
/// unpartitioned.
#[test]
fn partitioned_iframe_equals_one_shot() {
    let (Some(at_once), Some(in_parts)) = (run(false), run(true)) else {
        return;
    };
    assert_eq!(at_once.i_frame_psnr_min, 100.0);
    assert_eq!(
        in_parts.i_frame_psnr_min, 100.0,
        "a part lost what another drew"
    );
    for m in &at_once.methods {
        let partitioned = method(&in_parts, m.method);
        assert_eq!(partitioned.ssim_mean, m.ssim_mean, "{}", m.method.name());
        assert_eq!(partitioned.psnr_mean, m.psnr_mean, "{}", m.method.name());
    }
    assert!(in_parts
        .notes
        .iter()
        .any(|n| n.contains("drawn in 4 parts")));
}

/// What partitioning changes in the report: with the I-frame drawn at
/// once, sample-and-hold's displayed frames are not partitioned and add no
/// latency; in four parts they are, and every method adds n − 1 frames of
/// latency. How evenly the parts spread the I-frame's cost is a timing:
/// the cut's balance is tested on given costs
/// (`interpolate::partition`'s unit tests), the measured spreads are in
/// docs/results-interpolation.md.
#[test]
fn partitioned_frames_add_n_minus_1_frames_of_latency() {
    let Some(at_once) = run(false) else {
        return;
    };
    let hold = |report: &crate::interpolate::report::Report| {
        let m = method(report, Method::SampleAndHold);
        (m.displayed_frame_ms, m.added_latency_frames)
    };
    let (before, latency) = hold(&at_once);
    assert!(!before.partitioned);
    assert_eq!(latency, 0.0);
    let in_parts = run(true).unwrap();
    let (after, latency) = hold(&in_parts);
    assert!(after.partitioned);
    assert_eq!(latency, 3.0);
    for m in &in_parts.methods {
        assert_eq!(m.added_latency_frames, 3.0, "{}", m.method.name());
        assert!(m.displayed_frame_ms.spread >= 1.0, "{}", m.method.name());
    }
}
