//! The interleaved measured run: every frame, the unmodified shader and
//! then everything measured against it, each drawn and timed in turn, so
//! that what the machine does meanwhile (another tenant, a clock change)
//! falls on all of them alike.
//!
//! What is drawn is a [`Measured`]: a runner, when it starts, and what it
//! keeps of each measured frame. The reference is drawn first each frame
//! and read back, so that what follows is compared with the same frame
//! ([`Sample::reference`]). The profiler's payload passes, fixed-cost
//! probes and configurations are `Measured`; another stage (whole-frame
//! reuse) can add its own.

use crate::diagnostic::Error;
use crate::measure::clock::{read_linear, timed, Clock, Timed};
use crate::runtime::{FrameInputs, Gpu, Runner};

use super::{fail, Progress};
use crate::measure::metrics::LinearFrame;

/// One measured frame of one [`Measured`], as [`Measured::record`] gets it.
pub(super) struct Sample<'a> {
    pub gpu: &'a Gpu,
    /// The frame's time (ms): its passes' span, from GPU timestamps.
    pub time: f64,
    /// Each pass's time (ms), by name.
    pub passes: Vec<(String, f64)>,
    /// The reference's picture of this frame and of the frame before.
    pub reference: &'a ReferenceRun,
}

/// What the measured run draws besides the reference.
pub(super) trait Measured {
    /// The progress label, also the timer scope's.
    fn label(&self) -> &str;
    /// The runner it draws this frame.
    fn runner(&mut self) -> &mut Runner;
    /// Draws its frame of `inputs` and times it, as `label`: its
    /// runner's frame, unless it draws more (the governed way's watched
    /// frames draw the original and a comparison as well).
    fn frame(
        &mut self,
        clock: &mut Clock,
        inputs: &FrameInputs,
        label: &str,
    ) -> Result<Timed, String> {
        timed(clock, self.runner(), inputs, label)
    }
    /// The first frame it is drawn at: 0, or later for what has no cache
    /// to warm.
    fn first_frame(&self, _warmup: u32) -> u32 {
        0
    }
    /// Whether its last frame's GPU scopes go into the report's trace.
    fn traced(&self) -> bool {
        true
    }
    /// Keeps what it needs of a measured frame.
    fn record(&mut self, sample: Sample) -> Result<(), String>;
}

/// The reference's side of the run: its frame times and pictures.
#[derive(Default)]
pub(super) struct ReferenceRun {
    pub times: Vec<f64>,
    /// This measured frame's picture, in linear float.
    pub now: LinearFrame,
    /// The measured frame before's (empty on the first).
    pub before: LinearFrame,
    /// What every measured frame shows, for the reference check.
    pub stats: super::reference_check::ReferenceStats,
}

/// A runner drawn every frame and timed, nothing else kept: a node's
/// payload over every pixel (for its P/T), `play`'s fixed cache.
pub(super) struct TimedRun {
    pub label: &'static str,
    pub runner: Runner,
    pub times: Vec<f64>,
}

impl Measured for TimedRun {
    fn label(&self) -> &str {
        self.label
    }
    fn runner(&mut self) -> &mut Runner {
        &mut self.runner
    }
    fn record(&mut self, sample: Sample) -> Result<(), String> {
        self.times.push(sample.time);
        Ok(())
    }
}

/// Runs `warmup + frames` frames of `reference` and then each of
/// `measured` in turn, with `inputs_of(frame)`; the last `frames` are
/// measured. Returns the GPU scopes of the last frame (of the reference
/// and what is traced).
pub(super) fn measured_run(
    clock: &mut Clock,
    (reference, run): (&mut Runner, &mut ReferenceRun),
    measured: &mut [&mut dyn Measured],
    inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
    (warmup, frames): (u32, u32),
    progress: &mut dyn Progress,
) -> Result<Vec<wgpu_profiler::GpuTimerQueryResult>, Error> {
    let total = u64::from(warmup + frames)
        + measured
            .iter()
            .map(|m| u64::from(warmup + frames - m.first_frame(warmup).min(warmup + frames)))
            .sum::<u64>();
    progress.start(total);
    let mut trace = Vec::new();
    for frame in 0..warmup + frames {
        let is_measured = frame >= warmup;
        let last = frame + 1 == warmup + frames;
        let inputs = inputs_of(frame)?;

        let (time, _, raw) = timed(clock, reference, &inputs, "reference").map_err(fail)?;
        if last {
            trace.extend(raw);
        }
        progress.step("reference");
        if is_measured {
            run.times.push(time);
            let color = reference
                .color()
                .ok_or_else(|| fail("the reference draws no colour".into()))?;
            let now = read_linear(clock.gpu, color).map_err(fail)?;
            run.before = std::mem::replace(&mut run.now, now);
            let depth = crate::runtime::read_depth(clock.gpu, reference.depth()).map_err(fail)?;
            let clear = &reference.plan().clear;
            run.stats.add(&run.now, &depth, (clear.color, clear.depth));
        }
        for item in measured.iter_mut() {
            if frame < item.first_frame(warmup) {
                continue;
            }
            let label = item.label().to_string();
            let (time, passes, raw) = item.frame(clock, &inputs, &label).map_err(fail)?;
            if last && item.traced() {
                trace.extend(raw);
            }
            progress.step(&label);
            if is_measured {
                item.record(Sample {
                    gpu: clock.gpu,
                    time,
                    passes,
                    reference: run,
                })
                .map_err(fail)?;
            }
        }
    }
    Ok(trace)
}
