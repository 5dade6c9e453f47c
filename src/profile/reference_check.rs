//! The reference check: whether the unmodified shader's frames show
//! something a cache's figures can be measured on.
//!
//! A profile compares every variant with the reference frames. When those
//! frames are empty, black, one flat colour, full of NaNs, or the same
//! every frame, every variant matches them and scores a perfect error
//! while saying nothing about the shader (a hash-cells shader on a black
//! frame scores SSIM 1.0). So the reference is looked at before anything
//! is ranked, over every measured frame:
//!
//! - **coverage**: the share of pixels the draw reached: its depth
//!   buffer no longer at the clear depth (an opaque black pixel is drawn,
//!   though it shows the clear colour);
//! - **luminance** (Rec. 709, linear) of the drawn pixels: its mean, the
//!   share of drawn pixels above [`DARK`], and its spread (standard
//!   deviation);
//! - **non-finite** channel values (NaN, ±∞);
//! - **change**: the share of pixels that differ at all between the first
//!   measured frame and each later one, the largest (a dim or flat frame
//!   changes by little, but changes; a still one not by a bit).
//!
//! A finding that makes the figures meaningless is a [`Problem`], said
//! first in the terminal and at the top of the report, with what likely
//! caused it, and the answer never recommends a configuration measured on
//! such a reference.

use crate::report::{ReferenceCheck, ReferenceProblem};
use crate::scene::Scene;

/// Linear luminance below which a pixel counts as dark (about 1/40 of
/// white: sRGB 0.18, a very dark grey).
pub const DARK: f64 = 0.025;

/// Below this share of drawn pixels above [`DARK`], the frame is "nearly
/// black".
const NEARLY_BLACK: f64 = 0.01;

/// Below this standard deviation of luminance, and this largest channel
/// range, the drawn pixels are one colour.
const FLAT_SPREAD: f64 = 1.0e-3;
const FLAT_RANGE: f64 = 4.0 / 255.0;

/// Running sums over the reference's measured frames.
#[derive(Debug, Default)]
pub(crate) struct ReferenceStats {
    frames: u64,
    pixels: u64,
    drawn: u64,
    bright: u64,
    non_finite: u64,
    luminance_sum: f64,
    luminance_squares: f64,
    channel_min: [f64; 3],
    channel_max: [f64; 3],
    first: Vec<f32>,
    changed: Option<f64>,
}

/// Rec. 709 luminance of linear RGB.
fn luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

impl ReferenceStats {
    /// Adds one measured frame: `now`, RGBA linear float, and `depth`, its
    /// depth buffer (empty: a pixel is drawn where its colour is not the
    /// `clear` one); `clear` is the colour and depth the frame starts from.
    pub fn add(&mut self, now: &[f32], depth: &[f32], clear: ([f64; 4], f64)) {
        let (clear, clear_depth) = clear;
        if self.frames == 0 {
            self.channel_min = [f64::INFINITY; 3];
            self.channel_max = [f64::NEG_INFINITY; 3];
        }
        self.frames += 1;
        for (index, pixel) in now.chunks_exact(4).enumerate() {
            self.pixels += 1;
            let reached = depth
                .get(index)
                .map(|&d| (f64::from(d) - clear_depth).abs() > 1e-7);
            if pixel.iter().any(|v| !v.is_finite()) {
                self.non_finite += 1;
                self.drawn += 1;
                continue;
            }
            let value = [0, 1, 2, 3].map(|c| f64::from(pixel[c]));
            let drawn = reached
                .unwrap_or_else(|| value.iter().zip(clear).any(|(v, c)| (v - c).abs() > 1.0e-6));
            if !drawn {
                continue;
            }
            self.drawn += 1;
            let rgb = [value[0], value[1], value[2]];
            let y = luminance(rgb);
            self.luminance_sum += y;
            self.luminance_squares += y * y;
            self.bright += u64::from(y > DARK);
            for ((low, high), value) in self
                .channel_min
                .iter_mut()
                .zip(&mut self.channel_max)
                .zip(rgb)
            {
                *low = low.min(value);
                *high = high.max(value);
            }
        }
        if self.first.is_empty() {
            self.first = now.to_vec();
        } else if self.first.len() == now.len() {
            let pixels = now.len() / 4;
            let changed = now
                .chunks_exact(4)
                .zip(self.first.chunks_exact(4))
                .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.to_bits() != y.to_bits()))
                .count();
            let share = changed as f64 / pixels.max(1) as f64;
            self.changed = Some(self.changed.map_or(share, |c: f64| c.max(share)));
        }
    }

    /// The check of these frames; `scene` and `defaulted` (what nothing
    /// said the value of) suggest the likely causes.
    pub fn check(&self, scene: &Scene, defaulted: &[String]) -> ReferenceCheck {
        let share = |n: u64, of: u64| if of == 0 { 0.0 } else { n as f64 / of as f64 };
        let lit = self.drawn - self.non_finite;
        let mean = if lit == 0 {
            0.0
        } else {
            self.luminance_sum / lit as f64
        };
        let spread = if lit == 0 {
            0.0
        } else {
            (self.luminance_squares / lit as f64 - mean * mean)
                .max(0.0)
                .sqrt()
        };
        let range = if lit == 0 {
            0.0
        } else {
            (0..3)
                .map(|c| self.channel_max[c] - self.channel_min[c])
                .fold(0.0, f64::max)
        };
        let mut check = ReferenceCheck {
            frames: self.frames as u32,
            coverage: share(self.drawn, self.pixels),
            mean_luminance: mean,
            bright_share: share(self.bright, lit),
            luminance_spread: spread,
            channel_range: range,
            non_finite_share: share(self.non_finite, self.drawn),
            changed_share: self.changed,
            problems: Vec::new(),
        };
        check.problems = problems(&check, scene, defaulted);
        check
    }
}

/// Defaulted inputs named in a reference problem's cause.
const LISTED_INPUTS: usize = 8;

/// " Defaulted inputs to look at: …." for the first [`LISTED_INPUTS`] of
/// `inputs`, saying how many more there are (an engine's shader defaults
/// thousands: every element of its mesh and light arrays).
fn listed_inputs(inputs: &[String]) -> String {
    if inputs.is_empty() {
        return String::new();
    }
    let shown = &inputs[..inputs.len().min(LISTED_INPUTS)];
    let more = match inputs.len() - shown.len() {
        0 => String::new(),
        n => format!("; and {n} more (`shadecache scene init` writes every one)"),
    };
    format!(" Defaulted inputs to look at: {}{more}.", shown.join("; "))
}

/// What makes a reference's figures meaningless, each with its likely
/// cause.
fn problems(check: &ReferenceCheck, scene: &Scene, defaulted: &[String]) -> Vec<ReferenceProblem> {
    let mut out = Vec::new();
    let mut add = |kind: &str, finding: String, cause: String| {
        out.push(ReferenceProblem {
            kind: kind.into(),
            finding,
            cause,
        });
    };
    let suspects = |words: &[&str]| -> Vec<String> {
        defaulted
            .iter()
            .filter(|d| {
                let lower = d.to_ascii_lowercase();
                words.iter().any(|w| lower.contains(w))
            })
            .cloned()
            .collect()
    };
    let listed = |inputs: Vec<String>| listed_inputs(&inputs);
    if check.coverage == 0.0 {
        add(
            "empty",
            "the reference draws no pixel: every frame is the clear colour".into(),
            format!(
                "an empty view: the camera does not see the objects, or the vertex stage places them off screen (a matrix the scene does not fill, left the identity or zero, puts every vertex outside the view).{}",
                listed(suspects(&["matri", "transform", "view", "proj", "model", "world"]))
            ),
        );
        return out;
    }
    if check.non_finite_share > 0.0 {
        add(
            "non-finite",
            format!(
                "{:.1}% of the drawn pixels are NaN or infinite",
                check.non_finite_share * 100.0
            ),
            format!(
                "a division by zero or the square root or logarithm of a negative value, usually from an input at zero (a normalised zero vector, a roughness or distance of 0).{}",
                listed(defaulted.to_vec())
            ),
        );
    }
    if check.bright_share < NEARLY_BLACK {
        add(
            "nearly-black",
            format!(
                "the frame is nearly black: {:.2}% of the drawn pixels are brighter than luminance {DARK} (mean {:.4})",
                check.bright_share * 100.0,
                check.mean_luminance
            ),
            format!(
                "an unlit input: a light's colour, intensity or count at zero, a shadow map that shadows everything, or a black texture; or a shader whose output is meant for another pass (a mask, an id).{}",
                listed(suspects(&["light", "colo", "intens", "exposure", "count", "shadow", "texture"]))
            ),
        );
    } else if check.luminance_spread < FLAT_SPREAD && check.channel_range < FLAT_RANGE {
        add(
            "constant",
            format!(
                "every drawn pixel has the same colour (luminance {:.4}, no channel varies by more than {:.4})",
                check.mean_luminance, check.channel_range
            ),
            format!(
                "inputs that do not vary over the surface: a flat texture, a factor that zeroes the shading, or a shader that ignores its vertex inputs.{}",
                listed(defaulted.to_vec())
            ),
        );
    }
    if check.changed_share == Some(0.0) {
        add(
            "still",
            "the frames do not change: every measured frame is the first to the bit".into(),
            if scene.effects.is_empty() {
                "the scene declares no effect (`effects`), so nothing moves: a cache never misses and its error is that of a still picture".into()
            } else {
                "the scene's motion does not reach the shader: its matrices and positions are not filled by the simulation (see `[roles]`), or it draws a fullscreen pass or a 2D image that no camera or object motion moves; its picture changes only with its own inputs (a `time` uniform), so the draw is the same every frame".into()
            },
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn scene() -> Scene {
        let text = "effects = [\"object-motion\"]\n[[objects]]\nmesh = { kind = \"cube\" }\n";
        Scene::parse(Arc::new(crate::diagnostic::SourceFile::new("s.toml", text))).unwrap()
    }

    /// `pixels` RGBA pixels of colour `rgba`, followed by `clear` ones.
    fn frame(pixels: usize, rgba: [f32; 4], background: usize) -> Vec<f32> {
        let mut out = Vec::new();
        for _ in 0..pixels {
            out.extend(rgba);
        }
        for _ in 0..background {
            out.extend([0.0; 4]);
        }
        out
    }

    fn kinds(frames: &[Vec<f32>]) -> Vec<String> {
        let mut stats = ReferenceStats::default();
        for now in frames {
            stats.add(now, &[], ([0.0; 4], 1.0));
        }
        stats
            .check(&scene(), &[])
            .problems
            .into_iter()
            .map(|p| p.kind)
            .collect()
    }

    /// An opaque black pixel on an opaque black clear is drawn when the
    /// depth buffer says it was: a black frame is "nearly black", not an
    /// empty view.
    #[test]
    fn black_on_black_is_drawn_by_its_depth() {
        let black = frame(4, [0.0, 0.0, 0.0, 1.0], 0);
        let mut stats = ReferenceStats::default();
        stats.add(&black, &[0.5, 0.5, 1.0, 1.0], ([0.0, 0.0, 0.0, 1.0], 1.0));
        let check = stats.check(&scene(), &[]);
        assert_eq!(check.coverage, 0.5);
        let kinds: Vec<&str> = check.problems.iter().map(|p| p.kind.as_str()).collect();
        assert_eq!(kinds, ["nearly-black"]);
    }

    #[test]
    fn an_engine_shaders_thousand_defaulted_inputs_are_listed_in_part() {
        let inputs: Vec<String> = (0..1000)
            .map(|i| format!("uniform `mesh[{i}].world`"))
            .collect();
        let listed = listed_inputs(&inputs);
        assert!(
            listed.contains("mesh[7]") && !listed.contains("mesh[8]"),
            "{listed}"
        );
        assert!(listed.contains("and 992 more"), "{listed}");
        assert_eq!(
            listed_inputs(&inputs[..2]),
            " Defaulted inputs to look at: uniform `mesh[0].world`; uniform `mesh[1].world`."
        );
        assert_eq!(listed_inputs(&[]), "");
    }

    #[test]
    fn a_shaded_moving_frame_passes() {
        let mut a = frame(50, [0.5, 0.4, 0.3, 1.0], 50);
        a.extend(frame(50, [0.1, 0.2, 0.9, 1.0], 0));
        let mut b = a.clone();
        b[0] = 0.9;
        assert!(kinds(&[a, b]).is_empty());
    }

    #[test]
    fn empty_black_flat_nan_and_still_frames_are_named() {
        assert_eq!(kinds(&[frame(0, [0.0; 4], 100)]), ["empty"]);
        // Black, opaque: drawn, but dark; two lit pixels do not make it lit.
        let mut black = frame(998, [0.0, 0.0, 0.0, 1.0], 2);
        black.extend(frame(2, [1.0; 4], 0));
        assert!(kinds(&[black]).contains(&"nearly-black".to_string()));
        assert_eq!(kinds(&[frame(100, [0.5, 0.5, 0.5, 1.0], 0)]), ["constant"]);
        let mut nan = frame(100, [0.5, 0.4, 0.3, 1.0], 0);
        nan.extend(frame(100, [0.1, 0.9, 0.3, 1.0], 0));
        nan[0] = f32::NAN;
        assert_eq!(kinds(&[nan]), ["non-finite"]);
        let mut shaded = frame(100, [0.5, 0.4, 0.3, 1.0], 0);
        shaded.extend(frame(100, [0.1, 0.9, 0.3, 1.0], 0));
        assert_eq!(kinds(&[shaded.clone(), shaded]), ["still"]);
    }
}
