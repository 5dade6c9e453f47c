//! The extrapolators (Didyk et al. 2010): the frames after an I-frame
//! warped from it alone by the snapped grid morph
//! ([`crate::interpolate::morph`]), with the next I-frame's exact motion
//! ([`Method::Morph`]) or the motion from the I-frame before
//! ([`Method::MorphPast`]), blurred and the I-frame compensated; or the
//! warp alone ([`Method::MorphWarp`]). The morph's preparation is an
//! I-frame pass of theirs: it counts in their I-frame time.

use crate::diagnostic::Error;
use crate::interpolate::bframe::BFrameParams;
use crate::interpolate::frame_method::{FrameMethod, Reads};
use crate::interpolate::frames::{Drawn, Frames, IntervalAt, THRESHOLD};
use crate::interpolate::measured::Measured;
use crate::interpolate::morph::{Morph, MorphParams, MorphSetup, Source};
use crate::interpolate::report::KeptFrame;
use crate::interpolate::thin::FrameDepth;
use crate::interpolate::Method;
use crate::interpolate::Options;
use crate::measure::clock::{read_linear, timed_recording, Clock};
use crate::measure::fail;
use crate::measure::metrics;
use crate::runtime::Gpu;

/// One extrapolator, drawn with the run's morph passes.
pub(super) struct Extrapolator<'a> {
    pub method: Method,
    pub morph: &'a Morph,
}

impl Extrapolator<'_> {
    /// The morph's knobs for this method, at step 0.
    fn params(&self, frames: &Frames) -> MorphParams {
        let o = frames.options;
        let n = o.frames_per_interval as f32;
        MorphParams {
            step: 0.0,
            frames: n,
            gamma: o.gamma,
            exact_motion: self.method != Method::MorphPast,
            speed_scale: frames.speed_scale(),
            tracking: o.tracking,
            blur_min_speed: o.blur_min_speed,
            distortion: o.distortion_blur,
            snap_threshold: o.snap_threshold,
            far_depth: frames.far_depth,
            blur: self.method != Method::MorphWarp,
            snap: o.snap,
        }
    }

    /// What it extrapolates from: the interval's I-frame 0 and the flow
    /// its motion is taken from.
    fn source<'t>(at: &'t IntervalAt, params: &MorphParams) -> Source<'t> {
        let earlier = &at.textures.0;
        Source {
            color: earlier.color,
            depth: earlier.depth,
            flow: if params.exact_motion {
                earlier.flow_next
            } else {
                earlier.flow_previous
            },
        }
    }

    /// What it shows at its interval's I-frame: compensated (with blur:
    /// [`Morph::displayed`]) or the I-frame itself. The compensated one is
    /// compared with the reference, kept with `keep_frames` and put in the
    /// pursuit group (the I-frame itself is there by default); either
    /// joins the motion-blur composites.
    fn displayed_iframe(
        &self,
        frames: &Frames,
        at: &IntervalAt,
        measured: &mut Measured,
        blur: bool,
    ) -> Result<(), Error> {
        let (method, start) = (self.method, at.start);
        if !blur {
            if let Some(composites) = measured.blur.as_mut() {
                let shown = read_linear(frames.gpu, at.textures.0.color).map_err(fail)?;
                composites.add(Some(method), start, &shown);
            }
            return Ok(());
        }
        if measured.previous_end.is_none() {
            return Ok(());
        }
        let shown = read_linear(frames.gpu, self.morph.displayed()).map_err(fail)?;
        let reference = frames.reference_at(0, at.pictures, measured)?;
        let [width, height] = frames.size;
        let error = metrics::compare_frames(&reference, &shown, width, height, THRESHOLD);
        let run = measured.methods.entry(method).or_default();
        run.displayed_iframes.push((start, error));
        if let Some(composites) = measured.blur.as_mut() {
            composites.add(Some(method), start, &shown);
        }
        if frames.options.keep_frames {
            measured.kept.push(KeptFrame {
                method,
                frame: start,
                alpha: 0.0,
                error,
                reference,
                result: shown.clone(),
                decisions: Vec::new(),
            });
        }
        let n = frames.options.frames_per_interval as usize;
        measured
            .groups
            .entry(method)
            .or_insert_with(|| vec![None; n])[0] = Some(shown);
        Ok(())
    }
}

impl FrameMethod for Extrapolator<'_> {
    fn method(&self) -> Method {
        self.method
    }

    fn reads_flows(&self) -> bool {
        true
    }

    fn shows_rendered_iframe(&self) -> bool {
        false
    }

    /// With the next I-frame's exact motion, both I-frames' flows; with
    /// the past's, the I-frame before's.
    fn reads(&self) -> Reads {
        match self.method {
            Method::MorphPast => Reads::PastIFrames,
            _ => Reads::BothIFrames,
        }
    }

    /// Nothing is morphed or blurred after the I-frame: it is shown as it
    /// is, uncompensated.
    fn prepare_held(
        &mut self,
        frames: &Frames,
        at: &IntervalAt,
        measured: &mut Measured,
    ) -> Result<(), Error> {
        if at.record {
            self.displayed_iframe(frames, at, measured, false)?;
        }
        Ok(())
    }

    /// The morph's preparation from I-frame 0, timed; in a recorded
    /// interval, what the method shows at I-frame 0.
    fn prepare(
        &mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &IntervalAt,
        measured: &mut Measured,
    ) -> Result<Option<f64>, Error> {
        let params = self.params(frames);
        let source = Self::source(at, &params);
        let (prepare_ms, _, _) = timed_recording(clock, "morph", |profiler| {
            self.morph.prepare(frames.gpu, &source, &params, profiler);
            Ok(())
        })
        .map_err(fail)?;
        if at.record {
            self.displayed_iframe(frames, at, measured, params.blur)?;
        }
        Ok(Some(prepare_ms))
    }

    /// Extrapolated from I-frame 0 alone: α = 1 is no end point of it.
    fn builds(&self, k: u32, n: u32) -> bool {
        k != n
    }

    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        k: u32,
        _params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error> {
        let mut params = self.params(frames);
        params.step = k as f32 / frames.options.frames_per_interval as f32;
        let source = Self::source(at, &params);
        let (time, _, _) = timed_recording(clock, "bframe", |profiler| {
            self.morph.render(frames.gpu, &source, &params, profiler);
            Ok(())
        })
        .map_err(fail)?;
        Ok(Drawn {
            time,
            color: self.morph.color(),
            depth: FrameDepth::Buffer(at.textures.0.depth),
            decisions: None,
        })
    }
}

/// The morph's passes, when a method extrapolates; its grid checked
/// against the frame's `size`.
pub(in crate::interpolate) fn passes(
    gpu: &Gpu,
    options: &Options,
    size: [u32; 2],
) -> Result<Option<Morph>, Error> {
    if !options.methods.iter().any(|m| m.extrapolates()) {
        return Ok(None);
    }
    // The grid against the size was checked with the run's plan
    // (`RunPlan::new`), before the GPU.
    let setup = MorphSetup {
        size,
        grid: options.grid,
        blur_level: options.blur_level,
        blur_gated_by_speed: options.blur_min_speed.is_some(),
        blur_order: options.blur_order,
    };
    Ok(Some(Morph::new(gpu, setup).map_err(fail)?))
}
