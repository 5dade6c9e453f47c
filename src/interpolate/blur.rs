//! Motion blur from B-frames (seed 000 §9): "B-frames immediately before
//! and after a given I-frame are composited together to generate a
//! motion-blurred scene with little added cost". The shutter and weights
//! are not given; here a box filter over the displayed frames within n/2
//! of each I-frame (the I-frame and n − 1 B-frames for odd n, n B-frames
//! for even n: ten at n = 10, the paper's count), compared with the same
//! composite of the reference frames.

use std::collections::BTreeMap;

use super::Method;
use crate::measure::metrics::{self, FrameError};

/// Running composites, keyed by (method, or `None` for the reference;
/// the I-frame at their centre).
pub(super) struct MotionBlur {
    n: u32,
    size: [u32; 2],
    open: BTreeMap<(Option<Method>, u32), (Vec<f32>, u32)>,
    /// Finished reference composites, by centre.
    reference: BTreeMap<u32, Vec<f32>>,
    /// Each method's composites against the reference's.
    errors: BTreeMap<Method, Vec<FrameError>>,
}

impl MotionBlur {
    pub fn new(n: u32, size: [u32; 2]) -> MotionBlur {
        MotionBlur {
            n,
            size,
            open: BTreeMap::new(),
            reference: BTreeMap::new(),
            errors: BTreeMap::new(),
        }
    }

    /// Frames in a composite.
    fn window(&self) -> u32 {
        2 * (self.n / 2) + 1
    }

    /// Adds what `who` (a method, or the reference for `None`) shows at
    /// displayed frame `frame` to every composite it falls in.
    pub fn add(&mut self, who: Option<Method>, frame: u32, picture: &[f32]) {
        let half = self.n / 2;
        let first = frame.saturating_sub(half).div_ceil(self.n);
        let last = (frame + half) / self.n;
        let (n, window) = (self.n, self.window());
        for centre in (first..=last).map(|i| i * n) {
            let (sum, count) = self
                .open
                .entry((who, centre))
                .or_insert_with(|| (vec![0.0; picture.len()], 0));
            for (s, v) in sum.iter_mut().zip(picture) {
                *s += v;
            }
            *count += 1;
            if *count == window {
                let (sum, count) = self.open.remove(&(who, centre)).unwrap_or_default();
                let composite: Vec<f32> = sum.iter().map(|v| v / count as f32).collect();
                self.finish(who, centre, composite);
            }
        }
    }

    fn finish(&mut self, who: Option<Method>, centre: u32, composite: Vec<f32>) {
        let Some(method) = who else {
            self.reference.insert(centre, composite);
            return;
        };
        let Some(reference) = self.reference.get(&centre) else {
            return;
        };
        let [width, height] = self.size;
        let error = metrics::compare_frames(reference, &composite, width, height, 1.0 / 255.0);
        self.errors.entry(method).or_default().push(error);
    }

    /// A method's composites against the reference's: mean SSIM and PSNR;
    /// `None` where none was complete.
    pub fn of(&self, method: Method) -> Option<(f64, f64)> {
        let errors = self.errors.get(&method)?;
        let ssim: Vec<f64> = errors.iter().map(|e| e.ssim).collect();
        let psnr: Vec<f64> = errors.iter().map(|e| e.psnr_frame).collect();
        Some((metrics::mean(&ssim), metrics::mean(&psnr)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A composite is the mean of the 2·⌊n/2⌋ + 1 frames around its
    /// I-frame, and a method whose frames are the reference's has no
    /// error.
    #[test]
    fn motion_blur_composites_the_frames_around_each_i_frame() {
        let mut blur = MotionBlur::new(4, [8, 8]);
        let picture = |v: f32| vec![v; 8 * 8 * 4];
        for frame in 0..=12 {
            let value = frame as f32 / 16.0;
            blur.add(None, frame, &picture(value));
            blur.add(Some(Method::LinearBlend), frame, &picture(value));
            blur.add(Some(Method::SampleAndHold), frame, &picture(0.0));
        }
        // Centres 4 and 8 are complete (frames 2–6 and 6–10); 0 and 12
        // are not.
        assert_eq!(blur.reference.len(), 2);
        assert_eq!(blur.reference[&4][0], 4.0 / 16.0);
        let (ssim, psnr) = blur.of(Method::LinearBlend).unwrap();
        assert_eq!((ssim, psnr), (1.0, metrics::PSNR_CAP));
        assert!(blur.of(Method::SampleAndHold).unwrap().1 < 30.0);
    }
}
