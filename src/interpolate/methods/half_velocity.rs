//! Half-velocity up-conversion (Andreev 2010): the frame between two
//! I-frames fetched at half the motion from both, with velocity merging
//! and a direction test; one fullscreen pass
//! ([`crate::interpolate::bframe`]).
//!
//! Moving objects (slides 33–47): where the scene has some, the pass of
//! the geometry at each B-frame's time draws only them (their exact
//! offsets and mask), and once an interval they are wiped out of the
//! earlier I-frame where they have left; both count in its B-frame time.

use crate::diagnostic::Error;
use crate::interpolate::bframe::{BFrameParams, BFrames, MovingObjects};
use crate::interpolate::frame_method::{FrameMethod, Setup};
use crate::interpolate::frames::{Drawn, Frames, IntervalAt};
use crate::interpolate::gpu::reborrow;
use crate::interpolate::iframe::SceneMode;
use crate::interpolate::measured::Measured;
use crate::interpolate::thin::FrameDepth;
use crate::interpolate::Method;
use crate::measure::clock::{timed_recording, Clock};
use crate::measure::fail;

use super::scene_assisted::SceneRun;

/// [`Method::HalfVelocity`].
pub(super) struct HalfVelocity<'a> {
    pub bframes: &'a BFrames,
    /// The moving objects' pass, when the scene has some and the knobs
    /// ask for them.
    pub moving: Option<SceneRun>,
    /// Whether this interval's moving objects are still to be wiped out
    /// of its earlier I-frame (with its first B-frame).
    removal: bool,
}

impl<'a> HalfVelocity<'a> {
    /// The method, drawn with `setup`'s B-frame passes; its moving
    /// objects' pass is named in `notes`, or why it is not made.
    pub fn new(setup: &Setup<'a>, notes: &mut Vec<String>) -> HalfVelocity<'a> {
        let count = setup.moving.iter().filter(|m| **m).count();
        let moving = if setup.options.moving_objects && count > 0 {
            match SceneRun::new(setup, Method::HalfVelocity, SceneMode::MovingObjects) {
                Ok(run) => {
                    notes.push(format!(
                        "half-velocity draws the {count} moving object(s) at each B-frame's time and wipes them out of the earlier I-frame (Andreev 2010 slides 33–47): both count in its B-frame time (--no-moving-objects leaves them to the velocity)"
                    ));
                    Some(run)
                }
                Err(reason) => {
                    notes.push(format!(
                        "half-velocity treats moving objects as the rest (no exact offsets, no removal): {reason}"
                    ));
                    None
                }
            }
        } else {
            None
        };
        HalfVelocity {
            bframes: setup.bframes,
            moving,
            removal: false,
        }
    }
}

impl FrameMethod for HalfVelocity<'_> {
    fn method(&self) -> Method {
        Method::HalfVelocity
    }

    /// It reads the later I-frame's depth and velocity alone, which an
    /// engine renders first (Andreev 2010's one-frame mode): no latency.
    fn reads_flows(&self) -> bool {
        true
    }

    fn prepare(
        &mut self,
        _frames: &Frames,
        _clock: &mut Clock,
        _at: &IntervalAt,
        _measured: &mut Measured,
    ) -> Result<Option<f64>, Error> {
        self.removal = self.moving.is_some();
        Ok(None)
    }

    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        k: u32,
        params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error> {
        let (gpu, textures, bframes) = (frames.gpu, at.textures, self.bframes);
        let mut moving_now = match self.moving.as_mut() {
            Some(run) => {
                run.bind(gpu, textures, params)?;
                let inputs =
                    frames.twinned_inputs(at.inputs_of, [at.start + k, at.start, at.end])?;
                Some((run, frames.only_moving(inputs)))
            }
            None => None,
        };
        let removal = &mut self.removal;
        let (time, _, _) = timed_recording(clock, "bframe", |mut profiler| {
            let mut objects = None;
            if let Some((run, inputs)) = moving_now.as_mut() {
                if std::mem::take(removal) {
                    bframes.remove_moving_objects(
                        gpu,
                        (textures.0.color, textures.0.flow_next),
                        params,
                        frames.options.inpaint_passes,
                        reborrow(&mut profiler),
                    );
                }
                run.runner.frame(gpu, inputs, reborrow(&mut profiler))?;
                objects = Some(MovingObjects {
                    now: run.output(frames.instrumented.scene_locations[0])?,
                    removed: bframes.removed(),
                });
            }
            bframes.render(
                gpu,
                Method::HalfVelocity,
                (&textures.0, &textures.1),
                params,
                objects,
                profiler,
            )
        })
        .map_err(fail)?;
        Ok(Drawn {
            time,
            color: bframes.color(),
            depth: FrameDepth::Buffer(textures.0.depth),
            decisions: Some(bframes.decisions()),
        })
    }
}
