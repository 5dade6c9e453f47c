//! What a way of showing the frames between I-frames is to the schedule
//! ([`FrameMethod`]), and what making one needs ([`Setup`]). Each family
//! implements it in its own file under [`super::methods`]; the schedule
//! ([`super::run`]) draws every interval's frames with each in turn, and
//! times, reads back and compares them in one place.

use std::collections::HashMap;

use super::bframe::{BFrameParams, BFrames};
use super::frames::{Drawn, Frames, InputsOf, IntervalAt};
use super::iframe::IFrameShader;
use super::measured::Measured;
use super::morph::Morph;
use super::setup::RunPlan;
use super::{Method, Options};
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::bench::Bench;
use crate::measure::clock::Clock;

/// One method's passes through an interval: what its I-frames add, then
/// each frame between them.
///
/// The schedule calls, per interval, [`FrameMethod::prepare`] once, then
/// for each frame `k` the method [`builds`](FrameMethod::builds)
/// [`FrameMethod::draw`] (timed by the method, since only it knows which
/// of its passes count), and in a recorded interval, after the frame is
/// compared and kept, [`FrameMethod::measure`].
pub(super) trait FrameMethod {
    /// The method it runs, as the report names it.
    fn method(&self) -> Method;

    /// Whether its I-frames are the instrumented pass that writes the
    /// flows (else the original shader's frame, what the methods that read
    /// no flows show): which I-frame time it pays.
    fn reads_flows(&self) -> bool {
        false
    }

    /// Whether its frames read the later I-frame's colour, which must then
    /// be rendered before they are shown: n − 1 displayed frames of added
    /// latency.
    fn reads_later_frame(&self) -> bool {
        false
    }

    /// Which I-frames its frames are made from: a camera cut between
    /// them leaves it nothing to reuse ([`IntervalAt::repeats`]).
    fn reads(&self) -> Reads {
        Reads::BothIFrames
    }

    /// In place of [`FrameMethod::prepare`], in an interval where every
    /// frame of it repeats the earlier I-frame (a camera cut): what it
    /// shows at the I-frame then, in a recorded interval (the extrapolators
    /// show the I-frame itself, uncompensated, as nothing after it is
    /// blurred).
    fn prepare_held(
        &mut self,
        _frames: &Frames,
        _at: &IntervalAt,
        _measured: &mut Measured,
    ) -> Result<(), Error> {
        Ok(())
    }

    /// Whether it shows each rendered I-frame as it is; the extrapolators
    /// show their own ([`FrameMethod::prepare`] adds it to the
    /// composites).
    fn shows_rendered_iframe(&self) -> bool {
        true
    }

    /// Its passes at the run's first I-frame (frame 0, I-frame slot 0),
    /// unmeasured.
    fn open(
        &mut self,
        _frames: &Frames,
        _clock: &mut Clock,
        _inputs_of: &InputsOf,
    ) -> Result<(), Error> {
        Ok(())
    }

    /// Its passes at the interval's I-frames, before its first frame: the
    /// time they take (ms), which counts in its I-frame time, or `None`
    /// where it adds none.
    fn prepare(
        &mut self,
        _frames: &Frames,
        _clock: &mut Clock,
        _at: &IntervalAt,
        _measured: &mut Measured,
    ) -> Result<Option<f64>, Error> {
        Ok(None)
    }

    /// Whether it builds the `k`-th frame of an interval of `n` (an
    /// extrapolator does not build α = 1, which is no end point of it).
    fn builds(&self, _k: u32, _n: u32) -> bool {
        true
    }

    /// Draws the `k`-th frame of the interval at `params`, timed.
    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        k: u32,
        params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error>;

    /// What else it measures of the `k`-th frame of a recorded interval,
    /// once it is kept (image-based: its correspondences).
    fn measure(
        &mut self,
        _frames: &Frames,
        _at: &IntervalAt,
        _k: u32,
        _params: &BFrameParams,
        _measured: &mut Measured,
    ) -> Result<(), Error> {
        Ok(())
    }
}

/// Which rendered frames a method's frames between I-frames are made
/// from: where a camera cut falls between them, its frames repeat the
/// earlier I-frame instead (design note, hard case 16 of seed 004:
/// "reset: no morph; repeat the frame").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Reads {
    /// The earlier I-frame alone, shown again (sample-and-hold): nothing
    /// to reset.
    EarlierIFrame,
    /// The interval's two I-frames, or the motion between them (every
    /// interpolator, and the extrapolators with the next I-frame's exact
    /// motion).
    BothIFrames,
    /// The earlier I-frame and the motion from the one before it (an
    /// extrapolator that knows only the past).
    PastIFrames,
}

/// What making the methods needs: the run's bench and plan, the
/// instrumented I-frame shader and its sources, the knobs, and the
/// B-frame and morph passes the methods share.
pub(super) struct Setup<'a> {
    pub bench: &'a Bench<'a>,
    pub shader: &'a Shader,
    pub plan: &'a RunPlan,
    pub instrumented: &'a IFrameShader,
    /// The instrumented module's text by its file name.
    pub sources: &'a HashMap<String, String>,
    pub options: &'a Options,
    /// Which of the scene's objects move.
    pub moving: &'a [bool],
    /// The fullscreen B-frame passes of the image-space methods.
    pub bframes: &'a BFrames,
    /// The morph's passes, when a method extrapolates.
    pub morph: Option<&'a Morph>,
}

impl Setup<'_> {
    /// The image-based search's knobs: its iterations, and with
    /// latest-frame initialisation the radius of its taps.
    pub fn search(&self) -> (u32, Option<u32>) {
        let o = self.options;
        (o.iterations, o.latest_frame_init.then_some(o.latest_radius))
    }
}
