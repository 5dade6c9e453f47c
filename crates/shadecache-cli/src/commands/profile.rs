//! `shadecache profile`: run the variants on a scene, measure time and
//! error against the unmodified shader, rank the nodes, write a report.

use std::path::PathBuf;

use shadecache::back::{self, Language};
use shadecache::diagnostic::{Color, Diagnostic, Error};
use shadecache::profile::{self, Budget, Nodes, Options, Progress};
use shadecache::report;

use super::rewrite::{CacheFormatArg, CacheReadArg, UpsamplerArg, VariantArg};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The WGSL shader to profile.
    pub shader: PathBuf,

    /// The scene to render (TOML; see docs/scene-toml.md). Without one, a
    /// default scene: a lit, rotating sphere under an orbiting camera, the
    /// shader's matrices found from its vertex stage and every other
    /// binding a neutral value, listed (`shadecache scene init` writes it).
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: Option<PathBuf>,

    /// Nodes to profile: `all`, `top:N` (highest estimated P/T) or ids separated by commas.
    #[arg(long, value_name = "all|top:N|ID,...", default_value = "top:3")]
    pub nodes: String,

    /// Which variants to run, separated by commas.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "all")]
    pub variant: Vec<VariantArg>,

    /// Refresh periods Δn to measure, separated by commas (0 turns refresh
    /// off; at most 65535) [default: 32; with --sweep 4,8,16,32,64].
    #[arg(long, value_name = "N,...", value_delimiter = ',', value_parser = clap::value_parser!(u32).range(0..=shadecache::rewrite::MAX_REFRESH_PERIOD as i64))]
    pub refresh_period: Option<Vec<u32>>,

    /// Refresh block sizes k to measure, separated by commas [default: 4;
    /// with --sweep 1,2,4,8].
    #[arg(long, value_name = "K,...", value_delimiter = ',')]
    pub refresh_quad: Option<Vec<u32>>,

    /// Texture formats of the payload cache to measure [default:
    /// rgba16float; with --sweep both].
    #[arg(long, value_enum, value_name = "FORMAT,...", value_delimiter = ',')]
    pub cache_format: Option<Vec<CacheFormatArg>>,

    /// ε values of the cache's depth test to measure, relative: about the
    /// share of a point's distance by which two surfaces must differ to be
    /// told apart [default: 0.02; with --sweep 0.005,0.02,0.08].
    #[arg(long, value_name = "E,...", value_delimiter = ',', value_parser = super::rewrite::epsilon)]
    pub depth_epsilon: Option<Vec<f32>>,

    /// Reconstructions to measure, separated by commas: bilinear, nearest,
    /// bilinear-packed, nearest-packed (the packed ones keep the depth in
    /// the payload's fourth channel) [default: bilinear; with --sweep all
    /// four].
    #[arg(long, value_name = "R,...", value_delimiter = ',', value_parser = CacheReadArg::parse)]
    pub reconstruction: Option<Vec<CacheReadArg>>,

    /// How lowres rebuilds the payload from its samples, separated by
    /// commas: nearest, bilinear, spatial, temporal, spatio-temporal
    /// [default: spatio-temporal; with --sweep all five].
    #[arg(long, value_name = "R,...", value_enum, value_delimiter = ',')]
    pub lowres_reconstruction: Option<Vec<UpsamplerArg>>,

    #[command(flatten)]
    pub upsampling: super::rewrite::UpsamplingArgs,

    /// Adaptive refresh: the cache variants refresh a value that changed by
    /// 10% since it was cached after Δn/4 frames instead of Δn, and lowres
    /// shades its unreliable pixels at full resolution [default: off; with
    /// --sweep both ways].
    #[arg(long)]
    pub adaptive_refresh: bool,

    /// Sweep accuracy against time: every knob over its sweep values (lists
    /// given explicitly are kept), pruned with the cost model and by
    /// measuring the refresh and read-back planes (docs/accuracy.md).
    #[arg(long)]
    pub sweep: bool,

    /// Measure only the K-th of N deterministic slices of the grid (each
    /// with its own reference run), for a sweep spread over machines;
    /// `shadecache merge` joins the shards' reports.
    #[arg(long, value_name = "K/N", value_parser = shadecache::report::Shard::parse)]
    pub shard: Option<shadecache::report::Shard>,

    /// An error budget, `psnr:DB` or `ssim:S` (mean over the measured
    /// frames): pick the fastest configuration within it and write its
    /// shaders and plan to DIR/choice.
    #[arg(long, value_name = "psnr:DB|ssim:S", value_parser = clap::value_parser!(Budget))]
    pub max_error: Option<Budget>,

    /// Frames to measure, 1 to 10000 (default: the scene's).
    #[arg(long, value_name = "N", value_parser = frame_count)]
    pub frames: Option<u32>,

    /// Warm-up frames, not measured (default: the scene's, and at least
    /// the longest refresh period, so that errors are measured in the
    /// cache's steady state); at most 10000.
    #[arg(long, value_name = "N", value_parser = warmup_count)]
    pub warmup: Option<u32>,

    /// Frame size (default: the scene's).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<[u32; 2]>,

    /// Where to write report.json, report.html and the pictures.
    #[arg(long, value_name = "DIR", default_value = "shadecache-report")]
    pub out: PathBuf,

    /// Write into an --out folder that holds files a previous run did not
    /// list as its own (they stay; files of the same names are replaced).
    /// Without it, such a folder is refused before anything runs.
    #[arg(long)]
    pub overwrite: bool,

    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,

    #[command(flatten)]
    pub stages: super::StageArgs,
}

/// A count of measured frames: 1 to [`MAX_FRAMES`](shadecache::scene::bounds::MAX_FRAMES).
pub(super) fn frame_count(text: &str) -> Result<u32, String> {
    let max = shadecache::scene::bounds::MAX_FRAMES;
    match text.trim().parse::<u32>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("a frame count is a whole number from 1 to {max}")),
    }
}

/// A count of warm-up frames: 0 to [`MAX_FRAMES`](shadecache::scene::bounds::MAX_FRAMES).
fn warmup_count(text: &str) -> Result<u32, String> {
    let max = shadecache::scene::bounds::MAX_FRAMES;
    match text.trim().parse::<u32>() {
        Ok(n) if n <= max => Ok(n),
        _ => Err(format!(
            "a warm-up is a whole number of frames from 0 to {max}"
        )),
    }
}

pub(super) fn parse_size(text: &str) -> Result<[u32; 2], String> {
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
pub(super) struct Bar {
    pub bar: Option<indicatif::ProgressBar>,
    pub quiet: bool,
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

pub fn exec(args: Args, color: Color) -> Result<(), Error> {
    let out = crate::out_folder::OutFolder::check(&args.out, args.overwrite)?;
    // Entry points that could not be profiled, beside those that were: an
    // error once the reports of the others are kept.
    let mut failed = None;
    out.run(|out| profile_into(&args, color, out, &mut failed))?;
    failed.map_or(Ok(()), Err)
}

/// The profile of each fragment entry point, written into `out`;
/// `failed` is set when some could not be profiled.
fn profile_into(
    args: &Args,
    color: Color,
    out: &crate::out_folder::OutFolder,
    failed_entries: &mut Option<Error>,
) -> Result<(), Error> {
    let shader = args.stages.load(&args.shader)?;
    // Every fragment entry point in turn, unless `--entry` names one:
    // each into `OUT/<entry>/`, with an index in OUT.
    let analyses = shadecache::analysis::analyze_entries(
        &shader,
        &shadecache::analysis::Options {
            entry: args.stages.entry.clone(),
            ..Default::default()
        },
    )?;
    if analyses.len() == 1 {
        let (_, summary) = profile_entry(args, &shader, &args.stages, out, &args.out)?;
        return super::write_stdout(&summary);
    }
    let mut sections = Vec::new();
    let mut failed = Vec::new();
    for analysis in &analyses {
        let entry = &analysis.entry;
        let stages = super::StageArgs {
            entry: Some(entry.clone()),
            ..args.stages.clone()
        };
        let entry_out = args.out.join(entry);
        super::write_stdout(&format!("entry point `{entry}`:\n"))?;
        // An entry point with nothing to cache (a flat-colour wireframe
        // pass) is an answer, not a failure.
        if analysis.candidates.is_empty() {
            let why = "no cache candidates: it computes nothing a cache could keep (see `shadecache analyze --all`)".to_string();
            super::write_stdout(&format!("  {why}\n"))?;
            sections.push(report::EntrySection {
                entry: entry.clone(),
                outcome: Err(why),
            });
            continue;
        }
        match profile_entry(args, &shader, &stages, out, &entry_out) {
            Ok((report, summary)) => {
                super::write_stdout(&summary)?;
                sections.push(report::EntrySection {
                    entry: entry.clone(),
                    outcome: Ok(*report),
                });
            }
            Err(err) => {
                err.emit_to_stderr(color);
                failed.push(format!("`{entry}`"));
                sections.push(report::EntrySection {
                    entry: entry.clone(),
                    outcome: Err(err.render()),
                });
            }
        }
    }
    out.clear()?;
    super::write_report(
        &args.out,
        &report::entry_index(&shader.file.path, &sections),
        || Ok(Vec::new()),
        || report::entry_index_html(&shader.file.path, &sections),
    )?;
    super::write_stdout(&format!(
        "report: {} (one section per entry point)\n",
        args.out.join("report.html").display()
    ))?;
    if !failed.is_empty() {
        *failed_entries = Some(Error::plain(Diagnostic::error(format!(
            "{} of {} fragment entry points could not be profiled: {} (see above)",
            failed.len(),
            analyses.len(),
            failed.join(", ")
        ))));
    }
    Ok(())
}

/// The profile's options from the command line (a sweep's grid under
/// what was given).
fn options(args: &Args, stages: &super::StageArgs) -> Result<Options, Error> {
    note_unused_flags(args);
    let defaults = if args.sweep {
        Options::default().sweep()
    } else {
        Options::default()
    };
    Ok(Options {
        entry: stages.entry.clone(),
        vertex_entry: stages.vertex_entry.clone(),
        nodes: parse_nodes(&args.nodes)?,
        variants: VariantArg::variants(&args.variant),
        refresh_periods: args
            .refresh_period
            .clone()
            .unwrap_or(defaults.refresh_periods),
        refresh_quads: args
            .refresh_quad
            .as_ref()
            .map(|quads| quads.iter().map(|&k| k.max(1)).collect())
            .unwrap_or(defaults.refresh_quads),
        cache_formats: args
            .cache_format
            .as_ref()
            .map(|formats| formats.iter().map(|&f| f.into()).collect())
            .unwrap_or(defaults.cache_formats),
        depth_epsilons: args
            .depth_epsilon
            .clone()
            .unwrap_or(defaults.depth_epsilons),
        reconstructions: args
            .reconstruction
            .as_ref()
            .map(|r| r.iter().map(|&r| r.into()).collect())
            .unwrap_or(defaults.reconstructions),
        lowres_reconstructions: args
            .lowres_reconstruction
            .as_ref()
            .map(|r| r.iter().map(|&r| r.into()).collect())
            .unwrap_or(defaults.lowres_reconstructions),
        upsampling: args.upsampling.upsampling()?,
        // Adaptive refresh: on when asked, both ways in a sweep.
        adaptive_refresh: if args.upsampling.reshade_unreliable || args.adaptive_refresh {
            vec![true]
        } else {
            defaults.adaptive_refresh
        },
        max_error: args.max_error,
        shard: args.shard,
        frames: args.frames,
        warmup: args.warmup,
        size: args.size,
        command: std::env::args().collect::<Vec<_>>().join(" "),
        ..defaults
    })
}

/// A note for the knobs given that no variant asked for reads: lowres's
/// without lowres, the cache variants' with lowres alone (its Δn is s²,
/// its k is s, it reads no cache back and tests no depth with ε).
fn note_unused_flags(args: &Args) {
    let variants = VariantArg::variants(&args.variant);
    if !variants.iter().any(|v| v.upsamples()) {
        let mut given = args.upsampling.given();
        if args.lowres_reconstruction.is_some() {
            given.push("--lowres-reconstruction");
        }
        super::rewrite::note_unused(&given, super::rewrite::LOWRES_KNOBS_UNUSED);
    }
    let refresh_off = args
        .refresh_period
        .as_ref()
        .is_some_and(|periods| periods.iter().all(|&p| p == 0));
    if args.adaptive_refresh && refresh_off && !variants.iter().any(|v| v.upsamples()) {
        super::rewrite::note_unused(
            &["--adaptive-refresh"],
            "it refreshes changed values early, and --refresh-period 0 turns refresh off",
        );
    }
    if variants.iter().all(|v| v.upsamples()) {
        let given: Vec<&str> = [
            ("--refresh-period", args.refresh_period.is_some()),
            ("--refresh-quad", args.refresh_quad.is_some()),
            ("--reconstruction", args.reconstruction.is_some()),
            ("--depth-epsilon", args.depth_epsilon.is_some()),
        ]
        .into_iter()
        .filter_map(|(flag, given)| given.then_some(flag))
        .collect();
        super::rewrite::note_unused(
            &given,
            "the cache variants' knobs, and lowres alone is asked for (its Δn is s², its k is s)",
        );
    }
}

/// What the terminal says of a profile: the reference, its check, the
/// warnings, the best of each variant, the defaults, the miss causes and
/// what the grid left out.
/// Lowres's line: its knobs, and what its classes mean for it (pixels
/// shaded this frame, history reused, history missing).
fn lowres_line(report: &report::Report, row: &report::ResultRow) -> String {
    let knobs = report
        .upsampling
        .as_ref()
        .map_or(String::new(), |u| format!("{}, ", u.in_words()));
    format!(
        "  {:<15} {} `{}`: {:.2}× [{:.2}, {:.2}] ({knobs}{}{}, {:.2}× with its fixed costs, P/T {:.2}, shaded this frame {:.0}%, history reused {:.0}%, history missing {:.0}%), {}\n",
        row.variant.as_str(),
        row.node,
        row.node_text,
        row.speedup,
        row.speedup_ci[0],
        row.speedup_ci[1],
        row.reconstruction.as_str(),
        row.adaptive_words(),
        row.bound_with_fixed_costs,
        row.p_over_t,
        row.refresh_rate * 100.0,
        row.hit_rate * 100.0,
        row.miss_rate * 100.0,
        quality(row)
    )
}

/// A row's error against the reference, in words.
fn quality(row: &report::ResultRow) -> String {
    format!(
        "PSNR {:.1} dB over the covered pixels (worst frame {:.1}), SSIM {:.4}, flicker {:.4}",
        row.psnr, row.worst_psnr, row.ssim, row.flicker
    )
}

/// Defaulted inputs shown in the summary; an engine's shader defaults
/// thousands (every element of its mesh and light arrays).
const DEFAULTED_SHOWN: usize = 24;

/// The summary's lines naming the inputs nothing said the value of: the
/// first [`DEFAULTED_SHOWN`] and how many more (none when none).
fn defaulted_lines(defaulted: &[String]) -> String {
    if defaulted.is_empty() {
        return String::new();
    }
    let shown = &defaulted[..defaulted.len().min(DEFAULTED_SHOWN)];
    let mut lines = format!(
        "  defaulted (nothing said what they are; `shadecache scene init` writes them out to edit):\n    {}\n",
        shown.join("\n    ")
    );
    let more = defaulted.len() - shown.len();
    if more > 0 {
        lines.push_str(&format!(
            "    … and {more} more (report.json's `defaulted` lists every one)\n"
        ));
    }
    lines
}

fn summary(report: &report::Report) -> String {
    let mut summary = format!(
        "{} on {} ({}×{}, {} frames after {} warm-up, {}): reference {:.3} ms (frames {:.3}–{:.3})\n",
        report.shader,
        report.scene,
        report.size[0],
        report.size[1],
        report.frames,
        report.warmup,
        report.device.describe(),
        report.reference.time_ms,
        report.reference.spread_ms[0],
        report.reference.spread_ms[1]
    );
    if let Some(check) = &report.reference_check {
        summary.push_str(&format!("  reference check: {}\n", check.summary()));
        for problem in &check.problems {
            summary.push_str(&format!(
                "  warning: degenerate reference: {}. Likely cause: {}\n",
                problem.finding, problem.cause
            ));
        }
    }
    for warning in &report.warnings {
        summary.push_str(&format!("  warning: {warning}\n"));
    }
    for row in report.best_per_variant() {
        if row.variant.upsamples() {
            summary.push_str(&lowres_line(report, row));
            continue;
        }
        summary.push_str(&format!(
            "  {:<15} {} `{}`: {:.2}× [{:.2}, {:.2}] (ideal {:.2}×, {:.2}× with its fixed costs, P/T {:.2}, hit {:.0}% miss {:.0}% refresh {:.0}%, oldest value shown {} frames), {}\n",
            row.variant.as_str(),
            row.node,
            row.node_text,
            row.speedup,
            row.speedup_ci[0],
            row.speedup_ci[1],
            row.ideal_speedup,
            row.bound_with_fixed_costs,
            row.p_over_t,
            row.hit_rate * 100.0,
            row.miss_rate * 100.0,
            row.refresh_rate * 100.0,
            row.max_age,
            quality(row)
        ));
    }
    summary.push_str(&defaulted_lines(&report.defaulted));
    if !report.steady_state {
        summary.push_str(&format!(
            "  note: {} warm-up frames are fewer than the longest refresh period: the errors are those of a younger cache than in its steady state (leave --warmup out to measure that)\n",
            report.warmup
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
    if let Some(grid) = &report.grid {
        let pruned: usize = grid.pruned.iter().map(|p| p.configurations).sum();
        match report.shard {
            Some(shard) => summary.push_str(&format!(
                "  shard {shard}: measured {} of the grid's {} configurations; the others are pruned ({pruned}), other shards', or refused (see the report); `shadecache merge` joins the shards\n",
                grid.measured, grid.full,
            )),
            None if grid.measured < grid.full => summary.push_str(&format!(
                "  measured {} of the grid's {} configurations: {} pruned, {} refused (see the report)\n",
                grid.measured,
                grid.full,
                pruned,
                grid.full.saturating_sub(pruned + grid.measured)
            )),
            None => {}
        }
    }
    summary
}

/// The answer's line, and the chosen variant's files written to
/// `out/choice/`.
fn answer(
    report: &report::Report,
    pictures: &profile::Pictures,
    out: &std::path::Path,
) -> Result<Option<String>, Error> {
    let Some(choice) = &report.choice else {
        return Ok(None);
    };
    let budget = if choice.budget_given {
        format!("within {}", choice.budget)
    } else {
        format!(
            "within {} (the default; --max-error sets it)",
            choice.budget
        )
    };
    Ok(Some(match (choice.result, &pictures.chosen) {
        (Some(_), Some(rewritten)) => {
            let dir = out.join("choice");
            back::write_variant(&dir, rewritten, Language::Wgsl)?;
            format!(
                "  answer {budget}: {}\n  wrote its shaders and plan to {}\n",
                choice.reason,
                dir.display()
            )
        }
        _ => format!("  answer {budget}: {}\n", choice.reason),
    }))
}

/// Profiles the fragment entry point `stages` names (or the module's only
/// one) into `out`: the report, and the summary for the terminal.
fn profile_entry(
    args: &Args,
    shader: &shadecache::front::Shader,
    stages: &super::StageArgs,
    folder: &crate::out_folder::OutFolder,
    out: &std::path::Path,
) -> Result<(Box<report::Report>, String), Error> {
    let drawn = shader.clone_parts();
    let (shader, scene, scene_path) = stages.drawn(drawn, args.scene.as_deref(), false)?;
    let shader = &shader;
    let options = options(args, stages)?;
    let mut bar = Bar {
        bar: None,
        quiet: args.quiet,
    };
    let (report, pictures) = profile::profile(shader, &scene, &scene_path, &options, &mut bar)?;

    folder.clear()?;
    super::write_report(
        out,
        &report,
        || report::write_images(out, &report, &pictures),
        || report::html(&report, out),
    )?;
    let io = |what: &str, err: String| {
        Error::plain(Diagnostic::error(format!("cannot write {what}: {err}")))
    };
    // The last frame's GPU scopes, for chrome://tracing or Perfetto.
    wgpu_profiler::chrometrace::write_chrometrace(&out.join("trace.json"), &pictures.trace)
        .map_err(|e| io("trace.json", e.to_string()))?;

    let mut summary = summary(&report);
    if let Some(answer) = answer(&report, &pictures, out)? {
        summary.push_str(&answer);
    }
    summary.push_str(&format!("report: {}\n", out.join("report.html").display()));
    Ok((Box::new(report), summary))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_engine_shaders_defaulted_inputs_are_summarised_in_part() {
        let many: Vec<String> = (0..1000).map(|i| format!("uniform `mesh[{i}]`")).collect();
        let lines = defaulted_lines(&many);
        assert_eq!(lines.lines().count(), 1 + DEFAULTED_SHOWN + 1, "{lines}");
        assert!(lines.contains("`mesh[23]`") && !lines.contains("`mesh[24]`"));
        assert!(lines.contains("… and 976 more"), "{lines}");
        let few = defaulted_lines(&many[..2]);
        assert_eq!(few.lines().count(), 3, "{few}");
        assert!(!few.contains("more"));
        assert_eq!(defaulted_lines(&[]), "");
    }
}
