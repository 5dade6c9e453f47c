//! One measured configuration as the report shows it: its speed-up
//! against the reference of its own run, its error, its fixed costs and
//! bounds, and why its misses missed.

use super::config::{pass_medians, probed, speedup, Config, Probe, ProbeOf};
use crate::diagnostic::Error;
use crate::measure::fail;
use crate::measure::metrics::{self, Decisions, FrameError};
use crate::report::{FrameStats, MissCause, NodeReport, Picture, ResultRow};
use crate::runtime::{self, FrameInputs, Gpu, Runner};
use crate::scene::{self, Scene};

/// What every configuration's row is measured against: the reference's
/// frame times and median, the fixed-cost probes, the frame's pixels.
pub(super) struct Baseline<'a> {
    pub reference_times: &'a [f64],
    pub reference_ms: f64,
    pub probes: &'a [Probe],
    pub pixels: u32,
}

/// One configuration's row of the report, from its measured frames, and
/// its last frame's pictures.
pub(super) fn result_row(
    config: Config,
    node: &NodeReport,
    baseline: &Baseline,
) -> (ResultRow, Picture) {
    let time_ms = metrics::median(&config.times);
    let column = |f: fn(&Decisions) -> f64| {
        metrics::mean(&config.decisions.iter().map(f).collect::<Vec<_>>())
    };
    let error =
        |f: fn(&FrameError) -> f64| metrics::mean(&config.errors.iter().map(f).collect::<Vec<_>>());
    let hit_rate = column(|d| d.hit);
    let f = node.p_over_t;
    let ideal = 1.0 / (1.0 - hit_rate * f).max(1e-6);
    // The most the variant could reach were its payload and shade
    // free: its passes' fixed costs alone.
    // (Without GPU timestamps there are no pass times: the frame's.)
    let (fixed_frame_ms, fixed_passes) = probed(
        baseline.probes,
        ProbeOf::Variant(config.node, config.variant),
    )
    .unwrap_or_default();
    let fixed_ms = if fixed_passes.is_empty() {
        fixed_frame_ms
    } else {
        fixed_passes.iter().map(|p| p.time_ms).sum()
    };
    let bound = speedup(baseline.reference_ms, fixed_ms);
    let measured_speedup = speedup(baseline.reference_ms, time_ms);
    let passes = pass_medians(&config.passes);
    let row = ResultRow {
        node: node.id.clone(),
        node_text: node.text.clone(),
        variant: config.variant,
        refresh_period: config.setting.refresh_period,
        refresh_quad: config.setting.refresh_quad,
        reconstruction: config.setting.reconstruction,
        adaptive: config.setting.adaptive,
        // Set with the run's knobs when the report is made.
        upsampling: None,
        cache_format: config.setting.cache_format,
        depth_epsilon: config.setting.depth_epsilon,
        time_ms,
        passes,
        speedup: measured_speedup,
        speedup_ci: metrics::speedup_interval(baseline.reference_times, &config.times),
        psnr: error(|e| e.psnr),
        psnr_frame: error(|e| e.psnr_frame),
        worst_psnr: config
            .errors
            .iter()
            .map(|e| e.psnr)
            .fold(metrics::PSNR_CAP, f64::min),
        flicker: metrics::mean(&config.flicker),
        ssim: error(|e| e.ssim),
        max_abs_error: config
            .errors
            .iter()
            .map(|e| e.max_abs_error)
            .fold(0.0, f64::max),
        above_threshold: error(|e| e.above_threshold),
        coverage: metrics::mean(
            &config
                .decisions
                .iter()
                .map(|d| d.covered as f64 / baseline.pixels.max(1) as f64)
                .collect::<Vec<_>>(),
        ),
        hit_rate,
        miss_rate: column(Decisions::miss),
        offscreen_rate: column(|d| d.offscreen),
        disocclusion_rate: column(|d| d.disoccluded),
        invalid_rate: column(|d| d.invalid),
        refresh_rate: column(|d| d.refresh),
        max_age: config.ages.len().saturating_sub(1) as u32,
        age_histogram: config.ages.clone(),
        p_over_t: node.p_over_t,
        ideal_speedup: ideal,
        fixed_cost_ms: fixed_passes,
        bound_with_fixed_costs: bound,
        share_of_ideal: measured_speedup / ideal,
        pareto_psnr: false,
        pareto_ssim: false,
        frame_stats: frame_stats(&config),
    };
    let (color, classes) = config.last;
    (row, (metrics::rgba8(&color), classes))
}

/// Each measured frame of `config`: its time, error, flicker (against
/// the frame before) and decisions.
fn frame_stats(config: &Config) -> Vec<FrameStats> {
    config
        .times
        .iter()
        .zip(&config.errors)
        .zip(&config.decisions)
        .enumerate()
        .map(|(frame, ((&time_ms, e), d))| FrameStats {
            time_ms,
            psnr: e.psnr,
            psnr_frame: e.psnr_frame,
            flicker: frame
                .checked_sub(1)
                .and_then(|i| config.flicker.get(i).copied())
                .unwrap_or(0.0),
            ssim: e.ssim,
            max_abs_error: e.max_abs_error,
            hit_rate: d.hit,
            miss_rate: d.miss(),
            refresh_rate: d.refresh,
        })
        .collect()
}

/// The misses each declared effect causes alone: a run from `runner` per
/// moving effect, the scene with only that effect, its decisions averaged
/// over the measured frames (disocclusion is what the others cause).
pub(super) fn miss_causes(
    gpu: &Gpu,
    runner: &dyn Fn() -> Result<Runner, String>,
    scene: &Scene,
    inputs_of: &dyn Fn(&Scene, u32) -> Result<FrameInputs, Error>,
    warmup: u32,
    frames: u32,
) -> Result<Vec<MissCause>, Error> {
    let mut causes = Vec::new();
    let moving = scene
        .effects
        .iter()
        .filter(|e| !matches!(e, scene::Effect::Disocclusion));
    for &effect in moving {
        let alone = Scene {
            effects: vec![effect],
            ..scene.clone()
        };
        let mut runner = runner().map_err(fail)?;
        let mut decisions = Vec::new();
        for frame in 0..warmup + frames {
            runner
                .frame(gpu, &inputs_of(&alone, frame)?, None)
                .map_err(fail)?;
            if frame >= warmup {
                let classes = runtime::read_texture(gpu, runner.classes(), 4).map_err(fail)?;
                decisions.push(metrics::decisions(&classes));
            }
        }
        let column =
            |f: fn(&Decisions) -> f64| metrics::mean(&decisions.iter().map(f).collect::<Vec<_>>());
        causes.push(MissCause {
            effect,
            miss_rate: column(Decisions::miss),
            offscreen_rate: column(|d| d.offscreen),
            disocclusion_rate: column(|d| d.disoccluded),
        });
    }
    Ok(causes)
}
