//! Joining the shards of a sweep (`profile --shard K/N`, then `shadecache
//! merge`): one report, one Pareto front.
//!
//! Each shard measured its slice of the grid against its own reference,
//! so a row's speed-up is a ratio within one run wherever the shard ran;
//! its milliseconds are not comparable across machines. The merged report
//! keeps every row (a configuration two shards both measured, kept once:
//! the first), ranks them by speed-up, marks the Pareto fronts on time
//! against each row's own reference ([`super::choice::mark_pareto_fronts`],
//! the same function a single run uses) and gives the answer from them.
//! What each shard ran is listed in `merged_from`.
//!
//! Shards of different shaders, entry points, scenes, sizes, frame counts,
//! grids or adapters do not make one report: the merge refuses them,
//! naming what differs, unless told to keep them apart, when each group of
//! alike shards makes a report of its own.

use std::path::{Path, PathBuf};

use crate::report::{Budget, MergedShard, Report, ResultRow};

/// A shard's report, with where it was read.
#[derive(Clone, Debug)]
pub struct ShardReport {
    /// The `report.json` it came from.
    pub path: PathBuf,
    /// The report.
    pub report: Report,
}

/// What must agree for shards to make one report: (what, its value).
type Identity = Vec<(&'static str, String)>;

/// A report's [`Identity`]. Files by their names, not their paths: a
/// shard's checkout may be anywhere. The grid's nodes' ids (hashes of each
/// node's source text) tell one shader from another of the same name; a
/// shard reports only the nodes its slice touched, and names them all in
/// `grid_nodes`.
fn identity(report: &Report) -> Identity {
    let name = |path: &str| {
        Path::new(path)
            .file_name()
            .map_or(path.to_string(), |n| n.to_string_lossy().into_owned())
    };
    let nodes: Vec<&str> = match report.grid_nodes.is_empty() {
        true => report.nodes.iter().map(|n| n.id.as_str()).collect(),
        false => report.grid_nodes.iter().map(String::as_str).collect(),
    };
    vec![
        ("shader", name(&report.shader)),
        ("entry point", report.entry.clone()),
        ("nodes", nodes.join(", ")),
        (
            "scene",
            format!("{} ({})", name(&report.scene), report.scene_description),
        ),
        ("size", format!("{}×{}", report.size[0], report.size[1])),
        (
            "frames",
            format!("{} after {} of warm-up", report.frames, report.warmup),
        ),
        (
            "grid",
            report
                .grid
                .as_ref()
                .map(|g| {
                    format!(
                        "{:?} {}",
                        g.design,
                        serde_json::to_string(&g.axes).unwrap_or_default()
                    )
                })
                .unwrap_or_default(),
        ),
        (
            "adapter",
            format!(
                "{} ({}, {})",
                report.device.name, report.device.backend, report.device.driver
            ),
        ),
    ]
}

/// Joins `shards` into one report; with `keep_apart`, into one per group
/// of shards that agree (in the order each group first appears). Shards
/// that disagree are an error naming the first difference, without
/// `keep_apart`.
pub fn merge(shards: Vec<ShardReport>, keep_apart: bool) -> Result<Vec<Report>, String> {
    let mut groups: Vec<(Identity, Vec<ShardReport>)> = Vec::new();
    for shard in shards {
        let id = identity(&shard.report);
        match groups.iter_mut().find(|(key, _)| *key == id) {
            Some((_, members)) => members.push(shard),
            None => {
                if let (Some((key, members)), false) = (groups.first(), keep_apart) {
                    let (what, ours, theirs) = key
                        .iter()
                        .zip(&id)
                        .find(|(a, b)| a.1 != b.1)
                        .map(|(a, b)| (a.0, a.1.clone(), b.1.clone()))
                        .unwrap_or(("report", String::new(), String::new()));
                    return Err(format!(
                        "{} and {} are not shards of one sweep: their {what} differs ({ours} against {theirs}); merge them with --keep-apart for a report each",
                        members[0].path.display(),
                        shard.path.display()
                    ));
                }
                groups.push((id, vec![shard]));
            }
        }
    }
    groups
        .into_iter()
        .map(|(_, members)| joined(members))
        .collect()
}

/// The shards of one sweep as one report.
fn joined(members: Vec<ShardReport>) -> Result<Report, String> {
    let mut base = members.first().ok_or("nothing to merge")?.report.clone();
    let mut results: Vec<ResultRow> = Vec::new();
    let mut merged_from = Vec::new();
    for member in &members {
        let report = &member.report;
        for row in &report.results {
            if !results.iter().any(|r| same_configuration(r, row)) {
                results.push(row.clone());
            }
        }
        for node in &report.nodes {
            if !base.nodes.iter().any(|n| n.id == node.id) {
                base.nodes.push(node.clone());
            }
        }
        merged_from.push(MergedShard {
            report: member.path.display().to_string(),
            shard: report.shard,
            reference_ms: report.reference.time_ms,
            device: report.device.clone(),
            results: report.results.len(),
        });
    }
    results.sort_by(|a, b| b.speedup.total_cmp(&a.speedup));
    super::choice::mark_pareto_fronts(&mut results);
    if let Some(grid) = base.grid.as_mut() {
        grid.measured = results.len();
    }
    base.results = results;
    // The nodes in the grid's order, as an unsharded run lists them.
    let order = |id: &str| base.grid_nodes.iter().position(|n| n == id);
    if !base.grid_nodes.is_empty() {
        base.nodes.sort_by_key(|n| order(&n.id));
    }
    base.shard = None;
    base.grid_nodes.clear();
    base.merged_from = merged_from;
    base.miss_causes.clear();
    base.warnings.push(format!(
        "merged from {} shard(s): each row's time is its own shard's, its speed-up against that shard's reference; the reference shown is the first shard's",
        members.len()
    ));
    let (budget, budget_given) = base
        .choice
        .as_ref()
        .map_or((Budget::DEFAULT, false), |c| (c.budget, c.budget_given));
    let mut choice = base.choose(budget, budget_given);
    choice.reason = format!(
        "{} (from the merged shards; not measured again)",
        choice.reason
    );
    base.choice = Some(choice);
    Ok(base)
}

/// Whether two rows measured the same configuration.
fn same_configuration(a: &ResultRow, b: &ResultRow) -> bool {
    a.node == b.node
        && a.variant == b.variant
        && a.refresh_period == b.refresh_period
        && a.refresh_quad == b.refresh_quad
        && a.reconstruction == b.reconstruction
        && a.cache_format == b.cache_format
        && a.depth_epsilon == b.depth_epsilon
        && a.adaptive == b.adaptive
}

/// Reads `report.json` from `path` (a file, or a folder holding one).
pub fn read(path: &Path) -> Result<ShardReport, String> {
    let file = if path.is_dir() {
        path.join("report.json")
    } else {
        path.to_path_buf()
    };
    let text = std::fs::read_to_string(&file)
        .map_err(|err| format!("cannot read {}: {err}", file.display()))?;
    let report: Report = serde_json::from_str(&text).map_err(|err| {
        format!(
            "{} is not a profile's report.json: {err} (at line {}, column {})",
            file.display(),
            err.line(),
            err.column()
        )
    })?;
    Ok(ShardReport { path: file, report })
}
