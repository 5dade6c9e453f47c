//! Error of a frame against the reference frame, and the cache's decisions
//! counted from a classification image.

use serde::Serialize;

/// PSNR is capped here: identical frames would be infinite, which JSON
/// cannot hold.
pub const PSNR_CAP: f64 = 100.0;

/// How far a frame is from the reference frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameError {
    /// Peak signal-to-noise ratio over RGB of the covered pixels, in dB
    /// (capped at 100; 100 when none is covered).
    pub psnr: f64,
    /// The same over the whole frame, background included.
    pub psnr_frame: f64,
    /// Mean SSIM of the luminance over 8×8 windows, whole frame.
    pub ssim: f64,
    /// Largest difference of any channel, in [0, 1].
    pub max_abs_error: f64,
    /// Share of the covered pixels whose largest channel difference
    /// exceeds the threshold.
    pub above_threshold: f64,
}

/// Whether a pixel of a classification image is covered: the classify
/// pass writes every pixel the mesh covers, opaque; the rest stays clear.
fn covered(classes: &[u8], pixel: usize) -> bool {
    classes.get(pixel * 4 + 3).is_some_and(|&a| a > 0)
}

/// A frame read back in linear float: RGBA, row-major, as the shader
/// wrote it to an `rgba16float` target (values above 1 kept, none
/// clamped or quantised to 8 bits).
pub type LinearFrame = Vec<f32>;

/// Decodes an `rgba16float` readback into a [`LinearFrame`].
pub fn linear_from_f16(bytes: &[u8]) -> LinearFrame {
    bytes
        .chunks_exact(2)
        .map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32())
        .collect()
}

/// A linear frame as an RGBA8 picture for the report's images: clamped to
/// [0, 1] and quantised, with no transfer function (as an `rgba8unorm`
/// target would store it).
pub fn rgba8(frame: &[f32]) -> Vec<u8> {
    frame.iter().map(|&v| unorm8(v)).collect()
}

/// A channel value as 8 bits: NaN as 0, clamped to [0, 1], rounded.
fn unorm8(value: f32) -> u8 {
    let v = if value.is_nan() {
        0.0
    } else {
        value.clamp(0.0, 1.0)
    };
    (v * 255.0).round() as u8
}

/// A linear value encoded with sRGB's transfer function (IEC 61966-2-1):
/// what an `*-srgb` target stores and a display decodes back to light.
/// Written here: none of the crates the project uses exposes the transfer
/// function on plain floats (`image` converts no colour spaces), and it is
/// the standard's two branches.
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        linear * 12.92
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// A linear frame as a display shows it, 8 bits a channel: clamped to
/// [0, 1], encoded with sRGB's transfer function, quantised. SSIM is
/// taken of this picture: it assumes a perceptually encoded signal, and a
/// linear frame quantised to 8 bits crushes the darks, where the eye
/// tells most apart, into a few codes (0.004 and 0.012 are codes 1 and 3
/// in linear, 13 and 29 in sRGB).
pub fn srgb8(frame: &[f32]) -> Vec<u8> {
    frame
        .chunks(4)
        .flat_map(|texel| {
            // Alpha has no transfer function; NaN and the clamp as `unorm8`.
            texel.iter().enumerate().map(|(c, &v)| match c {
                3 => unorm8(v),
                _ => unorm8(srgb_encode(if v.is_nan() {
                    0.0
                } else {
                    v.clamp(0.0, 1.0)
                })),
            })
        })
        .collect()
}

/// The difference of two channel values, as a number: a NaN on either
/// side is the largest difference there is (a cache must never show one
/// the reference does not).
fn channel_difference(a: f32, b: f32) -> f64 {
    let d = f64::from((a - b).abs());
    if d.is_nan() {
        if a.is_nan() && b.is_nan() {
            0.0
        } else {
            f64::MAX.sqrt()
        }
    } else {
        d
    }
}

fn psnr_of(squared: f64, samples: usize) -> f64 {
    if samples == 0 {
        return PSNR_CAP;
    }
    // Peak 1: the display range; values above it add their whole error.
    let mse = squared / samples as f64;
    if mse == 0.0 {
        PSNR_CAP
    } else {
        (10.0 * (1.0 / mse).log10()).min(PSNR_CAP)
    }
}

/// Compares two linear float frames of `width × height` (alpha ignored),
/// over the pixels `classes` marks covered and over the whole frame: the
/// background matches exactly in every variant and would only dilute the
/// error of the pixels the shader draws. PSNR, the largest error and the
/// threshold are in linear float, peak 1, values above 1 counted as they
/// are (an HDR target's highlights); SSIM, a perceptual measure of the
/// displayed picture, is of the frames clamped to [0, 1] and quantised
/// as a display would show them.
pub fn compare(
    reference: &[f32],
    frame: &[f32],
    classes: &[u8],
    width: u32,
    height: u32,
    threshold: f64,
) -> FrameError {
    compare_where(
        reference,
        frame,
        |p| covered(classes, p),
        [width, height],
        threshold,
    )
}

/// [`compare`] with every pixel counted as covered: whole frames (the
/// interpolation stage's), where the background is part of what is
/// reconstructed.
#[cfg(feature = "interpolate")]
pub fn compare_frames(
    reference: &[f32],
    frame: &[f32],
    width: u32,
    height: u32,
    threshold: f64,
) -> FrameError {
    compare_where(reference, frame, |_| true, [width, height], threshold)
}

/// PSNR (dB, linear float, peak 1, capped) over the colour channels of
/// the pixels `within` marks; `None` where it marks none.
#[cfg(feature = "interpolate")]
pub fn psnr_where(reference: &[f32], frame: &[f32], within: &[bool]) -> Option<f64> {
    let mut squared = 0.0f64;
    let mut count = 0usize;
    for (p, _) in within.iter().enumerate().filter(|(_, &w)| w) {
        for c in 0..3 {
            let d = channel_difference(reference[p * 4 + c], frame[p * 4 + c]);
            squared += d * d;
        }
        count += 3;
    }
    (count > 0).then(|| psnr_of(squared, count))
}

fn compare_where(
    reference: &[f32],
    frame: &[f32],
    covered: impl Fn(usize) -> bool,
    [width, height]: [u32; 2],
    threshold: f64,
) -> FrameError {
    let pixels = (width * height) as usize;
    let (mut squared, mut squared_covered, mut count) = (0.0f64, 0.0f64, 0usize);
    let mut max = 0.0f64;
    let mut above = 0usize;
    for p in 0..pixels {
        let mut worst = 0.0f64;
        let mut sum = 0.0;
        for c in 0..3 {
            let d = channel_difference(reference[p * 4 + c], frame[p * 4 + c]);
            sum += d * d;
            worst = worst.max(d);
        }
        squared += sum;
        max = max.max(worst);
        if covered(p) {
            squared_covered += sum;
            count += 1;
            if worst > threshold {
                above += 1;
            }
        }
    }
    FrameError {
        psnr: psnr_of(squared_covered, count * 3),
        psnr_frame: psnr_of(squared, pixels * 3),
        ssim: ssim(&srgb8(reference), &srgb8(frame), width, height),
        max_abs_error: max,
        above_threshold: if count == 0 {
            0.0
        } else {
            above as f64 / count as f64
        },
    }
}

/// Flicker: how much a frame's change from the frame before differs from
/// the reference's own change, mean over the covered pixels' channels, in
/// [0, 1]. A cache that pops blocks in and out, or refreshes visibly, has
/// changes the reference does not; a stale but steady one has none.
pub fn flicker(
    reference_before: &[f32],
    reference: &[f32],
    before: &[f32],
    frame: &[f32],
    classes: &[u8],
) -> f64 {
    let pixels = reference.len() / 4;
    let (mut sum, mut count) = (0.0, 0usize);
    for p in 0..pixels {
        if !covered(classes, p) {
            continue;
        }
        for c in 0..3 {
            let i = p * 4 + c;
            let own = f64::from(frame[i]) - f64::from(before[i]);
            let expected = f64::from(reference[i]) - f64::from(reference_before[i]);
            let d = (own - expected).abs();
            // A NaN in either counts as the largest change there is.
            sum += if d.is_nan() { 1.0 } else { d };
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

fn luma(rgba: &[u8], width: u32, height: u32) -> image::GrayImage {
    image::GrayImage::from_fn(width, height, |x, y| {
        let i = ((y * width + x) * 4) as usize;
        let (r, g, b) = (
            f32::from(rgba[i]),
            f32::from(rgba[i + 1]),
            f32::from(rgba[i + 2]),
        );
        image::Luma([(0.2126 * r + 0.7152 * g + 0.0722 * b).round() as u8])
    })
}

fn ssim(reference: &[u8], frame: &[u8], width: u32, height: u32) -> f64 {
    image_compare::gray_similarity_structure(
        &image_compare::Algorithm::MSSIMSimple,
        &luma(reference, width, height),
        &luma(frame, width, height),
    )
    .map(|s| s.score)
    .unwrap_or(0.0)
}

/// The cache's decisions in one frame, as shares of the covered pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Decisions {
    /// Pixels the frame covers (the rest is background).
    pub covered: usize,
    /// Reused from the cache.
    pub hit: f64,
    /// Recomputed because the refresh indicator fired on a hit.
    pub refresh: f64,
    /// Missed because the point was behind the previous camera or outside
    /// the viewport.
    pub offscreen: f64,
    /// Missed because last frame's depth disagrees (disocclusion).
    pub disoccluded: f64,
    /// Missed because the cached payload read back is not finite.
    pub invalid: f64,
}

impl Decisions {
    pub fn miss(&self) -> f64 {
        self.offscreen + self.disoccluded + self.invalid
    }
}

/// The colour of each class in a classification image (RGBA8).
pub const HIT: [u8; 3] = [0, 255, 0];
pub const REFRESH: [u8; 3] = [0, 0, 255];
pub const DISOCCLUDED: [u8; 3] = [255, 0, 0];
pub const INVALID: [u8; 3] = [255, 0, 255];

/// The cache's decision a classification texel (RGBA8) shows; `None` for
/// the background and for pixels where the node is not computed (grey).
fn class_of(texel: &[u8]) -> Option<Class> {
    Some(match [texel[0], texel[1], texel[2]] {
        HIT => Class::Hit,
        REFRESH => Class::Refresh,
        DISOCCLUDED => Class::Disoccluded,
        INVALID => Class::Invalid,
        // Off-screen is [255, 128, 0]: rgba8unorm stores its 0.5 as 127
        // or 128.
        [255, 127 | 128, 0] => Class::Offscreen,
        _ => return None,
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Hit,
    Refresh,
    Offscreen,
    Disoccluded,
    Invalid,
}

/// Adds the age of the value at every pixel the cache covers this frame
/// (reused, refreshed or missed: classified, not background or absent) to
/// `histogram` (index: frames since the value was computed, 0 where it
/// was computed this frame). `ages` is the frame's age texture, r16float.
pub fn add_ages(classes: &[u8], ages: &[u8], histogram: &mut Vec<u64>) {
    for (texel, age) in classes.chunks_exact(4).zip(ages.chunks_exact(2)) {
        if class_of(texel).is_none() {
            continue;
        }
        let age = half::f16::from_le_bytes([age[0], age[1]]).to_f32();
        // Ages are whole numbers up to 2048; anything else is not one.
        let age = if age.is_finite() && age >= 0.0 {
            age.round() as usize
        } else {
            continue;
        };
        if histogram.len() <= age {
            histogram.resize(age + 1, 0);
        }
        histogram[age] += 1;
    }
}

/// Counts the classes of a classification image.
pub fn decisions(classes: &[u8]) -> Decisions {
    let (mut hit, mut refresh, mut offscreen, mut disoccluded, mut invalid) =
        (0usize, 0usize, 0usize, 0usize, 0usize);
    for texel in classes.chunks_exact(4) {
        match class_of(texel) {
            Some(Class::Hit) => hit += 1,
            Some(Class::Refresh) => refresh += 1,
            Some(Class::Disoccluded) => disoccluded += 1,
            Some(Class::Invalid) => invalid += 1,
            Some(Class::Offscreen) => offscreen += 1,
            None => {}
        }
    }
    let covered = hit + refresh + offscreen + disoccluded + invalid;
    let share = |n: usize| {
        if covered == 0 {
            0.0
        } else {
            n as f64 / covered as f64
        }
    };
    Decisions {
        covered,
        hit: share(hit),
        refresh: share(refresh),
        offscreen: share(offscreen),
        disoccluded: share(disoccluded),
        invalid: share(invalid),
    }
}

// The frame-time statistics the host's governor shares with the profiler.
pub use shadecache_plan::speed::{median, quantile, speedup_interval};

pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        0.0
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` RGBA pixels of one value.
    fn uniform(n: usize, value: f32) -> Vec<f32> {
        vec![value; n * 4]
    }

    /// SSIM is of the frame a display shows, sRGB-encoded. A dark
    /// gradient 5% too bright is a smooth, barely visible change, and
    /// scores near 1; of the linear frame quantised to 8 bits, where the
    /// gradient spans codes 1 to 7, the rounding turns the same change
    /// into structure, and it scored as a visible loss.
    #[test]
    fn ssim_is_of_the_srgb_encoded_frame() {
        let (width, height) = (32u32, 32u32);
        let gradient = |scale: f32| -> Vec<f32> {
            (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .flat_map(|(x, y)| {
                    let v = (0.002 + 0.0005 * x as f32 + 0.0003 * y as f32) * scale;
                    [v, v, v, 1.0]
                })
                .collect()
        };
        let (reference, brighter) = (gradient(1.0), gradient(1.05));
        let error = compare_frames(&reference, &brighter, width, height, 0.01);
        let encoded = ssim(&srgb8(&reference), &srgb8(&brighter), width, height);
        let linear = ssim(&rgba8(&reference), &rgba8(&brighter), width, height);
        assert_eq!(error.ssim, encoded);
        assert!(encoded > 0.97, "sRGB SSIM {encoded}");
        assert!(linear < 0.92, "linear 8-bit SSIM {linear}");
        assert_eq!(srgb8(&[0.004, 0.012, 1.0, 0.5]), vec![13, 29, 255, 128]);
    }

    #[test]
    fn identical_frames_have_capped_psnr_and_full_ssim() {
        let frame: Vec<f32> = (0..16 * 16 * 4)
            .map(|i| (i * 7 % 256) as f32 / 255.0)
            .collect();
        let all = vec![255u8; 16 * 16 * 4];
        let error = compare(&frame, &frame, &all, 16, 16, 0.05);
        assert_eq!(error.psnr, PSNR_CAP);
        assert!((error.ssim - 1.0).abs() < 1e-9);
        assert_eq!(error.max_abs_error, 0.0);
        assert_eq!(error.above_threshold, 0.0);
    }

    #[test]
    fn psnr_of_a_uniform_error() {
        let a = uniform(64, 100.0 / 255.0);
        let b = uniform(64, 110.0 / 255.0);
        // MSE = (10/255)², PSNR = 20 log10(255/10) ≈ 28.13 dB.
        let all = vec![255u8; 8 * 8 * 4];
        let error = compare(&a, &b, &all, 8, 8, 0.05);
        assert!((error.psnr - 28.1308).abs() < 1e-3, "{}", error.psnr);
        assert_eq!(error.psnr, error.psnr_frame);
        assert!((error.max_abs_error - 10.0 / 255.0).abs() < 1e-6);
        assert_eq!(error.above_threshold, 0.0);
        assert_eq!(compare(&a, &b, &all, 8, 8, 0.03).above_threshold, 1.0);
    }

    /// Over the covered pixels, in linear float: an error between values
    /// above 1, which an 8-bit target clamps to the same 255, counts in
    /// full; the exact background only raises the whole frame's figure;
    /// a NaN the reference lacks is the worst error there is.
    #[test]
    fn error_over_covered_pixels_in_float() {
        // Half the frame covered, at 2.0 against 2.1; the background exact.
        let reference = uniform(64, 2.0);
        let mut frame = reference.clone();
        let mut classes = vec![0u8; 8 * 8 * 4];
        for p in 0..32 {
            for c in 0..3 {
                frame[p * 4 + c] = 2.1;
            }
            classes[p * 4 + 3] = 255;
        }
        let error = compare(&reference, &frame, &classes, 8, 8, 0.05);
        // MSE = 0.1², PSNR = 20 dB.
        assert!((error.psnr - 20.0).abs() < 1e-3, "{}", error.psnr);
        assert!((error.psnr_frame - (20.0 + 10.0 * 2f64.log10())).abs() < 1e-3);
        assert!((error.max_abs_error - 0.1).abs() < 1e-6);
        assert_eq!(error.above_threshold, 1.0);
        // Clamped to 8 bits, as the pictures are, the two are one.
        assert_eq!(rgba8(&reference), rgba8(&frame));
        frame[0] = f32::NAN;
        let error = compare(&reference, &frame, &classes, 8, 8, 0.05);
        assert!(error.psnr < 0.0 && error.max_abs_error > 1e100, "{error:?}");
    }

    #[test]
    fn f16_readbacks_decode() {
        let bytes: Vec<u8> = [0.5f32, 2.0, 65504.0, -1.0]
            .iter()
            .flat_map(|&v| half::f16::from_f32(v).to_le_bytes())
            .collect();
        assert_eq!(linear_from_f16(&bytes), vec![0.5, 2.0, 65504.0, -1.0]);
        assert_eq!(rgba8(&[0.5, 2.0, -1.0, f32::NAN]), vec![128, 255, 0, 0]);
    }

    #[test]
    fn flicker_is_change_the_reference_does_not_make() {
        let classes = vec![255u8; 4 * 4 * 4];
        let still = uniform(16, 50.0 / 255.0);
        // A steady error is no flicker; a change the reference lacks is.
        let off = uniform(16, 60.0 / 255.0);
        assert_eq!(flicker(&still, &still, &off, &off, &classes), 0.0);
        let f = flicker(&still, &still, &still, &off, &classes);
        assert!((f - 10.0 / 255.0).abs() < 1e-6, "{f}");
        // The reference's own change, followed, is none either.
        assert_eq!(flicker(&still, &off, &still, &off, &classes), 0.0);
    }

    #[test]
    fn ages_count_covered_pixels_only() {
        let mut classes = Vec::new();
        for class in [HIT, REFRESH, [0, 0, 0], [128, 128, 128], HIT] {
            classes.extend(class);
            classes.push(255);
        }
        let ages: Vec<u8> = [3.0f32, 0.0, 7.0, 9.0, 3.0]
            .iter()
            .flat_map(|&a| half::f16::from_f32(a).to_le_bytes())
            .collect();
        let mut histogram = vec![0; 1];
        add_ages(&classes, &ages, &mut histogram);
        assert_eq!(histogram, vec![1, 0, 0, 2]);
    }

    #[test]
    fn decisions_count_shares_of_covered_pixels() {
        let mut classes = Vec::new();
        for class in [HIT, HIT, REFRESH, DISOCCLUDED, [255, 128, 0], [0, 0, 0]] {
            classes.extend(class);
            classes.push(255);
        }
        let d = decisions(&classes);
        assert_eq!(d.covered, 5);
        assert!((d.hit - 0.4).abs() < 1e-12);
        assert!((d.refresh - 0.2).abs() < 1e-12);
        assert!((d.miss() - 0.4).abs() < 1e-12);
        assert_eq!(median(&[3.0, 1.0, 2.0, 10.0]), 2.5);
    }
}
