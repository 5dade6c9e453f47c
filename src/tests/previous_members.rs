//! Resources that keep last frame's values themselves: where every member
//! the position reads has a `previous_` sibling (as Bevy's mesh keeps
//! `previous_world_from_local`), the previous position reads the siblings
//! and the resource gets no twin.

use crate::analysis;
use crate::front::{self, Shader};
use crate::profile::{Nodes, Options};
use crate::rewrite::{self, Variant};

use super::gpu::{build_pipelines, write_wgsl};
use super::profile::run_shader;
use super::util::marble_scene;
use super::util::{root, tint_validate};

/// The marble, its frame uniform keeping last frame's view-projection and
/// model beside this frame's.
fn marble_with_previous_members() -> String {
    let marble = std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap();
    let edited = marble.replacen(
        "    clip_from_world: mat4x4<f32>,\n    world_from_local: mat4x4<f32>,\n",
        "    clip_from_world: mat4x4<f32>,\n    world_from_local: mat4x4<f32>,\n    previous_clip_from_world: mat4x4<f32>,\n    previous_world_from_local: mat4x4<f32>,\n",
        1,
    );
    assert_ne!(
        edited, marble,
        "the marble's Frame struct is as this test expects"
    );
    edited
}

fn parsed(text: &str) -> Shader {
    front::parse(crate::diagnostic::SourceFile::new("test.wgsl", text))
        .unwrap_or_else(|e| panic!("{}", e.render()))
}

/// The rewrite reads the siblings: no twin of `frame`, the plan names the
/// members, the previous position helper reads the `previous_` members,
/// and every pass is valid (naga, Tint, a wgpu pipeline). Without the
/// siblings, the same shader gets its twin as before.
#[test]
fn an_engines_previous_members_replace_the_twin() {
    let shader = parsed(&marble_with_previous_members());
    let analysis = analysis::analyze(&shader, &analysis::Options::default())
        .unwrap_or_else(|e| panic!("{}", e.render()));
    let candidate = &analysis.candidates[0];
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for variant in Variant::CACHE {
        let rewritten =
            rewrite::rewrite(&shader, &analysis, candidate, variant, &Default::default())
                .unwrap_or_else(|r| panic!("{variant}: {r}"));
        let bindings = &rewritten.plan.bindings;
        assert!(
            bindings.previous.is_empty(),
            "{variant}: {:?}",
            bindings.previous
        );
        let [members] = bindings.previous_members.as_slice() else {
            panic!("{variant}: {:?}", bindings.previous_members)
        };
        assert_eq!(members.resource.name, "frame");
        let mut names = members.members.clone();
        names.sort();
        assert_eq!(
            names,
            [
                [
                    "clip_from_world".to_string(),
                    "previous_clip_from_world".into()
                ],
                [
                    "world_from_local".into(),
                    "previous_world_from_local".into()
                ],
            ]
        );
        let first = &rewritten.passes[0];
        let pass = crate::back::wgsl_text(&first.module, &first.info).unwrap();
        let helper = pass
            .split("fn vs_main_previous(")
            .nth(1)
            .and_then(|rest| rest.split("\nfn ").next())
            .unwrap_or_else(|| panic!("{variant}: no previous position helper in\n{pass}"));
        assert!(helper.contains(".previous_world_from_local"), "{helper}");
        assert!(helper.contains(".previous_clip_from_world"), "{helper}");
        build_pipelines(&rewritten, &format!("{variant}"));
        files.extend(write_wgsl(dir.path(), &variant.to_string(), &rewritten));
    }
    for result in tint_validate(&files) {
        assert!(result.ok, "{}: {:?}", result.file, result.messages);
    }

    // Without the siblings: the twin, as before.
    assert_twinned(&std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap());
}

/// The two-pass rewrite of `text`'s top node twins its frame uniform and
/// reads no `previous_` members.
fn assert_twinned(text: &str) {
    let shader = parsed(text);
    let analysis = analysis::analyze(&shader, &analysis::Options::default()).unwrap();
    let rewritten = rewrite::rewrite(
        &shader,
        &analysis,
        &analysis.candidates[0],
        Variant::TwoPass,
        &Default::default(),
    )
    .unwrap();
    assert_eq!(rewritten.plan.bindings.previous.len(), 1);
    assert!(rewritten.plan.bindings.previous_members.is_empty());
}

/// A `previous_` member covers only what it is the sibling of: the
/// position reading a member without one (here the frame's time, bending
/// the sphere) keeps the twin, since last frame's value of that member is
/// nowhere else.
#[test]
fn a_member_without_a_sibling_keeps_the_twin() {
    let text = marble_with_previous_members().replacen(
        "    let world = frame.world_from_local * vec4<f32>(in.position, 1.0);",
        "    let world = frame.world_from_local * vec4<f32>(in.position * (1.0 + 0.01 * sin(frame.time)), 1.0);",
        1,
    );
    assert_twinned(&text);
}

/// The scene fills a `previous_` member with last frame's value, so the
/// cache reprojects through the siblings exactly as through a twin: the
/// same node and variant on a turning sphere under an orbiting camera
/// give the same frames either way.
#[test]
fn previous_members_reproject_as_a_twin_does() {
    let scene = marble_scene("\"object-motion\", \"camera-motion\"", "");
    let options = || Options {
        nodes: Nodes::Top(1),
        variants: vec![Variant::TwoPass],
        refresh_periods: vec![8],
        size: Some([64, 64]),
        frames: Some(4),
        warmup: Some(8),
        ..Options::default()
    };
    let marble = std::fs::read_to_string(root().join("corpus/noise_marble.wgsl")).unwrap();
    let Some((_, twin, _)) = run_shader(&marble, &scene, options()) else {
        return;
    };
    let (_, members, _) = run_shader(&marble_with_previous_members(), &scene, options()).unwrap();
    let psnr = |report: &crate::report::Report| {
        assert_eq!(report.results.len(), 1, "{:?}", report.results);
        report.results[0].psnr
    };
    let (twin, members) = (psnr(&twin), psnr(&members));
    assert!(
        twin.is_finite() && twin < 60.0,
        "the motion must cost some error: {twin}"
    );
    assert!(
        (twin - members).abs() < 0.05,
        "through a twin {twin:.3} dB, through previous members {members:.3} dB"
    );
}
