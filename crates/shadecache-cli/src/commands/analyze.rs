//! `shadecache analyze`: list the cache candidates of a fragment shader.

use std::path::PathBuf;
use std::sync::Arc;

use shadecache::analysis::{self, text, Options};
use shadecache::cost::Weights;
use shadecache::diagnostic::Error;
use shadecache::diagnostic::{self, Color, Diagnostic, SourceFile};
use shadecache::front;

use super::write_stdout;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The WGSL shader to analyse.
    pub shader: PathBuf,

    /// The fragment entry point, when the shader has several.
    #[arg(long, value_name = "NAME")]
    pub entry: Option<String>,

    #[command(flatten)]
    pub compose: super::ComposeArgs,

    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,

    /// Also show the rejected expressions and why (text output; JSON always has them).
    #[arg(long)]
    pub all: bool,

    /// Cost weights as JSON (see docs/cost-model.md); unlisted weights keep their defaults.
    #[arg(long, value_name = "FILE.json")]
    pub weights: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    Text,
    Json,
}

pub fn exec(args: Args, color: Color) -> Result<(), Error> {
    let weights = match &args.weights {
        Some(path) => read_weights(path)?,
        None => Weights::default(),
    };
    let composition = args.compose.composition()?;
    let shader = front::load_with(&args.shader, &composition, None, None)?;
    super::warn_false_defs(&args.shader, &composition);
    // Every fragment entry point in turn, unless `--entry` names one.
    let analyses = analysis::analyze_entries(
        &shader,
        &Options {
            entry: args.entry,
            weights,
        },
    )?;
    match args.format {
        Format::Json => {
            // One entry point: its analysis; several: an array of them.
            let json = match &analyses[..] {
                [one] => serde_json::to_string_pretty(one),
                several => serde_json::to_string_pretty(several),
            };
            let mut json = json.map_err(|err| {
                Error::plain(Diagnostic::error(format!("cannot write JSON: {err}")))
            })?;
            json.push('\n');
            write_stdout(&json)
        }
        Format::Text => {
            for analysis in &analyses {
                if analyses.len() > 1 {
                    write_stdout(&format!("entry point `{}`:\n", analysis.entry))?;
                }
                for note in text::notes(analysis, args.all) {
                    diagnostic::emit_to_stdout(Some(&shader.file), &note, color);
                }
                write_stdout(&format!("{}\n", text::summary(analysis, args.all)))?;
            }
            Ok(())
        }
    }
}

fn read_weights(path: &std::path::Path) -> Result<Weights, Error> {
    let file = Arc::new(front::read_text(path, front::TextKind::Weights)?);
    let weights = Weights::from_json(&file.text).map_err(|err| {
        let offset = offset_of(&file, err.line(), err.column());
        Error::in_file(
            file.clone(),
            Diagnostic::error("invalid cost weights").with_label(offset..offset, err.to_string()),
        )
    })?;
    if let Some((name, why)) = weights.out_of_bounds() {
        // serde_json keeps no spans: the key's first quoted occurrence
        // places the label.
        let at = file
            .text
            .find(&format!("\"{name}\""))
            .map_or(0..0, |at| at..at + name.len() + 2);
        return Err(Error::in_file(
            file.clone(),
            Diagnostic::error(why).with_label(at, "this weight"),
        ));
    }
    Ok(weights)
}

/// The byte offset of a 1-based line and column as serde_json reports them.
fn offset_of(file: &SourceFile, line: usize, column: usize) -> usize {
    let line_start: usize = file
        .text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    (line_start + column.saturating_sub(1)).min(file.text.len())
}
