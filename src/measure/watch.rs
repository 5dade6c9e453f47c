//! What a measured run is about to give the GPU, told to whoever watches.
//!
//! A GPU driver can end the process: a compiler bug that segfaults
//! (Mesa 22.3.6's lavapipe on Bevy's PBR shader), a shader that loops for
//! minutes, a device lost. Nothing after that point runs, so a report of
//! what was being drawn has to be made *before* each step. Like
//! [`std::panic::set_hook`], the watch is one per process: the command
//! installs one that keeps the last step where a supervising process can
//! read it after a crash (`shadecache-cli`'s `supervise`); a library user
//! installs nothing and pays an uncontended lock read per step.
//!
//! The steps, in the order a run takes them: the device is opened
//! ([`Step::Opened`]), the scene's inputs are known with what they left at
//! a neutral value ([`Step::Defaulted`]), pipelines are made for each
//! runner ([`Step::Building`], where drivers compile the shader), and each
//! frame is submitted and waited for ([`Step::Drawing`], then
//! [`Step::Idle`] once it is done).

use std::sync::{Arc, OnceLock, RwLock};

pub use crate::runtime::describe_adapter;

/// One step of a measured run, told before the GPU is given it.
#[derive(Debug)]
pub enum Step<'a> {
    /// The run draws on this adapter.
    Opened(&'a wgpu::AdapterInfo),
    /// The scene gave these inputs a neutral value (the default scene's
    /// matrices, a uniform nothing named, a vertex input fed a constant).
    Defaulted(&'a [String]),
    /// The pipelines that draw `what` are being made.
    Building(&'a str),
    /// A frame of `what` (`reference`, a variant's label, a B-frame
    /// method) is being recorded, submitted and waited for.
    Drawing(&'a str),
    /// The GPU has finished what it was given.
    Idle,
}

/// What watches the steps.
pub type Watch = dyn Fn(&Step) + Send + Sync;

fn slot() -> &'static RwLock<Option<Arc<Watch>>> {
    static SLOT: OnceLock<RwLock<Option<Arc<Watch>>>> = OnceLock::new();
    SLOT.get_or_init(|| RwLock::new(None))
}

/// Installs the process's watch, replacing any other.
pub fn set_watch(watch: Box<Watch>) {
    let mut slot = slot()
        .write()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    *slot = Some(Arc::from(watch));
}

/// Whether a watch is installed: what a step's words cost to make need
/// not be paid otherwise.
pub(crate) fn watching() -> bool {
    slot()
        .read()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
        .is_some()
}

/// Tells the watch, if there is one, of `step`.
pub(crate) fn tell(step: Step) {
    let watch = slot()
        .read()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
        .clone();
    if let Some(watch) = watch {
        watch(&step);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// The installed watch hears every step, in order, and a second
    /// installation replaces the first.
    #[test]
    fn the_watch_hears_each_step_in_order() {
        let heard = Arc::new(Mutex::new(Vec::new()));
        let into = heard.clone();
        set_watch(Box::new(move |step| {
            let line = match step {
                Step::Building(what) => format!("building {what}"),
                Step::Drawing(what) => format!("drawing {what}"),
                Step::Idle => "idle".to_string(),
                Step::Defaulted(list) => format!("defaulted {}", list.len()),
                Step::Opened(adapter) => format!("opened {}", adapter.name),
            };
            into.lock().unwrap().push(line);
        }));
        // Other tests of this binary may draw meanwhile: only this
        // test's labels count.
        tell(Step::Building("watch test"));
        tell(Step::Drawing("watch test"));
        set_watch(Box::new(|_| {}));
        tell(Step::Drawing("watch test, never heard"));
        let heard: Vec<String> = heard
            .lock()
            .unwrap()
            .iter()
            .filter(|line| line.contains("watch test"))
            .cloned()
            .collect();
        assert_eq!(heard, ["building watch test", "drawing watch test"]);
    }
}
