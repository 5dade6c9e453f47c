//! Sharded sweeps merged equal the unsharded sweep.

use super::profile::run;
use super::util::marble_scene;
use crate::profile::merge::{self, ShardReport};
use crate::profile::{Nodes, Options};
use crate::report::{Report, Shard};
use crate::rewrite::{CacheFormat, CacheRead, Variant};
use std::collections::BTreeSet;

/// A small sweep: the sweep's pruned planes over two periods, two block
/// sizes and two reconstructions, two variants of the top two nodes.
fn sweep(shard: Option<Shard>) -> Option<Report> {
    let options = Options {
        nodes: Nodes::Top(2),
        variants: vec![Variant::TwoPass, Variant::ThreePass],
        refresh_periods: vec![8, 32],
        refresh_quads: vec![1, 4],
        reconstructions: vec![CacheRead::Bilinear, CacheRead::Nearest],
        cache_formats: vec![CacheFormat::Rgba16float],
        depth_epsilons: vec![crate::rewrite::DEFAULT_DEPTH_EPSILON],
        adaptive_refresh: vec![false],
        size: Some([32, 32]),
        frames: Some(3),
        warmup: Some(2),
        shard,
        ..Options::default().sweep()
    };
    run(&marble_scene("\"object-motion\"", ""), options).map(|(_, report, _)| report)
}

/// The configurations a report measured, in words.
fn configurations(report: &Report) -> BTreeSet<String> {
    report
        .results
        .iter()
        .map(|r| format!("{} {} {}", r.node, r.variant, r.setting()))
        .collect()
}

fn shard_report(name: &str, report: Report) -> ShardReport {
    ShardReport {
        path: name.into(),
        report,
    }
}

/// Two shards measure, between them, exactly the unsharded sweep's
/// configurations, neither twice; each reports (and times the fixed costs
/// of) only the nodes its slice touches; merged they are one report of
/// those configurations and of the sweep's nodes, in its order. The merge
/// marks the fronts from the merged rows with the function a single run
/// uses: one run's rows split into shards and merged again give that
/// run's fronts back, row for row. Shards of another shader are refused,
/// naming it, unless kept apart.
#[test]
fn merged_shards_equal_the_unsharded_sweep() {
    let Some(whole) = sweep(None) else { return };
    let shards: Vec<Report> = (1..=2)
        .map(|index| sweep(Some(Shard { index, count: 2 })).unwrap())
        .collect();
    let (all, first, second) = (
        configurations(&whole),
        configurations(&shards[0]),
        configurations(&shards[1]),
    );
    assert!(all.len() >= 4, "{all:?}");
    assert!(!first.is_empty() && !second.is_empty());
    assert!(first.is_disjoint(&second), "{first:?} {second:?}");
    assert_eq!(&first | &second, all);
    assert_eq!(shards[0].shard, Some(Shard { index: 1, count: 2 }));
    let ids =
        |report: &Report| -> Vec<String> { report.nodes.iter().map(|n| n.id.clone()).collect() };
    assert_eq!(whole.nodes.len(), 2);
    assert_eq!(ids(&shards[0]), ids(&whole)[..1]);
    assert_eq!(ids(&shards[1]), ids(&whole)[1..]);
    assert_eq!(shards[1].grid_nodes, ids(&whole));

    let merged = merge::merge(
        shards
            .iter()
            .enumerate()
            .map(|(i, r)| shard_report(&format!("shard{i}"), r.clone()))
            .collect(),
        false,
    )
    .unwrap();
    assert_eq!(merged.len(), 1);
    assert_eq!(configurations(&merged[0]), all);
    assert_eq!(ids(&merged[0]), ids(&whole));
    assert!(merged[0].grid_nodes.is_empty());
    assert_eq!(merged[0].merged_from.len(), 2);
    assert!(merged[0].choice.is_some());

    // The same rows, split and merged: the same fronts.
    let split = |keep: usize| {
        let mut part = whole.clone();
        part.results = whole
            .results
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 2 == keep)
            .map(|(_, r)| r.clone())
            .collect();
        part.results.iter_mut().for_each(|r| {
            r.pareto_psnr = false;
            r.pareto_ssim = false;
        });
        shard_report(&format!("half{keep}"), part)
    };
    let rejoined = merge::merge(vec![split(0), split(1)], false).unwrap();
    let fronts = |report: &Report| -> BTreeSet<(String, bool, bool)> {
        report
            .results
            .iter()
            .map(|r| {
                (
                    format!("{} {} {}", r.node, r.variant, r.setting()),
                    r.pareto_psnr,
                    r.pareto_ssim,
                )
            })
            .collect()
    };
    assert_eq!(fronts(&rejoined[0]), fronts(&whole));

    // Another shader's shard.
    let mut other = shards[1].clone();
    other.shader = "other.wgsl".into();
    let refused = merge::merge(
        vec![
            shard_report("a", shards[0].clone()),
            shard_report("b", other.clone()),
        ],
        false,
    )
    .unwrap_err();
    assert!(refused.contains("their shader differs"), "{refused}");
    let apart = merge::merge(
        vec![
            shard_report("a", shards[0].clone()),
            shard_report("b", other),
        ],
        true,
    )
    .unwrap();
    assert_eq!(apart.len(), 2);
}
