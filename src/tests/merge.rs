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
        merge::Options::default(),
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
    let rejoined = merge::merge(vec![split(0), split(1)], merge::Options::default()).unwrap();
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
        merge::Options::default(),
    )
    .unwrap_err();
    assert!(refused.contains("their shader differs"), "{refused}");
    let apart = merge::merge(
        vec![
            shard_report("a", shards[0].clone()),
            shard_report("b", other),
        ],
        merge::Options {
            keep_apart: true,
            allow_partial: true,
        },
    )
    .unwrap();
    assert_eq!(apart.len(), 2);
}

/// A report of shard `index`/`count` holding one two-pass row per period
/// in `periods`.
fn shard_of(index: u32, count: u32, periods: &[u32]) -> Report {
    use crate::report::fixtures::{node, report, row};
    let mut report = report(
        periods
            .iter()
            .map(|&p| {
                let mut row = row(10.0 / f64::from(p), 40.0, 0.99);
                row.node = "n1".into();
                row.variant = Variant::TwoPass;
                row.refresh_period = p;
                row
            })
            .collect(),
    );
    report.nodes.push(node("n1", 0.5));
    report.shard = Some(Shard { index, count });
    report
}

/// A sweep in three shards merges whole; one missing, one given twice,
/// or one of another N is an error naming it (a CI matrix with a failed
/// or retried job), and `--allow-partial` merges what there is, saying so
/// in the warnings and the answer. A report of another format, or a shard
/// K/N with K > N, is refused where it is read.
#[test]
fn merge_refuses_an_incomplete_or_duplicated_sweep() {
    let whole = || {
        vec![
            shard_report("s1", shard_of(1, 3, &[4])),
            shard_report("s2", shard_of(2, 3, &[8])),
            shard_report("s3", shard_of(3, 3, &[16])),
        ]
    };
    let merged = merge::merge(whole(), merge::Options::default()).unwrap();
    assert_eq!(merged[0].results.len(), 3);
    assert!(!merged[0].warnings.iter().any(|w| w.contains("partial")));

    let mut missing = whole();
    missing.remove(1);
    let err = merge::merge(missing.clone(), merge::Options::default()).unwrap_err();
    assert!(err.contains("missing shard 2/3"), "{err}");
    assert!(err.contains("--allow-partial"), "{err}");

    let mut twice = whole();
    twice.push(shard_report("s3-retried", shard_of(3, 3, &[16])));
    let err = merge::merge(twice, merge::Options::default()).unwrap_err();
    assert!(
        err.contains("shard 3/3 given 2 times (s3, s3-retried)"),
        "{err}"
    );

    let mut other_n = whole();
    other_n.push(shard_report("t2", shard_of(2, 2, &[32])));
    let err = merge::merge(other_n, merge::Options::default()).unwrap_err();
    assert!(
        err.contains("t2 is shard 2/2, of another N than the others' 3"),
        "{err}"
    );

    let partial = merge::merge(
        missing,
        merge::Options {
            allow_partial: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(partial[0].results.len(), 2);
    assert!(
        partial[0]
            .warnings
            .iter()
            .any(|w| w.contains("a partial sweep") && w.contains("2/3")),
        "{:?}",
        partial[0].warnings
    );
    let reason = &partial[0].choice.as_ref().unwrap().reason;
    assert!(
        reason.contains("from a partial sweep, missing shard 2/3"),
        "{reason}"
    );

    // An unsharded run of the grid is whole by itself.
    let mut with_whole_run = whole();
    with_whole_run.truncate(1);
    let mut unsharded = shard_of(1, 1, &[4, 8, 16]);
    unsharded.shard = None;
    with_whole_run.push(shard_report("all", unsharded));
    assert!(merge::merge(with_whole_run, merge::Options::default()).is_ok());

    // Read from files: a report of another format, a shard 5/2, a huge
    // file.
    let temp = tempfile::tempdir().unwrap();
    let dir = temp.path();
    let write = |name: &str, report: &Report| {
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_string(report).unwrap()).unwrap();
        path
    };
    let mut future = shard_of(1, 2, &[4]);
    future.format = 999;
    let err = merge::read(&write("future.json", &future)).unwrap_err();
    assert!(err.contains("a report of format 999"), "{err}");
    let beyond = shard_of(5, 2, &[4]);
    let err = merge::read(&write("beyond.json", &beyond)).unwrap_err();
    assert!(err.contains("says it is shard 5/2"), "{err}");
    let huge = dir.join("huge.json");
    let file = std::fs::File::create(&huge).unwrap();
    file.set_len(merge::MAX_REPORT_BYTES + 10).unwrap();
    let err = merge::read(&huge).unwrap_err();
    assert!(err.contains("larger than the 512 MiB"), "{err}");
    assert!(merge::read(&write("fine.json", &shard_of(1, 2, &[4]))).is_ok());
    // A row no run measures would win the merged answer.
    let mut absurd = shard_of(1, 2, &[4]);
    absurd.results[0].speedup = 1e300;
    let err = merge::read(&write("absurd.json", &absurd)).unwrap_err();
    assert!(err.contains("which no run measures"), "{err}");
    let mut stranger = shard_of(1, 2, &[4]);
    stranger.results[0].node = "nzzzz".into();
    let err = merge::read(&write("stranger.json", &stranger)).unwrap_err();
    assert!(err.contains("names node nzzzz"), "{err}");
}

/// Two lowres runs that differ only in σn are two configurations, each
/// row keeping its own knobs (the header shows none of them then);
/// kept apart, they are two reports.
#[test]
fn merge_keeps_rows_that_differ_in_upsampling_knobs() {
    let lowres = |sigma_normal: f32, factor: u32| {
        let mut report = shard_of(1, 1, &[16]);
        report.shard = None;
        let knobs = crate::rewrite::Upsampling {
            sigma_normal,
            factor,
            ..crate::rewrite::DEFAULT_UPSAMPLING
        };
        report.upsampling = Some(knobs.clone());
        for row in &mut report.results {
            row.variant = Variant::Lowres;
            row.upsampling = Some(knobs.clone());
        }
        report
    };
    let merged = merge::merge(
        vec![
            shard_report("a", lowres(0.2, 4)),
            shard_report("b", lowres(1e-3, 4)),
            shard_report("c", lowres(0.2, 2)),
        ],
        merge::Options::default(),
    )
    .unwrap();
    assert_eq!(merged.len(), 1);
    let rows = &merged[0].results;
    assert_eq!(rows.len(), 3, "one row per set of knobs");
    let knobs: BTreeSet<String> = rows
        .iter()
        .map(|r| {
            let u = r.upsampling.as_ref().unwrap();
            format!("{} {}", u.factor, u.sigma_normal)
        })
        .collect();
    assert_eq!(knobs.len(), 3, "{knobs:?}");
    assert!(merged[0].upsampling.is_none());

    let apart = merge::merge(
        vec![
            shard_report("a", lowres(0.2, 4)),
            shard_report("b", lowres(1e-3, 4)),
        ],
        merge::Options {
            keep_apart: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(apart.len(), 2);
    assert_eq!(apart[0].upsampling.as_ref().unwrap().sigma_normal, 0.2);
    assert_eq!(apart[1].upsampling.as_ref().unwrap().sigma_normal, 1e-3);
}
