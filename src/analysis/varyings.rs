//! What the fragment stage's inputs carry from the vertex stage.
//!
//! Engines and tutorials compute view and light vectors per vertex (a
//! tangent-space eye position, a projected reflection coordinate) and
//! interpolate them: a fragment value that reads such an input goes stale
//! with the camera or the light although the fragment stage reads no
//! per-frame uniform itself. For each location the vertex stage writes,
//! this finds the per-frame inputs its value depends on — the slice of the
//! output in the vertex function, and every buffer member the helpers it
//! calls read — so the candidates' `depends_on` follows varyings back.

use std::collections::{BTreeSet, HashMap};

use naga::{Expression, Handle, Module, Statement, TypeInner};

use super::graph::{ExprGraph, ExprSet};
use super::per_frame::{loaded_buffer_member, per_frame_slots};
use crate::proc;

/// For each location the vertex stage drawing with fragment entry point
/// `fragment` outputs, the [`super::per_frame::PER_FRAME_INPUTS`] slots
/// its value depends on. Empty when no vertex stage pairs with it.
pub(super) fn per_frame_varyings(module: &Module, fragment: usize) -> HashMap<u32, Vec<usize>> {
    let mut out = HashMap::new();
    let Ok(vertex) = proc::vertex_entry(module, fragment, None) else {
        return out;
    };
    let function = &module.entry_points[vertex].function;
    let Some(result) = &function.result else {
        return out;
    };
    let location = proc::location_of;
    let outputs: Vec<(u32, Option<u32>)> = match module.types[result.ty].inner {
        TypeInner::Struct { ref members, .. } => members
            .iter()
            .enumerate()
            .filter_map(|(i, m)| location(&m.binding).map(|l| (l, Some(i as u32))))
            .collect(),
        _ => location(&result.binding)
            .map(|l| (l, None))
            .into_iter()
            .collect(),
    };
    if outputs.is_empty() {
        return out;
    }
    let layout = proc::layout(module, function, 8.0);
    let graph = ExprGraph::new(function, &layout);
    let exprs: Vec<&Expression> = function.expressions.iter().map(|(_, e)| e).collect();
    for (location, member) in outputs {
        let mut slice = ExprSet::with_capacity(exprs.len());
        for value in proc::output_values(function, &layout, member) {
            slice.union_with(&graph.slice(value));
        }
        let mut names = Vec::new();
        let mut seen = BTreeSet::new();
        for i in slice.ones() {
            names.extend(loaded_buffer_member(module, &exprs, exprs[i]));
            if let Expression::CallResult(callee) = *exprs[i] {
                read_by_function(module, callee, &mut names, &mut seen);
            }
        }
        let slots: BTreeSet<usize> = names.iter().flat_map(|n| per_frame_slots(n)).collect();
        if !slots.is_empty() {
            out.insert(location, slots.into_iter().collect());
        }
    }
    out
}

/// Every uniform or storage member `function` and the helpers it calls
/// read, into `names`.
fn read_by_function(
    module: &Module,
    function: Handle<naga::Function>,
    names: &mut Vec<String>,
    seen: &mut BTreeSet<Handle<naga::Function>>,
) {
    if !seen.insert(function) {
        return;
    }
    let f = &module.functions[function];
    let exprs: Vec<&Expression> = f.expressions.iter().map(|(_, e)| e).collect();
    for expr in &exprs {
        names.extend(loaded_buffer_member(module, &exprs, expr));
    }
    let mut callees = Vec::new();
    proc::each_statement(&f.body, &mut |statement| {
        if let Statement::Call { function, .. } = *statement {
            callees.push(function);
        }
    });
    for callee in callees {
        read_by_function(module, callee, names, seen);
    }
}
