//! What `shadecache interpolate` writes: `report.json` (its schema in
//! `docs/report-interpolation-json.md`), `report.html` and the pictures of
//! each method's worst B-frame.

use std::fmt::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::Method;
use crate::report::plots::{self, Series};

/// Version of `report.json`'s format.
pub const FORMAT: u32 = 1;

/// The mean SSIM a method must keep for the report's answer to pick it.
pub const ANSWER_SSIM: f64 = 0.95;

#[derive(Clone, Debug, Serialize)]
/// What `interpolate` measured: every method against rendering every frame.
#[non_exhaustive]
pub struct Report {
    /// The report format's version.
    pub format: u32,
    /// The shader's path.
    pub shader: String,
    /// The scene's path.
    pub scene: String,
    /// What the scene is and how it moves, as the scene says.
    pub scene_description: String,
    /// The adapter the run drew on.
    pub adapter: String,
    /// Its driver and the driver's version (`llvmpipe Mesa 25.0.7 (LLVM
    /// 15.0.6)`): a software driver's figures are that driver's.
    #[serde(default)]
    pub driver: String,
    /// `gpu-timestamps`, or `cpu` where the device has no timestamp
    /// queries (then times include submission).
    pub timing: String,
    /// The frame's size in pixels.
    pub size: [u32; 2],
    /// n: displayed frames per I-frame interval.
    pub frames_per_interval: u32,
    /// Intervals measured (after one of warm-up).
    pub intervals: u32,
    /// The knobs the B-frame passes used.
    pub parameters: Parameters,
    /// Median time of a reference frame (ms).
    pub reference_ms: f64,
    /// Median time of the I-frame pass with both flows (ms).
    pub i_frame_ms: f64,
    /// The I-frames against the reference at the same time: the worst
    /// PSNR (dB, capped at 100). The I-frame is the user's shader with
    /// outputs added, so it must equal the reference.
    pub i_frame_psnr_min: f64,
    /// Each method's cost and error.
    pub methods: Vec<MethodReport>,
    /// SSIM of every displayed frame measured, per method.
    pub frames: Vec<DisplayedFrame>,
    /// What the reader should know of the run.
    pub notes: Vec<String>,
    /// How many frames can be skipped, with which method, at what cost.
    pub answer: String,
}

/// The knobs of the run, as the B-frame passes used them.
#[derive(Clone, Debug, Serialize)]
pub struct Parameters {
    /// m, ε1, ε2, the initialisations, half-velocity's knobs.
    #[serde(flatten)]
    pub options: super::Options,
    /// The flow targets' format.
    pub flow_format: String,
    /// How the flows were rendered.
    pub flows: String,
}

#[derive(Clone, Debug, Serialize)]
/// One method's cost against the reference and its error.
#[non_exhaustive]
pub struct MethodReport {
    /// The method.
    pub method: Method,
    /// n: displayed frames per I-frame interval.
    pub frames_per_interval: u32,
    /// T_I / T_ref: the I-frame's passes (with flows where the method
    /// reads them) over a reference frame.
    pub i_frame_time_ratio: f64,
    /// T_B / T_ref: one B-frame over a reference frame.
    pub b_frame_time_ratio: f64,
    /// (T_I + (n − 1)·T_B) / (n·T_ref).
    pub amortized_time_ratio: f64,
    /// Median B-frame time (ms); 0 for the reference.
    pub b_frame_ms: f64,
    /// Over the B-frames, against the reference at the same time.
    pub ssim_mean: f64,
    /// The worst B-frame's SSIM.
    pub ssim_min: f64,
    /// Mean PSNR over the B-frames (dB, capped at 100).
    pub psnr_mean: f64,
    /// Share of the B-frames' pixels with geometry in either I-frame that
    /// neither search found (image-based only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub double_miss_rate: Option<f64>,
    /// Image-based only: how far (pixels) its forward search's point in
    /// I-frame 0 is from the exact one the scene-assisted pass computes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub correspondence_error_px: Option<CorrespondenceError>,
    /// Latency it adds, in displayed frames: the B-frames of an interval
    /// wait for its closing I-frame when the method reads it; with
    /// `--partition` every method's I-frames are begun n − 1 frames
    /// before they are shown.
    pub added_latency_frames: f64,
    /// Its displayed frames' times: how even the frame rate is
    /// ([`super::partition::IntervalWork`]).
    pub displayed_frame_ms: FrameTimes,
    /// With `--motion-blur`: the motion-blurred composites around each
    /// I-frame against the reference's, mean SSIM and PSNR.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion_blur_ssim: Option<f64>,
    /// The motion-blurred composites' mean PSNR.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion_blur_psnr: Option<f64>,
    /// The displayed frame of its worst B-frame (lowest SSIM).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub worst_frame: Option<u32>,
    /// What an eye tracking the motion integrates over each interval's n
    /// displayed frames against the same of the reference: RMS over RGB,
    /// display values, mean over the intervals (`pursuit.rs` has the
    /// formula); 0 for the reference.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pursuit_error: Option<f64>,
    /// What the pursuit error cannot see: the change between consecutive
    /// displayed frames where the tracking eye is, against the
    /// reference's (RMS over RGB, display values, mean over the
    /// intervals; `pursuit.rs` has the formula); 0 for the reference.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flicker: Option<f64>,
    /// The extrapolators that compensate: the I-frame as they display it
    /// (its high frequencies amplified) against the reference, mean PSNR
    /// over the intervals (dB).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub displayed_i_frame_psnr: Option<f64>,
    /// Mean PSNR (dB, capped at 100) over the pixels within
    /// [`super::edges::EDGE_RADIUS_PX`] of a motion edge of each
    /// interval's I-frame 0, over the B-frames that have such pixels:
    /// where warping, searching and blurring fail, which the whole
    /// frame's PSNR dilutes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_psnr: Option<f64>,
    /// The extrapolators: an extrapolated frame with its share of the
    /// morph's preparation (spread over the n − 1 frames it serves), over
    /// a rendered frame. Seed 004's test is break-even, this below 1
    /// (Table 1: the operator pays "if rendering takes more than half of
    /// the total upsampling time"); 0.25 is the project's own target.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extrapolated_frame_ratio: Option<f64>,
}

/// The times of a method's displayed frames over the measured intervals.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct FrameTimes {
    /// Median, ms.
    pub median: f64,
    /// The slowest, ms.
    pub max: f64,
    /// max / median: 1 where every displayed frame costs the same.
    pub spread: f64,
    /// Whether the I-frames were drawn in parts (`--partition`).
    pub partitioned: bool,
}

impl FrameTimes {
    /// The median, maximum and spread of `times`.
    pub fn of(times: &[f64], partitioned: bool) -> FrameTimes {
        let median = crate::measure::metrics::median(times);
        let max = times.iter().copied().fold(0.0, f64::max);
        FrameTimes {
            median,
            max,
            spread: if median > 0.0 { max / median } else { 1.0 },
            partitioned,
        }
    }
}

/// 000 Fig. 11's correspondence error, mean pixels over the B-frames.
#[derive(Clone, Debug, Serialize)]
pub struct CorrespondenceError {
    /// Over every pixel the geometry covers (E_total^all).
    pub all: f64,
    /// Over those whose point I-frame 0 shows: where a correspondence
    /// exists (E_total^hit).
    pub hit: f64,
    /// E_total over every covered pixel of every measured B-frame: mean,
    /// 95th percentile, silhouettes and interiors, shares by range.
    pub total: Option<super::correspondence::Spread>,
    /// E_total of the correspondence image-based used, forward or
    /// backward as §5.2 chose, against the exact point in that I-frame.
    pub used: Option<super::correspondence::Spread>,
    /// E_lin, the linear-motion assumption's error: I-frame 0's point
    /// carried α of the way along its exact flow, against where it is at
    /// the B-frame's time.
    pub linear: Option<super::correspondence::Spread>,
}

#[derive(Clone, Debug, Serialize)]
/// One displayed frame's SSIM under every method.
pub struct DisplayedFrame {
    /// Its displayed frame.
    pub frame: u32,
    /// Where it is in its interval: 0 for an I-frame.
    pub alpha: f64,
    /// Per method, in the order of `methods`.
    pub ssim: Vec<f64>,
}

/// Each method's worst B-frame: (method, the reference, the B-frame), as
/// RGBA8; and the B-frames kept whole.
#[derive(Clone, Debug, Default)]
pub struct Pictures {
    /// Each method's worst B-frame and the reference at its time, RGBA8.
    pub worst: Vec<(Method, Vec<u8>, Vec<u8>)>,
    /// The B-frames kept whole (`keep_frames`, or the end points); with
    /// `keep_frames` also the I-frames the compensating extrapolators
    /// display (α = 0).
    pub kept: Vec<KeptFrame>,
    /// With `keep_frames`, every measured I-frame.
    pub iframes: Vec<KeptIFrame>,
}

/// An I-frame read back: its colour, depth buffer and flows, row-major.
#[derive(Clone, Debug)]
pub struct KeptIFrame {
    /// Its displayed frame.
    pub frame: u32,
    /// RGBA.
    pub color: Vec<f32>,
    /// Its depth buffer.
    pub depth: Vec<f32>,
    /// RGBA per pixel: Δx, Δy (pixels), Δz, valid; to the previous
    /// I-frame.
    pub flow_previous: Vec<f32>,
    /// The same to the next I-frame.
    pub flow_next: Vec<f32>,
}

/// A B-frame kept whole, with the reference of its time.
#[derive(Clone, Debug)]
pub struct KeptFrame {
    /// The method.
    pub method: Method,
    /// Its displayed frame.
    pub frame: u32,
    /// α: where it is in its interval.
    pub alpha: f64,
    /// Its error against the reference.
    pub error: crate::measure::metrics::FrameError,
    /// The reference at its time, RGBA linear.
    pub reference: Vec<f32>,
    /// The B-frame, RGBA linear.
    pub result: Vec<f32>,
    /// Each pixel's decision (`bframe::Decision` codes).
    pub decisions: Vec<u32>,
}

/// The answer: the cheapest method (amortised) whose mean SSIM is at
/// least [`ANSWER_SSIM`].
pub fn answer(methods: &[MethodReport], n: u32) -> String {
    let skipped = format!("{} of every {n} frames interpolated", n - 1);
    let best = methods
        .iter()
        .filter(|m| m.method != Method::Reference && m.ssim_mean >= ANSWER_SSIM)
        .min_by(|a, b| a.amortized_time_ratio.total_cmp(&b.amortized_time_ratio));
    let interpolated = match best {
        Some(m) if m.amortized_time_ratio < 1.0 => format!(
            "at n = {n} ({skipped}), {} costs {:.2}× of rendering every frame, with B-frames at mean SSIM {:.4} (worst {:.4}) and {} frame(s) of added latency",
            m.method.name(),
            m.amortized_time_ratio,
            m.ssim_mean,
            m.ssim_min,
            m.added_latency_frames
        ),
        Some(m) => format!(
            "at n = {n} ({skipped}), {} keeps mean SSIM {:.4} but costs {:.2}× of rendering every frame: render every frame",
            m.method.name(),
            m.ssim_mean,
            m.amortized_time_ratio
        ),
        None => format!(
            "at n = {n} ({skipped}), no method keeps mean SSIM ≥ {ANSWER_SSIM}: render every frame, or interpolate fewer"
        ),
    };
    match lag_free(methods) {
        Some(lag_free) => format!("{interpolated}; {lag_free}"),
        None => interpolated,
    }
}

/// The lag-free choice beside it: of the methods that add no latency
/// (frame repetition aside), the one an eye tracking the motion sees
/// nearest the reference (least pursuit error) among those cheaper than
/// rendering every frame, else the nearest of all; with frame
/// repetition's pursuit error to weigh it against.
fn lag_free(methods: &[MethodReport]) -> Option<String> {
    let lag_free: Vec<(&MethodReport, f64)> = methods
        .iter()
        .filter(|m| !matches!(m.method, Method::Reference | Method::SampleAndHold))
        .filter(|m| m.added_latency_frames == 0.0)
        .filter_map(|m| Some((m, m.pursuit_error?)))
        .collect();
    let nearest = |cheaper_only: bool| {
        lag_free
            .iter()
            .filter(|(m, _)| !cheaper_only || m.amortized_time_ratio < 1.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .copied()
    };
    let (best, error) = nearest(true).or_else(|| nearest(false))?;
    let hold = methods
        .iter()
        .find(|m| m.method == Method::SampleAndHold)
        .and_then(|m| m.pursuit_error);
    Some(format!(
        "with no added latency, {} costs {:.2}× with pursuit error {:.4}{}",
        best.method.name(),
        best.amortized_time_ratio,
        error,
        hold.map_or(String::new(), |h| format!(" (frame repetition's: {h:.4})"))
    ))
}

/// What not knowing the future costs the morph: `morph-past` (the
/// motion of the interval before, carried on) against `morph` (the
/// twin's exact motion), when both ran.
pub fn motion_difference(methods: &[MethodReport]) -> Option<String> {
    let find = |method: Method| methods.iter().find(|m| m.method == method);
    let (exact, past) = (find(Method::Morph)?, find(Method::MorphPast)?);
    let pursuit = |m: &MethodReport| {
        m.pursuit_error
            .map_or("—".to_string(), |e| format!("{e:.4}"))
    };
    Some(format!(
        "morph-past extrapolates the motion of the interval before, what an application that does not know its next frame has; morph uses the exact motion to the next I-frame (the next-frame twin): pursuit error {} against {}, B-frame SSIM {:.4} against {:.4}, PSNR {:.1} against {:.1} dB",
        pursuit(past),
        pursuit(exact),
        past.ssim_mean,
        exact.ssim_mean,
        past.psnr_mean,
        exact.psnr_mean
    ))
}

/// Writes each method's worst B-frame, its reference and their
/// difference (×4) as `images/<method>-{reference,result,difference}.png`.
pub fn write_images(
    dir: &Path,
    report: &Report,
    pictures: &Pictures,
) -> Result<Vec<PathBuf>, String> {
    let images = dir.join("images");
    crate::report::images::create_dir(&images)?;
    let mut written = Vec::new();
    for (method, reference, result) in &pictures.worst {
        let names = ["reference", "result", "difference"]
            .map(|what| format!("{}-{what}.png", method.name()));
        written.extend(crate::report::images::save_comparison(
            &images,
            names.each_ref().map(String::as_str),
            (reference, result),
            report.size,
        )?);
    }
    Ok(written)
}

/// The HTML report: the answer, the time ratios and errors per method,
/// SSIM per displayed frame (000's figs. 7–10), each method's worst
/// B-frame beside its reference.
pub fn html(report: &Report) -> String {
    let esc = plots::escape;
    let mut out = String::new();
    let _ = write!(
        out,
        "<!doctype html><meta charset=utf-8><title>shadecache interpolate: {}</title>\
         <style>body{{font-family:sans-serif;max-width:960px;margin:2em auto}}table{{border-collapse:collapse}}td,th{{padding:2px 8px;border-bottom:1px solid #ddd;text-align:right}}th:first-child,td:first-child{{text-align:left}}img{{image-rendering:pixelated;width:256px}}</style>\
         <h1>{} on {}</h1><p>{}{}×{}, n = {}, {} interval(s) measured, {}, {} ({}).</p><p><b>Answer:</b> {}</p>",
        esc(&report.shader),
        esc(&report.shader),
        esc(&report.scene),
        if report.scene_description.is_empty() {
            String::new()
        } else {
            format!("{}. ", esc(&report.scene_description))
        },
        report.size[0],
        report.size[1],
        report.frames_per_interval,
        report.intervals,
        esc(&report.adapter),
        esc(&report.driver),
        esc(&report.timing),
        esc(&report.answer),
    );
    let _ = write!(
        out,
        "<h2>Methods</h2><p>Reference frame {:.3} ms; I-frame with flows {:.3} ms (worst PSNR against the reference {:.1} dB). Latency: displayed frames a method delays the picture (the bidirectional ones wait for the next I-frame). Pursuit error: what an eye tracking the motion integrates over each interval's displayed frames on a hold-type display, against the same for the reference (RMS, display values; frame repetition's is the hold-type blur of rendering fewer frames). Flicker: the change between consecutive displayed frames where the tracking eye is, against the reference's (RMS, display values), which the pursuit error averages away. Near motion edges: PSNR over the pixels within 12 px of a motion edge of the interval's first I-frame. Extrapolated frame ×: an extrapolated frame with its share of the morph's preparation over a rendered frame (break-even below 1, seed 004's test; 0.25 is ours). Displayed frames: the median and slowest displayed frame (ms), an I-frame's whole or, with partitioning, spread in parts over the interval.</p>\
         <table><tr><th>method</th><th>I-frame ×</th><th>B-frame ×</th><th>amortised ×</th><th>SSIM mean</th><th>SSIM min</th><th>PSNR mean</th><th>double misses</th><th>latency (frames)</th><th>pursuit error</th><th>flicker</th><th>PSNR near motion edges</th><th>extrapolated frame ×</th><th>displayed frames (ms)</th></tr>",
        report.reference_ms, report.i_frame_ms, report.i_frame_psnr_min
    );
    for m in &report.methods {
        let _ = write!(
            out,
            "<tr><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{:.4}</td><td>{:.4}</td><td>{:.1}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3} median, {:.3} slowest ({:.2}×{})</td></tr>",
            m.method.name(),
            m.i_frame_time_ratio,
            m.b_frame_time_ratio,
            m.amortized_time_ratio,
            m.ssim_mean,
            m.ssim_min,
            m.psnr_mean,
            m.double_miss_rate
                .map_or("—".to_string(), |r| format!("{:.2}%", r * 100.0)),
            m.added_latency_frames,
            m.pursuit_error
                .map_or("—".to_string(), |e| format!("{e:.4}")),
            m.flicker.map_or("—".to_string(), |e| format!("{e:.4}")),
            m.edge_psnr.map_or("—".to_string(), |p| format!("{p:.1}")),
            m.extrapolated_frame_ratio
                .map_or("—".to_string(), |r| format!("{r:.3}")),
            m.displayed_frame_ms.median,
            m.displayed_frame_ms.max,
            m.displayed_frame_ms.spread,
            if m.displayed_frame_ms.partitioned {
                ", in parts"
            } else {
                ""
            },
        );
    }
    out.push_str("</table>");
    let series: Vec<Series> = report
        .methods
        .iter()
        .enumerate()
        .map(|(i, m)| Series {
            name: m.method.name().into(),
            points: report
                .frames
                .iter()
                .map(|f| (f64::from(f.frame), f.ssim[i]))
                .collect(),
            line: true,
            ..Series::default()
        })
        .collect();
    out.push_str("<h2>SSIM per displayed frame</h2>");
    out.push_str(&plots::chart(
        "SSIM against the reference at the same time (I-frames every n frames)",
        "displayed frame",
        "SSIM",
        &series,
        None,
    ));
    out.push_str("<h2>Worst B-frame per method</h2><p>Reference, result, difference ×4.</p>");
    for m in &report.methods {
        if let Some(frame) = m.worst_frame {
            let name = m.method.name();
            let _ = write!(
                out,
                "<h3>{name}, frame {frame}</h3><img src=\"images/{name}-reference.png\"> <img src=\"images/{name}-result.png\"> <img src=\"images/{name}-difference.png\">"
            );
        }
    }
    if !report.notes.is_empty() {
        out.push_str("<h2>Notes</h2><ul>");
        for note in &report.notes {
            let _ = write!(out, "<li>{}</li>", esc(note));
        }
        out.push_str("</ul>");
    }
    out
}
