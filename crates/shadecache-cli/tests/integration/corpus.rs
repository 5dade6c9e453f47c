//! The corpus: valid for naga and Tint, and every shader has candidates
//! with stable ids.

use std::collections::BTreeSet;

use serde_json::Value;

use crate::util::{analyze_json, corpus, root, temp_file};

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
