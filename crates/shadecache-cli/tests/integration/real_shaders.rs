//! A real engine's G-buffer shader through `shadecache profile`.

use crate::util::*;
use shadecache::rewrite::{self, Options, Variant};

/// A deferred renderer's fragment stage writes an HDR colour and an
/// integer material id (`vec4<u32>`): the plan gives the integer output
/// an integer target (`rgba32uint`), so the shader profiles; a float
/// target there is a pipeline the GPU refuses.
#[test]
fn a_g_buffer_with_an_integer_output_profiles() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let output = crate::util::shadecache([
        "profile",
        "crates/shadecache-host/tests/fixtures/gbuffer.wgsl",
        "--nodes",
        "nf0aaf62f",
        "--variant",
        "three-pass",
        "--frames",
        "2",
        "--size",
        "48x48",
        "--quiet",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", crate::util::stderr(&output));
    let (shader, analysis) = analyzed(
        "gbuffer.wgsl",
        &std::fs::read_to_string(root().join("crates/shadecache-host/tests/fixtures/gbuffer.wgsl"))
            .unwrap(),
    );
    let node = analysis
        .candidates
        .iter()
        .find(|c| c.node.id == "nf0aaf62f")
        .unwrap();
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        node,
        Variant::ThreePass,
        &Options::default(),
    )
    .unwrap();
    let formats: Vec<(u32, &str)> = rewritten.plan.passes[2]
        .color_targets
        .iter()
        .map(|t| (t.location, t.format.as_str()))
        .collect();
    assert_eq!(formats, [(0, "rgba8unorm"), (1, "rgba32uint")]);
}
