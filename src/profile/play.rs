//! `shadecache play`: a scene played as an application plays it, to see
//! what the host crate's governor does on this GPU.
//!
//! `profile` answers which variant pays on the machine it runs on; an
//! application that ships a variant cannot know that of the player's GPU,
//! and the host crate's `Governor` decides there, from the frame times it
//! measures, whether to draw the cached or the original frame
//! (`crates/shadecache-host/src/governor.rs`). `play` runs the same scene
//! three ways in one interleaved run (each frame the original, then the
//! fixed cache, then the governed one, so that drift hits all three
//! alike), each frame timed with GPU timestamps:
//!
//! - **original**: the shader as written, every frame;
//! - **fixed**: the variant every frame, as an application that always
//!   caches;
//! - **auto**: the governor choosing per frame between an original and a
//!   cached runner, fed each frame's time, starting the cache afresh
//!   (`reset`) where it says so.
//!
//! The answer ([`Play`]) is each way's mean frame time (what a player
//! sees over the run), the governor's decisions and the share of frames
//! it cached. The governor's settings are its defaults, its warm-up the
//! variant's refresh period and one frame.
//!
//! With an error budget (`--min-psnr`), the governed way runs the host
//! crate's error watch as an application would: on the frames the
//! governor watches it draws the original as well and records the
//! watch's comparison, all inside the frame's time, and gives the watch's
//! PSNR back to the governor, which lowers Δn or turns the cache off.
//! Each watched frame is also measured the profiler's way, its picture
//! read back and compared with the reference's after the frame was timed
//! ([`PlayWatch::profiler_psnr`]): what the watch measured on the GPU
//! beside what `profile` would report for the same frame.

use serde::Serialize;
use shadecache_host::{Cause, Choice, ErrorWatch, GovernedFrame, Governor, GovernorSettings};

use super::run::{measured_run, Measured, ReferenceRun, Sample, TimedRun};
use super::{sources_of, Options, Progress};
use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;
use crate::measure::bench::{reference, Bench};
use crate::measure::clock::Clock;
use crate::measure::clock::{read_linear, timed, timed_recording, Timed};
use crate::measure::{fail, open_gpu};
use crate::rewrite::{self, Variant};
use crate::runtime::FrameInputs;
use crate::runtime::Runner;
use crate::scene::Scene;

/// What a play of a scene found (`play.json`).
#[derive(Clone, Debug, Serialize)]
pub struct Play {
    /// The format of this file.
    pub format: u32,
    /// The shader.
    pub shader: String,
    /// The scene.
    pub scene: String,
    /// The adapter and driver it ran on.
    pub device: String,
    /// The frame size.
    pub size: [u32; 2],
    /// The frames played of each way.
    pub frames: u32,
    /// The variant the fixed way draws: the first of `auto_variants`.
    pub fixed_variant: String,
    /// The variants the governed way chooses among, in the order given
    /// (with several, it tries each and draws the fastest within the
    /// budget).
    pub auto_variants: Vec<String>,
    /// The governor's trials of the variants, each its turns.
    pub trials: Vec<Vec<PlayTurn>>,
    /// The variants asked for that the rewrite refused, each with its
    /// reason (left out of the play).
    pub refused: Vec<String>,
    /// Mean GPU time of a displayed frame of the original every frame, in
    /// ms.
    pub original_ms: f64,
    /// Of the variant every frame.
    pub fixed_ms: f64,
    /// Of the governor's choice each frame.
    pub auto_ms: f64,
    /// The share of the governed frames that were cached.
    pub auto_cached_share: f64,
    /// Whether the governor had the cache on at the end.
    pub auto_on_at_end: bool,
    /// The error budget the governor kept, as the least PSNR in dB
    /// (`null`: none, no watch).
    pub min_psnr: Option<f64>,
    /// The refresh period Δn the governed cache ran with at the end.
    pub auto_period_at_end: u32,
    /// Mean time of a watched frame (the cached frame, the original and
    /// the comparison), in ms; 0 without watches.
    pub watch_frame_ms: f64,
    /// The watch's comparison pass alone, mean, in ms.
    pub watch_compare_ms: f64,
    /// The governor's switches and changes of Δn, in order.
    pub decisions: Vec<PlayDecision>,
    /// The watched frames.
    pub watches: Vec<PlayWatch>,
    /// The governed frames: what each drew and its time.
    pub auto_frames: Vec<AutoFrame>,
}

/// One watched frame.
#[derive(Clone, Debug, Serialize)]
pub struct PlayWatch {
    /// The frame.
    pub frame: u64,
    /// Its refresh period Δn.
    pub period: u32,
    /// The watch's PSNR (the GPU's comparison), in dB.
    pub psnr: f64,
    /// The same frame's PSNR the profiler's way (read back, compared with
    /// the reference over the pixels the classification marks); `null`
    /// where the watch's answer came after the frame was gone.
    pub profiler_psnr: Option<f64>,
}

/// One variant's turn in a trial.
#[derive(Clone, Debug, Serialize)]
pub struct PlayTurn {
    /// The variant (its index in `auto_variants`).
    pub variant: usize,
    /// Its speed-up against the original over its turn.
    pub speedup: f64,
    /// That speed-up's interval.
    pub interval: [f64; 2],
    /// Its watched frame's PSNR, with a budget.
    pub psnr: Option<f64>,
}

/// One decision of the governor.
#[derive(Clone, Debug, Serialize)]
pub struct PlayDecision {
    /// The frame it applies from.
    pub frame: u64,
    /// The cache on or off from then.
    pub on: bool,
    /// The refresh period Δn from then.
    pub period: u32,
    /// The variant drawn from then (its index in `auto_variants`).
    pub variant: usize,
    /// `trial` (a trial of the variants ended), `speed` (the interval lay
    /// across 1×), `error` (a watched frame
    /// was below the budget: Δn halved, or the cache off at Δn's floor) or
    /// `margin` (the watched frames stayed well within it: Δn doubled
    /// again).
    pub cause: &'static str,
    /// The speed-up last weighed (0 before there was one).
    pub speedup: f64,
    /// That speed-up's bootstrap interval.
    pub interval: [f64; 2],
    /// With `error` and `margin`: the watched frame's PSNR.
    pub psnr: Option<f64>,
}

/// One governed frame.
#[derive(Clone, Debug, Serialize)]
pub struct AutoFrame {
    /// The frame.
    pub frame: u64,
    /// `original`, `cached` or `reset` (cached, the cache started afresh).
    pub drew: &'static str,
    /// Its GPU time, in ms.
    pub ms: f64,
    /// Whether it was watched (its time holds the original and the
    /// comparison too).
    pub watched: bool,
    /// Which of `auto_variants` a cached frame drew.
    pub variant: usize,
}

/// `play.json`'s format: 2 added the error watch (`min_psnr`,
/// `watches`, the decisions' `period` and `cause`) and several variants
/// (`auto_variants`, `trials`, the decisions' and frames' `variant`).
pub const PLAY_FORMAT: u32 = 2;

/// The governed way: each frame the governor's choice of runner, its time
/// given back to the governor; on a watched frame, the original drawn as
/// well and the two compared by the error watch.
struct Governed {
    original: Runner,
    /// A runner per variant the governor chooses among.
    cached: Vec<Runner>,
    governor: Governor,
    watch: Option<ErrorWatch>,
    /// This frame's choice, made when its runner is asked for.
    now: Option<GovernedFrame>,
    frames: Vec<AutoFrame>,
    watches: Vec<PlayWatch>,
    /// The watched frames' times, and their comparisons' alone.
    watch_times: (Vec<f64>, Vec<f64>),
    size: [u32; 2],
    /// The refresh period before the first decision.
    governor_start_period: u32,
}

impl Governed {
    /// Asks the governor for this frame, and sets the cache up for it:
    /// started afresh where it says, at the refresh period it says.
    fn choose(&mut self) -> Result<GovernedFrame, String> {
        let next = self.governor.next_frame();
        self.now = Some(next);
        if let Choice::Cached { reset } = next.choice {
            let cached = self.cached_runner(next.variant)?;
            if reset {
                cached.reset();
            }
            if cached.refresh_period() != next.period {
                cached.set_refresh_period(next.period)?;
            }
        }
        Ok(next)
    }

    /// The runner of variant `variant`.
    fn cached_runner(&mut self, variant: usize) -> Result<&mut Runner, String> {
        self.cached
            .get_mut(variant)
            .ok_or_else(|| format!("the governor asked for variant {variant}, which is not played"))
    }

    /// The profiler's PSNR of the cached runner's last frame against the
    /// reference's of the same frame.
    fn profiler_psnr(&self, sample: &Sample, variant: usize) -> Result<f64, String> {
        let cached = self.cached.get(variant).ok_or("no such variant")?;
        let color = cached.color().ok_or("the cached variant draws no colour")?;
        let frame = read_linear(sample.gpu, color)?;
        let classes = crate::runtime::read_texture(sample.gpu, cached.classes(), 4)?;
        Ok(crate::measure::metrics::compare(
            &sample.reference.now,
            &frame,
            &classes,
            self.size[0],
            self.size[1],
            0.0,
        )
        .psnr)
    }
}

impl Measured for Governed {
    fn label(&self) -> &str {
        "auto"
    }
    fn runner(&mut self) -> &mut Runner {
        match self.now {
            Some(GovernedFrame {
                choice: Choice::Cached { .. },
                variant,
                ..
            }) if variant < self.cached.len() => &mut self.cached[variant],
            _ => &mut self.original,
        }
    }
    fn frame(
        &mut self,
        clock: &mut Clock,
        inputs: &FrameInputs,
        label: &str,
    ) -> Result<Timed, String> {
        let mut next = self.choose()?;
        let free = self.watch.as_ref().is_some_and(ErrorWatch::is_free);
        if next.watch && !free {
            // No watch to run, or its last answer still on the way: an
            // ordinary cached frame.
            self.governor.unwatched(next.frame);
            next.watch = false;
            self.now = Some(next);
        }
        let gpu = clock.gpu;
        let Governed {
            original,
            cached,
            watch,
            ..
        } = self;
        let cached = cached
            .get_mut(next.variant)
            .ok_or("the governor asked for a variant that is not played")?;
        match (next.choice, watch.as_mut().filter(|_| next.watch)) {
            (Choice::Original, _) => timed(clock, original, inputs, label),
            (Choice::Cached { .. }, None) => timed(clock, cached, inputs, label),
            (Choice::Cached { .. }, Some(watch)) => {
                timed_recording(clock, label, |mut profiler| {
                    cached.frame(gpu, inputs, again(&mut profiler))?;
                    original.frame(gpu, inputs, again(&mut profiler))?;
                    cached.watch(gpu, (watch, next.frame), original, again(&mut profiler))?;
                    Ok(())
                })
            }
        }
    }
    fn record(&mut self, sample: Sample) -> Result<(), String> {
        let now = self
            .now
            .take()
            .ok_or("a governed frame was measured before it was drawn")?;
        self.governor.measured(now.frame, sample.time);
        let watched = now.watch && self.watch.is_some();
        if watched {
            self.watch_times.0.push(sample.time);
            if let Some((_, ms)) = sample.passes.iter().find(|(pass, _)| pass == "watch") {
                self.watch_times.1.push(*ms);
            }
        }
        // The GPU is idle after each timed frame: the watch's answer is
        // read here, without a wait of its own.
        let answer = match &mut self.watch {
            Some(watch) => watch
                .ready(&sample.gpu.device)
                .map_err(|err| err.to_string())?,
            None => None,
        };
        if let Some(answer) = answer {
            self.governor.watched(answer.frame, answer.psnr);
            let same_frame = answer.frame == now.frame;
            let profiler_psnr = if same_frame {
                Some(self.profiler_psnr(&sample, now.variant)?)
            } else {
                None
            };
            self.watches.push(PlayWatch {
                frame: answer.frame,
                period: self
                    .governor
                    .decisions()
                    .iter()
                    .rev()
                    .find(|d| d.frame <= answer.frame)
                    .map_or(self.governor_start_period, |d| d.period),
                psnr: answer.psnr,
                profiler_psnr,
            });
        }
        self.frames.push(AutoFrame {
            frame: now.frame,
            drew: match now.choice {
                Choice::Original => "original",
                Choice::Cached { reset: false } => "cached",
                Choice::Cached { reset: true } => "reset",
            },
            ms: sample.time,
            watched,
            variant: now.variant,
        });
        Ok(())
    }
}

/// The frame's profiler again, for one more runner in the same frame.
fn again<'p>(
    profiler: &'p mut Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
) -> Option<(&'p mut wgpu_profiler::GpuProfiler, &'p str)> {
    profiler.as_mut().map(|(p, label)| (&mut **p, *label))
}

/// Plays `scene` `frames` frames each way with the first node and variant
/// `options` ask for (its base setting: the first Δn, k, reconstruction,
/// format and ε).
pub fn play(
    shader: &Shader,
    scene: &Scene,
    scene_path: &std::path::Path,
    options: &Options,
    (frames, min_psnr): (u32, Option<f64>),
    progress: &mut dyn Progress,
) -> Result<Play, Error> {
    super::refuse_fragment_only(shader)?;
    let prepared = super::setup::prepare(shader, scene, options)?;
    rewrite::check_entry_point(shader, &prepared.analysis)?;
    let candidate = prepared.selected.first().ok_or_else(|| {
        Error::plain(Diagnostic::error(
            "no node to play: the selection of nodes is empty",
        ))
    })?;
    // A variant the rewrite refuses is left out, with its reason; only
    // where every one is refused is there nothing to play.
    let (mut variants, mut refused) = (Vec::new(), Vec::new());
    for &variant in options.variants.iter().chain(
        // One-pass where none is named.
        options.variants.is_empty().then_some(&Variant::OnePass),
    ) {
        let rewritten = prepared
            .base_setting
            .rewrite_options_of(variant, &prepared.base)
            .and_then(|rewrite_options| {
                rewrite::rewrite(
                    shader,
                    &prepared.analysis,
                    candidate,
                    variant,
                    &rewrite_options,
                )
            });
        match rewritten {
            Ok(rewritten) => {
                let sources = sources_of(&rewritten)?;
                variants.push((variant, rewritten, sources));
            }
            Err(refusal) => refused.push(format!(
                "node {} {variant}: {}",
                candidate.node.id, refusal.reason
            )),
        }
    }
    let Some((variant, rewritten, _)) = variants.first() else {
        return Err(Error::plain(Diagnostic::error(refused.join("\n"))));
    };
    let variant = *variant;
    let reference_plan =
        rewrite::plan::reference(shader, &prepared.analysis, &prepared.base).map_err(fail)?;
    let scene_inputs =
        super::scene_inputs((shader, scene, scene_path), &prepared, &reference_plan)?;
    let gpu = open_gpu()?;
    let mut clock = Clock::new(&gpu)?;
    let bench = Bench {
        gpu: &gpu,
        inputs: &scene_inputs,
        size: prepared.size,
        cull_back_faces: scene.cull_back_faces,
    };
    let runner = |index: usize, what: &str, classify: bool| {
        let (variant, rewritten, sources) = &variants[index];
        bench
            .runner(&rewritten.plan, sources, classify)
            .map_err(|err| fail(format!("{what} ({variant}): {err}")))
    };
    let mut original = reference(&bench, shader, &reference_plan)?;
    let mut fixed = TimedRun {
        label: "fixed",
        runner: runner(0, "the fixed cache", false)?,
        times: Vec::new(),
    };
    let period = rewritten.plan.refresh.period.max(1);
    let mut settings = GovernorSettings {
        variants: variants.len(),
        ..GovernorSettings::for_plan(&rewritten.plan)
    };
    if let Some(min_psnr) = min_psnr {
        settings = settings.with_min_psnr(min_psnr);
    }
    // The governed caches classify their frames for the profiler's PSNR of
    // the watched ones; the classification is not part of a frame's time.
    let cached = (0..variants.len())
        .map(|index| runner(index, "the governed cache", min_psnr.is_some()))
        .collect::<Result<Vec<Runner>, Error>>()?;
    let watch = match min_psnr {
        Some(_) => {
            let format = cached[0]
                .color()
                .ok_or_else(|| fail("the variant draws no colour to watch".into()))?
                .format();
            let size = (prepared.size[0], prepared.size[1]);
            Some(ErrorWatch::new(&gpu.device, size, format).map_err(|err| fail(err.to_string()))?)
        }
        None => None,
    };
    let mut governed = Governed {
        original: reference(&bench, shader, &reference_plan)?,
        cached,
        governor_start_period: settings.period,
        governor: Governor::new(settings).map_err(fail)?,
        watch,
        now: None,
        frames: Vec::new(),
        watches: Vec::new(),
        watch_times: (Vec::new(), Vec::new()),
        size: prepared.size,
    };
    // The reference's frames are read back each frame, as in a profile,
    // though nothing here is compared with them: the wait for them starts
    // each frame's draws from an idle GPU. Without it, on lavapipe, the
    // way drawn first in the frame (the reference) took 5.9 ms where the
    // same pipeline drawn third took 3.6 (Bevy's PBR at 64²).
    let mut reference_run = ReferenceRun::default();
    let mut measured: Vec<&mut dyn Measured> = vec![&mut fixed, &mut governed];
    measured_run(
        &mut clock,
        (&mut original, &mut reference_run),
        &mut measured,
        &|frame| scene_inputs.frame(scene, frame),
        (0, frames),
        progress,
    )?;
    drop(measured);
    progress.finish();

    let mean = crate::measure::metrics::mean;
    let auto_times: Vec<f64> = governed.frames.iter().map(|f| f.ms).collect();
    let cached = governed
        .frames
        .iter()
        .filter(|f| f.drew != "original")
        .count();
    Ok(Play {
        format: PLAY_FORMAT,
        shader: shader.file.path.clone(),
        scene: scene_path.display().to_string(),
        device: gpu.describe(),
        size: prepared.size,
        frames,
        fixed_variant: format!(
            "{variant} of node {} `{}`, Δn = {period}",
            candidate.node.id, candidate.node.text
        ),
        auto_variants: variants.iter().map(|(v, _, _)| v.to_string()).collect(),
        refused,
        trials: governed
            .governor
            .trials()
            .iter()
            .map(|turns| {
                turns
                    .iter()
                    .map(|turn| PlayTurn {
                        variant: turn.variant,
                        speedup: turn.estimate.speedup,
                        interval: turn.estimate.interval,
                        psnr: turn.psnr,
                    })
                    .collect()
            })
            .collect(),
        original_ms: mean(&reference_run.times),
        fixed_ms: mean(&fixed.times),
        auto_ms: mean(&auto_times),
        auto_cached_share: cached as f64 / governed.frames.len().max(1) as f64,
        auto_on_at_end: governed.governor.is_on(),
        min_psnr,
        auto_period_at_end: governed.governor.period(),
        watch_frame_ms: mean(&governed.watch_times.0),
        watch_compare_ms: mean(&governed.watch_times.1),
        decisions: governed
            .governor
            .decisions()
            .iter()
            .map(|d| PlayDecision {
                frame: d.frame,
                on: d.on,
                period: d.period,
                variant: d.variant,
                cause: match d.cause {
                    Cause::Trial => "trial",
                    Cause::Speed => "speed",
                    Cause::Error { .. } => "error",
                    Cause::Margin { .. } => "margin",
                },
                speedup: d.estimate.map_or(0.0, |e| e.speedup),
                interval: d.estimate.map_or([0.0; 2], |e| e.interval),
                psnr: match d.cause {
                    Cause::Error { psnr } | Cause::Margin { psnr } => Some(psnr),
                    Cause::Speed | Cause::Trial => None,
                },
            })
            .collect(),
        watches: governed.watches,
        auto_frames: governed.frames,
    })
}

impl Play {
    /// The variants left out, refused, with their reasons; nothing
    /// where none was.
    fn refused_list(&self) -> String {
        if self.refused.is_empty() {
            return String::new();
        }
        let escape = |text: &str| {
            text.replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
        };
        let items: String = self
            .refused
            .iter()
            .map(|reason| format!("<li>{}</li>\n", escape(reason)))
            .collect();
        format!("<h2>Variants left out</h2>\n<ul>\n{items}</ul>\n")
    }

    /// The governor's trials of the variants as a table; nothing with
    /// one variant.
    fn trial_table(&self) -> String {
        if self.trials.is_empty() {
            return String::new();
        }
        let mut rows = String::new();
        for (index, trial) in self.trials.iter().enumerate() {
            for turn in trial {
                let name = self
                    .auto_variants
                    .get(turn.variant)
                    .map_or("?", String::as_str);
                let psnr = turn.psnr.map_or("—".to_string(), |db| format!("{db:.2}"));
                rows += &format!(
                    "<tr><td>{}</td><td>{name}</td><td>{:.2}× [{:.2}, {:.2}]</td><td>{psnr}</td></tr>\n",
                    index + 1,
                    turn.speedup,
                    turn.interval[0],
                    turn.interval[1]
                );
            }
        }
        format!(
            "<h2>Trials of the variants</h2>\n<p>Each variant in turn, started afresh, warmed up and measured against the original; the governor draws the fastest within the budget.</p>\n<table><tr><th>trial</th><th>variant</th><th>speed-up</th><th>watched dB</th></tr>\n{rows}</table>\n"
        )
    }

    /// The watched frames as a table, with the profiler's PSNR of each;
    /// nothing without an error budget.
    fn watch_table(&self) -> String {
        let Some(min_psnr) = self.min_psnr else {
            return String::new();
        };
        let mut rows = String::new();
        for watch in &self.watches {
            let profiler = watch
                .profiler_psnr
                .map_or("—".to_string(), |db| format!("{db:.2}"));
            rows += &format!(
                "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td>{profiler}</td></tr>\n",
                watch.frame, watch.period, watch.psnr
            );
        }
        format!(
            "<h2>Error watch</h2>\n<p>Budget {min_psnr} dB. A watched frame took {:.3} ms (its comparison {:.3} ms); Δn = {} at the end.</p>\n<table><tr><th>frame</th><th>Δn</th><th>watch dB</th><th>profiler dB</th></tr>\n{rows}</table>\n",
            self.watch_frame_ms, self.watch_compare_ms, self.auto_period_at_end
        )
    }

    /// The play as a page: the three ways' mean frame times, and a chart
    /// of every governed frame's GPU time (original, cached, cache
    /// started afresh) over the frames, with the two means as lines and
    /// each switch marked.
    pub fn html(&self) -> String {
        use std::fmt::Write;
        let escape = |text: &str| {
            text.replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
        };
        let (width, height, margin) = (900.0, 300.0, 40.0);
        let frames = self.auto_frames.len().max(1) as f64;
        let top = self
            .auto_frames
            .iter()
            .map(|f| f.ms)
            .chain([self.original_ms, self.fixed_ms])
            .fold(0.0f64, f64::max)
            .max(1e-6)
            * 1.1;
        let x = |frame: f64| margin + frame / frames * (width - 2.0 * margin);
        let y = |ms: f64| height - margin - ms / top * (height - 2.0 * margin);
        let mut svg = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" role=\"img\" aria-label=\"governed frame times\">\n"
        );
        let _ = writeln!(
            svg,
            "<text x=\"4\" y=\"14\" font-size=\"12\">{top:.2} ms</text><text x=\"4\" y=\"{}\" font-size=\"12\">0</text>",
            height - margin
        );
        for (ms, color, label) in [
            (self.original_ms, "#3366cc", "original, mean"),
            (self.fixed_ms, "#2e9e44", "fixed cache, mean"),
        ] {
            let _ = writeln!(
                svg,
                "<line x1=\"{0:.1}\" x2=\"{1:.1}\" y1=\"{2:.1}\" y2=\"{2:.1}\" stroke=\"{color}\" stroke-dasharray=\"6 4\"/><text x=\"{3:.1}\" y=\"{4:.1}\" font-size=\"11\" fill=\"{color}\">{label} {ms:.3} ms</text>",
                x(0.0),
                x(frames),
                y(ms),
                x(frames) - 170.0,
                y(ms) - 4.0
            );
        }
        for frame in &self.auto_frames {
            let color = match frame.drew {
                _ if frame.watched => "#8e44ad",
                "original" => "#3366cc",
                "reset" => "#cc2222",
                _ => "#e08a00",
            };
            let _ = writeln!(
                svg,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"1.6\" fill=\"{color}\"><title>frame {}: {} {:.3} ms</title></circle>",
                x(frame.frame as f64),
                y(frame.ms),
                frame.frame,
                frame.drew,
                frame.ms
            );
        }
        for (index, decision) in self.decisions.iter().enumerate() {
            let state = if decision.on { "cache on" } else { "cache off" };
            let why = match decision.psnr {
                Some(psnr) => format!("Δn = {}, watched {psnr:.1} dB", decision.period),
                None => format!(
                    "{:.2}× [{:.2}, {:.2}]",
                    decision.speedup, decision.interval[0], decision.interval[1]
                ),
            };
            // Labels step down so that decisions close together stay
            // legible.
            let _ = writeln!(
                svg,
                "<line x1=\"{0:.1}\" x2=\"{0:.1}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#555\"/><text x=\"{3:.1}\" y=\"{4}\" font-size=\"11\">{state} at {5} ({why})</text>",
                x(decision.frame as f64),
                margin,
                height - margin,
                x(decision.frame as f64) + 4.0,
                margin + 12.0 + 13.0 * (index % 4) as f64,
                decision.frame,
            );
        }
        svg.push_str("</svg>\n");
        let ratio = |ms: f64| if ms > 0.0 { self.original_ms / ms } else { 0.0 };
        format!(
            "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>shadecache play: {shader}</title>\n<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}td,th{{padding:.2em .8em;text-align:right}}</style></head><body>\n<h1>{shader} on {scene}</h1>\n<p>{w}×{h}, {frames} frames each way, interleaved; {variant}; {device}.</p>\n<table><tr><th>way</th><th>mean frame ms</th><th>speed-up</th></tr>\n<tr><td>original</td><td>{o:.3}</td><td>1×</td></tr>\n<tr><td>fixed cache</td><td>{f:.3}</td><td>{fr:.2}×</td></tr>\n<tr><td>governor</td><td>{a:.3}</td><td>{ar:.2}× ({share:.0}% of its frames cached, cache {end} at the end)</td></tr></table>\n<h2>Each governed frame</h2>\n<p>Blue: the original drawn; orange: cached; red: the cache started afresh; purple: watched (the cached frame, the original and the error watch's comparison). Dashed: the means of the original and of the fixed cache every frame.</p>\n{svg}{watch}</body></html>\n",
            shader = escape(&self.shader),
            scene = escape(&self.scene),
            w = self.size[0],
            h = self.size[1],
            frames = self.frames,
            variant = escape(&self.fixed_variant),
            device = escape(&self.device),
            o = self.original_ms,
            f = self.fixed_ms,
            fr = ratio(self.fixed_ms),
            a = self.auto_ms,
            ar = ratio(self.auto_ms),
            share = self.auto_cached_share * 100.0,
            end = if self.auto_on_at_end { "on" } else { "off" },
            watch = self.watch_table() + &self.trial_table() + &self.refused_list(),
        )
    }
}
