//! The index of a profile of several fragment entry points: each entry
//! point's profile is a report of its own in `DIR/<entry>/`; `DIR` gets a
//! `report.json` listing them and a `report.html` with a section per
//! entry point (its reference check, its answer, a link to its report),
//! or the error that stopped it.

use std::fmt::Write as _;

use serde::Serialize;

use super::plots::escape;
use super::{ReferenceCheck, Report};

/// One fragment entry point's profile, or why there is none.
#[derive(Debug)]
pub struct EntrySection {
    /// The entry point's name.
    pub entry: String,
    /// The report, or the rendered error that stopped its profile.
    pub outcome: Result<Report, String>,
}

/// `report.json` of an index.
#[derive(Debug, Serialize)]
pub struct EntryIndex<'a> {
    format: u32,
    shader: &'a str,
    entries: Vec<IndexEntry<'a>>,
}

#[derive(Debug, Serialize)]
struct IndexEntry<'a> {
    entry: &'a str,
    /// The entry point's own report, relative to the index.
    report: Option<String>,
    /// The answer, as its report gives it.
    answer: Option<&'a str>,
    reference_check: Option<&'a ReferenceCheck>,
    /// Why it has no report.
    error: Option<&'a str>,
}

/// The index of `sections` (profiles of `shader`'s entry points), as
/// `report.json` holds it.
pub fn entry_index<'a>(shader: &'a str, sections: &'a [EntrySection]) -> EntryIndex<'a> {
    let entries = sections
        .iter()
        .map(|section| {
            let report = section.outcome.as_ref().ok();
            IndexEntry {
                entry: &section.entry,
                report: report.map(|_| format!("{}/report.json", section.entry)),
                answer: report
                    .and_then(|r| r.choice.as_ref())
                    .map(|c| c.reason.as_str()),
                reference_check: report.and_then(|r| r.reference_check.as_ref()),
                error: section.outcome.as_ref().err().map(String::as_str),
            }
        })
        .collect();
    EntryIndex {
        format: 1,
        shader,
        entries,
    }
}

/// The index as `report.html`: a section per entry point.
pub fn entry_index_html(shader: &str, sections: &[EntrySection]) -> String {
    let mut page = format!(
        "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>shadecache profile: {0}</title><style>body{{font-family:sans-serif;margin:2em;max-width:1200px}}section{{border-left:4px solid #58a;padding:4px 12px;margin:16px 0}}section.failed{{border-left-color:#c33}}code{{background:#f3f3f3;padding:0 3px}}pre{{white-space:pre-wrap}}</style></head><body><h1>shadecache profile of <code>{0}</code></h1><p>The shader has {1} fragment entry points; each was profiled on its own (<code>--entry NAME</code> profiles one).</p>",
        escape(shader),
        sections.len()
    );
    for section in sections {
        let entry = escape(&section.entry);
        match &section.outcome {
            Ok(report) => {
                let _ = write!(
                    page,
                    "<section><h2>Entry point <code>{entry}</code></h2><p>Scene <code>{}</code>, {}×{}, {} measured frames.</p>",
                    escape(&report.scene),
                    report.size[0],
                    report.size[1],
                    report.frames
                );
                if let Some(check) = &report.reference_check {
                    let _ = write!(
                        page,
                        "<p><b>Reference check:</b> {}.</p>",
                        escape(&check.summary())
                    );
                }
                if let Some(choice) = &report.choice {
                    let _ = write!(page, "<p><b>Answer:</b> {}</p>", escape(&choice.reason));
                }
                let _ = write!(
                    page,
                    "<p><a href=\"{entry}/report.html\">The full report of <code>{entry}</code></a></p></section>"
                );
            }
            Err(error) => {
                let _ = write!(
                    page,
                    "<section class=\"failed\"><h2>Entry point <code>{entry}</code></h2><p>Not profiled:</p><pre>{}</pre></section>",
                    escape(error)
                );
            }
        }
    }
    page.push_str("</body></html>\n");
    page
}
