//! The `shadecache` command: a thin shell over the library. Each subcommand
//! lives in `commands/` with its clap arguments and an `exec` that builds
//! the library's options and calls it.
//!
//! Exit codes: 0 success; 1 bad input or refused work (a diagnostic was
//! printed); 2 internal error (a bug in shadecache).

use std::process::ExitCode;

use clap::Parser;

mod commands;

use commands::Command;

#[derive(Debug, Parser)]
#[command(
    name = "shadecache",
    version,
    about = "Find the values of a WGSL fragment shader worth caching across frames",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,

    /// When to colour diagnostics: auto colours on a terminal unless NO_COLOR is set.
    #[arg(long, global = true, value_enum, default_value_t = commands::ColorArg::Auto)]
    color: commands::ColorArg,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            let code = if err.use_stderr() { 1 } else { 0 };
            // clap formats its own usage errors and help text.
            let _ = err.print();
            return ExitCode::from(code);
        }
    };
    let color = cli.color.into();
    match std::panic::catch_unwind(|| commands::exec(cli.command, color)) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(err)) => {
            err.emit_to_stderr(color);
            ExitCode::from(1)
        }
        // The panic hook has printed the message.
        Err(_) => {
            shadecache::diagnostic::emit_to_stderr(
                None,
                &shadecache::diagnostic::Diagnostic::error(
                    "internal error: shadecache panicked; this is a bug, please report it with the input",
                ),
                color,
            );
            ExitCode::from(2)
        }
    }
}
