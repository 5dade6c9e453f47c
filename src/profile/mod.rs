//! plans + scene → runs: measuring variants against the unmodified shader.
//!
//! [`profile`] renders the scene with the reference (the original shader)
//! and with every requested node × variant × Δn × k, frame after frame,
//! **interleaved** — each frame renders every configuration in turn — so
//! machine drift hits all alike. Each pass is timed with GPU timestamp
//! queries (wgpu-profiler); a frame's time spans its passes, and a
//! configuration's time is the median over the measured frames (after the
//! warm-up), with a bootstrap interval over the frames. After the warm-up every frame is read back and compared with
//! the reference frame of the same index (PSNR, SSIM, largest error, share
//! of pixels above a threshold), and the classification pass counts hits,
//! misses (off-screen, disoccluded) and refreshes.
//!
//! P/T is measured too: the payload pass of three-pass, drawn over every
//! pixel, times the node's slice alone; over the reference time it is f,
//! and with ρ the measured reuse fraction the ideal speed-up is
//! 1 / (1 − ρ·f) (ours: Amdahl's law for the reused share of the payload;
//! seed 002 gives no formula, its §4.1 sorts nodes by measured P/T), which
//! every result is compared with.
//!
//! The stages, in order: the scene's inputs (`inputs`: textures,
//! meshes, each frame's buffers); the configurations the [`grid`] keeps,
//! each a runner; the interleaved measured run (`run`: anything
//! `run::Measured` is drawn after the reference every frame); each
//! configuration's row (`result_row`); the misses each effect causes alone
//! (`miss_causes`); and the answer, its winner measured again (`confirm`).

#![warn(missing_docs)]

pub(crate) mod bench;
mod choice;
mod config;
pub mod grid;
pub mod merge;
pub mod play;
pub(crate) mod reference_check;
mod row;
pub(crate) mod run;
pub(crate) mod setup;

use std::collections::HashMap;
use std::path::Path;

use crate::analysis::{self, Candidate};
use crate::back::{self, Language};
use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;
use crate::measure::clock::{timed, Clock};
use crate::measure::inputs::SceneInputs;
use crate::measure::metrics;
use crate::measure::{fail, open_gpu};
use crate::plan::Plan;
use crate::report::{
    Confirmation, Device, GridReport, MissCause, NodeReport, Reference, ReferenceCheck, Report,
    ResultRow,
};
use crate::rewrite::{self, CacheFormat, CacheRead, Options as RewriteOptions, Upsampler, Variant};
use crate::runtime::{FrameInputs, Runner};
use crate::scene::{self, Scene};
use config::{probed, speedup, Config, Probe, ProbeOf};
use grid::{shard_nodes, variant_settings, Axes, Design, Setting};
use row::{miss_causes, result_row, Baseline};
use run::{measured_run, Measured, ReferenceRun, TimedRun};

pub use crate::measure::{Progress, Quiet, MEASURED_COLOR_FORMAT};

pub use crate::analysis::Nodes;
pub use crate::report::Budget;

/// What to measure.
#[derive(Clone, Debug)]
pub struct Options {
    /// Which nodes to measure.
    pub nodes: Nodes,
    /// Which variants to measure.
    pub variants: Vec<Variant>,
    /// The values of each knob to measure: Δn, k, reconstruction, cache
    /// format, depth ε.
    pub refresh_periods: Vec<u32>,
    /// The k values (refresh blocks of k×k pixels) to measure.
    pub refresh_quads: Vec<u32>,
    /// The cache variants' reads of their cache to measure.
    pub reconstructions: Vec<CacheRead>,
    /// The upsamplers lowres is measured with (its Δn and k are its
    /// factor: s² and s); spatio-temporal by default, all five in a sweep.
    pub lowres_reconstructions: Vec<Upsampler>,
    /// Lowres's factor and knobs.
    pub upsampling: crate::rewrite::Upsampling,
    /// Adaptive refresh to measure, for every variant: off, on, or both (a
    /// sweep measures both). Lowres re-shades its unreliable pixels; the
    /// cache variants refresh a changed value after Δn/4 frames.
    pub adaptive_refresh: Vec<bool>,
    /// The cache formats to measure.
    pub cache_formats: Vec<CacheFormat>,
    /// The depth tolerances ε to measure.
    pub depth_epsilons: Vec<f32>,
    /// Measure their full product, or prune it as a sweep does (see
    /// [`grid`]).
    pub design: Design,
    /// Pick the fastest configuration within this error budget.
    pub max_error: Option<Budget>,
    /// Frames measured; `None` takes the scene's.
    pub frames: Option<u32>,
    /// Warm-up frames, rendered and not measured. `None` takes the scene's,
    /// extended to the longest refresh period measured, so that every
    /// measured frame is in the cache's steady state: each pixel has been
    /// recomputed at least once, and a reused value is between 0 and Δn − 1
    /// frames old, as it stays. (A shorter warm-up measures a younger
    /// cache: on the marble sphere with Δn = 64, 31.8 dB over frames 8–40
    /// against 23.9 dB from frame 160 on.)
    pub warmup: Option<u32>,
    /// Frame size; `None` takes the scene's.
    pub size: Option<[u32; 2]>,
    /// A pixel counts as wrong when a channel differs by more than this
    /// (in [0, 1]).
    pub error_threshold: f64,
    /// The command line, recorded in the report.
    pub command: String,
    /// The fragment entry point, when the shader has several.
    pub entry: Option<String>,
    /// The vertex entry point that draws with it; `None` infers it.
    pub vertex_entry: Option<String>,
    /// Measure only this slice of the grid (`--shard K/N`), for a sweep
    /// spread over machines and joined by [`merge`].
    pub shard: Option<crate::report::Shard>,
}

impl Options {
    /// The sweep of `profile --sweep`: every knob over [`Axes::sweep`],
    /// pruned (see [`grid`]).
    pub fn sweep(self) -> Self {
        let axes = Axes::sweep();
        Options {
            refresh_periods: axes.refresh_periods,
            refresh_quads: axes.refresh_quads,
            reconstructions: CacheRead::ALL.to_vec(),
            cache_formats: axes.cache_formats,
            depth_epsilons: axes.depth_epsilons,
            adaptive_refresh: vec![false, true],
            lowres_reconstructions: Upsampler::ALL.to_vec(),
            design: Design::Planes,
            ..self
        }
    }

    fn axes(&self) -> Axes {
        Axes {
            refresh_periods: self.refresh_periods.clone(),
            refresh_quads: self.refresh_quads.clone(),
            reconstructions: self.reconstructions.iter().map(|&r| r.into()).collect(),
            cache_formats: self.cache_formats.clone(),
            depth_epsilons: self.depth_epsilons.clone(),
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            nodes: Nodes::Top(3),
            variants: Variant::ALL.to_vec(),
            refresh_periods: vec![32],
            refresh_quads: vec![4],
            reconstructions: vec![CacheRead::Bilinear],
            lowres_reconstructions: vec![Upsampler::SpatioTemporal],
            adaptive_refresh: vec![false],
            upsampling: crate::rewrite::DEFAULT_UPSAMPLING,
            cache_formats: vec![CacheFormat::Rgba16float],
            depth_epsilons: vec![RewriteOptions::default().depth_epsilon],
            design: Design::Full,
            max_error: None,
            frames: None,
            warmup: None,
            size: None,
            error_threshold: 0.05,
            command: String::new(),
            entry: None,
            vertex_entry: None,
            shard: None,
        }
    }
}

pub use crate::report::{Picture, Pictures};

/// Profiles `shader` on `scene`. `scene_path` names the scene file (its
/// folder resolves relative files).
pub fn profile(
    shader: &Shader,
    scene: &Scene,
    scene_path: &Path,
    options: &Options,
    progress: &mut dyn Progress,
) -> Result<(Report, Pictures), Error> {
    refuse_fragment_only(shader)?;
    let prepared = setup::prepare(shader, scene, options)?;
    rewrite::check_entry_point(shader, &prepared.analysis)?;
    let lowres = (
        options.lowres_reconstructions.as_slice(),
        options.adaptive_refresh.as_slice(),
    );
    let Share {
        nodes,
        takes,
        grid_nodes,
    } = sharded(&prepared, options)?;
    let (size, warmup, frames) = (prepared.size, prepared.warmup, prepared.frames);
    let reference_plan =
        rewrite::plan::reference(shader, &prepared.analysis, &prepared.base).map_err(fail)?;
    let scene_inputs = scene_inputs((shader, scene, scene_path), &prepared, &reference_plan)?;
    let inputs_of = |scene: &Scene, frame: u32| scene_inputs.frame(scene, frame);

    let gpu = open_gpu()?;
    let mut clock = Clock::new(&gpu)?;
    let bench = crate::measure::bench::Bench {
        gpu: &gpu,
        inputs: &scene_inputs,
        size,
        cull_back_faces: scene.cull_back_faces,
    };
    let mut reference = crate::measure::bench::reference(&bench, shader, &reference_plan)?;
    let (mut payloads, mut probes) =
        bench::fixed_cost_runs(&bench, shader, &prepared, &nodes, &options.variants)?;
    let mut configs = configurations(
        (shader, &prepared.analysis),
        (&nodes, &takes),
        (&options.variants, lowres),
        &prepared.base,
        &|plan, sources| bench.runner(plan, sources, true),
        (size, options.error_threshold),
        progress,
    )?;

    let mut reference_run = ReferenceRun::default();
    let mut measured: Vec<&mut dyn Measured> = Vec::new();
    measured.extend(payloads.iter_mut().map(|p| p as &mut dyn Measured));
    measured.extend(probes.iter_mut().map(|p| p as &mut dyn Measured));
    measured.extend(configs.iter_mut().map(|c| c as &mut dyn Measured));
    let trace = measured_run(
        &mut clock,
        (&mut reference, &mut reference_run),
        &mut measured,
        &|frame| inputs_of(scene, frame),
        (warmup, frames),
        progress,
    )?;
    drop(measured);
    progress.finish();

    let reference_ms = metrics::median(&reference_run.times);
    let node_reports = node_reports(shader, &nodes, (&payloads, &probes), reference_ms);
    let baseline = Baseline {
        reference_times: &reference_run.times,
        reference_ms,
        probes: &probes,
        pixels: size[0] * size[1],
    };
    let (results, pictures) = rows(configs, &node_reports, &baseline);

    // What causes the misses: the best configuration again, with one
    // declared effect at a time.
    let miss_causes = match results.first() {
        Some(best) => best_miss_causes(&bench, &prepared, (shader, scene), best)?,
        None => Vec::new(),
    };
    let run = RunContext {
        shader,
        scene: (scene, scene_path),
        options,
        prepared: &prepared,
        clock: &clock,
        reference_times: &reference_run.times,
        probes: &probes,
    };
    let report = run.report(Findings {
        warnings: view_warnings(scene, prepared.aspect, warmup, &results),
        reference_check: reference_run.stats.check(scene, &scene_inputs.defaulted),
        defaulted: scene_inputs.defaulted.clone(),
        nodes: node_reports,
        results,
        miss_causes,
        grid_nodes,
    });

    // The answer, and its winner measured again before it is given.
    let winner = Winner {
        shader,
        prepared: &prepared,
        bench: &bench,
        scene,
    };
    let (choice, chosen) = winner.choose(&report, options, &mut clock, &mut reference, progress)?;
    let report = Report {
        choice: Some(choice),
        ..report
    };
    let reference = metrics::rgba8(&reference_run.now);
    Ok((
        report,
        Pictures {
            reference,
            results: pictures,
            trace,
            chosen,
        },
    ))
}

/// The scene's inputs for a run of `shader` on `scene` (its textures,
/// meshes and each frame's buffers, for the reference's layout), once the
/// scene is checked to provide everything else the shader binds.
fn scene_inputs<'a>(
    (shader, scene, scene_path): (&Shader, &Scene, &Path),
    prepared: &'a setup::Prepared,
    reference_plan: &'a Plan,
) -> Result<SceneInputs<'a>, Error> {
    scene::storage::check(&prepared.storage, scene)?;
    crate::measure::setup::check_instancing(shader, scene, &reference_plan.vertex_layout)?;
    SceneInputs::new(
        shader,
        scene,
        scene_path,
        reference_plan,
        &prepared.used,
        (&prepared.uniforms, &prepared.storage),
        prepared.size,
    )
}

/// What this run of the grid measures.
struct Share<'p> {
    /// The grid's nodes this run measures (a shard's, or all).
    nodes: Vec<GridNode<'p>>,
    /// Which of each node's configurations ([`shard_nodes`]).
    takes: Vec<std::ops::Range<usize>>,
    /// With a shard, every node of the grid (the report's `grid_nodes`,
    /// for the merge).
    grid_nodes: Vec<String>,
}

/// The share of the grid this run measures: a shard's, or all of it.
fn sharded<'p>(prepared: &'p setup::Prepared, options: &Options) -> Result<Share<'p>, Error> {
    let all_nodes = prepared.nodes();
    let lowres = (
        options.lowres_reconstructions.as_slice(),
        options.adaptive_refresh.as_slice(),
    );
    let grid_nodes: Vec<String> = match options.shard {
        Some(_) => all_nodes.iter().map(|(c, _)| c.node.id.clone()).collect(),
        None => Vec::new(),
    };
    let configurations_of = |(_, settings): &GridNode| {
        let of_variant = |&v: &Variant| variant_settings(settings, v, &prepared.base, lowres).len();
        options.variants.iter().map(of_variant).sum()
    };
    let (nodes, takes, total) = shard_nodes(all_nodes, configurations_of, options.shard);
    // More shards than configurations leave some with nothing: that is
    // an error for every shard of such a sweep, not only the empty ones,
    // so that no CI job of it measures a slice that merges into nothing.
    if let Some(shard) = options.shard.filter(|s| s.count as usize > total) {
        return Err(Error::plain(Diagnostic::error(format!(
            "shard {shard}: the grid has {total} configuration{}, fewer than the {} shards, so some would measure nothing; use at most {total}",
            if total == 1 { "" } else { "s" },
            shard.count
        ))));
    }
    Ok(Share {
        nodes,
        takes,
        grid_nodes,
    })
}

/// Each measured node as the report says it: its payload's time and
/// fixed cost against the reference's `reference_ms`.
fn node_reports(
    shader: &Shader,
    nodes: &[GridNode],
    (payloads, probes): (&[TimedRun], &[Probe]),
    reference_ms: f64,
) -> Vec<NodeReport> {
    nodes
        .iter()
        .zip(payloads)
        .enumerate()
        .map(|(node, ((candidate, _), payload))| {
            let payload_ms = metrics::median(&payload.times);
            let fixed_ms = probed(probes, ProbeOf::Payload(node)).map_or(0.0, |(ms, _)| ms);
            node_report(shader, candidate, payload_ms, fixed_ms, reference_ms)
        })
        .collect()
}

/// The misses each declared effect causes alone, with the `best`
/// configuration drawn again.
fn best_miss_causes(
    bench: &crate::measure::bench::Bench,
    prepared: &setup::Prepared,
    (shader, scene): (&Shader, &Scene),
    best: &ResultRow,
) -> Result<Vec<MissCause>, Error> {
    let rewritten = rewrite_of(shader, &prepared.analysis, best, &prepared.defaults)?;
    let sources = sources_of(&rewritten)?;
    let runner = || bench.runner(&rewritten.plan, &sources, true);
    let inputs_of = |scene: &Scene, frame: u32| bench.inputs.frame(scene, frame);
    miss_causes(
        bench.gpu,
        &runner,
        scene,
        &inputs_of,
        prepared.warmup,
        prepared.frames,
    )
}

/// A fragment-only module cannot be drawn by itself.
fn refuse_fragment_only(shader: &Shader) -> Result<(), Error> {
    if !crate::rewrite::vertex::is_fragment_only(&shader.module) {
        return Ok(());
    }
    Err(Error::in_file(
        shader.file.clone(),
        Diagnostic::error(format!(
            "`{}` has no vertex stage, and drawing it needs one: give the module that has it with --vertex FILE",
            shader.file.path
        ))
        .with_label(0..0, "a fragment-only module")
        .with_note("`rewrite` emits its fragment passes without one; plan.json's `host_vertex` says what the host's vertex stage must output"),
    ))
}

/// Every configuration's row, fastest first, the Pareto fronts marked;
/// and each one's pictures.
fn rows(
    configs: Vec<Config>,
    node_reports: &[NodeReport],
    baseline: &Baseline,
) -> (Vec<ResultRow>, Vec<Picture>) {
    let mut rows: Vec<(ResultRow, Picture)> = configs
        .into_iter()
        .map(|config| {
            let node = &node_reports[config.node];
            result_row(config, node, baseline)
        })
        .collect();
    rows.sort_by(|a, b| b.0.speedup.total_cmp(&a.0.speedup));
    let (mut results, pictures): (Vec<_>, Vec<_>) = rows.into_iter().unzip();
    choice::mark_pareto_fronts(&mut results);
    (results, pictures)
}

/// What a profile ran with: the shader, the scene and its file, the
/// options, the plan of work, the clock, the reference's frame times and
/// the fixed-cost probes.
struct RunContext<'a> {
    shader: &'a Shader,
    scene: (&'a Scene, &'a Path),
    options: &'a Options,
    prepared: &'a setup::Prepared,
    clock: &'a Clock<'a>,
    reference_times: &'a [f64],
    probes: &'a [Probe],
}

/// What the run found: per node, per configuration, the miss causes, and
/// what the report warns of and lists as defaulted.
struct Findings {
    nodes: Vec<NodeReport>,
    results: Vec<ResultRow>,
    miss_causes: Vec<MissCause>,
    warnings: Vec<String>,
    defaulted: Vec<String>,
    reference_check: ReferenceCheck,
    /// A shard's: every node of the grid, its own or not.
    grid_nodes: Vec<String>,
}

impl RunContext<'_> {
    /// The report, before the choice.
    fn report(&self, findings: Findings) -> Report {
        let (scene, scene_path) = self.scene;
        let prepared = self.prepared;
        let adapter = &self.clock.gpu.adapter;
        let grid = &prepared.grid;
        let reference_times = self.reference_times;
        let upsampling = self
            .options
            .variants
            .iter()
            .any(|v| v.upsamples())
            .then(|| prepared.defaults.upsampling.clone());
        let mut results = findings.results;
        for row in results.iter_mut().filter(|r| r.variant.upsamples()) {
            row.upsampling = upsampling.clone();
        }
        Report {
            format: crate::report::FORMAT,
            shader: self.shader.file.path.clone(),
            entry: prepared.analysis.entry.clone(),
            scene: scene_path.display().to_string(),
            scene_description: scene.description.clone(),
            defaulted: findings.defaulted,
            effects: scene.effects.clone(),
            size: prepared.size,
            frames: prepared.frames,
            warmup: prepared.warmup,
            steady_state: prepared.steady_state,
            device: Device {
                name: adapter.name.clone(),
                backend: format!("{:?}", adapter.backend),
                driver: crate::runtime::driver_line(adapter),
            },
            timing: if self.clock.timestamps {
                "gpu-timestamps"
            } else {
                "cpu-wall-clock"
            }
            .into(),
            command: self.options.command.clone(),
            reference: Reference {
                time_ms: metrics::median(reference_times),
                spread_ms: [
                    metrics::quantile(reference_times, 0.1),
                    metrics::quantile(reference_times, 0.9),
                ],
                fixed_ms: probed(self.probes, ProbeOf::Reference).map_or(0.0, |(ms, _)| ms),
                frame_ms: reference_times.to_vec(),
            },
            nodes: findings.nodes,
            grid: Some(GridReport {
                design: grid.design,
                base: prepared.base_setting,
                axes: grid.axes.clone(),
                full: grid.full,
                measured: results.len(),
                pruned: grid.pruned.clone(),
            }),
            results,
            warnings: findings.warnings,
            miss_causes: findings.miss_causes,
            reference_check: Some(findings.reference_check),
            choice: None,
            upsampling,
            shard: self.options.shard,
            grid_nodes: findings.grid_nodes,
            merged_from: Vec::new(),
        }
    }
}

/// Choosing the answer from a report, and measuring its winner again.
struct Winner<'a> {
    shader: &'a Shader,
    prepared: &'a setup::Prepared,
    bench: &'a crate::measure::bench::Bench<'a>,
    scene: &'a Scene,
}

impl Winner<'_> {
    /// The choice within the budget, confirmed by a run of the original
    /// and the winner of their own; and the winner's rewrite, which is
    /// what was measured, when the confirmation keeps it.
    fn choose(
        &self,
        report: &Report,
        options: &Options,
        clock: &mut Clock,
        reference: &mut Runner,
        progress: &mut dyn Progress,
    ) -> Result<(crate::report::Choice, Option<rewrite::Rewritten>), Error> {
        let budget = options.max_error.unwrap_or(Budget::DEFAULT);
        let mut choice = report.choose(budget, options.max_error.is_some());
        let Some(winner) = choice.result else {
            return Ok((choice, None));
        };
        let (analysis, defaults) = (&self.prepared.analysis, &self.prepared.defaults);
        let rewritten = rewrite_of(self.shader, analysis, &report.results[winner], defaults)?;
        let sources = sources_of(&rewritten)?;
        let mut runner = self
            .bench
            .runner(&rewritten.plan, &sources, false)
            .map_err(fail)?;
        let (warmup, frames) = (self.prepared.warmup, self.prepared.frames);
        progress.start(u64::from(warmup + frames) * 2);
        let inputs = |frame| self.bench.inputs.frame(self.scene, frame);
        let confirmation = confirm(
            clock,
            [reference, &mut runner],
            &inputs,
            warmup,
            frames,
            progress,
        )?;
        progress.finish();
        choice.confirm(confirmation);
        let chosen = choice.result.is_some().then_some(rewritten);
        Ok((choice, chosen))
    }
}

/// Less than this share of the image covered, the figures say little.
const FEW_PIXELS: f64 = 0.01;

/// Warnings about what the measured frames show: few or no covered pixels
/// (`results` measured over them), or a scene the warm-up moved far from
/// its first frame (an object's centre by more than a quarter of the
/// screen, or out of the view).
fn view_warnings(scene: &Scene, aspect: f32, warmup: u32, results: &[ResultRow]) -> Vec<String> {
    let mut warnings = Vec::new();
    let coverage = results.iter().map(|r| r.coverage).fold(0.0, f64::max);
    if !results.is_empty() && coverage == 0.0 {
        warnings.push(
            "the measured frames cover no pixels: the scene shows nothing of the shader there, so its speed-ups and errors say nothing about it (check the camera, the objects and --warmup)".into(),
        );
    } else if !results.is_empty() && coverage < FEW_PIXELS {
        warnings.push(format!(
            "the measured frames cover {:.2}% of the image: its speed-ups and errors rest on a few pixels",
            coverage * 100.0
        ));
    }
    if warmup > 0 {
        let (first, measured) = (scene.frame(0, aspect), scene.frame(warmup, aspect));
        for object in 0..first.objects.len().min(measured.objects.len()) {
            let at = |state: &scene::FrameState| {
                state.clip_from_world * state.objects[object] * glam::Vec4::W
            };
            let (a, b) = (at(&first), at(&measured));
            let ndc = |c: glam::Vec4| (c.w > 0.0).then(|| c.truncate().truncate() / c.w);
            let inside = |p: Option<glam::Vec2>| p.is_some_and(|p| p.abs().max_element() <= 1.0);
            let moved = match (ndc(a), ndc(b)) {
                (Some(p), Some(q)) => (q - p).length() > 0.5,
                _ => true,
            };
            if moved || (inside(ndc(a)) && !inside(ndc(b))) {
                warnings.push(format!(
                    "the {warmup} warm-up frames moved object {object} far from where frame 0 shows it ({}): the measured frames show another view than the scene starts with (--warmup sets the warm-up)",
                    match (ndc(a), ndc(b)) {
                        (Some(p), Some(q)) => format!(
                            "its centre from ({:.2}, {:.2}) to ({:.2}, {:.2}) in normalised device coordinates",
                            p.x, p.y, q.x, q.y
                        ),
                        _ => "its centre went behind the camera".into(),
                    }
                ));
            }
        }
    }
    warnings
}

/// Makes a runner for a plan and its shaders by file name, drawing the
/// scene's meshes and textures at the profile's size.
type NewRunner<'a> = dyn Fn(&Plan, &HashMap<String, String>) -> Result<Runner, String> + 'a;

/// A node of the grid and the settings it is measured at.
type GridNode<'a> = (&'a Candidate, &'a [Setting]);

/// Every node × variant × setting the grid keeps, rewritten and with its
/// runner from `new_runner`; a refusal, or a setting that runs as another
/// one (an rgba16float three-pass cache widened to rgba32float), is told
/// to `progress` and skipped. Of node i's configurations, only those in
/// `takes[i]` ([`shard_nodes`]). Each compares its frames at `size` with
/// `error_threshold`.
fn configurations(
    (shader, analysis): (&Shader, &analysis::Analysis),
    (nodes, takes): (&[GridNode], &[std::ops::Range<usize>]),
    (variants, lowres): (&[Variant], (&[Upsampler], &[bool])),
    base: &RewriteOptions,
    new_runner: &NewRunner,
    (size, error_threshold): ([u32; 2], f64),
    progress: &mut dyn Progress,
) -> Result<Vec<Config>, Error> {
    let mut configs = Vec::new();
    // Configurations set up, to measure each once.
    let mut seen = Vec::new();
    for (node, ((candidate, settings), takes)) in nodes.iter().zip(takes).enumerate() {
        // The node's configurations in order, whether measured here or
        // not: what `takes` counts.
        let mut index = 0usize;
        for &variant in variants {
            let settings = variant_settings(settings, variant, base, lowres);
            for setting in settings.iter() {
                index += 1;
                if !takes.contains(&(index - 1)) {
                    continue;
                }
                let what = format!(
                    "{} {variant} Δn={} k={} {} {} ε={}{}",
                    candidate.node.id,
                    setting.refresh_period,
                    setting.refresh_quad,
                    setting.reconstruction.as_str(),
                    setting.cache_format.as_str(),
                    setting.depth_epsilon,
                    if setting.adaptive { " adaptive" } else { "" }
                );
                let rewritten = setting
                    .rewrite_options_of(variant, base)
                    .and_then(|options| {
                        rewrite::rewrite(shader, analysis, candidate, variant, &options)
                    });
                let rewritten = match rewritten {
                    Ok(rewritten) => rewritten,
                    Err(refusal) => {
                        progress.refused(&what, &refusal.reason);
                        continue;
                    }
                };
                // The rewrite may keep a three-pass cache in rgba32float
                // (a payload that may not fit f16): record what runs, and
                // measure it once.
                let mut setting = *setting;
                if rewritten.plan.cache.format_note.is_some() {
                    setting.cache_format = CacheFormat::Rgba32float;
                }
                if seen.contains(&(node, variant, setting)) {
                    // Whichever of the pair came second: the widened
                    // rgba16float one carries the note, the rgba32float one
                    // asked for does not.
                    let why = rewritten.plan.cache.format_note.as_deref().unwrap_or(
                        "the rgba16float setting of this node ran in rgba32float, so this is the same configuration",
                    );
                    progress.refused(&what, &format!("measured already: {why}"));
                    continue;
                }
                seen.push((node, variant, setting));
                let runner = new_runner(&rewritten.plan, &sources_of(&rewritten)?)
                    .map_err(|err| fail(format!("{what}: {err}")))?;
                configs.push(Config {
                    node,
                    variant,
                    setting,
                    runner,
                    label: what,
                    times: Vec::new(),
                    passes: HashMap::new(),
                    errors: Vec::new(),
                    flicker: Vec::new(),
                    decisions: Vec::new(),
                    ages: Vec::new(),
                    last: (Vec::new(), Vec::new()),
                    size,
                    error_threshold,
                });
            }
        }
    }

    Ok(configs)
}

/// The original (`runners[0]`) and the run's winner (`runners[1]`) again,
/// in a run of their own: frame by frame, alternating which renders first,
/// so that neither always follows the other's work.
fn confirm(
    clock: &mut Clock,
    runners: [&mut Runner; 2],
    inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
    warmup: u32,
    frames: u32,
    progress: &mut dyn Progress,
) -> Result<Confirmation, Error> {
    let [reference, chosen] = runners;
    let mut times = [Vec::new(), Vec::new()];
    for frame in 0..warmup + frames {
        let inputs = inputs_of(frame)?;
        let order = if frame % 2 == 0 { [0, 1] } else { [1, 0] };
        for which in order {
            let runner = if which == 0 {
                &mut *reference
            } else {
                &mut *chosen
            };
            let label = ["reference again", "chosen again"][which];
            let (time, _, _) = timed(clock, runner, &inputs, label).map_err(fail)?;
            progress.step(label);
            if frame >= warmup {
                times[which].push(time);
            }
        }
    }
    let (reference_ms, time_ms) = (metrics::median(&times[0]), metrics::median(&times[1]));
    Ok(Confirmation {
        frames,
        reference_ms,
        time_ms,
        speedup: speedup(reference_ms, time_ms),
        speedup_ci: metrics::speedup_interval(&times[0], &times[1]),
    })
}

/// The rewrite a result measured: its node and variant, with its knobs
/// over `defaults` (which carry the scene's depth convention).
pub fn rewrite_of(
    shader: &Shader,
    analysis: &analysis::Analysis,
    row: &ResultRow,
    defaults: &RewriteOptions,
) -> Result<rewrite::Rewritten, Error> {
    let candidates = analysis.select(&shader.file, &Nodes::Ids(vec![row.node.clone()]))?;
    let candidate = candidates.first().ok_or_else(|| {
        Error::plain(Diagnostic::error(format!(
            "no node {} in the shader",
            row.node
        )))
    })?;
    let setting = Setting {
        refresh_period: row.refresh_period,
        refresh_quad: row.refresh_quad,
        reconstruction: row.reconstruction,
        cache_format: row.cache_format,
        depth_epsilon: row.depth_epsilon,
        adaptive: row.adaptive,
    };
    setting
        .rewrite_options_of(row.variant, defaults)
        .and_then(|options| rewrite::rewrite(shader, analysis, candidate, row.variant, &options))
        .map_err(|refusal| {
            Error::plain(Diagnostic::error(format!(
                "node {} {}: {}",
                row.node, row.variant, refusal.reason
            )))
        })
}

/// Each shader file of a variant as WGSL text, by the name its plan uses.
fn sources_of(rewritten: &rewrite::Rewritten) -> Result<HashMap<String, String>, Error> {
    Ok(back::render_variant(rewritten, Language::Wgsl)?
        .into_iter()
        .map(|(name, bytes)| (name, String::from_utf8_lossy(&bytes).into_owned()))
        .collect())
}

fn node_report(
    shader: &Shader,
    candidate: &Candidate,
    payload_ms: f64,
    payload_fixed_ms: f64,
    reference_ms: f64,
) -> NodeReport {
    let node = &candidate.node;
    let lines: Vec<&str> = shader.file.text.lines().collect();
    let source = lines
        .get(node.span.start[0].saturating_sub(1)..node.span.end[0].min(lines.len()))
        .map(|l| l.join("\n"))
        .unwrap_or_default();
    NodeReport {
        id: node.id.clone(),
        text: node.text.clone(),
        start: node.span.start,
        end: node.span.end,
        ty: node.ty.clone(),
        source,
        estimated_p_over_t: candidate.ratio,
        p_over_t: if reference_ms > 0.0 {
            (payload_ms - payload_fixed_ms).max(0.0) / reference_ms
        } else {
            0.0
        },
        payload_ms,
        payload_fixed_ms,
        range: candidate.range,
        fits_f16: candidate.fits_f16,
        function: node.function.clone(),
        depends_on: candidate.depends_on.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::shard_nodes;
    use crate::report::Shard;

    /// Shards deal the grid's configurations out in contiguous slices: N
    /// shards take each configuration once between them, and a shard
    /// keeps only the nodes its slice touches (so it times only their
    /// fixed costs), a node split between two shards kept by both.
    #[test]
    fn a_shard_keeps_only_the_nodes_its_slice_touches() {
        // Ten nodes of four configurations each (4 variants, 1 setting).
        let nodes: Vec<usize> = (0..10).collect();
        let count = |_: &usize| 4;
        let (all, takes, total) = shard_nodes(nodes.clone(), count, None);
        assert_eq!((all, total), (nodes.clone(), 40));
        assert!(takes.iter().all(|t| *t == (0..4)));

        let mut dealt = vec![0; 40];
        for index in 1..=6 {
            let shard = Shard { index, count: 6 };
            let (kept, takes, _) = shard_nodes(nodes.clone(), count, Some(shard));
            assert!(kept.len() <= 3, "shard {index} kept {kept:?}");
            for (node, take) in kept.iter().zip(&takes) {
                assert!(!take.is_empty() && take.end <= 4);
                take.clone().for_each(|i| dealt[node * 4 + i] += 1);
            }
        }
        assert!(dealt.iter().all(|&n| n == 1), "{dealt:?}");

        // More shards than configurations: some shards measure nothing.
        let (kept, _, _) = shard_nodes(vec![0], |_| 2, Some(Shard { index: 1, count: 3 }));
        assert!(kept.is_empty());
    }
}
