//! `shadecache merge`: the shards of a sweep (`profile --shard K/N`, each
//! run where it was scheduled) joined into one report and one Pareto front
//! (`shadecache::profile::merge`).

use std::path::PathBuf;

use shadecache::diagnostic::{Color, Diagnostic, Error};
use shadecache::profile::merge;
use shadecache::report;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The shards' report folders (or their report.json files).
    #[arg(required = true, value_name = "DIR")]
    pub shards: Vec<PathBuf>,

    /// Where to write the merged report.json and report.html.
    #[arg(long, value_name = "DIR", default_value = "shadecache-merged")]
    pub out: PathBuf,

    /// Write into an --out folder that holds files a previous run did not
    /// list as its own (they stay; files of the same names are replaced).
    /// Without it, such a folder is refused before anything runs.
    #[arg(long)]
    pub overwrite: bool,

    /// Shards of different shaders, scenes, grids or adapters: a merged
    /// report per group of alike shards (in DIR/1, DIR/2...) instead of an
    /// error.
    #[arg(long)]
    pub keep_apart: bool,

    /// Merge a sweep with shards missing or given twice (a failed or
    /// retried CI job) from what there is; the report and its answer say
    /// which part it is. Without it, that is an error naming the shards.
    #[arg(long)]
    pub allow_partial: bool,
}

pub fn exec(args: Args, _color: Color) -> Result<(), Error> {
    let plain = |message: String| Error::plain(Diagnostic::error(message));
    let shards = args
        .shards
        .iter()
        .map(|path| merge::read(path))
        .collect::<Result<Vec<_>, _>>()
        .map_err(plain)?;
    // The merged report may not replace what it is made of.
    let inside = |path: &std::path::Path| {
        let canonical = |p: &std::path::Path| std::fs::canonicalize(p).ok();
        let out = canonical(&args.out)?;
        let folder = canonical(path.parent()?)?;
        folder.starts_with(&out).then_some(())
    };
    if let Some(shard) = shards.iter().find(|s| inside(&s.path).is_some()) {
        return Err(plain(format!(
            "--out `{}` holds the input {}: the merged report would replace a shard it is made of; name another folder",
            args.out.display(),
            shard.path.display()
        )));
    }
    let folder = crate::out_folder::OutFolder::check(&args.out, args.overwrite)?;
    let count = shards.len();
    let merged = merge::merge(
        shards,
        merge::Options {
            keep_apart: args.keep_apart,
            allow_partial: args.allow_partial,
        },
    )
    .map_err(plain)?;
    folder.run(|folder| write(&args, &merged, count, folder))
}

/// Writes the merged reports into `folder` (one, or one per group in
/// `DIR/1`, `DIR/2`...) and says what they answer.
fn write(
    args: &Args,
    merged: &[report::Report],
    count: usize,
    folder: &crate::out_folder::OutFolder,
) -> Result<(), Error> {
    folder.clear()?;
    let single = merged.len() == 1;
    for (i, report) in merged.iter().enumerate() {
        let out = if single {
            args.out.clone()
        } else {
            args.out.join((i + 1).to_string())
        };
        super::write_report(
            &out,
            report,
            || Ok(Vec::new()),
            || report::html(report, &out),
        )?;
        let best = report
            .results
            .first()
            .map(|r| format!("; fastest {} {} at {:.2}×", r.node, r.variant, r.speedup))
            .unwrap_or_default();
        println!(
            "{} shard(s) into {} rows{best}; the answer: {}\nreport: {}",
            report.merged_from.len(),
            report.results.len(),
            report.choice.as_ref().map_or("none", |c| c.reason.as_str()),
            out.join("report.html").display()
        );
    }
    if !single {
        println!("{count} shard(s) kept apart in {} reports", merged.len());
    }
    Ok(())
}
