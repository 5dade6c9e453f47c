//! The report as one self-contained HTML page: the answer first, then the
//! tables, the nodes in their source, the charts (inline SVG) and the
//! pictures (inline PNG).

use std::fmt::Write;
use std::path::Path;

use base64::Engine;

use super::plots::{chart, escape, informative, Series};
use super::{images, Report, ResultRow};
use crate::plan::Variant;

/// Renders `report`; PNGs under `dir` (from [`super::write_images`]) are
/// embedded.
pub fn html(report: &Report, dir: &Path) -> String {
    let mut page = header(report);
    page.push_str(&reference_box(report, dir));
    for warning in &report.warnings {
        let _ = write!(
            page,
            "<p class=\"answer\"><b>Warning:</b> {}.</p>",
            escape(warning)
        );
    }
    page.push_str(&answer(report));
    page.push_str(&results_tables(report));
    page.push_str(&miss_causes(report));
    page.push_str(&nodes(report));
    page.push_str(&charts(report));
    page.push_str(&pareto_table(report));
    page.push_str(&grid_section(report));
    page.push_str(&pictures(report, dir));
    page.push_str("</div></body></html>\n");
    page
}

/// The page's head, title, what was run, and the warm-up's caveat.
fn header(report: &Report) -> String {
    let mut page = String::new();
    let _ = write!(
        page,
        "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>shadecache profile: {}</title><style>{}</style></head><body>",
        escape(&report.shader),
        STYLE
    );
    let _ = write!(
        page,
        "<h1>shadecache profile of <code>{}</code></h1>",
        escape(&report.shader)
    );
    let _ = write!(
        page,
        "<p class=\"meta\">Scene <code>{}</code>{} — {}×{}, {} measured frames after {} warm-up — effects: {} — {} ({}, {}) — timing: {}<br>Command: <code>{}</code></p>",
        escape(&report.scene),
        if report.scene_description.is_empty() { String::new() } else { format!(" ({})", escape(&report.scene_description)) },
        report.size[0],
        report.size[1],
        report.frames,
        report.warmup,
        if report.effects.is_empty() {
            "none".to_string()
        } else {
            report.effects.iter().map(|e| format!("{e:?}")).collect::<Vec<_>>().join(", ")
        },
        escape(&report.device.name),
        escape(&report.device.backend),
        escape(&report.device.driver),
        escape(&report.timing),
        escape(&report.command),
    );
    if let Some(u) = &report.upsampling {
        let _ = write!(
            page,
            "<p>Lowres (Herzog et al. 2010): one pixel of each {s}×{s} window shaded per frame (Δn = {}, k = {s} in the tables), σn = {}, σz = {} of the depth, a = {}. In its maps blue is a pixel shaded this frame, green one whose history was reused, red and orange one whose history was missing.</p>",
            u.factor * u.factor,
            u.sigma_normal,
            u.sigma_depth,
            u.sensitivity,
            s = u.factor,
        );
    }
    if !report.steady_state {
        let _ = write!(
            page,
            "<p class=\"answer\">The {} warm-up frames are fewer than the longest refresh period measured: the errors below are those of a cache younger than in its steady state, and lower than they will be. Leave <code>--warmup</code> out to measure them in the steady state.</p>",
            report.warmup
        );
    }
    page
}

/// The answer: the choice (the same sentence stdout gives), then the
/// fastest configuration measured, whatever its error.
fn answer(report: &Report) -> String {
    let mut page = String::new();
    page.push_str("<h2>Which value to cache</h2>");
    if let Some(choice) = &report.choice {
        let budget = if choice.budget_given {
            format!("within {}", choice.budget)
        } else {
            format!(
                "within {} (the default; <code>--max-error</code> sets it)",
                choice.budget
            )
        };
        let what = match choice.result.map(|i| &report.results[i]) {
            Some(row) => format!(
                "Cache <code>{}</code> (node <code>{}</code>) with the <b>{}</b> variant, {}. ",
                escape(&row.node_text),
                escape(&row.node),
                row.variant,
                escape(&row.setting())
            ),
            None => "<b>Keep the original shader.</b> ".into(),
        };
        let _ = write!(
            page,
            "<p class=\"answer\">{what}Answer {budget}: {}{}</p>",
            escape(&choice.reason),
            if choice.result.is_some() {
                " Its shaders and plan are in <code>choice/</code>."
            } else {
                ""
            }
        );
    }
    match report.results.first() {
        Some(best) => {
            let _ = write!(
                page,
                "<p>Fastest measured, whatever its error: <code>{}</code> (node <code>{}</code>), {}, Δn = {}, k = {}: {:.2}× [{:.2}, {:.2}] against the original ({:.3} ms against {:.3} ms, whose frames spread {:.3}–{:.3} ms), {:.0}% of the ideal {:.2}× for P/T = {:.2} and {:.0}% reuse; PSNR {:.1} dB, SSIM {:.4}, largest error {:.3}.</p>",
                escape(&best.node_text),
                escape(&best.node),
                best.variant,
                best.refresh_period,
                best.refresh_quad,
                best.speedup,
                best.speedup_ci[0],
                best.speedup_ci[1],
                best.time_ms,
                report.reference.time_ms,
                report.reference.spread_ms[0],
                report.reference.spread_ms[1],
                best.share_of_ideal * 100.0,
                best.ideal_speedup,
                best.p_over_t,
                best.hit_rate * 100.0,
                best.psnr,
                best.ssim,
                best.max_abs_error
            );
        }
        None => page.push_str("<p>No configuration could be measured.</p>"),
    }
    page
}

/// What each declared effect causes alone.
fn miss_causes(report: &Report) -> String {
    let mut page = String::new();
    if !report.miss_causes.is_empty() {
        page.push_str("<h2>What causes the misses</h2><p>The fastest configuration again, with one declared effect at a time (refreshes come from the refresh pattern alone).</p><table><tr><th>effect</th><th>miss</th><th>off-screen</th><th>disoccluded</th></tr>");
        for cause in &report.miss_causes {
            let _ = write!(
                page,
                "<tr><td>{:?}</td><td>{:.2}%</td><td>{:.2}%</td><td>{:.2}%</td></tr>",
                cause.effect,
                cause.miss_rate * 100.0,
                cause.offscreen_rate * 100.0,
                cause.disocclusion_rate * 100.0
            );
        }
        page.push_str("</table>");
    }
    page
}

/// The nodes in their source.
fn nodes(report: &Report) -> String {
    let mut page = String::new();
    page.push_str("<h2>Nodes</h2>");
    for node in &report.nodes {
        let _ = write!(
            page,
            "<h3><code>{}</code> — {} at {}:{}</h3><p>P/T estimated {:.3}, measured {:.3} (payload pass {:.3} ms). Value {} in this scene: {}.</p><pre>{}</pre>",
            escape(&node.id),
            escape(&node.ty),
            node.start[0],
            node.start[1],
            node.estimated_p_over_t,
            node.p_over_t,
            node.payload_ms,
            escape(&crate::analysis::range::describe(node.range)),
            if node.fits_f16 {
                "fits an rgba16float cache"
            } else {
                "may not fit rgba16float, so a three-pass cache of it runs in rgba32float"
            },
            highlight(&node.source, node.start, node.end)
        );
    }
    page
}

/// The charts with something to show: a knob measured at one value, a
/// single node or a single configuration draws nothing.
fn charts(report: &Report) -> String {
    let mut page = String::new();
    page.push_str("<h2>Charts</h2>");
    let charts = [
        time_per_node(report),
        speedup_per_period(report),
        error_against_time(report, "PSNR (dB)", |r| r.psnr, |r| r.pareto_psnr),
        error_against_time(report, "SSIM", |r| r.ssim, |r| r.pareto_ssim),
    ];
    if charts.iter().all(String::is_empty) {
        page.push_str("<p>Nothing to chart: the run measured one node at one value of each knob (<code>--sweep</code> or lists of values measure more).</p>");
    }
    for chart in charts {
        page.push_str(&chart);
    }
    page
}

/// The reference, the best result, their difference and the maps of
/// the cache's decisions (the page's last section, its `div` left open).
fn pictures(report: &Report, dir: &Path) -> String {
    let mut page = String::new();
    page.push_str("<h2>Pictures</h2><p>Maps of the cache's decisions: <span style=\"color:#0a0\">hit</span>, <span style=\"color:#00f\">refresh</span>, <span style=\"color:#f00\">miss (disoccluded)</span>, <span style=\"color:#f80\">miss (off-screen)</span>.</p><div class=\"pictures\">");
    for (caption, path) in [
        ("reference", dir.join("images/reference.png")),
        ("best result", dir.join("images/best.png")),
        ("difference ×4", dir.join("images/difference.png")),
    ] {
        embed(&mut page, caption, &path);
    }
    for (rank, row) in report.results.iter().enumerate().take(12) {
        let name = images::map_name(rank, row);
        embed(
            &mut page,
            &format!("#{} {} {}", rank + 1, row.node, row.variant),
            &dir.join("maps").join(name),
        );
    }
    page
}

/// What every figure below is measured against: the reference's last
/// measured frame (a thumbnail), its check, and the inputs nothing said
/// the value of. A degenerate reference is said here, before the answer.
fn reference_box(report: &Report, dir: &Path) -> String {
    let mut out = String::new();
    let degenerate = report
        .reference_check
        .as_ref()
        .is_some_and(|c| c.degenerate());
    let _ = write!(
        out,
        "<div class=\"{}\"><div class=\"pictures\">",
        if degenerate {
            "reference degenerate"
        } else {
            "reference"
        }
    );
    embed(
        &mut out,
        "reference, last measured frame",
        &dir.join("images/reference.png"),
    );
    out.push_str("<div>");
    if let Some(check) = &report.reference_check {
        let _ = write!(
            out,
            "<p><b>Reference check</b> ({} measured frames): {}.</p>",
            check.frames,
            escape(&check.summary())
        );
        for problem in &check.problems {
            let _ = write!(
                out,
                "<p><b>Degenerate reference:</b> {}. <i>Likely cause:</i> {}</p>",
                escape(&problem.finding),
                escape(&problem.cause)
            );
        }
        if degenerate {
            out.push_str("<p>No configuration is recommended on this reference: its errors compare frames that show nothing of the shader.</p>");
        }
    }
    if report.defaulted.is_empty() {
        out.push_str("<p>Every input the shader reads came from the scene.</p>");
    } else {
        let _ = write!(
            out,
            "<details{}><summary>Filled-in inputs ({}): nothing said what they are; <code>shadecache scene init</code> writes them out to edit</summary><ul>",
            if degenerate { " open" } else { "" },
            report.defaulted.len()
        );
        for line in &report.defaulted {
            let _ = write!(out, "<li><code>{}</code></li>", escape(line));
        }
        out.push_str("</ul></details>");
    }
    out.push_str("</div></div></div>");
    out
}

fn embed(page: &mut String, caption: &str, path: &Path) {
    if let Ok(bytes) = std::fs::read(path) {
        let _ = write!(
            page,
            "<figure><img alt=\"{0}\" src=\"data:image/png;base64,{1}\"><figcaption>{0}</figcaption></figure>",
            escape(caption),
            base64::engine::general_purpose::STANDARD.encode(bytes)
        );
    }
}

/// The node's lines with the node itself marked.
fn highlight(source: &str, start: [usize; 2], end: [usize; 2]) -> String {
    let mut out = String::new();
    for (i, line) in source.lines().enumerate() {
        let number = start[0] + i;
        let chars: Vec<char> = line.chars().collect();
        let from = if number == start[0] {
            start[1].saturating_sub(1)
        } else {
            0
        };
        let to = if number == end[0] {
            end[1].saturating_sub(1)
        } else {
            chars.len()
        };
        let (from, to) = (
            from.min(chars.len()),
            to.min(chars.len()).max(from.min(chars.len())),
        );
        let piece = |a: usize, b: usize| escape(&chars[a..b].iter().collect::<String>());
        let _ = writeln!(
            out,
            "{:>4} | {}<mark>{}</mark>{}",
            number,
            piece(0, from),
            piece(from, to),
            piece(to, chars.len())
        );
    }
    out
}

/// Nodes the fig. 8 chart names one by one on its x axis; with more (as
/// `--nodes all` gives) the axis is the measured P/T itself.
const NAMED_NODES: usize = 16;

/// Seed 002 fig. 8: render time per node, nodes in order of measured P/T,
/// one line per variant and the reference. Up to [`NAMED_NODES`] nodes,
/// each has a category of its own, as in the paper's figure; with more,
/// each sits at its measured P/T on an axis over the whole range (the
/// reference drawn from 0 to 1), so hundreds of nodes stay readable and
/// the gaps between their P/Ts show.
fn time_per_node(report: &Report) -> String {
    let mut nodes = report.nodes.clone();
    nodes.sort_by(|a, b| a.p_over_t.total_cmp(&b.p_over_t));
    if nodes.len() < 2 {
        return String::new();
    }
    let by_value = nodes.len() > NAMED_NODES;
    let x = |i: usize| {
        if by_value {
            nodes[i].p_over_t
        } else {
            i as f64
        }
    };
    let reference_xs: Vec<f64> = if by_value {
        vec![0f64.min(x(0)), 1f64.max(x(nodes.len() - 1))]
    } else {
        (0..nodes.len()).map(|i| i as f64).collect()
    };
    let mut series = vec![Series {
        name: "reference".into(),
        points: reference_xs
            .into_iter()
            .map(|x| (x, report.reference.time_ms))
            .collect(),
        line: true,
        ..Series::default()
    }];
    for variant in Variant::ALL {
        let (points, titles): (Vec<(f64, f64)>, Vec<String>) = nodes
            .iter()
            .enumerate()
            .filter_map(|(i, node)| {
                report
                    .results
                    .iter()
                    .filter(|r| r.node == node.id && r.variant == variant)
                    .map(|r| r.time_ms)
                    .min_by(f64::total_cmp)
                    .map(|t| {
                        let title =
                            format!("{variant} {}: P/T {:.3}, {t:.3} ms", node.id, node.p_over_t);
                        ((x(i), t), title)
                    })
            })
            .unzip();
        if !points.is_empty() {
            series.push(Series {
                name: variant.to_string(),
                points,
                line: true,
                titles,
                ..Series::default()
            });
        }
    }
    if by_value {
        chart(
            &format!(
                "Render time per node ({} nodes at their measured P/T)",
                nodes.len()
            ),
            "measured P/T",
            "ms per frame",
            &series,
            None,
        )
    } else {
        let labels: Vec<String> = nodes
            .iter()
            .map(|n| format!("{} ({:.2})", n.id, n.p_over_t))
            .collect();
        chart(
            "Render time per node (nodes by measured P/T)",
            "node (P/T)",
            "ms per frame",
            &series,
            Some(&labels),
        )
    }
}

/// Seed 002 fig. 9: speed-up against Δn, one line per k, for the best
/// node and variant.
fn speedup_per_period(report: &Report) -> String {
    let Some(best) = report.results.first() else {
        return String::new();
    };
    let mut quads: Vec<u32> = report.results.iter().map(|r| r.refresh_quad).collect();
    quads.sort_unstable();
    quads.dedup();
    let series: Vec<Series> = quads
        .iter()
        .map(|&k| {
            let mut rows: Vec<(usize, &ResultRow)> = report
                .results
                .iter()
                .enumerate()
                .filter(|(_, r)| {
                    r.node == best.node
                        && r.variant == best.variant
                        && r.reconstruction == best.reconstruction
                        && r.refresh_quad == k
                })
                .collect();
            rows.sort_by_key(|(_, r)| r.refresh_period);
            Series {
                name: format!("k = {k}"),
                points: rows
                    .iter()
                    .map(|(_, r)| (f64::from(r.refresh_period), r.speedup))
                    .collect(),
                line: true,
                titles: rows.iter().map(|&(i, r)| point_title(i, r, "")).collect(),
                marks: Vec::new(),
            }
        })
        .collect();
    // A knob measured at one value would draw an empty axis.
    if !informative(&series) {
        return String::new();
    }
    chart(
        &format!(
            "Speed-up against Δn ({} {}, {})",
            best.node,
            best.variant,
            best.reconstruction.as_str()
        ),
        "Δn (refresh period, frames)",
        "speed-up",
        &series,
        None,
    )
}

/// Error against time: every configuration, one colour per variant, and
/// the Pareto front through them (from the unmodified shader's exact image
/// at its time, see [`super::mark_pareto_fronts`]).
fn error_against_time(
    report: &Report,
    metric: &str,
    value: fn(&ResultRow) -> f64,
    on_front: fn(&ResultRow) -> bool,
) -> String {
    if report.results.len() < 2 {
        return String::new();
    }
    let mut series: Vec<Series> = Variant::ALL
        .iter()
        .map(|&variant| {
            let rows: Vec<(usize, &ResultRow)> = report
                .results
                .iter()
                .enumerate()
                .filter(|(_, r)| r.variant == variant)
                .collect();
            Series {
                name: variant.to_string(),
                points: rows.iter().map(|(_, r)| (r.time_ms, value(r))).collect(),
                line: false,
                titles: rows
                    .iter()
                    .map(|&(i, r)| point_title(i, r, metric))
                    .collect(),
                marks: Vec::new(),
            }
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    // The front's points are labelled with their rank in the results
    // table.
    let mut front: Vec<(usize, &ResultRow)> = report
        .results
        .iter()
        .enumerate()
        .filter(|(_, r)| on_front(r))
        .collect();
    front.sort_by(|a, b| a.1.time_ms.total_cmp(&b.1.time_ms));
    if !front.is_empty() {
        series.push(Series {
            name: "Pareto front".into(),
            points: front.iter().map(|(_, r)| (r.time_ms, value(r))).collect(),
            line: true,
            titles: front
                .iter()
                .map(|&(i, r)| point_title(i, r, metric))
                .collect(),
            marks: front.iter().map(|(i, _)| format!("#{}", i + 1)).collect(),
        });
    }
    chart(
        &format!("{metric} against time"),
        "ms per frame",
        metric,
        &series,
        None,
    )
}

/// What hovering a result's point says: its rank (`index` in the results
/// table), node, variant, knobs, time and error.
fn point_title(index: usize, row: &ResultRow, metric: &str) -> String {
    let rank = format!("#{} ", index + 1);
    format!(
        "{rank}{} {}, {}: {:.3} ms, {:.2}× [{:.2}, {:.2}], PSNR {:.1} dB, SSIM {:.4}{}",
        row.node,
        row.variant,
        row.setting(),
        row.time_ms,
        row.speedup,
        row.speedup_ci[0],
        row.speedup_ci[1],
        row.psnr,
        row.ssim,
        if metric.is_empty() {
            String::new()
        } else {
            format!(" ({metric} plotted)")
        }
    )
}

/// The cells naming a result's configuration: node, variant, Δn, k,
/// reconstruction, cache format, ε.
fn configuration_cells(row: &ResultRow) -> String {
    format!(
        "<td><code>{}</code></td><td>{}</td><td>{}</td>",
        escape(&row.node),
        row.variant,
        knobs(row)
    )
}

/// A configuration's knobs in one cell: Δn, k, reconstruction, cache
/// format, ε, adaptive refresh, and lowres's s, σn, σz and a.
fn knobs(row: &ResultRow) -> String {
    let lowres = row.upsampling.as_ref().map_or(String::new(), |u| {
        format!(
            " · s {} · σn {} · σz {} · a {}",
            u.factor, u.sigma_normal, u.sigma_depth, u.sensitivity
        )
    });
    format!(
        "Δn {} · k {} · {} · {} · ε {}{}{lowres}",
        row.refresh_period,
        row.refresh_quad,
        row.reconstruction.as_str(),
        row.cache_format.as_str(),
        row.depth_epsilon,
        row.adaptive_words().replace(", ", " · ")
    )
}

/// Every configuration measured: a table that fits a laptop's screen (the
/// figures a choice rests on), the rest in a second one on demand, and
/// what the figures that can pass their natural range mean.
fn results_tables(report: &Report) -> String {
    let mut page = String::from("<h2>Results</h2><div class=\"wide\"><table><tr><th>#</th><th>node</th><th>variant</th><th>knobs</th><th>time ms</th><th>speed-up [95%]</th><th>ideal</th><th title=\"measured speed-up over the ideal\">share of ideal</th><th>P/T</th><th>hit / miss / refresh</th><th>PSNR dB</th><th>SSIM</th><th>map</th></tr>");
    let _ = write!(
        page,
        "<tr class=\"reference\"><td></td><td colspan=\"3\">reference (unmodified shader)</td><td>{:.3}</td><td colspan=\"7\">frames {:.3}–{:.3} ms</td><td></td></tr>",
        report.reference.time_ms,
        report.reference.spread_ms[0],
        report.reference.spread_ms[1]
    );
    for (rank, row) in report.results.iter().enumerate() {
        let _ = write!(
            page,
            "<tr><td>{}</td>{}<td>{:.3}</td><td>{:.2}× [{:.2}, {:.2}]</td><td>{:.2}×</td><td>{:.0}%</td><td>{:.2}</td><td>{:.0}% / {:.1}% / {:.0}%</td><td>{:.1}</td><td>{:.4}</td><td><a href=\"maps/{}\">png</a></td></tr>",
            rank + 1,
            configuration_cells(row),
            row.time_ms,
            row.speedup,
            row.speedup_ci[0],
            row.speedup_ci[1],
            row.ideal_speedup,
            row.share_of_ideal * 100.0,
            row.p_over_t,
            row.hit_rate * 100.0,
            row.miss_rate * 100.0,
            row.refresh_rate * 100.0,
            row.psnr,
            row.ssim,
            images::map_name(rank, row),
        );
    }
    page.push_str("</table></div>");
    page.push_str("<p class=\"meta\"><b>ideal</b>: the most caching could give, 1 / (1 − ρ·P/T), with ρ the share of pixels reused (hits not refreshed). <b>share of ideal</b>: the measured speed-up over that. It passes 100% when a variant saves more than its payload's measured cost — the payload pass is timed alone and net of its fixed cost, so work the variant also skips, or the noise of a ratio of two short times, puts it above. <b>P/T</b>: the payload pass's time, net of its fixed cost, over the original's; it passes 1 when computing the payload alone costs more than the whole original (writing it to a target, overhead the fixed-cost probe does not catch). PSNR is over the pixels the shader draws.</p>");
    page.push_str("<details><summary>More per configuration: pass times, bounds with fixed costs, misses by cause, worst-frame and whole-frame PSNR, flicker, largest error</summary><div class=\"wide\"><table><tr><th>#</th><th>passes ms</th><th>bound with fixed costs (fixed ms per pass)</th><th>miss off-screen / disoccluded</th><th>PSNR worst frame, whole frame</th><th>flicker</th><th>max err</th></tr>");
    for (rank, row) in report.results.iter().enumerate() {
        let passes: Vec<String> = row
            .passes
            .iter()
            .map(|p| format!("{} {:.3}", p.name, p.time_ms))
            .collect();
        let fixed: Vec<String> = row
            .fixed_cost_ms
            .iter()
            .map(|p| format!("{} {:.3}", p.name, p.time_ms))
            .collect();
        let _ = write!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{:.2}× ({})</td><td>{:.1}% / {:.1}%</td><td>{:.1}, {:.1}</td><td>{:.4}</td><td>{:.3}</td></tr>",
            rank + 1,
            escape(&passes.join(", ")),
            row.bound_with_fixed_costs,
            escape(&fixed.join(", ")),
            row.offscreen_rate * 100.0,
            row.disocclusion_rate * 100.0,
            row.worst_psnr,
            row.psnr_frame,
            row.flicker,
            row.max_abs_error,
        );
    }
    page.push_str("</table></div></details>");
    page
}

/// The Pareto front of time against PSNR as a table, fastest first.
fn pareto_table(report: &Report) -> String {
    let mut page = String::from("<h2>Pareto front</h2><p>The configurations no other beats on time without losing PSNR (the unmodified shader counts as exact at its own time, so nothing slower than it is on the front). <b>S</b> marks those also on the SSIM front.</p><table><tr><th>#</th><th>node</th><th>variant</th><th>knobs</th><th>time ms</th><th>speed-up</th><th>PSNR dB</th><th>SSIM</th><th>SSIM front</th></tr>");
    let mut rows: Vec<(usize, &ResultRow)> = report
        .results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.pareto_psnr)
        .collect();
    rows.sort_by(|a, b| a.1.time_ms.total_cmp(&b.1.time_ms));
    if rows.is_empty() {
        return "<h2>Pareto front</h2><p>Empty: every configuration measured is slower than the unmodified shader, which is exact at its own time.</p>".into();
    }
    for (rank, row) in rows {
        let _ = write!(
            page,
            "<tr><td>{}</td>{}<td>{:.3}</td><td>{:.2}×</td><td>{:.1}</td><td>{:.4}</td><td>{}</td></tr>",
            rank + 1,
            configuration_cells(row),
            row.time_ms,
            row.speedup,
            row.psnr,
            row.ssim,
            if row.pareto_ssim { "S" } else { "" },
        );
    }
    page.push_str("</table>");
    page
}

/// What was measured of the grid, and what was pruned.
fn grid_section(report: &Report) -> String {
    let Some(grid) = &report.grid else {
        return String::new();
    };
    let axes = &grid.axes;
    let list = |values: Vec<String>| values.join(", ");
    let mut page = format!(
        "<h2>Grid</h2><p>Δn ∈ {{{}}}, k ∈ {{{}}}, reconstruction ∈ {{{}}}, cache format ∈ {{{}}}, ε ∈ {{{}}}, for every node and variant asked: {} configurations in the full product, {} measured ({} design; base Δn = {}, k = {}, {}, {}, ε = {}).</p>",
        list(axes.refresh_periods.iter().map(u32::to_string).collect()),
        list(axes.refresh_quads.iter().map(u32::to_string).collect()),
        list(axes.reconstructions.iter().map(|r| r.as_str().to_string()).collect()),
        list(axes.cache_formats.iter().map(|f| f.as_str().to_string()).collect()),
        list(axes.depth_epsilons.iter().map(f32::to_string).collect()),
        grid.full,
        grid.measured,
        match grid.design {
            super::Design::Full => "full",
            super::Design::Planes => "planes",
        },
        grid.base.refresh_period,
        grid.base.refresh_quad,
        grid.base.reconstruction.as_str(),
        grid.base.cache_format.as_str(),
        grid.base.depth_epsilon,
    );
    if !grid.pruned.is_empty() {
        page.push_str(
            "<table><tr><th>rule</th><th>node</th><th>configurations</th><th>why</th></tr>",
        );
        for pruned in &grid.pruned {
            let _ = write!(
                page,
                "<tr><td>{}</td><td><code>{}</code></td><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
                escape(&pruned.rule),
                escape(pruned.node.as_deref().unwrap_or("")),
                pruned.configurations,
                escape(&pruned.reason)
            );
        }
        page.push_str("</table>");
    }
    page
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em;max-width:1200px}table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}th{background:#eee}tr.reference{background:#f6f6f6}code{background:#f3f3f3;padding:0 3px}pre{background:#f8f8f8;padding:8px;overflow-x:auto}mark{background:#ffe08a}.answer{font-size:15px;background:#eef7ee;padding:10px;border-left:4px solid #2a2}.meta{color:#555}.pictures{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0}figure img{image-rendering:pixelated;width:256px;border:1px solid #ccc}svg{display:block;margin:12px 0}.reference{background:#f4f6fb;border-left:4px solid #58a;padding:10px;margin:12px 0}.degenerate{background:#fdf0ee;border-left-color:#c33}.wide{max-width:100%;overflow-x:auto}td:nth-child(4){white-space:nowrap}svg{max-width:100%;height:auto}";

#[cfg(test)]
mod tests {
    use super::*;

    /// A report with `n` nodes at P/T 0.1 to 0.9 and one two-pass result
    /// each.
    fn report_with_nodes(n: usize) -> Report {
        use crate::report::fixtures::{node, report, row};
        let mut report = report(Vec::new());
        for i in 0..n {
            let node = node(&format!("n{i:08x}"), 0.1 + 0.8 * i as f64 / (n - 1) as f64);
            let mut row = row(1.0 + node.p_over_t, 30.0, 0.9);
            row.node = node.id.clone();
            row.variant = Variant::TwoPass;
            report.nodes.push(node);
            report.results.push(row);
        }
        report
    }

    #[test]
    fn fig8_with_all_nodes_spans_the_whole_p_over_t_range() {
        let few = time_per_node(&report_with_nodes(4));
        assert!(few.contains("nodes by measured P/T"), "{few}");
        assert!(few.contains("n00000003 (0.90)"), "{few}");
        let many = time_per_node(&report_with_nodes(300));
        assert!(many.contains("300 nodes at their measured P/T"));
        // No node is named on the axis, every one is in a point's title.
        assert!(!many.contains("n00000001 (0.10)"));
        assert!(many.contains("two-pass n0000012b: P/T 0.900"));
        // The axis runs from P/T 0 to 1: its first and last ticks.
        assert!(many.contains(">0.000<") && many.contains(">1.00<"));
    }
}
