//! Reading a plan the toolchain wrote (a two-pass variant of the
//! repository's marble shader) with nothing but this crate and a serde
//! format.

use shadecache_plan::{Plan, StepMode, Variant, FORMAT_VERSION};

fn plan() -> Plan {
    serde_json::from_str(include_str!("two_pass_plan.json")).expect("the plan reads")
}

#[test]
fn a_written_plan_reads_checks_and_writes_back_the_same() {
    let plan = plan();
    plan.check().unwrap();
    assert_eq!(plan.format, FORMAT_VERSION);
    assert_eq!(plan.variant, Variant::TwoPass);
    assert_eq!(plan.passes.len(), 2);
    assert!(plan
        .vertex_layout
        .iter()
        .all(|a| a.step == StepMode::Vertex));
    // Written back as the toolchain wrote it (f32 fields as f32s).
    let written = serde_json::to_string_pretty(&plan).unwrap();
    assert_eq!(written.trim(), include_str!("two_pass_plan.json").trim());
}

#[test]
fn another_format_version_is_refused() {
    let mut plan = plan();
    plan.format = FORMAT_VERSION + 1;
    let err = plan.check().unwrap_err();
    assert!(err.contains("plan format 2"), "{err}");
}

#[test]
fn a_pass_binding_nothing_declares_is_refused() {
    let mut plan = plan();
    plan.passes[1].bindings.push([3, 9]);
    let err = plan.check().unwrap_err();
    assert!(err.contains("`pass2` binds group 3, binding 9"), "{err}");
}

/// A plan written before `assumes` existed reads, assuming what every
/// variant assumed then (one sample, no blending, the whole target, one
/// view).
#[test]
fn a_plan_without_assumptions_reads_with_the_defaults() {
    let mut json: serde_json::Value =
        serde_json::from_str(include_str!("two_pass_plan.json")).unwrap();
    json.as_object_mut().unwrap().remove("assumes");
    let plan: Plan = serde_json::from_value(json).unwrap();
    assert_eq!(plan.assumes, shadecache_plan::FrameAssumptions::default());
    assert_eq!(plan.assumes.sample_count, 1);
}

/// Formats are typed and read as WebGPU spells them; an unknown one is an
/// error when the plan is read, not when it is run.
#[test]
fn formats_are_typed_and_unknown_ones_are_refused_on_read() {
    let plan = plan();
    assert_eq!(
        plan.vertex_layout[0].format,
        shadecache_plan::VertexFormat::Float32x3
    );
    assert_eq!(
        plan.passes[0].depth.format,
        shadecache_plan::TextureFormat::Depth32Float
    );
    let text = include_str!("two_pass_plan.json").replacen("\"float32x3\"", "\"float33\"", 1);
    let err = serde_json::from_str::<Plan>(&text).unwrap_err().to_string();
    assert!(err.contains("float33"), "{err}");
}
