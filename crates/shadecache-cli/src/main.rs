//! The `shadecache` command: a thin shell over the library. Each subcommand
//! lives in `commands/` with its clap arguments and an `exec` that builds
//! the library's options and calls it.
//!
//! Exit codes: 0 success; 1 bad input or refused work (a diagnostic was
//! printed); 2 internal error (a bug in shadecache); 3 the GPU driver
//! ended or hung the measured run (a diagnostic says what was drawing,
//! `supervise`).

use std::process::ExitCode;

use clap::Parser;

mod commands;
mod out_folder;
mod supervise;

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

/// Mesa's device-select Vulkan layer connects to a Wayland display to
/// order the GPUs. Without `XDG_RUNTIME_DIR` (a headless machine, CI, ssh)
/// libwayland cannot connect and prints "error: XDG_RUNTIME_DIR is invalid
/// or not set in the environment.", which reads as a failure of ours. An
/// absolute `WAYLAND_DISPLAY` naming no socket fails the same attempt
/// without a word; with either variable set nothing changes. Called before
/// any other thread exists.
fn quiet_headless_wayland() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none()
        && std::env::var_os("WAYLAND_DISPLAY").is_none()
    {
        std::env::set_var("WAYLAND_DISPLAY", "/nonexistent/shadecache-headless");
    }
}

/// Stack size of the thread that does the work.
const WORKER_STACK: usize = 256 * 1024 * 1024;

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
    quiet_headless_wayland();
    // The commands that draw run in a child that this process watches.
    if supervise::is_child() {
        supervise::install_watch();
    } else if let Some(shader) = cli.command.draws() {
        return supervise::run_child(shader, color);
    }
    // naga's parser and lowering recurse over the expression tree; a long
    // chain like `x + x + ... + x` is valid WGSL but deeper than the main
    // thread's stack in an unoptimised build. Run the work on a thread with
    // room for it, as rustc does.
    let outcome = std::thread::Builder::new()
        .name("shadecache".into())
        .stack_size(WORKER_STACK)
        .spawn(move || commands::exec(cli.command, color))
        .map_err(|err| format!("cannot start a worker thread: {err}"))
        .and_then(|worker| {
            // The panic hook has printed the panic's message.
            worker.join().map_err(|_| {
                "shadecache panicked; this is a bug, please report it with the input".to_string()
            })
        });
    match outcome {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(err)) => {
            err.emit_to_stderr(color);
            ExitCode::from(if err.internal { 2 } else { 1 })
        }
        Err(message) => {
            shadecache::diagnostic::emit_to_stderr(
                None,
                &shadecache::diagnostic::Diagnostic::error(format!("internal error: {message}")),
                color,
            );
            ExitCode::from(2)
        }
    }
}
