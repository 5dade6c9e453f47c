//! The analysis as a person reads it: each candidate shown in the source
//! like a compiler note, highest P/T first.

use super::{Analysis, Node};
use crate::diagnostic::{Diagnostic, Severity};

/// One note per candidate (and, with `all`, per rejected node), in the
/// order they should be shown.
pub fn notes(analysis: &Analysis, all: bool) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for (rank, candidate) in analysis.candidates.iter().enumerate() {
        let node = &candidate.node;
        let mut note = Diagnostic::new(
            Severity::Note,
            format!(
                "#{} candidate {}: {}, P/T {:.3}",
                rank + 1,
                node.id,
                node.ty,
                candidate.ratio
            ),
        )
        .with_label(
            node.range.clone(),
            format!(
                "P {:.1} of T {:.1}, overlap {:.1}",
                candidate.cost, analysis.total_cost, candidate.overlap
            ),
        );
        note = with_call_path(note, node);
        if candidate.derivatives {
            note = note.with_note(
                "its slice takes implicit derivatives: a rewrite must keep them in uniform control flow",
            );
        }
        if !candidate.depends_on.is_empty() {
            note = note.with_note(format!(
                "it reads per-frame inputs ({}): a cached value goes stale as they change, so it ranks after object-space nodes of similar P/T",
                candidate.depends_on.join(", ")
            ));
        }
        if !candidate.fits_f16 {
            note = note.with_note(
                "its value may not fit an rgba16float cache (the analysis cannot bound it below 65504): three-pass keeps it in rgba32float",
            );
        }
        out.push(note);
    }
    if all {
        for rejected in &analysis.rejected {
            let node = &rejected.node;
            let note = Diagnostic::new(
                Severity::Note,
                format!(
                    "rejected {}: {} ({})",
                    node.id,
                    node.ty,
                    rejected.reason.as_str()
                ),
            )
            .with_label(node.range.clone(), rejected.detail.clone());
            out.push(with_call_path(note, node));
        }
    }
    out
}

/// For a node inside a helper: a label at each call on the way there, and
/// the path in a note.
fn with_call_path(mut note: Diagnostic, node: &Node) -> Diagnostic {
    if node.call_path.is_empty() {
        return note;
    }
    let mut path = Vec::new();
    for step in &node.call_path {
        note = note.with_label(
            step.range.clone(),
            format!("`{}` called here", step.function),
        );
        path.push(format!(
            "{} ({}:{})",
            step.text, step.span.start[0], step.span.start[1]
        ));
    }
    note.with_note(format!(
        "in `{}`, called along {}",
        node.function,
        path.join(" → ")
    ))
}

/// The closing line of the text output.
pub fn summary(analysis: &Analysis, all: bool) -> String {
    let mut line = format!(
        "`{}` in {}: {} candidate{}, {} rejected, estimated total cost T = {:.1}",
        analysis.entry,
        analysis.shader,
        analysis.candidates.len(),
        if analysis.candidates.len() == 1 {
            ""
        } else {
            "s"
        },
        analysis.rejected.len(),
        analysis.total_cost
    );
    if !all && !analysis.rejected.is_empty() {
        line.push_str(" (--all shows the rejected)");
    }
    line
}
