//! The commands that draw run in a child process the command supervises,
//! so that a GPU driver that crashes or hangs is a diagnostic, not a bare
//! signal.
//!
//! A driver can end the process that uses it: Mesa 22.3.6's lavapipe
//! segfaults compiling Bevy's PBR shader, a shader can loop for minutes, a
//! system can kill a process that ran out of memory. Nothing in the
//! process runs after that, so the report cannot come from it. Two ways
//! were open: a signal handler in the process, or a second process.
//! A handler for SIGSEGV may only call async-signal-safe functions (no
//! allocation, no formatting, no locks: not the codespan diagnostic), it
//! needs `unsafe` (which the workspace forbids), it cannot catch SIGKILL,
//! and it does nothing for a hang. A parent process can do all four, on
//! every platform, in safe code; it costs one process start (a few
//! milliseconds) per command that draws.
//!
//! So `shadecache profile` and `shadecache interpolate` start themselves
//! again as a child, with [`WATCH_FILE`] naming a small file. The child
//! installs a watch on the measured run ([`shadecache::watch`])
//! that writes, before each step is given to the GPU, what is being drawn
//! or built, the adapter and its driver, and what the scene defaulted. The
//! parent waits: the child's exit code is the command's; a child ended by
//! a signal, or still in one GPU step after [`TIMEOUT_ENV`] seconds (120
//! by default, then killed), becomes a diagnostic that names the shader,
//! the step, the adapter and driver, and the defaulted inputs, with exit
//! code 3.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, ExitStatus};
use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};
use shadecache::diagnostic::{self, Color, Diagnostic};
use shadecache::watch::{self, Step};

/// Set in the child: the file its watch writes.
pub const WATCH_FILE: &str = "SHADECACHE_WATCH_FILE";

/// Seconds one GPU step (a frame, the pipelines of one runner) may take
/// before the supervisor ends the run: 120 unless set.
pub const TIMEOUT_ENV: &str = "SHADECACHE_GPU_TIMEOUT";

/// Test-only: the child aborts (SIGABRT) when it is about to draw a frame
/// whose label contains this text, as a crashing driver would end it.
pub const ABORT_WHILE_DRAWING: &str = "SHADECACHE_TEST_ABORT_WHILE_DRAWING";

/// The exit code of a run the driver ended or that hung.
pub const DRIVER_FAILED: u8 = 3;

const DEFAULT_TIMEOUT: Duration = Duration::from_secs(120);

/// Where the child's measured run is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum Phase {
    /// No GPU step yet.
    #[default]
    Starting,
    /// Making pipelines: the driver compiles the shaders.
    Building,
    /// A frame submitted and waited for.
    Drawing,
    /// Between GPU steps (comparing frames, writing the report).
    Idle,
}

impl Phase {
    /// Whether the GPU has the step: only then can it hang.
    fn busy(self) -> bool {
        matches!(self, Phase::Building | Phase::Drawing)
    }
}

/// What the child last told: the file's content.
#[derive(Debug, Default, Serialize, Deserialize)]
struct Breadcrumb {
    adapter: Option<String>,
    /// What the scene left at a neutral value (the first few).
    defaulted: Vec<String>,
    defaulted_count: usize,
    step: Phase,
    /// The step in words (`drawing a frame of reference (its passes
    /// pass1)`), or for `idle` the last busy one.
    what: String,
    /// When the step began, ms since the Unix epoch.
    since_ms: u128,
}

fn now_ms() -> u128 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|elapsed| elapsed.as_millis())
        .unwrap_or(0)
}

/// Whether this process is a supervised child.
pub fn is_child() -> bool {
    std::env::var_os(WATCH_FILE).is_some()
}

/// In the child: installs the watch that keeps the breadcrumb file.
pub fn install_watch() {
    let Some(path) = std::env::var_os(WATCH_FILE).map(PathBuf::from) else {
        return;
    };
    let abort_at = std::env::var(ABORT_WHILE_DRAWING)
        .ok()
        .filter(|text| !text.is_empty());
    let state = Mutex::new(Breadcrumb::default());
    watch::set_watch(Box::new(move |step| {
        let Ok(mut crumb) = state.lock() else {
            return;
        };
        match step {
            Step::Opened(adapter) => {
                crumb.adapter = Some(watch::describe_adapter(adapter));
                return;
            }
            Step::Defaulted(list) => {
                crumb.defaulted = list.iter().take(8).cloned().collect();
                crumb.defaulted_count = list.len();
                return;
            }
            Step::Building(what) => {
                crumb.step = Phase::Building;
                crumb.what = format!("making the pipelines of {what}");
            }
            Step::Drawing(what) => {
                crumb.step = Phase::Drawing;
                crumb.what = format!("drawing a frame of {what}");
            }
            Step::Idle => crumb.step = Phase::Idle,
        }
        crumb.since_ms = now_ms();
        if let Ok(text) = serde_json::to_vec(&*crumb) {
            // A write that fails leaves the last one: the report is then
            // one step behind, never wrong about what ran before.
            let _ = std::fs::write(&path, text);
        }
        if let (Step::Drawing(what), Some(at)) = (step, &abort_at) {
            if what.contains(at.as_str()) {
                std::process::abort();
            }
        }
    }));
}

/// In the parent: runs this command again as a child and answers for it.
/// `shader` is the file the command draws.
pub fn run_child(shader: &Path, color: Color) -> ExitCode {
    let timeout = match std::env::var(TIMEOUT_ENV) {
        Err(_) => DEFAULT_TIMEOUT,
        Ok(text) => match text.trim().parse::<f64>() {
            Ok(seconds) if seconds > 0.0 && seconds.is_finite() => {
                Duration::from_secs_f64(seconds.min(1e6))
            }
            _ => {
                let message = format!(
                    "{TIMEOUT_ENV}={text} is not a number of seconds above 0 (the longest one GPU step may take)"
                );
                diagnostic::emit_to_stderr(None, &Diagnostic::error(message), color);
                return ExitCode::from(1);
            }
        },
    };
    let file = std::env::temp_dir().join(format!("shadecache-watch-{}.json", std::process::id()));
    let _ = std::fs::remove_file(&file);
    let exe = match std::env::current_exe() {
        Ok(exe) => exe,
        Err(err) => return internal(&format!("cannot find the command's own file: {err}"), color),
    };
    let mut child = match Command::new(exe)
        .args(std::env::args_os().skip(1))
        .env(WATCH_FILE, &file)
        .spawn()
    {
        Ok(child) => child,
        Err(err) => return internal(&format!("cannot start the measured run: {err}"), color),
    };
    let started = Instant::now();
    let outcome = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Ended::Exited(status),
            Ok(None) => {}
            Err(err) => break Ended::Lost(err.to_string()),
        }
        std::thread::sleep(poll_interval(started.elapsed()));
        if let Some(crumb) = read(&file) {
            let elapsed = now_ms().saturating_sub(crumb.since_ms);
            if crumb.step.busy() && elapsed > timeout.as_millis() {
                let _ = child.kill();
                let _ = child.wait();
                break Ended::TimedOut(crumb, timeout);
            }
        }
    };
    let crumb = read(&file);
    let _ = std::fs::remove_file(&file);
    match outcome {
        Ended::Exited(status) => match exit_code(status) {
            Ok(code) => ExitCode::from(code),
            Err(how) => {
                report(&ended_by(&how, shader, crumb.as_ref()), color);
                ExitCode::from(DRIVER_FAILED)
            }
        },
        Ended::TimedOut(crumb, timeout) => {
            report(&timed_out(shader, &crumb, timeout), color);
            ExitCode::from(DRIVER_FAILED)
        }
        Ended::Lost(err) => internal(&format!("lost the measured run: {err}"), color),
    }
}

enum Ended {
    Exited(ExitStatus),
    TimedOut(Breadcrumb, Duration),
    Lost(String),
}

/// Short at first, so that a quick command ends quickly; then a tenth of
/// a second.
fn poll_interval(elapsed: Duration) -> Duration {
    if elapsed < Duration::from_secs(1) {
        Duration::from_millis(5)
    } else {
        Duration::from_millis(100)
    }
}

fn read(file: &Path) -> Option<Breadcrumb> {
    serde_json::from_slice(&std::fs::read(file).ok()?).ok()
}

/// The child's exit code, or how it was ended otherwise.
fn exit_code(status: ExitStatus) -> Result<u8, String> {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            return Err(signal_name(signal));
        }
    }
    match status.code() {
        Some(code) => u8::try_from(code)
            .ok()
            .filter(|code| *code <= DRIVER_FAILED)
            .ok_or_else(|| format!("exit status {code:#x}")),
        None => Err("an unknown cause".into()),
    }
}

fn signal_name(signal: i32) -> String {
    let name = match signal {
        4 => "SIGILL, an illegal instruction",
        6 => "SIGABRT, an abort",
        7 => "SIGBUS, a bus error",
        8 => "SIGFPE, an arithmetic fault",
        9 => "SIGKILL: the system kills a process so when it runs out of memory",
        11 => "SIGSEGV, a segmentation fault",
        15 => "SIGTERM",
        _ => "",
    };
    if name.is_empty() {
        format!("signal {signal}")
    } else {
        format!("signal {signal} ({name})")
    }
}

/// What the step was, in words.
fn step_words(crumb: &Breadcrumb) -> String {
    match crumb.step {
        Phase::Building | Phase::Drawing => crumb.what.clone(),
        Phase::Idle if !crumb.what.is_empty() => {
            format!("between GPU steps, after {}", crumb.what)
        }
        Phase::Idle | Phase::Starting => "before the first GPU step".into(),
    }
}

/// The notes every report has: the shader, the step, the adapter and
/// driver, what the scene defaulted.
fn context(diagnostic: Diagnostic, shader: &Path, crumb: Option<&Breadcrumb>) -> Diagnostic {
    let mut diagnostic = diagnostic.with_note(format!("shader: {}", shader.display()));
    let Some(crumb) = crumb else {
        return diagnostic.with_note("it had not opened a GPU yet");
    };
    diagnostic = diagnostic.with_note(format!(
        "adapter and driver: {}",
        crumb.adapter.as_deref().unwrap_or("not opened yet")
    ));
    if crumb.defaulted_count > 0 {
        let more = crumb.defaulted_count.saturating_sub(crumb.defaulted.len());
        let mut list = crumb.defaulted.join("; ");
        if more > 0 {
            list.push_str(&format!("; and {more} more"));
        }
        diagnostic = diagnostic.with_note(format!("the scene gave a neutral value to: {list}"));
    }
    diagnostic
}

fn ended_by(how: &str, shader: &Path, crumb: Option<&Breadcrumb>) -> Diagnostic {
    let what = crumb.map(step_words).unwrap_or_else(|| "starting".into());
    context(
        Diagnostic::error(format!("the measured run was ended by {how} while {what}")),
        shader,
        crumb,
    )
    .with_note(
        "a crash inside the GPU driver, not an answer about the shader: try another driver or \
         adapter (lavapipe from Mesa 24 or newer; Mesa 22.3.6 crashes on engine shaders), \
         and report it to the driver with the shader",
    )
}

fn timed_out(shader: &Path, crumb: &Breadcrumb, timeout: Duration) -> Diagnostic {
    context(
        Diagnostic::error(format!(
            "one GPU step ran past {:.0} s, so the measured run was ended: {}",
            timeout.as_secs_f64(),
            step_words(crumb)
        )),
        shader,
        Some(crumb),
    )
    .with_note(format!(
        "a shader that loops for long, or a driver that hangs; {TIMEOUT_ENV}=SECONDS sets the bound"
    ))
}

fn report(diagnostic: &Diagnostic, color: Color) {
    diagnostic::emit_to_stderr(None, diagnostic, color);
}

fn internal(message: &str, color: Color) -> ExitCode {
    report(
        &Diagnostic::error(format!("internal error: {message}")),
        color,
    );
    ExitCode::from(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crumb(step: Phase, what: &str) -> Breadcrumb {
        Breadcrumb {
            adapter: Some("llvmpipe (LLVM 15.0.6, 256 bits), llvmpipe Mesa 22.3.6, Vulkan".into()),
            defaulted: vec!["`view_proj`: the camera's".into()],
            defaulted_count: 12,
            step,
            what: format!("drawing a frame of {what}"),
            since_ms: 0,
        }
    }

    /// A crash report names the signal, the step, the shader, the adapter
    /// with its driver, and the defaulted inputs with how many more.
    #[test]
    fn a_crash_names_the_step_adapter_and_defaulted_inputs() {
        let text = diagnostic::render_to_string(
            None,
            &ended_by(
                &signal_name(11),
                Path::new("pbr.wgsl"),
                Some(&crumb(Phase::Drawing, "reference")),
            ),
        );
        for part in [
            "SIGSEGV",
            "drawing a frame of reference",
            "pbr.wgsl",
            "Mesa 22.3.6",
            "view_proj",
            "and 11 more",
        ] {
            assert!(text.contains(part), "{part} not in {text}");
        }
    }

    /// The file the parent reads is the one the child writes, and only a
    /// step the GPU has can run past the bound: a child comparing frames
    /// on the CPU for minutes is not a hung driver.
    #[test]
    fn only_a_gpu_step_can_time_out() {
        for phase in [
            Phase::Starting,
            Phase::Building,
            Phase::Drawing,
            Phase::Idle,
        ] {
            let text = serde_json::to_vec(&crumb(phase, "reference")).unwrap();
            let read: Breadcrumb = serde_json::from_slice(&text).unwrap();
            assert_eq!(read.step, phase);
            assert_eq!(
                read.step.busy(),
                matches!(phase, Phase::Building | Phase::Drawing)
            );
        }
        assert_eq!(
            step_words(&crumb(Phase::Idle, "reference")),
            "between GPU steps, after drawing a frame of reference"
        );
    }

    #[test]
    fn exit_codes_above_the_documented_ones_are_not_passed_through() {
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt;
            assert_eq!(exit_code(ExitStatus::from_raw(1 << 8)), Ok(1));
            assert_eq!(exit_code(ExitStatus::from_raw(3 << 8)), Ok(3));
            assert!(exit_code(ExitStatus::from_raw(139 << 8)).is_err());
            assert!(exit_code(ExitStatus::from_raw(11))
                .unwrap_err()
                .contains("SIGSEGV"));
        }
    }
}
