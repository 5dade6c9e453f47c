//! `shadecache play`: a scene played as an application plays it, the
//! original, a fixed cache and the host crate's governor side by side, to
//! see on this GPU what the governor would do (`shadecache::profile::play`).

use std::path::PathBuf;

use shadecache::diagnostic::{Color, Diagnostic, Error};
use shadecache::profile::{play, Nodes, Options};

use super::profile::{frame_count, parse_size, Bar};
use super::rewrite::VariantArg;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The WGSL shader to play.
    pub shader: PathBuf,

    /// The scene to play (TOML; see docs/scene-toml.md). Without one, the
    /// default scene `shadecache scene init` writes.
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: Option<PathBuf>,

    /// The node the cache keeps (default: the one the analysis ranks
    /// first).
    #[arg(long, value_name = "ID")]
    pub node: Option<String>,

    /// The variant the fixed and the governed ways draw; several,
    /// separated by commas, and the governor tries each (at the start and
    /// every 3000 frames while the cache is on) and draws the fastest
    /// within the budget, while the fixed way draws the first.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "one-pass")]
    pub variant: Vec<VariantArg>,

    /// The refresh period Δn (default: the variant's).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=65535))]
    pub refresh_period: Option<u32>,

    /// Frames played of each way: the governor needs a few hundred to
    /// decide, and re-probes every 600 while the cache is off.
    #[arg(long, value_name = "N", default_value_t = 600, value_parser = frame_count)]
    pub frames: u32,

    /// The error budget of the governed way, as the least PSNR (dB, over
    /// the cached pixels, as `profile` measures it): the governor watches
    /// one cached frame in 64 against the original on the GPU, halves Δn
    /// below the budget and turns the cache off below it at Δn = 2.
    /// Without it, speed alone decides.
    #[arg(long, value_name = "DB", value_parser = min_psnr)]
    pub min_psnr: Option<f64>,

    /// Frame size (default: the scene's).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<[u32; 2]>,

    /// Where to write play.json and play.html.
    #[arg(long, value_name = "DIR", default_value = "shadecache-play")]
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

pub fn exec(args: Args, color: Color) -> Result<(), Error> {
    if args.variant.contains(&VariantArg::All) {
        let names: Vec<&str> = shadecache::rewrite::Variant::ALL
            .iter()
            .map(|v| v.as_str())
            .collect();
        return Err(Error::plain(Diagnostic::error(format!(
            "--variant all: play draws the variants it is given; name them ({}, separated by commas)",
            names.join(", ")
        ))));
    }
    let out = crate::out_folder::OutFolder::check(&args.out, args.overwrite)?;
    out.run(|out| play_into(&args, color, out))
}

/// The play, and play.json written into `out`.
fn play_into(args: &Args, _color: Color, out: &crate::out_folder::OutFolder) -> Result<(), Error> {
    let shader = args.stages.load(&args.shader)?;
    let (shader, scene, scene_path) = args.stages.drawn(shader, args.scene.as_deref(), false)?;
    let defaults = Options::default();
    let options = Options {
        nodes: match &args.node {
            Some(id) => Nodes::Ids(vec![id.clone()]),
            None => Nodes::Top(1),
        },
        variants: VariantArg::variants(&args.variant),
        refresh_periods: args
            .refresh_period
            .map_or(defaults.refresh_periods.clone(), |period| vec![period]),
        size: args.size,
        entry: args.stages.entry.clone(),
        vertex_entry: args.stages.vertex_entry.clone(),
        ..defaults
    };
    let mut bar = Bar {
        bar: None,
        quiet: args.quiet,
    };
    let played = play::play(
        &shader,
        &scene,
        &scene_path,
        &options,
        (args.frames, args.min_psnr),
        &mut bar,
    )?;

    out.clear()?;
    let path = args.out.join("play.json");
    let io = |err: String| {
        Error::plain(Diagnostic::error(format!(
            "cannot write `{}`: {err}",
            path.display()
        )))
    };
    std::fs::create_dir_all(&args.out).map_err(|e| io(e.to_string()))?;
    let json = serde_json::to_string_pretty(&played).map_err(|e| io(e.to_string()))?;
    std::fs::write(&path, json + "\n").map_err(|e| io(e.to_string()))?;
    let page = args.out.join("play.html");
    std::fs::write(&page, played.html()).map_err(|e| {
        Error::plain(Diagnostic::error(format!(
            "cannot write `{}`: {e}",
            page.display()
        )))
    })?;
    super::write_stdout(&summary(&played, &page))
}

/// What a play found, in a few lines.
fn summary(played: &play::Play, path: &std::path::Path) -> String {
    let ratio = |ms: f64| {
        if ms > 0.0 {
            played.original_ms / ms
        } else {
            0.0
        }
    };
    let mut text = format!(
        "{} on {} ({}×{}, {} frames each, {}): {}\n  original {:.3} ms a frame; fixed cache {:.3} ms ({:.2}×); governor {:.3} ms ({:.2}×, {:.0}% of its frames cached, cache {} at the end)\n",
        played.shader,
        played.scene,
        played.size[0],
        played.size[1],
        played.frames,
        played.device,
        played.fixed_variant,
        played.original_ms,
        played.fixed_ms,
        ratio(played.fixed_ms),
        played.auto_ms,
        ratio(played.auto_ms),
        played.auto_cached_share * 100.0,
        if played.auto_on_at_end { "on" } else { "off" },
    );
    for decision in &played.decisions {
        let state = if decision.on { "on" } else { "off" };
        if decision.cause == "trial" {
            let name = played
                .auto_variants
                .get(decision.variant)
                .map_or("?", String::as_str);
            let within = if played.min_psnr.is_some() {
                " within the budget"
            } else {
                ""
            };
            text += &format!(
                "  frame {}: cache {state} with {name}, the fastest of the trial{within} ({:.2}× [{:.2}, {:.2}])\n",
                decision.frame, decision.speedup, decision.interval[0], decision.interval[1]
            );
            continue;
        }
        text += &match decision.psnr {
            Some(psnr) => format!(
                "  frame {}: cache {state}, Δn = {} (a watched frame at {psnr:.1} dB, {})\n",
                decision.frame,
                decision.period,
                if decision.cause == "margin" {
                    "well within the budget"
                } else {
                    "below the budget"
                }
            ),
            None => format!(
                "  frame {}: cache {state} (speed-up {:.2}× [{:.2}, {:.2}])\n",
                decision.frame, decision.speedup, decision.interval[0], decision.interval[1]
            ),
        };
    }
    if played.decisions.is_empty() {
        text += "  no switch: the governor kept the cache on\n";
    }
    for (index, trial) in played.trials.iter().enumerate() {
        let turns: Vec<String> = trial
            .iter()
            .map(|turn| {
                let name = played
                    .auto_variants
                    .get(turn.variant)
                    .map_or("?", String::as_str);
                match turn.psnr {
                    Some(db) => format!("{name} {:.2}× at {db:.1} dB", turn.speedup),
                    None => format!("{name} {:.2}×", turn.speedup),
                }
            })
            .collect();
        text += &format!("  trial {}: {}\n", index + 1, turns.join(", "));
    }
    for refusal in &played.refused {
        text += &format!("  left out, refused: {refusal}\n");
    }
    if let Some(min_psnr) = played.min_psnr {
        let lowest = played
            .watches
            .iter()
            .map(|w| w.psnr)
            .fold(f64::INFINITY, f64::min);
        text += &format!(
            "  error watch, budget {min_psnr} dB: {} frames watched, lowest {lowest:.1} dB; a watched frame {:.3} ms (its comparison {:.3} ms); Δn = {} at the end\n",
            played.watches.len(),
            played.watch_frame_ms,
            played.watch_compare_ms,
            played.auto_period_at_end
        );
    }
    text += &format!("play: {}\n", path.display());
    text
}

/// An error budget: a finite PSNR in dB, above 0.
fn min_psnr(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(db) if db.is_finite() && db > 0.0 => Ok(db),
        _ => Err(format!("`{text}` is not a PSNR in dB above 0 (e.g. 35)")),
    }
}
