//! Morph-and-blur extrapolation (seed 004: `morph`, `morph-past`,
//! `morph-warp` of `shadecache interpolate`): the frames after an I-frame,
//! built from it alone, on small scenes.

use crate::interpolate::morph::{argmax_on_cpu, argmax_on_gpu, MorphSetup};
use crate::interpolate::report::{KeptFrame, Pictures, Report};
use crate::interpolate::{BlurOrder, Method, Options};
use crate::scene::Scene;

use super::interpolate::{
    error_at, kept, marble, method, run_interpolation, sphere_over_floor, square_speed,
    squares_before_wall, SLIDING_SHADED, SQUARE,
};

const SIZE: usize = 96;

/// The display's gamma the tests' energies are in (the default).
const GAMMA: f32 = 2.2;

fn run(scene: &str, options: Options) -> Option<(Report, Pictures, Scene)> {
    run_interpolation(SLIDING_SHADED, scene, options)
}

/// A square sliding right before a still wall at `pixels` a displayed
/// frame; `n` frames an interval, the frames kept.
fn sliding(pixels: f32, n: u32, methods: Vec<Method>) -> Option<(Report, Pictures, Scene)> {
    sliding_with(
        pixels,
        Options {
            methods,
            frames_per_interval: n,
            frames: Some(3 * n),
            keep_frames: true,
            ..Options::default()
        },
    )
}

fn sliding_with(pixels: f32, options: Options) -> Option<(Report, Pictures, Scene)> {
    let scene = squares_before_wall(0.0, &[(0.8, [-0.6, 0.0], square_speed(pixels))]);
    run(&scene, options)
}

/// The extrapolated frames of `method` (α > 0).
fn extrapolated(pictures: &Pictures, method: Method) -> Vec<&KeptFrame> {
    let frames: Vec<&KeptFrame> = kept(pictures, method)
        .into_iter()
        .filter(|f| f.alpha > 0.0)
        .collect();
    assert!(!frames.is_empty(), "no frame of {} kept", method.name());
    frames
}

/// The pixels within `radius` pixels (Chebyshev) of the square's outline
/// at any of `frames`.
fn near_outline(scene: &Scene, frames: &[u32], radius: i64) -> Vec<bool> {
    let masks: Vec<Vec<bool>> = frames
        .iter()
        .map(|&f| super::util::silhouette(scene, 1, f, SIZE, SIZE))
        .collect();
    let edge: Vec<bool> = (0..SIZE * SIZE)
        .map(|p| {
            masks
                .iter()
                .any(|m| super::util::near(m, SIZE, p) && !super::util::interior(m, SIZE)[p])
        })
        .collect();
    (0..SIZE * SIZE)
        .map(|p| {
            let (x, y) = ((p % SIZE) as i64, (p / SIZE) as i64);
            (-radius..=radius).any(|dy| {
                (-radius..=radius).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    (0..SIZE as i64).contains(&nx)
                        && (0..SIZE as i64).contains(&ny)
                        && edge[ny as usize * SIZE + nx as usize]
                })
            })
        })
        .collect()
}

/// The interval's I-frame of a kept frame (its α·n frames before).
fn iframe_of(frame: &KeptFrame, n: u32) -> u32 {
    frame.frame - (frame.alpha * f64::from(n)).round() as u32
}

/// Nothing moves: the warp is the identity, and with the blur gated by
/// speed (none below the drift limit) the full method shows the I-frame
/// in every slot, compensated by nothing. Without the gate the same frames
/// are blurred: the identity is the gate's doing.
#[test]
fn static_scene_extrapolation_is_identity() {
    let options = |blur_min_speed| Options {
        methods: vec![Method::MorphWarp, Method::Morph],
        frames_per_interval: 3,
        frames: Some(6),
        keep_frames: true,
        blur_min_speed,
        ..Options::default()
    };
    let scene = sphere_over_floor("", "", "");
    let Some((_, selective, _)) = run_interpolation(&marble(), &scene, options(Some(0.15))) else {
        return;
    };
    for method in [Method::MorphWarp, Method::Morph] {
        let frames = kept(&selective, method);
        assert!(
            frames.len() >= 4,
            "{}: {} frames",
            method.name(),
            frames.len()
        );
        for frame in frames {
            assert!(
                frame.error.max_abs_error < 2e-3,
                "{} frame {} (α = {}): {:?}",
                method.name(),
                frame.frame,
                frame.alpha,
                frame.error
            );
        }
    }
    let (_, everywhere, _) = run_interpolation(&marble(), &scene, options(None)).unwrap();
    let worst = extrapolated(&everywhere, Method::Morph)
        .iter()
        .map(|f| f.error.max_abs_error)
        .fold(0.0, f64::max);
    assert!(
        worst > 0.02,
        "blurred everywhere, the frames moved by {worst}"
    );
}

/// A square translating two pixels a displayed frame (n = 2: the
/// in-between frame is four pixels along the interval's motion, on texel
/// centres): away from the outlines, by a grid spacing, the warp is the
/// frame rendered at its time.
#[test]
fn constant_translation_warp_is_exact_away_from_edges() {
    let Some((_, pictures, scene)) = sliding(2.0, 2, vec![Method::MorphWarp]) else {
        return;
    };
    for frame in extrapolated(&pictures, Method::MorphWarp) {
        let band = near_outline(&scene, &[iframe_of(frame, 2), frame.frame], 8);
        let checked: Vec<usize> = (0..SIZE * SIZE).filter(|&p| !band[p]).collect();
        assert!(checked.len() > SIZE * SIZE / 2);
        let worst = checked
            .iter()
            .map(|&p| error_at(frame, p))
            .fold(0.0f32, f32::max);
        assert!(worst <= 0.02, "frame {}: worst error {worst}", frame.frame);
        // The square's stripes are checked too, not only the flat wall.
        let square = checked
            .iter()
            .filter(|&&p| frame.reference[p * 4] > SQUARE)
            .count();
        assert!(square > 100, "{square} pixels of the square checked");
    }
}

/// The square moves 12 pixels an in-between frame, more than a grid
/// spacing: its tiles fold over the wall's ahead of it, and the depth test
/// keeps the nearer square where the frame rendered at that time shows it,
/// with either depth convention (drawn in the grid's order instead, the
/// wall hides a third of it).
#[test]
fn fold_over_nearer_surface_wins() {
    for depth in ["standard", "reversed"] {
        let object = format!(
            r#"[[objects]]
mesh = {{ kind = "plane", size = 0.8, subdivisions = 2 }}
position = [-1.0, 0.0, 0.0]
rotation_degrees = [90.0, 0.0, 0.0]
translation_per_frame = [{}, 0.0, 0.0]
"#,
            square_speed(12.0)
        );
        let scene = super::interpolate::before_wall(depth, 0.0, &object);
        let options = Options {
            methods: vec![Method::MorphWarp],
            frames_per_interval: 2,
            frames: Some(4),
            keep_frames: true,
            ..Options::default()
        };
        let Some((_, pictures, scene)) = run(&scene, options) else {
            return;
        };
        for frame in extrapolated(&pictures, Method::MorphWarp) {
            let before = super::util::silhouette(&scene, 1, iframe_of(frame, 2), SIZE, SIZE);
            let now = super::util::silhouette(&scene, 1, frame.frame, SIZE, SIZE);
            let inside = super::util::interior(&now, SIZE);
            // Newly covered by the square: the wall before, the square now.
            let covered: Vec<usize> = (0..SIZE * SIZE)
                .filter(|&p| inside[p] && !super::util::near(&before, SIZE, p))
                .collect();
            assert!(covered.len() >= 40, "{depth}: {} pixels", covered.len());
            let lost: Vec<usize> = covered
                .iter()
                .copied()
                .filter(|&p| frame.result[p * 4] < SQUARE)
                .collect();
            // The corners, where two edges meet in one neighbourhood and
            // one vertex snaps to one of them, may smear a pixel.
            assert!(
                lost.len() * 50 <= covered.len(),
                "{depth}, frame {}: the wall shows at {} of {} pixels the square covers, e.g. {:?}",
                frame.frame,
                lost.len(),
                covered.len(),
                &lost[..lost.len().min(5)]
            );
        }
    }
}

/// Snapping, checked twice. The argmax pyramid finds, per vertex, the
/// largest motion gradient of its neighbourhood, as a brute-force search
/// on the CPU does (same tie-break), and a vertex whose neighbourhood a
/// diagonal motion edge crosses lands on it. And on the sliding square,
/// whose outline falls between grid lines, the warp is nearer the frame
/// rendered at its time along the outline with snapping than on the
/// regular grid.
#[test]
fn grid_snaps_to_motion_edge() {
    let Some(gpu) = super::gpu::gpu() else { return };
    let (size, grid) = ([64u32, 48u32], 8u32);
    let motion: Vec<[f32; 2]> = (0..size[0] * size[1])
        .map(|p| {
            let (x, y) = ((p % size[0]) as f32, (p / size[0]) as f32);
            if x + 0.6 * y > 37.3 {
                [6.0, -2.0]
            } else {
                [0.0, 0.0]
            }
        })
        .collect();
    let setup = MorphSetup {
        size,
        grid,
        blur_level: 2,
        blur_gated_by_speed: false,
        blur_order: Default::default(),
    };
    let gpu_argmax = argmax_on_gpu(&gpu, setup, &motion, 1.0).unwrap();
    let cpu_argmax = argmax_on_cpu(&motion, size, grid, 1.0);
    assert_eq!(gpu_argmax, cpu_argmax);
    let columns = size[0] / grid + 1;
    let on_edge = |x: i32, y: i32| {
        let at = |x: i32, y: i32| motion[(y * size[0] as i32 + x) as usize];
        at(x + 1, y) != at(x, y) || at(x, y + 1) != at(x, y)
    };
    let mut snapped = 0;
    for (v, packed) in gpu_argmax.iter().enumerate() {
        let (i, j) = (v as u32 % columns, v as u32 / columns);
        if i == 0 || j == 0 || i == columns - 1 || j == size[1] / grid {
            continue;
        }
        let corner = |at: u32, r: u32| (at * grid) as i32 - (grid / 2) as i32 + r as i32;
        let (x, y) = (corner(i, packed & 0xff), corner(j, (packed >> 8) & 0xff));
        let crossed = (0..grid).any(|ry| (0..grid).any(|rx| on_edge(corner(i, rx), corner(j, ry))));
        assert_eq!(packed >> 16 > 0, crossed, "vertex ({i}, {j})");
        if crossed {
            assert!(on_edge(x, y), "vertex ({i}, {j}) snapped to ({x}, {y})");
            snapped += 1;
        }
    }
    assert!(snapped >= 4, "{snapped} vertices snapped");

    let band_error = |snap: bool| {
        let options = Options {
            methods: vec![Method::MorphWarp],
            frames_per_interval: 2,
            frames: Some(6),
            keep_frames: true,
            snap,
            ..Options::default()
        };
        let (_, pictures, scene) = sliding_with(2.0, options).unwrap();
        let mut sum = 0.0f64;
        let mut count = 0usize;
        for frame in extrapolated(&pictures, Method::MorphWarp) {
            let band = near_outline(&scene, &[frame.frame], 3);
            for p in (0..SIZE * SIZE).filter(|&p| band[p]) {
                sum += f64::from(error_at(frame, p));
                count += 1;
            }
        }
        sum / count as f64
    };
    let (with, without) = (band_error(true), band_error(false));
    assert!(
        with < 0.8 * without,
        "mean error along the outline: {with:.4} snapped, {without:.4} on the regular grid"
    );
}

/// Light of a display value (clamped to the display's range).
fn light(v: f32) -> f32 {
    v.clamp(0.0, 1.0).powf(GAMMA)
}

/// Each interval's displayed frames of `method`: its I-frame as displayed
/// and its in-between frames, by interval.
fn groups(pictures: &Pictures, method: Method, n: u32) -> Vec<Vec<&KeptFrame>> {
    let frames = kept(pictures, method);
    let starts: Vec<u32> = frames
        .iter()
        .filter(|f| f.alpha == 0.0)
        .map(|f| f.frame)
        .collect();
    let groups: Vec<Vec<&KeptFrame>> = starts
        .iter()
        .map(|&start| {
            let mut group: Vec<&KeptFrame> = frames
                .iter()
                .copied()
                .filter(|f| f.frame >= start && f.frame < start + n)
                .collect();
            group.sort_by_key(|f| f.frame);
            group
        })
        .filter(|g| g.len() == n as usize)
        .collect();
    assert!(!groups.is_empty(), "no whole interval of {}", method.name());
    groups
}

/// On a still scene (the square standing before the wall, high contrast
/// at its stripes and edges) the in-between frames are blurred and the
/// I-frame compensated: the mean light of the n displayed frames is the
/// rendered frame's wherever no displayed value clips.
#[test]
fn hf_compensation_preserves_the_group_average() {
    for n in [2, 3] {
        let Some((_, pictures, _)) = sliding(0.0, n, vec![Method::Morph]) else {
            return;
        };
        let mut checked = 0;
        for group in groups(&pictures, Method::Morph, n) {
            let rendered = &group[0].reference;
            let mut changed = 0;
            for p in 0..SIZE * SIZE {
                for c in 0..3 {
                    let values: Vec<f32> = group.iter().map(|f| f.result[p * 4 + c]).collect();
                    if values.iter().any(|&v| !(0.002..=0.998).contains(&v)) {
                        continue;
                    }
                    let mean = values.iter().map(|&v| light(v)).sum::<f32>() / n as f32;
                    let want = light(rendered[p * 4 + c]);
                    assert!(
                        (mean - want).abs() <= 4e-3 + 4e-3 * want,
                        "n = {n}, pixel {p} channel {c}: frames {values:?} average {mean}, the rendered frame {want}"
                    );
                    checked += 1;
                    if (values[0] - rendered[p * 4 + c]).abs() > 0.02 {
                        changed += 1;
                    }
                }
            }
            assert!(changed > 200, "n = {n}: only {changed} values compensated");
        }
        assert!(checked > SIZE * SIZE, "n = {n}: {checked} values checked");
    }
}

/// Where the amplified detail would leave the display's range, the
/// displayed I-frame clips at 1 and the in-between frames take the light
/// it could not show: no value outside [0, 1], the group's mean light the
/// rendered frame's at the clipped pixels too (until the in-between frames
/// clip as well).
#[test]
fn compensation_clamped_at_display_range() {
    let n = 3;
    let Some((_, pictures, _)) = sliding(0.0, n, vec![Method::Morph]) else {
        return;
    };
    let mut clipped = 0;
    for group in groups(&pictures, Method::Morph, n) {
        for frame in &group {
            let worst = frame.result.iter().fold(0.0f32, |m, &v| m.max(v));
            assert!(worst <= 1.0 + 1e-3, "frame {}: {worst}", frame.frame);
            assert!(frame.result.iter().all(|&v| v >= -1e-3));
        }
        let rendered = &group[0].reference;
        for p in 0..SIZE * SIZE {
            for c in 0..3 {
                let values: Vec<f32> = group.iter().map(|f| f.result[p * 4 + c]).collect();
                let shifted = values[0] >= 0.999 && values[1..].iter().all(|&v| v < 0.998);
                if !shifted {
                    continue;
                }
                clipped += 1;
                let mean = values.iter().map(|&v| light(v)).sum::<f32>() / n as f32;
                let want = light(rendered[p * 4 + c]);
                assert!(
                    (mean - want).abs() <= 6e-3 + 4e-3 * want,
                    "pixel {p} channel {c}: frames {values:?} average {mean}, the rendered frame {want}"
                );
            }
        }
    }
    assert!(
        clipped > 20,
        "{clipped} values clipped: the scene does not test it"
    );
}

/// Behind the sliding square the wall it uncovers was never rendered:
/// the grid stretches over it (no pixel left unwritten), and the blurred
/// method shows something nearer the truth there than frame repetition's
/// square.
#[test]
fn disocclusion_hole_filled() {
    let n = 2;
    let Some((_, pictures, scene)) = sliding(
        3.0,
        n,
        vec![Method::Morph, Method::MorphWarp, Method::SampleAndHold],
    ) else {
        return;
    };
    let revealed_error = |method: Method| {
        let mut sum = 0.0f64;
        let mut count = 0;
        for frame in extrapolated(&pictures, method) {
            assert!(
                frame.result.chunks_exact(4).all(|p| p[3] > 0.5),
                "{} frame {}: a pixel left unwritten",
                method.name(),
                frame.frame
            );
            let before = super::util::silhouette(&scene, 1, iframe_of(frame, n), SIZE, SIZE);
            let now = super::util::silhouette(&scene, 1, frame.frame, SIZE, SIZE);
            let before_inside = super::util::interior(&before, SIZE);
            for p in
                (0..SIZE * SIZE).filter(|&p| before_inside[p] && !super::util::near(&now, SIZE, p))
            {
                sum += f64::from(error_at(frame, p));
                count += 1;
            }
        }
        assert!(count >= 40, "{count} revealed pixels");
        sum / f64::from(count)
    };
    let (morph, warp, hold) = (
        revealed_error(Method::Morph),
        revealed_error(Method::MorphWarp),
        revealed_error(Method::SampleAndHold),
    );
    assert!(
        morph < hold && warp < hold,
        "mean error where the wall is revealed: morph {morph:.4}, morph-warp {warp:.4}, frame repetition {hold:.4}"
    );
}

/// The camera orbits 4° a frame while the sphere turns and slides, so
/// every point's screen velocity changes from interval to interval (the
/// orbit's centripetal acceleration, the perspective's changing scale).
/// Extrapolated from the motion between the I-frame before and this one,
/// the frames are wrong by the change of velocity, not by all of it: they
/// stay nearer the truth than frame repetition, and within reach of the
/// exact motion's. The report gives both.
#[test]
fn acceleration_error_is_bounded() {
    let scene = super::util::sphere_over_floor(
        "size = [96, 96]\nframes = 9",
        "\"camera-motion\", \"object-motion\"",
        "orbit_degrees_per_frame = 4.0",
        "position = [0.0, 0.0, 0.0]\ntranslation_per_frame = [0.03, 0.0, 0.0]\nrotation_degrees_per_frame = [0.0, 9.0, 0.0]",
    );
    let options = Options {
        methods: vec![Method::SampleAndHold, Method::Morph, Method::MorphPast],
        frames_per_interval: 3,
        frames: Some(9),
        ..Options::default()
    };
    let Some((report, _, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    let (hold, exact, past) = (
        method(&report, Method::SampleAndHold),
        method(&report, Method::Morph),
        method(&report, Method::MorphPast),
    );
    let pursuit = |m: &crate::interpolate::report::MethodReport| m.pursuit_error.unwrap();
    assert!(
        pursuit(past) < pursuit(hold) && past.psnr_mean > hold.psnr_mean,
        "morph-past: pursuit {:.4}, PSNR {:.1}; frame repetition: {:.4}, {:.1}",
        pursuit(past),
        past.psnr_mean,
        pursuit(hold),
        hold.psnr_mean
    );
    assert!(
        pursuit(past) < 2.0 * pursuit(exact) + 0.01,
        "morph-past {:.4} against the exact motion's {:.4}",
        pursuit(past),
        pursuit(exact)
    );
    for m in [hold, exact, past] {
        assert_eq!(m.added_latency_frames, 0.0, "{}", m.method.name());
    }
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.starts_with("morph-past extrapolates")),
        "the report states the two motions' difference: {:?}",
        report.notes
    );
}

/// Past the eye's tracking limit (seed 004 §6: none beyond 90 deg/s) the
/// morph's motion is damped to nothing, f(v) = 0: the frames repeat the
/// I-frame, as the eye could not follow anyway. At 4 pixels per degree
/// the square's 8 pixels an interval at 60 rendered frames a second are
/// 120 deg/s: the warp shows the I-frame. At the default 37 px/deg
/// (13 deg/s) the same frames move.
#[test]
fn untrackable_motion_is_held() {
    let run = |pixels_per_degree: f32| {
        let options = Options {
            methods: vec![Method::MorphWarp, Method::SampleAndHold],
            frames_per_interval: 2,
            frames: Some(4),
            keep_frames: true,
            pixels_per_degree,
            ..Options::default()
        };
        sliding_with(4.0, options).map(|(_, pictures, _)| pictures)
    };
    let Some(untrackable) = run(4.0) else {
        return;
    };
    let tracked = run(37.0).unwrap();
    let largest_change = |pictures: &Pictures| {
        let held = kept(pictures, Method::SampleAndHold);
        extrapolated(pictures, Method::MorphWarp)
            .iter()
            .map(|frame| {
                let hold = held.iter().find(|h| h.frame == frame.frame).unwrap();
                frame
                    .result
                    .iter()
                    .zip(&hold.result)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0f32, f32::max)
            })
            .fold(0.0f32, f32::max)
    };
    let (untrackable, tracked) = (largest_change(&untrackable), largest_change(&tracked));
    assert!(
        untrackable < 2e-3,
        "untrackable: {untrackable} from the I-frame"
    );
    assert!(tracked > 0.3, "tracked: {tracked} from the I-frame");
}

/// The camera pans: what enters at the frame's edge was never rendered,
/// and the border vertices stay where they are (seed 004 §5.1), so the
/// edge shows the I-frame's border content stretched, never a black or
/// unwritten strip (what the I-frame did not show there, beyond the
/// floor's end, it cannot).
#[test]
fn pan_leaves_no_border_unwritten() {
    let scene = super::util::sphere_over_floor(
        "size = [96, 96]\nframes = 6",
        "\"camera-motion\"",
        "pan_per_frame = [0.08, 0.0, 0.0]",
        "",
    );
    let options = Options {
        methods: vec![Method::Morph, Method::MorphWarp, Method::SampleAndHold],
        frames_per_interval: 3,
        frames: Some(6),
        keep_frames: true,
        ..Options::default()
    };
    let Some((_, pictures, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    let held = kept(&pictures, Method::SampleAndHold);
    for method in [Method::Morph, Method::MorphWarp] {
        for frame in extrapolated(&pictures, method) {
            // The I-frame, which the border shows.
            let iframe = &held.iter().find(|h| h.frame == frame.frame).unwrap().result;
            let mut checked = 0;
            for y in 0..SIZE {
                for x in [0, 1, SIZE - 2, SIZE - 1] {
                    let p = (y * SIZE + x) * 4;
                    let there = &iframe[p..p + 4];
                    if there[3] < 0.5 || there[..3].iter().all(|&v| v < 0.02) {
                        continue;
                    }
                    let shown = &frame.result[p..p + 4];
                    assert!(
                        shown[3] > 0.5 && shown[..3].iter().any(|&v| v > 0.02),
                        "{} frame {}: pixel ({x}, {y}) shows {shown:?} where the I-frame shows {there:?}",
                        method.name(),
                        frame.frame
                    );
                    checked += 1;
                }
            }
            assert!(checked > 100, "{checked} border pixels checked");
        }
    }
}

/// A group longer than Bloch's ~40 ms (n = 3 at 60 Hz: 50 ms) is flagged
/// in the report: the sharpened and blurred frames may be seen to
/// alternate. The paper's 3 at 120 Hz (25 ms) is not.
#[test]
fn long_groups_are_flagged_for_flicker() {
    let notes = |display_hz: f32| {
        let options = Options {
            methods: vec![Method::Morph],
            frames_per_interval: 3,
            frames: Some(3),
            display_hz,
            ..Options::default()
        };
        sliding_with(0.0, options).map(|(report, _, _)| report.notes)
    };
    let Some(slow) = notes(60.0) else {
        return;
    };
    let flagged = |notes: &[String]| notes.iter().any(|n| n.contains("flicker"));
    assert!(flagged(&slow), "{slow:?}");
    assert!(!flagged(&notes(120.0).unwrap()));
}

/// A camera cut (hard case 16 of seed 004: "reset: no morph; repeat the
/// frame"): the camera orbits the marble sphere, then cuts to a view from
/// the other side at frame 10, inside the interval 8–12 (n = 4). There,
/// every method made from both I-frames (the morph with the next
/// I-frame's motion, image-based, the blend) shows the earlier I-frame
/// again, sample-and-hold's frame to the bit; morph-past, whose motion is
/// the past's, still extrapolates frame 9 (the old shot) and repeats from
/// the cut on, and in the interval after (its past motion crosses the
/// cut) repeats every frame. Elsewhere each extrapolates.
#[test]
fn camera_cut_resets_extrapolation_and_interpolation() {
    let camera = r#"orbit_degrees_per_frame = 2.0
[[camera.cuts]]
frame = 10
eye = [2.6, 0.6, -2.2]
"#;
    let scene = sphere_over_floor(r#""camera-motion""#, camera, "");
    let methods = vec![
        Method::SampleAndHold,
        Method::LinearBlend,
        Method::ImageBased,
        Method::Morph,
        Method::MorphPast,
    ];
    let options = Options {
        methods,
        frames_per_interval: 4,
        frames: Some(16),
        keep_frames: true,
        ..Options::default()
    };
    let Some((report, pictures, _)) = run_interpolation(&marble(), &scene, options) else {
        return;
    };
    let held = |frame: u32| {
        kept(&pictures, Method::SampleAndHold)
            .into_iter()
            .find(|k| k.frame == frame)
            .unwrap_or_else(|| panic!("no held frame {frame}"))
            .result
            .clone()
    };
    let repeats = |method: Method, frame: u32| {
        let shown = kept(&pictures, method)
            .into_iter()
            .find(|k| k.frame == frame && k.alpha > 0.0)
            .unwrap_or_else(|| panic!("no frame {frame} of {}", method.name()));
        shown.result == held(frame)
    };
    for method in [Method::LinearBlend, Method::ImageBased, Method::Morph] {
        for frame in [9, 10, 11] {
            assert!(
                repeats(method, frame),
                "{} makes frame {frame} across the cut",
                method.name()
            );
        }
        for frame in [5, 13] {
            assert!(
                !repeats(method, frame),
                "{} repeats frame {frame}, away from the cut",
                method.name()
            );
        }
    }
    assert!(
        !repeats(Method::MorphPast, 9),
        "morph-past repeats the old shot's frame 9"
    );
    for frame in [10, 11, 13, 14, 15] {
        assert!(
            repeats(Method::MorphPast, frame),
            "morph-past makes frame {frame}"
        );
    }
    assert!(
        !repeats(Method::MorphPast, 17),
        "morph-past repeats frame 17"
    );
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.contains("camera cut at motion frame 10:")),
        "{:?}",
        report.notes
    );
}

/// `--blur-order paper` (seed 004's R6–R8): each in-between frame morphed
/// sharp, then blurred, then assembled from the two. Where nothing moves
/// the morphed frame is the rendered one, so its low-pass is the rendered
/// frame's and both orders show the same frames (up to the half-float
/// low-pass the default order stores). Under motion the paper's blur is of
/// the morphed frame: near the square's outline, where the default warps
/// the rendered frame's low-pass, the two differ; beyond the low-pass's
/// reach of it they agree.
#[test]
fn paper_blur_order_morphs_then_blurs_each_frame() {
    let options = |blur_order| Options {
        methods: vec![Method::Morph],
        frames_per_interval: 3,
        frames: Some(6),
        keep_frames: true,
        blur_order,
        ..Options::default()
    };
    let (paper, ours) = (BlurOrder::Paper, BlurOrder::WarpBlurred);
    let still = sphere_over_floor("", "", "");
    let Some((_, warp_blurred, _)) = run_interpolation(&marble(), &still, options(ours)) else {
        return;
    };
    let (_, morph_then_blur, _) = run_interpolation(&marble(), &still, options(paper)).unwrap();
    let (a, b) = (
        extrapolated(&warp_blurred, Method::Morph),
        extrapolated(&morph_then_blur, Method::Morph),
    );
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(&b) {
        let largest = largest_difference(&a.result, &b.result);
        assert!(largest < 2e-3, "frame {}: {largest}", a.frame);
    }

    let (_, warp_blurred, scene) = sliding_with(3.0, options(ours)).unwrap();
    let (_, morph_then_blur, _) = sliding_with(3.0, options(paper)).unwrap();
    let (a, b) = (
        extrapolated(&warp_blurred, Method::Morph),
        extrapolated(&morph_then_blur, Method::Morph),
    );
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(&b) {
        let n = 3;
        let frames = [iframe_of(a, n), a.frame];
        // The low-pass (level 2, read with a cubic B-spline) reaches about
        // 16 pixels: beyond twice that, nothing of the outline is in it.
        let (near, reach) = (
            near_outline(&scene, &frames, 12),
            near_outline(&scene, &frames, 32),
        );
        let (mut near_edge, mut far) = (0.0f32, 0.0f32);
        for p in 0..near.len() {
            let d = (0..3)
                .map(|c| (a.result[p * 4 + c] - b.result[p * 4 + c]).abs())
                .fold(0.0, f32::max);
            if near[p] {
                near_edge = near_edge.max(d);
            } else if !reach[p] {
                far = far.max(d);
            }
        }
        assert!(
            near_edge > 0.02,
            "frame {}: the orders agree at the outline",
            a.frame
        );
        assert!(
            far < 2e-3,
            "frame {}: they differ away from it by {far}",
            a.frame
        );
    }
}

fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}
