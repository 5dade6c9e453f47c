//! Timing and reading back one frame: the clock every measured run
//! (the profiler's, whole-frame reuse's) times its frames with, and the
//! read-back of a measured colour target in linear float.

use super::metrics::{self, LinearFrame};
use crate::runtime::{FrameInputs, Gpu, Runner};

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
        super::watch::tell(super::watch::Step::Opened(&gpu.adapter));
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
    // What a supervisor reports should the driver die in this frame: the
    // runner and the passes it submits together (made only when watched:
    // this runs every frame).
    let what = if super::watch::watching() {
        let passes: Vec<&str> = runner
            .plan()
            .passes
            .iter()
            .map(|pass| pass.name.as_str())
            .collect();
        format!("{label} (its passes {})", passes.join(", "))
    } else {
        String::new()
    };
    timed_as(clock, label, &what, |profiler| {
        runner.frame(gpu, inputs, profiler)
    })
}

/// Times what `record` submits, as [`timed`] times a runner's frame:
/// `record` gets the profiler and the label to scope its passes with
/// (`<label>/<pass>`) when the device has timestamp queries.
pub(crate) fn timed_recording(
    clock: &mut Clock,
    label: &str,
    record: impl FnOnce(Option<(&mut wgpu_profiler::GpuProfiler, &str)>) -> Result<(), String>,
) -> Result<Timed, String> {
    timed_as(clock, label, label, record)
}

/// [`timed_recording`], telling the watch it draws `what`.
fn timed_as(
    clock: &mut Clock,
    label: &str,
    what: &str,
    record: impl FnOnce(Option<(&mut wgpu_profiler::GpuProfiler, &str)>) -> Result<(), String>,
) -> Result<Timed, String> {
    let (gpu, profiler, timestamps) = (clock.gpu, &mut clock.profiler, clock.timestamps);
    super::watch::tell(super::watch::Step::Drawing(what));
    let start = std::time::Instant::now();
    record(timestamps.then_some((&mut *profiler, label)))?;
    if timestamps {
        profiler.end_frame().map_err(|err| err.to_string())?;
    }
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|err| err.to_string())?;
    gpu.fault()
        .map_err(|fault| format!("while drawing {label}: {fault}"))?;
    super::watch::tell(super::watch::Step::Idle);
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
