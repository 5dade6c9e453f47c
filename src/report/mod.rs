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

/// The fastest configuration within an error budget.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Choice {
    pub budget: Budget,
    /// Index into `results`; none when no configuration is both within the
    /// budget and faster than the original shader.
    pub result: Option<usize>,
    /// Why this one, or why none.
    pub reason: String,
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
    /// P/T measured: the payload pass (the node's slice alone, every pixel)
    /// over the reference.
    pub p_over_t: f64,
    /// Median time of that payload pass, ms.
    pub payload_ms: f64,
    /// Bounds of the node's value over the scene's frames, by interval
    /// arithmetic with the uniform values the scene gives; `null` ends are
    /// unbounded.
    #[serde(default)]
    pub range: [Option<f64>; 2],
    /// Whether those bounds fit an rgba16float cache; when not, a
    /// three-pass cache runs in rgba32float.
    #[serde(default)]
    pub fits_f16: bool,
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
    /// Median frame time (sum of the passes), ms.
    pub time_ms: f64,
    /// Median time of each pass, ms.
    pub passes: Vec<PassTime>,
    /// Reference time over this variant's time, from the same run.
    pub speedup: f64,
    /// Means over the measured frames.
    pub psnr: f64,
    pub ssim: f64,
    /// Largest over the measured frames.
    pub max_abs_error: f64,
    pub above_threshold: f64,
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
    /// Measured P/T of the node (see [`NodeReport::p_over_t`]).
    pub p_over_t: f64,
    /// 1 / (1 − ρ·f) with ρ the hit rate (reuse fraction) and f = P/T.
    pub ideal_speedup: f64,
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
    pub psnr: f64,
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

    /// The fastest result within `budget` that is faster than the
    /// original shader.
    pub fn choose(&self, budget: Budget) -> Choice {
        let within: Vec<usize> = (0..self.results.len())
            .filter(|&i| budget.admits(&self.results[i]))
            .collect();
        let fastest = within
            .iter()
            .copied()
            .min_by(|&a, &b| self.results[a].time_ms.total_cmp(&self.results[b].time_ms));
        let (result, reason) = match fastest {
            Some(i) if self.results[i].speedup > 1.0 => {
                let row = &self.results[i];
                (
                    Some(i),
                    format!(
                        "the fastest of {} configurations within {budget}: {:.3} ms against {:.3} ms for the original ({:.2}×), PSNR {:.1} dB, SSIM {:.4}",
                        within.len(),
                        row.time_ms,
                        self.reference.time_ms,
                        row.speedup,
                        row.psnr,
                        row.ssim
                    ),
                )
            }
            Some(i) => (
                None,
                format!(
                    "{} configurations are within {budget}, but the fastest of them ({:.3} ms) is not faster than the original ({:.3} ms): keep the original shader",
                    within.len(),
                    self.results[i].time_ms,
                    self.reference.time_ms
                ),
            ),
            None => (
                None,
                format!(
                    "none of the {} configurations is within {budget}: keep the original shader",
                    self.results.len()
                ),
            ),
        };
        Choice {
            budget,
            result,
            reason,
        }
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
            psnr,
            ssim,
            max_abs_error: 0.0,
            above_threshold: 0.0,
            hit_rate: 0.0,
            miss_rate: 0.0,
            offscreen_rate: 0.0,
            disocclusion_rate: 0.0,
            invalid_rate: 0.0,
            refresh_rate: 0.0,
            p_over_t: 0.0,
            ideal_speedup: 1.0,
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
                frame_ms: vec![10.0],
            },
            nodes: Vec::new(),
            results,
            miss_causes: Vec::new(),
            grid: None,
            choice: None,
        }
    }

    #[test]
    fn the_choice_is_the_fastest_within_the_budget() {
        let r = report(vec![
            row(5.0, 28.0, 0.90),
            row(7.0, 35.0, 0.93),
            row(6.0, 31.0, 0.99),
        ]);
        assert_eq!(r.choose(Budget::Psnr(30.0)).result, Some(2));
        assert_eq!(r.choose(Budget::Psnr(33.0)).result, Some(1));
        assert_eq!(r.choose(Budget::Ssim(0.95)).result, Some(2));
        assert_eq!(r.choose(Budget::Psnr(20.0)).result, Some(0));
        let none = r.choose(Budget::Psnr(50.0));
        assert_eq!(none.result, None);
        assert!(none.reason.contains("none of the 3"), "{}", none.reason);
    }

    #[test]
    fn a_choice_slower_than_the_original_is_no_choice() {
        let r = report(vec![row(12.0, 35.0, 0.99)]);
        let choice = r.choose(Budget::Psnr(30.0));
        assert_eq!(choice.result, None);
        assert!(
            choice.reason.contains("keep the original"),
            "{}",
            choice.reason
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
