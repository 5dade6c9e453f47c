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
//! variant's refresh period and one frame. Not yet: the error watch.

use serde::Serialize;
use shadecache_host::{Choice, GovernedFrame, Governor, GovernorSettings};

use super::run::{measured_run, Measured, ReferenceRun, Sample, TimedRun};
use super::{sources_of, Options, Progress};
use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;
use crate::measure::bench::{reference, Bench};
use crate::measure::clock::Clock;
use crate::measure::{fail, open_gpu};
use crate::rewrite::{self, Variant};
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
    /// The variant the fixed and the governed ways draw.
    pub fixed_variant: String,
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
    /// The governor's switches, in order.
    pub decisions: Vec<PlayDecision>,
    /// The governed frames: what each drew and its time.
    pub auto_frames: Vec<AutoFrame>,
}

/// One switch of the governor.
#[derive(Clone, Debug, Serialize)]
pub struct PlayDecision {
    /// The frame it applies from.
    pub frame: u64,
    /// The cache on or off from then.
    pub on: bool,
    /// The speed-up it was decided on.
    pub speedup: f64,
    /// That speed-up's bootstrap interval.
    pub interval: [f64; 2],
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
}

/// `play.json`'s format.
pub const PLAY_FORMAT: u32 = 1;

/// The governed way: each frame the governor's choice of runner, its time
/// given back to the governor.
struct Governed {
    original: Runner,
    cached: Runner,
    governor: Governor,
    /// This frame's choice, made when its runner is asked for.
    now: Option<GovernedFrame>,
    frames: Vec<AutoFrame>,
}

impl Measured for Governed {
    fn label(&self) -> &str {
        "auto"
    }
    fn runner(&mut self) -> &mut Runner {
        let next = self.governor.next_frame();
        self.now = Some(next);
        match next.choice {
            Choice::Original => &mut self.original,
            Choice::Cached { reset } => {
                if reset {
                    self.cached.reset();
                }
                &mut self.cached
            }
        }
    }
    fn record(&mut self, sample: Sample) -> Result<(), String> {
        let now = self
            .now
            .take()
            .ok_or("a governed frame was measured before it was drawn")?;
        self.governor.measured(now.frame, sample.time);
        self.frames.push(AutoFrame {
            frame: now.frame,
            drew: match now.choice {
                Choice::Original => "original",
                Choice::Cached { reset: false } => "cached",
                Choice::Cached { reset: true } => "reset",
            },
            ms: sample.time,
        });
        Ok(())
    }
}

/// Plays `scene` `frames` frames each way with the first node and variant
/// `options` ask for (its base setting: the first Δn, k, reconstruction,
/// format and ε).
pub fn play(
    shader: &Shader,
    scene: &Scene,
    scene_path: &std::path::Path,
    options: &Options,
    frames: u32,
    progress: &mut dyn Progress,
) -> Result<Play, Error> {
    super::refuse_fragment_only(shader)?;
    let prepared = super::setup::prepare(shader, scene, options)?;
    rewrite::check_entry_point(shader, &prepared.analysis)?;
    let variant = *options.variants.first().unwrap_or(&Variant::OnePass);
    let candidate = prepared.selected.first().ok_or_else(|| {
        Error::plain(Diagnostic::error(
            "no node to play: the selection of nodes is empty",
        ))
    })?;
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
        })
        .map_err(|refusal| {
            Error::plain(Diagnostic::error(format!(
                "node {} {variant}: {}",
                candidate.node.id, refusal.reason
            )))
        })?;
    let sources = sources_of(&rewritten)?;
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
    let runner = |what: &str| {
        bench
            .runner(&rewritten.plan, &sources, false)
            .map_err(|err| fail(format!("{what}: {err}")))
    };
    let mut original = reference(&bench, shader, &reference_plan)?;
    let mut fixed = TimedRun {
        label: "fixed",
        runner: runner("the fixed cache")?,
        times: Vec::new(),
    };
    let period = rewritten.plan.refresh.period.max(1);
    let settings = GovernorSettings::for_plan(&rewritten.plan);
    let mut governed = Governed {
        original: reference(&bench, shader, &reference_plan)?,
        cached: runner("the governed cache")?,
        governor: Governor::new(settings).map_err(fail)?,
        now: None,
        frames: Vec::new(),
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
        original_ms: mean(&reference_run.times),
        fixed_ms: mean(&fixed.times),
        auto_ms: mean(&auto_times),
        auto_cached_share: cached as f64 / governed.frames.len().max(1) as f64,
        auto_on_at_end: governed.governor.is_on(),
        decisions: governed
            .governor
            .decisions()
            .iter()
            .map(|d| PlayDecision {
                frame: d.frame,
                on: d.on,
                speedup: d.estimate.speedup,
                interval: d.estimate.interval,
            })
            .collect(),
        auto_frames: governed.frames,
    })
}

impl Play {
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
        for decision in &self.decisions {
            let state = if decision.on { "cache on" } else { "cache off" };
            let _ = writeln!(
                svg,
                "<line x1=\"{0:.1}\" x2=\"{0:.1}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#555\"/><text x=\"{3:.1}\" y=\"{4}\" font-size=\"11\">{state} at {5} ({6:.2}× [{7:.2}, {8:.2}])</text>",
                x(decision.frame as f64),
                margin,
                height - margin,
                x(decision.frame as f64) + 4.0,
                margin + 12.0,
                decision.frame,
                decision.speedup,
                decision.interval[0],
                decision.interval[1]
            );
        }
        svg.push_str("</svg>\n");
        let ratio = |ms: f64| if ms > 0.0 { self.original_ms / ms } else { 0.0 };
        format!(
            "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>shadecache play: {shader}</title>\n<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}td,th{{padding:.2em .8em;text-align:right}}</style></head><body>\n<h1>{shader} on {scene}</h1>\n<p>{w}×{h}, {frames} frames each way, interleaved; {variant}; {device}.</p>\n<table><tr><th>way</th><th>mean frame ms</th><th>speed-up</th></tr>\n<tr><td>original</td><td>{o:.3}</td><td>1×</td></tr>\n<tr><td>fixed cache</td><td>{f:.3}</td><td>{fr:.2}×</td></tr>\n<tr><td>governor</td><td>{a:.3}</td><td>{ar:.2}× ({share:.0}% of its frames cached, cache {end} at the end)</td></tr></table>\n<h2>Each governed frame</h2>\n<p>Blue: the original drawn; orange: cached; red: the cache started afresh. Dashed: the means of the original and of the fixed cache every frame.</p>\n{svg}</body></html>\n",
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
        )
    }
}
