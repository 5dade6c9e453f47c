//! Pursuit error: what an eye tracking the motion sees of a group of
//! displayed frames, against what it sees of the reference's.
//!
//! Didyk et al. 2010 rest their claims on a user study of perceived blur;
//! this is the measurable stand-in (docs/interpolation-design.md).
//!
//! A hold-type display shows displayed frame k of a group of n for
//! [k, k + 1) (in displayed frames). An eye tracking the surface seen at
//! pixel p of the group's first frame is, at time τ ∈ [0, n), at
//! p + (τ/n)·f(v)·m(p), m(p) the surface's motion over the group (the
//! I-frame's exact flow to the next I-frame) and f(v) the eye-tracking
//! damping (seed 004 §6: no pursuit beyond 90 deg/s). The retina
//! integrates light (Bloch's law), so the pursuit image is
//!
//! P(p) = ( 1/(n·S) · Σ_k Σ_s clamp(D_k(p + ((k + (s + ½)/S)/n)·f·m(p)), 0, 1)^γ )^(1/γ)
//!
//! with S sub-steps per displayed frame, D_k sampled bilinearly, and the
//! pursuit error the RMS difference over RGB of a method's P and the
//! reference's (display values, 0 to 1). Frame repetition's error is the
//! hold-type blur a 1/n rate adds; the reference's is zero.
//!
//! Integrating light, the pursuit error cannot see what changes from one
//! displayed frame to the next and averages out: a sharp frame beside a
//! blurred one (the morph's blur and compensation), flicker, temporal
//! aliasing. The flicker term measures that change where the eye is:
//! each displayed frame sampled where the tracking eye is in the middle
//! of its display, S_k(p) = D_k(p + ((k + ½)/n)·f·m(p)), and
//!
//! F = RMS over p, RGB and k = 1..n−1 of (S_k − S_{k−1}) − (R_k − R_{k−1})
//!
//! with R the reference's: its frame-to-frame change against the
//! reference's, in the same pursuit frame (display values).

use super::frames::{Frames, IntervalAt};
use super::measured::Measured;
use crate::diagnostic::Error;

/// The pursuit image of `frames` (RGBA linear frames of `size`, the
/// group's displayed frames in order) along `motion` (per pixel, over the
/// whole group, damping applied), in display values, RGB.
pub fn integrate(
    frames: &[&[f32]],
    motion: &[[f32; 2]],
    size: [u32; 2],
    gamma: f32,
    substeps: u32,
) -> Vec<f32> {
    let [width, height] = [size[0] as usize, size[1] as usize];
    let n = frames.len() as f32;
    let samples = (frames.len() as u32 * substeps.max(1)) as f32;
    let mut out = vec![0.0f32; width * height * 3];
    for y in 0..height {
        for x in 0..width {
            let p = y * width + x;
            let m = motion[p];
            let mut light = [0.0f32; 3];
            for (k, frame) in frames.iter().enumerate() {
                for s in 0..substeps.max(1) {
                    let tau = (k as f32 + (s as f32 + 0.5) / substeps.max(1) as f32) / n;
                    let at = [x as f32 + 0.5 + tau * m[0], y as f32 + 0.5 + tau * m[1]];
                    let c = bilinear(frame, [width, height], at);
                    for (l, v) in light.iter_mut().zip(c) {
                        *l += v.clamp(0.0, 1.0).powf(gamma);
                    }
                }
            }
            for (c, l) in light.iter().enumerate() {
                out[p * 3 + c] = (l / samples).powf(1.0 / gamma);
            }
        }
    }
    out
}

/// Each of `frames` sampled where an eye tracking `motion` (over the whole
/// group) is in the middle of that frame's display: frame k at
/// p + ((k + ½)/n)·m(p), RGB, display values.
pub fn stabilized(frames: &[&[f32]], motion: &[[f32; 2]], size: [u32; 2]) -> Vec<Vec<f32>> {
    let [width, height] = [size[0] as usize, size[1] as usize];
    let n = frames.len() as f32;
    frames
        .iter()
        .enumerate()
        .map(|(k, frame)| {
            let tau = (k as f32 + 0.5) / n;
            let mut out = Vec::with_capacity(width * height * 3);
            for y in 0..height {
                for x in 0..width {
                    let m = motion[y * width + x];
                    let at = [x as f32 + 0.5 + tau * m[0], y as f32 + 0.5 + tau * m[1]];
                    out.extend(bilinear(frame, [width, height], at));
                }
            }
            out
        })
        .collect()
}

/// The flicker term (module comment): the RMS, over pixels, RGB and the
/// group's n − 1 frame-to-frame steps, of a method's change between
/// consecutive displayed frames (`ours`) less the reference's (`theirs`),
/// both sampled along the tracking eye's path ([`stabilized`]). 0 for a
/// group of one frame.
pub fn flicker(ours: &[Vec<f32>], theirs: &[Vec<f32>]) -> f64 {
    let mut squared = 0.0f64;
    let mut count = 0usize;
    for k in 1..ours.len().min(theirs.len()) {
        for i in 0..ours[k].len() {
            let step = ours[k][i] - ours[k - 1][i];
            let reference_step = theirs[k][i] - theirs[k - 1][i];
            squared += f64::from(step - reference_step).powi(2);
            count += 1;
        }
    }
    (squared / count.max(1) as f64).sqrt()
}

/// What the eye follows at each pixel of a frame whose flow to the next
/// I-frame is `flow` (RGBA: Δx, Δy, Δz, valid): the flow, damped by
/// [`tracking`] at its speed (deg/s per pixel: `speed_scale`), zero where
/// it is not valid.
pub fn tracked_motion(flow: &[f32], speed_scale: f32, ramp: [f32; 2]) -> Vec<[f32; 2]> {
    flow.chunks_exact(4)
        .map(|f| {
            if f[3] > 0.0 {
                let damping = tracking(f[0].hypot(f[1]) * speed_scale, ramp);
                [f[0] * damping, f[1] * damping]
            } else {
                [0.0; 2]
            }
        })
        .collect()
}

/// The RMS difference of two pursuit images.
pub fn error(a: &[f32], b: &[f32]) -> f64 {
    let squared: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    (squared / a.len().max(1) as f64).sqrt()
}

/// RGB of `frame` at continuous position `at` (pixel centres at +0.5),
/// bilinear, clamped to the edge.
fn bilinear(frame: &[f32], [width, height]: [usize; 2], at: [f32; 2]) -> [f32; 3] {
    let fx = (at[0] - 0.5).clamp(0.0, (width - 1) as f32);
    let fy = (at[1] - 0.5).clamp(0.0, (height - 1) as f32);
    let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(width - 1), (y0 + 1).min(height - 1));
    let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
    let texel = |x: usize, y: usize, c: usize| frame[(y * width + x) * 4 + c];
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let top = texel(x0, y0, c) * (1.0 - tx) + texel(x1, y0, c) * tx;
        let bottom = texel(x0, y1, c) * (1.0 - tx) + texel(x1, y1, c) * tx;
        *o = top * (1.0 - ty) + bottom * ty;
    }
    out
}

/// The eye-tracking damping of seed 004 §6: 1 below `from` deg/s, 0 above
/// `to`, a cubic smooth step between (`tracking` in `shaders/morph.wgsl`).
pub fn tracking(speed: f32, [from, to]: [f32; 2]) -> f32 {
    let t = ((speed - from) / (to - from)).clamp(0.0, 1.0);
    1.0 - t * t * (3.0 - 2.0 * t)
}

/// Each method's pursuit error over the interval just built: the
/// interval's displayed frames integrated along I-frame 0's exact
/// motion (damped where the eye cannot track), against the same of
/// the reference ([`integrate`], [`error`]).
pub(super) fn interval_errors(
    frames: &Frames,
    at: &IntervalAt,
    measured: &mut Measured,
) -> Result<(), Error> {
    let groups = std::mem::take(&mut measured.groups);
    let n = frames.options.frames_per_interval as usize;
    let Some(first) = measured.previous_end.as_ref() else {
        return Ok(());
    };
    let motion = tracked_motion(
        at.flow_next_0(frames.gpu)?,
        frames.speed_scale(),
        frames.options.tracking,
    );
    let (size, options) = (frames.size, frames.options);
    let seen_of = |shown: &[&[f32]]| {
        integrate(
            shown,
            &motion,
            size,
            options.gamma,
            options.pursuit_substeps,
        )
    };
    let reference: Vec<&[f32]> = std::iter::once(first.as_slice())
        .chain(at.pictures.iter().take(n - 1).map(Vec::as_slice))
        .collect();
    let seen = seen_of(&reference);
    let reference_path = stabilized(&reference, &motion, size);
    let mut errors = Vec::new();
    for (method, group) in &groups {
        // A method that shows the rendered I-frame shows, at k = 0, the
        // frame of that time: the reference's. Not the I-frame's colour
        // target, which lacks the objects drawn at every displayed frame
        // (`every_frame`): with it, a method whose frames all equal the
        // reference scored the blades' contribution as its error.
        let shown: Option<Vec<&[f32]>> = group
            .iter()
            .enumerate()
            .map(|(k, frame)| match (k, frame) {
                (_, Some(frame)) => Some(frame.as_slice()),
                (0, None) => Some(first.as_slice()),
                _ => None,
            })
            .collect();
        if let Some(shown) = shown {
            errors.push((
                *method,
                error(&seen_of(&shown), &seen),
                flicker(&stabilized(&shown, &motion, size), &reference_path),
            ));
        }
    }
    for (method, error, flicker) in errors {
        let run = measured.methods.entry(method).or_default();
        run.pursuit.push(error);
        run.flicker.push(flicker);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bright bar one pixel wide at column `column` of a 16×4 frame.
    fn bar(column: usize) -> Vec<f32> {
        let mut frame = vec![0.0f32; 16 * 4 * 4];
        for y in 0..4 {
            for c in 0..3 {
                frame[(y * 16 + column) * 4 + c] = 1.0;
            }
        }
        frame
    }

    #[test]
    fn still_frames_integrate_to_themselves() {
        let frame = bar(5);
        let out = integrate(&[&frame, &frame], &[[0.0; 2]; 64], [16, 4], 2.2, 8);
        for p in 0..64 {
            assert!((out[p * 3] - frame[p * 4]).abs() < 1e-5);
        }
    }

    /// A bar moving 2 pixels a displayed frame: shown where it is at each
    /// frame, the eye sees it sharp; held, it smears over the group.
    #[test]
    fn a_held_frame_smears_what_the_eye_tracks() {
        let motion = vec![[4.0, 0.0]; 64];
        let moving = [bar(4), bar(6)];
        let held = [bar(4), bar(4)];
        let reference = integrate(&[&moving[0], &moving[1]], &motion, [16, 4], 2.2, 8);
        let same = integrate(&[&moving[0], &moving[1]], &motion, [16, 4], 2.2, 8);
        let hold = integrate(&[&held[0], &held[1]], &motion, [16, 4], 2.2, 8);
        assert_eq!(error(&reference, &same), 0.0);
        assert!(
            error(&reference, &hold) > 0.05,
            "{}",
            error(&reference, &hold)
        );
    }

    /// A still bar at half brightness, shown by a method bright, dark,
    /// then at half: over the group the eye gathers the same light at
    /// every pixel as from the reference's steady bar, so the pursuit
    /// error is 0, and only the flicker term sees the alternation.
    #[test]
    fn a_flickering_bar_has_no_pursuit_error_and_a_flicker_term() {
        let at = |brightness: f32| bar(5).iter().map(|v| v * brightness).collect::<Vec<f32>>();
        let (half, bright, dark) = (at(0.5), at(1.0), at(0.0));
        let still = vec![[0.0f32; 2]; 64];
        let reference = [half.as_slice(), &half, &half];
        let flickering = [bright.as_slice(), &dark, &half];
        // Linear light (γ = 1): the three frames' light is the steady one's.
        let seen = integrate(&reference, &still, [16, 4], 1.0, 8);
        let shown = integrate(&flickering, &still, [16, 4], 1.0, 8);
        assert!(error(&seen, &shown) < 1e-6, "{}", error(&seen, &shown));
        let along = |frames: &[&[f32]]| stabilized(frames, &still, [16, 4]);
        let flickers = flicker(&along(&flickering), &along(&reference));
        assert!(flickers > 0.1, "{flickers}");
        // The reference against itself, and a still picture held, do not
        // flicker.
        assert_eq!(flicker(&along(&reference), &along(&reference)), 0.0);
        let held = [half.as_slice(), &half, &half];
        assert_eq!(flicker(&along(&held), &along(&reference)), 0.0);
    }

    #[test]
    fn tracking_ramps_from_one_to_zero() {
        assert_eq!(tracking(10.0, [70.0, 90.0]), 1.0);
        assert_eq!(tracking(80.0, [70.0, 90.0]), 0.5);
        assert_eq!(tracking(95.0, [70.0, 90.0]), 0.0);
    }
}
