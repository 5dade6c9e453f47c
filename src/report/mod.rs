//! runs → reports: what a profile found, as JSON (`report.json`, schema
//! in `docs/report-json.md`), as a self-contained HTML page with tables and
//! SVG plots, and as PNG maps of the cache's decisions.

mod html;
mod images;
mod plots;

use serde::{Deserialize, Serialize};

use crate::profile::grid::{Axes, Design, Pruned, Setting};
use crate::rewrite::{CacheFormat, Reconstruction, Variant};
use crate::scene::Effect;

pub use html::html;
pub use images::write_images;

/// Everything a profile measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// Version of this format.
    pub format: u32,
    pub shader: String,
    pub entry: String,
    pub scene: String,
    pub scene_description: String,
    /// What the scene set to a neutral value because nothing said what it
    /// is (the default scene's bindings, vertex inputs fed a constant).
    #[serde(default)]
    pub defaulted: Vec<String>,
    pub effects: Vec<Effect>,
    pub size: [u32; 2],
    /// Frames measured (after the warm-up).
    pub frames: u32,
    pub warmup: u32,
    /// Whether the warm-up covers the longest refresh period measured, so
    /// that the errors are those of the cache in its steady state (every
    /// pixel recomputed at least once, reused values 0 to Δn − 1 frames
    /// old). When not, they are a younger cache's, and optimistic.
    #[serde(default)]
    pub steady_state: bool,
    pub device: Device,
    /// `gpu-timestamps` (timestamp queries around each pass) or
    /// `cpu-wall-clock` (submit to completion, where the adapter has no
    /// timestamp queries).
    pub timing: String,
    /// The command that produced the report.
    pub command: String,
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
    /// The grid of knobs measured, and what was pruned from it.
    #[serde(default)]
    pub grid: Option<GridReport>,
    /// The configuration picked for an error budget (`--max-error`).
    #[serde(default)]
    pub choice: Option<Choice>,
}

/// Which configurations were measured (see `profile::grid`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GridReport {
    pub design: Design,
    pub axes: Axes,
    /// The setting the sweep's planes go through.
    pub base: Setting,
    /// Node × variant × setting configurations of the full product.
    pub full: usize,
    /// Configurations measured (refused rewrites excluded).
    pub measured: usize,
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
    pub frames: u32,
    pub reference_ms: f64,
    pub time_ms: f64,
    pub speedup: f64,
    pub speedup_ci: [f64; 2],
}

/// The misses of the best configuration when only `effect` is simulated.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MissCause {
    pub effect: Effect,
    pub miss_rate: f64,
    pub offscreen_rate: f64,
    pub disocclusion_rate: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Device {
    pub name: String,
    pub backend: String,
    pub driver: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
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
    pub frame_ms: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct NodeReport {
    pub id: String,
    pub text: String,
    /// `[line, column]` of the node's first and past-last characters.
    pub start: [usize; 2],
    pub end: [usize; 2],
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
pub struct ResultRow {
    pub node: String,
    pub node_text: String,
    pub variant: Variant,
    pub refresh_period: u32,
    pub refresh_quad: u32,
    pub reconstruction: Reconstruction,
    pub cache_format: CacheFormat,
    pub depth_epsilon: f32,
    /// Median frame time, ms: from the first pass's start timestamp to the
    /// last one's end, what runs between the passes included.
    pub time_ms: f64,
    /// Median time of each pass, ms.
    pub passes: Vec<PassTime>,
    /// Reference time over this variant's time, from the same run.
    pub speedup: f64,
    /// A 95% interval for `speedup` (a bootstrap over the measured frames
    /// of both, `profile::metrics::speedup_interval`).
    #[serde(default)]
    pub speedup_ci: [f64; 2],
    /// Means over the measured frames: PSNR over the covered pixels (those
    /// the shader draws), SSIM over the whole frame.
    pub psnr: f64,
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
    /// [0, 1] (`profile::metrics::flicker`).
    #[serde(default)]
    pub flicker: f64,
    /// Largest over the measured frames.
    pub max_abs_error: f64,
    pub above_threshold: f64,
    /// The share of the image the node covers (where it is computed),
    /// mean over the measured frames.
    #[serde(default)]
    pub coverage: f64,
    /// Shares of the covered pixels, means over the measured frames.
    pub hit_rate: f64,
    pub miss_rate: f64,
    pub offscreen_rate: f64,
    pub disocclusion_rate: f64,
    /// Missed because the cached payload was not finite (NaN, infinity,
    /// an rgba16float overflow).
    #[serde(default)]
    pub invalid_rate: f64,
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
    /// [`mark_pareto_fronts`]).
    #[serde(default)]
    pub pareto_psnr: bool,
    #[serde(default)]
    pub pareto_ssim: bool,
    pub frame_stats: Vec<FrameStats>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PassTime {
    pub name: String,
    pub time_ms: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FrameStats {
    pub time_ms: f64,
    /// Over the covered pixels.
    pub psnr: f64,
    /// Over the whole frame.
    #[serde(default)]
    pub psnr_frame: f64,
    /// Against the frame before ([`ResultRow::flicker`]); 0 for the first.
    #[serde(default)]
    pub flicker: f64,
    pub ssim: f64,
    /// Largest channel difference from the reference frame, in [0, 1].
    #[serde(default)]
    pub max_abs_error: f64,
    pub hit_rate: f64,
    pub miss_rate: f64,
    pub refresh_rate: f64,
}

/// An error budget: the mean PSNR (dB) or SSIM over the measured frames a
/// configuration must reach.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "metric", content = "at_least")]
pub enum Budget {
    Psnr(f64),
    Ssim(f64),
}

impl Budget {
    /// The budget when none is given: a picture a viewer would take for
    /// the original at a glance.
    pub const DEFAULT: Budget = Budget::Ssim(0.95);

    /// `row`'s error in this budget's metric (higher is better).
    fn metric(&self, row: &ResultRow) -> f64 {
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

/// Marks the rows on the Pareto front of GPU time against PSNR, and
/// against SSIM: those no other configuration beats on one without losing
/// on the other. The unmodified shader counts as a point (its time, an
/// exact image), so a configuration slower than the original is never on
/// a front.
pub fn mark_pareto_fronts(reference_ms: f64, rows: &mut [ResultRow]) {
    let front = |metric: fn(&ResultRow) -> f64, exact: f64| -> Vec<bool> {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (r.time_ms, metric(r)))
            .chain([(reference_ms, exact)])
            .collect();
        let dominated = |&(t, m): &(f64, f64)| {
            points
                .iter()
                .any(|&(u, n)| u <= t && n >= m && (u < t || n > m))
        };
        points[..rows.len()].iter().map(|p| !dominated(p)).collect()
    };
    let psnr = front(|r| r.psnr, f64::INFINITY);
    let ssim = front(|r| r.ssim, 1.0);
    for ((row, on_psnr), on_ssim) in rows.iter_mut().zip(psnr).zip(ssim) {
        row.pareto_psnr = on_psnr;
        row.pareto_ssim = on_ssim;
    }
}

impl ResultRow {
    /// Its knobs in words: `Δn = 32, k = 4, bilinear, rgba16float, ε = 0.02`.
    pub fn setting(&self) -> String {
        format!(
            "Δn = {}, k = {}, {}, {}, ε = {}",
            self.refresh_period,
            self.refresh_quad,
            self.reconstruction.as_str(),
            self.cache_format.as_str(),
            self.depth_epsilon
        )
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

    /// The answer from this run: the fastest configuration within
    /// `budget` whose speed-up interval lies above 1×, or none, with what
    /// came closest. The caller measures the winner again and settles the
    /// answer with [`Choice::confirm`].
    pub fn choose(&self, budget: Budget, budget_given: bool) -> Choice {
        let rows = &self.results;
        let faster = |i: &usize| rows[*i].speedup_ci[0] > 1.0;
        let fastest = |among: &mut dyn Iterator<Item = usize>| {
            among.min_by(|&a, &b| rows[a].time_ms.total_cmp(&rows[b].time_ms))
        };
        let within: Vec<usize> = (0..rows.len())
            .filter(|&i| budget.admits(&rows[i]))
            .collect();
        let winner = fastest(&mut within.iter().copied().filter(faster));
        let mut choice = Choice {
            budget,
            budget_given,
            result: winner,
            none_within_budget: within.is_empty(),
            closest: None,
            confirmation: None,
            reason: String::new(),
        };
        if let Some(i) = winner {
            choice.reason = format!(
                "the fastest of the {} configurations within {budget} whose speed-up interval lies above 1×: {}",
                within.len(),
                self.measured(&rows[i])
            );
            return choice;
        }
        // What came closest: within the budget, the fastest; else, of those
        // reliably faster, the least error; else the fastest of all.
        choice.closest = if within.is_empty() {
            (0..rows.len())
                .filter(faster)
                .max_by(|&a, &b| budget.metric(&rows[a]).total_cmp(&budget.metric(&rows[b])))
                .or_else(|| fastest(&mut (0..rows.len())))
        } else {
            fastest(&mut within.iter().copied())
        };
        let closest = choice
            .closest
            .map(|i| format!(" Closest: {}.", self.measured(&rows[i])))
            .unwrap_or_default();
        choice.reason = if rows.is_empty() {
            "no configuration could be measured: keep the original shader".into()
        } else if within.is_empty() {
            format!(
                "none of the {} configurations is within {budget}: keep the original shader.{closest}",
                rows.len()
            )
        } else {
            format!(
                "{} configurations are within {budget}, but none is faster than the original beyond this run's noise (a speed-up interval above 1×): keep the original shader.{closest}",
                within.len()
            )
        };
        choice
    }

    /// A row in words: node, variant, knobs, speed-up with its interval,
    /// error.
    pub fn measured(&self, row: &ResultRow) -> String {
        format!(
            "node {} `{}`, {}, {}: {:.3} ms against {:.3} ms for the original, {:.2}× [{:.2}, {:.2}], PSNR {:.1} dB, SSIM {:.4}",
            row.node,
            row.node_text,
            row.variant,
            row.setting(),
            row.time_ms,
            self.reference.time_ms,
            row.speedup,
            row.speedup_ci[0],
            row.speedup_ci[1],
            row.psnr,
            row.ssim
        )
    }
}

impl Choice {
    /// Settles the answer with the winner measured again: it stands only
    /// when that run's interval lies above 1× as well.
    pub fn confirm(&mut self, confirmation: Confirmation) {
        let again = format!(
            "measured again over {} frames, {:.3} ms against {:.3} ms, {:.2}× [{:.2}, {:.2}]",
            confirmation.frames,
            confirmation.time_ms,
            confirmation.reference_ms,
            confirmation.speedup,
            confirmation.speedup_ci[0],
            confirmation.speedup_ci[1]
        );
        if confirmation.speedup_ci[0] > 1.0 {
            self.reason = format!("{}; {again}", self.reason);
        } else {
            self.closest = self.result.take();
            self.reason = format!(
                "the run's winner ({}) is not faster than the original when {again}: keep the original shader",
                self.reason
            );
        }
        self.confirmation = Some(confirmation);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time_ms: f64, psnr: f64, ssim: f64) -> ResultRow {
        ResultRow {
            node: format!("n{time_ms}"),
            node_text: String::new(),
            variant: Variant::ThreePass,
            refresh_period: 32,
            refresh_quad: 4,
            reconstruction: Reconstruction::Bilinear,
            cache_format: CacheFormat::Rgba16float,
            depth_epsilon: 1e-3,
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

    #[test]
    fn the_front_keeps_the_rows_nothing_beats_on_both() {
        // Reference 10 ms. (5, 30) and (7, 35) trade off; (6, 29) loses to
        // (5, 30) on both; (8, 35) ties (7, 35) on PSNR but is slower;
        // (12, 40) is slower than the exact original.
        let mut rows = vec![
            row(5.0, 30.0, 0.90),
            row(6.0, 29.0, 0.95),
            row(7.0, 35.0, 0.93),
            row(8.0, 35.0, 0.99),
            row(12.0, 40.0, 0.999),
        ];
        mark_pareto_fronts(10.0, &mut rows);
        let psnr: Vec<bool> = rows.iter().map(|r| r.pareto_psnr).collect();
        assert_eq!(psnr, [true, false, true, false, false]);
        let ssim: Vec<bool> = rows.iter().map(|r| r.pareto_ssim).collect();
        assert_eq!(ssim, [true, true, false, true, false]);
    }

    #[test]
    fn equal_points_are_both_on_the_front() {
        let mut rows = vec![row(5.0, 30.0, 0.9), row(5.0, 30.0, 0.9)];
        mark_pareto_fronts(10.0, &mut rows);
        assert!(rows.iter().all(|r| r.pareto_psnr && r.pareto_ssim));
    }

    fn report(results: Vec<ResultRow>) -> Report {
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
            choice: None,
        }
    }

    #[test]
    fn answer_respects_its_budget() {
        let r = report(vec![
            row(5.0, 28.0, 0.90),
            row(7.0, 35.0, 0.93),
            row(6.0, 31.0, 0.99),
        ]);
        let pick = |budget| r.choose(budget, true).result;
        assert_eq!(pick(Budget::Psnr(30.0)), Some(2));
        assert_eq!(pick(Budget::Psnr(33.0)), Some(1));
        assert_eq!(pick(Budget::Ssim(0.95)), Some(2));
        assert_eq!(pick(Budget::Psnr(20.0)), Some(0));
        // The default budget is SSIM ≥ 0.95.
        assert_eq!(r.choose(Budget::DEFAULT, false).result, Some(2));
        let none = r.choose(Budget::Psnr(50.0), true);
        assert_eq!(none.result, None);
        assert!(none.none_within_budget);
        assert!(none.reason.contains("none of the 3"), "{}", none.reason);
        // Closest without the budget: the least error of those faster.
        assert_eq!(none.closest, Some(1));
    }

    #[test]
    fn answer_never_recommends_a_slowdown() {
        // Slower than the original: no answer, though within the budget.
        let r = report(vec![row(12.0, 35.0, 0.99)]);
        let choice = r.choose(Budget::Psnr(30.0), true);
        assert_eq!(choice.result, None);
        assert!(!choice.none_within_budget);
        assert_eq!(choice.closest, Some(0));
        assert!(
            choice.reason.contains("keep the original"),
            "{}",
            choice.reason
        );
        // Faster by its median, but its interval reaches below 1×: noise.
        let mut noisy = row(9.0, 35.0, 0.99);
        noisy.speedup_ci = [0.93, 1.25];
        let choice = report(vec![noisy]).choose(Budget::Psnr(30.0), true);
        assert_eq!(choice.result, None);
        assert!(
            choice.reason.contains("beyond this run's noise"),
            "{}",
            choice.reason
        );
    }

    #[test]
    fn a_winner_the_confirmatory_run_does_not_repeat_is_not_recommended() {
        let r = report(vec![row(5.0, 35.0, 0.99)]);
        let confirmation = |lo: f64| Confirmation {
            frames: 8,
            reference_ms: 10.0,
            time_ms: 9.0,
            speedup: 1.1,
            speedup_ci: [lo, 1.3],
        };
        let mut kept = r.choose(Budget::Psnr(30.0), true);
        kept.confirm(confirmation(1.02));
        assert_eq!(kept.result, Some(0));
        assert!(kept.reason.contains("measured again"), "{}", kept.reason);
        let mut dropped = r.choose(Budget::Psnr(30.0), true);
        dropped.confirm(confirmation(0.95));
        assert_eq!(dropped.result, None);
        assert_eq!(dropped.closest, Some(0));
        assert!(dropped.confirmation.is_some());
        assert!(
            dropped.reason.contains("keep the original"),
            "{}",
            dropped.reason
        );
    }

    #[test]
    fn budgets_parse() {
        assert_eq!("psnr:30".parse::<Budget>(), Ok(Budget::Psnr(30.0)));
        assert_eq!("SSIM=0.95".parse::<Budget>(), Ok(Budget::Ssim(0.95)));
        assert!("ssim:2".parse::<Budget>().is_err());
        assert!("psnr:NaN".parse::<Budget>().is_err());
        assert!("mse:1".parse::<Budget>().is_err());
        assert!("30".parse::<Budget>().is_err());
    }
}
