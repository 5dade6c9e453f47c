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
use crate::runtime::{FrameInputs, Gpu, Runner};

use super::metrics::{self, LinearFrame};
use super::{fail, Progress};

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
    fn runner(&mut self) -> &mut Runner;
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

/// A node's payload over every pixel, for its P/T.
pub(super) struct PayloadRun {
    pub runner: Runner,
    pub times: Vec<f64>,
}

impl Measured for PayloadRun {
    fn label(&self) -> &str {
        "payload"
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
            let (time, passes, raw) = timed(clock, item.runner(), &inputs, &label).map_err(fail)?;
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

/// Reads a colour target (rgba16float) back in linear float.
pub(crate) fn read_linear(gpu: &Gpu, texture: &wgpu::Texture) -> Result<LinearFrame, String> {
    Ok(metrics::linear_from_f16(&crate::runtime::read_texture(
        gpu, texture, 8,
    )?))
}

/// What times a frame.
pub(crate) struct Clock<'a> {
    pub gpu: &'a Gpu,
    pub profiler: wgpu_profiler::GpuProfiler,
    /// Whether the device has timestamp queries (else frames are timed on
    /// the CPU, submission to completion).
    pub timestamps: bool,
}

impl<'a> Clock<'a> {
    pub fn new(gpu: &'a Gpu) -> Result<Clock<'a>, crate::diagnostic::Error> {
        let timestamps = gpu
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY);
        let profiler = wgpu_profiler::GpuProfiler::new(
            &gpu.device,
            wgpu_profiler::GpuProfilerSettings::default(),
        )
        .map_err(|err| super::fail(format!("cannot start the GPU profiler: {err}")))?;
        Ok(Clock {
            gpu,
            profiler,
            timestamps,
        })
    }
}

/// A frame's time, each pass's (ms), and the profiler's raw scopes.
pub(crate) type Timed = (
    f64,
    Vec<(String, f64)>,
    Vec<wgpu_profiler::GpuTimerQueryResult>,
);

/// Renders one frame of `runner` and returns its time and each pass's, in
/// ms: from GPU timestamps when the device has them, else from submission
/// to completion on the CPU.
pub(crate) fn timed(
    clock: &mut Clock,
    runner: &mut Runner,
    inputs: &FrameInputs,
    label: &str,
) -> Result<Timed, String> {
    let gpu = clock.gpu;
    timed_recording(clock, label, |profiler| runner.frame(gpu, inputs, profiler))
}

/// Times what `record` submits, as [`timed`] times a runner's frame:
/// `record` gets the profiler and the label to scope its passes with
/// (`<label>/<pass>`) when the device has timestamp queries.
pub(crate) fn timed_recording(
    clock: &mut Clock,
    label: &str,
    record: impl FnOnce(Option<(&mut wgpu_profiler::GpuProfiler, &str)>) -> Result<(), String>,
) -> Result<Timed, String> {
    let (gpu, profiler, timestamps) = (clock.gpu, &mut clock.profiler, clock.timestamps);
    let start = std::time::Instant::now();
    record(timestamps.then_some((&mut *profiler, label)))?;
    if timestamps {
        profiler.end_frame().map_err(|err| err.to_string())?;
    }
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|err| err.to_string())?;
    let wall = start.elapsed().as_secs_f64() * 1e3;
    if !timestamps {
        return Ok((wall, Vec::new(), Vec::new()));
    }
    let results = profiler
        .process_finished_frame(gpu.queue.get_timestamp_period())
        .unwrap_or_default();
    // The frame's time runs from the first pass's start timestamp to the
    // last one's end: what runs between passes (barriers, layout changes,
    // the hand-over from one pass to the next) is part of it.
    let mut passes = Vec::new();
    let mut span: Option<(f64, f64)> = None;
    for result in &results {
        if let Some(range) = &result.time {
            let name = result
                .label
                .rsplit('/')
                .next()
                .unwrap_or_default()
                .to_string();
            // The classification is a diagnostic, not part of the frame.
            if name != "classify" {
                passes.push((name, (range.end - range.start) * 1e3));
                span = Some(match span {
                    None => (range.start, range.end),
                    Some((start, end)) => (start.min(range.start), end.max(range.end)),
                });
            }
        }
    }
    let total = span.map_or(0.0, |(start, end)| (end - start) * 1e3);
    Ok((total, passes, results))
}
