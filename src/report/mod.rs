//! runs → reports: what a profile found, as JSON (`report.json`, schema
//! in `docs/report-json.md`), as a self-contained HTML page with tables and
//! SVG plots, and as PNG maps of the cache's decisions.

mod html;
mod images;
mod plots;

use serde::{Deserialize, Serialize};

use crate::rewrite::{Reconstruction, Variant};
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
    pub effects: Vec<Effect>,
    pub size: [u32; 2],
    /// Frames measured (after the warm-up).
    pub frames: u32,
    pub warmup: u32,
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
    /// One row per node × variant × Δn × k, fastest first.
    pub results: Vec<ResultRow>,
    /// What causes the misses of the fastest configuration: the scene
    /// again with one declared effect at a time. Refreshes are caused by
    /// the refresh pattern alone (Δn, k) and are not listed.
    #[serde(default)]
    pub miss_causes: Vec<MissCause>,
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
    pub cache_format: String,
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
