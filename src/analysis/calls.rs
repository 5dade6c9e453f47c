//! Nodes inside helper functions, per call site.
//!
//! Before its nodes are found, the fragment entry point is analysed with
//! every helper call inlined ([`crate::proc::inline`]): each call site's
//! copy of a helper is then part of the entry point, with the value it has
//! there, and the slices, costs, ranges and rejections below apply to it
//! unchanged. A node keeps the span it has in the helper's source and
//! gains its *call path*: the calls from the entry point down to the
//! helper. A rewrite inlines only that path (see [`specialise`]).
//!
//! A call path is named, in ids, by each call's callee, its source text
//! with whitespace collapsed and its occurrence among the calling
//! function's calls of that text: the same across runs and edits
//! elsewhere in the file, as a node's own text and occurrence are.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use naga::{Expression, Handle};
use serde::Serialize;

use super::SourceSpan;
use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;
use crate::proc::inline::{self, Inlined};

/// One call on the way from the entry point into a helper.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct CallStep {
    /// The helper called.
    pub function: String,
    /// Where the call is, in the calling function's source.
    pub span: SourceSpan,
    /// The call's source text.
    pub text: String,
    /// The call's byte range in the source.
    #[serde(skip)]
    pub range: Range<usize>,
    /// Which `Call` statement of the calling function it is, in statement
    /// order (`InlinedCall::ordinal`).
    #[serde(skip)]
    pub ordinal: usize,
}

/// The entry point as analysed: with its helpers inlined when it calls
/// any.
#[derive(Debug)]
pub struct Analysed {
    pub module: naga::Module,
    pub info: naga::valid::ModuleInfo,
    pub inlined: Inlined,
}

/// The fragment entry point `entry_index` with every call inlined, or
/// `None` when it calls nothing.
pub fn inline_all(shader: &Shader, entry_index: usize) -> Result<Option<Arc<Analysed>>, Error> {
    let entry = &shader.module.entry_points[entry_index];
    let mut calls = false;
    crate::proc::each_statement(&entry.function.body, &mut |s| {
        calls |= matches!(s, naga::Statement::Call { .. });
    });
    if !calls {
        return Ok(None);
    }
    let (module, inlined) = specialised_module(shader, entry_index, &mut |_| true)
        .map_err(|err| internal(shader, entry_index, &err))?;
    let info = crate::front::validate(&module)
        .map_err(|err| internal(shader, entry_index, &validation_error(&err)))?;
    Ok(Some(Arc::new(Analysed {
        module,
        info,
        inlined,
    })))
}

/// naga's validation error in full: its `Display` names only the entry
/// point, its `Debug` the statement and the handles at fault.
fn validation_error(err: &naga::WithSpan<naga::valid::ValidationError>) -> String {
    format!("{:?}", err.as_inner())
}

fn internal(shader: &Shader, entry_index: usize, err: &str) -> Error {
    Error::internal(Diagnostic::error(format!(
        "inlining the helpers `{}` calls in `{}`: {err}",
        shader.module.entry_points[entry_index].name, shader.file.path
    )))
}

/// `shader`'s module with the calls `select` picks inlined into entry
/// point `entry_index`.
fn specialised_module(
    shader: &Shader,
    entry_index: usize,
    select: &mut dyn FnMut(&[usize]) -> bool,
) -> Result<(naga::Module, Inlined), String> {
    let mut module = shader.module.clone();
    let root = module.entry_points[entry_index].function.clone();
    let inlined = inline::inline(&mut module, &root, select)?;
    module.entry_points[entry_index].function = inlined.function.clone();
    Ok((module, inlined))
}

/// `shader` with the calls on `path` (ordinals from the entry point down)
/// inlined into entry point `entry_index`, and the handle there of
/// `expression` of the function at the end of the path.
pub fn specialise(
    shader: &Shader,
    entry_index: usize,
    path: &[usize],
    expression: Handle<Expression>,
) -> Result<(Shader, Handle<Expression>), String> {
    let (module, inlined) = specialised_module(shader, entry_index, &mut |at| {
        at.len() <= path.len() && path[..at.len()] == *at
    })?;
    if inlined.calls.len() != path.len() {
        return Err(format!(
            "the call path {path:?} names a call the entry point does not make"
        ));
    }
    let handle = inlined
        .find(path.len().checked_sub(1), expression)
        .ok_or("the node is not in the specialised entry point")?;
    let info = crate::front::validate(&module).map_err(|err| validation_error(&err))?;
    Ok((
        Shader {
            file: shader.file.clone(),
            module,
            info,
            vertex_file: shader.vertex_file.clone(),
            defs: shader.defs.clone(),
        },
        handle,
    ))
}

/// The call path of every inlined call, as nodes carry it, and the key
/// their ids hash.
#[derive(Debug)]
pub struct Paths {
    pub steps: Vec<Vec<CallStep>>,
    pub keys: Vec<String>,
}

impl Paths {
    pub fn new(
        module: &naga::Module,
        inlined: &Inlined,
        source: &str,
        line_col: &dyn Fn(usize) -> (usize, usize),
    ) -> Self {
        let mut steps: Vec<Vec<CallStep>> = Vec::with_capacity(inlined.calls.len());
        let mut keys: Vec<String> = Vec::with_capacity(inlined.calls.len());
        // Occurrences of each (parent, callee, text), in ordinal order:
        // calls are listed callers first, each caller's in ordinal order.
        let mut seen: HashMap<(Option<usize>, String), usize> = HashMap::new();
        for call in &inlined.calls {
            let name = module.functions[call.function]
                .name
                .clone()
                .unwrap_or_default();
            let range = call
                .span
                .to_range()
                .filter(|r| r.end <= source.len() && source.is_char_boundary(r.start))
                .filter(|r| source.is_char_boundary(r.end))
                .map(|r| super::spans::call_extent(source, r))
                .unwrap_or(0..0);
            let text = &source[range.clone()];
            let collapsed = text.split_whitespace().collect::<Vec<_>>().join(" ");
            let occurrence = seen
                .entry((call.parent, format!("{name}\0{collapsed}")))
                .or_insert(0);
            let step = CallStep {
                function: name.clone(),
                span: SourceSpan {
                    start: line_col(range.start).into(),
                    end: line_col(range.end).into(),
                },
                text: super::id::shown_text(text),
                range,
                ordinal: call.ordinal,
            };
            let key = format!("{name}({collapsed})#{occurrence}");
            *occurrence += 1;
            let (mut path, mut path_key) = match call.parent {
                Some(parent) => (steps[parent].clone(), format!("{}/", keys[parent])),
                None => (Vec::new(), String::new()),
            };
            path.push(step);
            path_key.push_str(&key);
            steps.push(path);
            keys.push(path_key);
        }
        Paths { steps, keys }
    }
}
