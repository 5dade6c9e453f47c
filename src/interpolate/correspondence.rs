//! Seed 000 Fig. 11's errors, from a B-frame's exact correspondences (the
//! scene-assisted pass in its correspondence mode: each covered pixel's
//! offset p − p₀ to where its surface point is in I-frame 0, and, drawn
//! with the I-frames swapped, p − p₁ into I-frame 1):
//! - E_total: how far image-based's forward search lands from p₀; and of
//!   the correspondence it used (either direction, as §5.2 chose), how
//!   far that lands from the exact point in that I-frame;
//! - E_lin: how far the linear-motion assumption every warping method
//!   makes lands from it: I-frame 0's point p₀ carried α of the way along
//!   its exact flow to I-frame 1, against where it is at the B-frame's
//!   time, |α·Vf(p₀) − (p − p₀)|. Zero for constant screen velocity; what
//!   a turning or accelerating object costs every method before any
//!   search error.
//!
//! Each is kept per pixel with whether the pixel lies on a silhouette (a
//! 4-neighbour uncovered, or its offset more than a pixel away), so the
//! report gives means, the 95th percentile, the split and the paper's
//! table of shares by range.

use serde::Serialize;

/// The ranges of Fig. 11's table, in pixels: [0, 0.5), [0.5, 1), [1, 2),
/// [2, 4), 4 and over.
pub const RANGES: [f32; 4] = [0.5, 1.0, 2.0, 4.0];

/// One error per covered pixel, and whether it is on a silhouette.
#[derive(Clone, Debug, Default)]
pub struct Samples {
    /// (error in pixels, on a silhouette).
    pub values: Vec<(f32, bool)>,
}

/// What one B-frame's correspondences give.
#[derive(Clone, Debug, Default)]
pub struct FrameErrors {
    /// E_total over every covered pixel.
    pub total: Samples,
    /// E_total over the covered pixels whose point I-frame 0 shows.
    pub total_hit: Samples,
    /// E_total of the correspondence used, forward or backward, over
    /// every covered pixel.
    pub used: Samples,
    /// E_lin over every covered pixel whose point I-frame 0 shows, with a
    /// valid flow.
    pub linear: Samples,
}

/// Fig. 11's errors of one B-frame at `alpha` (`size` pixels): `exact`
/// the correspondence pass's RGBA (p − p₀, seen in I-frame 0, covered),
/// `found` image-based's written offsets (p − q₀, p − q₁), `flow_next`
/// I-frame 0's flow to I-frame 1 (Δx, Δy, Δz, valid); `used` the
/// correspondence pass's RGBA into I-frame 1 (p − p₁, …) and per pixel the
/// direction image-based took (1 forward, 0 backward).
pub fn frame_errors(
    exact: &[f32],
    found: &[f32],
    flow_next: &[f32],
    (later, directions): (&[f32], &[f32]),
    [width, height]: [u32; 2],
    alpha: f32,
) -> FrameErrors {
    let (w, h) = (width as i64, height as i64);
    let covered = |x: i64, y: i64| -> Option<[f32; 2]> {
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let e = &exact[((y * w + x) * 4) as usize..][..4];
        (e[3] >= 0.5).then_some([e[0], e[1]])
    };
    let mut out = FrameErrors::default();
    for y in 0..h {
        for x in 0..w {
            let Some(offset) = covered(x, y) else {
                continue;
            };
            let silhouette = [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dx, dy)| {
                covered(x + dx, y + dy)
                    .is_none_or(|o| (o[0] - offset[0]).hypot(o[1] - offset[1]) > 1.0)
            });
            let p = ((y * w + x) * 4) as usize;
            let f = &found[p..p + 2];
            let total = (offset[0] - f[0]).hypot(offset[1] - f[1]);
            if total.is_finite() {
                out.total.values.push((total, silhouette));
                if exact[p + 2] > 0.5 {
                    out.total_hit.values.push((total, silhouette));
                }
            }
            let forward = directions
                .get((y * w + x) as usize)
                .is_none_or(|d| *d > 0.5);
            let used = if forward {
                total
            } else {
                let e = &later[p..p + 2];
                (e[0] - found[p + 2]).hypot(e[1] - found[p + 3])
            };
            if used.is_finite() {
                out.used.values.push((used, silhouette));
            }
            // Where the point is in I-frame 0, and its flow there: only
            // where I-frame 0 shows it (else the flow there is another
            // surface's).
            if exact[p + 2] <= 0.5 {
                continue;
            }
            let (x0, y0) = (
                (x as f32 + 0.5 - offset[0]).floor() as i64,
                (y as f32 + 0.5 - offset[1]).floor() as i64,
            );
            if x0 < 0 || y0 < 0 || x0 >= w || y0 >= h {
                continue;
            }
            let v = &flow_next[((y0 * w + x0) * 4) as usize..][..4];
            if v[3] <= 0.0 {
                continue;
            }
            let linear = (alpha * v[0] - offset[0]).hypot(alpha * v[1] - offset[1]);
            if linear.is_finite() {
                out.linear.values.push((linear, silhouette));
            }
        }
    }
    out
}

/// An error's spread over every measured B-frame, in pixels.
#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    /// Over every pixel.
    pub mean: f64,
    /// Its 95th percentile.
    pub p95: f64,
    /// The mean over the pixels on silhouettes.
    pub silhouette_mean: f64,
    /// The mean over the rest.
    pub interior_mean: f64,
    /// The share of the pixels in each of [`RANGES`]' five ranges.
    pub ranges: [f64; 5],
}

impl Samples {
    /// Adds another frame's samples.
    pub fn extend(&mut self, other: Samples) {
        self.values.extend(other.values);
    }

    /// The mean error.
    pub fn mean(&self) -> f64 {
        mean_of(self.values.iter().map(|v| v.0))
    }

    /// Its spread; `None` with no sample.
    pub fn spread(&self) -> Option<Spread> {
        if self.values.is_empty() {
            return None;
        }
        let mut sorted: Vec<f32> = self.values.iter().map(|v| v.0).collect();
        sorted.sort_by(f32::total_cmp);
        let p95 = sorted[((sorted.len() - 1) as f64 * 0.95).round() as usize];
        let mut ranges = [0.0; 5];
        for &(v, _) in &self.values {
            let bin = RANGES.iter().take_while(|&&edge| v >= edge).count();
            ranges[bin] += 1.0;
        }
        let count = self.values.len() as f64;
        Some(Spread {
            mean: self.mean(),
            p95: f64::from(p95),
            silhouette_mean: mean_of(self.values.iter().filter(|v| v.1).map(|v| v.0)),
            interior_mean: mean_of(self.values.iter().filter(|v| !v.1).map(|v| v.0)),
            ranges: ranges.map(|r| r / count),
        })
    }
}

fn mean_of(values: impl Iterator<Item = f32>) -> f64 {
    let (sum, count) = values.fold((0.0f64, 0usize), |(s, c), v| (s + f64::from(v), c + 1));
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×1 strip moving 2 px per interval, the B-frame half way: the
    /// exact offsets are 1 px, the linear prediction 0.5·2 = 1 px: E_lin 0.
    /// A search that found 1.5 px is 0.5 off.
    #[test]
    fn linear_motion_has_no_linear_error() {
        let exact: Vec<f32> = (0..4).flat_map(|_| [1.0, 0.0, 1.0, 1.0]).collect();
        let found: Vec<f32> = (0..4).flat_map(|_| [1.5, 0.0, 0.0, 0.0]).collect();
        let flow: Vec<f32> = (0..4).flat_map(|_| [2.0, 0.0, 0.0, 1.0]).collect();
        let forward = [1.0; 4];
        let errors = frame_errors(&exact, &found, &flow, (&exact, &forward), [4, 1], 0.5);
        assert!(errors.linear.values.iter().all(|v| v.0 < 1e-6));
        assert!(errors.total.values.iter().all(|v| (v.0 - 0.5).abs() < 1e-6));
        // Every pixel went forward: what it used is the forward search.
        assert_eq!(errors.used.values, errors.total.values);
        let spread = errors.total.spread().unwrap();
        assert_eq!(spread.ranges, [0.0, 1.0, 0.0, 0.0, 0.0]);
    }

    /// The error of the correspondence used is the forward search's where
    /// it took the forward direction, the backward search's against the
    /// exact point in I-frame 1 where it took that.
    #[test]
    fn used_correspondence_follows_the_chosen_direction() {
        // Exact: 1 px into I-frame 0, −1 px into I-frame 1. Found: 1.5 px
        // and −1.25 px. Pixels 0 and 1 went forward, 2 and 3 backward.
        let exact: Vec<f32> = (0..4).flat_map(|_| [1.0, 0.0, 1.0, 1.0]).collect();
        let later: Vec<f32> = (0..4).flat_map(|_| [-1.0, 0.0, 1.0, 1.0]).collect();
        let found: Vec<f32> = (0..4).flat_map(|_| [1.5, 0.0, -1.25, 0.0]).collect();
        let flow: Vec<f32> = (0..4).flat_map(|_| [2.0, 0.0, 0.0, 1.0]).collect();
        let directions = [1.0, 1.0, 0.0, 0.0];
        let errors = frame_errors(&exact, &found, &flow, (&later, &directions), [4, 1], 0.5);
        let used: Vec<f32> = errors.used.values.iter().map(|v| v.0).collect();
        assert_eq!(used, vec![0.5, 0.5, 0.25, 0.25]);
    }
}
