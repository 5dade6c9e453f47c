//! runs → reports: what a profile found, as JSON (`report.json`, schema
//! in `docs/report-json.md`), as a self-contained HTML page with tables and
//! SVG plots, and as PNG maps of the cache's decisions.

#![warn(missing_docs)]

mod html;
pub(crate) mod images;
mod index;
pub(crate) mod plots;

pub use images::{Picture, Pictures};

use serde::{Deserialize, Serialize};

use crate::plan::{CacheFormat, Reconstruction, Variant};
use crate::scene::Effect;

pub use html::html;
pub use images::write_images;
pub use index::{entry_index, entry_index_html, EntryIndex, EntrySection};

/// The version of [`Report`]'s format this build writes and reads.
pub const FORMAT: u32 = 1;

/// Everything a profile measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Report {
    /// Version of this format ([`FORMAT`]).
    pub format: u32,
    /// The shader's path.
    pub shader: String,
    /// The fragment entry point profiled.
    pub entry: String,
    /// The scene's path (`default scene` without one).
    pub scene: String,
    /// What the scene is and how it moves, as it says.
    pub scene_description: String,
    /// What the scene set to a neutral value because nothing said what it
    /// is (the default scene's bindings, vertex inputs fed a constant).
    #[serde(default)]
    pub defaulted: Vec<String>,
    /// What moves in the scene.
    pub effects: Vec<Effect>,
    /// The frame's width and height in pixels.
    pub size: [u32; 2],
    /// Frames measured (after the warm-up).
    pub frames: u32,
    /// Frames rendered before the measured ones.
    pub warmup: u32,
    /// Whether the warm-up covers the longest refresh period measured, so
    /// that the errors are those of the cache in its steady state (every
    /// pixel recomputed at least once, reused values 0 to Δn − 1 frames
    /// old). When not, they are a younger cache's, and optimistic.
    #[serde(default)]
    pub steady_state: bool,
    /// The adapter the run drew on.
    pub device: Device,
    /// `gpu-timestamps` (timestamp queries around each pass) or
    /// `cpu-wall-clock` (submit to completion, where the adapter has no
    /// timestamp queries).
    pub timing: String,
    /// The command that produced the report.
    pub command: String,
    /// The unmodified shader's frame times.
    pub reference: Reference,
    /// The nodes profiled, highest estimated P/T first.
    pub nodes: Vec<NodeReport>,
    /// One row per configuration measured (node × variant × Δn × k ×
    /// reconstruction × cache format × ε), fastest first.
    pub results: Vec<ResultRow>,
    /// What causes the misses of the fastest configuration: the scene
    /// again with one declared effect at a time. Refreshes are caused by
    /// the refresh pattern alone (Δn, k) and are not listed.
    #[serde(default)]
    pub miss_causes: Vec<MissCause>,
    /// What makes the figures say little about the shader: measured frames
    /// that cover few or no pixels, a warm-up that moved the scene far
    /// from where it starts.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// What the reference's measured frames show, checked before anything
    /// is ranked (`profile::reference_check`): a degenerate reference is
    /// said first and nothing is recommended on it.
    #[serde(default)]
    pub reference_check: Option<ReferenceCheck>,
    /// The grid of knobs measured, and what was pruned from it.
    #[serde(default)]
    pub grid: Option<GridReport>,
    /// The configuration picked for an error budget (`--max-error`).
    #[serde(default)]
    pub choice: Option<Choice>,
    /// Lowres's factor and knobs, when lowres was measured (its rows'
    /// reconstruction and adaptive refresh are their own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upsampling: Option<crate::rewrite::Upsampling>,
    /// With `--shard K/N`: the slice of the grid this run measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// With `--shard K/N`: the ids of every node of the grid, in order.
    /// `nodes` holds only those the shard's slice touched; this is what
    /// tells shards of one sweep from shards of another.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grid_nodes: Vec<String>,
    /// A report `shadecache merge` joined from shards: each shard's run
    /// (its rows' speed-ups are against its own reference).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub merged_from: Vec<MergedShard>,
}

/// The K-th of N deterministic slices of a profile's configurations
/// (`profile --shard K/N`): of the grid's T configurations, in the order
/// the profile walks them (nodes, variants, settings), shard K takes the
/// contiguous run [⌊T(K−1)/N⌋, ⌊TK/N⌋). Contiguous, so that a shard
/// touches few nodes and times only their fixed costs. Each shard runs its
/// own reference, so its rows are ratios within one run wherever it ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// K, from 1.
    pub index: u32,
    /// N.
    pub count: u32,
}

impl Shard {
    /// `K/N`, 1 ≤ K ≤ N.
    pub fn parse(text: &str) -> Result<Shard, String> {
        let bad = || format!("`{text}` is not K/N with 1 ≤ K ≤ N (e.g. 2/4)");
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count): (u32, u32) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        let shard = Shard { index, count };
        shard.is_valid().then_some(shard).ok_or_else(bad)
    }

    /// Whether it is K/N with 1 ≤ K ≤ N (what [`Shard::slice`] needs).
    pub fn is_valid(self) -> bool {
        1 <= self.index && self.index <= self.count
    }

    /// The configurations (from 0) of a grid of `total` that are this
    /// shard's.
    pub fn slice(self, total: usize) -> std::ops::Range<usize> {
        let at = |k: u32| total * k as usize / self.count as usize;
        at(self.index - 1)..at(self.index)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// One shard of a merged report: where its report was, which slice it
/// measured, its reference, and its adapter.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MergedShard {
    /// The shard's `report.json`.
    pub report: String,
    /// Its slice (`None`: an unsharded run merged in).
    pub shard: Option<Shard>,
    /// Its reference's median frame time, ms.
    pub reference_ms: f64,
    /// Its adapter.
    pub device: Device,
    /// Rows it measured.
    pub results: usize,
}

/// The reference's measured frames, looked at.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ReferenceCheck {
    /// Measured frames looked at.
    pub frames: u32,
    /// Share of the pixels the draw changed from the clear colour, over
    /// every measured frame.
    pub coverage: f64,
    /// Mean Rec. 709 luminance (linear) of the drawn pixels.
    pub mean_luminance: f64,
    /// Share of the drawn pixels brighter than luminance 0.025.
    pub bright_share: f64,
    /// Standard deviation of the drawn pixels' luminance.
    pub luminance_spread: f64,
    /// The largest range of any RGB channel over the drawn pixels.
    pub channel_range: f64,
    /// Share of the drawn pixels with a NaN or infinite channel.
    pub non_finite_share: f64,
    /// The largest share of the pixels that differ (by any bit) between
    /// the first measured frame and a later one; `None` with one measured
    /// frame.
    pub changed_share: Option<f64>,
    /// What makes the figures meaningless; empty when the reference
    /// passes.
    pub problems: Vec<ReferenceProblem>,
}

impl ReferenceCheck {
    /// Whether the reference shows nothing a cache's figures can be
    /// measured on.
    pub fn degenerate(&self) -> bool {
        !self.problems.is_empty()
    }

    /// The check in one line: its figures, and its verdict.
    pub fn summary(&self) -> String {
        let figures = format!(
            "{:.1}% of pixels drawn, mean luminance {:.3} (spread {:.3}), {:.1}% bright, {:.2}% NaN/∞, {}",
            self.coverage * 100.0,
            self.mean_luminance,
            self.luminance_spread,
            self.bright_share * 100.0,
            self.non_finite_share * 100.0,
            self.changed_share.map_or("no change measured (one frame)".into(), |c| {
                format!("{:.2}% of pixels change from the first measured frame", c * 100.0)
            })
        );
        if self.degenerate() {
            let kinds: Vec<&str> = self.problems.iter().map(|p| p.kind.as_str()).collect();
            format!("DEGENERATE ({}): {figures}", kinds.join(", "))
        } else {
            format!("passes: {figures}")
        }
    }
}

/// One reason a reference says nothing about the shader.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceProblem {
    /// `empty`, `non-finite`, `nearly-black`, `constant` or `still`.
    pub kind: String,
    /// What was measured.
    pub finding: String,
    /// What likely caused it, and what to look at.
    pub cause: String,
}

/// Which configurations were measured (see `profile::grid`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GridReport {
    /// How the grid was walked.
    pub design: Design,
    /// The values of each knob.
    pub axes: Axes,
    /// The setting the sweep's planes go through.
    pub base: Setting,
    /// Node × variant × setting configurations of the full product.
    pub full: usize,
    /// Configurations measured (refused rewrites excluded).
    pub measured: usize,
    /// What was left out, and why.
    pub pruned: Vec<Pruned>,
}

/// The answer: the configuration to use, or to keep the original.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Choice {
    /// The error a recommendation must stay within: `--max-error`, else
    /// [`Budget::DEFAULT`].
    pub budget: Budget,
    /// Whether the budget was given (`--max-error`).
    #[serde(default)]
    pub budget_given: bool,
    /// Index into `results` of the configuration recommended: the fastest
    /// within the budget whose speed-up interval lies above 1×, in the run
    /// and again in a confirmatory run. `None`: keep the original shader.
    pub result: Option<usize>,
    /// No configuration measured reached the budget.
    #[serde(default)]
    pub none_within_budget: bool,
    /// When none is recommended, what came closest (index into `results`).
    #[serde(default)]
    pub closest: Option<usize>,
    /// The configuration that won the run, measured again against the
    /// original.
    #[serde(default)]
    pub confirmation: Option<Confirmation>,
    /// Why this one, or why none.
    pub reason: String,
}

/// A configuration measured again against the original shader, in a run
/// of its own (the two interleaved frame by frame, alternating which goes
/// first).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Confirmation {
    /// Frames in the confirming run.
    pub frames: u32,
    /// The original's median frame time in it (ms).
    pub reference_ms: f64,
    /// The configuration's median frame time in it (ms).
    pub time_ms: f64,
    /// Original time over the configuration's.
    pub speedup: f64,
    /// The speed-up's 95% bootstrap interval.
    pub speedup_ci: [f64; 2],
}

/// The misses of the best configuration when only `effect` is simulated.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MissCause {
    /// The effect simulated alone.
    pub effect: Effect,
    /// Share of the covered pixels that missed.
    pub miss_rate: f64,
    /// Share that missed because last frame's point was off-screen.
    pub offscreen_rate: f64,
    /// Share that missed because last frame's point was hidden.
    pub disocclusion_rate: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
/// The adapter a run drew on, as wgpu names it.
pub struct Device {
    /// The adapter's name.
    pub name: String,
    /// The backend (Vulkan, Metal, DX12...).
    pub backend: String,
    /// The driver and its version.
    pub driver: String,
}

impl Device {
    /// The adapter with its driver and version, as the summary and the
    /// page name it: `llvmpipe (LLVM 15.0.6, 256 bits), llvmpipe Mesa
    /// 25.0.7 (LLVM 15.0.6)`.
    pub fn describe(&self) -> String {
        if self.driver.is_empty() {
            format!("{}, driver unnamed", self.name)
        } else {
            format!("{}, {}", self.name, self.driver)
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
/// The unmodified shader's measured frames.
pub struct Reference {
    /// Median frame time of the unmodified shader, ms.
    pub time_ms: f64,
    /// Its 10th and 90th percentiles, ms: how much one run's frames spread.
    #[serde(default)]
    pub spread_ms: [f64; 2],
    /// Median time of the original with its fragment stage made free
    /// (returning zero): what drawing the scene costs before shading.
    #[serde(default)]
    pub fixed_ms: f64,
    /// Every measured frame's time, ms, in order.
    pub frame_ms: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
/// A node measured: where it is and what caching it costs and saves.
pub struct NodeReport {
    /// The node's stable id.
    pub id: String,
    /// Its source text.
    pub text: String,
    /// `[line, column]` of the node's first and past-last characters.
    pub start: [usize; 2],
    /// Line and column just past its end.
    pub end: [usize; 2],
    /// Its WGSL type.
    #[serde(rename = "type")]
    pub ty: String,
    /// The source lines the node spans, for showing it.
    pub source: String,
    /// P/T from the cost model.
    pub estimated_p_over_t: f64,
    /// P/T measured: the payload pass (the node's slice alone, every
    /// pixel) less the same pass with the payload made free (its fixed
    /// cost: rasterisation, the twin vertex stage, the cache write), over
    /// the reference. Not clamped: at most 1 but for the run's noise.
    pub p_over_t: f64,
    /// Median time of that payload pass, ms.
    pub payload_ms: f64,
    /// Median time of the same pass with the payload made free, ms.
    #[serde(default)]
    pub payload_fixed_ms: f64,
    /// Bounds of the node's value over the scene's frames, by interval
    /// arithmetic with the uniform values the scene gives; `null` ends are
    /// unbounded.
    #[serde(default)]
    pub range: [Option<f64>; 2],
    /// Whether those bounds fit an rgba16float cache; when not, a
    /// three-pass cache runs in rgba32float.
    #[serde(default)]
    pub fits_f16: bool,
    /// The function whose source the node is in (a helper's, for a node
    /// inside one).
    #[serde(default)]
    pub function: String,
    /// The per-frame inputs its value reads (`time`, `camera`, `light`).
    #[serde(default)]
    pub depends_on: Vec<String>,
}

/// One configuration's measurements.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[non_exhaustive]
pub struct ResultRow {
    /// The node's id.
    pub node: String,
    /// The node's source text.
    pub node_text: String,
    /// The variant.
    pub variant: Variant,
    /// Δn: every pixel recomputed at least every Δn frames (0: never).
    pub refresh_period: u32,
    /// k: refresh decided per k×k block.
    pub refresh_quad: u32,
    /// How the payload and depth are read back.
    pub reconstruction: Reconstruction,
    /// The payload cache's format.
    pub cache_format: CacheFormat,
    /// The depth test's relative tolerance ε.
    pub depth_epsilon: f32,
    /// Adaptive refresh: lowres's unreliable pixels shaded at full
    /// resolution in a third pass; the cache variants' changed values
    /// refreshed after Δn/4 frames.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub adaptive: bool,
    /// Lowres's factor and knobs (s, σn, σz, a), on lowres's rows: a row
    /// merged from another run keeps its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upsampling: Option<crate::rewrite::Upsampling>,
    /// Median frame time, ms: from the first pass's start timestamp to the
    /// last one's end, what runs between the passes included.
    pub time_ms: f64,
    /// Median time of each pass, ms.
    pub passes: Vec<PassTime>,
    /// Reference time over this variant's time, from the same run.
    pub speedup: f64,
    /// A 95% interval for `speedup` (a bootstrap over the measured frames
    /// of both, `measure::metrics::speedup_interval`).
    #[serde(default)]
    pub speedup_ci: [f64; 2],
    /// Means over the measured frames: PSNR over the covered pixels (those
    /// the shader draws), SSIM over the whole frame.
    pub psnr: f64,
    /// Mean SSIM over the measured frames, against the reference.
    pub ssim: f64,
    /// PSNR over the whole frame, background included, mean.
    #[serde(default)]
    pub psnr_frame: f64,
    /// The lowest covered PSNR of any measured frame.
    #[serde(default)]
    pub worst_psnr: f64,
    /// How much each frame's change from the one before differs from the
    /// reference's own change (block popping, visible refreshes), mean
    /// over the covered pixels' channels and the measured frames, in
    /// [0, 1] (`measure::metrics::flicker`).
    #[serde(default)]
    pub flicker: f64,
    /// Largest over the measured frames.
    pub max_abs_error: f64,
    /// Share of pixels whose largest channel error is above the report's
    /// threshold.
    pub above_threshold: f64,
    /// The share of the image the node covers (where it is computed),
    /// mean over the measured frames.
    #[serde(default)]
    pub coverage: f64,
    /// Shares of the covered pixels, means over the measured frames.
    pub hit_rate: f64,
    /// Share of the covered pixels that missed.
    pub miss_rate: f64,
    /// Share that missed off-screen.
    pub offscreen_rate: f64,
    /// Share that missed disoccluded.
    pub disocclusion_rate: f64,
    /// Missed because the cached payload was not finite (NaN, infinity,
    /// an rgba16float overflow).
    #[serde(default)]
    pub invalid_rate: f64,
    /// Share of the covered pixels refreshed.
    pub refresh_rate: f64,
    /// The oldest value the cache showed in the measured frames, in
    /// frames since it was computed: below the refresh period Δn whatever
    /// the motion (a value is refreshed when its age reaches Δn).
    #[serde(default)]
    pub max_age: u32,
    /// Covered pixels by the age of their value (index: frames since it
    /// was computed, 0 for those computed that frame), summed over the
    /// measured frames.
    #[serde(default)]
    pub age_histogram: Vec<u64>,
    /// Measured P/T of the node (see [`NodeReport::p_over_t`]).
    pub p_over_t: f64,
    /// 1 / (1 − ρ·f) with ρ the hit rate (reuse fraction) and f = P/T.
    pub ideal_speedup: f64,
    /// Each pass's median time with the payload and the shade made free
    /// (this node and variant at the base setting), ms: its fixed cost.
    #[serde(default)]
    pub fixed_cost_ms: Vec<PassTime>,
    /// The speed-up the variant could reach were its payload and shade
    /// free: the reference's time over the sum of `fixed_cost_ms` (over
    /// the free run's median frame time when there are no GPU timestamps,
    /// hence no pass times). Beside
    /// `ideal_speedup` (which counts the payload only), it says how much of
    /// the gap is the passes' fixed cost.
    #[serde(default)]
    pub bound_with_fixed_costs: f64,
    /// speedup / ideal_speedup.
    pub share_of_ideal: f64,
    /// On the Pareto front of time against PSNR, and against SSIM (see
    /// `profile::choice::mark_pareto_fronts`).
    #[serde(default)]
    pub pareto_psnr: bool,
    /// Whether it is on the SSIM-against-time Pareto front.
    #[serde(default)]
    pub pareto_ssim: bool,
    /// Each measured frame's time, error and decisions.
    pub frame_stats: Vec<FrameStats>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
/// One pass's time in a frame.
pub struct PassTime {
    /// The pass's name in the plan.
    pub name: String,
    /// Its median time, ms.
    pub time_ms: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
/// One measured frame of a configuration.
pub struct FrameStats {
    /// The frame's time, ms.
    pub time_ms: f64,
    /// Over the covered pixels.
    pub psnr: f64,
    /// Over the whole frame.
    #[serde(default)]
    pub psnr_frame: f64,
    /// Against the frame before ([`ResultRow::flicker`]); 0 for the first.
    #[serde(default)]
    pub flicker: f64,
    /// SSIM against the reference's frame.
    pub ssim: f64,
    /// Largest channel difference from the reference frame, in [0, 1].
    #[serde(default)]
    pub max_abs_error: f64,
    /// Share of covered pixels reused.
    pub hit_rate: f64,
    /// Share that missed.
    pub miss_rate: f64,
    /// Share refreshed.
    pub refresh_rate: f64,
}

// What the grid measured: data of `report.json`; the profile's grid
// (`profile::grid`) makes and prunes it.

/// The values of each knob.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axes {
    /// The Δn values.
    pub refresh_periods: Vec<u32>,
    /// The k values.
    pub refresh_quads: Vec<u32>,
    /// The reconstructions.
    pub reconstructions: Vec<Reconstruction>,
    /// The cache formats.
    pub cache_formats: Vec<CacheFormat>,
    /// The depth tolerances ε.
    pub depth_epsilons: Vec<f32>,
}

/// The knobs of one configuration besides its node and variant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    /// Δn.
    pub refresh_period: u32,
    /// k.
    pub refresh_quad: u32,
    /// The reconstruction.
    pub reconstruction: Reconstruction,
    /// The cache format.
    pub cache_format: CacheFormat,
    /// ε.
    pub depth_epsilon: f32,
    /// Adaptive refresh: lowres shades its unreliable pixels at full
    /// resolution; the cache variants refresh a value that changed after
    /// Δn/4 frames.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub adaptive: bool,
}

/// How the grid is covered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Design {
    /// Every setting of the product.
    Full,
    /// The cost-model pruning and the two planes (`profile::grid`).
    Planes,
}

/// What was left out of the grid, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pruned {
    /// `cost-model` or `planes`.
    pub rule: String,
    /// The node it applies to, if one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<String>,
    /// Node × variant × setting configurations left out.
    pub configurations: usize,
    /// Why, in words.
    pub reason: String,
}

/// An error budget: the mean PSNR (dB) or SSIM over the measured frames a
/// configuration must reach.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "metric", content = "at_least")]
pub enum Budget {
    /// Mean PSNR (dB) at least this.
    Psnr(f64),
    /// Mean SSIM at least this.
    Ssim(f64),
}

impl Budget {
    /// The budget when none is given: a picture a viewer would take for
    /// the original at a glance.
    pub const DEFAULT: Budget = Budget::Ssim(0.95);

    /// `row`'s error in this budget's metric (higher is better).
    pub(crate) fn metric(&self, row: &ResultRow) -> f64 {
        match self {
            Budget::Psnr(_) => row.psnr,
            Budget::Ssim(_) => row.ssim,
        }
    }

    /// Whether `row` is within the budget.
    pub fn admits(&self, row: &ResultRow) -> bool {
        match *self {
            Budget::Psnr(db) => row.psnr >= db,
            Budget::Ssim(ssim) => row.ssim >= ssim,
        }
    }
}

impl std::fmt::Display for Budget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Budget::Psnr(db) => write!(f, "PSNR ≥ {db} dB"),
            Budget::Ssim(ssim) => write!(f, "SSIM ≥ {ssim}"),
        }
    }
}

impl std::str::FromStr for Budget {
    type Err = String;

    /// `psnr:30` or `ssim:0.95`.
    fn from_str(text: &str) -> Result<Self, String> {
        let (metric, value) = text
            .split_once([':', '='])
            .ok_or("expected psnr:DB or ssim:S, e.g. psnr:30")?;
        let value: f64 = value
            .trim()
            .parse()
            .map_err(|err| format!("`{value}`: {err}"))?;
        if !value.is_finite() {
            return Err(format!("`{value}` is not a finite number"));
        }
        match metric.trim().to_ascii_lowercase().as_str() {
            "psnr" => Ok(Budget::Psnr(value)),
            "ssim" if (0.0..=1.0).contains(&value) => Ok(Budget::Ssim(value)),
            "ssim" => Err("an SSIM budget lies between 0 and 1".into()),
            other => Err(format!("unknown metric `{other}`: use psnr or ssim")),
        }
    }
}

impl ResultRow {
    /// Its knobs in words: `Δn = 32, k = 4, bilinear, rgba16float, ε = 0.02`.
    pub fn setting(&self) -> String {
        format!(
            "Δn = {}, k = {}, {}, {}, ε = {}{}",
            self.refresh_period,
            self.refresh_quad,
            self.reconstruction.as_str(),
            self.cache_format.as_str(),
            self.depth_epsilon,
            self.adaptive_words()
        )
    }

    /// Its adaptive refresh in words, after a comma (nothing when off):
    /// lowres re-shades its unreliable pixels, a cache variant refreshes
    /// its changed values early.
    pub fn adaptive_words(&self) -> &'static str {
        match (self.adaptive, self.variant.upsamples()) {
            (false, _) => "",
            (true, true) => ", unreliable pixels re-shaded",
            (true, false) => ", adaptive refresh",
        }
    }
}

impl Report {
    /// The fastest result of each variant.
    pub fn best_per_variant(&self) -> Vec<&ResultRow> {
        let mut out: Vec<&ResultRow> = Vec::new();
        for row in &self.results {
            if !out.iter().any(|r| r.variant == row.variant) {
                out.push(row);
            }
        }
        out
    }
}

/// Reports and rows made by hand, for the tests of what reads them.
#[cfg(test)]
pub(crate) mod fixtures {
    use super::*;
    use crate::plan::{CacheFormat, Reconstruction, Variant};

    /// A row of a three-pass result taking `time_ms` with these errors
    /// (the node named after its time).
    pub(crate) fn row(time_ms: f64, psnr: f64, ssim: f64) -> ResultRow {
        ResultRow {
            node: format!("n{time_ms}"),
            node_text: String::new(),
            variant: Variant::ThreePass,
            refresh_period: 32,
            refresh_quad: 4,
            reconstruction: Reconstruction::Bilinear,
            cache_format: CacheFormat::Rgba16float,
            depth_epsilon: 1e-3,
            adaptive: false,
            upsampling: None,
            time_ms,
            passes: Vec::new(),
            speedup: 10.0 / time_ms,
            speedup_ci: [9.0 / time_ms, 11.0 / time_ms],
            psnr,
            ssim,
            psnr_frame: psnr,
            worst_psnr: psnr,
            flicker: 0.0,
            max_abs_error: 0.0,
            above_threshold: 0.0,
            coverage: 1.0,
            hit_rate: 0.0,
            miss_rate: 0.0,
            offscreen_rate: 0.0,
            disocclusion_rate: 0.0,
            invalid_rate: 0.0,
            refresh_rate: 0.0,
            max_age: 0,
            age_histogram: Vec::new(),
            p_over_t: 0.0,
            ideal_speedup: 1.0,
            fixed_cost_ms: Vec::new(),
            bound_with_fixed_costs: 1.0,
            share_of_ideal: 1.0,
            pareto_psnr: false,
            pareto_ssim: false,
            frame_stats: Vec::new(),
        }
    }

    /// A report of `results` against a 10 ms reference, with no nodes.
    pub(crate) fn report(results: Vec<ResultRow>) -> Report {
        Report {
            format: 1,
            shader: String::new(),
            entry: String::new(),
            scene: String::new(),
            scene_description: String::new(),
            defaulted: Vec::new(),
            effects: Vec::new(),
            size: [8, 8],
            frames: 1,
            warmup: 0,
            steady_state: true,
            device: Device {
                name: String::new(),
                backend: String::new(),
                driver: String::new(),
            },
            timing: String::new(),
            command: String::new(),
            reference: Reference {
                time_ms: 10.0,
                spread_ms: [10.0, 10.0],
                fixed_ms: 0.0,
                frame_ms: vec![10.0],
            },
            nodes: Vec::new(),
            results,
            miss_causes: Vec::new(),
            warnings: Vec::new(),
            grid: None,
            upsampling: None,
            shard: None,
            grid_nodes: Vec::new(),
            merged_from: Vec::new(),
            reference_check: None,
            choice: None,
        }
    }

    /// A node at measured P/T `p_over_t`.
    pub(crate) fn node(id: &str, p_over_t: f64) -> NodeReport {
        NodeReport {
            id: id.to_string(),
            text: String::new(),
            start: [1, 1],
            end: [1, 2],
            ty: "f32".into(),
            source: String::new(),
            estimated_p_over_t: p_over_t,
            p_over_t,
            payload_ms: 0.0,
            payload_fixed_ms: 0.0,
            range: [None, None],
            fits_f16: false,
            function: "fs_main".into(),
            depends_on: Vec::new(),
        }
    }
}
