//! What the profiler measures: each configuration (a node, a variant, a
//! setting) and the probes of fixed cost beside them, and how a measured
//! frame is recorded into each.

use std::collections::HashMap;

use super::grid::Setting;
use super::run::{Measured, Sample};
use crate::measure::clock::read_linear;
use crate::measure::metrics::{self, Decisions, FrameError};
use crate::report::PassTime;
use crate::rewrite::Variant;
use crate::runtime::{self, Runner};

/// What a [`Probe`] measures the fixed cost of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ProbeOf {
    /// The original shader.
    Reference,
    /// A node's payload pass.
    Payload(usize),
    /// A node's variant, at the base setting.
    Variant(usize, Variant),
}

/// A run made free of the shader's work (payload, shade, or the whole
/// fragment stage returning zero), timed like the others: what is left is
/// fixed cost — rasterisation, the vertex stages, lookups, cache writes.
pub(super) struct Probe {
    pub of: ProbeOf,
    pub runner: Runner,
    pub times: Vec<f64>,
    pub passes: HashMap<String, Vec<f64>>,
}

/// A probe has no cache to warm: it runs from the last warm-up frame on
/// (one frame before it is measured), not through the warm-up.
impl Measured for Probe {
    fn label(&self) -> &str {
        "fixed cost"
    }
    fn runner(&mut self) -> &mut Runner {
        &mut self.runner
    }
    fn first_frame(&self, warmup: u32) -> u32 {
        warmup.saturating_sub(1)
    }
    fn traced(&self) -> bool {
        false
    }
    fn record(&mut self, sample: Sample) -> Result<(), String> {
        self.times.push(sample.time);
        for (name, ms) in sample.passes {
            self.passes.entry(name).or_default().push(ms);
        }
        Ok(())
    }
}

impl Probe {
    pub fn new(of: ProbeOf, runner: Runner) -> Self {
        Probe {
            of,
            runner,
            times: Vec::new(),
            passes: HashMap::new(),
        }
    }
}

/// The median time of the probe of `of`, and its passes'.
pub(super) fn probed(probes: &[Probe], of: ProbeOf) -> Option<(f64, Vec<PassTime>)> {
    let probe = probes.iter().find(|p| p.of == of)?;
    Some((metrics::median(&probe.times), pass_medians(&probe.passes)))
}

/// Each pass's median time, by name.
pub(super) fn pass_medians(passes: &HashMap<String, Vec<f64>>) -> Vec<PassTime> {
    let mut out: Vec<PassTime> = passes
        .iter()
        .map(|(name, times)| PassTime {
            name: name.clone(),
            time_ms: metrics::median(times),
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

/// How many times faster `time_ms` is than `reference_ms`; 0 for no time.
pub(super) fn speedup(reference_ms: f64, time_ms: f64) -> f64 {
    if time_ms > 0.0 {
        reference_ms / time_ms
    } else {
        0.0
    }
}

pub(super) struct Config {
    pub node: usize,
    pub variant: Variant,
    pub setting: Setting,
    pub runner: Runner,
    pub label: String,
    pub times: Vec<f64>,
    pub passes: HashMap<String, Vec<f64>>,
    pub errors: Vec<FrameError>,
    /// Flicker of each measured frame after the first ([`metrics::flicker`]).
    pub flicker: Vec<f64>,
    pub decisions: Vec<Decisions>,
    /// Covered pixels by the age of their value, over the measured frames.
    pub ages: Vec<u64>,
    /// The last measured frame, in linear float, and its classes.
    pub last: (metrics::LinearFrame, Vec<u8>),
    /// The frame's size and the error threshold its frames are compared
    /// with.
    pub size: [u32; 2],
    pub error_threshold: f64,
}

impl Measured for Config {
    fn label(&self) -> &str {
        &self.label
    }
    fn runner(&mut self) -> &mut Runner {
        &mut self.runner
    }
    /// Its time and passes, its picture against the reference's (error,
    /// flicker), the cache's decisions and the ages it showed.
    fn record(&mut self, sample: Sample) -> Result<(), String> {
        self.times.push(sample.time);
        for (name, ms) in sample.passes {
            self.passes.entry(name).or_default().push(ms);
        }
        let color = self
            .runner
            .color()
            .ok_or("the configuration draws no colour")?;
        let color = read_linear(sample.gpu, color)?;
        let classes = runtime::read_texture(sample.gpu, self.runner.classes(), 4)?;
        let reference = sample.reference;
        self.errors.push(metrics::compare(
            &reference.now,
            &color,
            &classes,
            self.size[0],
            self.size[1],
            self.error_threshold,
        ));
        if self.errors.len() > 1 {
            self.flicker.push(metrics::flicker(
                &reference.before,
                &reference.now,
                &self.last.0,
                &color,
                &classes,
            ));
        }
        self.decisions.push(metrics::decisions(&classes));
        let ages = runtime::read_texture(sample.gpu, self.runner.age(), 2)?;
        metrics::add_ages(&classes, &ages, &mut self.ages);
        self.last = (color, classes);
        Ok(())
    }
}
