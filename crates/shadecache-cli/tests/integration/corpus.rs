//! The corpus: valid for naga and Tint, and every shader has candidates
//! with stable ids.

use std::collections::BTreeSet;

use serde_json::Value;

use crate::util::{analyze_json, corpus, root, temp_file, tint_validate};

#[test]
fn corpus_is_valid_for_naga() {
    for path in corpus() {
        if let Err(err) = shadecache::front::load(&root().join(&path)) {
            panic!(
                "{} is not valid for naga:\n{}",
                path.display(),
                err.render()
            );
        }
    }
}

#[test]
fn corpus_is_valid_for_tint() {
    let files = corpus();
    for result in tint_validate(&files) {
        assert!(
            result.ok,
            "{} is rejected by Tint: {:#?}",
            result.file, result.messages
        );
    }
}

/// The Tint harness must catch what naga 30 lets through: a derivative in
/// non-uniform control flow of a fragment shader.
#[test]
fn tint_rejects_derivatives_in_non_uniform_control_flow() {
    let source = "@fragment\nfn fs(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {\n    var c = 0.0;\n    if (uv.x > 0.5) {\n        c = dpdx(uv.y);\n    }\n    return vec4<f32>(c);\n}\n";
    let (_dir, path) = temp_file("non_uniform.wgsl", source.as_bytes());
    assert!(
        shadecache::front::load(&path).is_ok(),
        "naga 30 accepts this shader, which is why Tint is needed"
    );
    let result = tint_validate(&[path]).remove(0);
    assert!(!result.ok);
    let error = result
        .messages
        .iter()
        .find(|m| m.kind == "error")
        .expect("an error message");
    assert!(error.message.contains("uniform control flow"), "{error:?}");
    assert_eq!((error.line, error.column), (5, 13));
}

fn ids(analysis: &Value, list: &str) -> Vec<String> {
    analysis[list]
        .as_array()
        .unwrap()
        .iter()
        .map(|node| node["id"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn every_corpus_shader_has_candidates() {
    for path in corpus() {
        let analysis = analyze_json(&path);
        let candidates = analysis["candidates"].as_array().unwrap();
        assert!(
            !candidates.is_empty(),
            "{} has no candidates",
            path.display()
        );
        // Ids are unique within a shader.
        let mut all = ids(&analysis, "candidates");
        all.extend(ids(&analysis, "rejected"));
        let unique: BTreeSet<_> = all.iter().collect();
        assert_eq!(
            unique.len(),
            all.len(),
            "duplicate ids in {}",
            path.display()
        );
    }
}

#[test]
fn ids_are_stable_across_runs_and_unrelated_edits() {
    for path in corpus() {
        let first = analyze_json(&path);
        let second = analyze_json(&path);
        assert_eq!(first, second, "two runs differ on {}", path.display());

        // Add unrelated lines above the fragment entry point.
        let source = std::fs::read_to_string(root().join(&path)).unwrap();
        let at = source.find("@fragment").expect("a fragment entry point");
        let edited = format!(
            "{}// An unrelated helper added above the entry point.\nfn unrelated_helper(x: f32) -> f32 {{\n    return x * 3.0 + 1.0;\n}}\n\n{}",
            &source[..at],
            &source[at..]
        );
        let (_dir, edited_path) = temp_file("edited.wgsl", edited.as_bytes());
        let moved = analyze_json(&edited_path);
        for list in ["candidates", "rejected"] {
            assert_eq!(
                ids(&first, list).into_iter().collect::<BTreeSet<_>>(),
                ids(&moved, list).into_iter().collect::<BTreeSet<_>>(),
                "{list} ids of {} changed when lines were added above the entry point",
                path.display()
            );
        }
        // The entry point's spans moved down by the five added lines (a
        // helper's above the insertion stay).
        let line = |a: &Value| {
            a["candidates"]
                .as_array()
                .unwrap()
                .iter()
                .find(|c| c["call_path"].as_array().unwrap().is_empty())
                .unwrap()["span"]["start"][0]
                .as_u64()
                .unwrap()
        };
        assert_eq!(line(&moved), line(&first) + 5);
    }
}
