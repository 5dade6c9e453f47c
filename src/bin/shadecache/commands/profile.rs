//! `shadecache profile`: run the variants on a scene, measure time and
//! error against the unmodified shader, rank the nodes, write a report.

use std::path::PathBuf;

use shadecache::diagnostic::{Color, Diagnostic, Error};
use shadecache::front;
use shadecache::profile::{self, Nodes, Options, Progress};
use shadecache::report;
use shadecache::rewrite::{CacheFormat, Variant};
use shadecache::scene::Scene;

use super::rewrite::{CacheFormatArg, ReconstructionArg, VariantArg};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The WGSL shader to profile.
    pub shader: PathBuf,

    /// The scene to render (TOML; see docs/scene-toml.md).
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: PathBuf,

    /// Nodes to profile: `all`, `top:N` (highest estimated P/T) or ids separated by commas.
    #[arg(long, value_name = "all|top:N|ID,...", default_value = "top:3")]
    pub nodes: String,

    /// Which variants to run.
    #[arg(long, value_enum, default_value_t = VariantArg::All)]
    pub variant: VariantArg,

    /// Refresh periods Δn to measure, separated by commas (0 turns refresh off).
    #[arg(
        long,
        value_name = "N,...",
        value_delimiter = ',',
        default_value = "32"
    )]
    pub refresh_period: Vec<u32>,

    /// Refresh block sizes k to measure, separated by commas.
    #[arg(long, value_name = "K,...", value_delimiter = ',', default_value = "4")]
    pub refresh_quad: Vec<u32>,

    /// Texture format of the payload cache.
    #[arg(long, value_enum, default_value_t = CacheFormatArg::Rgba16float)]
    pub cache_format: CacheFormatArg,

    /// ε of the cache's depth test, relative: about the share of a point's
    /// distance by which two surfaces must differ to be told apart.
    #[arg(long, value_name = "E", default_value_t = shadecache::rewrite::DEFAULT_DEPTH_EPSILON, value_parser = super::rewrite::epsilon)]
    pub depth_epsilon: f32,

    /// Reconstructions to measure, separated by commas.
    #[arg(
        long,
        value_name = "bilinear,nearest",
        value_enum,
        value_delimiter = ',',
        default_value = "bilinear"
    )]
    pub reconstruction: Vec<ReconstructionArg>,

    /// Frames to measure (default: the scene's).
    #[arg(long, value_name = "N")]
    pub frames: Option<u32>,

    /// Warm-up frames, not measured (default: the scene's).
    #[arg(long, value_name = "N")]
    pub warmup: Option<u32>,

    /// Frame size (default: the scene's).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<[u32; 2]>,

    /// Where to write report.json, report.html and the pictures.
    #[arg(long, value_name = "DIR", default_value = "shadecache-report")]
    pub out: PathBuf,

    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

fn parse_size(text: &str) -> Result<[u32; 2], String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or("expected WIDTHxHEIGHT, e.g. 256x256")?;
    let parse = |s: &str| s.trim().parse::<u32>().map_err(|e| format!("`{s}`: {e}"));
    let size = [parse(w)?, parse(h)?];
    if size.iter().any(|&v| v == 0 || v > 8192) {
        return Err("sizes go from 1 to 8192".into());
    }
    Ok(size)
}

fn parse_nodes(text: &str) -> Result<Nodes, Error> {
    let text = text.trim();
    if text == "all" {
        return Ok(Nodes::All);
    }
    if let Some(n) = text.strip_prefix("top:") {
        return n
            .parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .map(Nodes::Top)
            .ok_or_else(|| {
                Error::plain(Diagnostic::error(format!(
                    "`--nodes {text}`: top:N needs a positive N"
                )))
            });
    }
    Ok(Nodes::Ids(
        text.split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect(),
    ))
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
struct Bar {
    bar: Option<indicatif::ProgressBar>,
    quiet: bool,
}

impl Progress for Bar {
    fn start(&mut self, total: u64) {
        if self.quiet {
            return;
        }
        let bar = indicatif::ProgressBar::new(total);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} frames, {eta} left — {msg}",
        ) {
            bar.set_style(style);
        }
        self.bar = Some(bar);
    }

    fn step(&mut self, what: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(what.to_string());
            bar.inc(1);
        }
    }

    fn refused(&mut self, what: &str, reason: &str) {
        let line = format!("warning: refused: {what}: {reason}");
        match &self.bar {
            Some(bar) => bar.println(line),
            None => eprintln!("{line}"),
        }
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

pub fn exec(args: Args, _color: Color) -> Result<(), Error> {
    let shader = front::load(&args.shader)?;
    let scene = Scene::load(&args.scene)?;
    let options = Options {
        nodes: parse_nodes(&args.nodes)?,
        variants: match args.variant {
            VariantArg::OnePass => vec![Variant::OnePass],
            VariantArg::TwoPass => vec![Variant::TwoPass],
            VariantArg::ThreePass => vec![Variant::ThreePass],
            VariantArg::All => Variant::ALL.to_vec(),
        },
        refresh_periods: args.refresh_period.clone(),
        refresh_quads: args.refresh_quad.iter().map(|&k| k.max(1)).collect(),
        cache_format: match args.cache_format {
            CacheFormatArg::Rgba16float => CacheFormat::Rgba16float,
            CacheFormatArg::Rgba32float => CacheFormat::Rgba32float,
        },
        depth_epsilon: args.depth_epsilon,
        reconstructions: args.reconstruction.iter().map(|&r| r.into()).collect(),
        frames: args.frames,
        warmup: args.warmup,
        size: args.size,
        command: std::env::args().collect::<Vec<_>>().join(" "),
        ..Options::default()
    };
    let mut bar = Bar {
        bar: None,
        quiet: args.quiet,
    };
    let (report, pictures) = profile::profile(&shader, &scene, &args.scene, &options, &mut bar)?;

    let io = |what: &str, err: String| {
        Error::plain(Diagnostic::error(format!("cannot write {what}: {err}")))
    };
    std::fs::create_dir_all(&args.out).map_err(|e| io("the report folder", e.to_string()))?;
    report::write_images(&args.out, &report, &pictures).map_err(|e| io("the pictures", e))?;
    let json =
        serde_json::to_string_pretty(&report).map_err(|e| io("report.json", e.to_string()))?;
    std::fs::write(args.out.join("report.json"), json + "\n")
        .map_err(|e| io("report.json", e.to_string()))?;
    std::fs::write(
        args.out.join("report.html"),
        report::html(&report, &args.out),
    )
    .map_err(|e| io("report.html", e.to_string()))?;
    // The last frame's GPU scopes, for chrome://tracing or Perfetto.
    wgpu_profiler::chrometrace::write_chrometrace(&args.out.join("trace.json"), &pictures.trace)
        .map_err(|e| io("trace.json", e.to_string()))?;

    let mut summary = format!(
        "{} on {} ({}×{}, {} frames, {}): reference {:.3} ms\n",
        report.shader,
        report.scene,
        report.size[0],
        report.size[1],
        report.frames,
        report.device.name,
        report.reference.time_ms
    );
    for row in report.best_per_variant() {
        summary.push_str(&format!(
            "  {:<10} {} `{}`: {:.2}× (ideal {:.2}×, P/T {:.2}, hit {:.0}% miss {:.0}% refresh {:.0}%), PSNR {:.1} dB, SSIM {:.4}\n",
            row.variant.as_str(),
            row.node,
            row.node_text,
            row.speedup,
            row.ideal_speedup,
            row.p_over_t,
            row.hit_rate * 100.0,
            row.miss_rate * 100.0,
            row.refresh_rate * 100.0,
            row.psnr,
            row.ssim
        ));
    }
    for cause in &report.miss_causes {
        summary.push_str(&format!(
            "  misses with {:?} alone: {:.2}% ({:.2}% off-screen, {:.2}% disoccluded)\n",
            cause.effect,
            cause.miss_rate * 100.0,
            cause.offscreen_rate * 100.0,
            cause.disocclusion_rate * 100.0
        ));
    }
    summary.push_str(&format!(
        "report: {}\n",
        args.out.join("report.html").display()
    ));
    super::write_stdout(&summary)
}
