//! Sample-and-hold and linear blending: the earlier I-frame shown again,
//! or the two cross-faded. The baselines every other method must beat,
//! one fullscreen pass each ([`crate::interpolate::bframe`]).

use crate::diagnostic::Error;
use crate::interpolate::bframe::{BFrameParams, BFrames};
use crate::interpolate::frame_method::{FrameMethod, Reads};
use crate::interpolate::frames::{Drawn, Frames, IntervalAt};
use crate::interpolate::thin::FrameDepth;
use crate::interpolate::Method;
use crate::measure::clock::{timed_recording, Clock};
use crate::measure::fail;

/// [`Method::SampleAndHold`] or [`Method::LinearBlend`].
pub(super) struct HoldOrBlend<'a> {
    pub method: Method,
    pub bframes: &'a BFrames,
}

impl FrameMethod for HoldOrBlend<'_> {
    fn method(&self) -> Method {
        self.method
    }

    /// A blend waits for the later I-frame; holding does not.
    fn reads_later_frame(&self) -> bool {
        self.method == Method::LinearBlend
    }

    /// Holding shows the earlier I-frame alone; blending reads both.
    fn reads(&self) -> Reads {
        match self.method {
            Method::SampleAndHold => Reads::EarlierIFrame,
            _ => Reads::BothIFrames,
        }
    }

    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        _k: u32,
        params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error> {
        drawn(self.bframes, self.method, frames, clock, at, params)
    }
}

/// `method`'s fullscreen B-frame pass drawn between the interval's two
/// I-frames at `params`, timed: what it shows. Sample-and-hold's is also
/// what every method shows where a camera cut leaves it nothing to reuse
/// ([`IntervalAt::repeats`](crate::interpolate::frames::Cuts::repeats)).
pub(in crate::interpolate) fn drawn<'s>(
    bframes: &'s BFrames,
    method: Method,
    frames: &Frames,
    clock: &mut Clock,
    at: &'s IntervalAt,
    params: &BFrameParams,
) -> Result<Drawn<'s>, Error> {
    let time = render_timed(bframes, method, frames, clock, at, params)?;
    Ok(Drawn {
        time,
        color: bframes.color(),
        depth: FrameDepth::Buffer(at.textures.0.depth),
        decisions: Some(bframes.decisions()),
    })
}

/// Draws `method`'s fullscreen B-frame pass between the interval's two
/// I-frames at `params`, timed (ms).
pub(super) fn render_timed(
    bframes: &BFrames,
    method: Method,
    frames: &Frames,
    clock: &mut Clock,
    at: &IntervalAt,
    params: &BFrameParams,
) -> Result<f64, Error> {
    let textures = at.textures;
    let (time, _, _) = timed_recording(clock, "bframe", |profiler| {
        bframes.render(
            frames.gpu,
            method,
            (&textures.0, &textures.1),
            params,
            None,
            profiler,
        )
    })
    .map_err(fail)?;
    Ok(time)
}
