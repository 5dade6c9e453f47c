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
//! A merge answers for the whole grid, so it proves that it has it: the
//! shards of one sweep must be 1/N … N/N of one N, each once (an unsharded
//! run of the same grid is whole by itself). A missing or doubled shard —
//! a CI job that failed or ran twice — is an error naming it, unless
//! [`Options::allow_partial`] asks for the answer from what there is;
//! then the report and its answer say which part it is.
//!
//! Shards of different shaders, entry points, scenes, sizes, frame counts,
//! grids or adapters do not make one report: the merge refuses them,
//! naming what differs, unless told to keep them apart, when each group of
//! alike shards makes a report of its own. Runs that differ only in
//! lowres's knobs (s, σn, σz, a) are different configurations of one
//! report: each row keeps its own knobs; kept apart, each gets a report.

use std::path::{Path, PathBuf};

use crate::report::{Budget, MergedShard, Report, ResultRow, Shard, FORMAT};

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

/// How shards are merged.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    /// Shards that do not agree make a report per group of alike shards
    /// (lowres's knobs included), instead of an error.
    pub keep_apart: bool,
    /// A sweep with shards missing or doubled is merged from what there
    /// is, and says so, instead of being an error.
    pub allow_partial: bool,
}

/// The largest `report.json` read: a sweep of 20 000 rows is about 35 MB.
/// A bound, so that a huge file given by mistake (a disk image, a link to
/// `/dev/zero`) is an error rather than the machine's memory.
pub const MAX_REPORT_BYTES: u64 = 512 << 20;

/// A report's [`Identity`]. Files by their names, not their paths: a
/// shard's checkout may be anywhere. The grid's nodes' ids (hashes of each
/// node's source text) tell one shader from another of the same name; a
/// shard reports only the nodes its slice touched, and names them all in
/// `grid_nodes`. Lowres's knobs are part of it when `with_knobs`.
fn identity(report: &Report, with_knobs: bool) -> Identity {
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
        (
            "lowres knobs",
            match with_knobs {
                true => knobs(report),
                false => String::new(),
            },
        ),
    ]
}

/// Lowres's knobs as a report sets them, in words (empty without lowres).
fn knobs(report: &Report) -> String {
    report
        .upsampling
        .as_ref()
        .map_or(String::new(), |u| u.in_words())
}

/// Joins `shards` into one report; with `keep_apart`, into one per group
/// of shards that agree (in the order each group first appears). Shards
/// that disagree are an error naming the first difference, without
/// `keep_apart`; so is a sweep with shards missing or doubled, without
/// `allow_partial`.
pub fn merge(shards: Vec<ShardReport>, options: Options) -> Result<Vec<Report>, String> {
    let mut groups: Vec<(Identity, Vec<ShardReport>)> = Vec::new();
    for shard in shards {
        let id = identity(&shard.report, options.keep_apart);
        match groups.iter_mut().find(|(key, _)| *key == id) {
            Some((_, members)) => members.push(shard),
            None => {
                if let (Some((key, members)), false) = (groups.first(), options.keep_apart) {
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
        .map(|(_, members)| {
            let gaps = gaps(&members);
            match (gaps.is_empty(), options.allow_partial) {
                (false, false) => Err(format!(
                    "the shards do not make a whole sweep: {}; merge them with --allow-partial for an answer from part of the grid",
                    gaps.join("; ")
                )),
                _ => joined(members, &gaps),
            }
        })
        .collect()
}

/// What keeps `members` from being whole sweeps, in words (nothing when
/// they are): per run of one set of lowres knobs, the shards missing, the
/// shards given twice, and shards of another N. An unsharded run is whole.
fn gaps(members: &[ShardReport]) -> Vec<String> {
    let mut sweeps: Vec<(String, Vec<&ShardReport>)> = Vec::new();
    for member in members {
        let key = knobs(&member.report);
        match sweeps.iter_mut().find(|(k, _)| *k == key) {
            Some((_, list)) => list.push(member),
            None => sweeps.push((key, vec![member])),
        }
    }
    let mut gaps = Vec::new();
    for (key, list) in sweeps {
        let of = match key.is_empty() {
            true => String::new(),
            false => format!(" (lowres at {key})"),
        };
        if list.iter().any(|m| m.report.shard.is_none()) {
            continue;
        }
        let shards: Vec<(Shard, &ShardReport)> = list
            .iter()
            .filter_map(|m| m.report.shard.map(|s| (s, *m)))
            .collect();
        // The N most shards give; the others are of another sweep.
        let count = shards
            .iter()
            .map(|(s, _)| s.count)
            .max_by_key(|&n| (shards.iter().filter(|(s, _)| s.count == n).count(), n))
            .unwrap_or(1);
        for (shard, member) in shards.iter().filter(|(s, _)| s.count != count) {
            gaps.push(format!(
                "{} is shard {shard}, of another N than the others' {count}{of}",
                member.path.display()
            ));
        }
        let missing: Vec<String> = (1..=count)
            .filter(|&k| !shards.iter().any(|(s, _)| s.count == count && s.index == k))
            .map(|k| format!("{k}/{count}"))
            .collect();
        if !missing.is_empty() {
            gaps.push(format!("missing shard {}{of}", missing.join(", ")));
        }
        for k in 1..=count {
            let twice: Vec<String> = shards
                .iter()
                .filter(|(s, _)| s.count == count && s.index == k)
                .map(|(_, m)| m.path.display().to_string())
                .collect();
            if twice.len() > 1 {
                gaps.push(format!(
                    "shard {k}/{count}{of} given {} times ({})",
                    twice.len(),
                    twice.join(", ")
                ));
            }
        }
    }
    gaps
}

/// The shards of one sweep as one report; `gaps` (what keeps it from
/// being whole, when merged anyway) said in its warnings and its answer.
fn joined(members: Vec<ShardReport>, gaps: &[String]) -> Result<Report, String> {
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
    // Lowres's knobs in the header only where every row has the same:
    // otherwise each row's are its own.
    let mut knobs = members.iter().filter_map(|m| m.report.upsampling.as_ref());
    if let Some(first) = knobs.next() {
        if knobs.any(|u| u != first) {
            base.upsampling = None;
            base.warnings.push(
                "the merged runs set lowres's knobs differently: each lowres row shows its own"
                    .into(),
            );
        }
    }
    if !gaps.is_empty() {
        base.warnings.push(format!(
            "a partial sweep (--allow-partial): {}; the answer is from part of the grid",
            gaps.join("; ")
        ));
    }
    let (budget, budget_given) = base
        .choice
        .as_ref()
        .map_or((Budget::DEFAULT, false), |c| (c.budget, c.budget_given));
    let mut choice = base.choose(budget, budget_given);
    choice.reason = match gaps.is_empty() {
        true => format!(
            "{} (from the merged shards; not measured again)",
            choice.reason
        ),
        false => format!(
            "{} (from a partial sweep, {}; not measured again)",
            choice.reason,
            gaps.join("; ")
        ),
    };
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
        && a.upsampling == b.upsampling
}

/// Reads `report.json` from `path` (a file, or a folder holding one): at
/// most [`MAX_REPORT_BYTES`], of this build's [`FORMAT`], and a shard
/// `K/N` with 1 ≤ K ≤ N where it is one.
pub fn read(path: &Path) -> Result<ShardReport, String> {
    use std::io::Read;
    let file = if path.is_dir() {
        path.join("report.json")
    } else {
        path.to_path_buf()
    };
    let cannot = |err: std::io::Error| format!("cannot read {}: {err}", file.display());
    let mut bytes = Vec::new();
    std::fs::File::open(&file)
        .and_then(|f| f.take(MAX_REPORT_BYTES + 1).read_to_end(&mut bytes))
        .map_err(cannot)?;
    if bytes.len() as u64 > MAX_REPORT_BYTES {
        return Err(format!(
            "{} is larger than the {} MiB a report.json can be: it is not a profile's report",
            file.display(),
            MAX_REPORT_BYTES >> 20
        ));
    }
    let not_a_report =
        |what: String| format!("{} is not a profile's report.json: {what}", file.display());
    let text = String::from_utf8(bytes).map_err(|_| not_a_report("it is not UTF-8 text".into()))?;
    let report: Report =
        serde_json::from_str(&text).map_err(|err| not_a_report(err.to_string()))?;
    if report.format != FORMAT {
        return Err(format!(
            "{} is a report of format {}, and this build reads format {FORMAT}: merge it with the shadecache that wrote it",
            file.display(),
            report.format
        ));
    }
    // The rows' figures are what the merged answer ranks: a hand-edited
    // or corrupted one must not win it.
    for (i, row) in report.results.iter().enumerate() {
        let sane = |v: f64| v.is_finite() && v > 0.0 && v < 1e6;
        if !(sane(row.speedup) && sane(row.time_ms) && row.psnr.is_finite()) {
            return Err(format!(
                "{}: row {} ({} {}) has speed-up {}, time {} ms and PSNR {}, which no run measures",
                file.display(),
                i + 1,
                row.node,
                row.variant,
                row.speedup,
                row.time_ms,
                row.psnr
            ));
        }
        if !report.nodes.iter().any(|n| n.id == row.node) {
            return Err(format!(
                "{}: row {} names node {}, which the report does not list",
                file.display(),
                i + 1,
                row.node
            ));
        }
    }
    if let Some(shard) = report.shard {
        if !shard.is_valid() {
            return Err(format!(
                "{} says it is shard {shard}, which is not K/N with 1 ≤ K ≤ N",
                file.display()
            ));
        }
    }
    Ok(ShardReport { path: file, report })
}
