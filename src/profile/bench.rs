//! The runners of one profile: every run draws the same scene (meshes,
//! textures) at the same size, through the host crate, with the same
//! culling. The reference, and the runs that time fixed costs: each
//! node's payload pass over every pixel (for P/T) and the same made free,
//! each variant with its payload and shade made free, the original with
//! its fragment stage made free.

use std::collections::HashMap;

use super::run::TimedRun;
use super::setup::Prepared;
use super::{sources_of, Probe, ProbeOf};
use crate::analysis::Candidate;
use crate::back;
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::bench::Bench;
use crate::measure::fail;
use crate::plan::{self, Plan};
use crate::rewrite::{self, Options as RewriteOptions, Variant};
use crate::runtime::Runner;

/// Per node, its payload pass over every pixel; and the fixed-cost
/// probes.
pub(super) fn fixed_cost_runs(
    bench: &Bench,
    shader: &Shader,
    prepared: &Prepared,
    nodes: &[(&Candidate, &[super::grid::Setting])],
    variants: &[Variant],
) -> Result<(Vec<TimedRun>, Vec<Probe>), Error> {
    let base = &prepared.base;
    let free = RewriteOptions {
        free_payload: true,
        ..base.clone()
    };
    let mut payloads = Vec::new();
    let mut probes = Vec::new();
    for (node, (candidate, _)) in nodes.iter().enumerate() {
        let payload = |options| payload_runner(bench, shader, prepared, candidate, options);
        payloads.push(TimedRun {
            label: "payload",
            runner: payload(base)?,
            times: Vec::new(),
        });
        probes.push(Probe::new(ProbeOf::Payload(node), payload(&free)?));
        // Each variant with its payload and shade free: its fixed cost.
        for &variant in variants {
            let Ok(rewritten) =
                rewrite::rewrite(shader, &prepared.analysis, candidate, variant, &free)
            else {
                continue;
            };
            let runner = bench
                .runner(&rewritten.plan, &sources_of(&rewritten)?, false)
                .map_err(fail)?;
            probes.push(Probe::new(ProbeOf::Variant(node, variant), runner));
        }
    }
    probes.push(Probe::new(
        ProbeOf::Reference,
        free_reference(bench, shader, prepared)?,
    ));
    Ok((payloads, probes))
}

/// The node's payload pass (three-pass's) drawn over every pixel: the
/// node's slice alone.
fn payload_runner(
    bench: &Bench,
    shader: &Shader,
    prepared: &Prepared,
    candidate: &Candidate,
    options: &RewriteOptions,
) -> Result<Runner, Error> {
    let rewritten = rewrite::rewrite(
        shader,
        &prepared.analysis,
        candidate,
        Variant::ThreePass,
        options,
    )
    .map_err(|r| fail(format!("node {}: {}", candidate.node.id, r.reason)))?;
    let payload_pass = rewrite::payload_pass(Variant::ThreePass)
        .and_then(|index| rewritten.plan.passes.get(index))
        .ok_or_else(|| fail("internal error: three-pass has no payload pass".into()))?;
    let mut pass = payload_pass.clone();
    pass.depth.load = plan::LoadOp::Clear;
    for target in &mut pass.color_targets {
        target.load = plan::LoadOp::Clear;
    }
    let plan = Plan {
        passes: vec![pass],
        classify: None,
        ..rewritten.plan.clone()
    };
    bench
        .runner(&plan, &sources_of(&rewritten)?, false)
        .map_err(fail)
}

/// The original with its fragment stage free: the reference's own fixed
/// cost, which every variant pays too. It binds only what its vertex
/// stage still reads: its plan is its own.
fn free_reference(bench: &Bench, shader: &Shader, prepared: &Prepared) -> Result<Runner, Error> {
    let entry = prepared.analysis.entry_index;
    let mut module = shader.module.clone();
    rewrite::free_function(&mut module.entry_points[entry].function);
    let info = crate::front::validate(&module)
        .map_err(|err| fail(format!("internal error: the free reference: {err}")))?;
    let text = back::wgsl_text(&module, &info).map_err(fail)?;
    let free = Shader {
        file: shader.file.clone(),
        module,
        info,
        vertex_file: shader.vertex_file.clone(),
        defs: shader.defs.clone(),
    };
    let plan = rewrite::plan::reference(&free, &prepared.analysis, &prepared.base).map_err(fail)?;
    let sources = HashMap::from([("reference.wgsl".to_string(), text)]);
    bench.runner(&plan, &sources, false).map_err(fail)
}
