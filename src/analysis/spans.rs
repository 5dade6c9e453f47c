//! Where the loads of local variables are in the source.
//!
//! naga's WGSL front end gives no span to the load it makes when a local
//! `var` is read by name (`color` in `return color;`), nor to the variable's
//! pointer. Such a load is the value of the variable at that point, and its
//! reaching definitions make it a node worth caching (the result of a loop,
//! of a branch, of a chain of `color *= ...`). To show and name it, the
//! load is given the span of the variable's name where it is read: the
//! name's occurrence inside the smallest spanned expression or statement
//! that reads the load. The source is only read here, never rewritten.

use std::collections::HashMap;
use std::ops::Range;

use naga::{Expression, Handle, Statement};

use crate::proc::{self, PointerRoot};

/// The span of every load of a named local variable that has none.
/// `copy_of` says which copy of which function's source a load is from
/// (a helper is inlined once per call site, and each copy's loads take
/// the occurrences of the names in the same source): an index of the
/// copy, and the function's name.
pub fn local_loads<'f>(
    function: &'f naga::Function,
    source: &str,
    copy_of: &dyn Fn(Handle<Expression>) -> (usize, Option<&'f str>),
) -> HashMap<Handle<Expression>, Range<usize>> {
    let name_of = unspanned_loads(function);
    if name_of.is_empty() {
        return HashMap::new();
    }

    let reader = first_readers(function, &name_of);

    // Several loads of one variable read by one reader (`c * c`) take its
    // occurrences in turn, in arena order.
    let mut taken: HashMap<(usize, usize, &str), usize> = HashMap::new();
    // Where a function's own source starts, for loads bound to a `let`.
    let body_start = |name: &str| {
        identifier_occurrences(source, 0..source.len(), name)
            .find(|at| source[..at.start].trim_end().ends_with("fn"))
            .map(|at| at.end)
    };
    let mut out = HashMap::new();
    let mut loads: Vec<_> = name_of.into_iter().collect();
    loads.sort_by_key(|(h, _)| h.index());
    for (load, name) in loads {
        let name = match name {
            Err(range) => {
                out.insert(load, range);
                continue;
            }
            Ok(name) => name,
        };
        let (copy, function_name) = copy_of(load);
        if let Some(within) = reader.get(&load) {
            let nth = taken.entry((copy, within.start, name)).or_insert(0);
            if let Some(found) = identifier_occurrences(source, within.clone(), name).nth(*nth) {
                out.insert(load, found);
                *nth += 1;
                continue;
            }
        }
        // Bound to a `let` and read by that name (`let _e157 = color;
        // return _e157;`, as naga_oil's flattened modules read): the
        // variable's name in the `let`'s initializer.
        if let Some(found) = function
            .named_expressions
            .get(&load)
            .zip(function_name.and_then(body_start))
            .and_then(|(binding, start)| let_initializer(source, start, binding))
            .and_then(|init| identifier_occurrences(source, init, name).next())
        {
            out.insert(load, found);
        }
    }
    out
}

/// The loads of `function` without a span, and what each reads: the name
/// of its local variable, or (`Err`) its pointer's span where the pointer
/// has one (`v.member`, `v[i]`).
fn unspanned_loads(
    function: &naga::Function,
) -> HashMap<Handle<Expression>, Result<&str, Range<usize>>> {
    let span_of = |h: Handle<Expression>| function.expressions.get_span(h).to_range();
    let mut name_of = HashMap::new();
    for (handle, expr) in function.expressions.iter() {
        let Expression::Load { pointer } = *expr else {
            continue;
        };
        if span_of(handle).is_some() {
            continue;
        }
        if let Some(range) = span_of(pointer) {
            // `v.member` and `v[i]` are spanned through their pointer.
            name_of.insert(handle, Err(range));
            continue;
        }
        if let Some(PointerRoot::Local(local)) = proc::pointer_root(function, pointer) {
            if let Some(name) = &function.local_variables[local].name {
                name_of.insert(handle, Ok(name.as_str()));
            }
        }
    }
    name_of
}

/// The first reader with a span of each load in `loads`: an expression,
/// else a statement.
fn first_readers<T>(
    function: &naga::Function,
    loads: &HashMap<Handle<Expression>, T>,
) -> HashMap<Handle<Expression>, Range<usize>> {
    let span_of = |h: Handle<Expression>| function.expressions.get_span(h).to_range();
    let mut reader: HashMap<Handle<Expression>, Range<usize>> = HashMap::new();
    for (handle, expr) in function.expressions.iter() {
        let Some(range) = span_of(handle) else {
            continue;
        };
        for operand in proc::operands(expr) {
            if loads.contains_key(&operand) {
                reader.entry(operand).or_insert_with(|| range.clone());
            }
        }
    }
    proc::each_spanned_statement(&function.body, &mut |statement, span| {
        let read: Vec<Handle<Expression>> = match *statement {
            Statement::Return { value } => value.into_iter().collect(),
            Statement::Store { value, .. } => vec![value],
            Statement::Call { ref arguments, .. } => arguments.clone(),
            Statement::If { condition, .. } => vec![condition],
            Statement::Switch { selector, .. } => vec![selector],
            _ => Vec::new(),
        };
        let Some(range) = span.to_range() else {
            return;
        };
        for expr in read.into_iter().filter(|e| loads.contains_key(e)) {
            reader.entry(expr).or_insert_with(|| range.clone());
        }
    });

    reader
}

/// The initializer of the first `let binding` in `source` from `start`
/// (the function's own source: names such as `_e157` repeat across
/// functions): the range from its `=` to its `;`.
fn let_initializer(source: &str, start: usize, binding: &str) -> Option<Range<usize>> {
    let at = identifier_occurrences(source, start..source.len(), binding)
        .find(|at| source[..at.start].trim_end().ends_with("let"))?;
    let equals = at.end + source[at.end..].find('=')?;
    let end = equals + source[equals..].find(';')?;
    Some(equals + 1..end)
}

/// The byte ranges where `name` occurs as a whole identifier within
/// `within`, skipping comments and member names (`x.name`).
fn identifier_occurrences<'a>(
    source: &'a str,
    within: Range<usize>,
    name: &'a str,
) -> impl Iterator<Item = Range<usize>> + 'a {
    let end = within.end.min(source.len());
    let text = source.get(within.start..end).unwrap_or_default();
    let is_ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut chars = text.char_indices().peekable();
    let mut previous: Option<char> = None;
    while let Some((i, c)) = chars.next() {
        if c == '/' && text[i..].starts_with("//") {
            let skip = text[i..].find('\n').unwrap_or(text.len() - i);
            while chars.peek().is_some_and(|&(j, _)| j < i + skip) {
                chars.next();
            }
            previous = None;
            continue;
        }
        if is_ident(c) && !previous.is_some_and(is_ident) {
            let word_end = text[i..]
                .find(|c: char| !is_ident(c))
                .map_or(text.len(), |n| i + n);
            let before = text[..i].trim_end().chars().next_back();
            if &text[i..word_end] == name && before != Some('.') {
                out.push(within.start + i..within.start + word_end);
            }
        }
        previous = Some(c);
    }
    out.into_iter()
}

/// naga spans a call of a built-in function (`mix(a, b, t)`, `dpdx(v)`,
/// `textureSample(...)`) by its name alone; a person expects the whole call.
/// When `range` covers just an identifier followed by `(` (after optional
/// template arguments), this extends it to the matching `)`. The source is
/// only read here, to show and name the node; nothing is rewritten as text.
pub(super) fn call_extent(source: &str, range: Range<usize>) -> Range<usize> {
    let name = &source[range.clone()];
    if !name.chars().all(|c| c.is_alphanumeric() || c == '_') {
        return range;
    }
    let bytes = source.as_bytes();
    let skip_space = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        i
    };
    let mut i = skip_space(range.end);
    if bytes.get(i) == Some(&b'<') {
        let Some(close) = source[i..].find('>') else {
            return range;
        };
        i = skip_space(i + close + 1);
    }
    if bytes.get(i) != Some(&b'(') {
        return range;
    }
    let mut depth = 0usize;
    while i < bytes.len() {
        match bytes[i] {
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return range.start..i + 1;
                }
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i += source[i..].find('\n').unwrap_or(source.len() - i);
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += source[i..]
                    .find("*/")
                    .map_or(source.len() - i, |end| end + 1);
            }
            _ => {}
        }
        i += 1;
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_whole_words_outside_comments_and_members() {
        let source = "c + cc * in.c // c\n + c";
        let found: Vec<_> = identifier_occurrences(source, 0..source.len(), "c").collect();
        assert_eq!(found, vec![0..1, 22..23]);
    }

    #[test]
    fn a_load_after_a_branch_is_spanned_by_its_name() {
        let source = "@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {\n    var color = vec4<f32>(0.0);\n    if (x > 0.5) { color = vec4<f32>(sin(x)); }\n    return color * color;\n}\n";
        let module = naga::front::wgsl::parse_str(source).unwrap();
        let function = &module.entry_points[0].function;
        let spans = local_loads(function, source, &|_| (0, function.name.as_deref()));
        let mut texts: Vec<_> = spans
            .values()
            .map(|r| (r.start, &source[r.clone()]))
            .collect();
        texts.sort();
        let at = source.find("return color").unwrap() + "return ".len();
        assert_eq!(texts, vec![(at, "color"), (at + 8, "color")]);
    }

    #[test]
    fn a_load_bound_to_a_let_is_spanned_in_its_initializer() {
        let source = "@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {\n    var color: vec4<f32>;\n    if (x > 0.5) { color = vec4<f32>(sin(x)); }\n    let _e9: vec4<f32> = color;\n    return _e9;\n}\n";
        let module = naga::front::wgsl::parse_str(source).unwrap();
        let function = &module.entry_points[0].function;
        let spans = local_loads(function, source, &|_| (0, function.name.as_deref()));
        let at = source.find("= color").unwrap() + 2;
        assert_eq!(
            spans.values().cloned().collect::<Vec<_>>(),
            vec![at..at + 5]
        );
    }
}
